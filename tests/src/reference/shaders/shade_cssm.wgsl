// Convolution soft shadow maps (Annen 2008, chapter 8; techniques/cssm.ron), the Shade pass.
// Follows cssm_mips.wgsl or cssm_table.wgsl, which bind the prefiltered images and define
// `series_texels` and `weighted_texels` (four decoded channels of a layer, filtered over a
// kernel u wide in uv). Per receiver:
//   1. the initial kernel (8.2.2): light_width (d - near) / d at the near plane, in uv;
//   2. s_f there (eq. 8.1, the raw CSM series) and the numerator of eq. 8.8; z_avg by the
//      guarded division of eq. 8.6 (no blocker: lit), clamped to [0, d];
//   3. the final kernel f_w = (light_width / d) ((d - z_avg) / z_avg) near (8.3.1), with d
//      and z_avg light-space distances;
//   4. the series at f_w, the fixes of 6.1.1, ringing suppression (8.2.3) and the
//      sharpening s^p, p = 1 + A exp(-B (d - z_avg)) (eq. 8.9).

struct Params {
    // light_width, world units along the light view's x and y
    light_width: vec2<f32>,
    near: f32,
    far: f32,
    // uv_width(len, near) = len * uv_per_world
    uv_per_world: f32,
    bias: f32,
    // subtracted from d - bias in the series: 1/(2M) with fix = 1
    offset: f32,
    // 2 with fix = 2, else 1
    scale: f32,
    ring: f32,
    min_blocker: f32,
    a: f32,
    b: f32,
    // M
    orders: u32,
    // shadow-map size in texels
    size: f32,
}

struct Encoding {
    lo: vec4<f32>,
    span: vec4<f32>,
}

// (sin, cos) of 2 pi t, the argument reduced to [-pi, pi]: c_k d = 2 pi ((2k - 1) d / 2).
fn sin_cos_turns(t: f32) -> vec2<f32> {
    let a = 6.2831853 * (t - round(t));
    return vec2<f32>(sin(a), cos(a));
}

// eq. 6.5-6.6: s_f = 1/2 + sum_k (2 a_k / c_k) [cos(c_k d) S_k - sin(c_k d) C_k]
fn series(uv: vec2<f32>, u: vec2<f32>, dr: f32) -> f32 {
    var s = 0.5;
    let layers = (params.orders + 1u) / 2u;
    for (var layer = 0u; layer < layers; layer++) {
        let b = series_texels(layer, uv, u);
        let k = 2u * layer + 1u;
        let w = sin_cos_turns(f32(2u * k - 1u) * 0.5 * dr);
        s += amplitude[k - 1u] * (w.y * b.x - w.x * b.y);
        if (k < params.orders) {
            let w2 = sin_cos_turns(f32(2u * k + 1u) * 0.5 * dr);
            s += amplitude[k] * (w2.y * b.z - w2.x * b.w);
        }
    }
    return s;
}

// eq. 8.8: [w * z/2] + sum_k (2 a_k / c_k) [sin(c_k d) [w * z cos] - cos(c_k d) [w * z sin]]
fn weighted(uv: vec2<f32>, u: vec2<f32>, dr: f32) -> f32 {
    var s = 0.0;
    let channels = 2u * params.orders + 1u;
    let layers = (channels + 3u) / 4u;
    for (var layer = 0u; layer < layers; layer++) {
        let b = weighted_texels(layer, uv, u);
        for (var i = 0u; i < 4u; i++) {
            let c = 4u * layer + i;
            if (c < 2u * params.orders) {
                let k = c / 2u + 1u;
                let w = sin_cos_turns(f32(2u * k - 1u) * 0.5 * dr);
                // z sin(c_k z) (even c) weighs -cos(c_k d), z cos(c_k z) weighs sin(c_k d)
                s += amplitude[k - 1u] * select(w.x, -w.y, c % 2u == 0u) * b[i];
            } else if (c == 2u * params.orders) {
                s += b[i];
            }
        }
    }
    return s;
}

// 6.1.1 and 8.2.3: scale (fix = 2), shift and scale against ringing, clamp
fn ringing(s: f32) -> f32 {
    return saturate((params.scale * s - params.ring) / (1.0 - 2.0 * params.ring));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let db = q.d - params.bias;
    let dr = db - params.offset;
    let near = params.near;
    // d_world = near + d (far - near): the Depth pass's linear normalisation
    let dist = max(near + q.d * (params.far - near), near);
    // 1. 8.2.2: the pyramid to the light cut by the near plane, in uv
    let u0 = params.light_width * ((dist - near) / dist) * params.uv_per_world;
    // 2. eq. 8.1 and 8.6
    let sf = series(q.uv, u0, dr);
    let num = weighted(q.uv, u0, dr);
    let blockers = 1.0 - sf;
    let no_blocker = blockers < params.min_blocker;
    var quotient = db;
    if (abs(blockers) >= params.min_blocker && blockers != 0.0) {
        quotient = num / blockers;
    }
    let zavg = clamp(quotient, 0.0, max(db, 0.0));
    // 3. 8.3.1 in light-space distances
    let zw = near + zavg * (params.far - near);
    let den = dist * zw;
    var ratio = 0.0;
    if (abs(den) >= 1e-30) {
        ratio = near * max(dist - zw, 0.0) / den;
    }
    let u1 = params.light_width * ratio * params.uv_per_world;
    // 4. the lookup at f_w, ringing suppression, sharpening (eq. 8.9)
    let v1 = ringing(series(q.uv, u1, dr));
    let p = 1.0 + params.a * exp(-params.b * max(db - zavg, 0.0));
    let sharpened = select(0.0, pow(v1, p), v1 > 0.0);
    store_visibility(id.x, select(sharpened, ringing(sf), no_blocker));
}
