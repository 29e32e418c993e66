//! Reading a box of a volume file without reading the rest: what each process of a sort-last
//! render does (`docs/scaling.md`): it seeks to every row of its box (plus apron) and reads only
//! those bytes, so no process ever holds the whole volume.

use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};

use super::dicom::SeriesSlices;
use super::{Endianness, Layout, LoadError, LoadOptions, decode, raw};
use crate::kd_split::VoxelBox;
use crate::volume::{Volume, VoxelData, VoxelType};
use crate::volume_meta::VolumeMeta;

/// What a volume file holds, from its name or header, with where its voxels start: enough to
/// read any box of it.
#[derive(Clone, Debug)]
pub struct VolumeHeader {
    /// Dataset name.
    pub name: String,
    /// Voxels per axis.
    pub dims: UVec3,
    /// Voxel type.
    pub dtype: VoxelType,
    /// Byte order.
    pub order: Endianness,
    /// Physical voxel size.
    pub spacing: DVec3,
    /// What the file says besides voxels (a DICOM series' modality and units; the default for
    /// files whose header has none), as the whole-volume loaders give it.
    pub meta: VolumeMeta,
    source: Source,
}

/// A volume stored in chunks (an OME-Zarr image's finest level) read a box at a time, in its
/// stored type, x fastest: how sort-last ranks read their boxes of a store.
pub trait RawBoxes: Send + Sync + std::fmt::Debug {
    /// The voxels of `bx` (within the volume), as stored.
    fn read_raw(&self, bx: VoxelBox) -> Result<VoxelData, LoadError>;
}

/// Where the voxels are.
#[derive(Clone, Debug)]
enum Source {
    /// In a chunked store, read through its reader.
    Boxes(std::sync::Arc<dyn RawBoxes>),
    /// In one file from `offset`, x fastest.
    File { path: PathBuf, offset: u64 },
    /// In the slices of a DICOM series (read as rescaled f32).
    Dicom { slices: Box<SeriesSlices>, path: PathBuf },
}

impl VolumeHeader {
    /// The header of volume `path` (reads no voxels): headerless `.raw` files, raw-encoded NRRD
    /// (`.nrrd`, `.nhdr`) and uncompressed MetaImage (`.mha`, `.mhd`), attached or detached, and
    /// DICOM series (a folder or a `.dcm` file; `options.series` picks one), whose axes are the
    /// world's; anything else (NIfTI, compressed or reoriented data) is a
    /// [`LoadError::NoBoxRead`]. Its spacing is held to what a whole-volume load allows.
    pub fn read(path: &Path, options: &LoadOptions<'_>) -> Result<Self, LoadError> {
        let mut header = Self::read_header(path, options)?;
        header.spacing = super::checked_spacing(path, options.raw.spacing, header.spacing)?;
        Ok(header)
    }

    fn read_header(path: &Path, options: &LoadOptions<'_>) -> Result<Self, LoadError> {
        let opts = &options.raw;
        let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        if matches!(extension.as_str(), "nrrd" | "nhdr" | "mhd" | "mha") {
            super::check_no_raw_layout(path, opts)?;
            let head = read_head(path)?;
            let (Layout { name, dims, dtype, order, spacing, .. }, data_path, offset) = if extension.starts_with('n') {
                super::nrrd::raw_data(path, &head)?
            } else {
                super::metaimage::raw_data(path, &head)?
            };
            let source = Source::File { path: data_path, offset };
            let spacing = opts.spacing.unwrap_or(spacing);
            return Ok(Self { name, dims, dtype, order, spacing, meta: VolumeMeta::default(), source });
        }
        if path.is_dir() || extension == "dcm" {
            let slices = SeriesSlices::open(&[path.to_path_buf()], options.series.as_deref())?;
            return Ok(Self {
                name: slices.name.clone(),
                dims: slices.dims,
                dtype: VoxelType::F32,
                order: Endianness::Little,
                spacing: opts.spacing.unwrap_or(slices.spacing),
                meta: slices.meta.clone(),
                source: Source::Dicom { slices: Box::new(slices), path: path.to_path_buf() },
            });
        }
        let format = match extension.as_str() {
            "raw" => None,
            _ if super::is_nifti(path) => Some("NIfTI"),
            _ => return Err(LoadError::UnknownFormat { path: path.to_path_buf(), extension }),
        };
        if let Some(format) = format {
            return Err(LoadError::NoBoxRead { path: path.to_path_buf(), format });
        }
        let Layout { name, dims, dtype, order, spacing, .. } = raw::layout(path, opts)?;
        Ok(Self {
            name,
            dims,
            dtype,
            order,
            spacing: opts.spacing.unwrap_or(spacing),
            meta: VolumeMeta::default(),
            source: Source::File { path: path.to_path_buf(), offset: 0 },
        })
    }

    /// The file the voxels are read from (a DICOM series: the path it was opened by; a store:
    /// its name).
    pub fn data_path(&self) -> &Path {
        match &self.source {
            Source::File { path, .. } | Source::Dicom { path, .. } => path,
            Source::Boxes(_) => Path::new(&self.name),
        }
    }

    /// The normalization range of the whole volume when its type fixes it (integer files: the
    /// type range, as [`Volume::new`] gives it; 8-bit DICOM: 0..=255); `None` when the range is
    /// the data's own (float data; 16-bit DICOM, whose range the loader fits to the data) and
    /// must be surveyed.
    pub fn type_range(&self) -> Option<(f64, f64)> {
        match &self.source {
            Source::Dicom { slices, .. } => slices.eight_bit.then_some((0.0, 255.0)),
            Source::File { .. } | Source::Boxes(_) => self.dtype.integer_range(),
        }
    }

    /// The header of a volume held in a chunked store: `dims` voxels of `dtype` and `spacing`,
    /// read box by box through `boxes`.
    pub fn from_boxes(
        name: &str,
        (dims, dtype, spacing): (UVec3, VoxelType, DVec3),
        meta: VolumeMeta,
        boxes: std::sync::Arc<dyn RawBoxes>,
    ) -> Self {
        Self {
            name: name.to_string(),
            dims,
            dtype,
            order: Endianness::Little,
            spacing,
            meta,
            source: Source::Boxes(boxes),
        }
    }

    /// The voxels of `bx` as a volume of `bx.size()` voxels, normalized over `value_range` (the
    /// whole volume's, so every box maps values alike); non-finite floats are replaced as the
    /// loaders do (NaN and −∞ by the range's low end, +∞ by its high end). Reads only the rows
    /// of the box.
    pub fn read_box(&self, bx: VoxelBox, value_range: (f64, f64)) -> Result<Volume, LoadError> {
        let (data_path, data_offset) = match &self.source {
            Source::File { path, offset } => (path, *offset),
            Source::Boxes(boxes) => {
                let data = boxes.read_raw(bx)?;
                return Ok(self.volume_of(bx.size(), data, value_range));
            }
            Source::Dicom { slices, .. } => {
                // Whole slices of the box's z-range, then its rows and columns.
                let all = slices.read_slices(bx.lo.z..bx.hi.z)?;
                let size = bx.size();
                let mut values = Vec::with_capacity(bx.voxels() as usize);
                for z in 0..size.z as usize {
                    for y in bx.lo.y as usize..bx.hi.y as usize {
                        let row = (z * self.dims.y as usize + y) * self.dims.x as usize;
                        values.extend_from_slice(&all[row + bx.lo.x as usize..row + bx.hi.x as usize]);
                    }
                }
                let mut volume = Volume::new(self.name.clone(), size, self.spacing, VoxelData::F32(values));
                volume.value_range = value_range;
                volume.meta = self.meta.clone();
                return Ok(volume);
            }
        };
        let io = |source| LoadError::Io { path: data_path.clone(), source };
        let size = bx.size();
        let voxel = self.dtype.size_bytes() as u64;
        let mut file = std::fs::File::open(data_path).map_err(io)?;
        let row = size.x as usize * voxel as usize;
        let mut bytes = vec![0u8; row * size.y as usize * size.z as usize];
        // A box's rows of one plane lie a file row apart: read in one go when the gaps are at
        // most 8 times what the box needs (a brick of a wide volume: one read a plane instead of
        // one a row), else row by row.
        let stride = self.dims.x as usize * voxel as usize;
        let span = (size.y.max(1) as usize - 1) * stride + row;
        let mut plane = Vec::new();
        let whole_planes = size.y > 1 && span <= 8 * row * size.y as usize;
        let mut at = 0;
        for z in bx.lo.z..bx.hi.z {
            let first = bx.lo.x as u64 + self.dims.x as u64 * (bx.lo.y as u64 + self.dims.y as u64 * z as u64);
            if whole_planes {
                plane.resize(span, 0);
                file.seek(SeekFrom::Start(data_offset + first * voxel)).map_err(io)?;
                file.read_exact(&mut plane).map_err(io)?;
                for y in 0..size.y as usize {
                    bytes[at..at + row].copy_from_slice(&plane[y * stride..y * stride + row]);
                    at += row;
                }
                continue;
            }
            for y in 0..u64::from(size.y) {
                file.seek(SeekFrom::Start(data_offset + (first + y * self.dims.x as u64) * voxel)).map_err(io)?;
                file.read_exact(&mut bytes[at..at + row]).map_err(io)?;
                at += row;
            }
        }
        Ok(self.volume_of(size, decode(&bytes, self.dtype, self.order), value_range))
    }

    /// A box's voxels as a volume: non-finite floats replaced as the loaders do (NaN and −∞ by
    /// the range's low end, +∞ by its high end), normalized over `value_range`.
    fn volume_of(&self, size: UVec3, mut data: VoxelData, value_range: (f64, f64)) -> Volume {
        if let VoxelData::F32(values) = &mut data {
            for v in values.iter_mut() {
                if v.is_nan() || *v == f32::NEG_INFINITY {
                    *v = value_range.0 as f32;
                } else if *v == f32::INFINITY {
                    *v = value_range.1 as f32;
                }
            }
        }
        let mut volume = Volume::new(self.name.clone(), size, self.spacing, data);
        volume.value_range = value_range;
        volume.meta = self.meta.clone();
        volume
    }

    /// Reads the slabs of whole z slices `z.start..z.end`, `slices` at a time, and gives each to
    /// `visit` with its first z: streaming over a part of the file in bounded memory.
    pub fn for_each_slab(
        &self,
        z: std::ops::Range<u32>,
        slices: u32,
        value_range: (f64, f64),
        mut visit: impl FnMut(u32, &Volume),
    ) -> Result<(), LoadError> {
        let mut z0 = z.start;
        while z0 < z.end {
            let z1 = (z0 + slices.max(1)).min(z.end);
            let slab = VoxelBox::new(UVec3::new(0, 0, z0), UVec3::new(self.dims.x, self.dims.y, z1));
            visit(z0, &self.read_box(slab, value_range)?);
            z0 = z1;
        }
        Ok(())
    }
}

impl VolumeHeader {
    /// The finite (min, max) of the values in planes `z`, read a slab at a time (a float file's
    /// range, which no type fixes); `(+∞, −∞)` when none is finite.
    pub fn finite_range(&self, z: std::ops::Range<u32>) -> Result<(f64, f64), LoadError> {
        self.finite_survey(z).map(|(range, _)| range)
    }

    /// [`Self::finite_range`] and how many values are NaN or infinite (what a reader replaces
    /// by the range's ends, as the loaders do).
    pub fn finite_survey(&self, z: std::ops::Range<u32>) -> Result<((f64, f64), u64), LoadError> {
        let mut lo_hi = (f64::INFINITY, f64::NEG_INFINITY);
        let mut non_finite = 0u64;
        // A range of NaN leaves NaN and ±∞ as NaN: with (0, 1) they were read as 0 and 1, and a
        // float file with a NaN got a range reaching 0.
        self.for_each_slab(z, 8, (f64::NAN, f64::NAN), |_, slab| {
            for i in 0..slab.voxel_count() {
                let v = slab.raw_value(i);
                if v.is_finite() {
                    lo_hi = (lo_hi.0.min(v), lo_hi.1.max(v));
                } else {
                    non_finite += 1;
                }
            }
        })?;
        Ok((lo_hi, non_finite))
    }
}

/// The first MiB of `path`: enough for any header volgraph reads.
fn read_head(path: &Path) -> Result<Vec<u8>, LoadError> {
    // A FIFO or device would block the open or never end: refused by name first.
    super::check_is_file(path)?;
    let io = |source| LoadError::Io { path: path.to_path_buf(), source };
    let mut head = Vec::new();
    std::fs::File::open(path).map_err(io)?.take(1 << 20).read_to_end(&mut head).map_err(io)?;
    Ok(head)
}

#[cfg(test)]
mod tests {
    use super::super::RawOptions;
    use super::*;

    /// `part` holds box `bx` of `whole`, voxel for voxel (stored values).
    fn assert_is_box_of(part: &Volume, whole: &Volume, bx: VoxelBox, what: &str) {
        assert_eq!(part.dims, bx.size(), "{what}");
        for z in 0..part.dims.z {
            for y in 0..part.dims.y {
                for x in 0..part.dims.x {
                    let w = whole.index(x + bx.lo.x, y + bx.lo.y, z + bx.lo.z);
                    assert_eq!(part.raw_value(part.index(x, y, z)), whole.raw_value(w), "{what} at ({x}, {y}, {z})");
                }
            }
        }
    }

    /// A box read by seeking equals the same box cut from the whole volume.
    #[test]
    fn a_box_read_by_seeking_equals_the_box_of_the_whole_volume() {
        let dir = std::env::temp_dir().join(format!("volgraph-region-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("ramp_13x7x5_uint16.raw");
        let values: Vec<u16> = (0..13 * 7 * 5).map(|i| (i * 37 % 65536) as u16).collect();
        std::fs::write(&path, values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()).expect("write");
        let header = VolumeHeader::read(&path, &LoadOptions::default()).expect("header");
        let whole = super::super::load_volume(&path, &RawOptions::default()).expect("whole").volume;
        let bx = VoxelBox::new(UVec3::new(2, 1, 3), UVec3::new(11, 7, 5));
        let part = header.read_box(bx, header.type_range().expect("integer")).expect("box");
        assert_is_box_of(&part, &whole, bx, "raw");
        assert_eq!(part.value_range, whole.value_range, "normalized alike");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// NRRD, attached and detached: the box read by seeking equals the box of the loaded volume.
    #[test]
    fn a_box_of_a_nrrd_file_equals_the_box_of_the_whole_volume() {
        let dir = std::env::temp_dir().join(format!("volgraph-region-nrrd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let values: Vec<u8> = (0..9 * 8 * 7).map(|i| (i * 31 % 251) as u8).collect();
        let header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 9 8 7\nspacings: 1 1 2\nencoding: raw\n";
        let attached = dir.join("attached.nrrd");
        std::fs::write(&attached, [format!("{header}\n").as_bytes(), &values].concat()).expect("write");
        std::fs::write(dir.join("voxels.raw"), &values).expect("write");
        let detached = dir.join("detached.nhdr");
        std::fs::write(&detached, format!("{header}data file: voxels.raw\n\n")).expect("write");
        let bx = VoxelBox::new(UVec3::new(1, 2, 3), UVec3::new(8, 8, 6));
        for path in [attached, detached] {
            let whole = super::super::load_volume(&path, &RawOptions::default()).expect("whole").volume;
            let header = VolumeHeader::read(&path, &LoadOptions::default()).expect("header");
            assert_eq!(header.spacing, DVec3::new(1.0, 1.0, 2.0));
            let part = header.read_box(bx, whole.value_range).expect("box");
            assert_is_box_of(&part, &whole, bx, &path.display().to_string());
        }
        // MetaImage, attached and detached.
        let mha = dir.join("attached.mha");
        let fields = "NDims = 3\nDimSize = 9 8 7\nElementSpacing = 1 1 2\nElementType = MET_UCHAR\n";
        std::fs::write(&mha, [format!("{fields}ElementDataFile = LOCAL\n").as_bytes(), &values].concat())
            .expect("write");
        let mhd = dir.join("detached.mhd");
        std::fs::write(&mhd, format!("{fields}ElementDataFile = voxels.raw\n")).expect("write");
        for path in [mha, mhd] {
            let whole = super::super::load_volume(&path, &RawOptions::default()).expect("whole").volume;
            let header = VolumeHeader::read(&path, &LoadOptions::default()).expect("header");
            let part = header.read_box(bx, whole.value_range).expect("box");
            assert_is_box_of(&part, &whole, bx, &path.display().to_string());
        }
        let gz = dir.join("packed.nrrd");
        std::fs::write(&gz, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: gzip\n\n").expect("write");
        let e = VolumeHeader::read(&gz, &LoadOptions::default()).expect_err("gzip");
        assert!(e.to_string().contains("gzip-encoded NRRD files cannot be read a box at a time"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A DICOM series: a box read from only the slices it spans equals the box of the loaded
    /// series (rescaled values, as f32).
    #[test]
    fn a_box_of_a_dicom_series_equals_the_box_of_the_loaded_series() {
        let dir = std::env::temp_dir().join(format!("volgraph-region-dicom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let dims = UVec3::new(12, 10, 9);
        let values: Vec<i16> = (0..dims.x * dims.y * dims.z).map(|i| ((i * 37 % 2000) as i16) - 1000).collect();
        let ct = Volume::new("ct", dims, DVec3::new(0.5, 0.5, 1.5), VoxelData::I16(values));
        super::super::dicom::write_ct_series(&dir, &ct).expect("series written");
        let whole =
            super::super::load_volumes(std::slice::from_ref(&dir), &LoadOptions::default()).expect("whole").volume;
        let header = VolumeHeader::read(&dir, &LoadOptions::default()).expect("header");
        assert_eq!(header.dims, whole.dims);
        assert_eq!(header.type_range(), None, "16-bit DICOM: the range is surveyed");
        let bx = VoxelBox::new(UVec3::new(2, 3, 4), UVec3::new(11, 10, 7));
        let part = header.read_box(bx, whole.value_range).expect("box");
        assert_is_box_of(&part, &whole, bx, "box");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A FIFO named like a header is refused by name, never opened (opening it would block).
    #[cfg(unix)]
    #[test]
    fn a_fifo_header_is_refused_without_blocking() {
        let dir = std::env::temp_dir().join(format!("volgraph-region-fifo-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let fifo = dir.join("pipe.nrrd");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
        assert!(made.success());
        let e = VolumeHeader::read(&fifo, &LoadOptions::default()).expect_err("a FIFO");
        assert!(e.to_string().contains("FIFO"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn formats_without_box_reads_say_so() {
        let e = VolumeHeader::read(Path::new("brain.nii.gz"), &LoadOptions::default()).expect_err("nifti");
        assert!(e.to_string().contains("NIfTI files cannot be read a box at a time"), "{e}");
    }
}
