//! The DICOM fuzzer (issue 47): valid small files (native 16-bit, multi-frame, RLE Lossless,
//! JPEG 2000, Float Pixel Data, a BINARY segmentation, with and without the preamble) with attributes replaced by
//! hostile values (sizes 0 and 2³²−1, NumberOfFrames 10⁸, NaN, inf, 1e300, junk text, wrong
//! value counts, PALETTE COLOR, newlines), RLE headers and segments made of junk, bytes flipped
//! and the file cut short; some cases load a folder of it and a second slice with its own
//! hostile attributes. Every load must return Ok or Err: a panic, or a case slower than
//! `HANG_SECONDS`, fails the test; a watchdog ends the process on a real hang. The files are a
//! few hundred bytes and the cases run in a child process under `ulimit -v` of 4 GiB: a loader
//! that allocated what a hostile header claims rather than what the file holds aborts it, and
//! the test fails.
//!
//! `VOLGRAPH_FUZZ_CASES` sets the number of cases (default 1000, a few seconds); the summary
//! line on stderr gives the counts a long run is recorded with. The watchdog, the counters and
//! `HANG_SECONDS` are `fuzz_support`'s, shared with the NIfTI fuzzer.

mod dicom_support;
mod fuzz_support;

use std::path::PathBuf;

use dicom_core::value::PrimitiveValue;
use dicom_core::{DataElement, Tag, VR};
use dicom_dictionary_std::tags;
use dicom_support::*;
use fuzz_support::Harness;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use volgraph_accel::load::{LoadOptions, load_volumes};

/// The address-space limit (KiB) the cases run under: a 4 GiB `ulimit -v`.
const MEMORY_LIMIT_KIB: u64 = 4 << 20;
/// Set in the child process that runs the cases under the limit.
const CHILD: &str = "VOLGRAPH_DICOM_FUZZ_CHILD";

/// The attributes replaced, each with the VR its hostile text is written as.
const FIELDS: &[(Tag, VR)] = &[
    (tags::ROWS, VR::IS),
    (tags::COLUMNS, VR::IS),
    (tags::NUMBER_OF_FRAMES, VR::IS),
    (tags::BITS_ALLOCATED, VR::IS),
    (tags::BITS_STORED, VR::IS),
    (tags::HIGH_BIT, VR::IS),
    (tags::PIXEL_REPRESENTATION, VR::IS),
    (tags::SAMPLES_PER_PIXEL, VR::IS),
    (tags::RESCALE_SLOPE, VR::DS),
    (tags::RESCALE_INTERCEPT, VR::DS),
    (tags::PIXEL_SPACING, VR::DS),
    (tags::IMAGE_ORIENTATION_PATIENT, VR::DS),
    (tags::IMAGE_POSITION_PATIENT, VR::DS),
    (tags::SLICE_THICKNESS, VR::DS),
    (tags::SPACING_BETWEEN_SLICES, VR::DS),
    (tags::GRID_FRAME_OFFSET_VECTOR, VR::DS),
    (tags::PHOTOMETRIC_INTERPRETATION, VR::CS),
    (tags::SERIES_DESCRIPTION, VR::LO),
    (tags::WINDOW_CENTER, VR::DS),
    (tags::WINDOW_WIDTH, VR::DS),
    (tags::DOSE_GRID_SCALING, VR::DS),
    (tags::PLANAR_CONFIGURATION, VR::IS),
    (tags::MODALITY, VR::CS),
    (tags::SEGMENTATION_TYPE, VR::CS),
    (tags::MAXIMUM_FRACTIONAL_VALUE, VR::US),
];

/// Hostile values.
const VALUES: &[&str] = &[
    "0",
    "1",
    "-1",
    "2",
    "3",
    "8",
    "15",
    "16",
    "31",
    "32",
    "64",
    "65535",
    "65536",
    "2147483647",
    "4294967295",
    "100000000",
    "NaN",
    "inf",
    "-inf",
    "1e300",
    "-1e300",
    "1e39",
    "1e-300",
    "abc",
    "",
    "1\\2",
    "1\\2\\3",
    "1\\0\\0\\0\\1",
    "1\\0\\0\\0\\1\\0",
    "0\\1\\0\\1\\0\\0",
    "0.6\\0.8\\0\\0\\0\\1",
    "0\\0\\0\\0\\0\\0",
    "0.5\\0.5",
    "PALETTE COLOR",
    "MONOCHROME1",
    "RGB",
    "axial\nerror: fake",
    "SEG",
    "BINARY",
    "FRACTIONAL",
    "LABELMAP",
    "\u{1b}]0;x\u{7}",
];

/// Which valid file a case starts from.
#[derive(Clone, Copy, Debug)]
enum Base {
    Native,
    MultiFrame,
    Rle,
    Jpeg2000,
    Float,
    /// A BINARY DICOM SEG (`write_segmentation`) of two segments over three slices.
    Segmentation,
}

/// One fuzz case.
#[derive(Clone, Debug)]
struct Case {
    base: Base,
    /// (field, value) indices into [`FIELDS`] and [`VALUES`].
    edits: Vec<(usize, usize)>,
    /// An RLE frame in place of the base's pixels: segment count, offsets, body.
    rle: Option<(u32, Vec<u32>, Vec<u8>)>,
    /// (position, xor) byte flips, positions taken modulo the length.
    flips: Vec<(usize, u8)>,
    /// Keep this many thousandths of the file.
    cut: Option<u16>,
    no_preamble: bool,
    /// A second slice of the same series (2 mm on) with these edits; the folder is loaded.
    neighbour: Option<Vec<(usize, usize)>>,
}

impl Case {
    /// The neighbour's bytes, when there is one.
    fn neighbour_bytes(&self) -> Option<Vec<u8>> {
        let edits = self.neighbour.as_ref()?;
        let mut image = Image { z: 2.0, ..Image::default() };
        if matches!(self.base, Base::Rle) {
            image.transfer_syntax = RLE;
            image.pixels = Some(encapsulated(vec![rle_constant(30, 1000)]));
        }
        for &(field, value) in edits {
            let (tag, vr) = FIELDS[field % FIELDS.len()];
            image = image.with(tag, vr, VALUES[value % VALUES.len()]);
        }
        Some(image.bytes())
    }

    fn bytes(&self) -> Vec<u8> {
        let mut bytes = match self.base {
            Base::Segmentation => segmentation_bytes(&self.edits),
            _ => self.image_bytes(),
        };
        if self.no_preamble {
            bytes.drain(..128);
        }
        let len = bytes.len();
        for &(at, xor) in &self.flips {
            bytes[at % len] ^= xor;
        }
        if let Some(keep) = self.cut {
            bytes.truncate(len * usize::from(keep) / 1000);
        }
        bytes
    }

    /// The image bases' bytes, with the case's pixels and edits.
    fn image_bytes(&self) -> Vec<u8> {
        let mut image = Image::default();
        match self.base {
            Base::Segmentation => unreachable!("segmentation_bytes"),
            Base::Native => {}
            Base::MultiFrame => {
                let values: Vec<u16> = (0..90).map(|i| i * 7).collect();
                image.pixels = Some(DataElement::new(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(values.into())));
                image = image.with(tags::NUMBER_OF_FRAMES, VR::IS, "3").with(tags::SPACING_BETWEEN_SLICES, VR::DS, "2");
            }
            Base::Rle => {
                image.transfer_syntax = RLE;
                image.pixels = Some(encapsulated(vec![rle_constant(30, 1100)]));
            }
            Base::Jpeg2000 => {
                image.transfer_syntax = JPEG2000;
                let mut fragment = vec![0xFF, 0x4F, 0xFF, 0x51, 0x00, 0x29, 0x00, 0x00];
                fragment.extend((0..64u32).map(|i| (i * 29 + 3) as u8));
                image.pixels = Some(encapsulated(vec![fragment]));
            }
            Base::Float => {
                let values: Vec<f32> = (0..30).map(|i| i as f32 - 3.5).collect();
                image.pixels = Some(DataElement::new(Tag(0x7FE0, 0x0008), VR::OF, PrimitiveValue::F32(values.into())));
                image = image.with(tags::BITS_ALLOCATED, VR::US, "32");
            }
        }
        if let Some((count, offsets, body)) = &self.rle {
            image.transfer_syntax = RLE;
            image.pixels = Some(encapsulated(vec![rle_frame(*count, offsets, body)]));
        }
        for &(field, value) in &self.edits {
            let (tag, vr) = FIELDS[field % FIELDS.len()];
            image = image.with(tag, vr, VALUES[value % VALUES.len()]);
        }
        image.bytes()
    }
}

/// The SEG base: a 6×5×3 map of labels 1 and 2 written by `write_segmentation`, with `edits`
/// put into its data set (numbers for US, text otherwise).
fn segmentation_bytes(edits: &[(usize, usize)]) -> Vec<u8> {
    use volgraph_accel::volume::{Volume, VoxelData};
    let values: Vec<u8> = (0..90u32).map(|i| [0, 1, 1, 2, 0][(i % 5) as usize]).collect();
    let map = Volume::new("seg", glam::UVec3::new(6, 5, 3), glam::DVec3::new(0.5, 0.5, 2.0), VoxelData::U8(values));
    let path = scratch_file().with_file_name("segmentation_base.dcm");
    volgraph_accel::load::dicom::write_segmentation(&path, &map, &[(1, "one", [255, 0, 0]), (2, "two", [0, 0, 255])])
        .expect("the SEG base");
    let mut object = dicom_object::open_file(&path).expect("reads back");
    for &(field, value) in edits {
        let (tag, vr) = FIELDS[field % FIELDS.len()];
        let v = VALUES[value % VALUES.len()];
        let value = match vr {
            VR::US => PrimitiveValue::from(v.parse::<u16>().unwrap_or(0)),
            _ => PrimitiveValue::from(v),
        };
        object.put(DataElement::new(tag, vr, value));
    }
    let mut bytes = Vec::new();
    object.write_all(&mut bytes).expect("written");
    bytes
}

fn case() -> impl Strategy<Value = Case> {
    let base = prop_oneof![
        Just(Base::Native),
        Just(Base::MultiFrame),
        Just(Base::Rle),
        Just(Base::Jpeg2000),
        Just(Base::Float),
        Just(Base::Segmentation)
    ];
    let count = prop_oneof![0u32..20, Just(0xFFFF_FFFFu32), any::<u32>()];
    let rle = proptest::option::weighted(
        0.25,
        (
            count,
            proptest::collection::vec(prop_oneof![40u32..200, any::<u32>()], 0..4),
            proptest::collection::vec(any::<u8>(), 0..160),
        ),
    );
    (
        base,
        proptest::collection::vec((0..FIELDS.len(), 0..VALUES.len()), 0..4),
        rle,
        proptest::collection::vec((any::<usize>(), 1..=255u8), 0..3),
        proptest::option::weighted(0.15, 0..1000u16),
        proptest::bool::weighted(0.1),
        proptest::option::weighted(0.3, proptest::collection::vec((0..FIELDS.len(), 0..VALUES.len()), 0..2)),
    )
        .prop_map(|(base, edits, rle, flips, cut, no_preamble, neighbour)| Case {
            base,
            edits,
            rle,
            flips,
            cut,
            no_preamble,
            neighbour,
        })
}

/// This process's scratch file.
fn scratch_file() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("dicom_fuzz").join(std::process::id().to_string());
    std::fs::create_dir_all(&dir).expect("fuzz folder");
    dir.join("IM0001.dcm")
}

#[test]
fn valid_fuzz_bases_load() {
    let path = scratch_file().with_file_name("base.dcm");
    for base in [Base::Native, Base::MultiFrame, Base::Rle, Base::Float, Base::Segmentation] {
        for no_preamble in [false, true] {
            let case =
                Case { base, edits: Vec::new(), rle: None, flips: Vec::new(), cut: None, no_preamble, neighbour: None };
            std::fs::write(&path, case.bytes()).expect("written");
            let loaded = load_volumes(std::slice::from_ref(&path), &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{case:?}: {e}"));
            let want = if matches!(base, Base::MultiFrame | Base::Segmentation) { 90 } else { 30 };
            assert_eq!(loaded.volume.voxel_count(), want, "{case:?}");
        }
    }
}

#[test]
fn hostile_dicom_files_are_errors_never_panics_aborts_or_hangs() {
    if std::env::var_os(CHILD).is_some() {
        return run_cases();
    }
    // The cases run in this test binary again, under the memory limit.
    let exe = std::env::current_exe().expect("the test binary");
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_LIMIT_KIB}; exec \"$0\" \"$@\""))
        .arg(exe)
        .args([
            "--exact",
            "hostile_dicom_files_are_errors_never_panics_aborts_or_hangs",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD, "1")
        .output()
        .expect("the child runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprint!("{stderr}");
    assert!(out.status.success(), "the cases failed or aborted under a 4 GiB limit ({:?}):\n{stderr}", out.status);
}

fn run_cases() {
    let path = scratch_file();
    let mut runner =
        TestRunner::new(Config { cases: fuzz_support::cases(1000), failure_persistence: None, ..Config::default() });
    let harness = Harness::new("dicom fuzz", 50_000);
    let folder = path.parent().expect("a folder").to_path_buf();
    let second = folder.join("IM0002.dcm");
    let name = folder.display().to_string();
    let result = runner.run(&case(), |case| {
        std::fs::write(&path, case.bytes()).expect("written");
        let input = match case.neighbour_bytes() {
            Some(bytes) => {
                std::fs::write(&second, bytes).expect("written");
                folder.clone()
            }
            None => {
                let _ = std::fs::remove_file(&second);
                path.clone()
            }
        };
        harness.run(
            &case,
            || load_volumes(std::slice::from_ref(&input), &LoadOptions::default()),
            |text| {
                // The first line names the file (or its folder); more lines only list series.
                let mut lines = text.lines();
                let first_names = lines.next().is_some_and(|l| l.contains(&name));
                (!first_names || !lines.all(|l| l.starts_with("  ")))
                    .then(|| format!("an error that does not name the file, or forges a line: {text}"))
            },
        );
        Ok(())
    });
    harness.finish(result);
}
