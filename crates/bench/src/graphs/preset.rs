//! The named benchmark presets (`--preset NAME`), written as data: which graphs, datasets,
//! viewports and transfer functions each paper's comparison needs, and the baseline its speed-ups
//! are measured against.

use super::antialias_study::AntialiasStudy;
use super::peer::PeerSpec;

/// One preset: everything `volgraph bench graphs --preset NAME` runs unless a flag overrides it.
#[derive(Clone, Copy, Debug)]
pub struct BenchPreset {
    /// The name given to `--preset`.
    pub name: &'static str,
    /// What the preset reproduces, printed above the table.
    pub about: &'static str,
    /// Graph files, relative to the workspace root.
    pub graphs: &'static [&'static str],
    /// The baseline graph (file stem) speed-ups are relative to.
    pub baseline: &'static str,
    /// `(graph, its own baseline)` pairs (file stems): rows of `graph` are measured against
    /// that graph instead of `baseline` (e.g. each leaping graph against its plain twin).
    pub baselines: &'static [(&'static str, &'static str)],
    /// Dataset names (`volgraph_accel::data_dir` names or generated names such as `ml64`).
    pub datasets: &'static [&'static str],
    /// Viewports `(width, height)` before `--scale`.
    pub viewports: &'static [(u32, u32)],
    /// Transfer functions (`default`, `opaque`, `sparse`, or names in `$VOLGRAPH_DATA/tf`); every
    /// dataset is measured with every one.
    pub tfs: &'static [&'static str],
    /// `(dataset, transfer function)` pairs measured instead of datasets × tfs when not empty
    /// (a TF written for one dataset's values).
    pub cases: &'static [(&'static str, &'static str)],
    /// Parameter overrides applied to every graph, `"pass.param" = value` (e.g. the step the
    /// issue asks for).
    pub params: &'static [(&'static str, f64)],
    /// Overrides for one dataset's cases, `(dataset, knob, value)` (e.g. the isovalue that shows
    /// its surface, `input.iso_value`); they win over `params`.
    pub dataset_params: &'static [(&'static str, &'static str, f64)],
    /// Timed frames after the warm-up frame.
    pub frames: u32,
    /// Start camera (azimuth, elevation, distance), default 30,20,3.2.
    pub camera: Option<[f64; 3]>,
    /// Whether the timed frames cover a whole turn (360/frames degrees each) instead of 1°.
    pub full_turn: bool,
    /// A peer program measured in the same run (its rows join the table), if any.
    pub peer: Option<PeerSpec>,
    /// Klein et al. 2005 §5's antialiasing study, run after the table, if any.
    pub antialias: Option<AntialiasStudy>,
    /// Graphs whose pooled vs unpooled transient memory the report states, at a viewport.
    pub memory: &'static [(&'static str, (u32, u32))],
}

/// Every preset.
pub const PRESETS: &[BenchPreset] = &[
    BenchPreset {
        name: "basic",
        about: "First light: fragment vs compute raycast, hydrogen_atom 128³ at 512², step 0.5 voxel",
        graphs: &["graphs/basic/fragment_raycast.ron", "graphs/basic/compute_raycast.ron"],
        baseline: "fragment_raycast",
        datasets: &["hydrogen_atom"],
        viewports: &[(512, 512)],
        tfs: &["default"],
        params: &[("march.step_voxels", 0.5)],
        frames: 36,
        cases: &[],
        camera: None,
        full_turn: false,
        peer: None,
        baselines: &[],
        dataset_params: &[],
        antialias: None,
        memory: &[],
    },
    BenchPreset {
        name: "kw2003-table1",
        about: "Krüger & Westermann 2003 Table 1: SBVR vs RC, RC-a (early ray termination), RC-b (+ empty-space skipping) at 512²",
        graphs: &[
            "graphs/kruger_westermann_2003/sbvr.ron",
            "graphs/kruger_westermann_2003/rc.ron",
            "graphs/kruger_westermann_2003/rc_a.ron",
            "graphs/kruger_westermann_2003/rc_b.ron",
            "graphs/kruger_westermann_2003/rc_b_leap.ron",
            // The modern answer to the same question: one pass, leaping over empty blocks with
            // a DDA and terminating in the loop, beside the plain single pass.
            "graphs/basic/fragment_raycast.ron",
            "graphs/modern/single_pass_ess_ert.ron",
        ],
        baseline: "sbvr",
        datasets: &["engine_vollib", "hydrogen_atom", "neghip", "lobster", "fuel"],
        viewports: &[(512, 512)],
        tfs: &["opaque", "sparse"],
        params: &[],
        frames: 36,
        cases: &[],
        camera: None,
        full_turn: false,
        peer: None,
        baselines: &[],
        dataset_params: &[],
        antialias: None,
        memory: &[],
    },
    BenchPreset {
        name: "thesis-tables",
        about: "DirectCompute thesis Tables 1–4: pixel-shader vs compute-shader raycast at 800×600 and 1920×1080 over datasets of several sizes",
        graphs: &["graphs/compute_raycast_2013/pixel_shader.ron", "graphs/compute_raycast_2013/compute_shader.ron"],
        baseline: "pixel_shader",
        datasets: &["neghip", "hydrogen_atom", "engine_vollib"],
        viewports: &[(800, 600), (1920, 1080)],
        tfs: &["default"],
        params: &[],
        frames: 36,
        cases: &[],
        camera: None,
        full_turn: false,
        peer: None,
        baselines: &[],
        dataset_params: &[],
        antialias: None,
        memory: &[],
    },
    BenchPreset {
        name: "peer",
        about: "The peer comparison (issue \"the fastest path\"): VTK's CPU raycaster \
                (vtkFixedPointVolumeRayCastMapper), run in the same session by bench/peer/vtk_cpu_raycast.py, against \
                volgraph's graphs; 512², step 0.5 voxel, early termination at α ≥ 1 − 1/255, camera as VTK's reset \
                camera (azimuth 0, elevation 0, distance 3.2), 12 views over a full turn about y. Speed-up = VTK's \
                median / the row's (the issue's goal: ≥ 2×; its own VTK figures were 112–120, 144–154 and 116–124 ms)",
        graphs: &[
            "graphs/modern/single_pass_ess_ert.ron",
            "graphs/basic/compute_raycast.ron",
            "graphs/modern/fastest.ron",
        ],
        baseline: "vtk_fixed_point",
        datasets: &[],
        viewports: &[(512, 512)],
        tfs: &[],
        cases: &[("engine_vollib", "engine_opaque"), ("engine_vollib", "engine_sparse"), ("hydrogen_atom", "hydrogen")],
        params: &[("march.step_voxels", 0.5), ("march.threshold", 1.0 - 1.0 / 255.0)],
        frames: 12,
        camera: Some([0.0, 0.0, 3.2]),
        full_turn: true,
        peer: Some(PeerSpec {
            label: "vtk_fixed_point",
            about: "vtk_fixed_point: VTK's vtkFixedPointVolumeRayCastMapper on this machine's CPU cores, offscreen, \
                    timed per Render() by bench/peer/vtk_cpu_raycast.py in this run",
            script: "bench/peer/vtk_cpu_raycast.py",
            script_text: include_str!("../../../../bench/peer/vtk_cpu_raycast.py"),
            install: "install the peer with `pip install vtk==9.7.2`, or pass --no-peer",
        }),
        baselines: &[],
        dataset_params: &[],
        antialias: None,
        memory: &[],
    },
    BenchPreset {
        name: "klein2005",
        about: "Klein et al. 2005 Table 1: the plain single-pass raycast against empty-space leaping by reprojected \
                hit points, isosurface and DVR, while the volume turns 1° per frame at 512², step 0.5 voxel: \
                `leap_*` reproject them as per-tile depth bounds (reprojection_tiles), `leap_*_splats` as the paper's \
                per-pixel splats and hole fill, `leap_dvr_cubes` adds the paper's §6 suggestion (skip the empty \
                blocks behind the first visible sample too, by a min/max grid's distance map); samples per pixel with and without leaping counted on the GPU. \
                Speed-up: each leaping graph against its baseline (the paper: engine 1.8×, head 2.2×, foot 2.7×; \
                177 → 25 samples per pixel on its abdomen). tooth256 is the generated molar CT (volgraph_accel::tooth) \
                under the TF `volgraph render` fits to it, at the isovalue of a real surface, 0.45. Then §5's antialiasing study and the pooled memory of \
                leap_iso_aa at 1920×1080",
        graphs: &[
            "graphs/klein_2005/baseline_iso.ron",
            "graphs/klein_2005/leap_iso.ron",
            "graphs/klein_2005/leap_iso_splats.ron",
            "graphs/klein_2005/baseline_dvr.ron",
            "graphs/klein_2005/leap_dvr.ron",
            "graphs/klein_2005/leap_dvr_splats.ron",
            "graphs/klein_2005/leap_dvr_cubes.ron",
        ],
        baseline: "baseline_iso",
        baselines: &[
            ("leap_iso", "baseline_iso"),
            ("leap_iso_splats", "baseline_iso"),
            ("baseline_dvr", "baseline_dvr"),
            ("leap_dvr", "baseline_dvr"),
            ("leap_dvr_splats", "baseline_dvr"),
            ("leap_dvr_cubes", "baseline_dvr"),
        ],
        datasets: &[],
        viewports: &[(512, 512)],
        tfs: &[],
        cases: &[
            ("engine_vollib", "engine_sparse"),
            ("lobster", "default"),
            ("hydrogen_atom", "hydrogen"),
            ("neghip", "default"),
            ("tooth256", "fitted"),
        ],
        params: &[("input.step_voxels", 0.5)],
        dataset_params: &[
            ("engine_vollib", "input.iso_value", 0.3),
            ("lobster", "input.iso_value", 0.2),
            ("hydrogen_atom", "input.iso_value", 0.12),
            ("neghip", "input.iso_value", 0.25),
            ("tooth256", "input.iso_value", 0.45),
        ],
        frames: 24,
        camera: None,
        full_turn: false,
        peer: None,
        antialias: Some(AntialiasStudy {
            dataset: "engine_vollib",
            tf: "engine_sparse",
            iso_value: 0.3,
            size: (512, 512),
            reference_rays_per_side: 4,
            frames: 12,
        }),
        memory: &[("graphs/klein_2005/leap_iso_aa.ron", (1920, 1080))],
    },
    BenchPreset {
        name: "ruijters2006",
        about: "Ruijters & Vilanova 2006 Table 1: the same raycast over the whole volume in one texture \
                (unoptimized) against bricks, bricks + per-brick octrees, and + early ray termination, at 800², \
                1.5 samples per voxel (step 2/3 voxel), on the generated vessel tree (about 3 % visible under \
                graphs/tf/vessels.ron, like the paper's angiography: optimized vs unoptimized 7.66× on a QuadroFX \
                3400) and on the dense engine (the paper's ERT on a dense volume: 2.2 → 5.2 → 16.1 fps). Bricks \
                64³, node limit 4³ (the fastest of our Figure 6 sweep with 2³), ratio 1; uploads and pool occupancy \
                from the brick pass",
        graphs: &[
            "graphs/ruijters_vilanova_2006/unoptimized.ron",
            "graphs/ruijters_vilanova_2006/bricks.ron",
            "graphs/ruijters_vilanova_2006/bricks_octree.ron",
            "graphs/ruijters_vilanova_2006/bricks_octree_ert.ron",
        ],
        baseline: "unoptimized",
        baselines: &[],
        datasets: &[],
        viewports: &[(800, 800)],
        tfs: &[],
        cases: &[("vessels256", "graphs/tf/vessels.ron"), ("engine_vollib", "default")],
        params: &[("input.step_voxels", 0.6666666666666666)],
        dataset_params: &[],
        frames: 8,
        camera: None,
        full_turn: false,
        peer: None,
        antialias: None,
        memory: &[],
    },
    BenchPreset {
        name: "effects-off",
        about: "A graph that offers every scene effect, with the effects off, against the same graph written by hand \
                without them (graphs/bench/fastest_minimal.ron): the ratio should be 1 within noise",
        graphs: &["graphs/bench/fastest_minimal.ron", "graphs/modern/fastest.ron"],
        baseline: "fastest_minimal",
        datasets: &["ml64", "hydrogen_atom", "neghip"],
        viewports: &[(512, 512)],
        tfs: &["default"],
        cases: &[],
        params: &[],
        frames: 24,
        camera: None,
        full_turn: false,
        peer: None,
        baselines: &[],
        dataset_params: &[],
        antialias: None,
        memory: &[],
    },
];

/// The preset named `name`, if any.
pub fn find(name: &str) -> Option<&'static BenchPreset> {
    PRESETS.iter().find(|p| p.name == name)
}

/// The preset names, for messages.
pub fn names() -> String {
    PRESETS.iter().map(|p| p.name).collect::<Vec<_>>().join(", ")
}
