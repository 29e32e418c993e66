//! Benchmark datasets by name: real volumes found through `volgraph_accel::data_dir`
//! (`$VOLGRAPH_DATA`), or volumes generated on the spot (`ml64`, `mlf64`, `sphere64`, `noise64`,
//! `vessels256`: the sparse vessel tree of `volgraph_accel::vessels`).

use anyhow::anyhow;
use volgraph_accel::generate;
use volgraph_accel::volume::Volume;

/// Largest edge of a generated volume (512³ u8 is 128 MiB; more is surely a typo).
const MAX_GENERATED_EDGE: u32 = 512;

/// The generator and edge a generated-volume name asks for, if it is one.
fn generated(name: &str) -> Option<anyhow::Result<Volume>> {
    let (make, digits): (fn(u32) -> Volume, &str) = if let Some(d) = name.strip_prefix("mlf") {
        (generate::marschner_lobb_f32, d)
    } else if let Some(d) = name.strip_prefix("ml") {
        (generate::marschner_lobb, d)
    } else if let Some(d) = name.strip_prefix("sphere") {
        (|n| generate::sphere(n, 0.6), d)
    } else if let Some(d) = name.strip_prefix("noise") {
        (|n| generate::noise(n, 1), d)
    } else if let Some(d) = name.strip_prefix("vessels") {
        (|n| volgraph_accel::vessels::vessel_tree(n, 1), d)
    } else {
        return None;
    };
    let edge: u32 = digits.parse().ok()?;
    if !(2..=MAX_GENERATED_EDGE).contains(&edge) {
        return Some(Err(anyhow!(
            "--datasets {name}: a generated volume's edge must be 2..={MAX_GENERATED_EDGE} voxels"
        )));
    }
    Some(Ok(make(edge)))
}

/// The generated volume `name` (`ml64`, `mlf64`, `sphere64`, `noise64`), or an error listing them.
pub fn load_generated(name: &str) -> anyhow::Result<Volume> {
    generated(name).unwrap_or_else(|| {
        Err(anyhow!(
            "Generated(\"{name}\") names no generated volume; use ml<N>, mlf<N>, sphere<N>, noise<N> or vessels<N>, e.g. ml64"
        ))
    })
}

/// Loads dataset `name`: a generated volume when the name is one (`ml64`), else the data folder's
/// volume of that name with its manifest spacing.
pub fn load(name: &str) -> anyhow::Result<Volume> {
    if let Some(volume) = generated(name) {
        return volume;
    }
    let loaded = volgraph_accel::data_dir::load_dataset(name).map_err(|e| {
        anyhow!("--datasets {name}: {e} (generated volumes: ml<N>, mlf<N>, sphere<N>, noise<N>, vessels<N>, e.g. ml64)")
    })?;
    Ok(loaded.volume)
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
