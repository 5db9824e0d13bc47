// Percentage-closer soft shadows (Fernando 2005; Annen 2008, section 4.2; techniques/pcss.ron).
// Per receiver: an N x N blocker search over the near-plane cut of the pyramid from the
// receiver to the light, the mean depth of the samples nearer than the receiver, the
// penumbra width w = (d_r - d_b) light_width / d_b (light-space distances) projected to the
// near plane, and the mean of M x M binary tests (eq. 3.2) over it. Both sample sets lie on
// the lattice ((i n + j + 1/2) / n^2, (j n + i + 1/2) / n^2) - 1/2 scaled to the region, each
// read from the texel containing uv + offset (`nearest_at`), clamped to the edge.

struct Params {
    light_width: vec2<f32>,
    near: f32,
    far: f32,
    // uv_width(len, near) = len * uv_per_world
    uv_per_world: f32,
    bias: f32,
    // N, M
    search: i32,
    taps: i32,
}

@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var<uniform> params: Params;

fn offset(n: i32, i: i32, j: i32) -> vec2<f32> {
    let nn = f32(n * n);
    return vec2<f32>((f32(i * n + j) + 0.5) / nn, (f32(j * n + i) + 0.5) / nn) - 0.5;
}

fn nearest_at(uv: vec2<f32>, o: vec2<f32>) -> f32 {
    let size = vec2<i32>(textureDimensions(depth));
    let texel = clamp(vec2<i32>(floor((uv + o) * vec2<f32>(size))), vec2<i32>(0), size - 1);
    return textureLoad(depth, texel, 0).r;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let near = params.near;
    let dist = max(near + q.d * (params.far - near), near);
    // depth_slope = 0: the slope-scaled terms vanish
    let db = q.d - params.bias;
    // 1. blocker search
    let su = params.light_width * ((dist - near) / dist) * params.uv_per_world;
    let n = params.search;
    var count = 0.0;
    var sum = 0.0;
    for (var i = 0; i < n; i++) {
        for (var j = 0; j < n; j++) {
            let zs = nearest_at(q.uv, offset(n, i, j) * su);
            if (zs < db) {
                count += 1.0;
                sum += zs;
            }
        }
    }
    var zb = db;
    if (count >= 0.5) {
        zb = sum / count;
    }
    // 2. penumbra width on the receiver, projected to the near plane
    let zbw = near + zb * (params.far - near);
    var wp = 0.0;
    if (abs(zbw) >= 1e-30) {
        wp = max(dist - zbw, 0.0) / zbw;
    }
    let pu = params.light_width * wp * (near / dist) * params.uv_per_world;
    // 3. PCF
    let m = params.taps;
    var lit = 0.0;
    for (var i = 0; i < m; i++) {
        for (var j = 0; j < m; j++) {
            lit += select(0.0, 1.0, db <= nearest_at(q.uv, offset(m, i, j) * pu));
        }
    }
    store_visibility(id.x, select(lit / f32(m * m), 1.0, count < 0.5));
}
