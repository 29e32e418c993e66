//! Issue 21, item 5: the fitted default transfer function skips the background. On a scanned
//! object in a noise floor at 0.27–0.31 of the range (`generate::scanned_sphere`), the default
//! render's footprint is the object's — it matches a render that hides everything below 95/255
//! — where the plain ramp over the whole range draws the box of noise.

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::generate::scanned_sphere;
use volgraph_accel::reference::{RaycastSettings, render_reference};
use volgraph_accel::transfer_function::{Preset, TransferFunction};

const SIZE: u32 = 48;

/// The pixels whose accumulated opacity is over 0.05.
fn footprint(tf: &TransferFunction) -> Vec<bool> {
    let volume = scanned_sphere(32);
    let lut = tf.to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 20.0, distance: 3.2, ..OrbitCamera::default() };
    let image = render_reference(&volume, &lut, &camera, SIZE, SIZE, &RaycastSettings::default());
    image.color.iter().map(|c| c[3] > 0.05).collect()
}

#[test]
fn the_default_tf_shows_the_object_not_the_noise_floor() {
    let volume = scanned_sphere(32);
    let fitted = footprint(&TransferFunction::default_for(&volume));
    // What a user would write by hand: the same ramp, everything below 95/255 hidden.
    let by_hand = footprint(&TransferFunction::preset(Preset::Default, (0.0, 255.0)).hidden_below(95.0));
    let plain = footprint(&TransferFunction::preset(Preset::Default, (0.0, 255.0)));
    let count = |f: &[bool]| f.iter().filter(|&&b| b).count();
    let differ = fitted.iter().zip(&by_hand).filter(|(a, b)| a != b).count();
    eprintln!(
        "footprints (pixels): fitted {}, by hand {}, plain ramp {}",
        count(&fitted),
        count(&by_hand),
        count(&plain)
    );
    // The sphere covers a disc of the image; the box of noise covers most of it.
    assert!(count(&fitted) > 50, "the object is visible ({} pixels)", count(&fitted));
    // 5 %: only silhouette pixels may differ — there a grazing ray's blend of 200 and the floor
    // crosses the 0.05 line at another place, the fitted cut lying just above the floor
    // (just above the noise, 80/255) and the hand-made one at 95/255.
    assert!(differ * 20 <= count(&by_hand), "{differ} pixels differ from the hand-made footprint");
    assert!(
        count(&plain) > 2 * count(&fitted),
        "the plain ramp draws the noise floor: {} vs {}",
        count(&plain),
        count(&fitted)
    );
}

/// A volume whose background lies where the ramp is transparent anyway (a solid sphere in
/// zeros) keeps the plain ramp.
#[test]
fn a_background_below_the_ramp_changes_nothing() {
    let sphere = volgraph_accel::generate::sphere(16, 0.6);
    assert_eq!(TransferFunction::default_for(&sphere), TransferFunction::preset(Preset::Default, (0.0, 255.0)));
}
