//! The label tables a graph's `LabelTable` inputs are bound to (issue "several volumes", item 3):
//! `--tf NAME=FILE` (an ITK-SNAP label description, a 3D Slicer colour table, a `.seg.nrrd` or DICOM SEG
//! whose segments name their values) or `--tf NAME=default`; without one, the label map's own
//! names where its file has them (`.seg.nrrd`, DICOM SEG), else the default palette. Which map a table
//! colours: input `X_table` colours volume input `X`; `label_table` the volume input `labels`,
//! else the frame's volume.

use std::path::Path;

use anyhow::anyhow;
use volgraph_accel::labels::LabelTable;
use volgraph_accel::labels::census::census;
use volgraph_accel::labels::names_its_labels;
use volgraph_accel::volume::Volume;

/// Label values a table texture holds at most (256 per row, 8192 rows: wgpu's least 2D limit).
pub const MAX_LABEL_VALUES: usize = 256 * 8192;

/// The volume input whose labels table input `table` colours (module docs).
pub fn map_input_of(table: &str, volume_inputs: &[&str]) -> Option<String> {
    if let Some(base) = table.strip_suffix("_table")
        && volume_inputs.contains(&base)
    {
        return Some(base.to_string());
    }
    if volume_inputs.contains(&"labels") {
        return Some("labels".to_string());
    }
    None
}

/// The flag a message about label table input `table` and its map names: the table's `--tf`
/// when one was given, else the map's `--volume` (a scan given as the label map is the map's
/// fault, not a table's the user never named).
pub fn blamed_flag(table: &str, table_given: bool, map_input: Option<&str>) -> String {
    match map_input {
        Some(map) if !table_given => format!("--volume {map}=…"),
        _ => format!("--tf {table}"),
    }
}

/// The LUT (RGBA by label value) of label map `map` (read from `map_path` when known) through
/// the table `given` names (`default`, or a file), with the notes a user should see: values the
/// map holds that the table does not name, labels the table names that the map lacks.
/// `flag` names where the table came from in messages (`--tf labels_table=…`).
pub fn label_lut(
    map: &Volume,
    map_path: Option<&Path>,
    given: Option<&Path>,
    flag: &str,
) -> anyhow::Result<(Vec<[f32; 4]>, Vec<String>)> {
    let (table, largest, notes) = label_table(map, map_path, given, flag)?;
    Ok((table.lut(largest as usize + 1), notes))
}

/// [`label_lut`]'s table, with the largest value the map holds and the notes.
pub fn label_table(
    map: &Volume,
    map_path: Option<&Path>,
    given: Option<&Path>,
    flag: &str,
) -> anyhow::Result<(LabelTable, u32, Vec<String>)> {
    let counted = census(map).map_err(|e| anyhow!("{flag}: {e}"))?;
    let present = counted.values();
    let mut notes = Vec::new();
    let table_file = match given {
        Some(p) if p.as_os_str() == "default" => None,
        Some(p) => Some(p),
        None => map_path.filter(|p| names_its_labels(p)),
    };
    let table = match table_file {
        // The generated organ phantom's map comes with its organs' names and colours.
        None if map.name.starts_with("organs_labels") => volgraph_accel::organs::label_table(),
        None => LabelTable::default_for(present.iter().copied()),
        Some(path) => {
            let (table, read_notes) = LabelTable::read(path).map_err(|e| anyhow!("{flag}: {e}"))?;
            notes.extend(read_notes.into_iter().map(|n| format!("note: {n}")));
            let unnamed: Vec<u32> =
                present.iter().copied().filter(|v| *v != 0 && !table.labels.contains_key(v)).collect();
            if !unnamed.is_empty() {
                notes.push(format!(
                    "note: {flag}: {} label value(s) of {} have no entry in {} ({}); they take the default palette",
                    unnamed.len(),
                    map.name,
                    path.display(),
                    short_list(&unnamed)
                ));
            }
            let missing = table.missing_from(&present);
            if !missing.is_empty() {
                notes.push(format!(
                    "note: {flag}: {} names {} label(s) that {} does not hold ({})",
                    path.display(),
                    missing.len(),
                    map.name,
                    short_list(&missing)
                ));
            }
            table
        }
    };
    let largest = present.last().copied().unwrap_or(0) as usize;
    if largest >= MAX_LABEL_VALUES {
        return Err(anyhow!(
            "{flag}: {} holds label {largest}; label values up to {} are shown — renumber the labels",
            map.name,
            MAX_LABEL_VALUES - 1
        ));
    }
    Ok((table, largest as u32, notes))
}

/// Up to 8 values, then how many more.
fn short_list(values: &[u32]) -> String {
    let shown: Vec<String> = values.iter().take(8).map(u32::to_string).collect();
    match values.len() {
        n if n > 8 => format!("{}, … {} more", shown.join(", "), n - 8),
        _ => shown.join(", "),
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};
    use volgraph_accel::volume::VoxelData;

    use super::*;

    #[test]
    fn a_table_input_names_its_map() {
        assert_eq!(map_input_of("organs_table", &["volume", "organs"]), Some("organs".into()));
        assert_eq!(map_input_of("label_table", &["volume", "labels"]), Some("labels".into()));
        assert_eq!(map_input_of("label_table", &["volume"]), None);
    }

    #[test]
    fn the_default_palette_covers_the_maps_values_and_a_table_notes_what_it_lacks() {
        let map = Volume::new("seg", UVec3::new(4, 1, 1), DVec3::ONE, VoxelData::U8(vec![0, 1, 3, 3]));
        let (lut, notes) = label_lut(&map, None, None, "--tf label_table").expect("default");
        assert_eq!(lut.len(), 4);
        assert_eq!(lut[0][3], 0.0, "the background is hidden");
        assert!(lut[1][3] > 0.0 && lut[3][3] > 0.0);
        assert!(notes.is_empty());
        let dir = tempfile::tempdir().expect("dir");
        let file = dir.path().join("t.txt");
        std::fs::write(&file, "1 liver 255 0 0 255\n7 spleen 0 0 255 255\n").expect("write");
        let (lut, notes) = label_lut(&map, None, Some(&file), "--tf label_table").expect("table");
        assert_eq!(lut[1], [1.0, 0.0, 0.0, 1.0]);
        let text = notes.join("\n");
        assert!(text.contains("have no entry") && text.contains("(3)"), "{text}");
        assert!(text.contains("does not hold (7)"), "{text}");
        let float = Volume::new("ct", UVec3::new(2, 1, 1), DVec3::ONE, VoxelData::F32(vec![0.0, 0.5]));
        let err = label_lut(&float, None, None, "--tf label_table").expect_err("not labels").to_string();
        assert!(err.contains("voxel (1, 0, 0) holds 0.5"), "{err}");
    }
}
