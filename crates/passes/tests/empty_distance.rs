//! `empty_distance` on the GPU equals `volgraph_accel::chebyshev` cell for cell: the map is read
//! back through a [`GridTap`] and compared with the CPU transform of the GPU's own empty-block
//! flags (the flags themselves are checked against the CPU classification in
//! `kruger_westermann.rs`). Exact equality, no tolerance: both are whole numbers of blocks.

use glam::{DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::chebyshev::chebyshev_distance;
use volgraph_accel::generate::SplitMix64;
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;
use volgraph_passes::empty_distance::EmptyDistance;
use volgraph_passes::empty_space::EmptySpace;
use volgraph_passes::grid_tap::GridTap;

mod support;

use support::{gpu, graph_source, render_once};

/// The shader's cap (`DISTANCE_CAP` of `empty_distance.wgsl`).
const CAP: u32 = 255;

/// A LUT that hides values below the middle and shows the rest opaque white.
fn threshold_lut() -> Vec<[f32; 4]> {
    (0..256).map(|i| if i < 128 { [0.0; 4] } else { [1.0; 4] }).collect()
}

/// `dims` voxels of 0 with `count` random voxels at 255 (seeded: the same volume every run).
fn sprinkled(dims: UVec3, count: usize, seed: u64) -> Volume {
    let mut rng = SplitMix64(seed);
    let mut data = vec![0u8; (dims.x * dims.y * dims.z) as usize];
    for _ in 0..count {
        let i = (rng.next_u64() % data.len() as u64) as usize;
        data[i] = 255;
    }
    Volume::new(format!("sprinkled_{}x{}x{}", dims.x, dims.y, dims.z), dims, DVec3::ONE, VoxelData::U8(data))
}

/// Renders `modern/fastest` over `volume` at `block` and returns (GPU flags as "visible",
/// grid dims, GPU distances).
fn gpu_map(volume: &Volume, lut: &[[f32; 4]], block: u32) -> (Vec<bool>, UVec3, Vec<u32>) {
    let gpu = gpu();
    let (flags_tap, distance_tap) = (GridTap::new(), GridTap::new());
    let mut registry = builtin_registry();
    registry.register(EmptySpace::tapped(flags_tap.clone())).register(EmptyDistance::tapped(distance_tap.clone()));
    let graph = "modern/fastest.ron";
    let options =
        CompileOptions::new(32, 32).with_param("minmax", "block_size", block).with_param("march", "block_size", block);
    let source = graph_source(graph);
    compile(graph, &source, &registry, &options).unwrap_or_else(|d| panic!("{graph} compiles:\n{d}"));
    render_once(&gpu, &registry, graph, &source, &options, volume, lut, &OrbitCamera::default())
        .unwrap_or_else(|e| panic!("{}: {e}", volume.name));
    let (dims, flags) = flags_tap.read_f32(&gpu, 1).expect("GPU flags");
    let (distance_dims, distance) = distance_tap.read_f32(&gpu, 1).expect("GPU distance map");
    assert_eq!(dims, distance_dims, "{}: the map has the flags' size", volume.name);
    let visible = flags.iter().map(|f| *f <= 0.5).collect();
    let distance = distance
        .iter()
        .map(|d| {
            assert!(d.fract() == 0.0 && (0.0..=CAP as f32).contains(d), "{}: distance {d} is not 0..=255", volume.name);
            *d as u32
        })
        .collect();
    (visible, UVec3::from_array(dims), distance)
}

fn assert_map_equals_cpu(volume: &Volume, lut: &[[f32; 4]], block: u32) {
    let (visible, dims, distance) = gpu_map(volume, lut, block);
    let cpu = chebyshev_distance(&visible, dims, CAP);
    let differing: Vec<usize> = (0..cpu.len()).filter(|i| cpu[*i] != distance[*i]).collect();
    let largest = cpu.iter().max().copied().unwrap_or(0);
    eprintln!(
        "{} at block {block}: {dims} blocks, {} visible, largest distance {largest}, {} cells differ",
        volume.name,
        visible.iter().filter(|v| **v).count(),
        differing.len()
    );
    if let Some(&i) = differing.first() {
        let (x, y) = (i as u32 % dims.x, i as u32 / dims.x % dims.y);
        let z = i as u32 / (dims.x * dims.y);
        panic!(
            "{}: {} cells differ from the CPU transform, first at block ({x}, {y}, {z}): GPU {}, CPU {}",
            volume.name,
            differing.len(),
            distance[i],
            cpu[i]
        );
    }
}

#[test]
fn distance_map_equals_the_cpu_transform_on_sprinkled_grids() {
    let lut = threshold_lut();
    // Ragged sizes, few and many visible blocks, one voxel per block (every distance in reach).
    assert_map_equals_cpu(&sprinkled(UVec3::new(40, 33, 29), 12, 1), &lut, 1);
    assert_map_equals_cpu(&sprinkled(UVec3::new(37, 41, 23), 400, 2), &lut, 1);
    assert_map_equals_cpu(&sprinkled(UVec3::new(64, 64, 64), 30, 3), &lut, 2);
}

#[test]
fn distance_map_caps_long_lines_and_an_all_empty_grid() {
    let lut = threshold_lut();
    // A 600-block line with one visible block near an end: distances pass the cap of 255.
    let mut line = sprinkled(UVec3::new(600, 3, 2), 0, 4);
    if let VoxelData::U8(data) = &mut line.data {
        data[5] = 255;
    }
    assert_map_equals_cpu(&line, &lut, 1);
    // Nothing visible: the cap everywhere.
    assert_map_equals_cpu(&sprinkled(UVec3::new(20, 20, 20), 0, 5), &lut, 1);
}

#[test]
fn distance_map_equals_the_cpu_transform_on_real_data() {
    let lut = threshold_lut();
    assert_map_equals_cpu(&volgraph_accel::generate::marschner_lobb(64), &lut, 4);
    if volgraph_accel::data_dir::require_dataset("engine_vollib").is_some() {
        let engine = volgraph_accel::data_dir::load_dataset("engine_vollib").expect("engine loads").volume;
        assert_map_equals_cpu(&engine, &lut, 4);
    }
}
