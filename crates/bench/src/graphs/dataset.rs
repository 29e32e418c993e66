//! Benchmark datasets by name: real volumes found through `volgraph_accel::data_dir`
//! (`$VOLGRAPH_DATA`), or volumes generated on the spot (`ml64`, `mlf64`, `sphere64`, `noise64`,
//! `vessels256`: the sparse vessel tree of `volgraph_accel::vessels`).

use anyhow::anyhow;
use volgraph_accel::generate;
use volgraph_accel::volume::Volume;

/// The generated volume a benchmark measures in place of a real dataset the data folder lacks,
/// so every preset runs on a fresh machine ([`load_or_stand_in`]).
pub const STAND_IN: &str = "ml64";

/// A dataset as a benchmark measures it.
pub struct BenchVolume {
    /// The volume.
    pub volume: Volume,
    /// Its name in tables: the requested name, or `NAME→ml64` for a stand-in.
    pub label: String,
    /// Why a stand-in was measured instead, for the report's notes.
    pub stand_in_note: Option<String>,
}

/// [`load`], except that a real dataset missing from the data folder (no such file, no volumes
/// folder) is replaced by the generated [`STAND_IN`], labelled `NAME→ml64` and explained in a
/// note — a table never shows a generated volume under a real dataset's name. Other errors (a
/// malformed file or manifest) stay errors.
pub fn load_or_stand_in(name: &str) -> anyhow::Result<BenchVolume> {
    use volgraph_accel::data_dir::DataError;
    match generate::by_name(name) {
        Err(generate::NamedVolumeError::Unknown { .. }) => match volgraph_accel::data_dir::load_dataset(name) {
            Ok(loaded) => Ok(BenchVolume { volume: loaded.volume, label: name.to_string(), stand_in_note: None }),
            Err(e @ (DataError::NotFound { .. } | DataError::NoVolumesDir { .. })) => Ok(BenchVolume {
                volume: generate::by_name(STAND_IN).map_err(|e| anyhow!("{e}"))?,
                label: format!("{name}→{STAND_IN}"),
                stand_in_note: Some(format!(
                    "dataset {name} is not in the data folder ({e}); its rows ({name}→{STAND_IN}) measure the generated \
                     {STAND_IN} instead: give --data DIR for the real one"
                )),
            }),
            Err(e) => Err(anyhow!("--datasets {name}: {e}")),
        },
        _ => Ok(BenchVolume { volume: load(name)?, label: name.to_string(), stand_in_note: None }),
    }
}

/// Loads `--datasets` entry `name`: a generated volume when the name is one (`ml64`), else the
/// data folder's volume of that name with its manifest spacing.
pub fn load(name: &str) -> anyhow::Result<Volume> {
    match generate::by_name(name) {
        Ok(volume) => Ok(volume),
        Err(e @ (generate::NamedVolumeError::Edge { .. } | generate::NamedVolumeError::StreamedEdge { .. })) => {
            Err(anyhow!("--datasets {name}: {e}"))
        }
        Err(generate::NamedVolumeError::Unknown { .. }) => {
            let loaded = volgraph_accel::data_dir::load_dataset(name)
                .map_err(|e| anyhow!("--datasets {name}: {e} (generated volumes: {})", generate::NAMED_GENERATORS))?;
            Ok(loaded.volume)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_names_make_volumes_of_that_edge() {
        let v = load("ml16").expect("ml16 is a generated name");
        assert_eq!(v.dims.x, 16);
        assert!(load("ml100000").is_err());
    }

    /// A real dataset the data folder lacks is measured as the generated stand-in, labelled so.
    #[test]
    fn a_missing_dataset_is_measured_as_a_labelled_stand_in() {
        let loaded = load_or_stand_in("no_such_dataset_anywhere").expect("a stand-in");
        assert_eq!(loaded.label, "no_such_dataset_anywhere→ml64");
        assert_eq!(loaded.volume.dims.x, 64);
        assert!(loaded.stand_in_note.expect("a note").contains("give --data DIR"));
        let generated = load_or_stand_in("ml16").expect("generated");
        assert_eq!((generated.label.as_str(), generated.stand_in_note), ("ml16", None));
    }
}
