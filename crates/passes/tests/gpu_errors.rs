//! wgpu's default error handler panics; volgraph turns every GPU error into a value that names
//! what was being done (issue "bad input never crashes"). Each test provokes one real error.

use volgraph_core::runtime::{ApplyError, GpuFaultKind, GpuOptions, RuntimeError, VolumeTexels};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;

mod support;

use support::{gpu, graph_source, runtime};

#[test]
fn a_texture_the_device_cannot_make_is_a_fault_not_a_panic() {
    let gpu = volgraph_core::runtime::Gpu::new_headless_with(&GpuOptions {
        without_features: wgpu::Features::TEXTURE_FORMAT_16BIT_NORM,
        ..Default::default()
    })
    .expect("a Vulkan adapter");
    let fault = gpu
        .checked(
            || "making an R16Unorm texture".to_string(),
            || {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("r16"),
                    size: wgpu::Extent3d { width: 4, height: 4, depth_or_array_layers: 4 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D3,
                    format: wgpu::TextureFormat::R16Unorm,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
            },
        )
        .expect_err("R16Unorm needs TEXTURE_FORMAT_16BIT_NORM");
    assert_eq!(fault.kind, GpuFaultKind::Validation);
    let text = fault.to_string();
    assert!(text.starts_with("making an R16Unorm texture: the GPU rejected it:"), "{text}");
    // The device keeps working after a captured error.
    assert!(gpu.checked(|| "nothing".to_string(), || ()).is_ok());
}

#[test]
fn a_volume_over_the_texture_limit_names_the_volume_and_the_limit() {
    let gpu = gpu();
    let side = gpu.limits.max_texture_dimension_3d + 1;
    let texels = vec![0u8; side as usize];
    let err = volgraph_core::runtime::upload_volume(&gpu, "tall", [1, 1, side], &VolumeTexels::Unorm8(&texels))
        .err()
        .expect("over the limit");
    let text = err.to_string();
    assert!(text.contains("volume \"tall\" is 1x1x") && text.contains("bricking"), "{text}");
}

#[test]
fn a_viewport_over_the_texture_limit_is_an_error_naming_the_target() {
    let gpu = gpu();
    let side = gpu.limits.max_texture_dimension_2d + 1;
    let registry = builtin_registry();
    let plan = compile(
        "fragment_raycast.ron",
        &graph_source("basic/fragment_raycast.ron"),
        &registry,
        &CompileOptions::new(side, 8),
    )
    .expect("compiles: the size is only known to be too big on this device");
    let mut runtime = runtime(&gpu);
    let err = runtime.apply(plan, &registry).expect_err("the GPU refuses the targets");
    let RuntimeError::Apply(ApplyError::Gpu(fault)) = &err else { panic!("expected a GPU fault, got {err}") };
    assert_eq!(fault.kind, GpuFaultKind::Validation);
    assert!(fault.what.starts_with("creating target slot0") && fault.what.contains("entry.entry"), "{}", fault.what);
    assert!(runtime.plan().is_none(), "nothing half-applied");
}

/// Issue 20: the four compute passes with a workgroup parameter share one check against the
/// device's invocation limit; 256×256 (within the parameter's range) is over every device's.
#[test]
fn a_workgroup_over_the_device_limit_names_both_sizes() {
    let gpu = gpu();
    let limit = gpu.limits.max_compute_invocations_per_workgroup;
    let registry = builtin_registry();
    for (graph, pass) in [("basic/compute_raycast.ron", "march"), ("modern/fastest.ron", "march")] {
        let options =
            CompileOptions::new(16, 16).with_param(pass, "workgroup_x", 256u64).with_param(pass, "workgroup_y", 256u64);
        let plan = compile(graph, &graph_source(graph), &registry, &options).unwrap_or_else(|d| panic!("{d}"));
        let mut runtime = runtime(&gpu);
        let err = runtime.apply(plan, &registry).expect_err("over the invocation limit").to_string();
        assert!(
            err.contains(&format!("workgroup 256x256 has 65536 invocations, over this GPU's limit of {limit}")),
            "{graph}: {err}"
        );
    }
}

/// The transfer function is a 1D texture: a LUT over the device's 1D limit, or one with no
/// entries, is a fault naming the upload, never a panic, and the device keeps working.
#[test]
fn a_lut_the_device_cannot_hold_is_a_fault_naming_it() {
    let gpu = gpu();
    let limit = gpu.limits.max_texture_dimension_1d as usize;
    for (entries, what) in [(limit + 1, "over the 1D limit"), (0, "empty")] {
        let lut = vec![[0.5f32, 0.5, 0.5, 0.1]; entries];
        let fault = volgraph_core::runtime::upload_lut(&gpu, "tf", &lut).expect_err(what);
        let text = fault.to_string();
        assert!(text.starts_with("uploading the transfer-function LUT \"tf\""), "{what}: {text}");
    }
    assert!(volgraph_core::runtime::upload_lut(&gpu, "tf", &[[0.0; 4]; 256]).is_ok(), "a 256-entry LUT uploads");
}
