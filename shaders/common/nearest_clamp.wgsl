// The runtime's non-filtering, clamp-to-edge sampler (crates/core/src/runtime/record.rs). Texels
// read through it at their centres cost less than `textureLoad` on llvmpipe, whose texel fetch
// takes a level per lane and reads every level's size and strides lane by lane
// (bench/one-march-final.md, "llvmpipe profile"), and any float texture may be read so,
// filterable or not (volgraph_compiler::binding_rules::system_sampler_filters).
@group(0) @binding(auto) var nearest_clamp: sampler;
