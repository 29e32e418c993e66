//! A benchmark transfer function: a built-in preset stretched over each volume's value range
//! (`default`, `opaque`, `sparse`), `fitted` (the default ramp made transparent up to the
//! volume's background of air or noise: what `volgraph render` picks for a scan), or a file — a path to a `.ron` / ParaView `.json`, or the
//! name of one in `$VOLGRAPH_DATA/tf/` (the peer benchmark's `engine_opaque`, `hydrogen`, …),
//! whose points are in the volume's own values.

use std::path::{Path, PathBuf};

use anyhow::anyhow;
use volgraph_accel::data_dir::data_dir;
use volgraph_accel::transfer_function::{Preset, TransferFunction};
use volgraph_accel::volume::Volume;

use volgraph_app::inputs::LUT_SIZE;

/// One `--tf` value.
#[derive(Clone, Debug, PartialEq)]
pub enum TfChoice {
    /// Stretched over the volume's value range.
    Preset(Preset),
    /// `TransferFunction::default_for` the volume: the ramp, transparent up to its background.
    Fitted,
    /// One of `graphs/tf/`, compiled into the program (`graphs/tf/vessels.ron` where no such
    /// file exists): the presets name these, and they work from any folder.
    Builtin {
        /// The file stem, for tables.
        name: &'static str,
        /// The RON text.
        text: &'static str,
    },
    /// Read from a file when the case runs (a missing file skips its cases with a note).
    File {
        /// The file stem, for tables.
        name: String,
        /// Where it is read from.
        path: PathBuf,
    },
}

/// The folder of named transfer functions: `$VOLGRAPH_DATA/tf`.
pub fn tf_dir() -> PathBuf {
    data_dir().join("tf")
}

fn is_tf_file(text: &str) -> bool {
    let p = Path::new(text);
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron") || e.eq_ignore_ascii_case("json"))
}

impl TfChoice {
    /// Reads one `--tf` value: a preset name, a `.ron`/`.json` path, or a name in
    /// `$VOLGRAPH_DATA/tf/`.
    pub fn parse(text: &str) -> anyhow::Result<TfChoice> {
        if let Some(p) = Preset::from_name(text) {
            return Ok(TfChoice::Preset(p));
        }
        if text == "fitted" {
            return Ok(TfChoice::Fitted);
        }
        let stem = |p: &Path| p.file_stem().map_or_else(|| text.to_string(), |s| s.to_string_lossy().into_owned());
        if is_tf_file(text) {
            let path = PathBuf::from(text);
            if let Some((name, text)) = volgraph_app::builtin_graphs::find_tf(&path) {
                return Ok(TfChoice::Builtin { name, text });
            }
            return Ok(TfChoice::File { name: stem(&path), path });
        }
        let named = tf_dir().join(format!("{text}.ron"));
        if !text.is_empty() && !text.contains(['/', '\\']) && named.is_file() {
            return Ok(TfChoice::File { name: text.to_string(), path: named });
        }
        Err(anyhow!(
            "--tf \"{text}\": expected a preset (default, opaque, sparse), fitted, a transfer-function file (.ron or ParaView \
             .json), or the name of a file in {} (without .ron)",
            tf_dir().display()
        ))
    }

    /// The name in tables.
    pub fn name(&self) -> String {
        match self {
            TfChoice::Preset(p) => p.name().to_string(),
            TfChoice::Fitted => "fitted".to_string(),
            TfChoice::Builtin { name, .. } => name.to_string(),
            TfChoice::File { name, .. } => name.clone(),
        }
    }

    /// The LUT the runtime uploads for `volume`.
    pub fn lut_for(&self, volume: &Volume) -> anyhow::Result<Vec<[f32; 4]>> {
        let tf = match self {
            TfChoice::Preset(p) => {
                let (lo, hi) = volume.value_range;
                TransferFunction::preset(*p, (lo, if hi > lo { hi } else { lo + 1.0 }))
            }
            TfChoice::Fitted => TransferFunction::default_for(volume),
            TfChoice::Builtin { name, text } => {
                TransferFunction::from_ron_str(text, Path::new(&format!("graphs/tf/{name}.ron")))
                    .map_err(|e| anyhow!("{e}"))?
            }
            TfChoice::File { path, .. } => {
                let json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
                let loaded = if json { TransferFunction::load_paraview(path) } else { TransferFunction::load(path) };
                loaded.map_err(|e| anyhow!("{e}"))?
            }
        };
        Ok(tf.to_lut_for(volume, LUT_SIZE))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_files_and_unknown_names() {
        assert_eq!(TfChoice::parse("opaque").expect("a preset"), TfChoice::Preset(Preset::Opaque));
        let file = TfChoice::parse("some/dir/mine.ron").expect("a file");
        assert_eq!(file.name(), "mine");
        let err = TfChoice::parse("opaqe").expect_err("no such name").to_string();
        assert!(err.contains("--tf \"opaqe\"") && err.contains("default, opaque, sparse"), "{err}");
    }

    #[test]
    fn a_missing_file_is_an_error_naming_it_when_read() {
        let choice = TfChoice::parse("/nonexistent/tf.ron").expect("a file name");
        let volume = volgraph_accel::generate::marschner_lobb(8);
        let err = choice.lut_for(&volume).expect_err("the file is missing").to_string();
        assert!(err.contains("/nonexistent/tf.ron"), "{err}");
    }

    /// The presets' `graphs/tf/…` files are compiled in: a run from any folder finds them.
    /// (Tests run in `crates/bench`, where no `graphs/` folder is.)
    #[test]
    fn graphs_tf_files_are_built_in() {
        assert!(!std::path::Path::new("graphs/tf/vessels.ron").exists(), "run from a folder without graphs/");
        let choice = TfChoice::parse("graphs/tf/vessels.ron").expect("built in");
        assert!(matches!(choice, TfChoice::Builtin { name: "vessels", .. }), "{choice:?}");
        let volume = volgraph_accel::generate::marschner_lobb(8);
        assert_eq!(choice.lut_for(&volume).expect("parses").len(), LUT_SIZE);
        assert!(matches!(TfChoice::parse("graphs/tf/nope.ron"), Ok(TfChoice::File { .. })));
    }
}
