// Convolution shadow maps (Annen 2008, chapter 6): the filtered test is the sum of the
// filtered basis images weighted by the receiver's coefficients (eq. 5.8), with the Fourier
// expansion of eq. 6.5:
//   s_f = 1/2 + sum_k (2 a_k / c_k) [cos(c_k d) [w * sin(c_k z)] - sin(c_k d) [w * cos(c_k z)]]
// c_k = pi (2k - 1), a_k = exp(-alpha (k/M)^2) against ringing (6.1.1), and one of the two
// fixes of fig. 6.3 for lit surfaces reading 1/2: d offset by 1/(2M), or s_f scaled by 2.

struct Params {
    // M
    orders: u32,
    // subtracted from d: the depth bias, plus 1/(2M) with the offset fix
    shift: f32,
    // 2 with the scaling fix, else 1
    scale: f32,
}

struct Encoding {
    lo: vec4<f32>,
    span: vec4<f32>,
}

// layer l: (sin, cos) of orders 2l + 1 and 2l + 2, blurred and mipmapped
@group(0) @binding(2) var basis: texture_2d_array<f32>;
@group(0) @binding(3) var linear_clamp: sampler;
@group(0) @binding(4) var<uniform> params: Params;
@group(0) @binding(5) var<storage, read> encoding: array<Encoding>;
// 2 a_k / c_k for k = 1..M
@group(0) @binding(6) var<storage, read> amplitude: array<f32>;

// (sin, cos) of 2 pi t, the argument reduced to [-pi, pi]: c_k d = 2 pi ((2k - 1) d / 2).
fn sin_cos_turns(t: f32) -> vec2<f32> {
    let a = 6.2831853 * (t - round(t));
    return vec2<f32>(sin(a), cos(a));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let d = q.d - params.shift;
    var s = 0.5;
    let layers = (params.orders + 1u) / 2u;
    for (var layer = 0u; layer < layers; layer++) {
        let e = encoding[layer];
        let b = textureSampleLevel(basis, linear_clamp, q.uv, layer, q.lod) * e.span + e.lo;
        // a_(2k-1)(d) B_(2k-1) + a_(2k)(d) B_(2k) (eq. 6.6) for the layer's first order k
        let k = 2u * layer + 1u;
        let w = sin_cos_turns(f32(2u * k - 1u) * 0.5 * d);
        s += amplitude[k - 1u] * (w.y * b.x - w.x * b.y);
        if (k < params.orders) {
            let w2 = sin_cos_turns(f32(2u * k + 1u) * 0.5 * d);
            s += amplitude[k] * (w2.y * b.z - w2.x * b.w);
        }
    }
    store_visibility(id.x, params.scale * s);
}
