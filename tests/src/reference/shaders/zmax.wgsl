// One axis of a separable maximum filter of the depth (Annen 2008, 7.3.1: z-max
// classification), reads outside the map clamped to the edge.

struct Params {
    // (1, 0) or (0, 1)
    axis: vec2<i32>,
    // (taps - 1) / 2
    radius: i32,
}

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dst: texture_storage_2d<r32float, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(textureDimensions(src));
    let p = vec2<i32>(id.xy);
    if (any(p >= size)) {
        return;
    }
    var m = textureLoad(src, clamp(p - params.radius * params.axis, vec2<i32>(0), size - 1), 0).r;
    for (var t = 1 - params.radius; t <= params.radius; t++) {
        m = max(m, textureLoad(src, clamp(p + t * params.axis, vec2<i32>(0), size - 1), 0).r);
    }
    textureStore(dst, p, vec4<f32>(m, 0.0, 0.0, 1.0));
}
