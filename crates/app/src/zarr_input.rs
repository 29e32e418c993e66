//! `--volume image.ome.zarr` and `volgraph info image.ome.zarr`: an OME-Zarr pyramid
//! (`volgraph_zarr`) read in core — the finest level whose voxels fit in
//! [`IN_CORE_LIMIT_BYTES`], the volume `--frame N` (or `image.ome.zarr#N`, one per named input)
//! picks — with notes saying which level was read and what the reader met (missing or
//! undecodable chunks, named). The image's volumes are counted as a 4D NIfTI's are: channels
//! fastest within each time point, N = t·C + c, so a store of channels binds as
//! `--volume volume=cells.ome.zarr#0 --volume second=cells.ome.zarr#1`.

use std::path::Path;

use anyhow::anyhow;
use volgraph_accel::load::LoadOptions;
use volgraph_accel::volume::Volume;
use volgraph_zarr::{OmeZarr, Pick};

/// The most voxel bytes one level read in core may hold (2 GiB).
pub const IN_CORE_LIMIT_BYTES: u64 = 2 << 30;

/// Decoded chunks a streamed store keeps in memory when `--memory-mb` does not say (512 MiB).
pub const DEFAULT_CHUNK_CACHE_MB: u64 = 512;

/// A volume bound as a pyramid, read brick by brick by a streaming graph: an OME-Zarr image,
/// or a volume file larger than the memory budget ([`stream_file`]).
pub struct Streamed {
    /// The source the streaming pass reads.
    pub source: std::sync::Arc<dyn volgraph_accel::pyramid::PyramidSource>,
    /// Its coarsest level, whole: what the transfer function is fitted to and the camera framed
    /// on (the same box as the finest).
    pub coarsest: Volume,
    /// Notes for stderr.
    pub notes: Vec<String>,
}

/// Whether graph `source` draws its `volume` input brick by brick (a `raycast_stream` pass):
/// then an OME-Zarr store is streamed, never read a level whole.
pub fn graph_streams(source: &str) -> bool {
    use volgraph_core::graph::ast::NodeDoc;
    volgraph_core::graph::parse_graph(source).is_ok_and(|doc| {
        doc.passes.iter().any(|node| match node {
            NodeDoc::Pass(p) => p.kind == "raycast_stream",
            NodeDoc::Repeat(r) => r.body.iter().any(|p| p.kind == "raycast_stream"),
        })
    })
}

/// The coarsest level's largest edge of a pyramid built from a file (what `volgraph convert`
/// writes).
const FILE_PYRAMID_EDGE: u32 = 64;

/// For a streaming graph shown a raw, NRRD or MetaImage file (or a DICOM series): one whose
/// voxels exceed the memory budget (`memory_mb`, default [`DEFAULT_CHUNK_CACHE_MB`]) is streamed
/// from the file brick by brick (`volgraph_accel::pyramid_file::FilePyramid`: one pass builds
/// the coarse levels, a quarter of the budget holds them), never read whole; `None` for a
/// smaller one (read in core) or a format read only whole (NIfTI, compressed). `announce` is
/// told, before the opening pass, that it starts (the command line prints it: the pass takes a
/// while on a big file; the Python API stays quiet).
pub fn stream_file(
    path: &Path,
    options: &LoadOptions<'_>,
    memory_mb: Option<u64>,
    announce: impl FnOnce(&str),
) -> anyhow::Result<Option<Streamed>> {
    let Ok(mut header) = volgraph_accel::load::VolumeHeader::read(path, options) else { return Ok(None) };
    let budget = memory_mb.unwrap_or(DEFAULT_CHUNK_CACHE_MB) << 20;
    let bytes = header.dims.as_u64vec3().element_product() * header.dtype.size_bytes() as u64;
    if bytes <= budget {
        return Ok(None);
    }
    if let Some(spacing) = options.raw.spacing {
        header.spacing = spacing;
    }
    // The pass takes a while on a big file (about 4 s a GiB here): say so before it starts.
    announce(&format!(
        "{}: more than --memory-mb {}: reading it once to build its coarse levels, then brick by brick",
        path.display(),
        budget >> 20
    ));
    let started = std::time::Instant::now();
    let source = volgraph_accel::pyramid_file::FilePyramid::open(header, FILE_PYRAMID_EDGE, budget / 4)
        .map_err(|e| anyhow!("{e}"))?;
    let coarsest = volgraph_accel::pyramid::PyramidSource::coarsest(&source).map_err(|e| anyhow!(e))?;
    let levels = volgraph_accel::pyramid::PyramidSource::levels(&source);
    let mut notes = vec![format!(
        "{}: {} of voxels, more than --memory-mb {}: streamed brick by brick from the file ({} levels down to \
         {}×{}×{}); building the coarse levels read it once in {:.1} s (`volgraph convert {} OUT.ome.zarr` writes a \
         store that opens at once)",
        path.display(),
        if bytes >= 1 << 30 {
            format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
        } else {
            format!("{} MiB", bytes >> 20)
        },
        budget >> 20,
        levels.len(),
        coarsest.dims.x,
        coarsest.dims.y,
        coarsest.dims.z,
        started.elapsed().as_secs_f64(),
        path.display()
    )];
    if source.non_finite_replaced() > 0 {
        notes.push(format!("{}: replaced {} NaN/Inf voxels", path.display(), source.non_finite_replaced()));
    }
    Ok(Some(Streamed { source: std::sync::Arc::new(source), coarsest, notes }))
}

/// For a graph that holds its volume whole, shown a raw, NRRD or MetaImage file larger than
/// [`IN_CORE_LIMIT_BYTES`]: refused before it is read, naming the streaming graph that reads it
/// brick by brick.
pub fn refuse_large_file(path: &Path, options: &LoadOptions<'_>) -> anyhow::Result<()> {
    let Ok(header) = volgraph_accel::load::VolumeHeader::read(path, options) else { return Ok(()) };
    let bytes = header.dims.as_u64vec3().element_product() * header.dtype.size_bytes() as u64;
    if bytes <= IN_CORE_LIMIT_BYTES {
        return Ok(());
    }
    Err(anyhow!(
        "{}: {:.1} GiB of voxels, more than the {} GiB a graph that holds its volume whole reads into memory; \
         streaming/ray_guided reads it brick by brick: `volgraph render streaming/ray_guided --volume {}`",
        path.display(),
        bytes as f64 / f64::from(1u32 << 30),
        IN_CORE_LIMIT_BYTES >> 30,
        path.display()
    ))
}

/// The store `path` as a streamed pyramid (the volume `--frame N` picks), its decoded chunks
/// held within `memory_mb` MiB.
pub fn stream(path: &Path, options: &LoadOptions<'_>, memory_mb: Option<u64>) -> anyhow::Result<Streamed> {
    let image = OmeZarr::open(path).map_err(|e| anyhow!("{e}"))?;
    let pick = pick_of(path, &image, options)?;
    let levels = image.levels.len();
    let (fine, coarse) = (image.levels[0].dims, image.levels[levels - 1].dims);
    let cache = memory_mb.unwrap_or(DEFAULT_CHUNK_CACHE_MB) << 20;
    let mut source = volgraph_zarr::ZarrPyramid::new(image, pick, cache).map_err(|e| anyhow!("{e}"))?;
    if let Some(spacing) = options.raw.spacing {
        source.set_spacing(spacing);
    }
    let coarsest = volgraph_accel::pyramid::PyramidSource::coarsest(&source).map_err(|e| anyhow!(e))?;
    let notes = vec![format!(
        "{}: streamed brick by brick from {levels} levels ({}×{}×{} … {}×{}×{}), decoded chunks within {} MiB",
        path.display(),
        fine.x,
        fine.y,
        fine.z,
        coarse.x,
        coarse.y,
        coarse.z,
        cache >> 20
    )];
    Ok(Streamed { source: std::sync::Arc::new(source), coarsest, notes })
}

/// The header of store `path`'s finest level at the volume `--frame N` picks, read box by box
/// (`render --distributed`: each rank reads its kd-tree box, chunk by chunk).
pub fn store_header(path: &Path, options: &LoadOptions<'_>) -> anyhow::Result<volgraph_accel::load::VolumeHeader> {
    let image = OmeZarr::open(path).map_err(|e| anyhow!("{e}"))?;
    let pick = pick_of(path, &image, options)?;
    let mut header = volgraph_zarr::StoreBoxes::header(image, pick);
    if let Some(spacing) = options.raw.spacing {
        header.spacing = spacing;
    }
    Ok(header)
}

/// The volume `--frame N` (or `#N`) picks of `image`: N = t·C + c.
fn pick_of(path: &Path, image: &OmeZarr, options: &LoadOptions<'_>) -> anyhow::Result<Pick> {
    if options.series.is_some() || options.raw.dims.is_some() || options.raw.dtype.is_some() {
        return Err(anyhow!(
            "{}: an OME-Zarr image says its own layout; --series, --dims and --dtype are for DICOM and raw files",
            path.display()
        ));
    }
    let volumes = image.times * image.channels;
    let n = options.frame.unwrap_or(0);
    if n >= volumes {
        return Err(anyhow!(
            "{}: volume {n} asked for (--frame or #N); the image holds {volumes} ({} time point{} × {} channel{}, \
             counted t·C + c from 0)",
            path.display(),
            image.times,
            if image.times == 1 { "" } else { "s" },
            image.channels,
            if image.channels == 1 { "" } else { "s" }
        ));
    }
    Ok(Pick { time: n / image.channels, channel: n % image.channels })
}

/// The volume `path` (an OME-Zarr image) shows, and notes for stderr.
pub fn read(path: &Path, options: &LoadOptions<'_>) -> anyhow::Result<(Volume, Vec<String>)> {
    let image = OmeZarr::open(path).map_err(|e| anyhow!("{e}"))?;
    let pick = pick_of(path, &image, options)?;
    let volumes = image.times * image.channels;
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
    if volumes > 1 && options.frame.is_none() {
        notes.push(format!(
            "{}: the image holds {volumes} volumes ({} time points × {} channels); volume 0 is shown: --frame N or \
             {}#N picks N = t·C + c",
            path.display(),
            image.times,
            image.channels,
            path.display()
        ));
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
