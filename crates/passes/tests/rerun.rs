//! Passes that declare `Rerun::WhenInputsChange` (the min/max grid, the empty-block
//! classification and its distance map) are recorded only when something they read changed: a
//! steady camera orbit records them once, a new transfer function re-records the two that read
//! it, a new volume all three, and a parameter edit the edited pass and what reads its output.
//! The real passes are wrapped in a plugin that counts their `record` calls.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::transfer_function::{Preset, TransferFunction};
use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{CameraData, CreateContext, Gpu, PassError, RecordContext, Runtime};
use volgraph_core::{CompileOptions, ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortSpec, Registry, Rerun};
use volgraph_passes::builtin_registry;

mod support;

/// `inner` with a counter of its nodes' `record` calls.
struct Counting {
    inner: Arc<dyn PassPlugin>,
    records: Arc<AtomicUsize>,
}

struct CountingNode {
    inner: Box<dyn PassNode>,
    records: Arc<AtomicUsize>,
}

impl PassNode for CountingNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        self.records.fetch_add(1, Ordering::SeqCst);
        self.inner.record(ctx)
    }
    fn owned_output(&self, port: &str) -> Option<wgpu::TextureView> {
        self.inner.owned_output(port)
    }
    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.inner.update_params(gpu, params)
    }
}

impl PassDecl for Counting {
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }
    fn summary(&self) -> &'static str {
        self.inner.summary()
    }
    fn params(&self) -> Vec<ParamSpec> {
        self.inner.params()
    }
    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        self.inner.ports(params)
    }
    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        self.inner.shaders(params)
    }
    fn rerun(&self) -> Rerun {
        self.inner.rerun()
    }
    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        self.inner.updates_in_place(old, new)
    }
}

impl PassPlugin for Counting {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        Ok(Box::new(CountingNode { inner: self.inner.create(ctx)?, records: self.records.clone() }))
    }
}

/// The built-in registry with every pass of `fastest.ron` counting; the counters by kind.
fn counting_registry() -> (Registry, BTreeMap<&'static str, Arc<AtomicUsize>>) {
    let builtin = builtin_registry();
    let mut registry = builtin.clone();
    let mut counters = BTreeMap::new();
    for kind in ["minmax_grid", "empty_space", "empty_distance", "raycast_compute", "present"] {
        let records = Arc::new(AtomicUsize::new(0));
        let inner = builtin.get(kind).expect("a built-in kind").clone();
        registry.register(Counting { inner, records: records.clone() });
        counters.insert(kind, records);
    }
    (registry, counters)
}

fn counts(counters: &BTreeMap<&'static str, Arc<AtomicUsize>>) -> [usize; 4] {
    ["minmax_grid", "empty_space", "empty_distance", "raycast_compute"].map(|k| counters[k].load(Ordering::SeqCst))
}

#[test]
fn grid_classification_and_distance_run_only_when_what_they_read_changes() {
    let (registry, counters) = counting_registry();
    let mut runtime = support::runtime(&support::gpu());
    let source = support::graph_source("modern/fastest.ron");
    let volume = volgraph_accel::generate::marschner_lobb(32);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    let compile = |runtime: &mut Runtime, options: &CompileOptions| {
        runtime.compile("modern/fastest.ron", &source, &registry, options).expect("compiles")
    };
    let plan = compile(&mut runtime, &CompileOptions::new(32, 32));
    runtime.bind_scene(&plan.inputs, &volume, &lut).expect("binds");
    let inputs = plan.inputs.clone();
    // Compiled again with the volume bound, as an application does: the scene values (the
    // volume's block size, 2 here against the graph's default 4) are the plan's from now on.
    let plan = compile(&mut runtime, &CompileOptions::new(32, 32));
    runtime.apply(plan, &registry).expect("applies");
    let frame = |runtime: &mut Runtime, azimuth: f64| {
        let camera = OrbitCamera { azimuth_deg: azimuth, ..OrbitCamera::default() };
        runtime.render(CameraData::from_orbit(&camera, (32, 32))).expect("frame");
    };
    for azimuth in [0.0, 10.0, 20.0] {
        frame(&mut runtime, azimuth);
    }
    assert_eq!(counts(&counters), [1, 1, 1, 3], "an orbit records the grid passes once, the raycast every frame");

    let sparse = TransferFunction::preset(Preset::Sparse, volume.value_range).to_lut_for(&volume, 256);
    runtime.bind_scene(&inputs, &volume, &sparse).expect("binds");
    frame(&mut runtime, 30.0);
    frame(&mut runtime, 40.0);
    assert_eq!(counts(&counters), [1, 2, 2, 5], "a new TF re-records what reads it and what reads that");

    runtime.bind_scene(&inputs, &volume, &sparse).expect("binds");
    frame(&mut runtime, 50.0);
    assert_eq!(counts(&counters), [1, 2, 2, 6], "binding equal content changes nothing");

    let other = volgraph_accel::generate::sphere(32, 0.6);
    runtime.bind_scene(&inputs, &other, &sparse).expect("binds");
    frame(&mut runtime, 60.0);
    assert_eq!(counts(&counters), [2, 3, 3, 7], "a new volume re-records all three");

    let edited = compile(&mut runtime, &CompileOptions::new(32, 32).with_param("march", "threshold", 0.9));
    runtime.apply(edited, &registry).expect("applies");
    frame(&mut runtime, 70.0);
    assert_eq!(counts(&counters), [2, 3, 3, 8], "editing the raycast leaves the grid passes alone");

    let edited = compile(&mut runtime, &CompileOptions::new(32, 32).with_scalar("block_size", 8.0));
    runtime.apply(edited, &registry).expect("applies");
    frame(&mut runtime, 80.0);
    assert_eq!(counts(&counters), [3, 4, 4, 9], "a new block size rebuilds the grid and everything after it");
}
