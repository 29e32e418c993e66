//! Klein et al. 2005 §5's antialiasing study, as the `klein2005` preset runs it after its table:
//! the leaping isosurface without antialiasing (`leap_iso.ron`), with full-scene super-sampling
//! (every pixel: 2×, 4× regular, 4× rotated grid) and with selective super-sampling (pixels
//! that differ from a 4-neighbour: 2×, 4×, rotated grid) through `leap_iso_aa.ron`; ms per frame
//! while the volume turns, and the error of one frame against the f64 reference super-sampled
//! with n×n rays per pixel (16 for n = 4). The paper: no AA 30.7 fps, 2× 12.6, 4× 9.4.

use serde::Serialize;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::render_supersampled;
use volgraph_core::runtime::{CameraData, Image, Runtime};
use volgraph_core::{CompileOptions, Diagnostics, Registry};

use super::accuracy::{self, ImageError};
use super::measure::{self, frame_camera, median};
use super::tf_choice::TfChoice;
use super::{dataset, gpu_count};

/// What the study renders.
#[derive(Clone, Copy, Debug)]
pub struct AntialiasStudy {
    /// Dataset name (as `--datasets` takes it).
    pub dataset: &'static str,
    /// Transfer function (as `--tf` takes it).
    pub tf: &'static str,
    /// The isovalue (normalized), the graphs' `iso_value` input.
    pub iso_value: f64,
    /// Viewport before `--scale`.
    pub size: (u32, u32),
    /// The reference's rays per pixel side (4: 16 rays per pixel).
    pub reference_rays_per_side: u32,
    /// Timed frames per variant.
    pub frames: u32,
}

/// One variant: a label, the graph, and the antialias pass's pattern and selection.
struct Variant {
    label: &'static str,
    graph: &'static str,
    aa: Option<(&'static str, &'static str)>,
}

const PLAIN: &str = "graphs/klein_2005/leap_iso.ron";
const WITH_AA: &str = "graphs/klein_2005/leap_iso_aa.ron";

const VARIANTS: [Variant; 7] = [
    Variant { label: "none", graph: PLAIN, aa: None },
    Variant { label: "FSAA 2×", graph: WITH_AA, aa: Some(("2x", "full")) },
    Variant { label: "FSAA 4×", graph: WITH_AA, aa: Some(("4x", "full")) },
    Variant { label: "FSAA 4× rotated grid", graph: WITH_AA, aa: Some(("rgss", "full")) },
    Variant { label: "selective 2×", graph: WITH_AA, aa: Some(("2x", "selective")) },
    Variant { label: "selective 4×", graph: WITH_AA, aa: Some(("4x", "selective")) },
    Variant { label: "selective rotated grid", graph: WITH_AA, aa: Some(("rgss", "selective")) },
];

/// One measured variant.
#[derive(Clone, Debug, Serialize)]
pub struct AntialiasRow {
    /// Variant label.
    pub variant: String,
    /// Graph file.
    pub graph: String,
    /// `aa.pattern` and `aa.selection`, when the variant antialiases.
    pub pattern: Option<String>,
    /// `aa.selection`.
    pub selection: Option<String>,
    /// Median ms per frame.
    pub median_ms: f64,
    /// Frame rate relative to "none" (the paper's 12.6/30.7 for 2×).
    pub fps_vs_none: Option<f64>,
    /// Fraction of pixels re-rendered (flagged by the contrast test, or all).
    pub refined_fraction: f64,
    /// Rays per pixel: 1 + refined fraction × sub-pixel rays.
    pub rays_per_pixel: f64,
    /// Error against the super-sampled reference.
    pub error: Option<ImageError>,
    /// Root-mean-square channel error in units of 1/255.
    pub rms_255: Option<f64>,
    /// On the Pareto front of (ms/frame, mean error).
    pub pareto: bool,
}

/// The study's result.
#[derive(Clone, Debug, Serialize)]
pub struct AntialiasReport {
    /// Dataset name and dims.
    pub dataset: String,
    /// Transfer function.
    pub tf: String,
    /// Isovalue.
    pub iso_value: f64,
    /// Viewport.
    pub viewport: [u32; 2],
    /// Timed frames per variant.
    pub frames: u32,
    /// Rays per pixel of the reference.
    pub reference_rays_per_pixel: u32,
    /// The variants.
    pub rows: Vec<AntialiasRow>,
}

/// Pixels whose colour differs from a 4-neighbour (clamped at the border) by more than
/// `contrast` in some channel: `antialias`'s selection rule, on the same f32 values.
fn flagged_fraction(color: &Image, contrast: f32) -> f64 {
    let (w, h) = (color.width as i64, color.height as i64);
    let at = |x: i64, y: i64| color.rgba(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32);
    let mut flagged = 0usize;
    for y in 0..h {
        for x in 0..w {
            let c = at(x, y);
            let differs = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(dx, dy)| (0..4).any(|i| (at(x + dx, y + dy)[i] - c[i]).abs() > contrast));
            flagged += differs as usize;
        }
    }
    flagged as f64 / (w * h).max(1) as f64
}

/// Runs the study on `runtime`: every variant timed over `spec.frames` frames turning
/// `degrees_per_frame` from `camera`, then one frame at `camera` (after one at the previous view,
/// so the leap starts are reprojected as in the timed frames) compared with the reference.
pub fn run(
    runtime: &mut Runtime,
    registry: &Registry,
    spec: &AntialiasStudy,
    viewport: (u32, u32),
    camera: &OrbitCamera,
    degrees_per_frame: f64,
) -> Result<AntialiasReport, String> {
    let volume = dataset::load(spec.dataset).map_err(|e| format!("{e:#}"))?;
    let lut = TfChoice::parse(spec.tf).and_then(|tf| tf.lut_for(&volume)).map_err(|e| format!("{e:#}"))?;
    let mut reference: Option<Vec<[f64; 4]>> = None;
    let mut rows = Vec::new();
    for variant in &VARIANTS {
        let source =
            volgraph_app::inputs::read_graph(std::path::Path::new(variant.graph)).map_err(|e| format!("{e:#}"))?;
        let mut options = CompileOptions::new(viewport.0, viewport.1)
            .with_scalar("iso_value", spec.iso_value)
            .with_scalar("step_voxels", 0.5);
        if let Some((pattern, selection)) = variant.aa {
            options = options.with_param("aa", "pattern", pattern).with_param("aa", "selection", selection);
        }
        runtime.bind_scene(&gpu_count::scene_inputs(), &volume, &lut).map_err(|e| e.to_string())?;
        let file = variant.graph.to_string();
        let plan = runtime.compile(&file, &source, registry, &options).map_err(|d: Diagnostics| d.to_string())?;
        let settings = accuracy::raycast_settings(&plan).ok_or("the graph has no raycast step")?;
        let contrast = plan.steps.iter().find(|s| s.pass_id == "aa").map(|s| s.params.float("contrast") as f32);
        runtime.apply(plan, registry).map_err(|e| e.to_string())?;
        let timing =
            measure::time_frames(runtime, camera, degrees_per_frame, spec.frames, || {}).map_err(|e| e.to_string())?;
        let previous = frame_camera(camera, -degrees_per_frame, 1);
        runtime.render(CameraData::from_orbit(&previous, viewport)).map_err(|e| e.to_string())?;
        runtime.render(CameraData::from_orbit(camera, viewport)).map_err(|e| e.to_string())?;
        let image = runtime.read_output("image").map_err(|e| e.to_string())?;
        let refined = match (variant.aa, contrast) {
            (Some((_, "full")), _) => 1.0,
            (Some(_), Some(contrast)) => {
                flagged_fraction(&runtime.read_output("raw").map_err(|e| e.to_string())?, contrast)
            }
            _ => 0.0,
        };
        let sub_rays = variant.aa.map_or(0.0, |(pattern, _)| if pattern == "2x" { 2.0 } else { 4.0 });
        let reference = reference.get_or_insert_with(|| {
            render_supersampled(&volume, &lut, camera, viewport.0, viewport.1, spec.reference_rays_per_side, &settings)
        });
        let error = accuracy::image_error(&image, reference);
        rows.push(AntialiasRow {
            variant: variant.label.to_string(),
            graph: variant.graph.to_string(),
            pattern: variant.aa.map(|(p, _)| p.to_string()),
            selection: variant.aa.map(|(_, s)| s.to_string()),
            median_ms: median(&timing.frame_ms),
            fps_vs_none: None,
            refined_fraction: refined,
            rays_per_pixel: 1.0 + refined * sub_rays,
            error,
            rms_255: error.map(|e| if e.non_finite > 0 { f64::INFINITY } else { 255.0 * e.rms }),
            pareto: false,
        });
    }
    let none_ms = rows[0].median_ms;
    for row in &mut rows {
        row.fps_vs_none = Some(none_ms / row.median_ms).filter(|x| x.is_finite());
    }
    let points: Vec<(f64, f64)> =
        rows.iter().map(|r| (r.median_ms, r.error.map_or(f64::NAN, |e| e.mean_abs))).collect();
    for (row, on) in rows.iter_mut().zip(accuracy::pareto_front(&points)) {
        row.pareto = on;
    }
    let dims = volume.dims;
    Ok(AntialiasReport {
        dataset: format!("{} {}×{}×{}", spec.dataset, dims.x, dims.y, dims.z),
        tf: spec.tf.to_string(),
        iso_value: spec.iso_value,
        viewport: [viewport.0, viewport.1],
        frames: spec.frames,
        reference_rays_per_pixel: spec.reference_rays_per_side.pow(2),
        rows,
    })
}

impl AntialiasReport {
    /// The study as a markdown section.
    pub fn to_markdown(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "\n### Antialiasing (Klein et al. 2005 §5)\n\n{} with {}, isovalue {}, {}×{}: ms/frame median of {} frames turning \
             as above; error of one frame against the f64 reference with {} rays per pixel (regular sub-pixel grid, box \
             filter), linear premultiplied RGBA. Selective variants re-render the pixels that differ from a 4-neighbour \
             by more than the contrast; ★ = Pareto front of (ms/frame, mean error). The paper: no AA 30.7 fps, 2× 12.6 \
             (0.41×), 4× 9.4 (0.31×).\n",
            self.dataset,
            self.tf,
            self.iso_value,
            self.viewport[0],
            self.viewport[1],
            self.frames,
            self.reference_rays_per_pixel
        );
        let _ = writeln!(
            s,
            "| antialiasing | ms/frame | fps vs none | re-rendered px | rays/px | mean err | RMS (1/255) | max err | PSNR dB | Pareto |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for r in &self.rows {
            let e = r.error;
            let _ = writeln!(
                s,
                "| {} | {:.1} | {} | {:.1} % | {:.2} | {} | {} | {} | {} | {} |",
                r.variant,
                r.median_ms,
                r.fps_vs_none.map_or_else(|| "n/a".into(), |x| format!("{x:.2}×")),
                r.refined_fraction * 100.0,
                r.rays_per_pixel,
                e.map_or_else(|| "n/a".into(), |e| format!("{:.2e}", e.mean_abs)),
                r.rms_255.map_or_else(|| "n/a".into(), |x| format!("{x:.2}")),
                e.map_or_else(|| "n/a".into(), |e| format!("{:.3}", e.max_abs)),
                e.map_or_else(|| "n/a".into(), |e| e.psnr_label()),
                if r.pareto { "★" } else { "" }
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flagged_pixels_are_those_differing_from_a_4_neighbour() {
        // One bright pixel in the middle of 3×3: it and its four neighbours are flagged.
        let mut data = vec![0.0f32; 3 * 3 * 4];
        data[(4 * 4)..(4 * 4 + 4)].copy_from_slice(&[1.0, 1.0, 1.0, 1.0]);
        let image = Image { width: 3, height: 3, channels: 4, data };
        assert!((flagged_fraction(&image, 0.05) - 5.0 / 9.0).abs() < 1e-12);
        assert_eq!(flagged_fraction(&image, 1.0), 0.0);
    }
}
