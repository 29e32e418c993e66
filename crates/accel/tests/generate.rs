//! Generated volumes contain what their documentation promises.

use glam::{DVec3, UVec3};
use volgraph_accel::generate::{self, Axis, SplitMix64, marschner_lobb_value, voxel_centre};
use volgraph_accel::volume::{Volume, VoxelData};

fn bytes(v: &Volume) -> &[u8] {
    match &v.data {
        VoxelData::U8(b) => b,
        other => panic!("{} is {}, expected uint8", v.name, other.type_name()),
    }
}

fn count_on(v: &Volume) -> usize {
    bytes(v).iter().filter(|&&b| b == 255).count()
}

#[test]
fn marschner_lobb_matches_hand_values() {
    // r = 0: ρ_r = cos(2π·6·cos 0) = 1, so ρ = (1 - sin(πz/2) + 0.5) / 2.5.
    assert!((marschner_lobb_value(DVec3::ZERO) - 0.6).abs() < 1e-12);
    assert!((marschner_lobb_value(DVec3::new(0.0, 0.0, 1.0)) - 0.2).abs() < 1e-12);
    // r = 1, z = -1: ρ_r = cos(2π·6·cos(π/2)) = 1 and sin(-π/2) = -1: ρ = 2.5/2.5 = 1.
    assert!((marschner_lobb_value(DVec3::new(1.0, 0.0, -1.0)) - 1.0).abs() < 1e-12);

    let n = 41;
    let ml = generate::marschner_lobb(n);
    assert_eq!(ml.name, "marschner_lobb_41");
    assert_eq!(ml.dims, UVec3::splat(n));
    let (x, y, z) = (3, 17, 29);
    let expected = (marschner_lobb_value(voxel_centre(n, x, y, z)) * 255.0).round() as u8;
    assert_eq!(bytes(&ml)[ml.index(x, y, z)], expected);
    // Voxel centres are at (i + 0.5)/n in texture space: the middle voxel of an odd axis is 0.
    assert_eq!(voxel_centre(n, 20, 20, 20), DVec3::ZERO);

    let f = generate::marschner_lobb_f32(16);
    assert_eq!(f.value_range, (0.0, 1.0));
    let i = f.index(5, 9, 2);
    assert!((f.normalized(i) - marschner_lobb_value(voxel_centre(16, 5, 9, 2))).abs() < 1e-6, "normalized is ρ");
}

#[test]
fn sphere_and_shell_volumes_match_their_analytic_size() {
    let n = 64;
    // Fraction of the box [-1,1]³ inside radius 0.5: (4/3)π·0.125 / 8.
    let sphere = generate::sphere(n, 0.5);
    let expected = 4.0 / 3.0 * std::f64::consts::PI * 0.125 / 8.0 * (n as f64).powi(3);
    let got = count_on(&sphere) as f64;
    assert!((got / expected - 1.0).abs() < 0.02, "sphere voxels {got} vs {expected}");
    assert_eq!(bytes(&sphere)[sphere.index(32, 32, 32)], 255);
    assert_eq!(bytes(&sphere)[sphere.index(0, 0, 0)], 0);

    let shell = generate::spherical_shell(n, 0.4, 0.6);
    let expected = 4.0 / 3.0 * std::f64::consts::PI * (0.216 - 0.064) / 8.0 * (n as f64).powi(3);
    let got = count_on(&shell) as f64;
    assert!((got / expected - 1.0).abs() < 0.02, "shell voxels {got} vs {expected}");
    assert_eq!(bytes(&shell)[shell.index(32, 32, 32)], 0, "hollow centre");
}

#[test]
fn slabs_checkerboard_and_sheet() {
    let slabs = generate::slabs(8, Axis::X, 2);
    assert_eq!(slabs.name, "slabs_x_8");
    let row: Vec<u8> = (0..8).map(|x| bytes(&slabs)[slabs.index(x, 5, 6)]).collect();
    assert_eq!(row, vec![0, 0, 255, 255, 0, 0, 255, 255]);

    let board = generate::checkerboard(8, 2);
    assert_eq!(count_on(&board), 8 * 8 * 8 / 2);
    assert_eq!(bytes(&board)[board.index(0, 0, 0)], 0);
    assert_eq!(bytes(&board)[board.index(2, 0, 0)], 255);
    assert_eq!(bytes(&board)[board.index(2, 2, 0)], 0);

    let sheet = generate::sheet(16, Axis::Z, 5);
    assert_eq!(count_on(&sheet), 16 * 16, "exactly one plane of voxels");
    assert_eq!(bytes(&sheet)[sheet.index(3, 9, 5)], 255);
    assert_eq!(bytes(&sheet)[sheet.index(3, 9, 4)], 0);
}

#[test]
fn noise_is_seeded_and_uniform() {
    // SplitMix64 from state 0 starts with 0xE220A8397B1DCDAF (Vigna's reference splitmix64.c).
    assert_eq!(SplitMix64(0).next_u64(), 0xE220_A839_7B1D_CDAF);
    let a = generate::noise(32, 7);
    assert_eq!(a.name, "noise_32_seed7");
    assert_eq!(a, generate::noise(32, 7), "same seed, same volume");
    assert_ne!(a.data, generate::noise(32, 8).data);
    // Mean of 32768 uniform bytes: 127.5 with a standard error of 73.9/181 ≈ 0.41.
    let mean = bytes(&a).iter().map(|&b| b as f64).sum::<f64>() / 32768.0;
    assert!((mean - 127.5).abs() < 2.0, "mean {mean}");
}

#[test]
fn edge_case_volumes() {
    let zeros = generate::zeros(8);
    assert!(bytes(&zeros).iter().all(|&b| b == 0));
    let one = generate::one_voxel(8, UVec3::new(1, 2, 3), 200);
    let lit: Vec<usize> = bytes(&one).iter().enumerate().filter(|(_, b)| **b != 0).map(|(i, _)| i).collect();
    assert_eq!(lit, vec![one.index(1, 2, 3)]);
    assert_eq!(bytes(&one)[one.index(1, 2, 3)], 200);

    let (nf, (nan, pos, neg)) = generate::non_finite_f32(8);
    let VoxelData::F32(values) = &nf.data else { panic!("float32") };
    assert_eq!(values.iter().filter(|v| v.is_nan()).count(), nan);
    assert_eq!(values.iter().filter(|&&v| v == f32::INFINITY).count(), pos);
    assert_eq!(values.iter().filter(|&&v| v == f32::NEG_INFINITY).count(), neg);
    assert_eq!(nf.value_range, (0.0, 7.0), "Volume::new takes the finite range");
}
