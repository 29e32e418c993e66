//! `reslice` (graphs/clinical/slices.ron) against its f64 twin `volgraph_accel::reslice`: the
//! three panes of a CT in HU on an anisotropic grid, at a position between voxel centres, through
//! the file's window and through one given in HU; and a crosshair move as a parameter written in
//! place (nothing rebuilt).

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reslice::{SliceAxis, SlicePlane, reslice};
use volgraph_accel::volume::Volume;
use volgraph_accel::volume_meta::Window;
use volgraph_core::CompileOptions;
use volgraph_core::runtime::{CameraData, Image, Runtime};
use volgraph_passes::builtin_registry;

mod support;

use support::{gpu, graph_source, render_once};

const GRAPH: &str = "clinical/slices.ron";
/// Panes wider than the head is tall in two of them: the fit letterboxes along both axes.
const PANE: (u32, u32) = (120, 88);

/// The synthetic CT (i16 HU, spacing 1 × 1 × 2 mm) with a soft-tissue window in its header.
fn ct() -> Volume {
    let mut ct = volgraph_accel::organs::organs_ct(64);
    ct.meta.window = Some(Window { center: 40.0, width: 400.0 });
    ct
}

fn options(overrides: &[(&str, ron::Value)]) -> CompileOptions {
    let mut options = CompileOptions::new(PANE.0, PANE.1);
    for (name, value) in overrides {
        options.param_overrides.insert((*name).to_string(), value.clone());
    }
    options
}

fn render(volume: &Volume, overrides: &[(&str, ron::Value)]) -> Runtime {
    let camera = OrbitCamera::default();
    let (runtime, _) = render_once(
        &gpu(),
        &builtin_registry(),
        GRAPH,
        &graph_source(GRAPH),
        &options(overrides),
        volume,
        &[],
        &camera,
    )
    .expect("the slice graph renders");
    runtime
}

/// Compares a pane with the f64 slice. The target holds 8 bits: a grey level rounds to the
/// nearest code, so a pixel may differ by half a code plus the f32 error of the trilinear filter
/// (16-bit normalized texels, weights in f32 on lavapipe: ~1e-6 of the value range) amplified by
/// the window (range / width ≈ 11 for 400 HU over ~4400 HU): ~0.01 of a code, so 0.75 bounds it
/// (measured: 0.51). A sample half a voxel off would miss by tens of codes at the organs' edges.
/// A pixel whose centre lies on the slice's edge may fall either side in f32: pixels within
/// 1e-3 px of it are left out (none in these panes, which is checked).
fn assert_pane_matches(pane: &Image, volume: &Volume, plane: SlicePlane, window: Window) -> (usize, f64) {
    let expected = reslice(volume, plane, window, PANE);
    let fit = volgraph_accel::reslice::PaneFit::of(plane.axis, volume.dims, volume.spacing, PANE);
    let (mut inside, mut worst, mut on_edge) = (0usize, 0.0f64, 0usize);
    for y in 0..PANE.1 {
        for x in 0..PANE.0 {
            let f = fit.fractions(glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
            let edge = [f.x * fit.size.x, (1.0 - f.x) * fit.size.x, f.y * fit.size.y, (1.0 - f.y) * fit.size.y]
                .iter()
                .any(|d| d.abs() < 1e-3);
            if edge {
                on_edge += 1;
                continue;
            }
            let got = pane.rgba(x, y);
            match expected[(y * PANE.0 + x) as usize] {
                Some(grey) => {
                    inside += 1;
                    assert_eq!(got[3], 1.0, "{:?} ({x}, {y}): on the slice", plane.axis);
                    let off = (f64::from(got[0]) - grey).abs() * 255.0;
                    worst = worst.max(off);
                    assert!(off <= 0.75, "{:?} ({x}, {y}): {:.3} vs {:.3} ({off:.2} codes)", plane.axis, got[0], grey);
                }
                None => assert_eq!(got, [0.0; 4], "{:?} ({x}, {y}): beside the slice", plane.axis),
            }
        }
    }
    assert_eq!(on_edge, 0, "{:?}: no pixel centre on the slice's edge in these panes", plane.axis);
    (inside, worst)
}

#[test]
fn the_three_panes_are_their_f64_slices_through_the_files_window() {
    let volume = ct();
    // Between voxel centres on every axis: the filter interpolates along the normal too.
    let position = 0.437;
    let overrides = SliceAxis::ALL.map(|a| (a.name(), ron::Value::from(position as f32)));
    let keys: Vec<String> = overrides.iter().map(|(a, _)| format!("{a}.position")).collect();
    let overrides: Vec<(&str, ron::Value)> = keys.iter().zip(overrides).map(|(k, (_, v))| (k.as_str(), v)).collect();
    let mut runtime = render(&volume, &overrides);
    for axis in SliceAxis::ALL {
        let pane = runtime.read_output(axis.name()).expect("a pane per plane");
        let plane = SlicePlane { axis, position: f64::from(position as f32) };
        let (inside, worst) = assert_pane_matches(&pane, &volume, plane, Window { center: 40.0, width: 400.0 });
        eprintln!("{}: {inside} pixels on the slice, worst {worst:.2} codes", axis.name());
        // The slice fills the pane along one axis at least (the fit is the largest one).
        assert!(inside as f64 > 0.35 * (PANE.0 * PANE.1) as f64, "{}: {inside} pixels", axis.name());
    }
}

#[test]
fn a_window_in_hu_and_a_crosshair_move_are_written_in_place() {
    let volume = ct();
    let bone =
        [("axial.window_center", ron::Value::from(400.0f32)), ("axial.window_width", ron::Value::from(1800.0f32))];
    let mut runtime = render(&volume, &bone);
    let window = Window { center: 400.0, width: 1800.0 };
    let before = runtime.read_output("axial").expect("axial");
    assert_pane_matches(&before, &volume, SlicePlane { axis: SliceAxis::Axial, position: 0.5 }, window);

    // The crosshair moves down 5 slices of 32: a parameter, written in place.
    let position = (10.5 / 32.0) as f32;
    let moved = [bone[0].clone(), bone[1].clone(), ("axial.position", ron::Value::from(position))];
    let plan =
        volgraph_core::compile(GRAPH, &graph_source(GRAPH), &builtin_registry(), &options(&moved)).expect("compiles");
    let report = runtime.apply(plan, &builtin_registry()).expect("applies");
    assert_eq!((report.nodes_created, report.pipelines_built), (0, 0), "a move rebuilds nothing: {report:?}");
    assert!(report.nodes_updated >= 1, "{report:?}");
    runtime.render(CameraData::from_orbit(&OrbitCamera::default(), PANE)).expect("renders");
    let after = runtime.read_output("axial").expect("axial");
    let plane = SlicePlane { axis: SliceAxis::Axial, position: f64::from(position) };
    assert_pane_matches(&after, &volume, plane, window);
    let changed = (0..PANE.1)
        .flat_map(|y| (0..PANE.0).map(move |x| (x, y)))
        .filter(|&(x, y)| before.rgba(x, y) != after.rgba(x, y))
        .count();
    assert!(changed > 100, "another slice shows other tissue ({changed} pixels changed)");
}

/// `clinical/slices_labels` rendered with `labels` over `volume` (the organ phantom's table).
fn render_with_labels(volume: &Volume, labels: &Volume, table: &[[f32; 4]], position: f32) -> Runtime {
    const LABELLED: &str = "clinical/slices_labels.ron";
    let registry = builtin_registry();
    let overrides: Vec<(String, ron::Value)> =
        SliceAxis::ALL.iter().map(|a| (format!("{}.position", a.name()), ron::Value::from(position))).collect();
    let overrides: Vec<(&str, ron::Value)> = overrides.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let plan = volgraph_core::compile(LABELLED, &graph_source(LABELLED), &registry, &options(&overrides))
        .expect("the labelled slice graph compiles");
    let mut runtime = support::runtime(&gpu());
    runtime.bind_volume("volume", volume).expect("volume");
    runtime.bind_volume("labels", labels).expect("labels");
    runtime.bind_label_table("label_table", table).expect("table");
    runtime.apply(plan, &registry).expect("applies");
    runtime.render(CameraData::from_orbit(&OrbitCamera::default(), PANE)).expect("renders");
    runtime
}

/// A segmentation over the slices, on the scan's grid and on one of half its resolution (the
/// same box): each pane is its f64 twin (`reslice_with_labels`). Grey and label colours blend
/// in f32 and round to 8 bits (≤ 0.75 codes, as the grey alone); where a pixel centre lies on a
/// boundary between two label voxels (exactly, in f64) f32 may take the other voxel — such
/// pixels are counted and must stay under 0.5 % of the pane.
#[test]
fn a_label_map_over_the_panes_is_its_f64_twin_on_its_own_grid_or_a_coarser_one() {
    use volgraph_accel::reslice::{LabelOverlay, reslice_with_labels};
    let volume = ct();
    let table = volgraph_accel::organs::label_table().lut(256);
    let same = volgraph_accel::organs::organs_labels(64);
    // Half the resolution over the same box: voxels twice the size, voxel (0,0,0)'s centre half a
    // (coarse) voxel in from the scan's corner.
    let mut coarse = volgraph_accel::organs::organs_labels(32);
    coarse.spacing *= 2.0;
    coarse.meta.origin = Some(glam::DVec3::new(0.5, 0.5, 1.0));
    let mut scan = volume.clone();
    scan.meta.origin = Some(glam::DVec3::ZERO);
    let position = 0.437f32;
    for (name, labels, volume) in [("same grid", &same, &volume), ("half resolution", &coarse, &scan)] {
        let mut runtime = render_with_labels(volume, labels, &table, position);
        let overlay = LabelOverlay { labels, table: &table, opacity: 0.5 };
        let window = Window { center: 40.0, width: 400.0 };
        for axis in SliceAxis::ALL {
            let pane = runtime.read_output(axis.name()).expect("a pane");
            let plane = SlicePlane { axis, position: f64::from(position) };
            let expected = reslice_with_labels(volume, plane, window, PANE, &overlay).expect("one frame");
            let (mut coloured, mut ties, mut worst) = (0usize, 0usize, 0.0f64);
            for (i, e) in expected.iter().enumerate() {
                let got = pane.rgba(i as u32 % PANE.0, i as u32 / PANE.0);
                let Some(e) = e else {
                    assert_eq!(got, [0.0; 4], "{name} {axis:?} {i}: beside the slice");
                    continue;
                };
                coloured += usize::from(e[0] != e[1] || e[1] != e[2]);
                let off = (0..3).map(|c| (f64::from(got[c]) - e[c]).abs() * 255.0).fold(0.0, f64::max);
                if off > 0.75 {
                    ties += 1;
                } else {
                    worst = worst.max(off);
                }
            }
            eprintln!(
                "{name} {}: {coloured} labelled pixels, {ties} boundary ties, worst {worst:.2} codes",
                axis.name()
            );
            // The organs (the body itself is label 0, hidden) cover a few hundred pixels a pane.
            assert!(coloured > 100, "{name} {axis:?}: the organs show ({coloured} pixels)");
            assert!(ties * 200 < expected.len(), "{name} {axis:?}: {ties} pixels differ by more than 0.75 codes");
        }
    }
}
