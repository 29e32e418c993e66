//! The panel's "Save image" section: a size and a file name, and the view rendered again at
//! that size (`LiveSession::save_image`); `S` saves what the window shows at the window's size.

use std::path::PathBuf;

use super::panel::Action;

/// What the section's fields hold between frames (egui's memory).
#[derive(Clone, Debug, PartialEq)]
struct SaveForm {
    width: u32,
    height: u32,
    path: String,
}

impl Default for SaveForm {
    fn default() -> Self {
        Self { width: 1920, height: 1080, path: "volgraph_image.png".to_string() }
    }
}

/// The section; returns the save asked for.
pub fn section(ui: &mut egui::Ui) -> Option<Action> {
    let id = egui::Id::unique("save image form");
    let mut form: SaveForm = ui.ctx().data_mut(|d| d.get_temp::<SaveForm>(id)).unwrap_or_default();
    let mut asked = None;
    ui.collapsing("Save image", |ui| {
        ui.horizontal(|ui| {
            let max = super::session::MAX_SAVED_SIDE;
            ui.add(egui::DragValue::new(&mut form.width).range(1..=max).suffix(" px"));
            ui.label("×");
            ui.add(egui::DragValue::new(&mut form.height).range(1..=max).suffix(" px"));
            for (name, size) in [("1080p", (1920, 1080)), ("4K", (3840, 2160)), ("square", (2048, 2048))] {
                if ui.small_button(name).clicked() {
                    (form.width, form.height) = size;
                }
            }
        });
        ui.horizontal(|ui| {
            let label = ui.label("file");
            ui.add(egui::TextEdit::singleline(&mut form.path).desired_width(160.0)).labelled_by(label.id);
            let save = ui.button("save image").on_hover_text(
                "the view rendered again at this size at full quality (PNG); S saves the window's image at its size",
            );
            if save.clicked() {
                asked =
                    Some(Action::SaveImage { path: PathBuf::from(form.path.trim()), size: (form.width, form.height) });
            }
        });
    });
    ui.ctx().data_mut(|d| d.insert_temp(id, form));
    asked
}
