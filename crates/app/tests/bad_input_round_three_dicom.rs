//! Issue 47 (bad input, round three), the DICOM causes through the real binary. Each corrupt
//! file that used to panic (exit 101) or abort on a 10–309 GB allocation runs `volgraph info`
//! under a 4 GiB address-space limit (`ulimit -v`), so an absurd allocation shows as a failed
//! test, not a slow machine: exit status 1 and a message naming the file and the attribute.
//! Fixtures are written with dicom-rs (`crates/accel/tests/dicom_support`).

#[path = "../../accel/tests/dicom_support/mod.rs"]
mod dicom_support;

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use dicom_core::VR;
use dicom_dictionary_std::tags;
use dicom_support::*;

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// `volgraph ARGS` under `ulimit -v 4194304` (4 GiB), killed after `limit`.
fn volgraph_limited(args: &[&str], limit: Duration) -> Run {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 4194304; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("sh runs");
    let started = Instant::now();
    while child.try_wait().expect("waits").is_none() {
        if started.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("volgraph {args:?} did not return within {limit:?} (a hang)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("output");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
}

/// `volgraph info` on `image` written alone as `IM0001.dcm`: must exit 1 (not 101, not killed by
/// the limit) with an error naming the file and every one of `words`.
fn assert_info_fails(name: &str, image: Image, words: &[&str]) {
    let dir = fresh(&root(), name);
    let path = image.write(&dir, "IM0001.dcm");
    let run = volgraph_limited(&["info", path.to_str().expect("utf-8")], Duration::from_secs(60));
    assert_eq!(run.code, Some(1), "exit status (101 = panic, none = killed):\n{}", run.stderr);
    assert!(run.stderr.starts_with("error: "), "{}", run.stderr);
    assert!(run.stderr.contains(&path.display().to_string()), "the file is not named:\n{}", run.stderr);
    for w in words {
        assert!(run.stderr.contains(w), "missing {w:?} in:\n{}", run.stderr);
    }
    assert_eq!(run.stderr.lines().count(), 1, "one line, the error:\n{}", run.stderr);
}

fn rle_image(fragment: Vec<u8>) -> Image {
    Image { transfer_syntax: RLE, pixels: Some(encapsulated(vec![fragment])), ..Image::default() }
}

#[test]
fn rle_short_segment_is_exit_1_not_a_panic() {
    assert_info_fails(
        "cli_rle_short",
        rle_image(rle_frame(2, &[64, 66], &[0xFE, 1, 0xFE, 2])),
        &["RLE frame 0: segment 0 decodes to 3 bytes"],
    );
}

#[test]
fn rle_tiny_frame_is_exit_1_not_a_panic() {
    assert_info_fails("cli_rle_tiny", rle_image(vec![9, 0]), &["shorter than the 64-byte RLE header"]);
}

#[test]
fn rle_header_claiming_0xffffffff_segments_is_exit_1_not_an_abort() {
    assert_info_fails(
        "cli_rle_segments",
        rle_image(rle_frame(0xFFFF_FFFF, &[64], &[0; 8])),
        &["claims 4294967295 segments; the standard allows 1 to 15"],
    );
}

#[test]
fn junk_as_an_rle_frame_is_exit_1_not_an_abort() {
    let junk: Vec<u8> = (0..4000u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8 | 0x81).collect();
    assert_info_fails("cli_rle_junk", rle_image(junk), &["RLE frame 0"]);
}

#[test]
fn number_of_frames_1e8_or_2_to_the_31_is_exit_1_not_an_abort() {
    for frames in ["100000000", "2147483647"] {
        assert_info_fails(
            "cli_frames",
            Image::default().with(tags::NUMBER_OF_FRAMES, VR::IS, frames),
            &[&format!("NumberOfFrames (0028,0008) {frames}"), "but the file has only"],
        );
    }
}

#[test]
fn a_malformed_rescale_slope_is_exit_1_naming_the_attribute() {
    assert_info_fails(
        "cli_slope",
        Image::default().with(tags::RESCALE_SLOPE, VR::DS, "abc"),
        &["cannot use RescaleSlope (0028,1053) = \"abc\""],
    );
}

#[test]
fn a_corrupt_jpeg2000_frame_prints_only_the_error_not_the_decoders_log() {
    // The JPEG 2000 start-of-codestream and size markers (the header's 5 × 6 pixels, one
    // component), then junk.
    let mut fragment = siz(5, 6);
    fragment.extend((0..200u32).map(|i| (i * 37 + 11) as u8));
    let image = Image { transfer_syntax: JPEG2000, pixels: Some(encapsulated(vec![fragment])), ..Image::default() };
    assert_info_fails("cli_jpeg2k", image, &["cannot decode the pixel data"]);
}

/// SOC and a SIZ marker (ITU-T T.800 A.5.1) for `width` × `height` pixels of one 16-bit
/// component, in one tile.
fn siz(width: u32, height: u32) -> Vec<u8> {
    let mut bytes = vec![0xFF, 0x4F, 0xFF, 0x51, 0x00, 0x29, 0x00, 0x00];
    for v in [width, height, 0, 0, width, height, 0, 0] {
        bytes.extend(v.to_be_bytes());
    }
    bytes.extend([0x00, 0x01, 0x0F, 0x01, 0x01]);
    bytes
}

/// A codestream claiming 60000 × 60000 pixels under Rows 6 and Columns 5: OpenJPEG would
/// decode (and allocate) at the codestream's size; it is refused from its SIZ marker first.
#[test]
fn a_jpeg2000_codestream_larger_than_rows_and_columns_is_refused_before_decoding() {
    let mut fragment = siz(60000, 60000);
    fragment.extend((0..200u32).map(|i| (i * 37 + 11) as u8));
    let image = Image { transfer_syntax: JPEG2000, pixels: Some(encapsulated(vec![fragment])), ..Image::default() };
    assert_info_fails("cli_jpeg2k_siz", image, &["SIZ marker says 60000 × 60000 pixels", "are 5 × 6"]);
}

#[cfg(unix)]
#[test]
fn info_on_a_folder_with_two_links_to_itself_returns() {
    let dir = fresh(&root(), "cli_links");
    series(&dir, 3, &Image::default());
    std::os::unix::fs::symlink(".", dir.join("x")).expect("link");
    std::os::unix::fs::symlink(".", dir.join("y")).expect("link");
    let run = volgraph_limited(&["info", dir.to_str().expect("utf-8")], Duration::from_secs(60));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(run.stdout.contains("5 × 6 × 3 voxels"), "{}", run.stdout);
}

#[test]
fn a_newline_in_a_series_description_cannot_forge_a_line_in_info() {
    let dir = fresh(&root(), "cli_newline");
    series(&dir, 2, &Image { description: "axial\nerror: fake message".into(), ..Image::default() });
    let run = volgraph_limited(&["info", dir.to_str().expect("utf-8")], Duration::from_secs(60));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let all = format!("{}{}", run.stdout, run.stderr);
    assert!(!all.lines().any(|l| l.starts_with("error")), "a forged line:\n{all}");
    assert!(run.stdout.contains("description  axial\\nerror: fake message"), "{}", run.stdout);
    assert!(run.stdout.contains("\"axial\\nerror: fake message\""), "{}", run.stdout);
}

#[test]
fn a_file_without_the_preamble_is_described() {
    let dir = fresh(&root(), "cli_no_preamble");
    let path = dir.join("IM0001.dcm");
    std::fs::write(&path, &Image::default().bytes()[128..]).expect("written");
    let run = volgraph_limited(&["info", path.to_str().expect("utf-8")], Duration::from_secs(60));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(run.stdout.contains("5 × 6 × 1 voxels"), "{}", run.stdout);
}

/// A NIfTI-1 file of 2×2×2 uint8 voxels whose `descrip` is `description`.
fn nifti_with_description(description: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3i16, 2, 2, 2, 1, 1, 1, 1].iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes()); // uint8
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    for i in 0..8 {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[148..148 + description.len()].copy_from_slice(description);
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend([0, 10, 20, 30, 40, 50, 60, 70]);
    h
}

#[test]
fn a_newline_in_a_nifti_description_cannot_forge_a_line_in_info() {
    let dir = fresh(&root(), "cli_nifti_newline");
    let path = dir.join("head.nii");
    std::fs::write(&path, nifti_with_description(b"T1\nerror: fake message")).expect("written");
    let run = volgraph_limited(&["info", path.to_str().expect("utf-8")], Duration::from_secs(60));
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let all = format!("{}{}", run.stdout, run.stderr);
    assert!(!all.lines().any(|l| l.starts_with("error")), "a forged line:\n{all}");
    assert!(run.stdout.contains("description  T1\\nerror: fake message"), "{}", run.stdout);
}
