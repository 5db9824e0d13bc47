// Moment soft shadow maps (Peters, Münstermann, Wetzstein and Klein, JCGT 2017), the Shade
// pass over 16-bit fixed-point summed-area tables of q1..q4 (sat.wgsl, codes
// round(q 65535) summed in u32). Per receiver, ts = d - bias, sf = 2 ts - 1 (signed depth):
//   1. the search region (as PCSS); box means of q1..q4 there;
//   2. back to the signed-depth moments (the transform's inverse, or the binomial expansion
//      of (2z - 1)^k), biased: b' = (1 - alpha) b + alpha (0, 0.628, 0, 0.628);
//   3. the blocker search: the Hamburger bounding distribution at sf (hamburger.wgsl), the
//      weights of its roots in front of sf (each clamped to [0, 1], a vanishing
//      denominator giving 0), s_occ = (lit_weight sf + sum w s) / (lit_weight + sum w),
//      clamped to [-1, 1]; z_occ = (s_occ + 1) / 2;
//   4. the filter region from z_occ (as PCSS, at least one texel); box means, decoded and
//      biased;
//   5. the 4MSM intensity G at sf; visibility 1 - clamp(G).

struct Params {
    light_width: vec2<f32>,
    near: f32,
    far: f32,
    uv_per_world: f32,
    bias: f32,
    alpha: f32,
    lit_weight: f32,
    quantise: u32,
    size: f32,
}

// the u32 tables of the four channels (sat.wgsl)
@group(0) @binding(2) var<storage, read> table: array<u32>;
@group(0) @binding(3) var<uniform> params: Params;

const SQRT3: f32 = 1.7320508;

fn entry(c: u32, x: i32, y: i32) -> u32 {
    if (x < 0 || y < 0) {
        return 0u;
    }
    let n = u32(params.size);
    return table[(c * n + u32(y)) * n + u32(x)];
}

// the sum of the codes of texels [x0, x1) x [y0, y1), exact modulo 2^32
fn block(c: u32, x0: i32, x1: i32, y0: i32, y1: i32) -> u32 {
    if (x1 <= x0 || y1 <= y0) {
        return 0u;
    }
    return entry(c, x1 - 1, y1 - 1) - entry(c, x0 - 1, y1 - 1) - entry(c, x1 - 1, y0 - 1) + entry(c, x0 - 1, y0 - 1);
}

// the means of q1..q4 over the box w wide centred at uv, decoded (codes / 65535)
fn box_means(uv: vec2<f32>, w: vec2<f32>) -> vec4<f32> {
    let rx = box_axis(uv.x, w.x, params.size);
    let ry = box_axis(uv.y, w.y, params.size);
    var sum = vec4<f32>(0.0);
    for (var j = 0; j < 3; j++) {
        for (var i = 0; i < 3; i++) {
            let wt = rx.weight[i] * ry.weight[j];
            if (wt > 0.0) {
                for (var c = 0u; c < 4u; c++) {
                    sum[c] += wt * f32(block(c, rx.start[i], rx.end[i], ry.start[j], ry.end[j]));
                }
            }
        }
    }
    return sum / (rx.length * ry.length * 65535.0);
}

// the biased signed-depth moments from the channels' means
fn signed_moments(q: vec4<f32>) -> vec4<f32> {
    var b: vec4<f32>;
    if (params.quantise != 0u) {
        let u = q.x - 0.5;
        let v = q.z - 0.5;
        b = vec4<f32>(SQRT3 * v - u / 3.0, q.w + 0.125 * q.y, 0.75 * (SQRT3 * v - u), q.w - 0.125 * q.y);
    } else {
        b = vec4<f32>(
            2.0 * q.x - 1.0,
            4.0 * q.y - 4.0 * q.x + 1.0,
            8.0 * q.z - 12.0 * q.y + 6.0 * q.x - 1.0,
            16.0 * q.w - 32.0 * q.z + 24.0 * q.y - 8.0 * q.x + 1.0);
    }
    return (1.0 - params.alpha) * b + params.alpha * vec4<f32>(0.0, 0.628, 0.0, 0.628);
}

fn root_weight(b: vec4<f32>, x: f32, y: f32, z: f32) -> f32 {
    let den = (x - y) * (x - z);
    if (abs(den) < 1e-12) {
        return 0.0;
    }
    return saturate((b.y - (y + z) * b.x + y * z) / den);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let near = params.near;
    let ts = q.d - params.bias;
    let sf = 2.0 * ts - 1.0;
    let dist = max(near + q.d * (params.far - near), near);
    // 1-2. the search region's moments
    let su = params.light_width * ((dist - near) / dist) * params.uv_per_world;
    let bs = signed_moments(box_means(q.uv, su));
    // 3. the blocker search
    let roots = hamburger_roots(bs, sf);
    var w = 0.0;
    var s = 0.0;
    if (roots.x < sf) {
        let wl = root_weight(bs, roots.x, sf, roots.y);
        w += wl;
        s += wl * roots.x;
    }
    if (roots.y < sf) {
        let wl = root_weight(bs, roots.y, sf, roots.x);
        w += wl;
        s += wl * roots.y;
    }
    let s_occ = clamp((params.lit_weight * sf + s) / (params.lit_weight + w), -1.0, 1.0);
    let z_occ = 0.5 * (s_occ + 1.0);
    // 4. the filter region
    let zbw = near + z_occ * (params.far - near);
    var ratio = 0.0;
    if (zbw > 1e-30) {
        ratio = max(dist - zbw, 0.0) / zbw;
    }
    let pu = max(params.light_width * ratio * (near / dist) * params.uv_per_world, vec2<f32>(1.0 / params.size));
    let bf = signed_moments(box_means(q.uv, pu));
    // 5. the 4MSM intensity at the receiver
    let g = hamburger_intensity(hamburger_roots(bf, sf), bf, sf);
    store_visibility(id.x, 1.0 - saturate(g));
}
