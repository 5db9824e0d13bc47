// Variance soft shadow maps (Yang, Dong, Feng, Seidel and Kautz, PG 2010), the Shade pass,
// over f32 summed-area tables of (z, z^2) less 1/2 (sat_f32.wgsl). Per receiver, t = d - bias:
//   1. the search region: the pyramid from the receiver to the light cut by the near plane
//      (as PCSS), in uv; its mean and second moment from the tables;
//   2. Chebyshev's one-sided bound P there (section 3), at most 0.9999; no blocker when it
//      reaches 0.9999; else the blocker depth z_occ = (mu - P t) / (1 - P), the lit part of
//      the region taken at the receiver's depth;
//   3. the filter region from z_occ: the penumbra width (d - z_occ) light_width / z_occ in
//      light-space distances, projected to the near plane, at least one texel;
//   4. the bound over the whole filter region; where it reads lit (1: the receiver in front
//      of the region's mean) and `subdivide` is set, the mean of the bounds over its four
//      quadrants (section 4), each box half as wide, centred a quarter of the region off.

struct Params {
    light_width: vec2<f32>,
    near: f32,
    far: f32,
    // uv_width(len, near) = len * uv_per_world
    uv_per_world: f32,
    bias: f32,
    min_variance: f32,
    subdivide: u32,
    // the shadow map's size in texels
    size: f32,
    // the tables' centre (1/2)
    centre: f32,
}

// the f32 tables (sat_f32.wgsl): channel 0 z, channel 1 z^2
@group(0) @binding(2) var<storage, read> table: array<f32>;
@group(0) @binding(3) var<uniform> params: Params;

const LIT: f32 = 0.9999;

fn entry(c: u32, x: i32, y: i32) -> f32 {
    if (x < 0 || y < 0) {
        return 0.0;
    }
    let n = u32(params.size);
    return table[(c * n + u32(y)) * n + u32(x)];
}

// the sum of v - centre over texels [x0, x1) x [y0, y1)
fn block(c: u32, x0: i32, x1: i32, y0: i32, y1: i32) -> f32 {
    if (x1 <= x0 || y1 <= y0) {
        return 0.0;
    }
    return entry(c, x1 - 1, y1 - 1) - entry(c, x0 - 1, y1 - 1) - entry(c, x1 - 1, y0 - 1) + entry(c, x0 - 1, y0 - 1);
}

// (mean of z, mean of z^2) over the box w wide centred at `at` (`sample_box_at`)
fn moments(at: vec2<f32>, w: vec2<f32>) -> vec2<f32> {
    let rx = box_axis(at.x, w.x, params.size);
    let ry = box_axis(at.y, w.y, params.size);
    var sum = vec2<f32>(0.0);
    for (var j = 0; j < 3; j++) {
        for (var i = 0; i < 3; i++) {
            let wt = rx.weight[i] * ry.weight[j];
            if (wt > 0.0) {
                for (var c = 0u; c < 2u; c++) {
                    sum[c] += wt * block(c, rx.start[i], rx.end[i], ry.start[j], ry.end[j]);
                }
            }
        }
    }
    return sum / (rx.length * ry.length) + params.centre;
}

// Chebyshev's one-sided bound: 1 in front of the mean, var / (var + (t - mean)^2) behind
fn chebyshev(m: vec2<f32>, t: f32) -> f32 {
    if (t <= m.x) {
        return 1.0;
    }
    let variance = max(m.y - m.x * m.x, params.min_variance);
    let delta = t - m.x;
    return variance / (variance + delta * delta);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let near = params.near;
    let t = q.d - params.bias;
    let dist = max(near + q.d * (params.far - near), near);
    // 1. the search region
    let su = params.light_width * ((dist - near) / dist) * params.uv_per_world;
    let ms = moments(q.uv, su);
    // 2. the blocker
    let p = min(chebyshev(ms, t), LIT);
    if (p >= LIT) {
        store_visibility(id.x, 1.0);
        return;
    }
    let z_occ = clamp((ms.x - p * t) / (1.0 - p), 0.0, 1.0);
    // 3. the filter region
    let zbw = near + z_occ * (params.far - near);
    var ratio = 0.0;
    if (zbw > 1e-30) {
        ratio = max(dist - zbw, 0.0) / zbw;
    }
    let pu = max(params.light_width * ratio * (near / dist) * params.uv_per_world, vec2<f32>(1.0 / params.size));
    // 4. the bound over it, or over its quadrants
    let whole = chebyshev(moments(q.uv, pu), t);
    var v = whole;
    if (params.subdivide != 0u && whole >= 1.0) {
        let o = 0.25 * pu;
        let h = 0.5 * pu;
        v = 0.25 * (chebyshev(moments(q.uv + vec2<f32>(-o.x, -o.y), h), t)
            + chebyshev(moments(q.uv + vec2<f32>(o.x, -o.y), h), t)
            + chebyshev(moments(q.uv + vec2<f32>(-o.x, o.y), h), t)
            + chebyshev(moments(q.uv + vec2<f32>(o.x, o.y), h), t));
    }
    store_visibility(id.x, v);
}
