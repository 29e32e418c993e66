//! Reading the user's inputs: graph files, volumes (or a generated default), transfer
//! functions, sizes and cameras from the command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow, bail};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::load::{RawOptions, load_volume};
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;

/// The LUT resolution uploaded for every transfer function.
pub const LUT_SIZE: usize = 256;

/// Reads a graph file's text.
pub fn read_graph(path: &Path) -> anyhow::Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("{}: cannot read graph file", path.display()))
}

/// Raw-file options from `--dims`, `--dtype`, `--spacing`, `--big-endian`.
pub fn raw_options(raw: &crate::cli::RawArgs) -> anyhow::Result<RawOptions> {
    let mut o = RawOptions::default();
    if let Some(d) = &raw.dims {
        let parts: Vec<&str> = d.split(['x', 'X']).collect();
        let fail = || anyhow!("--dims \"{d}\": expected XxYxZ with positive integers, e.g. 128x128x64");
        if parts.len() != 3 {
            return Err(fail());
        }
        let v: Vec<u32> =
            parts.iter().map(|p| p.trim().parse::<u32>().map_err(|_| fail())).collect::<Result<_, _>>()?;
        if v.contains(&0) {
            return Err(fail());
        }
        o.dims = Some(glam::UVec3::new(v[0], v[1], v[2]));
    }
    if let Some(t) = &raw.dtype {
        o.dtype = Some(
            volgraph_accel::volume::VoxelType::from_name(t)
                .ok_or_else(|| anyhow!("--dtype \"{t}\": expected uint8, uint16, int16 or float32"))?,
        );
    }
    if let Some(s) = &raw.spacing {
        let fail = || anyhow!("--spacing \"{s}\": expected three positive numbers X,Y,Z, e.g. 1,1,1.4");
        let v: Vec<f64> =
            s.split(',').map(|p| p.trim().parse::<f64>().map_err(|_| fail())).collect::<Result<_, _>>()?;
        if v.len() != 3 || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(fail());
        }
        o.spacing = Some(glam::DVec3::new(v[0], v[1], v[2]));
    }
    if raw.big_endian {
        o.endianness = volgraph_accel::load::Endianness::Big;
    }
    Ok(o)
}

/// Loads `--volume`, or generates the default (Marschner–Lobb 64³) when none is given.
pub fn volume(path: Option<&PathBuf>, raw: &RawOptions) -> anyhow::Result<Volume> {
    match path {
        None => Ok(volgraph_accel::generate::marschner_lobb(64)),
        Some(p) => {
            let loaded = load_volume(p, raw).map_err(|e| anyhow!("{e}"))?;
            if loaded.report.non_finite_replaced() > 0 {
                eprintln!("note: {}: replaced {} NaN/Inf voxels", p.display(), loaded.report.non_finite_replaced());
            }
            Ok(loaded.volume)
        }
    }
}

/// The transfer function for the generated default volume: an opaque band around ρ = 0.5 that
/// shows Marschner–Lobb's rings (`graphs/tf/marschner_lobb.ron`, compiled in so a fresh clone
/// renders it from any directory).
const MARSCHNER_LOBB_TF: &str = include_str!("../../../graphs/tf/marschner_lobb.ron");

/// Loads `--tf` (RON, or ParaView JSON by extension), or the default for the volume (for the
/// generated default volume, `graphs/tf/marschner_lobb.ron`).
pub fn transfer_function(path: Option<&PathBuf>, volume: &Volume, generated: bool) -> anyhow::Result<TransferFunction> {
    match path {
        None if generated => {
            TransferFunction::from_ron_str(MARSCHNER_LOBB_TF, Path::new("graphs/tf/marschner_lobb.ron"))
                .map_err(|e| anyhow!("{e}"))
        }
        None => Ok(TransferFunction::default_for(volume)),
        Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) => {
            TransferFunction::load_paraview(p).map_err(|e| anyhow!("{e}"))
        }
        Some(p) => TransferFunction::load(p).map_err(|e| anyhow!("{e}")),
    }
}

/// Parses `WxH`.
pub fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let fail = || anyhow!("--size \"{text}\": expected WIDTHxHEIGHT, e.g. 512x512, each 1..=16384");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(fail)?;
    let w: u32 = w.trim().parse().map_err(|_| fail())?;
    let h: u32 = h.trim().parse().map_err(|_| fail())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(fail());
    }
    Ok((w, h))
}

/// Parses `azimuth,elevation,distance` (degrees, degrees, world units; the volume's longest
/// side is 1).
pub fn parse_camera(text: &str) -> anyhow::Result<OrbitCamera> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let fail = || {
        anyhow!(
            "--camera \"{text}\": expected AZIMUTH,ELEVATION,DISTANCE in degrees, degrees and world units, e.g. 30,20,3.2"
        )
    };
    if parts.len() != 3 {
        return Err(fail());
    }
    let v: Vec<f64> = parts.iter().map(|p| p.parse::<f64>().map_err(|_| fail())).collect::<Result<_, _>>()?;
    if !v.iter().all(|x| x.is_finite()) || v[2] <= 0.0 {
        bail!("--camera \"{text}\": values must be finite and the distance positive");
    }
    if v[1].abs() > 90.0 {
        bail!("--camera \"{text}\": elevation must be within -90..=90 degrees");
    }
    Ok(OrbitCamera { azimuth_deg: v[0], elevation_deg: v[1], distance: v[2], ..OrbitCamera::default() })
}
