//! `present` (shaders/present.wgsl) against the exact sRGB encoding, on a real render: every
//! 8-bit code of its `display` output is the exact code of its `image` input composited over the
//! background, or one off (its power segment is a fit of three square roots, within 0.25/255 of
//! the curve, so rounding may land on the neighbouring code), and that only for a few percent
//! of the channels.

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_core::CompileOptions;
use volgraph_passes::builtin_registry;

mod support;

use support::{gpu, graph_source, render_once};

#[test]
fn present_encodes_within_one_code_of_the_exact_srgb() {
    // A graph with both outputs; a generated volume whose default TF covers the whole range of
    // colours and alphas, from a view where the image has background, translucent and opaque
    // pixels.
    let volume = volgraph_accel::generate::marschner_lobb(64);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    let background = 0.25;
    let mut options = CompileOptions::new(96, 96);
    options.param_overrides.insert("present.background".into(), ron::Value::from(background));
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 20.0, distance: 3.6, ..OrbitCamera::default() };
    let source = graph_source("modern/fastest.ron");
    let (mut runtime, _) =
        render_once(&gpu(), &builtin_registry(), "modern/fastest.ron", &source, &options, &volume, &lut, &camera)
            .expect("fastest renders");
    let image = runtime.read_output("image").expect("image");
    let display = runtime.read_output("display").expect("display");
    assert_eq!((image.width, image.height), (display.width, display.height));

    let (mut channels, mut one_off, mut covered) = (0usize, 0usize, 0usize);
    for y in 0..image.height {
        for x in 0..image.width {
            let c = image.rgba(x, y);
            let shown = display.rgba(x, y);
            covered += usize::from(c[3] > 0.0);
            for i in 0..3 {
                let over = f64::from(c[i]) + (1.0 - f64::from(c[3])) * background;
                let exact = (volgraph_accel::srgb::encode(over) * 255.0).round();
                let code = (f64::from(shown[i]) * 255.0).round();
                let off = (code - exact).abs();
                assert!(off <= 1.0, "pixel ({x}, {y}) channel {i}: code {code}, exact {exact} (linear {over})");
                channels += 1;
                one_off += usize::from(off == 1.0);
            }
            assert_eq!(shown[3], 1.0, "pixel ({x}, {y}): the display is opaque");
        }
    }
    let pixels = (image.width * image.height) as usize;
    assert!(covered > pixels / 4 && covered < pixels, "the view shows volume and background ({covered} of {pixels})");
    // The fit is one code off for ~1.6 % of uniformly spread inputs; allow for an image whose
    // values cluster near a code boundary, not for a systematic error.
    let fraction = one_off as f64 / channels as f64;
    assert!(fraction < 0.05, "{one_off} of {channels} channels one code off ({:.1} %)", 100.0 * fraction);
}
