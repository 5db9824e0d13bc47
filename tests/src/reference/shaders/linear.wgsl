// Soft shadow maps for linear lights (Heidrich, Brabec & Seidel 2000, section 3.2): one
// visibility channel of target view j made of the skins of source view i, as a hand-written
// compute shader in f32. One invocation per texel of view j loops over every triangle of view
// i's mesh over its texel centres (cell (x, y), T1 = (c00, c10, c11), T2 = (c00, c11, c01)),
// keeps the skins (corner-depth spread > tau and some corner's |LoG| > tau, the LoG
// 4 z(t) - z(t-x) - z(t+x) - z(t-y) - z(t+y) with neighbours clamped), places their corners
// in the world (view distance near_i + z (far_i - near_i) on the ray through the texel
// centre), projects them into view j, and tests the texel centre against the projected
// triangle (edge functions, edges included, either winding; a shared edge's function is
// computed from the corner whose source texel comes first, so both triangles get exact
// negatives). Values: corner 0 below the triangle's depth midpoint (occluder), else 1;
// interpolated perspective-correctly (screen = 0) or affinely in view j's screen (screen = 1).
// A fragment is kept iff its linear depth in view j is <= z_j + keep_bias and in [0, 1]; the
// nearest kept one wins, of equal depths the first in cell order. Skins with a corner at or
// behind view j's eye are skipped (the f64 reference ray-casts them).
//
// uv = clip.xy / clip.w * (0.5, -0.5) + 0.5; texel (x, y) has its centre at uv
// ((x + 0.5) / S, (y + 0.5) / S); linear depth (dist - near) / (far - near), dist = -(view p).z.

struct Params {
    view_i: mat4x4<f32>,
    vp_i: mat4x4<f32>,
    view_j: mat4x4<f32>,
    vp_j: mat4x4<f32>,
    size: u32,
    screen: u32,
    tau: f32,
    keep_bias: f32,
    near_i: f32,
    far_i: f32,
    near_j: f32,
    far_j: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
// the depth maps of views i and j (linear normalised, row-major, row 0 first)
@group(0) @binding(1) var<storage, read> depth_i: array<f32>;
@group(0) @binding(2) var<storage, read> depth_j: array<f32>;
// per texel of view j: (value, depth of the winning fragment, 0, 0); value 0.5 and depth -1
// where no skin was kept
@group(0) @binding(3) var<storage, read_write> channel: array<vec4<f32>>;
// per texel: the winning skin's index 2 (y (S - 1) + x) + half, 0xffffffff for none
@group(0) @binding(4) var<storage, read_write> winner: array<u32>;

fn z_at(x: i32, y: i32) -> f32 {
    let n = i32(params.size);
    let cx = clamp(x, 0, n - 1);
    let cy = clamp(y, 0, n - 1);
    return depth_i[u32(cy * n + cx)];
}

fn log_at(t: vec2<i32>) -> f32 {
    return 4.0 * z_at(t.x, t.y) - z_at(t.x - 1, t.y) - z_at(t.x + 1, t.y) - z_at(t.x, t.y - 1) - z_at(t.x, t.y + 1);
}

fn row_of(m: mat4x4<f32>, r: u32) -> vec4<f32> {
    return vec4<f32>(m[0][r], m[1][r], m[2][r], m[3][r]);
}

// The world point at view distance dist on view i's ray through the centre of texel t:
// clip.x - ndc_x clip.w = 0, clip.y - ndc_y clip.w = 0, -(view p).z = dist, by Cramer's rule.
fn corner_world(t: vec2<i32>, dist: f32) -> vec3<f32> {
    let s = f32(params.size);
    let nx = 2.0 * (f32(t.x) + 0.5) / s - 1.0;
    let ny = 1.0 - 2.0 * (f32(t.y) + 0.5) / s;
    let r0 = row_of(params.vp_i, 0u);
    let r1 = row_of(params.vp_i, 1u);
    let r3 = row_of(params.vp_i, 3u);
    let rz = row_of(params.view_i, 2u);
    let a0 = r0.xyz - nx * r3.xyz;
    let a1 = r1.xyz - ny * r3.xyz;
    let a2 = -rz.xyz;
    let b = vec3<f32>(-(r0.w - nx * r3.w), -(r1.w - ny * r3.w), dist + rz.w);
    let c12 = cross(a1, a2);
    let c20 = cross(a2, a0);
    let c01 = cross(a0, a1);
    let det = dot(a0, c12);
    return (b.x * c12 + b.y * c20 + b.z * c01) / det;
}

// Row-major order of a source texel: the corner that computes a shared edge's function.
fn key(t: vec2<i32>) -> i32 {
    return t.y * i32(params.size) + t.x;
}

fn edge_fn(ta: vec2<i32>, tb: vec2<i32>, qa: vec2<f32>, qb: vec2<f32>, p: vec2<f32>) -> f32 {
    if key(ta) <= key(tb) {
        return (qb.x - qa.x) * (p.y - qa.y) - (qb.y - qa.y) * (p.x - qa.x);
    }
    return -((qa.x - qb.x) * (p.y - qb.y) - (qa.y - qb.y) * (p.x - qb.x));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = params.size;
    if gid.x >= n || gid.y >= n {
        return;
    }
    let s = f32(n);
    let p = vec2<f32>(f32(gid.x) + 0.5, f32(gid.y) + 0.5);
    let texel = gid.y * n + gid.x;
    let z_j = depth_j[texel];
    var best_value = 0.5;
    var best_depth = -1.0;
    var best = 0xffffffffu;
    for (var cy = 0; cy < i32(n) - 1; cy++) {
        for (var cx = 0; cx < i32(n) - 1; cx++) {
            for (var half = 0; half < 2; half++) {
                var t: array<vec2<i32>, 3>;
                t[0] = vec2<i32>(cx, cy);
                if half == 0 {
                    t[1] = vec2<i32>(cx + 1, cy);
                    t[2] = vec2<i32>(cx + 1, cy + 1);
                } else {
                    t[1] = vec2<i32>(cx + 1, cy + 1);
                    t[2] = vec2<i32>(cx, cy + 1);
                }
                var d: array<f32, 3>;
                for (var k = 0; k < 3; k++) {
                    d[k] = z_at(t[k].x, t[k].y);
                }
                let lo = min(d[0], min(d[1], d[2]));
                let hi = max(d[0], max(d[1], d[2]));
                if !(hi - lo > params.tau) {
                    continue;
                }
                if !(abs(log_at(t[0])) > params.tau || abs(log_at(t[1])) > params.tau || abs(log_at(t[2])) > params.tau) {
                    continue;
                }
                let mid = 0.5 * (lo + hi);
                var v: array<f32, 3>;
                var q: array<vec2<f32>, 3>;
                var w: array<f32, 3>;
                var dj: array<f32, 3>;
                var behind = false;
                for (var k = 0; k < 3; k++) {
                    v[k] = select(1.0, 0.0, d[k] < mid);
                    let world = corner_world(t[k], params.near_i + d[k] * (params.far_i - params.near_i));
                    let c = params.vp_j * vec4<f32>(world, 1.0);
                    if !(c.w > 0.0) {
                        behind = true;
                    }
                    q[k] = vec2<f32>((c.x / c.w * 0.5 + 0.5) * s, (c.y / c.w * -0.5 + 0.5) * s);
                    w[k] = c.w;
                    let dist = -dot(row_of(params.view_j, 2u), vec4<f32>(world, 1.0));
                    dj[k] = (dist - params.near_j) / (params.far_j - params.near_j);
                }
                if behind {
                    continue;
                }
                // l_2 from edge 0-1, l_0 from edge 1-2, l_1 from edge 2-0
                let e = vec3<f32>(
                    edge_fn(t[1], t[2], q[1], q[2], p),
                    edge_fn(t[2], t[0], q[2], q[0], p),
                    edge_fn(t[0], t[1], q[0], q[1], p),
                );
                let inside = all(e >= vec3<f32>(0.0)) || all(e <= vec3<f32>(0.0));
                let area = e.x + e.y + e.z;
                if !inside || area == 0.0 {
                    continue;
                }
                let l = e / area;
                let r = vec3<f32>(l.x / w[0], l.y / w[1], l.z / w[2]);
                let sum = r.x + r.y + r.z;
                if !(sum > 0.0) {
                    continue;
                }
                let b = r / sum;
                let depth = b.x * dj[0] + b.y * dj[1] + b.z * dj[2];
                var value = b.x * v[0] + b.y * v[1] + b.z * v[2];
                if params.screen == 1u {
                    value = l.x * v[0] + l.y * v[1] + l.z * v[2];
                }
                if !(depth >= 0.0 && depth <= 1.0) || !(depth <= z_j + params.keep_bias) {
                    continue;
                }
                if best == 0xffffffffu || depth < best_depth {
                    best_depth = depth;
                    best_value = clamp(value, 0.0, 1.0);
                    best = u32(2 * (cy * (i32(n) - 1) + cx) + half);
                }
            }
        }
    }
    channel[texel] = vec4<f32>(best_value, best_depth, 0.0, 0.0);
    winner[texel] = best;
}
