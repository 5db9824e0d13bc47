// Penumbra map (Wyman & Hansen 2003, section 3, equation 1) as a hand-written compute
// shader: one invocation per shadow-map texel intersects the texel's light ray analytically
// with every cone and sheet (not rasterised), applies the discard Z_F > Z_P, equation 1, the
// Bernstein interpolant s = 3 I^2 - 2 I^3 and the resolve rule, and writes the texel's value
// (f32, or rounded to f16 as an r16float target would store it) and its fragment count.
//
// Everything is in the light's view space, depths are Z = -z. Texel (i, j), row 0 at the
// top, has its centre at NDC x = 2 (i + 0.5) / N - 1, y = 1 - 2 (j + 0.5) / N; its ray
// starts at o with o.z = 0 and has direction d with d.z = -1, so the ray parameter is the
// depth: perspective o = 0, d = (x / f, y / f, -1); orthographic o = (x h, y h, 0),
// d = (0, 0, -1).

struct Params {
    size: u32,
    // 0 perspective, 1 orthographic
    orthographic: u32,
    // 0 KeepMin, 1 KeepMax, 2 Add, 3 Multiply
    resolve: u32,
    // 1: round the stored value to f16
    half: u32,
    cones: u32,
    sheets: u32,
    // f = 1 / tan(fov / 2) (perspective) or the half height h (orthographic)
    scale: f32,
    near: f32,
    far: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

// A cone (figure 4, left): tip v (view space) at depth Z_v; cross-sections at constant depth
// are circles centred on the light ray through v, of radius (Z - Z_v) k.
struct Cone {
    // xyz: tip, w: Z_v
    tip: vec4<f32>,
    // x: k, the radius growth per unit of depth (L_r / Z_v, or tan(angle / 2))
    spread: vec4<f32>,
}

// A sheet (figure 4, right): the bilinear patch (1 - s) e(t) + s T(t) with
// e(t) = (1 - t) v0 + t v1 (the silhouette edge) and T(t) = (1 - t) t0 + t t1 (the outer
// common tangent points of the cones' base circles on the far plane).
struct Sheet {
    // xyz: v0, w: Z_v0
    v0: vec4<f32>,
    // xyz: v1, w: Z_v1
    v1: vec4<f32>,
    // xyz: t0, w: the spread k of the cone at v0
    t0: vec4<f32>,
    // xyz: t1, w: the spread k of the cone at v1
    t1: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
// Z_P per texel (view depth, world units), row-major
@group(0) @binding(1) var<storage, read> depth: array<f32>;
@group(0) @binding(2) var<storage, read> cones: array<Cone>;
@group(0) @binding(3) var<storage, read> sheets: array<Sheet>;
// the penumbra map value per texel
@group(0) @binding(4) var<storage, read_write> value: array<f32>;
// the number of kept fragments per texel
@group(0) @binding(5) var<storage, read_write> count: array<u32>;

// The resolve state of one texel.
struct Acc {
    v: f32,
    n: u32,
}

fn start() -> Acc {
    switch params.resolve {
        case 0u: { return Acc(1.0, 0u); }       // KeepMin: the white clear
        case 1u: { return Acc(0.0, 0u); }       // KeepMax: max over the fragments only
        case 2u: { return Acc(0.0, 0u); }       // Add: sum of (1 - s)
        default: { return Acc(1.0, 0u); }       // Multiply: product of s
    }
}

// A fragment at depth z_f of a primitive whose silhouette depth is z_v, with
// n = Z_F - Z_v computed by the caller from the intersection (better conditioned than the
// difference of the two depths). Pseudocode lines 4-8: discard, equation 1, Bernstein.
fn fragment(acc: ptr<function, Acc>, z_f: f32, n: f32, z_v: f32, z_p: f32) {
    if (!(z_f >= params.near && z_f <= params.far && z_f <= z_p)) {
        return;
    }
    let den = z_p - z_v;
    var i = 0.0;
    if (den > 0.0) {
        i = clamp(max(n, 0.0) / den, 0.0, 1.0);
    }
    let s = i * i * (3.0 - 2.0 * i);
    switch params.resolve {
        case 0u: { (*acc).v = min((*acc).v, s); }
        case 1u: { (*acc).v = max((*acc).v, s); }
        case 2u: { (*acc).v = (*acc).v + (1.0 - s); }
        default: { (*acc).v = (*acc).v * s; }
    }
    (*acc).n = (*acc).n + 1u;
}

fn finish(acc: Acc) -> f32 {
    if (acc.n == 0u) {
        return 1.0;
    }
    var v = acc.v;
    if (params.resolve == 2u) {
        v = 1.0 - acc.v;
    }
    return clamp(v, 0.0, 1.0);
}

// The ray meets the cone's lateral surface once, where its lateral distance from the axis
// equals the cross-section's radius.
//  perspective: at depth z the ray is at z d.xy, the axis at z v.xy / Z_v, so the distance
//    is z g with g = |d.xy - v.xy / Z_v|; z g = (z - Z_v) k gives z = Z_v k / (k - g), and
//    Z_F - Z_v = Z_v g / (k - g) (needs g < k).
//  orthographic: the distance is a = |o.xy - v.xy| at every depth; Z_F - Z_v = a / k.
fn cone(acc: ptr<function, Acc>, c: Cone, o: vec3<f32>, d: vec3<f32>, z_p: f32) {
    let v = c.tip.xyz;
    let z_v = c.tip.w;
    let k = c.spread.x;
    if (!(k > 0.0)) {
        return; // zero width: no area, no fragment
    }
    var n: f32;
    if (params.orthographic == 0u) {
        let g = length(d.xy - v.xy / z_v);
        if (!(g < k)) {
            return;
        }
        n = z_v * g / (k - g);
    } else {
        n = length(o.xy - v.xy) / k;
    }
    let z_f = z_v + n;
    if (!(z_f <= params.far)) {
        return; // past the base on the far plane
    }
    fragment(acc, z_f, n, z_v, z_p);
}

// The ray meets the ruling (e(t), T(t)) when the ruling and the ray are coplanar:
// det(e(t) - o, T(t) - o, d) = 0, a quadratic in t. On that ruling the point on the ray is
// found from the lateral offsets of its two ends from the ray at their own depths (for a
// point p with depth Z = -p.z, p.xy - (o.xy + Z d.xy)): (1 - s) off(e) + s off(T) = 0.
// Depth along a ruling is linear in s, so Z_F - Z_v(t) = s (Z_T - Z_v(t)).
fn sheet_at(acc: ptr<function, Acc>, sh: Sheet, t: f32, o: vec3<f32>, d: vec3<f32>, z_p: f32) {
    if (!(t >= 0.0 && t <= 1.0)) {
        return;
    }
    let e = mix(sh.v0.xyz, sh.v1.xyz, t);
    let tt = mix(sh.t0.xyz, sh.t1.xyz, t);
    let z_v = mix(sh.v0.w, sh.v1.w, t);
    let z_t = -tt.z;
    let oe = e.xy - (o.xy + z_v * d.xy);
    let ot = tt.xy - (o.xy + z_t * d.xy);
    let w = oe - ot;
    let ww = dot(w, w);
    if (!(ww > 0.0)) {
        return;
    }
    let s = dot(oe, w) / ww;
    if (!(s >= 0.0 && s <= 1.0)) {
        return;
    }
    let n = s * (z_t - z_v);
    fragment(acc, z_v + n, n, z_v, z_p);
}

fn sheet(acc: ptr<function, Acc>, sh: Sheet, o: vec3<f32>, d: vec3<f32>, z_p: f32) {
    if (!(sh.t0.w > 0.0 && sh.t1.w > 0.0)) {
        return; // zero width
    }
    // e(t) - o = a0 + t a1, T(t) - o = b0 + t b1
    let a0 = sh.v0.xyz - o;
    let a1 = sh.v1.xyz - sh.v0.xyz;
    let b0 = sh.t0.xyz - o;
    let b1 = sh.t1.xyz - sh.t0.xyz;
    // det(a0 + t a1, b0 + t b1, d) = q2 t^2 + q1 t + q0
    let q0 = dot(cross(a0, b0), d);
    let q1 = dot(cross(a0, b1) + cross(a1, b0), d);
    let q2 = dot(cross(a1, b1), d);
    let disc = q1 * q1 - 4.0 * q2 * q0;
    if (disc < 0.0) {
        return;
    }
    // the numerically stable pair of roots: q / q2 and q0 / q
    var sgn = 1.0;
    if (q1 < 0.0) {
        sgn = -1.0;
    }
    let q = -0.5 * (q1 + sgn * sqrt(disc));
    if (q == 0.0) {
        // q1 = 0 and q2 q0 = 0: the root 0 when q2 != 0 (q0 = 0); with q2 = 0 too the ray
        // lies in the sheet (seen edge-on): no fragment
        if (q2 != 0.0) {
            sheet_at(acc, sh, 0.0, o, d, z_p);
        }
        return;
    }
    let r1 = q0 / q;
    sheet_at(acc, sh, r1, o, d, z_p);
    if (q2 != 0.0) {
        let r2 = q / q2;
        if (r2 != r1) {
            sheet_at(acc, sh, r2, o, d, z_p);
        }
    }
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = params.size;
    if (id.x >= size || id.y >= size) {
        return;
    }
    let k = id.y * size + id.x;
    let nf = f32(size);
    let x = 2.0 * (f32(id.x) + 0.5) / nf - 1.0;
    let y = 1.0 - 2.0 * (f32(id.y) + 0.5) / nf;
    var o = vec3<f32>(0.0);
    var d = vec3<f32>(0.0, 0.0, -1.0);
    if (params.orthographic == 0u) {
        d = vec3<f32>(x / params.scale, y / params.scale, -1.0);
    } else {
        o = vec3<f32>(x * params.scale, y * params.scale, 0.0);
    }
    let z_p = depth[k];
    var acc = start();
    for (var c = 0u; c < params.cones; c++) {
        cone(&acc, cones[c], o, d, z_p);
    }
    for (var c = 0u; c < params.sheets; c++) {
        sheet(&acc, sheets[c], o, d, z_p);
    }
    var v = finish(acc);
    if (params.half != 0u) {
        v = quantizeToF16(v);
    }
    value[k] = v;
    count[k] = acc.n;
}
