// Penumbra limit maps (Lawlor 2006, section 3.1, steps 2 and 3; section 2.2's channels) as a
// hand-written compute shader: one invocation per map texel loops over the silhouette edges'
// ribbons at the texel's centre (evaluated exactly, not rasterised), keeps the one with the
// smallest depth-test key ("highest penumbra limit wins"), writes its occluder depth c and
// penumbra limit p_i, raises the nearest-surface depth to g = min(depth, key), then casts the
// texel's ray at the back-facing triangles for b (the nearest deeper than c + bias_b, and
// inside the silhouette, p_i < 0, than the inner penumbra limit c + |p_i|).
//
// View space: the light looks down -z, Z = -z. Image-plane coordinates: a distant disk
// (orthographic) uses the view x, y (world units); a local light (perspective) uses
// (x / Z, y / Z) (tangent units). Texel (i, j), row 0 at the top, has its centre at
// NDC x = 2 (i + 0.5) / N - 1, y = 1 - 2 (j + 0.5) / N: image point (x h, y h) (orthographic,
// half height h) or (x / f, y / f) (perspective, f = 1 / tan(fov / 2)). Depths written are
// linear normalised, (Z - near) / (far - near).

struct Params {
    size: u32,
    // 1 perspective (local light), 0 orthographic (distant disk)
    perspective: u32,
    ribbons: u32,
    triangles: u32,
    // f (perspective) or the half height h (orthographic)
    scale: f32,
    near: f32,
    far: f32,
    // tan(angle / 2) (distant disk) or the light radius L_r (local)
    spread: f32,
    bias_b: f32,
    // 1 penumbra limit maps, 2 smoothies: the ribbon's reach in units of the light's
    reach_scale: f32,
    _pad0: f32,
    _pad1: f32,
}

// A silhouette edge: view-space end points A (a.xyz) and B (b.xyz); a.w = +1 when the outward
// side is that of perp(along) = (-along.y, along.x), -1 for the other side.
struct Edge {
    a: vec4<f32>,
    b: vec4<f32>,
}

// A triangle in view space (w unused).
struct Tri {
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
// the unraised nearest-surface depth per texel (linear normalised), row-major
@group(0) @binding(1) var<storage, read> depth: array<f32>;
@group(0) @binding(2) var<storage, read> edges: array<Edge>;
@group(0) @binding(3) var<storage, read> tris: array<Tri>;
// per texel: (g, c, b, p_i)
@group(0) @binding(4) var<storage, read_write> maps: array<vec4<f32>>;
// per texel: the winning edge's index, 0xffffffff for none
@group(0) @binding(5) var<storage, read_write> winner: array<u32>;

fn linear(z: f32) -> f32 {
    return (z - params.near) / (params.far - params.near);
}

// The image-plane point of a view-space point, in .xy, and its Z in .z; .w = 0 when a local
// light cannot project it (Z <= 0).
fn project(p: vec3<f32>) -> vec4<f32> {
    let z = -p.z;
    if (params.perspective == 0u) {
        return vec4<f32>(p.xy, z, 1.0);
    }
    if (!(z > 0.0)) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(p.xy / z, z, 1.0);
}

// p_i = w / S, S = tan(angle / 2) (far - near) or L_r (1 / near - 1 / far); a light of size 0
// gives 2 sign(w).
fn penumbra_limit(w: f32) -> f32 {
    var s: f32;
    if (params.perspective == 0u) {
        s = params.spread * (params.far - params.near);
    } else {
        s = params.spread * (1.0 / params.near - 1.0 / params.far);
    }
    if (s > 0.0) {
        return w / s;
    }
    return 2.0 * sign(w);
}

// The penumbra-limit surface's linear normalised depth, clamped to [0, 1]: c + |p_i|
// (distant), or for a local light in hyperbolic depth H = (1/near - 1/C) / (1/near - 1/far)
// + |p_i|, taken back to Z = 1 / (1/near - H (1/near - 1/far)).
fn key_of(c: f32, p_i: f32) -> f32 {
    if (params.perspective == 0u) {
        return clamp(c + abs(p_i), 0.0, 1.0);
    }
    let k = 1.0 / params.near - 1.0 / params.far;
    let cz = params.near + c * (params.far - params.near);
    let h = clamp((1.0 / params.near - 1.0 / cz) / k + abs(p_i), 0.0, 1.0);
    if (h >= 1.0) {
        return 1.0; // far, exactly
    }
    return clamp(linear(1.0 / (1.0 / params.near - h * k)), 0.0, 1.0);
}

// Moller-Trumbore, both sides, edges included: the ray parameter (= the depth Z, since
// d.z = -1 and o.z = 0), or -1 for a miss.
fn hit(o: vec3<f32>, d: vec3<f32>, t: Tri) -> f32 {
    let e1 = t.p1.xyz - t.p0.xyz;
    let e2 = t.p2.xyz - t.p0.xyz;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if (det == 0.0) {
        return -1.0;
    }
    let inv = 1.0 / det;
    let s = o - t.p0.xyz;
    let u = dot(s, p) * inv;
    if (!(u >= 0.0 && u <= 1.0)) {
        return -1.0;
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if (!(v >= 0.0 && u + v <= 1.0)) {
        return -1.0;
    }
    return dot(e2, q) * inv;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.size;
    if (id.x >= n || id.y >= n) {
        return;
    }
    let k = id.y * n + id.x;
    let nf = f32(n);
    let x = 2.0 * (f32(id.x) + 0.5) / nf - 1.0;
    let y = 1.0 - 2.0 * (f32(id.y) + 0.5) / nf;
    var q: vec2<f32>;
    var texel: f32;
    if (params.perspective == 0u) {
        q = vec2<f32>(x, y) * params.scale;
        texel = 2.0 * params.scale / nf;
    } else {
        q = vec2<f32>(x, y) / params.scale;
        texel = 2.0 / (params.scale * nf);
    }

    // step 2: ribbons, the smallest key wins (the first on ties)
    var best_key = 1.0;
    var best_c = 1.0;
    var best_p = 0.0;
    var best = 0xffffffffu;
    for (var r = 0u; r < params.ribbons; r++) {
        let e = edges[r];
        let pa = project(e.a.xyz);
        let pb = project(e.b.xyz);
        if (pa.w == 0.0 || pb.w == 0.0) {
            continue;
        }
        let ab = pb.xy - pa.xy;
        let len = length(ab);
        if (!(len > 0.0)) {
            continue; // seen end-on
        }
        let along = ab / len;
        let outward = e.a.w * vec2<f32>(-along.y, along.x);
        let zmin = min(pa.z, pb.z);
        var reach: f32;
        if (params.perspective == 0u) {
            reach = (params.far - zmin) * params.spread;
        } else {
            reach = params.spread * (1.0 / zmin - 1.0 / params.far);
        }
        let h = params.reach_scale * reach + 2.0 * texel;
        let rel = q - pa.xy;
        let t = dot(rel, along);
        let s = dot(rel, outward);
        if (!(h > 0.0 && t >= -h && t <= len + h && abs(s) <= h)) {
            continue;
        }
        let f = clamp(t, 0.0, len) / len;
        var z: f32;
        if (params.perspective == 0u) {
            z = pa.z + (pb.z - pa.z) * f;
        } else {
            z = 1.0 / (1.0 / pa.z + (1.0 / pb.z - 1.0 / pa.z) * f);
        }
        let c = linear(z);
        var w = s;
        if (t < 0.0) {
            w = length(q - pa.xy);
        } else if (t > len) {
            w = length(q - pb.xy);
        }
        let p_i = penumbra_limit(w);
        let key = key_of(c, p_i);
        if (best == 0xffffffffu || key < best_key) {
            best_key = key;
            best_c = c;
            best_p = p_i;
            best = r;
        }
    }
    // step 2's raise of g to the outer penumbra limit
    let g = min(depth[k], best_key);

    // step 3: the nearest back face deeper than c + bias_b, and inside the silhouette
    // (p_i < 0) deeper than the inner penumbra limit, the key (issue 35: a face in the edge's
    // umbra blocks no light the edge lets through)
    var floor_b = best_c;
    if (best_p < 0.0) {
        floor_b = best_key;
    }
    var o = vec3<f32>(0.0);
    var d = vec3<f32>(0.0, 0.0, -1.0);
    if (params.perspective == 0u) {
        o = vec3<f32>(q, 0.0);
    } else {
        d = vec3<f32>(q, -1.0);
    }
    var b = 1.0;
    for (var i = 0u; i < params.triangles; i++) {
        let t = tris[i];
        let nrm = cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz);
        var back: bool;
        if (params.perspective == 0u) {
            back = nrm.z < 0.0;
        } else {
            back = dot(nrm, t.p0.xyz) > 0.0;
        }
        if (!back) {
            continue;
        }
        let zh = hit(o, d, t);
        if (!(zh >= params.near && zh <= params.far)) {
            continue;
        }
        let zl = linear(zh);
        if (zl > floor_b + params.bias_b && zl < b) {
            b = zl;
        }
    }
    maps[k] = vec4<f32>(g, best_c, b, best_p);
    winner[k] = best;
}
