//! Issue 47, "bad input, round three": the NIfTI, general-loading and preset causes, through the
//! real binary. Every run is bounded in time (a hang fails) and in address space (`ulimit -v`
//! 4 GiB: an allocation the input does not justify aborts, and an abort fails), and checks the
//! exit status and the message; none may panic.

use std::io::{Read as _, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

/// Runs volgraph with `args` under a 4 GiB address-space limit, failing after 60 s.
fn volgraph(args: &[&str]) -> Run {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 4194304; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(&root)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("sh runs the volgraph binary");
    let (mut out, mut err) = (child.stdout.take().expect("piped"), child.stderr.take().expect("piped"));
    let out_reader = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = out.read_to_end(&mut b);
        b
    });
    let err_reader = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = err.read_to_end(&mut b);
        b
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("waits") {
            break status;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} hung: still running after 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let run = Run {
        code: status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out_reader.join().unwrap_or_default()).into_owned(),
        stderr: String::from_utf8_lossy(&err_reader.join().unwrap_or_default()).into_owned(),
    };
    assert_ne!(run.code, -1, "{args:?} was killed by a signal (an abort?):\n{}", run.stderr);
    assert_ne!(run.code, 101, "{args:?} panicked:\n{}", run.stderr);
    assert!(!run.stderr.contains("memory allocation"), "{args:?} aborted:\n{}", run.stderr);
    run
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("round_three_nifti").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// A NIfTI-1 file (`n+1`, data at byte 352): `dims` voxels of `datatype`, `pixdim` sizes, no
/// orientation, every field in the byte order asked for.
fn nifti1(dims: [i16; 3], datatype: i16, pixdim: [f32; 3], big: bool, data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let mut put = |at: usize, le: &[u8]| {
        let mut b = le.to_vec();
        if big {
            b.reverse();
        }
        h[at..at + b.len()].copy_from_slice(&b);
    };
    put(0, &348i32.to_le_bytes());
    for (i, d) in [3, dims[0], dims[1], dims[2], 1, 1, 1, 1].iter().enumerate() {
        put(40 + 2 * i, &d.to_le_bytes());
    }
    put(70, &datatype.to_le_bytes());
    for (i, p) in [1.0, pixdim[0], pixdim[1], pixdim[2]].iter().enumerate() {
        put(76 + 4 * i, &p.to_le_bytes());
    }
    put(108, &352f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(data);
    h
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).expect("gzip into memory");
    enc.finish().expect("gzip into memory")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write the fixture");
    path.display().to_string()
}

#[test]
fn nii_gz_of_zeros_is_refused_from_its_header_not_inflated_whole() {
    // 5 GiB of zeros in 80 gzip members of 64 MiB (5 MB on disk): inflated whole it would not
    // fit the 4 GiB limit; read header first, four bytes say it is not NIfTI.
    let dir = scratch("zeros");
    let path = write(&dir, "zeros.nii.gz", &gzip(&vec![0u8; 64 << 20]).repeat(80));
    let run = volgraph(&["info", &path]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "{path}: cannot read the NIfTI file: not a NIfTI file: the header size (sizeof_hdr, bytes 0..4 once \
             inflated) is 0"
        )),
        "{}",
        run.stderr
    );
    // A valid header followed by the same 5 GiB: only the voxels the header asks for are read.
    let mut bytes = gzip(&nifti1([4, 4, 4], 2, [1.0; 3], false, &[3; 64]));
    bytes.extend(gzip(&vec![0u8; 64 << 20]).repeat(80));
    let path = write(&dir, "trailing.nii.gz", &bytes);
    let run = volgraph(&["info", &path]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains("4 × 4 × 4 voxels, uint8"), "{}", run.stdout);
}

#[test]
fn nifti_size_error_names_the_real_datatype_and_dimensions() {
    let dir = scratch("size");
    // Big-endian int32, 300 × 2 × 8, with 100 of its 4800 voxels.
    let path = write(&dir, "short.nii", &nifti1([300, 2, 8], 8, [1.0; 3], true, &[0; 400]));
    let run = volgraph(&["info", &path]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "{path}: cannot read the NIfTI file: 300x2x8 int32 voxels need 19200 bytes from byte 352 (to byte 19552), \
             but the file has 752 bytes"
        )),
        "{}",
        run.stderr
    );
}

#[test]
fn nifti_dimension_errors_read_as_prose() {
    let dir = scratch("prose");
    let path = write(&dir, "negative.nii", &nifti1([4, -3, 4], 2, [1.0; 3], false, &[0; 64]));
    let run = volgraph(&["info", &path]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "{path}: cannot read the NIfTI file: dim[2] is -3 (dim = 4 × -3 × 4); every axis needs at least one voxel"
        )),
        "{}",
        run.stderr
    );
}

#[test]
fn frame_on_a_3d_nifti_says_the_file_is_3d_not_a_4d_series() {
    let dir = scratch("frame");
    let path = write(&dir, "three.nii", &nifti1([4, 4, 4], 2, [1.0; 3], false, &[0; 64]));
    let run = volgraph(&["info", &path, "--frame", "1"]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(!run.stderr.contains("4D series"), "{}", run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "{path}: --frame picks a volume of a 4D NIfTI file, but this file holds a single 3D volume: there are no \
             frames to pick; remove --frame"
        )),
        "{}",
        run.stderr
    );
}

#[test]
fn header_spacing_with_a_million_to_one_ratio_is_refused_like_the_spacing_flag() {
    let dir = scratch("spacing");
    let path = write(&dir, "flat.nii", &nifti1([4, 4, 4], 2, [1.0, 1.0, 1e6], false, &[1; 64]));
    let run = volgraph(&["info", &path]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "{path}: the header's voxel spacing (1, 1, 1000000): the longest voxel side is 1.0e6 times the shortest; \
             at most 1e4"
        )),
        "{}",
        run.stderr
    );
    let flag = volgraph(&["info", &path, "--spacing", "1,1,1e6"]);
    assert_eq!(flag.code, 1, "{}", flag.stderr);
    assert!(flag.stderr.contains("the longest voxel side is 1.0e6 times the shortest; at most 1e4"), "{}", flag.stderr);
    let fixed = volgraph(&["info", &path, "--spacing", "1,1,2"]);
    assert_eq!(fixed.code, 0, "{}", fixed.stderr);
}

#[test]
fn constant_int16_volume_reports_its_value_not_the_type_range() {
    let dir = scratch("constant");
    let data: Vec<u8> = std::iter::repeat_n(7i16.to_le_bytes(), 64).flatten().collect();
    let path = write(&dir, "flat16.nii", &nifti1([4, 4, 4], 4, [1.0; 3], false, &data));
    let run = volgraph(&["info", &path]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.contains("value range  7 … 7"), "{}", run.stdout);
    assert!(!run.stdout.contains("-32768"), "{}", run.stdout);
    assert!(
        run.stderr.contains(&format!(
            "note: {path}: every voxel holds the value 7: the volume is constant, so a transfer function shows it as an \
             empty or a uniform box"
        )),
        "{}",
        run.stderr
    );
    // Drawn with the default TF it is the background with the same note a constant float32
    // volume gets, not a solid box.
    let out = dir.join("flat16.png").display().to_string();
    let run =
        volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--volume", &path, "-o", &out, "--size", "16x16"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stderr.contains("volume \"flat16\" is constant (every voxel normalizes to 0.0000)"), "{}", run.stderr);
}

#[test]
fn misspelt_tf_presets_get_a_did_you_mean_not_just_no_such_file() {
    let out = scratch("tf").join("out.png").display().to_string();
    for typo in ["ct-bones", "CT-BONE", "ct_bone"] {
        let run = volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--tf", typo, "-o", &out]);
        assert_eq!(run.code, 1, "{typo}: {}", run.stderr);
        assert!(
            run.stderr.contains(&format!("{typo}: cannot read the transfer function"))
                && run.stderr.contains(
                    "did you mean the built-in preset \"ct-bone\" (--tf ct-bone)? The presets are ct-bone, \
                     ct-soft-tissue, ct-lung, ct-angio and mr-default"
                ),
            "{typo}: {}",
            run.stderr
        );
    }
    let run = volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--tf", "zzz", "-o", &out]);
    assert_eq!(run.code, 1, "{}", run.stderr);
    assert!(run.stderr.contains("nor is it a built-in preset (they are ct-bone, ct-soft-tissue"), "{}", run.stderr);
    assert!(run.stderr.contains("or a transfer function of the data folder"), "{}", run.stderr);
}
