//! The label list on a live session (issue "several volumes", item 5): a label map opened with
//! `multi/labels` lists its labels by the names its file gives; showing one label alone is a
//! table upload — the plan and its pipelines stay — and the next frame shows only it; the value
//! under the cursor names its label.

use volgraph_accel::camera::OrbitCamera;

use super::{frame, gpu, scratch, session_args};
use crate::view::label_list::LabelEdit;
use crate::view::session::{Event, LiveSession, SessionArgs};

#[test]
fn a_label_shown_alone_is_a_table_upload_and_the_cursor_names_it() {
    let s = scratch("labels", "graphs/multi/labels.ron");
    let args = session_args(&s, &["organs_labels32"], None);
    let (mut session, _) = LiveSession::open(gpu(), &args).unwrap_or_else(|_| panic!("multi/labels opens"));
    let list = session.labels().expect("a label list");
    let names: Vec<&str> = list.rows.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["liver", "left kidney", "right kidney", "spleen", "aorta", "vertebra"]);
    let all = frame(&mut session);
    let covered = |image: &[f32]| image.chunks(4).filter(|p| p[3] > 0.01).count();
    let plan = session.plan().map(|p| p.to_text());
    let events = session.edit_labels(&LabelEdit::ShowOnly(6));
    let [Event::Reloaded { what, detail, .. }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!((what.as_str(), detail.as_str()), ("label table", "uploaded (no recompile)"));
    assert_eq!(session.plan().map(|p| p.to_text()), plan, "the plan stays");
    let vertebra = frame(&mut session);
    assert!(
        covered(&vertebra) > 0 && covered(&vertebra) < covered(&all),
        "{} of {}",
        covered(&vertebra),
        covered(&all)
    );
    session.edit_labels(&LabelEdit::ShowAll);
    assert_eq!(frame(&mut session), all, "every label again: the first image");
    // The centre of the view lies on an organ, which the probe names.
    let line = session.probe_line(&OrbitCamera::default(), (24.0, 24.0)).expect("something under the cursor");
    assert!(line.contains(", label "), "{line}");
}

/// `view multi/ct_with_labels --volume volume=… --volume labels=…`: the viewer binds inputs by
/// name as `render` does; the label list is the `labels` volume's (the organ phantom's names),
/// and a TF edit leaves a named TF alone.
#[test]
fn the_viewer_binds_volumes_by_name_and_lists_the_label_maps_labels() {
    let s = scratch("named", "graphs/multi/ct_with_labels.ron");
    let args = SessionArgs {
        named: vec![("volume".into(), "organs32".into()), ("labels".into(), "organs_labels32".into())],
        ..session_args(&s, &["organs32"], Some("ct-soft-tissue".into()))
    };
    let (mut session, _) = LiveSession::open(gpu(), &args).unwrap_or_else(|_| panic!("ct_with_labels opens"));
    let list = session.labels().expect("the labels volume's list");
    assert_eq!(list.rows.first().map(|r| r.name.as_str()), Some("liver"));
    let tinted = frame(&mut session);
    assert!(tinted.chunks(4).any(|p| p[3] > 0.01), "the scan shows");
    // Every label hidden: the scan alone, in its own colours.
    for value in 1..=6 {
        session.edit_labels(&LabelEdit::Visible(value, false));
    }
    let plain = frame(&mut session);
    assert_ne!(plain, tinted, "the labels tinted the scan");
    // A saved view holds one volume: refused with what to do instead.
    let err = session.saved_view(&OrbitCamera::default(), (48, 48)).map(drop).expect_err("several volumes");
    assert!(err.to_string().contains("binds others by name (labels)"), "{err}");
}
