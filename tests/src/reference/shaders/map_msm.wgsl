// Moment shadow mapping (Peters & Klein 2015): store the first four powers of the depth,
// b = (z, z^2, z^3, z^4) in layer 0, so that filtering them gives the moments over the
// filter region. All lie in [0, 1], which every precision holds as is.

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var moments: texture_storage_2d_array<FORMAT, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    let z2 = z * z;
    textureStore(moments, id.xy, 0, vec4<f32>(z, z2, z2 * z, z2 * z2));
}
