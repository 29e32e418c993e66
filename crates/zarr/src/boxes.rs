//! An OME-Zarr image's finest level read a box at a time in its stored type
//! (`volgraph_accel::load::RawBoxes`): how `volgraph render --distributed` ranks each read
//! their kd-tree box of a store, chunk by chunk, without any rank holding the volume.

use std::path::PathBuf;
use std::sync::Arc;

use volgraph_accel::kd_split::VoxelBox;
use volgraph_accel::load::{LoadError, RawBoxes, VolumeHeader};
use volgraph_accel::volume::{VoxelData, VoxelType};
use zarrs::array::ArraySubset;
use zarrs::array::ElementOwned;

use crate::ngff::AxisKind;
use crate::read::Pick;
use crate::store::OmeZarr;

/// Level 0 of an image at one time point and channel, read box by box.
pub struct StoreBoxes {
    image: Arc<OmeZarr>,
    pick: Pick,
}

impl std::fmt::Debug for StoreBoxes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "StoreBoxes({}, {:?})", self.image.path.display(), self.pick)
    }
}

impl StoreBoxes {
    /// The header of `image`'s finest level at `pick`, read box by box: name, dims, type,
    /// spacing (millimetres where the unit is a length) and what the converter kept of the
    /// source (patient frame, modality, window).
    pub fn header(image: OmeZarr, pick: Pick) -> VolumeHeader {
        let level = &image.levels[0];
        let mm = image.millimetres_per_unit().unwrap_or(1.0);
        let name = image.path.file_name().map_or("ome-zarr".into(), |n| n.to_string_lossy().into_owned());
        let mut meta = image.volgraph_meta();
        meta.origin = Some(level.origin * mm);
        let shape = (level.dims, level.voxel_type, level.spacing * mm);
        VolumeHeader::from_boxes(&name, shape, meta, Arc::new(Self { image: Arc::new(image), pick }))
    }

    fn read<T: ElementOwned + Copy + Default + Send + Sync>(&self, bx: VoxelBox) -> Result<Vec<T>, String> {
        let level = &self.image.levels[0];
        let axes = &self.image.multiscale.axes;
        let [az, ay, ax] = self.image.multiscale.space_axes();
        let mut ranges = vec![0..1u64; axes.len()];
        ranges[az] = u64::from(bx.lo.z)..u64::from(bx.hi.z);
        ranges[ay] = u64::from(bx.lo.y)..u64::from(bx.hi.y);
        ranges[ax] = u64::from(bx.lo.x)..u64::from(bx.hi.x);
        for (kind, value) in [(AxisKind::Time, self.pick.time), (AxisKind::Channel, self.pick.channel)] {
            if let Some(a) = self.image.multiscale.axis_of(&kind) {
                ranges[a] = value..value + 1;
            }
        }
        let subset = ArraySubset::new_with_ranges(&ranges);
        // A FIFO or device in a chunk's place would block the read: refused by name.
        let chunks = level.array.chunks_in_array_subset(&subset).map_err(|e| e.to_string())?;
        if let Some(chunks) = chunks {
            for index in chunks.indices().iter() {
                crate::store::check_file(&self.image.path.join(level.array.chunk_key(&index).as_str()))?;
            }
        }
        level.array.retrieve_array_subset::<Vec<T>>(&subset).map_err(|e| e.to_string())
    }
}

impl RawBoxes for StoreBoxes {
    fn read_raw(&self, bx: VoxelBox) -> Result<VoxelData, LoadError> {
        let level = &self.image.levels[0];
        let read = match level.voxel_type {
            VoxelType::U8 => self.read::<u8>(bx).map(VoxelData::U8),
            VoxelType::U16 => self.read::<u16>(bx).map(VoxelData::U16),
            VoxelType::I16 => self.read::<i16>(bx).map(VoxelData::I16),
            VoxelType::F32 => self.read::<f32>(bx).map(VoxelData::F32),
        };
        read.map_err(|problem| LoadError::StoreBox {
            path: PathBuf::from(&self.image.path),
            problem: format!("level \"{}\", box {:?}..{:?}: {problem}", level.path, bx.lo, bx.hi),
        })
    }
}
