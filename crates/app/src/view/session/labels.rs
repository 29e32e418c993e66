//! The label list on the session (issue "several volumes", item 5): built when the graph reads a
//! label table (the volume is its label map), each edit one table upload — no recompile, no
//! reclassification — and "save labels" as an ITK-SNAP file.

use std::path::PathBuf;
use std::time::Instant;

use super::{Event, LiveSession, bind_label_list};
use crate::view::label_list::{LabelEdit, LabelList};

/// Where "save labels" writes (the working folder: the viewer may show a generated map).
pub const SAVED_LABELS: &str = "labels.txt";

impl LiveSession {
    /// The label list, when the graph reads a label table.
    pub fn labels(&self) -> Option<&LabelList> {
        self.labels.as_ref()
    }

    /// Whether the TF editor edits what is seen: not where the volume is a label map coloured by
    /// its table.
    pub fn shows_transfer_function(&self) -> bool {
        !self.labels_are_the_volume
    }

    /// Sets the label list's search text.
    pub fn set_label_search(&mut self, text: String) {
        if let Some(list) = &mut self.labels {
            list.search = text;
        }
    }

    /// Applies a label list edit: the table uploaded to every `LabelTable` input (the next frame
    /// shows it), or the list saved.
    pub fn edit_labels(&mut self, edit: &LabelEdit) -> Vec<Event> {
        let Some(list) = &mut self.labels else { return Vec::new() };
        if *edit == LabelEdit::Save {
            let path = PathBuf::from(SAVED_LABELS);
            return match crate::atomic_write::write_atomically(&path, &list.itk_snap_text()) {
                Ok(()) => vec![Event::Saved { what: "label table".to_string(), path }],
                Err(e) => vec![Event::NotSaved { what: "label table".to_string(), message: format!("{e:#}") }],
            };
        }
        let start = Instant::now();
        if !list.apply(edit) {
            return Vec::new();
        }
        let inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        let mut events = match bind_label_list(&mut self.runtime, &inputs, self.labels.as_ref()) {
            Ok(_) => vec![Event::Reloaded {
                what: "label table".to_string(),
                detail: "uploaded (no recompile)".to_string(),
                ms: start.elapsed().as_secs_f64() * 1e3,
            }],
            Err(e) => vec![Event::Error { what: "label table".to_string(), message: e.to_string() }],
        };
        events.extend(self.label_table_to_slices());
        events
    }
}
