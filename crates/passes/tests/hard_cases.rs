//! Numerically hard cases of geometry and data, each a named test, rendered on the GPU and
//! compared with the f64 reference (no NaN or Inf anywhere: it makes the difference infinite):
//! camera inside the volume, exactly on a face, an edge, a corner; axis-aligned and grazing
//! rays; a 130° field of view; a far camera; tiny steps and a step longer than the volume; NaN
//! in the data; a one-voxel-thick sheet and volumes one voxel thick along each axis; anisotropic
//! spacing (1,1,2), (1,1,20), (0.01,1,1); 16-bit volumes in both byte orders and their fallbacks;
//! flipped NRRD axes. Transfer-function, effect and precision cases: hard_cases_effects.rs.
//! Tolerances as in `gpu_vs_reference.rs` (2/255 max, same reasons) unless a test says otherwise.

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::render_reference;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::Image;
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;
use volgraph_passes::raycast_params::reference_settings;

mod support;

use support::{diff_reference, gpu, graph_source, render_once};

#[allow(unused_imports, reason = "save_images is used on failure")]
use support::save_images;

const SIZE: u32 = 64;

/// Renders graphs/basic/fragment_raycast.ron and returns (GPU image, reference colour).
fn render(
    volume: &Volume,
    tf: &TransferFunction,
    camera: &OrbitCamera,
    options: CompileOptions,
) -> (Image, Vec<[f64; 4]>) {
    render_on(&gpu(), volume, tf, camera, options)
}

/// [`render`] on a given device (one opened without some optional feature).
fn render_on(
    gpu: &std::sync::Arc<volgraph_core::runtime::Gpu>,
    volume: &Volume,
    tf: &TransferFunction,
    camera: &OrbitCamera,
    options: CompileOptions,
) -> (Image, Vec<[f64; 4]>) {
    let source = graph_source("basic/fragment_raycast.ron");
    let registry = builtin_registry();
    let plan = compile("fragment_raycast.ron", &source, &registry, &options).expect("compiles");
    let settings = reference_settings(&plan.steps.iter().find(|s| s.pass_id == "march").expect("march").params);
    let lut = tf.to_lut_for(volume, 256);
    let (mut runtime, _) =
        render_once(gpu, &registry, "fragment_raycast.ron", &source, &options, volume, &lut, camera).expect("renders");
    let image = runtime.read_output("image").expect("image");
    let reference = render_reference(volume, &lut, camera, options.viewport.0, options.viewport.1, &settings);
    (image, reference.color)
}

fn coverage(reference: &[[f64; 4]]) -> f64 {
    reference.iter().filter(|c| c[3] > 1e-3).count() as f64 / reference.len() as f64
}

fn assert_close(name: &str, image: &Image, reference: &[[f64; 4]], min_coverage: f64) {
    // NaN or Inf anywhere makes the max difference infinite.
    let (max, _) = diff_reference(image, reference);
    let finite = max.is_finite();
    let cov = coverage(reference);
    eprintln!("{name}: max {:.3}/255, coverage {cov:.2}", max * 255.0);
    if max.is_nan() || max > 2.0 / 255.0 {
        support::save_images(&format!("hard_{name}"), image, reference);
    }
    assert!(finite, "{name}: the GPU image has NaN or Inf");
    assert!(cov >= min_coverage, "{name}: reference nearly empty ({cov:.2}); the test would prove nothing");
    assert!(max <= 2.0 / 255.0, "{name}: max abs {:.3}/255 > 2/255", max * 255.0);
}

/// For cases where a ray's first or last sample can fall on either side of a thin slab's face
/// (rasterized entry on the GPU, analytic on the CPU): one sample more or fewer moves such a
/// pixel by up to one opaque sample, so only a fraction `allowed` of pixels may exceed 2/255,
/// and the mean must stay under 0.5/255. No NaN or Inf anywhere.
fn assert_mostly_close(name: &str, image: &Image, reference: &[[f64; 4]], min_coverage: f64, allowed: f64) {
    let (max, mean) = diff_reference(image, reference);
    let over = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let g = image.rgba(x, y);
            let r = reference[(y * image.width + x) as usize];
            (0..4).any(|c| (g[c] as f64 - r[c]).abs() > 2.0 / 255.0)
        })
        .count() as f64
        / (image.width * image.height) as f64;
    let cov = coverage(reference);
    eprintln!(
        "{name}: max {:.3}/255, mean {:.4}/255, {:.2}% over 2/255, coverage {cov:.2}",
        max * 255.0,
        mean * 255.0,
        over * 100.0
    );
    assert!(max.is_finite(), "{name}: the GPU image has NaN or Inf");
    assert!(cov >= min_coverage, "{name}: reference nearly empty ({cov:.2})");
    assert!(
        over <= allowed && mean <= 0.5 / 255.0,
        "{name}: {:.2}% over 2/255, mean {:.4}/255",
        over * 100.0,
        mean * 255.0
    );
}

fn ml() -> (Volume, TransferFunction) {
    let v = volgraph_accel::generate::marschner_lobb(32);
    let tf = TransferFunction::default_for(&v);
    (v, tf)
}

#[test]
fn camera_inside_the_volume_starts_rays_at_the_near_plane() {
    let (v, tf) = ml();
    let camera = OrbitCamera { azimuth_deg: 20.0, elevation_deg: 10.0, distance: 0.15, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("inside", &image, &reference, 0.9);
}

#[test]
fn axis_aligned_rays_have_no_nan() {
    let (v, tf) = ml();
    for (az, el) in [(0.0, 0.0), (90.0, 0.0), (180.0, 0.0), (0.0, 90.0), (0.0, -90.0)] {
        let camera = OrbitCamera { azimuth_deg: az, elevation_deg: el, ..OrbitCamera::default() };
        let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
        assert_close(&format!("axis az {az} el {el}"), &image, &reference, 0.2);
    }
}

#[test]
fn grazing_rays_along_an_edge_match() {
    let (v, tf) = ml();
    // Looking along a box edge: many rays enter and leave within a fraction of a voxel.
    let camera = OrbitCamera { azimuth_deg: 45.0, elevation_deg: 0.0, distance: 3.2, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("grazing edge", &image, &reference, 0.2);
}

#[test]
fn tiny_steps_match() {
    let (v, tf) = ml();
    let options = CompileOptions::new(32, 32).with_param("march", "step_voxels", 0.02);
    let (image, reference) = render(&v, &tf, &OrbitCamera::default(), options);
    // 50× more samples than the default step compound f32 rounding further; still within 2/255.
    assert_close("step 0.02", &image, &reference, 0.2);
}

#[test]
fn nan_in_float_data_is_replaced_and_renders_finite() {
    let (mut v, counts) = volgraph_accel::generate::non_finite_f32(24);
    assert!(counts.0 + counts.1 + counts.2 > 0, "the generator put non-finite values in");
    let replaced = volgraph_accel::load::sanitize_volume(&mut v);
    assert_eq!(replaced, counts, "every NaN/Inf is counted when replaced");
    let tf = TransferFunction::default_for(&v);
    let (image, reference) = render(&v, &tf, &OrbitCamera::default(), CompileOptions::new(SIZE, SIZE));
    assert_close("NaN replaced", &image, &reference, 0.05);
}

#[test]
fn one_voxel_thick_sheet_is_not_missed() {
    let v = volgraph_accel::generate::sheet(32, volgraph_accel::generate::Axis::X, 16);
    let tf = TransferFunction::preset(volgraph_accel::transfer_function::Preset::Opaque, (0.0, 255.0));
    let camera = OrbitCamera { azimuth_deg: 90.0, elevation_deg: 0.0, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("sheet", &image, &reference, 0.2);
}

#[test]
fn anisotropic_spacing_is_carried_to_the_gpu() {
    // Like the lobster (1, 1, 1.4), exaggerated: the box is flattened in z and the unit step is
    // the smallest voxel side, on both sides of the comparison.
    let (mut v, tf) = ml();
    v.spacing = glam::DVec3::new(1.0, 1.0, 2.0);
    let camera = OrbitCamera { azimuth_deg: 60.0, elevation_deg: 35.0, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("spacing 1,1,2", &image, &reference, 0.1);
}

/// Marschner–Lobb quantized to 16 bits, written as a raw file of `dtype` in `endianness` and
/// read back through the loader, so the test covers file decoding, upload and sampling.
fn sixteen_bit_ml(dtype: &str, endianness: volgraph_accel::load::Endianness) -> Volume {
    use volgraph_accel::load::{Endianness, RawOptions, load_volume};
    let ml = volgraph_accel::generate::marschner_lobb_f32(24);
    let unorm: Vec<u16> = ml.normalized_f32().iter().map(|v| (v * 65535.0).round() as u16).collect();
    let bytes: Vec<u8> = unorm
        .iter()
        .flat_map(|&u| {
            // i16 stores u - 32768, so both types normalize to the same value.
            let raw = if dtype == "int16" { (u as i32 - 32768) as i16 as u16 } else { u };
            match endianness {
                Endianness::Little => raw.to_le_bytes(),
                Endianness::Big => raw.to_be_bytes(),
            }
        })
        .collect();
    let order = if endianness == Endianness::Big { "be" } else { "le" };
    // A directory of its own per call: tests run in parallel and two of them write the same
    // name (the name carries the dims and type the loader reads).
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("volgraph_hard_{}_{call}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("ml{order}_24x24x24_{dtype}.raw"));
    std::fs::write(&path, bytes).expect("temp file");
    let loaded = load_volume(&path, &RawOptions { endianness, ..RawOptions::default() }).expect("loads");
    let _ = std::fs::remove_dir_all(&dir);
    loaded.volume
}

#[test]
fn sixteen_bit_volumes_in_both_byte_orders_match_the_reference() {
    use volgraph_accel::load::Endianness;
    let gpu = gpu();
    let camera = OrbitCamera { azimuth_deg: 35.0, elevation_deg: 25.0, ..OrbitCamera::default() };
    for dtype in ["uint16", "int16"] {
        for order in [Endianness::Little, Endianness::Big] {
            let v = sixteen_bit_ml(dtype, order);
            let tf = TransferFunction::default_for(&v);
            let (image, reference) = render_on(&gpu, &v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
            // 16-bit normalized texels filter like 8-bit ones on lavapipe (same 2/255 bound).
            assert_close(&format!("{dtype} {order:?}"), &image, &reference, 0.2);
        }
    }
}

#[test]
fn sixteen_bit_volume_without_norm16_is_widened_to_float() {
    use volgraph_core::runtime::{Gpu, GpuOptions};
    let gpu = std::sync::Arc::new(
        Gpu::new_headless_with(&GpuOptions {
            without_features: wgpu::Features::TEXTURE_FORMAT_16BIT_NORM,
            ..Default::default()
        })
        .expect("a Vulkan adapter"),
    );
    assert!(!gpu.norm16);
    let v = sixteen_bit_ml("uint16", volgraph_accel::load::Endianness::Little);
    let tf = TransferFunction::default_for(&v);
    let uploaded = volgraph_core::runtime::upload_volume_texture(&gpu, &v).expect("uploads without the feature");
    let expected = if gpu.float32_filterable {
        volgraph_core::runtime::VolumeFormat::R32Float
    } else {
        volgraph_core::runtime::VolumeFormat::R16Float
    };
    assert_eq!(uploaded.format, expected);
    let (image, reference) = render_on(&gpu, &v, &tf, &OrbitCamera::default(), CompileOptions::new(SIZE, SIZE));
    assert_close("uint16 as float", &image, &reference, 0.2);
}

#[test]
fn sixteen_bit_volume_on_a_device_with_neither_format_uses_half_floats() {
    use volgraph_core::runtime::{Gpu, GpuOptions, VolumeFormat};
    let without = wgpu::Features::TEXTURE_FORMAT_16BIT_NORM | wgpu::Features::FLOAT32_FILTERABLE;
    let gpu = std::sync::Arc::new(
        Gpu::new_headless_with(&GpuOptions { without_features: without, ..Default::default() })
            .expect("a Vulkan adapter"),
    );
    let v = sixteen_bit_ml("int16", volgraph_accel::load::Endianness::Big);
    let uploaded = volgraph_core::runtime::upload_volume_texture(&gpu, &v).expect("uploads");
    assert_eq!(uploaded.format, VolumeFormat::R16Float);
    let tf = TransferFunction::default_for(&v);
    let (image, reference) = render_on(&gpu, &v, &tf, &OrbitCamera::default(), CompileOptions::new(SIZE, SIZE));
    // f16 keeps 11 significant bits: a normalized value moves by up to 2⁻¹², which the
    // default TF's slope turns into well under 1/255 of opacity per sample; the 2/255 bound holds.
    assert_close("int16 as f16", &image, &reference, 0.2);
}

#[test]
fn camera_beyond_the_default_far_plane_still_sees_the_volume() {
    // Distance 150 is past the camera's nominal far plane (100): the clip planes follow the
    // camera, so the volume is drawn, not clipped away to a black image. A narrow field of view
    // keeps the volume large on screen.
    let (v, tf) = ml();
    let camera = OrbitCamera { distance: 150.0, fov_y_deg: 0.5, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("far camera", &image, &reference, 0.2);
}

#[test]
fn extreme_anisotropy_long_z_voxels() {
    // Spacing 1, 1, 20: a 32×32×4 grid twenty times deeper per voxel in z than in x and y; the
    // unit step is the smallest side (1), so a z-ray takes ~160 samples through 4 voxels.
    // Slices z = 0, 8, 16, 24 of Marschner–Lobb 32³.
    let ml = volgraph_accel::generate::marschner_lobb(32);
    let volgraph_accel::volume::VoxelData::U8(values) = &ml.data else { panic!("u8") };
    let slices: Vec<u8> = (0..4u32)
        .flat_map(|k| (0..32 * 32).map(move |i| (k, i)))
        .map(|(k, i)| values[(k * 8 * 32 * 32 + i) as usize])
        .collect();
    let v = Volume::new(
        "ml_1_1_20",
        glam::UVec3::new(32, 32, 4),
        glam::DVec3::new(1.0, 1.0, 20.0),
        volgraph_accel::volume::VoxelData::U8(slices),
    );
    let tf = TransferFunction::default_for(&v);
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 25.0, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("spacing 1,1,20", &image, &reference, 0.1);
}

#[test]
fn extreme_anisotropy_thin_x_voxels() {
    // Spacing 0.01, 1, 1: x voxels a hundredth as wide; the unit step (0.01) makes rays along y
    // and z take thousands of samples — f32 accumulation over them stays within 2/255.
    let (mut v, tf) = ml();
    v.spacing = glam::DVec3::new(0.01, 1.0, 1.0);
    let camera = OrbitCamera { azimuth_deg: 70.0, elevation_deg: 20.0, ..OrbitCamera::default() };
    let (image, reference) =
        render(&v, &tf, &camera, CompileOptions::new(32, 32).with_param("march", "step_voxels", 4.0));
    // Boxes a hundredth as deep as wide: silhouette rays graze the thin faces.
    assert_mostly_close("spacing 0.01,1,1", &image, &reference, 0.02, 0.01);
}

/// A volume one voxel thick along `axis` (the other sides 32): the middle slice of Marschner–Lobb.
fn one_voxel_thick(axis: usize) -> Volume {
    let mut dims = [32u32; 3];
    dims[axis] = 1;
    let ml = volgraph_accel::generate::marschner_lobb(32);
    let volgraph_accel::volume::VoxelData::U8(values) = &ml.data else { panic!("u8") };
    let mut data = Vec::with_capacity((dims[0] * dims[1] * dims[2]) as usize);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let mut p = [x, y, z];
                p[axis] = 16;
                data.push(values[ml.index(p[0], p[1], p[2])]);
            }
        }
    }
    let data = volgraph_accel::volume::VoxelData::U8(data);
    Volume::new(format!("thick1_{axis}"), glam::UVec3::from_array(dims), glam::DVec3::ONE, data)
}

fn check_one_voxel_thick(axis: usize) {
    let v = one_voxel_thick(axis);
    let tf = TransferFunction::preset(volgraph_accel::transfer_function::Preset::Opaque, v.value_range);
    // Look across the thin axis, obliquely, so rays cross the one-voxel slab.
    let (az, el) = match axis {
        0 => (60.0, 10.0),
        1 => (20.0, 60.0),
        _ => (20.0, 10.0),
    };
    let camera = OrbitCamera { azimuth_deg: az, elevation_deg: el, distance: 2.0, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    // The slab is one voxel (1/32 of the box) thick and the TF opaque: rays cross it in a few
    // samples, and at its silhouette one more or fewer is a large step.
    assert_mostly_close(&format!("one voxel thick along axis {axis}"), &image, &reference, 0.05, 0.03);
}

#[test]
fn one_voxel_thick_volume_along_x() {
    check_one_voxel_thick(0);
}

#[test]
fn one_voxel_thick_volume_along_y() {
    check_one_voxel_thick(1);
}

#[test]
fn one_voxel_thick_volume_along_z() {
    check_one_voxel_thick(2);
}

#[test]
fn camera_exactly_on_a_face() {
    // The eye at (0, 0, 0.5): on the +z face of the unit box (half extent 0.5).
    let (v, tf) = ml();
    let camera =
        OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 0.5, fov_y_deg: 60.0, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("on a face", &image, &reference, 0.5);
}

#[test]
fn camera_exactly_on_an_edge() {
    // The eye at (0.5, 0, 0.5) up to rounding: on the edge where the +x and +z faces meet.
    let (v, tf) = ml();
    let camera = OrbitCamera {
        azimuth_deg: 45.0,
        elevation_deg: 0.0,
        distance: 0.5f64.sqrt(),
        fov_y_deg: 60.0,
        ..OrbitCamera::default()
    };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("on an edge", &image, &reference, 0.2);
}

#[test]
fn camera_exactly_on_a_corner() {
    // The eye at (0.5, 0.5, 0.5) up to rounding: the corner of the +x, +y, +z faces.
    let (v, tf) = ml();
    let elevation = (0.5f64 / 0.5f64.sqrt()).atan().to_degrees();
    let camera = OrbitCamera {
        azimuth_deg: 45.0,
        elevation_deg: elevation,
        distance: 0.75f64.sqrt(),
        fov_y_deg: 60.0,
        ..OrbitCamera::default()
    };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("on a corner", &image, &reference, 0.1);
}

#[test]
fn wide_field_of_view() {
    // 130°: rays at the image edge leave the eye 65° off axis; the near-plane start and the
    // per-pixel directions stay exact.
    let (v, tf) = ml();
    let camera = OrbitCamera { fov_y_deg: 130.0, distance: 0.62, ..OrbitCamera::default() };
    let (image, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("fov 130", &image, &reference, 0.1);
}

#[test]
fn a_step_longer_than_the_volume() {
    // Step 16 voxels through an 8³ volume: most rays take no sample (the first sits half a step
    // in, past their exit), diagonal ones one — and the GPU agrees on which.
    let v = volgraph_accel::generate::marschner_lobb(8);
    let tf = TransferFunction::preset(volgraph_accel::transfer_function::Preset::Opaque, v.value_range);
    let camera = OrbitCamera { azimuth_deg: 40.0, elevation_deg: 35.0, distance: 2.0, ..OrbitCamera::default() };
    let (image, reference) =
        render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE).with_param("march", "step_voxels", 16.0));
    let (max, _) = diff_reference(&image, &reference);
    assert!(max.is_finite() && max <= 2.0 / 255.0, "step 16: max {:.3}/255", max * 255.0);
    assert!(coverage(&reference) > 0.0, "some diagonal rays are long enough for one sample");
}

#[test]
fn flipped_nrrd_axes_render_like_the_original() {
    // The same voxels written reversed along x with `space directions: (-1,0,0) ...`: the loader
    // puts them back, so the GPU image equals the reference of the original volume.
    let (v, tf) = ml();
    let n = v.dims;
    let volgraph_accel::volume::VoxelData::U8(data) = &v.data else { panic!("u8") };
    let mut flipped = Vec::with_capacity(data.len());
    for z in 0..n.z {
        for y in 0..n.y {
            for x in (0..n.x).rev() {
                flipped.push(data[v.index(x, y, z)]);
            }
        }
    }
    let dir = std::env::temp_dir().join(format!("volgraph-hard-nrrd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("flipped.nrrd");
    let mut bytes = format!(
        "NRRD0004\ntype: uchar\ndimension: 3\nspace: left-posterior-superior\nsizes: {} {} {}\n\
         space directions: (-1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n\n",
        n.x, n.y, n.z
    )
    .into_bytes();
    bytes.extend_from_slice(&flipped);
    std::fs::write(&path, bytes).expect("write");
    let loaded =
        volgraph_accel::load::load_volume(&path, &volgraph_accel::load::RawOptions::default()).expect("loads").volume;
    assert_eq!(loaded.data, v.data, "the loader undoes the flip");
    let camera = OrbitCamera { azimuth_deg: 35.0, elevation_deg: 25.0, ..OrbitCamera::default() };
    let (image, _) = render(&loaded, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    let (_, reference) = render(&v, &tf, &camera, CompileOptions::new(SIZE, SIZE));
    assert_close("flipped NRRD", &image, &reference, 0.2);
    let _ = std::fs::remove_dir_all(&dir);
}
