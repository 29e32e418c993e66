//! Malformed NRRD and MetaImage inputs produce their documented errors, compared word for word.
//! Headers are parsed from memory under a fixed file name so the expected strings are literal.

use std::path::Path;

use volgraph_accel::load::{parse_metaimage, parse_nrrd};

fn nrrd_err(bytes: &[u8]) -> String {
    parse_nrrd(Path::new("bad.nrrd"), bytes).expect_err("malformed NRRD").to_string()
}

fn mhd_err(name: &str, bytes: &[u8]) -> String {
    parse_metaimage(Path::new(name), bytes).expect_err("malformed MetaImage").to_string()
}

/// A valid 2x2x2 uint8 header with `line` (1-based, after the magic) replaced by `with`.
fn nrrd_with(replace: &str, with: &str) -> Vec<u8> {
    let header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n";
    assert!(header.contains(replace), "test bug: {replace:?} is not in the header");
    let mut bytes = header.replacen(replace, with, 1).into_bytes();
    bytes.extend_from_slice(&[1u8; 8]);
    bytes
}

#[test]
fn nrrd_errors_word_for_word() {
    assert_eq!(
        nrrd_err(b"P6\n2 2\n255\n"),
        "bad.nrrd: not a NRRD file: the first line is \"P6\", expected \"NRRD0001\" to \"NRRD0005\""
    );
    assert_eq!(
        nrrd_err(&nrrd_with("type: uchar", "type: double")),
        "bad.nrrd:2: unsupported voxel type \"double\"; supported: uchar/uint8, ushort/uint16, short/int16, float (convert the data to one of them)"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("dimension: 3", "dimension: 4")),
        "bad.nrrd:3: dimension is 4, but only 3D scalar volumes can be loaded (set it to 3 with three sizes)"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("sizes: 2 2 2", "sizes: 64 64")),
        "bad.nrrd:4: cannot use sizes = \"64 64\"; expected three whole numbers, e.g. `sizes: 64 64 32`"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("sizes: 2 2 2", "sizes 2 2 2")),
        "bad.nrrd:4: cannot parse header line \"sizes 2 2 2\"; expected `field: value`, `key:=value` or a `#` comment"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("sizes: 2 2 2", "sizes: 2 0 2")),
        "bad.nrrd:4: dimensions 2x0x2 contain a zero; every axis needs at least one voxel"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("sizes: 2 2 2\n", "")),
        "bad.nrrd: the header has no \"sizes\" field; add a line like `sizes: 64 64 64`"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("encoding: raw", "encoding: bzip2")),
        "bad.nrrd:5: unsupported encoding \"bzip2\"; supported: raw, gzip (re-save the file with one of them)"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("encoding: raw", "encoding: raw\nfrobnicate: 3")),
        "bad.nrrd:6: unsupported header field \"frobnicate\" = \"3\"; it is not a NRRD field volgraph knows; remove it or turn it into a `key:=value` pair"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("encoding: raw", "encoding: raw\nspacings: 1 -1 1")),
        "bad.nrrd:6: spacing (1, -1, 1) must be finite and positive on every axis"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("type: uchar", "type: ushort\nendian: little")),
        "bad.nrrd: 2x2x2 uint16 voxels need 16 bytes, but the data has 8 bytes; check \"sizes\", \"type\", \"encoding\" and \"byte skip\" in the header, or whether the data is complete"
    );
    assert_eq!(
        nrrd_err(b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"),
        "bad.nrrd: the NRRD header does not end with an empty line before the data; the file is truncated or not a NRRD file"
    );
    assert_eq!(
        nrrd_err(&nrrd_with("encoding: raw", "encoding: raw\ndata file: slice%03d.raw 1 10 1")),
        "bad.nrrd:6: unsupported header field \"data file\" = \"slice%03d.raw 1 10 1\"; only a single data file is supported; join the slices into one file"
    );
    // Raw bytes claimed to be gzip: the decoder's message is flate2's, so only the frame is
    // compared here.
    let gz = nrrd_err(&nrrd_with("encoding: raw", "encoding: gzip"));
    assert!(gz.starts_with("bad.nrrd: cannot decompress the gzip data: "), "{gz}");
    assert!(gz.ends_with("; the file is truncated or not compressed as its header says"), "{gz}");
}

#[test]
fn detached_nhdr_without_data_file_is_an_error() {
    let header = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n";
    let err = parse_nrrd(Path::new("v.nhdr"), header).expect_err("no data file").to_string();
    assert_eq!(err, "v.nhdr: the header has no \"data file\" field; add a line like `data file: volume.raw`");
}

fn mha_with(replace: &str, with: &str, data: &[u8]) -> Vec<u8> {
    let header = "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    assert!(header.contains(replace), "test bug: {replace:?} is not in the header");
    let mut bytes = header.replacen(replace, with, 1).into_bytes();
    bytes.extend_from_slice(data);
    bytes
}

#[test]
fn metaimage_errors_word_for_word() {
    let ok = [7u8; 8];
    assert!(parse_metaimage(Path::new("ok.mha"), &mha_with("NDims", "NDims", &ok)).is_ok());
    assert_eq!(
        mhd_err("bad.mha", &mha_with("MET_UCHAR", "MET_DOUBLE", &ok)),
        "bad.mha:3: unsupported voxel type \"MET_DOUBLE\"; supported: MET_UCHAR, MET_USHORT, MET_SHORT, MET_FLOAT (convert the data to one of them)"
    );
    assert_eq!(
        mhd_err("bad.mha", &mha_with("NDims = 3", "NDims = 2", &ok)),
        "bad.mha:1: NDims is 2, but only 3D scalar volumes can be loaded (set it to 3 with three sizes)"
    );
    assert_eq!(
        mhd_err("bad.mha", &mha_with("ElementDataFile = LOCAL\n", "", &[])),
        "bad.mha: the header has no \"ElementDataFile\" field; add a line like `ElementDataFile = LOCAL`"
    );
    assert_eq!(
        mhd_err("bad.mha", &mha_with("MET_UCHAR", "MET_USHORT", &ok)),
        "bad.mha: 2x2x2 uint16 voxels need 16 bytes, but the data has 8 bytes; check DimSize, ElementType, HeaderSize and CompressedData in the header, or whether the data is complete"
    );
    assert_eq!(
        mhd_err("bad.mha", &mha_with("DimSize = 2 2 2", "DimSize: 2 2 2", &ok)),
        "bad.mha:2: cannot parse header line \"DimSize: 2 2 2\"; expected `Key = Value`"
    );
    assert_eq!(
        mhd_err("bad.mha", &mha_with("NDims = 3", "NDims = 3\nElementNumberOfChannels = 3", &ok)),
        "bad.mha:2: unsupported header field \"ElementNumberOfChannels\" = \"3\"; only scalar volumes (1 channel) are supported; extract one channel first"
    );
    assert_eq!(
        mhd_err("bad.mha", &mha_with("NDims = 3", "NDims = 3\nBinaryDataByteOrderMSB = maybe", &ok)),
        "bad.mha:2: cannot use BinaryDataByteOrderMSB = \"maybe\"; expected `True` or `False`"
    );
    assert_eq!(
        mhd_err("bad.mhd", &mha_with("LOCAL", "LIST", &[])),
        "bad.mhd:4: unsupported header field \"ElementDataFile\" = \"LIST\"; use `LOCAL` or a single data file name; join slice files into one"
    );
}

#[test]
fn a_directory_or_fifo_is_named_for_what_it_is() {
    use volgraph_accel::load::{RawOptions, load_volume};
    let dir = std::env::temp_dir().join("volgraph-not-a-file_4x4x4_uint8.raw");
    std::fs::create_dir_all(&dir).expect("temp dir");
    // A folder is read as DICOM slices; an empty one says so and what else to give.
    let err = load_volume(&dir, &RawOptions::default()).expect_err("a directory");
    assert!(
        err.to_string().ends_with(
            "is a folder with no DICOM images (0 file(s): 0 not DICOM, 0 DICOMDIR index); give the folder holding the slices, \
             a slice file, or a volume file (.raw, .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz)"
        ),
        "{err}"
    );
    #[cfg(unix)]
    {
        let fifo = std::env::temp_dir().join(format!("volgraph-fifo-{}_4x4x4_uint8.raw", std::process::id()));
        let _ = std::fs::remove_file(&fifo);
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
        if made {
            // Reading a FIFO nobody writes to would block forever; it is refused up front.
            let err = load_volume(&fifo, &RawOptions::default()).expect_err("a FIFO");
            assert!(err.to_string().contains("is a FIFO (named pipe), not a volume file"), "{err}");
            let _ = std::fs::remove_file(&fifo);
        }
    }
}

#[test]
fn raw_layout_options_on_a_headered_file_are_refused() {
    use volgraph_accel::load::{Endianness, RawOptions, load_volume};
    let dir = std::env::temp_dir().join("volgraph-raw-opts");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("h.nrrd");
    let mut bytes = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n".to_vec();
    bytes.extend(0u8..8);
    std::fs::write(&path, bytes).expect("write");
    let opts = RawOptions { dims: Some(glam::UVec3::splat(2)), endianness: Endianness::Big, ..RawOptions::default() };
    let err = load_volume(&path, &opts).expect_err("the header gives the layout");
    assert!(err.to_string().ends_with(
        "h.nrrd: --dims, --big-endian describe headerless .raw files, but this file has a header that gives the layout; remove --dims, --big-endian (--spacing alone may override a header)"
    ), "{err}");
    let spacing_only = RawOptions { spacing: Some(glam::DVec3::new(1.0, 1.0, 2.0)), ..RawOptions::default() };
    assert_eq!(load_volume(&path, &spacing_only).expect("spacing may override").volume.spacing.z, 2.0);
}
