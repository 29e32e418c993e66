//! What accuracy costs, live (issue 24 §5): once the camera rests, the view on screen is
//! compared with the converged f64 reference — the same model with a fine step (`REFERENCE_STEP`
//! voxels), lossless termination, no jitter, the scene's effects and cuts — on a sparse grid of
//! the screen's own pixels, computed on a worker thread; the panel shows the error beside
//! ms/frame, so moving the step, the threshold or an effect shows its price and its error
//! together (`volgraph sweep`'s study, for the view on screen).

use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::Cuts;
use volgraph_accel::reference::RaycastSettings;
use volgraph_accel::volume::Volume;

/// The converged reference's step, in voxels (as `volgraph sweep`'s reference).
pub const REFERENCE_STEP: f64 = 0.1;
/// About this many pixels are compared (a grid over the screen).
const PIXELS: u32 = 4096;

/// One comparison's outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct Accuracy {
    /// Mean absolute error per channel of premultiplied linear RGBA.
    pub mean_abs: f64,
    /// The largest.
    pub max_abs: f64,
    /// Pixels compared.
    pub pixels: usize,
    /// The grid's stride in pixels.
    pub stride: u32,
    /// Worker time, ms.
    pub ms: f64,
}

impl Accuracy {
    /// The panel's line.
    pub fn line(&self) -> String {
        format!(
            "error vs converged f64: mean {:.2}/255, max {:.1}/255 ({} px, {:.1} s)",
            self.mean_abs * 255.0,
            self.max_abs * 255.0,
            self.pixels,
            self.ms / 1e3
        )
    }
}

/// What a comparison needs: the GPU image (premultiplied linear RGBA, row-major) and the
/// scene it showed.
pub struct Job {
    /// The GPU's `image` output of the view.
    pub image: Vec<[f64; 4]>,
    /// Its size.
    pub size: (u32, u32),
    /// The volume, LUT, camera and settings of the march.
    pub volume: Volume,
    /// The LUT.
    pub lut: Vec<[f32; 4]>,
    /// The camera.
    pub camera: OrbitCamera,
    /// The raycaster's settings (the step and threshold are replaced by the converged ones).
    pub settings: RaycastSettings,
    /// The cuts.
    pub cuts: Cuts,
    /// A label map coloured by its table (`fusion: "labels"`): the table by label value and how
    /// labels are sampled.
    pub labels: Option<(Vec<[f32; 4]>, volgraph_accel::labels::sample::LabelFilter)>,
}

/// Compares on the calling thread.
pub fn measure(job: &Job) -> Accuracy {
    let start = Instant::now();
    let (w, h) = job.size;
    let stride = (((w as f64 * h as f64) / PIXELS as f64).sqrt().floor() as u32).max(1);
    let settings = RaycastSettings {
        step_voxels: REFERENCE_STEP.min(job.settings.step_voxels),
        threshold: 1.0,
        max_steps: u32::MAX,
        jitter: false,
        cuts: job.cuts,
        ..job.settings
    };
    let frame = job.camera.frame(w, h);
    let fusion = job.labels.as_ref().map(|(table, filter)| volgraph_accel::fusion::Fusion {
        combine: volgraph_accel::fusion::Combine::Labels,
        label_lut: table,
        filter: *filter,
        second: None,
        more: &[],
        overlay: None,
    });
    // The shadows' light grid once for the whole view, not once per pixel.
    let grid = volgraph_accel::reference::shadow_grid(&job.volume, &job.lut, fusion.as_ref(), &frame, &settings);
    let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0usize);
    for y in (stride / 2..h).step_by(stride as usize) {
        for x in (stride / 2..w).step_by(stride as usize) {
            let (reference, _, _) = volgraph_accel::reference::fused_pixel_lit(
                &job.volume,
                &job.lut,
                (fusion.as_ref(), grid.as_ref()),
                &job.camera,
                &frame,
                (x, y),
                &settings,
            );
            let gpu = job.image[(y * w + x) as usize];
            for c in 0..4 {
                let d = (gpu[c] - reference[c]).abs();
                let d = if d.is_nan() { f64::INFINITY } else { d };
                sum += d;
                max = max.max(d);
            }
            n += 1;
        }
    }
    Accuracy {
        mean_abs: if n > 0 { sum / (4 * n) as f64 } else { 0.0 },
        max_abs: max,
        pixels: n,
        stride,
        ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

/// The worker: at most one comparison at a time; a newer view waits for the running one.
#[derive(Default)]
pub struct LiveAccuracy {
    running: Option<Receiver<Accuracy>>,
    /// The last result.
    pub last: Option<Accuracy>,
}

impl LiveAccuracy {
    /// Whether a comparison is running.
    pub fn busy(&self) -> bool {
        self.running.is_some()
    }

    /// Starts comparing `job` on a worker thread.
    pub fn start(&mut self, job: Job) {
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let _ = tx.send(measure(&job));
        });
        self.running = Some(rx);
    }

    /// Takes a finished result.
    pub fn poll(&mut self) {
        if let Some(rx) = &self.running
            && let Ok(result) = rx.try_recv()
        {
            self.last = Some(result);
            self.running = None;
        }
    }
}
