// One level of a mean mip chain: each texel the mean of the 2 x 2 texels below it, clamped
// at the edge of an odd-sized level.

@group(0) @binding(0) var src: texture_2d_array<f32>;
@group(0) @binding(1) var dst: texture_storage_2d_array<FORMAT, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(dst))) {
        return;
    }
    let last = vec2<i32>(textureDimensions(src)) - 1;
    let p = 2 * vec2<i32>(id.xy);
    let sum = textureLoad(src, min(p, last), id.z, 0)
        + textureLoad(src, min(p + vec2<i32>(1, 0), last), id.z, 0)
        + textureLoad(src, min(p + vec2<i32>(0, 1), last), id.z, 0)
        + textureLoad(src, min(p + vec2<i32>(1, 1), last), id.z, 0);
    textureStore(dst, id.xy, id.z, 0.25 * sum);
}
