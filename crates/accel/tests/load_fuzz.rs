//! No input makes a parser panic: random bytes, every truncation of valid files, and valid
//! headers mutated byte-wise or with hostile field lines spliced in, for NRRD, MetaImage, raw
//! names, transfer-function RON and ParaView JSON. Every case must return (Ok or Err); a panic
//! fails the test. Case counts keep the whole file to a few seconds.

mod common;

use std::path::Path;

use proptest::prelude::*;
use volgraph_accel::load::{parse_metaimage, parse_nrrd, parse_raw_name};
use volgraph_accel::transfer_function::{ControlPoint, TransferFunction, lut_sample};

/// A valid attached NRRD: 3x2x2 uint16 (24 bytes), raw or gzip.
fn valid_nrrd(gzip: bool) -> Vec<u8> {
    let data: Vec<u8> = (0..24u8).collect();
    let header = format!(
        "NRRD0004\n# comment\ntype: ushort\ndimension: 3\nsizes: 3 2 2\nspacings: 1 1 2\nendian: little\nencoding: {}\n\n",
        if gzip { "gzip" } else { "raw" }
    );
    let mut bytes = header.into_bytes();
    bytes.extend(if gzip { common::gzip(&data) } else { data });
    bytes
}

/// A valid `.mha`: 3x2x2 MET_FLOAT (48 bytes), plain or zlib.
fn valid_mha(compressed: bool) -> Vec<u8> {
    let data: Vec<u8> = (0..12).flat_map(|i| (i as f32 * 0.5).to_le_bytes()).collect();
    let header = format!(
        "ObjectType = Image\nNDims = 3\nDimSize = 3 2 2\nElementSpacing = 1 1 2\nElementByteOrderMSB = False\nCompressedData = {}\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n",
        if compressed { "True" } else { "False" }
    );
    let mut bytes = header.into_bytes();
    bytes.extend(if compressed { common::zlib(&data) } else { data });
    bytes
}

/// Field lines chosen to hit edge cases: overflow, zero, negative, NaN, unsupported values.
const HOSTILE_LINES: &[&str] = &[
    "sizes: 4294967295 4294967295 4294967295",
    "sizes: 18446744073709551615 1 1",
    "sizes: 0 0 0",
    "sizes: -1 2 2",
    "dimension: 4",
    "type: double",
    "type: float",
    "encoding: gzip",
    "encoding: raw",
    "byte skip: -1",
    "byte skip: 99999999999999",
    "spacings: nan 1 1",
    "space directions: (",
    "space directions: ()()()",
    "space directions: (1,0,0) (0,1,0) none",
    "space directions: (0,-1,0) (1,0,0) (0,0,-2)",
    "space directions: (-1,0,0) (0,-1,0) (0,0,-1)",
    "space directions: (1,0,0) (1,0,0) (0,0,1)",
    "space directions: (0.6,0.8,0) (0,1,0) (0,0,1)",
    "space directions: (0,0,0) (0,1,0) (0,0,1)",
    "space directions: (nan,0,0) (0,1,0) (0,0,1)",
    "space directions: (1e308,0,0) (0,1e-308,0) (0,0,inf)",
    "TransformMatrix = 0 1 0 -1 0 0 0 0 1",
    "TransformMatrix = 0 0 0 0 0 0 0 0 0",
    "TransformMatrix = 1 0 0 0 1",
    "\u{feff}NRRD0004",
    "endian: big",
    "data file: LIST",
    "line skip: 3",
    "key:=value",
    ":",
    "",
    "DimSize = 4294967295 4294967295 4294967295",
    "DimSize = 0 1 2",
    "HeaderSize = -1",
    "HeaderSize = 99999999999",
    "CompressedData = True",
    "ElementType = MET_DOUBLE",
    "ElementSpacing = inf 1 1",
    "NDims = 3",
    "ElementDataFile = LOCAL",
    "=",
];

fn mutate(mut bytes: Vec<u8>, edits: &[(usize, u8)], splice: Option<(usize, usize)>) -> Vec<u8> {
    for &(at, b) in edits {
        if !bytes.is_empty() {
            let i = at % bytes.len();
            bytes[i] = b;
        }
    }
    if let Some((at, line)) = splice {
        // Insert a hostile line at a line start so it parses as a field.
        let starts: Vec<usize> = std::iter::once(0)
            .chain(bytes.iter().enumerate().filter(|(_, b)| **b == b'\n').map(|(i, _)| i + 1))
            .collect();
        let pos = starts[at % starts.len()].min(bytes.len());
        let text = format!("{}\n", HOSTILE_LINES[line % HOSTILE_LINES.len()]);
        bytes.splice(pos..pos, text.into_bytes());
    }
    bytes
}

fn fuzz_cases(default: u32) -> u32 {
    std::env::var("VOLGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn parse_all(bytes: &[u8]) {
    let _ = parse_nrrd(Path::new("fuzz.nrrd"), bytes);
    let _ = parse_nrrd(Path::new("fuzz.nhdr"), bytes);
    let _ = parse_metaimage(Path::new("fuzz.mha"), bytes);
    let _ = parse_metaimage(Path::new("fuzz.mhd"), bytes);
}

#[test]
fn valid_fuzz_bases_parse() {
    // The mutation tests start from files that really load, so mutations explore near-valid input.
    for gzip in [false, true] {
        parse_nrrd(Path::new("fuzz.nrrd"), &valid_nrrd(gzip)).expect("valid NRRD");
        parse_metaimage(Path::new("fuzz.mha"), &valid_mha(gzip)).expect("valid MetaImage");
    }
}

proptest! {
    // VOLGRAPH_FUZZ_CASES raises the count for a long hunt (the 1,000,000 per target).
    #![proptest_config(ProptestConfig { cases: fuzz_cases(2000), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        parse_all(&bytes);
        let mut with_magic = b"NRRD0004\n".to_vec();
        with_magic.extend_from_slice(&bytes);
        parse_all(&with_magic);
    }

    #[test]
    fn truncations_never_panic(cut in 0usize..200, gzip in any::<bool>()) {
        for valid in [valid_nrrd(gzip), valid_mha(gzip)] {
            let end = cut.min(valid.len());
            parse_all(&valid[..end]);
            // Also cut from the far end, through the data.
            parse_all(&valid[..valid.len() - end]);
        }
    }

    #[test]
    fn mutated_headers_never_panic(
        edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..4),
        splice in proptest::option::of((any::<usize>(), any::<usize>())),
        gzip in any::<bool>(),
    ) {
        parse_all(&mutate(valid_nrrd(gzip), &edits, splice));
        parse_all(&mutate(valid_mha(gzip), &edits, splice));
    }

    #[test]
    fn raw_names_never_panic(name in "[a-z0-9_xX.]{0,40}") {
        let _ = parse_raw_name(&name);
    }

    #[test]
    fn tf_text_never_panics(text in "[()\\[\\]:,.0-9a-zA-Z_ \n-]{0,200}") {
        let _ = TransferFunction::from_ron_str(&text, Path::new("fuzz.ron"));
        let _ = TransferFunction::from_paraview_json(&text, Path::new("fuzz.json"));
    }

    #[test]
    fn paraview_shapes_never_panic(
        rgb in proptest::collection::vec(prop_oneof![Just(f64::NAN), -2.0..2.0f64], 0..13),
        alpha in proptest::option::of(proptest::collection::vec(-2.0..2.0f64, 0..9)),
    ) {
        let fmt = |v: &[f64]| v.iter().map(|x| if x.is_nan() { "null".to_string() } else { x.to_string() }).collect::<Vec<_>>().join(",");
        let mut json = format!("[{{\"Name\": \"fuzz\", \"RGBPoints\": [{}]", fmt(&rgb));
        if let Some(a) = &alpha {
            json.push_str(&format!(", \"Points\": [{}]", fmt(a)));
        }
        json.push_str("}]");
        if let Ok(tf) = TransferFunction::from_paraview_json(&json, Path::new("fuzz.json")) {
            // Whatever is accepted is valid by the RON rules too.
            prop_assert!(tf.validate(Path::new("fuzz.json")).is_ok());
        }
    }

    #[test]
    fn sampling_unvalidated_tfs_never_panics(
        points in proptest::collection::vec((prop_oneof![Just(f64::NAN), -10.0..10.0f64], -1.0..2.0f64), 0..6),
        s in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), -3.0..3.0f64],
        n in 0usize..8,
    ) {
        let tf = TransferFunction {
            domain: (0.0, 1.0),
            points: points.iter().map(|&(value, a)| ControlPoint { value, color: [a; 3], alpha: a }).collect(),
        };
        let _ = tf.eval(s);
        let _ = tf.lookup(s);
        let _ = lut_sample(&tf.to_lut(n), s);
    }
}
