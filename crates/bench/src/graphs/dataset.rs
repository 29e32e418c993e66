//! Benchmark datasets by name: real volumes found through `volgraph_accel::data_dir`
//! (`$VOLGRAPH_DATA`), or volumes generated on the spot (`ml64`, `mlf64`, `sphere64`, `noise64`,
//! `vessels256`: the sparse vessel tree of `volgraph_accel::vessels`).

use anyhow::anyhow;
use volgraph_accel::generate;
use volgraph_accel::volume::Volume;

/// Loads `--datasets` entry `name`: a generated volume when the name is one (`ml64`), else the
/// data folder's volume of that name with its manifest spacing.
pub fn load(name: &str) -> anyhow::Result<Volume> {
    match generate::by_name(name) {
        Ok(volume) => Ok(volume),
        Err(e @ generate::NamedVolumeError::Edge { .. }) => Err(anyhow!("--datasets {name}: {e}")),
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
}
