//! `volgraph convert IN OUT.ome.zarr`: any volume volgraph reads (a raw, NRRD, MHD, NIfTI or
//! DICOM file or folder, a dataset or a generated volume by name) written as an OME-Zarr
//! pyramid (NGFF 0.5, zstd), levels halving to 64³, every chunk's value range beside it, with
//! a progress bar. The writer streams (a slab of chunks per level); the input is read as
//! `--volume` reads it.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::anyhow;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cli::RawArgs;

/// `volgraph convert` arguments.
#[derive(clap::Args, Debug)]
pub struct ConvertArgs {
    /// The volume to convert, as `--volume` takes it.
    pub input: PathBuf,
    /// The OME-Zarr image to write (a new folder; `.ome.zarr` by convention).
    pub output: PathBuf,
    /// Chunk side in voxels (an even number, 2 to 1024).
    #[arg(long, default_value_t = 64)]
    pub chunk: u32,
    /// How to read a headerless raw volume.
    #[command(flatten)]
    pub raw: RawArgs,
}

/// Converts; prints what was written.
pub fn run(args: &ConvertArgs) -> anyhow::Result<String> {
    let start = Instant::now();
    let options = crate::inputs::raw_options(&args.raw)?;
    let (mut source, how) = source(args, &options)?;
    let open_s = start.elapsed().as_secs_f64();
    let write = volgraph_zarr::WriteOptions { chunk: args.chunk, ..Default::default() };
    let dims = source.dims();
    let total = volgraph_zarr::write::chunk_count(dims, &write);
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("writing {msg} {bar:40} {pos}/{len} chunks ({eta} left)")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(args.output.display().to_string());
    let report =
        volgraph_zarr::write_pyramid(source.as_mut(), &args.output, &write, &mut |done, _| bar.set_position(done))
            .map_err(|e| anyhow!("{e}"));
    bar.finish_and_clear();
    let report = report?;
    let bytes = folder_bytes(&args.output);
    let raw = dims.x as u64 * dims.y as u64 * dims.z as u64 * source.voxel_type().size_bytes() as u64;
    let levels: Vec<String> = report.levels.iter().map(|d| format!("{}×{}×{}", d.x, d.y, d.z)).collect();
    Ok(format!(
        "wrote {} ({how}): {} levels ({}), chunks {}³: {} written, {} empty (not stored); {:.1} MiB on disk for \
         {:.1} MiB of voxels ({:.2}×); opened in {:.2} s, written in {:.2} s\n",
        args.output.display(),
        report.levels.len(),
        levels.join(", "),
        args.chunk,
        report.chunks_written,
        report.chunks_empty,
        bytes as f64 / (1 << 20) as f64,
        raw as f64 / (1 << 20) as f64,
        raw as f64 / bytes.max(1) as f64,
        open_s,
        start.elapsed().as_secs_f64() - open_s
    ))
}

/// The input as a slab source, and how it is read.
fn source(
    args: &ConvertArgs,
    options: &volgraph_accel::load::LoadOptions<'static>,
) -> anyhow::Result<(Box<dyn volgraph_zarr::SlabSource>, &'static str)> {
    use crate::convert_sources::{FileSlabs, VesselSlabs};
    let name = args.input.to_string_lossy();
    if !args.input.exists()
        && let Some(tree) = volgraph_accel::generate::streamed_vessels(&name)
    {
        return Ok((Box::new(VesselSlabs(tree.map_err(|e| anyhow!("{e}"))?)), "generated a slab at a time"));
    }
    if args.input.is_file()
        && let Some(file) = FileSlabs::open(&args.input, options)
    {
        return Ok((Box::new(file?), "read a slab at a time"));
    }
    let shown = crate::scene::load_shown_volume(std::slice::from_ref(&args.input), None, options)?;
    for note in &shown.notes {
        crate::stdout::eprintln_escaped!("note: {note}");
    }
    Ok((Box::new(volgraph_zarr::InMemory(shown.volume)), "read whole"))
}

/// Bytes of the files under `dir` (a store's size on disk, before block rounding).
pub fn folder_bytes(dir: &std::path::Path) -> u64 {
    let mut total = 0;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            match entry.metadata() {
                Ok(m) if m.is_dir() => stack.push(entry.path()),
                Ok(m) => total += m.len(),
                Err(_) => {}
            }
        }
    }
    total
}
