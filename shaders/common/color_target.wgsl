// The premultiplied linear RGBA a compute raycaster writes: Rgba16Float, or Rgba32Float where the
// graph or the scene's precision asks for f32 (the pass compiles with COLOR_F32 then:
// `volgraph_passes::shared::color_precision_defines`). One declaration for every compute march.
#if COLOR_F32
@group(0) @binding(auto) var color: texture_storage_2d<rgba32float, write>;
#else
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;
#endif
