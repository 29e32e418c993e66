//! The session's slice panes (`view::slice_panes`): opened on the session's volume and GPU,
//! closed to free their runtime.

use super::{Event, LiveSession};
use crate::view::slice_panes::{PaneLabels, SlicePanes};

impl LiveSession {
    /// The slice panes, while open.
    pub fn slices(&self) -> Option<&SlicePanes> {
        self.slices.as_ref()
    }

    /// The slice panes, while open, to move their crosshair, window or render them.
    pub fn slices_mut(&mut self) -> Option<&mut SlicePanes> {
        self.slices.as_mut()
    }

    /// Opens the slice panes (on the session's volume) or closes them; a failure to open is
    /// an error event and leaves them closed.
    pub fn set_slice_panes(&mut self, open: bool) -> Vec<Event> {
        if !open {
            self.slices = None;
            return Vec::new();
        }
        if self.slices.is_some() {
            return Vec::new();
        }
        // A graph that reads a label table: its map over the panes, coloured as the list says.
        let labels = self.labels.as_ref().and_then(|list| {
            let map = match &self.label_map_input {
                None => Some(&self.volume),
                Some(input) => self.bindings.as_ref()?.others.iter().find(|(n, _)| n == input).map(|(_, v)| v),
            }?;
            Some(PaneLabels { map, table: list.lut() })
        });
        match SlicePanes::new(self.runtime.gpu_arc(), &self.volume, labels) {
            Ok(panes) => {
                self.slices = Some(panes);
                Vec::new()
            }
            Err(message) => vec![Event::Error { what: "slice panes".to_string(), message }],
        }
    }

    /// What lies at the crosshair, for the panel: the data value (trilinear, in the data's
    /// units), the label there and the patient point in mm; `None` while the panes are closed.
    pub fn crosshair_line(&self) -> Option<String> {
        let panes = self.slices.as_ref()?;
        let u = panes.view.crosshair;
        let v = &self.volume;
        let value = v.value_range.0 + v.sample_trilinear(u) * (v.value_range.1 - v.value_range.0);
        let units = v.meta.units.as_deref().map_or(String::new(), |u| format!(" {u}"));
        let voxel = panes.crosshair_voxel();
        let place = match v.meta.patient_point(voxel, v.spacing) {
            Some(mm) => volgraph_accel::volume_meta::patient_label(mm),
            None => format!("voxel ({:.1}, {:.1}, {:.1})", voxel.x, voxel.y, voxel.z),
        };
        Some(format!("crosshair: {value:.1}{units}{} at {place}", self.label_line(u)))
    }

    /// The label list's table, over the slice panes too (after an edit of the list).
    pub(super) fn label_table_to_slices(&mut self) -> Vec<Event> {
        let (Some(panes), Some(list)) = (self.slices.as_mut(), self.labels.as_ref()) else { return Vec::new() };
        match panes.set_label_table(&list.lut()) {
            Ok(()) => Vec::new(),
            Err(message) => vec![Event::Error { what: "slice panes".to_string(), message }],
        }
    }
}
