//! `--volume image.ome.zarr` and `volgraph info image.ome.zarr`: an OME-Zarr pyramid
//! (`volgraph_zarr`) read in core — the finest level whose voxels fit in
//! [`IN_CORE_LIMIT_BYTES`], the time point `--frame` picks, channel 0 — with notes saying which
//! level was read and what the reader met (missing or undecodable chunks, named).

use std::path::Path;

use anyhow::anyhow;
use volgraph_accel::load::LoadOptions;
use volgraph_accel::volume::Volume;
use volgraph_zarr::{OmeZarr, Pick};

/// The most voxel bytes one level read in core may hold (2 GiB).
pub const IN_CORE_LIMIT_BYTES: u64 = 2 << 30;

/// The volume `path` (an OME-Zarr image) shows, and notes for stderr.
pub fn read(path: &Path, options: &LoadOptions<'_>) -> anyhow::Result<(Volume, Vec<String>)> {
    let image = OmeZarr::open(path).map_err(|e| anyhow!("{e}"))?;
    if options.series.is_some() || options.raw.dims.is_some() || options.raw.dtype.is_some() {
        return Err(anyhow!(
            "{}: an OME-Zarr image says its own layout; --series, --dims and --dtype are for DICOM and raw files",
            path.display()
        ));
    }
    let pick = Pick { time: options.frame.unwrap_or(0), channel: 0 };
    let index = image.finest_within(IN_CORE_LIMIT_BYTES).unwrap_or(image.levels.len() - 1);
    let read = image.read_level(index, pick, IN_CORE_LIMIT_BYTES).map_err(|e| anyhow!("{e}"))?;
    let mut notes = read.notes;
    if index > 0 {
        let (fine, level) = (&image.levels[0], &image.levels[index]);
        notes.push(format!(
            "{}: level \"{}\" ({}×{}×{}) of {} is read, the finest within {} GiB in memory (level \"{}\" is \
             {}×{}×{})",
            path.display(),
            level.path,
            level.dims.x,
            level.dims.y,
            level.dims.z,
            image.levels.len(),
            IN_CORE_LIMIT_BYTES >> 30,
            fine.path,
            fine.dims.x,
            fine.dims.y,
            fine.dims.z
        ));
    }
    if image.channels > 1 {
        notes.push(format!("{}: channel 0 of {} is shown", path.display(), image.channels));
    }
    if image.times > 1 && options.frame.is_none() {
        notes.push(format!("{}: time point 0 of {} is shown; --frame N picks another", path.display(), image.times));
    }
    let mut volume = read.volume;
    if let Some(spacing) = options.raw.spacing {
        volume.spacing = spacing;
    }
    Ok((volume, notes))
}

/// `volgraph info` of an OME-Zarr image: the store's levels, chunks, codecs and sizes, then the
/// level read in core.
pub fn describe(path: &Path) -> anyhow::Result<String> {
    let image = OmeZarr::open(path).map_err(|e| anyhow!("{e}"))?;
    let mut out = image.describe().join("\n");
    let index = image.finest_within(IN_CORE_LIMIT_BYTES);
    out.push_str(&match index {
        Some(i) => format!(
            "\nread in core: level \"{}\" (the finest within {} GiB)\n",
            image.levels[i].path,
            IN_CORE_LIMIT_BYTES >> 30
        ),
        None => format!("\nno level fits in {} GiB of memory\n", IN_CORE_LIMIT_BYTES >> 30),
    });
    Ok(out)
}
