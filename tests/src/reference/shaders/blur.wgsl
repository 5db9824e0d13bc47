// One axis of a separable convolution (Annen 2008, eq. 5.2; box or Gaussian weights) over
// every layer of a 2D array texture, reads outside the map clamped to the edge. The
// horizontal step writes an rgba32float intermediate, so only the vertical step rounds to
// the storage precision.

struct Params {
    // (1, 0) or (0, 1)
    axis: vec2<i32>,
    // (taps - 1) / 2
    radius: i32,
}

@group(0) @binding(0) var src: texture_2d_array<f32>;
@group(0) @binding(1) var dst: texture_storage_2d_array<FORMAT, write>;
@group(0) @binding(2) var<uniform> params: Params;
// the 2 radius + 1 weights, summing to 1
@group(0) @binding(3) var<storage, read> weights: array<f32>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(textureDimensions(src));
    let p = vec2<i32>(id.xy);
    if (any(p >= size)) {
        return;
    }
    var sum = vec4<f32>(0.0);
    for (var t = -params.radius; t <= params.radius; t++) {
        let texel = clamp(p + t * params.axis, vec2<i32>(0), size - 1);
        sum += weights[t + params.radius] * textureLoad(src, texel, id.z, 0);
    }
    textureStore(dst, p, id.z, sum);
}
