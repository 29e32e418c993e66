//! Samples counted on the GPU, not estimated on the CPU: a pass whose plugin has a
//! `count_samples` parameter (e.g. `raycast_compute`, `fetch_probe`) writes, when it is on, the
//! samples it took to its `samples` buffer — one u32 per image row, so that no word can overflow
//! (a row of 4096 pixels × 2²⁰ samples would; the shaders' row sums stay far below) — and the
//! benchmark renders one extra, untimed frame with it on and adds the rows up.

use std::collections::BTreeMap;

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::graph::ast::InputKind;
use volgraph_core::runtime::{CameraData, Runtime};
use volgraph_core::{CompileOptions, Diagnostics, Plan, Registry};

/// The parameter that turns counting on.
pub const COUNT_PARAM: &str = "count_samples";
/// The buffer port counting passes write.
pub const COUNT_PORT: &str = "samples";

/// What one counted frame gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Counted {
    /// Samples taken in the frame.
    pub samples: u64,
    /// `samples` / viewport pixels.
    pub samples_per_pixel: f64,
}

/// The scene inputs every benchmark graph binds.
pub fn scene_inputs() -> BTreeMap<String, InputKind> {
    BTreeMap::from([("volume".to_string(), InputKind::Volume), ("tf".to_string(), InputKind::TransferFunction)])
}

/// Ids of the plan's passes that can count their samples, each once.
pub fn counting_passes(plan: &Plan, registry: &Registry) -> Vec<String> {
    let mut ids: Vec<String> = Vec::new();
    for step in &plan.steps {
        let counts = registry.get(&step.kind).is_some_and(|p| p.params().iter().any(|s| s.name == COUNT_PARAM));
        if counts && !ids.contains(&step.pass_id) {
            ids.push(step.pass_id.clone());
        }
    }
    ids
}

/// Adds up a `samples` buffer: little-endian u32 per row.
pub fn sum_rows(bytes: &[u8]) -> u64 {
    bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as u64).sum()
}

/// Compiles the graph with every counting pass counting, renders one frame from `previous` and
/// then the counted one from `camera` (a graph with history — Klein's reprojected starts — counts
/// the samples of a frame that follows another, as in the timed frames), and adds up their
/// `samples` buffers; `Ok(None)` when no pass of the graph counts. The runtime keeps the counting
/// plan applied.
pub fn count(
    runtime: &mut Runtime,
    registry: &Registry,
    file: &str,
    source: &str,
    options: &mut CompileOptions,
    previous: &OrbitCamera,
    camera: &OrbitCamera,
) -> Result<Option<Counted>, String> {
    let compile = |runtime: &mut Runtime, options: &CompileOptions| {
        runtime.compile(file, source, registry, options).map_err(|d: Diagnostics| d.to_string())
    };
    let passes = counting_passes(&compile(runtime, options)?, registry);
    if passes.is_empty() {
        return Ok(None);
    }
    for id in &passes {
        options.param_overrides.insert(format!("{id}.{COUNT_PARAM}"), ron::Value::Bool(true));
    }
    let plan = compile(runtime, options)?;
    let viewport = plan.viewport;
    let buffers: Vec<usize> = plan
        .resources
        .iter()
        .enumerate()
        .filter(|(_, r)| {
            let step = &plan.steps[r.producer];
            passes.contains(&step.pass_id) && r.name.ends_with(&format!(".{COUNT_PORT}"))
        })
        .map(|(rid, _)| rid)
        .collect();
    runtime.apply(plan, registry).map_err(|e| e.to_string())?;
    runtime.render(CameraData::from_orbit(previous, viewport)).map_err(|e| e.to_string())?;
    runtime.render(CameraData::from_orbit(camera, viewport)).map_err(|e| e.to_string())?;
    let mut samples = 0u64;
    for rid in buffers {
        samples += sum_rows(&runtime.read_buffer_resource(rid).map_err(|e| e.to_string())?);
    }
    let pixels = (viewport.0 as f64 * viewport.1 as f64).max(1.0);
    Ok(Some(Counted { samples, samples_per_pixel: samples as f64 / pixels }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_add_up_as_u64() {
        let bytes: Vec<u8> = [u32::MAX, 1, 2].iter().flat_map(|w| w.to_le_bytes()).collect();
        assert_eq!(sum_rows(&bytes), u32::MAX as u64 + 3);
    }
}
