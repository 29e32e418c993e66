//! Where `volgraph convert` reads voxels, a slab of planes at a time where the input allows it,
//! so a volume larger than memory converts: a generated vessel tree of any size up to 8192³
//! (`vessels4096`: 64 GiB) made plane by plane; a headerless raw file, raw-encoded NRRD or
//! uncompressed MetaImage read by seeking (`VolumeHeader::read_box`). Anything else (NIfTI,
//! compressed files, DICOM, datasets and other generated volumes) is read whole, as `--volume`
//! reads it, and written from memory (`volgraph_zarr::InMemory`).

use std::ops::Range;
use std::path::Path;

use anyhow::anyhow;
use glam::{DVec3, UVec3};
use volgraph_accel::kd_split::VoxelBox;
use volgraph_accel::load::LoadOptions;
use volgraph_accel::load::VolumeHeader;
use volgraph_accel::vessels::VesselTree;
use volgraph_accel::volume::{VoxelData, VoxelType};
use volgraph_accel::volume_meta::VolumeMeta;
use volgraph_zarr::SlabSource;

/// A generated vessel tree, made plane by plane.
pub struct VesselSlabs(pub VesselTree);

impl SlabSource for VesselSlabs {
    fn dims(&self) -> UVec3 {
        self.0.dims()
    }
    fn voxel_type(&self) -> VoxelType {
        VoxelType::U8
    }
    fn spacing(&self) -> DVec3 {
        DVec3::ONE
    }
    fn origin(&self) -> DVec3 {
        DVec3::ZERO
    }
    fn value_range(&self) -> (f64, f64) {
        (0.0, 255.0)
    }
    fn read_slab(&mut self, z: Range<u32>) -> Result<VoxelData, String> {
        Ok(VoxelData::U8(self.0.planes(z)))
    }
}

/// A volume file read a box at a time by seeking.
pub struct FileSlabs {
    header: VolumeHeader,
    value_range: (f64, f64),
}

impl FileSlabs {
    /// The file at `path`, if it can be read a box at a time (not a DICOM series: its slices
    /// read as rescaled floats there, unlike `--volume`'s reading). A float file's value range
    /// is surveyed first (one streaming pass).
    pub fn open(path: &Path, options: &LoadOptions<'_>) -> Option<anyhow::Result<Self>> {
        if path.is_dir() || volgraph_accel::load::dicom::is_dicom_input(std::slice::from_ref(&path.to_path_buf())) {
            return None;
        }
        let header = VolumeHeader::read(path, options).ok()?;
        let value_range = match header.type_range() {
            Some(range) => range,
            None => match header.finite_range(0..header.dims.z) {
                Ok((lo, hi)) if lo < hi => (lo, hi),
                // A constant file (or none finite): a range around its value, as the loader gives.
                Ok((lo, _)) if lo.is_finite() => (lo, lo + 1.0),
                Ok(_) => (0.0, 1.0),
                Err(e) => return Some(Err(anyhow!("{e}"))),
            },
        };
        Some(Ok(Self { header, value_range }))
    }
}

impl SlabSource for FileSlabs {
    fn dims(&self) -> UVec3 {
        self.header.dims
    }
    fn voxel_type(&self) -> VoxelType {
        self.header.dtype
    }
    fn spacing(&self) -> DVec3 {
        self.header.spacing
    }
    fn origin(&self) -> DVec3 {
        self.header.meta.origin.unwrap_or_default()
    }
    fn meta(&self) -> VolumeMeta {
        self.header.meta.clone()
    }
    fn value_range(&self) -> (f64, f64) {
        self.value_range
    }
    fn read_slab(&mut self, z: Range<u32>) -> Result<VoxelData, String> {
        let d = self.header.dims;
        let slab = VoxelBox::new(UVec3::new(0, 0, z.start), UVec3::new(d.x, d.y, z.end));
        self.header.read_box(slab, self.value_range).map(|v| v.data).map_err(|e| e.to_string())
    }
}
