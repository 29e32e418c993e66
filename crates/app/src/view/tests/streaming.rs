//! The viewer on an OME-Zarr store with the streaming graph (issue 48 item 3): the session
//! holds the coarsest level only, binds the store as a pyramid, and frames refine as bricks
//! arrive — the panel's line counts them down to none pending; a graph edit re-applied keeps
//! the store streamed (the pass keeps its pool); the live accuracy measure, which would compare
//! the full image with the coarsest level, is not taken.

use super::*;

#[test]
fn the_viewer_streams_a_store_and_refines_as_bricks_arrive() {
    let s = scratch("streaming", "graphs/streaming/ray_guided.ron");
    let store = s.dir.join("v.ome.zarr");
    let volume = volgraph_accel::generate::by_name("vessels128").expect("generated");
    let mut source = volgraph_zarr::InMemory(volume);
    volgraph_zarr::write_pyramid(
        &mut source,
        &store,
        &volgraph_zarr::WriteOptions { chunk: 32, ..Default::default() },
        &mut |_, _| (),
    )
    .expect("a store");
    let args = SessionArgs { viewport: (64, 64), ..session_args(&s, &[store.to_str().expect("utf-8")], None) };
    let (mut session, loaded) = LiveSession::open(gpu(), &args).unwrap_or_else(|_| panic!("the store opens"));
    assert!(matches!(loaded, Event::Loaded { .. }), "{loaded}");
    assert_eq!(session.volume().dims, glam::UVec3::splat(64), "the session holds the coarsest level, not 128³");
    // Close enough that a level-1 voxel (2 of level 0) is wider than a pixel: level 0 is wanted.
    let camera = OrbitCamera { distance: 1.6, ..OrbitCamera::default() };
    let line = |session: &LiveSession| crate::render::counter_lines(&session.runtime.pass_counters()).join(" ");
    frames(&mut session, 1, &camera);
    assert!(line(&session).contains("2 levels; 1 of 9 bricks read"), "{}", line(&session));
    let mut done = false;
    for _ in 0..50 {
        session.runtime.wait_for_background(std::time::Duration::from_secs(5));
        frames(&mut session, 1, &camera);
        let progress = crate::stream_progress::StreamProgress::of(&session.runtime.pass_counters());
        if progress.iter().all(crate::stream_progress::StreamProgress::complete) {
            done = true;
            break;
        }
    }
    assert!(done && line(&session).contains("0 pending"), "{}", line(&session));
    // The session holds the coarsest level only: no reference to compare the full image with
    // (one over the coarsest level said "max 253/255" of a right image).
    assert!(session.accuracy_job(&camera).is_none(), "no accuracy measure of a streamed volume");
    let read_before = crate::stream_progress::StreamProgress::of(&session.runtime.pass_counters())[0].read;
    assert!(read_before > 1.0, "finer bricks were read");
    // A graph edit (the step) re-applies the plan: the store stays bound, its bricks stay.
    edit(&s.graph, "\"step_voxels\": Scalar(0.5)", "\"step_voxels\": Scalar(0.75)");
    let events = session.files_changed(std::slice::from_ref(&s.graph));
    assert!(events.iter().all(|e| !matches!(e, Event::Error { .. })), "{events:?}");
    frames(&mut session, 2, &camera);
    let after = crate::stream_progress::StreamProgress::of(&session.runtime.pass_counters());
    assert!(after[0].read >= read_before && after[0].levels == 2.0, "{}", line(&session));
}
