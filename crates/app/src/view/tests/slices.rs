//! The slice panes through the session, as the window drives them: opened on the session's
//! volume, a click on a pane moves the crosshair within its plane, the wheel steps one slice a
//! notch, a window preset — and every pane rendered is its f64 slice
//! (`volgraph_accel::reslice`), within the 8-bit rounding of the target.

use glam::DVec2;
use volgraph_accel::reslice::{SliceAxis, reslice};
use volgraph_accel::volume_meta::Window;

use super::super::slice_panes::{FourUp, SlicePanes};
use super::{LiveSession, SessionArgs, gpu, scratch, session_args};

/// Each pane against the f64 slice through the same crosshair: half a code of rounding and the
/// f32 filter's error (crates/passes/tests/reslice.rs measures 0.51 codes at worst).
fn assert_panes_match(session: &mut LiveSession, pane: (u32, u32)) {
    let volume = session.volume().clone();
    let panes = session.slices_mut().expect("open");
    assert!(panes.update(pane).expect("renders"), "a change renders");
    assert!(!panes.update(pane).expect("renders"), "nothing changed: nothing rendered");
    for axis in SliceAxis::ALL {
        let expected = reslice(&volume, panes.plane(axis), panes.view.window, pane);
        let image = panes.read(axis).expect("a pane");
        let worst = expected
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let got = image.rgba(i as u32 % pane.0, i as u32 / pane.0);
                e.map_or(f64::from(got[3]), |grey| (f64::from(got[0]) - grey).abs() * 255.0)
            })
            .fold(0.0, f64::max);
        assert!(worst <= 0.75, "{}: {worst:.2} codes from the f64 slice", axis.name());
    }
}

#[test]
fn a_click_moves_the_crosshair_the_wheel_steps_a_slice_and_the_panes_stay_their_f64_slices() {
    let s = scratch("slices", "graphs/basic/fragment_raycast.ron");
    let (mut session, _) =
        LiveSession::open(gpu(), &session_args(&s, &["organs48"], None)).unwrap_or_else(|_| panic!("opens"));
    assert!(session.set_slice_panes(true).is_empty());
    let layout = FourUp::of((200, 160));
    let pane = layout.pane();
    assert_eq!(pane, (100, 80));
    assert_panes_match(&mut session, pane);

    let panes = session.slices_mut().expect("open");
    let start = panes.view.crosshair;
    // The central voxel: 48 × 48 × 24 voxels, the crosshair on voxel centres.
    assert_eq!(panes.crosshair_voxel().to_array(), [24.5, 24.5, 12.5]);
    // A click on the coronal pane at its slice's upper-left quarter point: x and z move, y
    // (the coronal plane's own position) stays.
    let fit = panes.fit(SliceAxis::Coronal, pane);
    panes.click(SliceAxis::Coronal, pane, fit.point(DVec2::new(0.25, 0.25)));
    let moved = panes.view.crosshair;
    assert!((moved.x - 0.25).abs() < 1e-9 && (moved.z - 0.75).abs() < 1e-9, "{moved}");
    assert_eq!(moved.y, start.y);
    // The crosshair shows in the other panes where it was put.
    let axial = panes.crosshair_in(SliceAxis::Axial, pane);
    let axial_fit = panes.fit(SliceAxis::Axial, pane);
    assert!((axial_fit.fractions(axial).x - 0.25).abs() < 1e-9);
    // Three notches up on the axial pane: three slices up, onto voxel centres.
    let before = panes.slice_index(SliceAxis::Axial);
    panes.scroll(SliceAxis::Axial, 3);
    assert_eq!(panes.slice_index(SliceAxis::Axial), before + 3);
    // Past the last slice it stops there.
    panes.scroll(SliceAxis::Axial, 1000);
    assert_eq!(panes.slice_index(SliceAxis::Axial), 23);
    panes.scroll(SliceAxis::Axial, -5);
    // The bone window, as the panel's preset gives it.
    panes.view.window = Window { center: 400.0, width: 1800.0 };
    assert_panes_match(&mut session, pane);

    // Closed, the panes' runtime is gone; opened again, the crosshair starts at the centre.
    assert!(session.set_slice_panes(false).is_empty());
    assert!(session.slices().is_none());
    session.set_slice_panes(true);
    assert_eq!(session.slices().map(|p| p.crosshair_voxel().to_array()), Some([24.5, 24.5, 12.5]));
    let _ = std::fs::remove_dir_all(&s.dir);
}

#[test]
fn the_panes_open_on_the_files_window_else_the_value_range() {
    let mut ct = volgraph_accel::organs::organs_ct(32);
    ct.meta.window = Some(Window { center: 40.0, width: 400.0 });
    let panes = SlicePanes::new(gpu(), &ct, None).expect("opens");
    assert_eq!(panes.view.window, Window { center: 40.0, width: 400.0 });
    ct.meta.window = None;
    let panes = SlicePanes::new(gpu(), &ct, None).expect("opens");
    let (lo, hi) = ct.value_range;
    assert_eq!(panes.view.window, Window { center: 0.5 * (lo + hi), width: hi - lo });
}

/// The panel's Slices and Save image sections at 800×600, driven with egui's test harness: the
/// CT presets, the planes-in-3D and panes checkboxes, a size preset and "save image" ask for
/// what they say, and the foot's buttons stay in the window.
#[test]
fn the_slices_and_save_image_sections_ask_for_what_they_say() {
    use super::super::panel::{Action, Timings, show};
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable as _;

    let s = scratch("slices-panel", "graphs/basic/fragment_raycast.ron");
    let (mut session, _) =
        LiveSession::open(gpu(), &session_args(&s, &["organs32"], None)).unwrap_or_else(|_| panic!("opens"));
    assert!(session.set_slice_panes(true).is_empty());
    let window = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::Vec2::new(800.0, 600.0));
    let (timings, lod) = (Timings::default(), super::super::lod::Lod::default());
    let mut h = Harness::builder().with_size(window.size()).build_ui_state(
        |ui, asked: &mut Vec<Action>| {
            asked.extend(show(ui, &session, &timings, "lavapipe", None, &lod, "").actions);
        },
        Vec::new(),
    );
    h.run();
    // Scrolled into view first (the sections lie below the TF editor), then clicked where it
    // is, as a user would.
    let clicked = |h: &mut Harness<'_, Vec<Action>>, label: &str| {
        h.get_by_label(label).scroll_to_me();
        h.run();
        h.state_mut().clear();
        h.get_by_label(label).click();
        h.run();
        std::mem::take(h.state_mut())
    };
    let bone = clicked(&mut h, "bone");
    assert!(matches!(bone.as_slice(), [Action::SliceWindow(w)] if (w.center, w.width) == (400.0, 1800.0)), "{bone:?}");
    let planes = clicked(&mut h, "the planes in the 3D view");
    assert!(matches!(planes.as_slice(), [Action::SlicePlanesIn3d(false)]), "{planes:?}");
    let close = clicked(&mut h, "axial, coronal, sagittal panes (M)");
    assert!(matches!(close.as_slice(), [Action::SlicePanes(false)]), "{close:?}");
    clicked(&mut h, "Save image");
    clicked(&mut h, "4K");
    let save = clicked(&mut h, "save image");
    assert!(
        matches!(save.as_slice(), [Action::SaveImage { size: (3840, 2160), path }] if path.ends_with("volgraph_image.png")),
        "{save:?}"
    );
    for button in ["screenshot", "save view"] {
        let rect = h.get_by_label(button).rect();
        assert!(window.contains_rect(rect), "\"{button}\" at {rect:?} is outside the window");
    }
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// A graph with a segmentation over its scan (`multi/ct_with_labels`): the panes show the label
/// map too, coloured as the label list says; hiding every label but one (the list's "show only")
/// takes the others off the panes as well — one table upload, the panes rendered again.
#[test]
fn the_panes_show_the_label_map_as_the_label_list_colours_it() {
    use super::super::label_list::LabelEdit;
    let s = scratch("slices-labels", "graphs/multi/ct_with_labels.ron");
    let args = SessionArgs {
        named: vec![("volume".into(), "organs48".into()), ("labels".into(), "organs_labels48".into())],
        ..session_args(&s, &["organs48"], Some("ct-soft-tissue".into()))
    };
    let (mut session, _) = LiveSession::open(gpu(), &args).unwrap_or_else(|_| panic!("opens"));
    assert!(session.set_slice_panes(true).is_empty());
    let pane = (96, 72);
    let coloured = |session: &mut LiveSession| {
        let panes = session.slices_mut().expect("open");
        assert!(panes.labelled(), "the label map lies over the panes");
        panes.update(pane).expect("renders");
        let image = panes.read(SliceAxis::Coronal).expect("a pane");
        image.data.chunks(4).filter(|p| (p[0] - p[1]).abs() > 0.02 || (p[1] - p[2]).abs() > 0.02).count()
    };
    let all = coloured(&mut session);
    assert!(all > 200, "the organs show in colour ({all} pixels)");
    let shown = session.labels().expect("a label list").rows.iter().map(|r| r.value).min().expect("labels");
    let events = session.edit_labels(&LabelEdit::ShowOnly(shown));
    assert!(events.iter().all(|e| !matches!(e, super::Event::Error { .. })), "{events:?}");
    let one = coloured(&mut session);
    assert!(one < all, "only label {shown} keeps its colour ({one} of {all} pixels)");
    // The crosshair on a voxel of that organ: the panel's line names it, with the value in HU
    // and the place (the generated phantom has no origin, so by voxel rather than in mm).
    let map = volgraph_accel::organs::organs_labels(48);
    let i = (0..map.voxel_count()).find(|&i| map.raw_value(i) as u32 == shown).expect("the organ's voxels");
    let d = map.dims;
    let voxel =
        glam::DVec3::new((i as u32 % d.x) as f64, ((i as u32 / d.x) % d.y) as f64, (i as u32 / (d.x * d.y)) as f64);
    session.slices_mut().expect("open").view.crosshair = (voxel + 0.5) / d.as_dvec3();
    let line = session.crosshair_line().expect("a line");
    let name = session.labels().and_then(|l| l.name_of(shown)).expect("named").to_string();
    assert!(
        line.contains(&format!("label {shown} \"{name}\"")) && line.contains(" HU") && line.contains("at voxel (13.5"),
        "{line}"
    );
    let _ = std::fs::remove_dir_all(&s.dir);
}
