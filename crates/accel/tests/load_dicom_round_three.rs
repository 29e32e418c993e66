//! Issue 47 (bad input, round three), the DICOM causes at the loader: corrupt scanner files are
//! errors naming the file and the attribute (never a panic or an absurd allocation), a folder
//! with link loops is read once, header text cannot forge lines, malformed attributes are never
//! replaced by defaults, and the messages say what the file holds. Fixtures are written here
//! with dicom-rs (`dicom_support`).

mod dicom_support;

use std::path::{Path, PathBuf};

use dicom_core::{Tag, VR};
use dicom_dictionary_std::tags;
use dicom_support::*;
use volgraph_accel::load::dicom::{self, DicomOptions};
use volgraph_accel::load::{LoadOptions, LoadedVolume, load_volumes};
use volgraph_accel::volume::VoxelData;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
}

fn load(paths: &[PathBuf]) -> Result<LoadedVolume, String> {
    load_volumes(paths, &LoadOptions::default()).map_err(|e| e.to_string())
}

/// One file `name` of `image` in a fresh folder, loaded: the error text.
fn error_of(name: &str, image: Image) -> (PathBuf, String) {
    let dir = fresh(&root(), name);
    let path = image.write(&dir, "IM0001.dcm");
    let e = load(std::slice::from_ref(&path)).map(|v| v.volume.dims).expect_err("an error");
    (path, e)
}

fn assert_names(e: &str, path: &Path, words: &[&str]) {
    assert!(e.contains(&path.display().to_string()), "the file is not named: {e}");
    for w in words {
        assert!(e.contains(w), "missing {w:?} in: {e}");
    }
}

fn rle_image(fragment: Vec<u8>) -> Image {
    Image { transfer_syntax: RLE, pixels: Some(encapsulated(vec![fragment])), ..Image::default() }
}

#[test]
fn a_valid_rle_frame_still_loads() {
    let dir = fresh(&root(), "rle_valid");
    let path = rle_image(rle_constant(30, 1100)).write(&dir, "IM0001.dcm");
    let v = load(&[path]).expect("loads").volume;
    assert_eq!(v.raw_value(0), 1100.0 - 1024.0);
}

#[test]
fn rle_short_segment_is_an_error_not_a_panic() {
    // Two segments of one 3-byte run each: 3 bytes where Rows × Columns is 30.
    let (path, e) = error_of("rle_short", rle_image(rle_frame(2, &[64, 66], &[0xFE, 1, 0xFE, 2])));
    assert_names(&e, &path, &["RLE frame 0", "segment 0 decodes to 3 bytes, fewer than the 30 pixels"]);
}

#[test]
fn rle_tiny_frame_is_an_error_not_a_panic() {
    let (path, e) = error_of("rle_tiny", rle_image(vec![1, 0]));
    assert_names(&e, &path, &["RLE frame 0: 2 bytes, shorter than the 64-byte RLE header"]);
}

#[test]
fn rle_header_claiming_four_billion_segments_is_refused_before_allocating() {
    let (path, e) = error_of("rle_segments", rle_image(rle_frame(0xFFFF_FFFF, &[64], &[0; 8])));
    assert_names(&e, &path, &["the header claims 4294967295 segments; the standard allows 1 to 15"]);
}

#[test]
fn junk_as_an_rle_frame_is_an_error() {
    let junk: Vec<u8> = (0..200u32).map(|i| (i * 97 + 13) as u8 | 0x80).collect();
    let (path, e) = error_of("rle_junk", rle_image(junk));
    assert_names(&e, &path, &["RLE frame 0", "the standard allows 1 to 15"]);
}

#[test]
fn rle_segment_offset_past_the_fragment_is_an_error() {
    let (path, e) = error_of("rle_offset", rle_image(rle_frame(2, &[64, 9000], &[0xE3, 1, 0xE3, 2])));
    assert_names(&e, &path, &["segment 1 starts at byte 9000"]);
}

#[test]
fn number_of_frames_beyond_the_file_is_refused_before_allocating() {
    for frames in ["100000000", "2147483647"] {
        let (path, e) = error_of("frames", Image::default().with(tags::NUMBER_OF_FRAMES, VR::IS, frames));
        assert_names(
            &e,
            &path,
            &[&format!("NumberOfFrames (0028,0008) {frames}"), "bytes of pixel data, but the file has only"],
        );
    }
}

#[test]
fn rows_zero_is_an_error_naming_the_attribute() {
    let (path, e) = error_of("rows0", Image { rows: 0, ..Image::default() });
    assert_names(&e, &path, &["cannot use Rows (0028,0010) = \"0\"", "from 1 to 65535"]);
}

#[test]
fn truncated_native_pixel_data_is_an_error_naming_its_size() {
    let short = dicom_core::DataElement::new(
        tags::PIXEL_DATA,
        VR::OW,
        dicom_core::value::PrimitiveValue::U16(vec![1u16; 7].into()),
    );
    let (path, e) = error_of("short_native", Image { pixels: Some(short), ..Image::default() });
    assert_names(&e, &path, &["PixelData (7FE0,0010) holds 14 bytes", "need 60"]);
}

#[test]
fn a_corrupt_length_is_an_error_before_dicom_rs_sizes_a_buffer_by_it() {
    // PhotometricInterpretation's VR "CS" made unknown: read as UN, its 4-byte length is
    // "MONO" (1.3 GB) in an 800-byte file; dicom-parser would allocate and zero that first.
    let dir = fresh(&root(), "bad_length");
    let mut bytes = Image::default().bytes();
    let at = bytes.windows(6).position(|w| w == [0x28, 0x00, 0x04, 0x00, b'C', b'S']).expect("the element");
    bytes[at + 4..at + 6].copy_from_slice(b"XX");
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &bytes).expect("written");
    let e = load(std::slice::from_ref(&path)).map(|_| ()).expect_err("an error");
    assert_names(&e, &path, &[&format!("element (0028,0004) at byte {at} claims 1330532173 bytes, but only")]);
}

#[test]
fn an_item_delimiter_outside_a_sequence_does_not_end_the_length_walk() {
    // Found by the DICOM fuzzer's segmentation base (1 M cases, 2 took 20 s and 3.7 GB): a
    // flipped length made the walk land on an item delimiter at the top level, where it stopped
    // checking, while dicom-rs read on into a length it then allocated. Here: a delimiter
    // after the pixel data, then an element claiming 268 MB in a file of a few hundred bytes.
    let dir = fresh(&root(), "top_level_delimiter");
    let mut bytes = Image::default().bytes();
    bytes.extend([0xFE, 0xFF, 0x0D, 0xE0, 0, 0, 0, 0]);
    let at = bytes.len();
    bytes.extend([0x09, 0x00, 0x10, 0x00, b'U', b'N', 0, 0, 0xF0, 0xFF, 0xFF, 0x0F]);
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &bytes).expect("written");
    let e = load(std::slice::from_ref(&path)).map(|_| ()).expect_err("an error");
    assert_names(&e, &path, &[&format!("element (0009,0010) at byte {at} claims 268435440 bytes, but only 0")]);
}

#[test]
fn a_length_that_is_not_a_whole_number_of_values_is_an_error_not_seconds_of_allocation() {
    // Found by the fuzzer: HighBit's VR US flipped to UL keeps its length 2; dicom-rs reads no
    // 4-byte value, leaves 2 bytes, and takes value bytes as the next header (a 1.5 GB length).
    let dir = fresh(&root(), "misaligned");
    let mut bytes = Image::default().bytes();
    let at = bytes.windows(6).position(|w| w == [0x28, 0x00, 0x02, 0x01, b'U', b'S']).expect("HighBit");
    bytes[at + 5] = b'L';
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &bytes).expect("written");
    let started = std::time::Instant::now();
    let e = load(std::slice::from_ref(&path)).map(|_| ()).expect_err("an error");
    assert_names(
        &e,
        &path,
        &[&format!("element (0028,0102) at byte {at} has VR UL and length 2, not a multiple of its 4-byte values")],
    );
    assert!(started.elapsed().as_millis() < 500, "{:?}", started.elapsed());
}

#[test]
fn an_undefined_length_outside_pixel_data_is_an_error_not_a_4_gb_read() {
    // Found by the fuzzer: RLE PixelData's tag flipped to (7FB8,0010) keeps VR OB and length
    // 0xFFFFFFFF, which dicom-rs read as 4 GB to allocate and zero (11 s).
    let dir = fresh(&root(), "undefined_ob");
    let mut bytes = rle_image(rle_constant(30, 1100)).bytes();
    let at = bytes.windows(4).position(|w| w == [0xE0, 0x7F, 0x10, 0x00]).expect("PixelData");
    bytes[at] = 0xB8;
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &bytes).expect("written");
    let started = std::time::Instant::now();
    let e = load(std::slice::from_ref(&path)).map(|_| ()).expect_err("an error");
    assert_names(&e, &path, &[&format!("element (7FB8,0010) at byte {at} has VR OB and an undefined length")]);
    assert!(started.elapsed().as_millis() < 500, "{:?}", started.elapsed());
}

fn folder_of_three(name: &str) -> PathBuf {
    let dir = fresh(&root(), name);
    series(&dir, 3, &Image::default());
    dir
}

#[cfg(unix)]
#[test]
fn a_folder_with_link_loops_is_read_once() {
    let dir = folder_of_three("link_loops");
    // Two links to the folder itself: 2^depth paths if followed blindly.
    std::os::unix::fs::symlink(".", dir.join("x")).expect("link");
    std::os::unix::fs::symlink(".", dir.join("y")).expect("link");
    let started = std::time::Instant::now();
    let v = load(&[dir]).expect("loads once").volume;
    assert_eq!(v.dims.z, 3, "each slice once");
    assert!(started.elapsed().as_secs() < 20, "the walk took {:?}", started.elapsed());
}

#[cfg(unix)]
#[test]
fn a_file_reached_through_two_links_is_one_slice() {
    let dir = folder_of_three("file_links");
    std::os::unix::fs::symlink(dir.join("IM0001"), dir.join("again")).expect("link");
    let v = load(&[dir]).expect("no duplicate-position error").volume;
    assert_eq!(v.dims.z, 3);
}

#[test]
fn a_newline_in_the_description_cannot_forge_a_line() {
    let dir = fresh(&root(), "newline");
    series(&dir.join("a"), 2, &Image { description: "axial\nerror: fake message".into(), ..Image::default() });
    series(
        &dir.join("b"),
        2,
        &Image { series_uid: "2.25.4702".into(), description: "b\r\u{1b}[2J".into(), ..Image::default() },
    );
    let list = dicom::series_list(&dicom::list_series(std::slice::from_ref(&dir)).expect("listed"));
    assert!(list.lines().all(|l| l.starts_with("  ")), "a forged line in:\n{list}");
    assert!(list.contains("\"axial\\nerror: fake message\""), "{list}");
    assert!(list.contains("\"b\\r\\u{1b}[2J\""), "{list}");
    let e = load(std::slice::from_ref(&dir)).map(|_| ()).expect_err("two series");
    assert!(e.lines().all(|l| !l.starts_with("error")), "a forged line in:\n{e}");
    let one = load(&[dir.join("a")]).expect("one series").volume;
    assert_eq!(one.name, "axial\\nerror: fake message", "the name is shown in notes");
    assert_eq!(one.meta.description.as_deref(), Some("axial\nerror: fake message"), "the raw text is kept");
}

#[test]
fn dicom_rs_quoting_a_newline_from_the_file_cannot_forge_a_line() {
    // Found by the fuzzer: a transfer syntax UID with a newline, quoted by dicom-rs's error.
    let dir = fresh(&root(), "ts_newline");
    let mut bytes = Image::default().bytes();
    let at = bytes.windows(19).position(|w| w == EXPLICIT_LE.as_bytes()).expect("the UID");
    bytes[at + 12] = b'\n';
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &bytes).expect("written");
    let e = load(std::slice::from_ref(&path)).map(|_| ()).expect_err("an error");
    assert_names(&e, &path, &["1.2.840.1000\\n.1.2.1"]);
    assert_eq!(e.lines().count(), 1, "{e}");
}

#[test]
fn numbers_written_with_vr_un_are_read_as_their_text() {
    // As pydicom's rtdose_rle.dcm has them: DS text in an element whose VR is UN.
    let dir = fresh(&root(), "un_numbers");
    let path = Image::default().write(&dir, "IM0001.dcm");
    let mut o = dicom_object::open_file(&path).expect("written");
    o.put(dicom_core::DataElement::new(
        tags::PIXEL_SPACING,
        VR::UN,
        dicom_core::value::PrimitiveValue::U8(b"0.25\\0.75".to_vec().into()),
    ));
    o.write_to_file(&path).expect("rewritten");
    let v = load(&[path]).expect("loads").volume;
    assert_eq!((v.spacing.x, v.spacing.y), (0.75, 0.25), "column spacing along x, row spacing along y");
}

#[test]
fn a_dicom_file_without_an_image_says_so() {
    let image = Image { remove: vec![tags::ROWS, tags::COLUMNS], ..Image::default() };
    let (path, e) = error_of("no_image", image);
    assert_names(&e, &path, &["is a DICOM object without an image (no Rows or Columns"]);
}

#[test]
fn a_malformed_rescale_slope_is_an_error_not_one() {
    for bad in ["NaN", "abc", "0"] {
        let (path, e) = error_of("slope", Image::default().with(tags::RESCALE_SLOPE, VR::DS, bad));
        assert_names(&e, &path, &[&format!("cannot use RescaleSlope (0028,1053) = \"{bad}\""), "finite, non-zero"]);
    }
}

#[test]
fn pixel_spacing_with_one_or_three_values_is_an_error_not_one_mm() {
    for bad in ["0.5", "0.5\\0.5\\0.5", "-1\\1"] {
        let (path, e) = error_of("spacing", Image::default().with(tags::PIXEL_SPACING, VR::DS, bad));
        assert_names(&e, &path, &["cannot use PixelSpacing (0028,0030)", "two positive numbers"]);
    }
}

#[test]
fn a_five_value_orientation_is_an_error_not_identity() {
    let (path, e) = error_of("iop5", Image::default().with(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, "1\\0\\0\\0\\1"));
    assert_names(
        &e,
        &path,
        &["cannot use ImageOrientationPatient (0020,0037) = \"1\\0\\0\\0\\1\"", "six finite numbers"],
    );
}

#[test]
fn palette_colour_is_an_error_not_grey_indices() {
    let (path, e) =
        error_of("palette", Image::default().with(tags::PHOTOMETRIC_INTERPRETATION, VR::CS, "PALETTE COLOR"));
    assert_names(&e, &path, &["PhotometricInterpretation (0028,0004) is PALETTE COLOR", "indices into a colour table"]);
}

#[test]
fn uint32_above_two_to_the_31_is_kept_not_clamped() {
    let dir = fresh(&root(), "uint32");
    let values: Vec<u32> = (0..30).map(|i| 3_000_000_000 + i * 256).collect();
    let image = Image {
        pixels: Some(dicom_core::DataElement::new(
            tags::PIXEL_DATA,
            VR::OW,
            dicom_core::value::PrimitiveValue::U32(values.into()),
        )),
        ..Image::default()
    }
    .with(tags::BITS_ALLOCATED, VR::US, "32")
    .with(tags::BITS_STORED, VR::US, "32")
    .with(tags::HIGH_BIT, VR::US, "31")
    .with(tags::RESCALE_INTERCEPT, VR::DS, "0");
    let loaded = load(&[image.write(&dir, "IM0001.dcm")]).expect("loads");
    assert!(matches!(loaded.volume.data, VoxelData::F32(_)));
    let v = &loaded.volume;
    assert!((v.raw_value(0) - 3e9).abs() < 1e3, "{}", v.raw_value(0));
    assert!(v.raw_value(29) > v.raw_value(0), "not clamped to one value");
    assert!(
        loaded.report.notes.iter().any(|n| n.contains("rounded to 24 significant bits")),
        "{:?}",
        loaded.report.notes
    );
}

#[test]
fn a_rescale_to_infinity_is_an_error_not_a_constant_volume() {
    let image =
        Image::default().with(tags::RESCALE_SLOPE, VR::DS, "1e300").with(tags::RESCALE_INTERCEPT, VR::DS, "1e39");
    let (path, e) = error_of("inf", image);
    assert_names(&e, &path, &["RescaleSlope (0028,1053) 1e300", "beyond float32's ±3.4e38"]);
}

/// Two series described `axial` and `AXIAL` (and, with `third`, another `axial`).
fn two_described(name: &str, third: bool) -> PathBuf {
    let dir = fresh(&root(), name);
    series(&dir.join("a"), 2, &Image { description: "axial".into(), ..Image::default() });
    series(
        &dir.join("b"),
        2,
        &Image { series_uid: "2.25.4702".into(), description: "AXIAL".into(), ..Image::default() },
    );
    if third {
        series(
            &dir.join("c"),
            2,
            &Image { series_uid: "2.25.4703".into(), description: "axial".into(), ..Image::default() },
        );
    }
    dir
}

fn series_error(dir: PathBuf, wanted: &str) -> Result<String, String> {
    let options = DicomOptions { series: Some(wanted.into()) };
    dicom::load(&[dir], &options, None).map(|v| v.volume.name).map_err(|e| e.to_string())
}

#[test]
fn an_ambiguous_series_description_is_an_error_listing_the_candidates() {
    let dir = two_described("series_case", false);
    assert_eq!(series_error(dir.clone(), "AXIAL").expect("the exact spelling wins"), "AXIAL");
    assert_eq!(series_error(dir.clone(), "axial").expect("the exact spelling wins"), "axial");
    let e = series_error(dir, "Axial").expect_err("two equal ignoring case");
    assert!(e.contains("2 series under") && e.contains("\"axial\"") && e.contains("\"AXIAL\""), "{e}");
    let e = series_error(two_described("series_twice", true), "axial").expect_err("two exact");
    assert!(e.contains("2 series under") && e.contains("--series N or --series UID"), "{e}");
}

#[test]
fn a_geometry_error_prints_the_orientation_with_sane_precision() {
    let (_, e) =
        error_of("iop_huge", Image::default().with(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, "1e300\\0\\0\\0\\1\\0"));
    assert!(
        e.contains(
            "ImageOrientationPatient (0020,0037) 1.000e300\\0\\0\\0\\1\\0 is not two perpendicular unit vectors"
        ),
        "{e}"
    );
    assert!(!e.contains("000000000000"), "a long number: {e}");
}

#[test]
fn a_file_without_the_preamble_is_read_as_dicom() {
    let dir = fresh(&root(), "no_preamble");
    let bytes = Image::default().bytes();
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &bytes[128..]).expect("written");
    let v = load(&[path]).expect("read without the preamble").volume;
    assert_eq!(v.raw_value(0), f64::from(value(0, 0)) - 1024.0);
}

#[test]
fn float_pixel_data_is_read_as_float32() {
    let dir = fresh(&root(), "float_pixels");
    let values: Vec<f32> = (0..30).map(|i| i as f32 * 0.25 - 2.0).collect();
    let mut image = Image {
        pixels: Some(dicom_core::DataElement::new(
            Tag(0x7FE0, 0x0008),
            VR::OF,
            dicom_core::value::PrimitiveValue::F32(values.clone().into()),
        )),
        ..Image::default()
    }
    .with(tags::BITS_ALLOCATED, VR::US, "32");
    image.remove = vec![
        tags::RESCALE_SLOPE,
        tags::RESCALE_INTERCEPT,
        tags::BITS_STORED,
        tags::HIGH_BIT,
        tags::PIXEL_REPRESENTATION,
    ];
    let v = load(&[image.write(&dir, "IM0001.dcm")]).expect("loads").volume;
    assert!(matches!(v.data, VoxelData::F32(_)));
    assert_eq!(v.raw_value(5), f64::from(values[5]));
}

#[test]
fn a_file_without_pixel_data_says_so() {
    let (path, e) = error_of("no_pixels", Image::default().without_pixels());
    assert_names(&e, &path, &["has no pixel data (no PixelData (7FE0,0010), Float Pixel Data (7FE0,0008)"]);
}

trait WithoutPixels {
    fn without_pixels(self) -> Image;
}

impl WithoutPixels for Image {
    /// The image with a pixel element that is not pixel data (an empty Overlay Data element
    /// stands in, so that the default 16-bit PixelData is not written either).
    fn without_pixels(self) -> Image {
        Image {
            pixels: Some(dicom_core::DataElement::new(
                Tag(0x6000, 0x3000),
                VR::OW,
                dicom_core::value::PrimitiveValue::U16(vec![0u16; 4].into()),
            )),
            ..self
        }
    }
}
