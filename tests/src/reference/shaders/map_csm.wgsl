// Convolution shadow maps (Annen 2008, chapter 6): the basis images of eq. 6.6,
// B_(2k-1)(z) = sin(c_k z) and B_(2k)(z) = cos(c_k z) with c_k = pi (2k - 1) (the factor pi
// makes the square wave of eq. 6.2 have period 2 in d - z). Layer l holds orders
// k = 2l + 1 and 2l + 2 as (sin, cos, sin, cos); a unorm precision keeps each as
// (v - lo) / span over its range.

struct Params {
    // M
    orders: u32,
}

struct Encoding {
    lo: vec4<f32>,
    span: vec4<f32>,
}

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var basis: texture_storage_2d_array<FORMAT, write>;
@group(0) @binding(2) var<uniform> params: Params;
@group(0) @binding(3) var<storage, read> encoding: array<Encoding>;

// (sin, cos) of 2 pi t, the argument reduced to [-pi, pi] where Vulkan bounds their error
// (2^-11 absolute): c_k z = 2 pi t with t = (2k - 1) z / 2 turns.
fn sin_cos_turns(t: f32) -> vec2<f32> {
    let a = 6.2831853 * (t - round(t));
    return vec2<f32>(sin(a), cos(a));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    let layer = id.z;
    let k = 2u * layer + 1u;
    let first = sin_cos_turns(f32(2u * k - 1u) * 0.5 * z);
    var second = vec2<f32>(0.0);
    if (k < params.orders) {
        second = sin_cos_turns(f32(2u * k + 1u) * 0.5 * z);
    }
    let e = encoding[layer];
    textureStore(basis, id.xy, layer, (vec4<f32>(first, second) - e.lo) / e.span);
}
