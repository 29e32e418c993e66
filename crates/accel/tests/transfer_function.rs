//! Transfer functions: the preset files, RON and ParaView parsing with their errors word for
//! word, LUT baking and sampling against hand-computed values, opacity correction.

mod common;

use std::path::{Path, PathBuf};

use volgraph_accel::generate;
use volgraph_accel::transfer_function::{
    ControlPoint, DEFAULT_LUT_SIZE, Preset, TransferFunction, lut_sample, opacity_correct, opacity_uncorrect,
};

fn tf_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/tf")
}

fn point(value: f64, rgb: f64, alpha: f64) -> ControlPoint {
    ControlPoint { value, color: [rgb; 3], alpha }
}

#[test]
fn preset_files_load_and_equal_the_presets() {
    for preset in Preset::ALL {
        let path = tf_dir().join(format!("{}.ron", preset.name()));
        let loaded = TransferFunction::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let expected = TransferFunction::preset(preset, (0.0, 255.0));
        assert_eq!(loaded.domain, expected.domain);
        assert_eq!(loaded.points.len(), expected.points.len(), "{}", path.display());
        for (a, b) in loaded.points.iter().zip(&expected.points) {
            // The files write t·255 in decimal; the preset computes it in f64.
            assert!((a.value - b.value).abs() < 1e-9, "{}: {a:?} vs {b:?}", path.display());
            assert_eq!((a.color, a.alpha), (b.color, b.alpha), "{}", path.display());
        }
    }
}

#[test]
fn presets_do_what_their_names_promise() {
    let opaque = TransferFunction::preset(Preset::Opaque, (0.0, 255.0));
    assert_eq!(opaque.eval(20.0)[3], 1.0, "opaque: full opacity from 5% of the range");
    let sparse = TransferFunction::preset(Preset::Sparse, (0.0, 255.0));
    let transparent = (0..=255).filter(|&v| sparse.eval(v as f64)[3] == 0.0).count();
    assert!(transparent > 150, "sparse: most values are transparent ({transparent}/256)");
    let ml = generate::marschner_lobb(8);
    assert_eq!(TransferFunction::default_for(&ml).domain, (0.0, 255.0));
}

#[test]
fn ron_round_trip() {
    let tf = TransferFunction::preset(Preset::Default, (-10.0, 30.0));
    let text = tf.to_ron_string();
    let back = TransferFunction::from_ron_str(&text, Path::new("mem.ron")).expect("parse own output");
    assert_eq!(back, tf);
}

#[test]
fn eval_is_piecewise_linear_and_clamped() {
    let tf = TransferFunction { domain: (0.0, 10.0), points: vec![point(2.0, 0.0, 0.0), point(6.0, 1.0, 0.5)] };
    assert_eq!(tf.eval(0.0), [0.0; 4], "before the first point: its value");
    assert_eq!(tf.eval(4.0), [0.5, 0.5, 0.5, 0.25], "halfway");
    assert_eq!(tf.eval(9.0), [1.0, 1.0, 1.0, 0.5], "after the last point: its value");
    // A step: two points at the same value.
    let step = TransferFunction { domain: (0.0, 1.0), points: vec![point(0.5, 0.0, 0.0), point(0.5, 1.0, 1.0)] };
    assert_eq!(step.eval(0.49)[3], 0.0);
    assert_eq!(step.eval(0.5)[3], 1.0);
}

#[test]
fn lut_texels_and_sampling_match_hand_computed_values() {
    // alpha = v/255 over the domain (0, 255): texel i of 4 sits at s = (i + 0.5)/4.
    let ramp = TransferFunction { domain: (0.0, 255.0), points: vec![point(0.0, 0.0, 0.0), point(255.0, 1.0, 1.0)] };
    let lut = ramp.to_lut(4);
    let alphas: Vec<f32> = lut.iter().map(|t| t[3]).collect();
    assert_eq!(alphas, vec![0.125, 0.375, 0.625, 0.875]);
    // s = 0.3: x = 0.3·4 - 0.5 = 0.7 → 0.3·0.125 + 0.7·0.375 = 0.3.
    assert!((lut_sample(&lut, 0.3)[3] - 0.3).abs() < 1e-12);
    assert_eq!(lut_sample(&lut, 0.5)[3], 0.5);
    assert_eq!(lut_sample(&lut, 0.05)[3], 0.125, "below the first texel centre: clamped");
    assert_eq!(lut_sample(&lut, 1.0)[3], 0.875, "above the last texel centre: clamped");
    assert_eq!(lut_sample(&lut, f64::NAN)[3], 0.125, "NaN reads as s = 0");
    assert_eq!(lut_sample(&[], 0.5), [0.0; 4]);

    // A kink at 100: texels of 2 at v = 63.75 (alpha 0.5·63.75/100 = 0.31875) and
    // v = 191.25 (0.5); halfway between them (s = 0.5) the sampler gives their mean 0.409375.
    let kink = TransferFunction {
        domain: (0.0, 255.0),
        points: vec![point(0.0, 0.0, 0.0), point(100.0, 1.0, 0.5), point(255.0, 1.0, 0.5)],
    };
    let lut = kink.to_lut(2);
    assert!((lut[0][3] as f64 - 0.31875).abs() < 1e-7);
    assert_eq!(lut[1][3], 0.5);
    assert!((lut_sample(&lut, 0.5)[3] - 0.409375).abs() < 1e-7);
}

#[test]
fn lookup_is_the_sampler_on_the_default_lut() {
    let tf = TransferFunction::preset(Preset::Default, (0.0, 255.0));
    let lut = tf.to_lut(DEFAULT_LUT_SIZE);
    for k in 0..=1000 {
        let s = k as f64 / 1000.0 * 1.2 - 0.1;
        assert_eq!(tf.lookup(s), lut_sample(&lut, s), "s = {s}");
    }
}

#[test]
fn lut_for_a_volume_uses_its_value_range() {
    // A float volume whose finite range is (0, 7): a TF with domain (0, 14) covers twice it.
    let (mut volume, _) = generate::non_finite_f32(8);
    volgraph_accel::load::sanitize_volume(&mut volume);
    assert_eq!(volume.value_range, (0.0, 7.0));
    let tf = TransferFunction { domain: (0.0, 14.0), points: vec![point(0.0, 0.0, 0.0), point(14.0, 1.0, 1.0)] };
    assert_eq!(tf.normalized_domain_for(&volume), (0.0, 2.0));
    // Texel 0 of 2 is s = 0.25 → v = 1.75 in data units → alpha 1.75/14 = 0.125.
    assert_eq!(tf.to_lut_for(&volume, 2)[0][3], 0.125);
    // to_lut maps s onto the TF's own domain: s = 0.25 → v = 3.5 → alpha 0.25.
    assert_eq!(tf.to_lut(2)[0][3], 0.25);
    // For uint8 data the default TF's domain is the volume's range: both LUTs agree.
    let ml = generate::marschner_lobb(8);
    let default = TransferFunction::default_for(&ml);
    assert_eq!(default.normalized_domain_for(&ml), (0.0, 1.0));
    assert_eq!(default.to_lut(64), default.to_lut_for(&ml, 64));
}

#[test]
fn opacity_correction_and_its_inverse() {
    assert_eq!(opacity_correct(0.5, 1.0), 0.5);
    assert_eq!(opacity_correct(0.5, 2.0), 0.75, "two half-opaque unit steps");
    assert!((opacity_correct(0.75, 0.5) - 0.5).abs() < 1e-15, "half a step of 0.75: 1 - 0.25^0.5");
    for &a in &[0.0, 0.01, 0.3, 0.9, 1.0] {
        for &step in &[0.25, 0.5, 1.0, 3.0] {
            let back = opacity_uncorrect(opacity_correct(a, step), step);
            assert!((back - a).abs() < 1e-12, "alpha {a}, step {step}: {back}");
        }
    }
}

fn ron_err(text: &str) -> String {
    TransferFunction::from_ron_str(text, Path::new("graphs/tf/bad.ron")).expect_err("invalid").to_string()
}

#[test]
fn ron_errors_word_for_word() {
    let p = |pts: &str| format!("TransferFunction(domain: (0.0, 255.0), points: [{pts}])");
    assert_eq!(
        ron_err(&p(
            "(value: 10.0, color: (1.0, 1.0, 1.0), alpha: 0.5), (value: 5.0, color: (1.0, 1.0, 1.0), alpha: 0.5)"
        )),
        "graphs/tf/bad.ron: points[1].value = 5 is smaller than points[0].value = 10; list the points in increasing value"
    );
    assert_eq!(
        ron_err(&p("(value: 10.0, color: (1.0, 1.0, 1.0), alpha: 1.5)")),
        "graphs/tf/bad.ron: points[0].alpha = 1.5 is outside [0, 1]; colours are linear RGB in 0..1 and alpha is opacity per unit step in 0..1"
    );
    assert_eq!(
        ron_err(&p(
            "(value: 0.0, color: (0.0, 0.0, 0.0), alpha: 0.0), (value: 10.0, color: (1.0, -0.1, 1.0), alpha: 0.5)"
        )),
        "graphs/tf/bad.ron: points[1].color.g = -0.1 is outside [0, 1]; colours are linear RGB in 0..1 and alpha is opacity per unit step in 0..1"
    );
    assert_eq!(
        ron_err(&p("(value: 300.0, color: (1.0, 1.0, 1.0), alpha: 0.5)")),
        "graphs/tf/bad.ron: points[0].value = 300 is outside the domain (0, 255); move the point into the domain or widen the domain"
    );
    assert_eq!(
        ron_err(&p("")),
        "graphs/tf/bad.ron: `points` is empty; add at least one point such as `(value: 0.0, color: (1.0, 1.0, 1.0), alpha: 0.0)`"
    );
    assert_eq!(
        ron_err("TransferFunction(domain: (255.0, 0.0), points: [(value: 0.0, color: (0.0, 0.0, 0.0), alpha: 0.0)])"),
        "graphs/tf/bad.ron: domain (255, 0) is not a range; write `domain: (min, max)` with finite min < max in data units"
    );
}

#[test]
fn ron_syntax_errors_carry_line_and_column() {
    // Columns are 1-based and point at the offending token: `colour` starts at column 25 of
    // line 3, `lut_size` at column 3, and the missing comma is found at `color` (column 61).
    assert_eq!(
        ron_err(
            "TransferFunction(\n  domain: (0.0, 255.0),\n  points: [(value: 0.0, colour: (0.0, 0.0, 0.0), alpha: 0.0)],\n)"
        ),
        "graphs/tf/bad.ron:3:25: Unexpected field named `colour` in `ControlPoint`, expected one of `value`, `color`, or `alpha` instead; see graphs/tf/default.ron for the format"
    );
    assert_eq!(
        ron_err("TransferFunction(\n  domain: (0.0, 255.0),\n  lut_size: 5,\n  points: [],\n)"),
        "graphs/tf/bad.ron:3:3: Unexpected field named `lut_size` in `TransferFunction`, expected either `domain` or `points` instead; see graphs/tf/default.ron for the format"
    );
    assert_eq!(
        ron_err("TransferFunction(\n  domain: (0.0, 255.0),\n  points: [(value: 0.0, color: (0.0, 0.0, 0.0))],\n)"),
        "graphs/tf/bad.ron:3:47: Unexpected missing field named `alpha` in `ControlPoint`; see graphs/tf/default.ron for the format"
    );
    assert_eq!(
        ron_err("TransferFunction(domain: (0.0, 255.0), points: [(value: 0.0 color: (0.0, 0.0, 0.0), alpha: 0.0)]"),
        "graphs/tf/bad.ron:1:61: Expected comma; see graphs/tf/default.ron for the format"
    );
}

fn pv_err(text: &str) -> String {
    TransferFunction::from_paraview_json(text, Path::new("t.json")).expect_err("invalid").to_string()
}

#[test]
fn paraview_import_converts_srgb_and_merges_opacity_points() {
    let json = r#"[{"ColorSpace": "RGB", "Name": "test", "NanColor": [1, 1, 0],
        "RGBPoints": [0, 0, 0, 0, 10, 1, 0.5, 0],
        "Points": [0, 0, 0.5, 0, 5, 0.4, 0.5, 0, 10, 1, 0.5, 0]}]"#;
    let tf = TransferFunction::from_paraview_json(json, Path::new("t.json")).expect("valid map");
    assert_eq!(tf.domain, (0.0, 10.0));
    let values: Vec<f64> = tf.points.iter().map(|p| p.value).collect();
    assert_eq!(values, vec![0.0, 5.0, 10.0], "union of the colour and opacity x values");
    // sRGB 0.5 is linear ((0.5 + 0.055)/1.055)^2.4 = 0.214041…; x = 5 is halfway in linear RGB.
    let srgb_half = ((0.5f64 + 0.055) / 1.055).powf(2.4);
    assert!((srgb_half - 0.214041).abs() < 1e-6);
    assert_eq!(tf.points[2].color, [1.0, srgb_half, 0.0]);
    assert_eq!(tf.points[1].color, [0.5, srgb_half / 2.0, 0.0]);
    let alphas: Vec<f64> = tf.points.iter().map(|p| p.alpha).collect();
    assert_eq!(alphas, vec![0.0, 0.4, 1.0]);
    // Without "Points" the opacity ramps from 0 to 1 over the domain.
    let ramp = TransferFunction::from_paraview_json(r#"{"RGBPoints": [-1, 1, 1, 1, 1, 1, 1, 1]}"#, Path::new("t.json"))
        .expect("a bare object is accepted too");
    assert_eq!(ramp.eval(0.0)[3], 0.5);
}

#[test]
fn paraview_errors_word_for_word() {
    assert_eq!(pv_err("[{\"RGBPoints\": [0, 1,"), "t.json:1:21: invalid JSON: EOF while parsing a value");
    assert_eq!(pv_err("[]"), "t.json: the JSON array is empty; it needs one colour map object with \"RGBPoints\"");
    assert_eq!(
        pv_err("[{\"Name\": \"x\"}]"),
        "t.json: the colour map has no \"RGBPoints\" array; it needs [x, r, g, b, …]"
    );
    assert_eq!(
        pv_err("[{\"RGBPoints\": [0, 0, 0, 0, 1, 1, 1]}]"),
        "t.json: \"RGBPoints\" has 7 numbers; it needs groups of four (x, r, g, b)"
    );
    assert_eq!(pv_err("[{\"RGBPoints\": [0, 0, 0, \"red\"]}]"), "t.json: RGBPoints[3] is \"red\", not a number");
    assert_eq!(
        pv_err("[{\"RGBPoints\": [1, 0, 0, 0, 0, 1, 1, 1]}]"),
        "t.json: \"RGBPoints\" x values must increase, but point 1 has x = 0 after x = 1"
    );
    assert_eq!(
        pv_err("[{\"RGBPoints\": [2, 0, 0, 0, 2, 1, 1, 1]}]"),
        "t.json: every point has x = 2; a colour map needs two different x values"
    );
}

#[test]
fn paraview_values_outside_the_unit_range_are_rejected_like_ron() {
    // The RON loader rejects the same values; ParaView import used to clamp them silently.
    assert_eq!(
        pv_err("[{\"RGBPoints\": [0, 0, 0, 0, 1, 1, 1.2, 1]}]"),
        "t.json: RGBPoints point 1 (g, RGBPoints[6]) = 1.2 is outside [0, 1]; ParaView colours are sRGB in 0..1"
    );
    assert_eq!(
        pv_err("[{\"RGBPoints\": [0, 0, 0, 0, 1, 1, 1, 1], \"Points\": [0, -0.5, 0.5, 0, 1, 1, 0.5, 0]}]"),
        "t.json: Points point 0 (alpha, Points[1]) = -0.5 is outside [0, 1]; opacity is in 0..1"
    );
    assert_eq!(
        pv_err("[{\"RGBPoints\": [0, 0, 0, 0, 1, 1, 1, 1], \"Points\": [0, 0, 0.5, 0, 1, 1.5, 0.5, 0]}]"),
        "t.json: Points point 1 (alpha, Points[5]) = 1.5 is outside [0, 1]; opacity is in 0..1"
    );
}

#[test]
fn a_paraview_file_with_several_maps_says_which_was_used_and_picks_by_name() {
    let dir = std::env::temp_dir().join("volgraph-pv-maps");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("maps.json");
    // A byte-order mark first, as some editors write: accepted.
    std::fs::write(
        &path,
        "\u{feff}[{\"Name\": \"Cool\", \"RGBPoints\": [0, 0, 0, 1, 1, 0, 0, 1]},
          {\"Name\": \"Warm\", \"RGBPoints\": [0, 1, 0, 0, 1, 1, 0, 0], \"Points\": [0, 0, 0.3, 0, 1, 1, 0.5, 0]}]",
    )
    .expect("write");
    let first = TransferFunction::load_paraview_map(&path, None).expect("first map");
    assert_eq!((first.name.as_deref(), first.index), (Some("Cool"), 0));
    assert_eq!(first.all, vec!["Cool".to_string(), "Warm".to_string()]);
    assert!(first.notes.is_empty());
    let warm = TransferFunction::load_paraview_map(&path, Some("Warm")).expect("by name");
    assert_eq!(warm.index, 1);
    assert_eq!(warm.tf.points[0].color, [1.0, 0.0, 0.0]);
    assert_eq!(
        warm.notes,
        vec!["Points point 0 has midpoint 0.3 and sharpness 0; volgraph interpolates opacity linearly (midpoint 0.5, sharpness 0)".to_string()]
    );
    let err = TransferFunction::load_paraview_map(&path, Some("warm")).expect_err("names are exact");
    assert!(
        err.to_string()
            .ends_with("holds no colour map named \"warm\"; did you mean \"Warm\"? it holds: \"Cool\", \"Warm\""),
        "{err}"
    );
}

#[test]
fn a_byte_order_mark_before_ron_is_accepted() {
    let text = format!(
        "\u{feff}{}",
        TransferFunction::preset(volgraph_accel::transfer_function::Preset::Default, (0.0, 1.0)).to_ron_string()
    );
    TransferFunction::from_ron_str(&text, Path::new("bom.ron")).expect("a BOM is not part of the RON");
}

/// Issue 19: `"ColorSpace": "HSV"` maps were interpolated in RGB. Red to blue the short way
/// round the hue circle passes magenta: halfway the colour is (1, 0, 1), not the (½, 0, ½) of
/// interpolating the end points (in linear RGB, as volgraph does for RGB maps).
/// Tolerance 0.02 (linear): 32 points per segment make the LUT's linear pieces follow the
/// HSV path that closely.
#[test]
fn an_hsv_paraview_map_follows_the_hue_circle() {
    let json =
        |space: &str| format!(r#"[{{"Name": "rb", "ColorSpace": "{space}", "RGBPoints": [0, 1, 0, 0, 1, 0, 0, 1]}}]"#);
    let hsv = TransferFunction::from_paraview_json(&json("HSV"), Path::new("rb.json")).expect("parses");
    let mid = hsv.eval(0.5);
    assert!((mid[0] - 1.0).abs() < 0.02 && mid[1].abs() < 0.02 && (mid[2] - 1.0).abs() < 0.02, "{mid:?}");
    let rgb = TransferFunction::from_paraview_json(&json("RGB"), Path::new("rb.json")).expect("parses");
    let mid = rgb.eval(0.5);
    assert!((mid[0] - 0.5).abs() < 0.01 && mid[1].abs() < 0.01 && (mid[2] - 0.5).abs() < 0.01, "{mid:?}");
}

/// Issue 24: the viewer saves an edited TF "as it came": RON reads back equal, and ParaView JSON
/// reads back to the same function (to sRGB rounding) with the file's other maps and keys kept.
#[test]
fn an_edited_tf_saves_as_it_came_and_reads_back() {
    use volgraph_accel::transfer_function::{ControlPoint, TransferFunction};
    let path = std::path::Path::new("edited.json");
    let tf = TransferFunction {
        domain: (0.0, 255.0),
        points: vec![
            ControlPoint { value: 20.0, color: [0.1, 0.2, 0.9], alpha: 0.0 },
            ControlPoint { value: 90.0, color: [1.0, 0.5, 0.0], alpha: 0.35 },
            ControlPoint { value: 200.0, color: [1.0, 1.0, 1.0], alpha: 0.8 },
        ],
    };
    let ron = TransferFunction::from_ron_str(&tf.to_ron_string(), path).expect("RON reads back");
    assert_eq!(ron, tf);
    let original = r#"[{"Name": "first", "Creator": "someone", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]},
                       {"Name": "second", "RGBPoints": [0, 1, 0, 0, 1, 0, 0, 1]}]"#;
    let written = tf.to_paraview_json(Some(original), 1);
    let value: serde_json::Value = serde_json::from_str(&written).expect("JSON");
    assert_eq!(value[0]["Creator"], "someone", "the other map is kept: {written}");
    assert_eq!(value[0]["RGBPoints"].as_array().map(Vec::len), Some(8));
    assert_eq!(value[1]["Name"], "second");
    let back = TransferFunction::load_paraview_map_from_str(&written, path, Some("second")).expect("reads back");
    // 1e-9: the only change is linear → sRGB → linear in f64 (round-off ~1e-15 per channel);
    // anything near 1e-9 would be a wrong formula, not rounding.
    for v in [0.0, 10.0, 20.0, 55.0, 90.0, 150.0, 200.0, 255.0] {
        let (a, b) = (tf.eval(v), back.eval(v));
        for c in 0..4 {
            assert!((a[c] - b[c]).abs() < 1e-9, "at {v}: {a:?} vs {b:?}");
        }
    }
}
