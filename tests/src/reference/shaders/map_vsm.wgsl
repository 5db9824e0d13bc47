// Variance shadow maps (Donnelly & Lauritzen 2006; Annen 2008, section 4.1): store the
// first two moments (z, z^2) of the depth, so that filtering them gives the moments over
// the filter region. Both lie in [0, 1], which every precision holds as is.

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var moments: texture_storage_2d_array<FORMAT, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    textureStore(moments, id.xy, 0, vec4<f32>(z, z * z, 0.0, 0.0));
}
