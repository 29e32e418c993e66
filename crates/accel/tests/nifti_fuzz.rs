//! The NIfTI fuzzer (issue 47): valid NIfTI-1 and NIfTI-2 files, plain and gzip, little and big
//! endian, 3D and 4D, with header fields replaced by hostile values (sizes 0, negative and
//! 2³¹−1, every datatype code and junk ones, vox_offset inside the header, past the file, NaN;
//! pixdim, srow and quaternions NaN, ±inf, 0, huge; scl_slope/scl_inter NaN, inf, 0, huge; the
//! magic and `sizeof_hdr`'s byte order broken), random bytes overwritten, the file cut short,
//! and any frame asked for. Every read must return Ok or Err: a panic or a case slower than
//! `HANG_SECONDS` fails the test; a watchdog ends the process on a real hang. Small files only,
//! so a loader that allocated what a hostile header claims (rather than what the file holds)
//! would show; run it under `ulimit -v` to make such an allocation an abort.
//!
//! `VOLGRAPH_FUZZ_CASES` sets the number of cases (default 2000, a few seconds); the summary
//! line on stderr gives the counts a long run is recorded with. The watchdog, the counters and
//! `HANG_SECONDS` are `fuzz_support`'s, shared with the DICOM fuzzer.

mod fuzz_support;
mod nifti_support;

use std::path::Path;

use fuzz_support::Harness;
use nifti_support::{NiftiSpec, gzip, voxels};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// The datatype codes tried: every one the loader reads, the ones it refuses, and junk.
const DATATYPES: &[i16] =
    &[2, 4, 8, 16, 64, 256, 512, 768, 1024, 1280, 0, 1, 32, 128, 1536, 1792, 2048, 2304, -1, 32767];

/// Hostile sizes (`dim[1..=7]`).
const SIZES: &[i64] =
    &[0, -1, 1, 2, 3, 255, 32767, -32768, 65535, 2147483647, -2147483648, 4294967296, i64::MAX, i64::MIN];

/// Hostile `dim[0]` values.
const NDIMS: &[i64] = &[0, 1, 2, 3, 4, 5, 7, 8, -1, 32767];

/// Hostile floats (pixdim, srow, quatern, scl, vox_offset).
const FLOATS: &[f64] = &[
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    -1.0,
    1.0,
    0.5,
    2.0,
    1e-30,
    1e30,
    3.0e38,
    -3.0e38,
    1e300,
    351.0,
    352.0,
    544.0,
    1e9,
    4294967296.0,
    9.3e18,
];

/// One field replaced: which field, which value (an index into the field's list), which axis.
#[derive(Clone, Copy, Debug)]
struct Edit {
    field: u8,
    value: usize,
    axis: usize,
}

/// One fuzz case, made into bytes by [`Case::bytes`].
#[derive(Clone, Debug)]
struct Case {
    version: u8,
    big: bool,
    gzip: bool,
    datatype: usize,
    dims: [i64; 3],
    frames: i64,
    edits: Vec<Edit>,
    swapped_size: bool,
    /// Per mille of the file kept (`None`: all of it).
    cut: Option<u16>,
    /// Bytes overwritten (position per million of the file, value).
    bytes: Vec<(u32, u8)>,
    /// Extra bytes after the voxels.
    tail: usize,
    frame: Option<u64>,
}

impl Case {
    fn bytes(&self) -> Vec<u8> {
        let datatype = DATATYPES[self.datatype % DATATYPES.len()];
        let mut spec = NiftiSpec::new(self.version, self.dims, self.frames, datatype);
        spec.big = self.big;
        spec.swapped_size = self.swapped_size;
        spec.codes = (0, 1);
        for e in &self.edits {
            let f = FLOATS[e.value % FLOATS.len()];
            match e.field % 12 {
                0 => spec.dim[1 + e.axis % 7] = SIZES[e.value % SIZES.len()],
                1 => spec.dim[0] = NDIMS[e.value % NDIMS.len()],
                2 => spec.datatype = DATATYPES[e.value % DATATYPES.len()],
                3 => spec.vox_offset = f,
                4 => spec.pixdim[e.axis % 8] = f,
                5 => spec.scl.0 = f,
                6 => spec.scl.1 = f,
                7 => spec.srow[e.axis % 3][e.value % 4] = FLOATS[e.axis % FLOATS.len()],
                8 => spec.quatern[e.axis % 3] = f,
                9 => spec.codes = ((e.value % 3) as i32 - 1, (e.axis % 3) as i32 - 1),
                10 => spec.descrip = format!("line\nerror: forged {}", e.value).into_bytes(),
                _ => spec.srow[e.axis % 3][e.axis % 3] = f,
            }
        }
        let count = (self.dims.iter().product::<i64>() * self.frames.max(1)) as usize;
        let mut file = spec.file(&voxels(datatype, count, self.big, |i| (i * 37 % 251) as f64 - 20.0));
        file.extend(std::iter::repeat_n(0xA5u8, self.tail));
        if self.gzip {
            file = gzip(&file);
        }
        for &(at, b) in &self.bytes {
            let len = file.len();
            if len > 0 {
                file[((at as usize * len) / 1_000_000).min(len - 1)] = b;
            }
        }
        if let Some(keep) = self.cut {
            file.truncate(file.len() * keep as usize / 1000);
        }
        file
    }
}

fn edit() -> impl Strategy<Value = Edit> {
    (any::<u8>(), any::<usize>(), any::<usize>()).prop_map(|(field, value, axis)| Edit { field, value, axis })
}

fn case() -> impl Strategy<Value = Case> {
    (
        (1u8..=2, any::<bool>(), any::<bool>(), any::<usize>(), [1i64..6, 1i64..6, 1i64..5], 1i64..4),
        prop::collection::vec(edit(), 0..4),
        prop::bool::weighted(0.05),
        prop::option::weighted(0.15, 0u16..1000),
        prop::collection::vec((0u32..1_000_000, any::<u8>()), 0..3),
        prop_oneof![4 => Just(0usize), 1 => 0usize..64],
        prop::option::of(prop_oneof![Just(0u64), Just(1), Just(2), Just(3), Just(u64::MAX)]),
    )
        .prop_map(
            |((version, big, gzip, datatype, dims, frames), edits, swapped_size, cut, bytes, tail, frame)| Case {
                version,
                big,
                gzip,
                datatype,
                dims,
                frames,
                edits,
                swapped_size,
                cut,
                bytes,
                tail,
                frame,
            },
        )
}

#[test]
fn valid_fuzz_bases_load() {
    // The mutations start from files that really load, so they explore near-valid input.
    for version in [1, 2] {
        for big in [false, true] {
            for gz in [false, true] {
                for &datatype in &DATATYPES[..10] {
                    let case = Case {
                        version,
                        big,
                        gzip: gz,
                        datatype: DATATYPES.iter().position(|&d| d == datatype).unwrap_or(0),
                        dims: [3, 2, 2],
                        frames: 2,
                        edits: Vec::new(),
                        swapped_size: false,
                        cut: None,
                        bytes: Vec::new(),
                        tail: 0,
                        frame: Some(1),
                    };
                    let loaded = volgraph_accel::load::nifti::parse(Path::new("base.nii"), &case.bytes(), case.frame)
                        .unwrap_or_else(|e| panic!("{case:?}: {e}"));
                    assert_eq!(loaded.volume.voxel_count(), 12, "{case:?}");
                }
            }
        }
    }
}

#[test]
fn hostile_nifti_headers_and_data_are_errors_never_panics_or_hangs() {
    let mut runner =
        TestRunner::new(Config { cases: fuzz_support::cases(2000), failure_persistence: None, ..Config::default() });
    let harness = Harness::new("nifti fuzz", 100_000);
    let result = runner.run(&case(), |case| {
        let bytes = case.bytes();
        let name = if case.gzip { "fuzz.nii.gz" } else { "fuzz.nii" };
        harness.run(
            &case,
            || volgraph_accel::load::nifti::parse(Path::new(name), &bytes, case.frame),
            |text| {
                (!text.contains(name) || text.contains('\n'))
                    .then(|| format!("an error that does not name the file on one line: {text}"))
            },
        );
        Ok(())
    });
    harness.finish(result);
}
