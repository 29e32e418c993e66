//! Pass declarations for the compiler's integration tests, which compile graph files with no GPU
//! stack at all (`malformed_graphs`, `fuzz_graphs`, ...).
//!
//! Their ports mirror the built-in passes of `volgraph-passes` (`entry_points`,
//! `ray_directions`, `raycast`, `present`) and the passes the papers' pipelines need
//! (`raycast_segment`, `termination_test` for Krüger–Westermann's multipass loop;
//! `reprojection_splat`, `hole_fill`, `antialias` for Klein et al.), so error messages read as
//! they would for real graphs. They are declarations only (`PassDecl`): nothing is ever created.

#![allow(dead_code, reason = "each test file uses a different subset of the helpers")]

use volgraph_compiler::params::ParamSpec;
use volgraph_compiler::{Kinds, PassDecl, PortKind, PortSpec, TargetFormat};

/// Float targets the ray passes accept (first is the default for outputs).
pub const FLOAT_TARGETS: [TargetFormat; 2] = [TargetFormat::Rgba32Float, TargetFormat::Rgba16Float];

/// A pass kind described as data.
pub struct TestPlugin {
    /// `kind:` name.
    pub kind: &'static str,
    /// Ports for the default parameters.
    pub ports: Vec<PortSpec>,
    /// Extra ports when `mode` is `"iso"` (the raycaster's `hit`).
    pub iso_ports: Vec<PortSpec>,
    /// Declared parameters.
    pub params: Vec<ParamSpec>,
    /// Scene features the kind serves.
    pub features: Vec<&'static str>,
}

impl TestPlugin {
    fn new(kind: &'static str, ports: Vec<PortSpec>) -> Self {
        Self { kind, ports, iso_ports: Vec::new(), params: Vec::new(), features: Vec::new() }
    }
}

impl PassDecl for TestPlugin {
    fn kind(&self) -> &'static str {
        self.kind
    }

    fn summary(&self) -> &'static str {
        "test plugin: declares ports, records nothing"
    }

    fn params(&self) -> Vec<ParamSpec> {
        self.params.clone()
    }

    fn ports(&self, params: &volgraph_compiler::Params) -> Vec<PortSpec> {
        let mut ports = self.ports.clone();
        if params.declares("mode") && params.choice("mode") == "iso" {
            ports.extend(self.iso_ports.iter().cloned());
        }
        ports
    }

    fn features(&self) -> Vec<&'static str> {
        self.features.clone()
    }
}

fn raycast_params() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("step_voxels", 0.5, 0.01, 16.0, "sample distance in units of the smallest voxel side"),
        ParamSpec::float("threshold", 1.0, 0.0, 1.0, "early ray termination once accumulated alpha reaches this"),
        ParamSpec::uint("max_steps", 4096, 1, 1 << 20, "upper bound on samples per ray"),
        ParamSpec::boolean("jitter", false, "offset each ray's first sample by a per-pixel hash"),
        ParamSpec::choice("mode", "dvr", &["dvr", "iso"], "direct volume rendering or first-hit isosurface"),
        ParamSpec::float("iso_value", 0.5, 0.0, 1.0, "isovalue in normalized scalar units"),
        // The scene effects graphs wire to features ("feature.shading").
        ParamSpec::boolean("shading", false, "gradient shading"),
        ParamSpec::boolean("preintegration", false, "pre-integrated classification"),
        ParamSpec::boolean("tricubic", false, "tricubic reconstruction"),
        ParamSpec::boolean("shadows", false, "light volume shadows"),
        ParamSpec::boolean("ambient_occlusion", false, "ambient occlusion"),
    ]
}

/// The test registry: built-in look-alikes plus the papers' passes.
pub fn registry() -> Kinds {
    let t = PortKind::target;
    let mut r = Kinds::new();
    r.register(TestPlugin::new("entry_points", vec![PortSpec::write("entry", t(&FLOAT_TARGETS))]));
    r.register(TestPlugin::new(
        "ray_directions",
        vec![PortSpec::read("entry", t(&FLOAT_TARGETS)), PortSpec::write("dir", t(&FLOAT_TARGETS))],
    ));
    let ray_inputs = || {
        vec![
            PortSpec::read("entry", t(&FLOAT_TARGETS)),
            PortSpec::read("dir", t(&FLOAT_TARGETS)),
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
        ]
    };
    let mut raycast_ports = ray_inputs();
    raycast_ports.push(PortSpec::write("color", t(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])));
    r.register(TestPlugin {
        params: raycast_params(),
        iso_ports: vec![PortSpec::write("hit", t(&FLOAT_TARGETS))],
        ..TestPlugin::new("raycast", raycast_ports)
    });
    let mut compute_ports = ray_inputs();
    compute_ports.push(PortSpec::write("color", t(&[TargetFormat::Rgba16Float])));
    let mut compute_params = raycast_params();
    compute_params.push(ParamSpec::uint("workgroup_x", 8, 1, 256, "workgroup width in pixels"));
    compute_params.push(ParamSpec::uint("workgroup_y", 8, 1, 256, "workgroup height in pixels"));
    r.register(TestPlugin { params: compute_params, ..TestPlugin::new("raycast_compute", compute_ports) });
    r.register(TestPlugin {
        params: vec![ParamSpec::float("background", 0.0, 0.0, 1.0, "linear grey level behind the volume")],
        ..TestPlugin::new(
            "present",
            vec![
                PortSpec::read("color", t(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
                PortSpec::write("display", t(&[TargetFormat::Rgba8Unorm])),
            ],
        )
    });
    // Krüger–Westermann 2003 multipass: cleared accumulation and depth, then segments.
    r.register(TestPlugin::new(
        "clear_targets",
        vec![
            PortSpec::write("color", t(&[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float])),
            PortSpec::write("depth", t(&[TargetFormat::Depth32Float])),
        ],
    ));
    let mut segment_ports = ray_inputs();
    segment_ports.extend([
        PortSpec::read("accum", t(&[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float])),
        PortSpec::modify("depth", t(&[TargetFormat::Depth32Float])),
        PortSpec::write("color", t(&[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float])),
    ]);
    r.register(TestPlugin {
        params: vec![ParamSpec::uint("steps", 8, 1, 1024, "samples per segment (the paper's M)")],
        ..TestPlugin::new("raycast_segment", segment_ports)
    });
    r.register(TestPlugin {
        params: vec![ParamSpec::float("alpha", 0.95, 0.0, 1.0, "opacity above which a ray terminates (the paper's T)")],
        ..TestPlugin::new(
            "termination_test",
            vec![
                PortSpec::read("color", t(&[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float])),
                PortSpec::modify("depth", t(&[TargetFormat::Depth32Float])),
            ],
        )
    });
    // Klein et al. 2005: start positions from the previous frame's hits.
    r.register(TestPlugin::new(
        "reprojection_splat",
        vec![PortSpec::read("hit", t(&FLOAT_TARGETS)), PortSpec::write("start", t(&FLOAT_TARGETS))],
    ));
    r.register(TestPlugin::new(
        "hole_fill",
        vec![
            PortSpec::read("start", t(&FLOAT_TARGETS)),
            PortSpec::read("entry", t(&FLOAT_TARGETS)),
            PortSpec::write("filled", t(&FLOAT_TARGETS)),
        ],
    ));
    r.register(TestPlugin {
        features: vec!["antialias"],
        ..TestPlugin::new(
            "antialias",
            vec![
                PortSpec::read("color", t(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
                PortSpec::read("hit", t(&FLOAT_TARGETS)),
                PortSpec::write("smooth", t(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
            ],
        )
    });
    r
}
