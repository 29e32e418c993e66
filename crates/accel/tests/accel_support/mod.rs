//! Shared helpers of the acceleration-structure tests: seeded random volumes and LUTs, and an
//! independent f64 model of the LUT's 1D linear sampler.

#![allow(dead_code, reason = "each test binary uses a different subset of the helpers")]

use glam::{DVec3, UVec3};
use volgraph_accel::volume::{Volume, VoxelData};

/// The library's SplitMix64 with the draws these tests need, so a proptest case is
/// reproducible from a seed.
pub struct Rng(volgraph_accel::generate::SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(volgraph_accel::generate::SplitMix64(seed))
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }
}

/// A volume with structure: a background level, a few boxes of other values and some noise, so
/// that blocks are sometimes empty and sometimes not under a random LUT.
pub fn random_volume(dims: UVec3, float: bool, seed: u64) -> Volume {
    let mut rng = Rng::new(seed);
    let count = (dims.x * dims.y * dims.z) as usize;
    let background = if rng.below(2) == 0 { 0.0 } else { rng.unit() };
    let mut values = vec![background; count];
    let noise = if rng.below(3) == 0 { rng.unit() * 0.3 } else { 0.0 };
    for v in values.iter_mut() {
        *v = (*v + (rng.unit() - 0.5) * noise).clamp(0.0, 1.0);
    }
    for _ in 0..rng.below(4) {
        let value = rng.unit();
        let lo = UVec3::new(
            rng.below(dims.x as u64) as u32,
            rng.below(dims.y as u64) as u32,
            rng.below(dims.z as u64) as u32,
        );
        let size = UVec3::new(1 + rng.below(6) as u32, 1 + rng.below(6) as u32, 1 + rng.below(6) as u32);
        let hi = (lo + size).min(dims);
        for z in lo.z..hi.z {
            for y in lo.y..hi.y {
                for x in lo.x..hi.x {
                    values[(x + dims.x * (y + dims.y * z)) as usize] = value;
                }
            }
        }
    }
    let (data, value_range) = if float {
        // Float data with an arbitrary affine scale, normalized by its own range.
        let scaled: Vec<f32> = values.iter().map(|v| (*v * 1000.0 - 200.0) as f32).collect();
        let lo = scaled.iter().copied().fold(f32::INFINITY, f32::min) as f64;
        let hi = scaled.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
        (VoxelData::F32(scaled), (lo, hi))
    } else {
        (VoxelData::U8(values.iter().map(|v| (v * 255.0).round() as u8).collect()), (0.0, 255.0))
    };
    Volume { dims, spacing: DVec3::ONE, data, name: format!("random-{seed}"), value_range, meta: Default::default() }
}

/// A LUT of 1..=64 texels whose alpha is zero in runs, so classification has gaps.
pub fn random_lut(seed: u64) -> Vec<[f32; 4]> {
    let mut rng = Rng::new(seed ^ 0x5EED);
    let n = 1 + rng.below(64) as usize;
    let p_visible = rng.unit();
    let mut lut = Vec::with_capacity(n);
    let mut visible = rng.unit() < p_visible;
    for _ in 0..n {
        if rng.below(4) == 0 {
            visible = rng.unit() < p_visible;
        }
        let a = if visible { 0.001 + rng.unit() as f32 } else { 0.0 };
        lut.push([1.0, 1.0, 1.0, a]);
    }
    lut
}

/// Alpha of the LUT at normalized `s`, an independent f64 model of a 1D linear sampler with
/// clamp-to-edge (texel centres at `(i+0.5)/n`).
pub fn lut_alpha(lut: &[[f32; 4]], s: f64) -> f64 {
    let n = lut.len();
    let x = s * n as f64 - 0.5;
    let i0 = x.floor();
    let f = x - i0;
    let clamp = |i: f64| i.clamp(0.0, (n - 1) as f64) as usize;
    let (a0, a1) = (lut[clamp(i0)][3] as f64, lut[clamp(i0 + 1.0)][3] as f64);
    a0 * (1.0 - f) + a1 * f
}

/// Positions to probe: random ones (some slightly outside [0,1]) plus voxel corners and centres.
pub fn probe_positions(dims: UVec3, seed: u64, random: usize) -> Vec<DVec3> {
    let mut rng = Rng::new(seed ^ 0xABCD);
    let n = dims.as_dvec3();
    let mut out = Vec::new();
    for _ in 0..random {
        out.push(DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 1.1 - 0.05);
    }
    // Every voxel corner `i/n` (block and brick faces lie on these) and centre `(i+0.5)/n`,
    // or 20,000 of them drawn at random when there are more (keeps a case in milliseconds).
    let half_steps = 2 * dims + 1;
    let grid_points = half_steps.x as u64 * half_steps.y as u64 * half_steps.z as u64;
    let grid_point = |x: u32, y: u32, z: u32| DVec3::new(x as f64, y as f64, z as f64) * 0.5 / n;
    if grid_points <= 20_000 {
        for z in 0..half_steps.z {
            for y in 0..half_steps.y {
                for x in 0..half_steps.x {
                    out.push(grid_point(x, y, z));
                }
            }
        }
    } else {
        for _ in 0..20_000 {
            let x = rng.below(half_steps.x as u64) as u32;
            let y = rng.below(half_steps.y as u64) as u32;
            let z = rng.below(half_steps.z as u64) as u32;
            out.push(grid_point(x, y, z));
        }
    }
    out
}
