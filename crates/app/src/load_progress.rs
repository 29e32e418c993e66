//! A progress bar (indicatif) while a DICOM series loads: one tick per slice file, drawn on
//! stderr only when it is a terminal and only for series large enough to take a moment.

use std::path::PathBuf;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use volgraph_accel::load::{LoadError, LoadOptions, LoadedVolume, load_volumes};

/// Series with fewer files than this load too fast for a bar to help.
const MIN_FILES_FOR_A_BAR: usize = 32;

/// Loads `paths` as [`load_volumes`] does, with a progress bar for long DICOM series.
pub fn load_with_progress(paths: &[PathBuf], options: &LoadOptions<'_>) -> Result<LoadedVolume, LoadError> {
    // Hidden until a series large enough reports: a raw file or a short series shows nothing.
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::hidden());
    let shown = std::sync::Once::new();
    bar.set_style(
        ProgressStyle::with_template("reading {msg} {bar:40} {pos}/{len} slices ({eta} left)")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(paths.first().map(|p| p.display().to_string()).unwrap_or_default());
    // Worker threads report out of order: count the reports rather than trusting `done`.
    let tick = |_done: usize, total: usize| {
        if total >= MIN_FILES_FOR_A_BAR {
            shown.call_once(|| {
                bar.set_length(total as u64);
                bar.set_draw_target(ProgressDrawTarget::stderr());
            });
            bar.inc(1);
        }
    };
    let with_bar = LoadOptions { progress: Some(&tick), ..options.clone() };
    let loaded = load_volumes(paths, &with_bar);
    bar.finish_and_clear();
    loaded
}
