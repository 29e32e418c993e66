//! The viewer's label list (issue "several volumes", item 5): a label map's labels — value,
//! name, colour swatch, visibility, opacity, voxel count — with a search field and "show only".
//! Each change is one table upload ([`LabelList::lut`] bound to the graph's `LabelTable`
//! inputs): no recompile, no reclassification. "Save labels" writes the list as an ITK-SNAP
//! label description file, which `--tf label_table=FILE` and `volgraph info --label-table` read
//! back. The model is GPU-free and tested here; the widget under egui_kittest.

use volgraph_accel::labels::census::{NotALabelMap, census};
use volgraph_accel::labels::{Label, LabelTable};
use volgraph_accel::volume::Volume;

/// One label of the list.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelRow {
    /// The label value.
    pub value: u32,
    /// Its table's name (or `Label N`).
    pub name: String,
    /// Colour bytes.
    pub rgb: [u8; 3],
    /// Opacity 0..1.
    pub opacity: f32,
    /// Shown.
    pub visible: bool,
    /// Voxels the map holds of it.
    pub voxels: u64,
}

/// A label map's labels as the viewer edits them.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelList {
    /// Every value the map holds but the background, ascending.
    pub rows: Vec<LabelRow>,
    /// The search field's text (rows whose value or name holds it are listed).
    pub search: String,
    /// The background (value 0) entry, kept as the table gives it.
    background: Label,
    /// Entries of the LUT: the largest value + 1.
    len: usize,
}

/// A change asked for in the list.
#[derive(Clone, Debug, PartialEq)]
pub enum LabelEdit {
    /// Show or hide a label.
    Visible(u32, bool),
    /// A label's opacity.
    Opacity(u32, f32),
    /// Show this label alone.
    ShowOnly(u32),
    /// Show every label.
    ShowAll,
    /// Write the list as a label table file.
    Save,
}

impl LabelList {
    /// The labels `map` holds, named and coloured by `table`.
    pub fn of(map: &Volume, table: &LabelTable) -> Result<Self, NotALabelMap> {
        let counted = census(map)?;
        let rows = counted
            .counts
            .iter()
            .filter(|c| c.value != 0)
            .map(|c| {
                let l = table.label(c.value);
                LabelRow {
                    value: c.value,
                    name: l.name,
                    rgb: l.rgb,
                    opacity: l.opacity,
                    visible: l.visible,
                    voxels: c.voxels,
                }
            })
            .collect();
        let len = counted.counts.last().map_or(1, |c| c.value as usize + 1);
        Ok(Self { rows, search: String::new(), background: table.label(0), len })
    }

    /// The list as a table (by value).
    pub fn table(&self) -> LabelTable {
        let mut labels: std::collections::BTreeMap<u32, Label> = self
            .rows
            .iter()
            .map(|r| (r.value, Label { name: r.name.clone(), rgb: r.rgb, opacity: r.opacity, visible: r.visible }))
            .collect();
        labels.insert(0, self.background.clone());
        LabelTable { labels, source: "the viewer's label list".to_string() }
    }

    /// What a `LabelTable` input holds: RGBA by label value.
    pub fn lut(&self) -> Vec<[f32; 4]> {
        self.table().lut(self.len)
    }

    /// The name of label `value`, for the value under the cursor.
    pub fn name_of(&self, value: u32) -> Option<&str> {
        self.rows.iter().find(|r| r.value == value).map(|r| r.name.as_str())
    }

    /// The rows the search lets through (value or name, case-insensitively).
    pub fn shown_rows(&self) -> impl Iterator<Item = &LabelRow> {
        let needle = self.search.trim().to_lowercase();
        self.rows.iter().filter(move |r| {
            needle.is_empty() || r.name.to_lowercase().contains(&needle) || r.value.to_string() == needle
        })
    }

    /// Applies `edit` (not `Save`); returns whether the table changed.
    pub fn apply(&mut self, edit: &LabelEdit) -> bool {
        let before = self.rows.clone();
        for row in &mut self.rows {
            match *edit {
                LabelEdit::Visible(v, on) if row.value == v => row.visible = on,
                LabelEdit::Opacity(v, a) if row.value == v => row.opacity = a.clamp(0.0, 1.0),
                LabelEdit::ShowOnly(v) => row.visible = row.value == v,
                LabelEdit::ShowAll => row.visible = true,
                _ => {}
            }
        }
        self.rows != before
    }

    /// The list as an ITK-SNAP label description file (`IDX R G B A VIS MSH "LABEL"`).
    pub fn itk_snap_text(&self) -> String {
        let mut out = String::from(
            "################################################\n# ITK-SnAP Label Description File\n# written by \
             volgraph view\n# Columns: IDX R G B A VIS MSH \"LABEL\"\n################################################\n",
        );
        let table = self.table();
        for (value, l) in &table.labels {
            let name = l.name.replace('"', "'");
            out.push_str(&format!(
                "{value:>5} {:>5} {:>5} {:>5} {:>9.4} {:>2} {:>2}    \"{name}\"\n",
                l.rgb[0],
                l.rgb[1],
                l.rgb[2],
                l.opacity,
                u8::from(l.visible),
                u8::from(l.visible)
            ));
        }
        out
    }
}

/// Draws the list; the change the user made this frame. The search field edits `list.search`
/// in place.
pub fn show(ui: &mut egui::Ui, list: &mut LabelList) -> Option<LabelEdit> {
    let mut edit = None;
    ui.horizontal(|ui| {
        let label = ui.label("search");
        ui.add(egui::TextEdit::singleline(&mut list.search).desired_width(120.0).id_salt("label search"))
            .labelled_by(label.id);
        if ui.button("show all").clicked() {
            edit = Some(LabelEdit::ShowAll);
        }
        if ui.button("save labels").clicked() {
            edit = Some(LabelEdit::Save);
        }
    });
    egui::Grid::new("labels").num_columns(5).striped(true).show(ui, |ui| {
        for row in list.shown_rows() {
            let mut visible = row.visible;
            if ui.checkbox(&mut visible, "").on_hover_text("shown").changed() {
                edit = Some(LabelEdit::Visible(row.value, visible));
            }
            let (rect, _) = ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
            ui.painter().rect_filled(rect, 2.0, egui::Color32::from_rgb(row.rgb[0], row.rgb[1], row.rgb[2]));
            ui.label(format!("{} {}", row.value, row.name));
            let mut opacity = row.opacity;
            // Named by the label's value (the accessible name a screen reader or test finds).
            let slider = egui::Slider::new(&mut opacity, 0.0..=1.0).show_value(false).text(format!("α {}", row.value));
            if ui.add(slider).changed() {
                edit = Some(LabelEdit::Opacity(row.value, opacity));
            }
            ui.horizontal(|ui| {
                ui.label(format!("{} vx", row.voxels));
                if ui.small_button("only").clicked() {
                    edit = Some(LabelEdit::ShowOnly(row.value));
                }
            });
            ui.end_row();
        }
    });
    edit
}

#[cfg(test)]
mod tests {
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;
    use glam::{DVec3, UVec3};
    use volgraph_accel::volume::VoxelData;

    use super::*;

    fn list() -> LabelList {
        let map = Volume::new("seg", UVec3::new(6, 1, 1), DVec3::ONE, VoxelData::U8(vec![0, 1, 1, 2, 5, 5]));
        let mut table = LabelTable::default_for([0, 1, 2, 5]);
        table.labels.get_mut(&1).expect("1").name = "liver".into();
        table.labels.get_mut(&5).expect("5").name = "aorta".into();
        LabelList::of(&map, &table).expect("a label map")
    }

    #[test]
    fn edits_change_the_lut_and_save_reads_back() {
        let mut l = list();
        assert_eq!(l.rows.iter().map(|r| (r.value, r.voxels)).collect::<Vec<_>>(), [(1, 2), (2, 1), (5, 2)]);
        assert_eq!(l.lut().len(), 6);
        assert!(l.apply(&LabelEdit::ShowOnly(5)));
        let lut = l.lut();
        assert_eq!((lut[1][3], lut[2][3]), (0.0, 0.0), "only the aorta shows");
        assert!(lut[5][3] > 0.0);
        assert!(!l.apply(&LabelEdit::ShowOnly(5)), "nothing changed the second time");
        assert!(l.apply(&LabelEdit::Opacity(5, 0.25)));
        assert_eq!(l.lut()[5][3], 0.25);
        assert_eq!(l.name_of(1), Some("liver"));
        let back = LabelTable::parse("saved.txt", &l.itk_snap_text()).expect("ITK-SNAP reads it");
        assert_eq!(back.lut(6), l.lut(), "the saved file is the list");
        l.search = "AOR".into();
        assert_eq!(l.shown_rows().map(|r| r.value).collect::<Vec<_>>(), [5]);
        l.search = "2".into();
        assert_eq!(l.shown_rows().map(|r| r.value).collect::<Vec<_>>(), [2]);
    }

    #[test]
    fn the_widget_lists_searches_and_toggles() {
        let mut h = Harness::builder().with_size(egui::Vec2::new(480.0, 240.0)).build_ui_state(
            |ui, state: &mut (LabelList, Vec<LabelEdit>)| {
                if let Some(edit) = show(ui, &mut state.0) {
                    state.0.apply(&edit);
                    state.1.push(edit);
                }
            },
            (list(), Vec::new()),
        );
        h.run();
        h.get_by_label("1 liver");
        h.get_by_label("5 aorta");
        // "only" on the aorta's row (the last row's button).
        let only: Vec<_> = h.query_all_by_label("only").collect();
        assert_eq!(only.len(), 3);
        only[2].click();
        h.run();
        assert_eq!(h.state().1.last(), Some(&LabelEdit::ShowOnly(5)));
        assert!(h.state().0.rows.iter().all(|r| r.visible == (r.value == 5)));
        h.get_by_label("show all").click();
        h.run();
        assert!(h.state().0.rows.iter().all(|r| r.visible));
        // Typing in the search narrows the list.
        h.get_by_label("search").focus();
        h.run();
        h.get_by_label("search").type_text("liv");
        h.run();
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "α 1").set_value_accesskit(0.5);
        h.run();
        assert!(h.query_by_label("5 aorta").is_none() && h.query_by_label("1 liver").is_some());
        assert_eq!(h.state().1.last(), Some(&LabelEdit::Opacity(1, 0.5)), "the liver's opacity slider");
    }
}
