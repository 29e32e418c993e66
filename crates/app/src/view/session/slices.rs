//! The session's slice panes (`view::slice_panes`): opened on the session's volume and GPU,
//! closed to free their runtime.

use super::{Event, LiveSession};
use crate::view::slice_panes::SlicePanes;

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
        match SlicePanes::new(self.runtime.gpu_arc(), &self.volume) {
            Ok(panes) => {
                self.slices = Some(panes);
                Vec::new()
            }
            Err(message) => vec![Event::Error { what: "slice panes".to_string(), message }],
        }
    }
}
