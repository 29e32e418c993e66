//! The voxel types a store holds, as one trait: read and written through zarrs, averaged 2×2×2
//! for the next level, compared for a chunk's range.

use volgraph_accel::volume::VoxelData;
use zarrs::array::{Element, ElementOwned};

/// A voxel value of a type volgraph renders.
pub trait Sample: Element + ElementOwned + Copy + Default + PartialOrd + Send + Sync + 'static {
    /// The Zarr v3 data type.
    fn data_type() -> zarrs::array::DataType;
    /// Zero, the fill value of the arrays written.
    fn fill_value() -> zarrs::array::FillValue;
    /// As f64 (exact for every type here).
    fn to_f64(self) -> f64;
    /// The mean of `sum / count` as this type (integers rounded to nearest).
    fn mean(sum: f64, count: u32) -> Self;
    /// The voxels of `data` if they are of this type.
    fn of(data: VoxelData) -> Option<Vec<Self>>;
}

macro_rules! integer_sample {
    ($t:ty, $variant:ident, $dt:ident) => {
        impl Sample for $t {
            fn data_type() -> zarrs::array::DataType {
                zarrs::array::data_type::$dt()
            }
            fn fill_value() -> zarrs::array::FillValue {
                zarrs::array::FillValue::from(0 as $t)
            }
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
            fn mean(sum: f64, count: u32) -> Self {
                (sum / f64::from(count)).round() as $t
            }
            fn of(data: VoxelData) -> Option<Vec<Self>> {
                match data {
                    VoxelData::$variant(v) => Some(v),
                    _ => None,
                }
            }
        }
    };
}

integer_sample!(u8, U8, uint8);
integer_sample!(u16, U16, uint16);
integer_sample!(i16, I16, int16);

impl Sample for f32 {
    fn data_type() -> zarrs::array::DataType {
        zarrs::array::data_type::float32()
    }
    fn fill_value() -> zarrs::array::FillValue {
        zarrs::array::FillValue::from(0.0f32)
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn mean(sum: f64, count: u32) -> Self {
        (sum / f64::from(count)) as f32
    }
    fn of(data: VoxelData) -> Option<Vec<Self>> {
        match data {
            VoxelData::F32(v) => Some(v),
            _ => None,
        }
    }
}

/// `planes` planes of `dims.0 × dims.1` voxels halved in x, y and z (odd edges averaged with
/// themselves): `ceil(planes / 2)` planes of `ceil(nx / 2) × ceil(ny / 2)`.
pub fn halve<T: Sample>(data: &[T], (nx, ny): (u32, u32), planes: u32) -> Vec<T> {
    let (hx, hy, hz) = (nx.div_ceil(2), ny.div_ceil(2), planes.div_ceil(2));
    let at = |x: u32, y: u32, z: u32| data[((z * ny + y) * nx + x) as usize].to_f64();
    let mut out = Vec::with_capacity((hx * hy * hz) as usize);
    for z in 0..hz {
        let zs = [2 * z, (2 * z + 1).min(planes - 1)];
        for y in 0..hy {
            let ys = [2 * y, (2 * y + 1).min(ny - 1)];
            for x in 0..hx {
                let xs = [2 * x, (2 * x + 1).min(nx - 1)];
                let mut sum = 0.0;
                for &zz in &zs {
                    for &yy in &ys {
                        for &xx in &xs {
                            sum += at(xx, yy, zz);
                        }
                    }
                }
                out.push(T::mean(sum, 8));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halving_averages_eight_and_clamps_odd_edges() {
        // 3×2×3: x 0..3, y 0..2, z 0..3; value = x + 10 y + 100 z.
        let data: Vec<u16> =
            (0..3).flat_map(|z| (0..2).flat_map(move |y| (0..3).map(move |x| x + 10 * y + 100 * z))).collect();
        let half = halve(&data, (3, 2), 3);
        assert_eq!(half.len(), 4, "2 × 1 × 2");
        // (0..2, 0..2, 0..2): mean of x 0,1 · y 0,1 · z 0,1 = 0.5 + 5 + 50 = 55.5 → 56.
        assert_eq!(half[0], 56);
        // x = 2 (odd edge: 2, 2), z 0,1: 2 + 5 + 50 = 57.
        assert_eq!(half[1], 57);
        // z = 2 (odd edge): 0.5 + 5 + 200 = 205.5 → 206.
        assert_eq!(half[2], 206);
    }
}
