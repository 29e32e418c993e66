// The volume's bounding box as 36 vertices (12 triangles), for Krüger & Westermann 2003 §2.1
// passes 1 and 2. Draw with `draw(0..36, 0..1)` and no vertex buffer.
//
// Winding: every triangle is counter-clockwise seen from outside the box (right-handed world).
// The orbit camera's view (look_at_rh) is a rotation, and the perspective (perspective_rh,
// depth [0,1]) scales x and y positively, so a face seen from outside stays counter-clockwise in
// NDC (y up): with `front_face: Ccw` use `cull_mode: Back` for front faces (entry points) and
// `cull_mode: Front` for back faces (ray exits). Checked on the CPU by
// crates/accel/tests/box_winding.rs, which parses BOX_CORNER_INDICES from this file.

// Corner `i` of the cube [-1,1]³ has x = +1 when bit 0 of `i` is set, y when bit 1, z when bit 2.
// Two triangles per face, faces in the order +x, -x, +y, -y, +z, -z.
const BOX_CORNER_INDICES = array<u32, 36>(1u, 3u, 7u, 1u, 7u, 5u, 4u, 6u, 2u, 4u, 2u, 0u, 6u, 7u, 3u, 6u, 3u, 2u, 0u, 1u, 5u, 0u, 5u, 4u, 4u, 5u, 7u, 4u, 7u, 6u, 2u, 3u, 1u, 2u, 1u, 0u);

// Vertex `vertex_index` (0..36) of the unit cube [-1,1]³; scale by `frame.half_extent.xyz`.
fn box_corner(vertex_index: u32) -> vec3<f32> {
    let i = BOX_CORNER_INDICES[min(vertex_index, 35u)];
    return vec3<f32>(
        select(-1.0, 1.0, (i & 1u) != 0u),
        select(-1.0, 1.0, (i & 2u) != 0u),
        select(-1.0, 1.0, (i & 4u) != 0u),
    );
}
