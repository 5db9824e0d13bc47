// Exponential shadow maps (Annen 2008, chapter 7). The filtered test is
// s_f = e^{-cd} [w * e^{cz}] (eq. 7.2); where the assumption d >= z fails inside the kernel
// the receiver is classified (7.3) and falls back to the ESM evaluated at the four nearest
// texels, each clamped to [0, 1] and interpolated bilinearly. One entry point per
// classification: `plain` (none), `threshold` (7.3.2), `z_max` (7.3.1).

struct Params {
    c: f32,
    bias: f32,
    // threshold classification: fall back where s_f > 1 + eps
    eps: f32,
    // z-max classification: added to d so that lit surfaces are not flagged
    zmax_offset: f32,
    // decoding of the stored basis: e^{cz} = stored * span + lo
    lo: f32,
    span: f32,
}

// the blurred basis e^{cz}, layer 0 .r
@group(0) @binding(2) var esm: texture_2d_array<f32>;
@group(0) @binding(3) var linear_clamp: sampler;
@group(0) @binding(4) var<uniform> params: Params;
// the maximum depth over the blur and bilinear footprint (z_max only)
@group(0) @binding(5) var zmax: texture_2d<f32>;

// e^{-cd}, the receiver's factor of eq. 7.1
fn decay(q: Query) -> f32 {
    return exp(-params.c * (q.d - params.bias));
}

fn decode(stored: f32) -> f32 {
    return stored * params.span + params.lo;
}

// eq. 7.2, unclamped
fn filtered(q: Query, e_cd: f32) -> f32 {
    return e_cd * decode(textureSampleLevel(esm, linear_clamp, q.uv, 0, 0.0).r);
}

// 7.3: the ESM itself at the four nearest texels, clamped, interpolated bilinearly
fn fallback(q: Query, e_cd: f32) -> f32 {
    let size = vec2<i32>(textureDimensions(esm));
    let st = q.uv * vec2<f32>(size) - 0.5;
    let base = vec2<i32>(floor(st));
    let tf = fract(st);
    let last = size - 1;
    let f00 = saturate(e_cd * decode(textureLoad(esm, clamp(base, vec2<i32>(0), last), 0, 0).r));
    let f10 = saturate(e_cd * decode(textureLoad(esm, clamp(base + vec2<i32>(1, 0), vec2<i32>(0), last), 0, 0).r));
    let f01 = saturate(e_cd * decode(textureLoad(esm, clamp(base + vec2<i32>(0, 1), vec2<i32>(0), last), 0, 0).r));
    let f11 = saturate(e_cd * decode(textureLoad(esm, clamp(base + vec2<i32>(1, 1), vec2<i32>(0), last), 0, 0).r));
    return mix(mix(f00, f10, tf.x), mix(f01, f11, tf.x), tf.y);
}

@compute @workgroup_size(64)
fn plain(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    store_visibility(id.x, filtered(q, decay(q)));
}

@compute @workgroup_size(64)
fn threshold(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let e_cd = decay(q);
    var s = filtered(q, e_cd);
    // 7.3.2: a filtered value above 1 + eps means some z under the kernel lies behind d
    if (s > 1.0 + params.eps) {
        s = fallback(q, e_cd);
    }
    store_visibility(id.x, s);
}

@compute @workgroup_size(64)
fn z_max(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let e_cd = decay(q);
    let size = vec2<i32>(textureDimensions(zmax));
    let texel = clamp(vec2<i32>(floor(q.uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
    // 7.3.1: conservative, some z under the kernel may lie behind d
    if (q.d + params.zmax_offset < textureLoad(zmax, texel, 0).r) {
        store_visibility(id.x, fallback(q, e_cd));
    } else {
        store_visibility(id.x, filtered(q, e_cd));
    }
}
