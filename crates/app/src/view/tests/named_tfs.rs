//! One TF editor per scalar volume (issue "several volumes", item 5): `view multi/pet_ct
//! --volume volume=CT --volume pet=PET --tf pet_tf=FILE` offers the CT's editor and the PET's;
//! an edit of one uploads that input's LUT alone (the other volume keeps its colours), and
//! "save TF" writes the edited one's own file.

use volgraph_accel::transfer_function::{ControlPoint, TransferFunction};

use super::{frame, gpu, scratch, session_args};
use crate::view::session::{Event, LiveSession, SessionArgs};

/// `tf` with every point's opacity 0: the volume it classifies disappears.
fn transparent(tf: &TransferFunction) -> TransferFunction {
    let points = tf.points.iter().map(|p| ControlPoint { alpha: 0.0, ..*p }).collect();
    TransferFunction { points, ..tf.clone() }
}

#[test]
fn each_scalar_volume_has_its_own_tf_editor() {
    let s = scratch("named-tfs", "graphs/multi/pet_ct.ron");
    // A coarser scan of the phantom stands in for the PET (one patient frame, another grid);
    // its TF from a file: the default over its values.
    let pet_file = s.dir.join("pet.tf.ron");
    let pet = volgraph_accel::organs::organs_ct(16);
    std::fs::write(&pet_file, TransferFunction::default_for(&pet).to_ron_string()).expect("TF file");
    let args = SessionArgs {
        named: vec![("volume".into(), "organs32".into()), ("pet".into(), "organs16".into())],
        named_tfs: vec![("pet_tf".into(), pet_file.clone())],
        ..session_args(&s, &["organs32"], Some("ct-soft-tissue".into()))
    };
    let (mut session, _) = LiveSession::open(gpu(), &args).unwrap_or_else(|e| panic!("pet_ct opens: {e:?}"));
    let targets: Vec<Option<String>> = session.transfer_function_targets().into_iter().map(|(t, _)| t).collect();
    assert_eq!(targets, [None, Some("pet_tf".to_string())], "the CT's editor, then the PET's");
    let both = frame(&mut session);
    let shown = |image: &[f32]| image.chunks(4).filter(|p| p[3] > 0.01).count();
    assert!(shown(&both) > 100, "{} pixels", shown(&both));

    // The PET's editor: its edit changes the image, the CT's TF stays.
    let ct_tf = session.workbench().tf.transfer_function().clone();
    let err = session.select_transfer_function("nothing").expect_err("no such input");
    assert!(err.contains("\"nothing\" is no transfer-function input") && err.contains("pet_tf"), "{err}");
    session.select_transfer_function("pet_tf").expect("the PET's TF");
    let pet_hidden = transparent(session.transfer_function());
    let events = session.edit_transfer_function(pet_hidden.clone());
    assert!(
        matches!(events.as_slice(), [Event::Reloaded { what, .. }] if what == "transfer function edit (pet_tf)"),
        "{events:?}"
    );
    assert_eq!(session.transfer_function(), &pet_hidden);
    assert_eq!(session.workbench().tf.transfer_function(), &ct_tf, "the CT's TF unchanged");
    let ct_only = frame(&mut session);
    assert_ne!(ct_only, both, "the PET's colours left the image");
    assert!(shown(&ct_only) > 100, "the CT still shows ({} pixels)", shown(&ct_only));

    // "save TF" writes the PET's own file.
    let saved = session.save_transfer_function().expect("saved");
    assert_eq!(saved, pet_file);
    let read = TransferFunction::load(&pet_file).expect("reads back");
    assert!(read.points.iter().all(|p| p.alpha == 0.0), "the edited PET TF was saved");

    // The CT's editor: hiding the CT too leaves nothing.
    session.select_transfer_function("tf").expect("the CT's TF");
    let hidden = transparent(session.transfer_function());
    session.edit_transfer_function(hidden);
    assert_eq!(shown(&frame(&mut session)), 0, "both volumes hidden");
}
