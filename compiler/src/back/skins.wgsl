// Library code of `primitive: Skins` (soft shadow maps for linear lights, Heidrich, Brabec &
// Seidel 2000, section 3.2).
//
// Run once per light-sample view k of a per-sample Geometry pass (`frame` is view k's; the
// `light_samples` uniform holds every sample's view). The source view i is the neighbour
// SKIN_FROM away (k - 1 or k + 1; wrapped where the samples close a loop, `frame.sample.z`;
// none past the ends of an open chain).
//
// `cs_skins` runs once per cell of the mesh joining view i's texel centres (cell (x, y) has
// corners c00 = (x, y), c10 = (x + 1, y), c01 = (x, y + 1), c11 = (x + 1, y + 1), and two
// triangles (c00, c10, c11) and (c00, c11, c01)). The paper triangulates the depth map and
// keeps the "phantom polygons" that span its depth discontinuities; the detector here, in
// place of its thresholded 3x3 Laplacian of Gaussian (section 4):
//   a triangle is a skin iff the spread of its corners' depths (max - min) exceeds tau and
//   some corner's |LoG| exceeds tau, LoG(t) = 4 z(t) - z(t - x) - z(t + x) - z(t - y) - z(t + y)
//   with neighbours clamped to the map; tau is `sk_threshold()` in normalised depth.
// Planes have LoG 0 whatever their slope, so a steep receiver is never mistaken for a skin.
// A skin's corners are unprojected from view i (the point at view distance near + z (far -
// near) on the ray through the texel centre; depth 1, no surface, is a point on the far
// plane) and take the Gouraud value 0 on the occluder side (depth below the middle of the
// triangle's range) and 1 on the receiver side. A skin that projects to (almost) no area in
// view k (the two samples coincide, or the discontinuity lies along the segment) is not
// appended: it could cover no texel centre, and its depth interpolation would be ill
// conditioned.
//
// `vs_skins` projects the skins into view k; the fragments interpolate the value linearly
// in view k's image (`skin`) and the view distance perspective-correctly (`z_frag`). The technique's `keep`
// discards fragments behind the surface sample k sees, and the depth test (`resolve:
// Nearest`) keeps the skin nearest to sample k.
//
// Constants and functions prepended by the compiler: SKIN_FROM (-1 or 1), `sk_depth(texel,
// view)` (the linear depth of view `view` at a texel, clamped to the map) and
// `sk_threshold()`; the generated buffer's structs and the group 3 bindings follow.

// One skin triangle: world position (xyz) and Gouraud value (w) of each corner.
struct Skin {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
}

struct SkinsVarying {
    @builtin(position) clip: vec4<f32>,
    // Gouraud shading in view k's image (screen-space, not perspective-correct): linear on
    // the receiver as it appears to sample k, which is the linear transition section 3.1
    // argues for (eq. 1 is linear in the receiver position for a receiver parallel to the
    // light); interpolating along the skin in 3D would bend it towards the occluder.
    @location(0) @interpolate(linear) skin: f32,
    @location(1) z_frag: f32,
}

// |LoG| of view `view` at texel t.
fn sk_log(t: vec2<i32>, view: i32) -> f32 {
    let z = sk_depth(t, view);
    let n = sk_depth(t - vec2<i32>(1, 0), view) + sk_depth(t + vec2<i32>(1, 0), view)
        + sk_depth(t - vec2<i32>(0, 1), view) + sk_depth(t + vec2<i32>(0, 1), view);
    return abs(4.0 * z - n);
}

// The world position of texel t of sample view `view` at linear depth z.
fn sk_world(t: vec2<i32>, z: f32, view: i32) -> vec3<f32> {
    let v = light_samples.views[view];
    let size = frame.shadow_size.x;
    let uv = (vec2<f32>(t) + 0.5) / size;
    let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let dist = v.depth_range.x + z * (v.depth_range.y - v.depth_range.x);
    // view-space direction with z = -1; the view's rotation R maps world to view, R^T back
    let tan_half = v.weights.w;
    let r = mat3x3<f32>(v.view[0].xyz, v.view[1].xyz, v.view[2].xyz);
    let dir = transpose(r) * vec3<f32>(ndc * tan_half, -1.0);
    return v.position.xyz + dir * dist;
}

// Twice the signed area, in view k's normalised device coordinates, of a triangle.
fn sk_area(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let pa = frame.light_view_proj * vec4<f32>(a, 1.0);
    let pb = frame.light_view_proj * vec4<f32>(b, 1.0);
    let pc = frame.light_view_proj * vec4<f32>(c, 1.0);
    if pa.w <= 0.0 || pb.w <= 0.0 || pc.w <= 0.0 {
        // behind the sample: let the rasteriser clip it
        return 1.0;
    }
    let qa = pa.xy / pa.w;
    let qb = pb.xy / pb.w;
    let qc = pc.xy / pc.w;
    let e1 = qb - qa;
    let e2 = qc - qa;
    return e1.x * e2.y - e1.y * e2.x;
}

// Append the triangle of corners (t0, t1, t2) with depths (z0, z1, z2) if it is a skin.
fn sk_triangle(t0: vec2<i32>, t1: vec2<i32>, t2: vec2<i32>, z: vec3<f32>, logs: vec3<f32>, view: i32) {
    let lo = min(z.x, min(z.y, z.z));
    let hi = max(z.x, max(z.y, z.z));
    let tau = sk_threshold();
    if hi - lo <= tau || max(logs.x, max(logs.y, logs.z)) <= tau {
        return;
    }
    let mid = 0.5 * (lo + hi);
    let a = sk_world(t0, z.x, view);
    let b = sk_world(t1, z.y, view);
    let c = sk_world(t2, z.z, view);
    // a texel of view k spans 2 / size in NDC: (almost) no area is far below a texel's
    let texel = 2.0 / frame.shadow_size.x;
    if abs(sk_area(a, b, c)) < 1e-6 * texel * texel {
        return;
    }
    let at = cs_claim();
    if at == NO_SLOT {
        return;
    }
    cs_out.records[at] = Skin(
        vec4<f32>(a, select(1.0, 0.0, z.x < mid)),
        vec4<f32>(b, select(1.0, 0.0, z.y < mid)),
        vec4<f32>(c, select(1.0, 0.0, z.z < mid)),
    );
    cs_commit(3u);
}

@compute @workgroup_size(64)
fn cs_skins(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = i32(frame.shadow_size.x);
    let x = i32(id.x);
    let y = i32(id.y);
    if x >= size - 1 || y >= size - 1 {
        return;
    }
    let n = i32(frame.sample.y);
    var view = i32(frame.sample.x) + SKIN_FROM;
    if frame.sample.z > 0.5 {
        view = (view + n) % n;
    }
    if view < 0 || view >= n {
        return;
    }
    let c00 = vec2<i32>(x, y);
    let c10 = vec2<i32>(x + 1, y);
    let c01 = vec2<i32>(x, y + 1);
    let c11 = vec2<i32>(x + 1, y + 1);
    let z00 = sk_depth(c00, view);
    let z10 = sk_depth(c10, view);
    let z01 = sk_depth(c01, view);
    let z11 = sk_depth(c11, view);
    // a cell whose depths spread no more than tau holds no skin: skip the 20 loads of its
    // corners' Laplacians (most cells of a map)
    let lo = min(min(z00, z10), min(z01, z11));
    let hi = max(max(z00, z10), max(z01, z11));
    if hi - lo <= sk_threshold() {
        return;
    }
    let l00 = sk_log(c00, view);
    let l10 = sk_log(c10, view);
    let l01 = sk_log(c01, view);
    let l11 = sk_log(c11, view);
    sk_triangle(c00, c10, c11, vec3<f32>(z00, z10, z11), vec3<f32>(l00, l10, l11), view);
    sk_triangle(c00, c11, c01, vec3<f32>(z00, z11, z01), vec3<f32>(l00, l11, l01), view);
}

@vertex
fn vs_skins(@builtin(vertex_index) vi: u32) -> SkinsVarying {
    var out: SkinsVarying;
    let index = vi / 3u;
    if index >= arrayLength(&cs_records.records) {
        // past the buffer's capacity (the count went on): no triangle
        out.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        out.skin = 0.0;
        out.z_frag = 0.0;
        return out;
    }
    let r = cs_records.records[index];
    var corners = array<vec4<f32>, 3>(r.a, r.b, r.c);
    let p = corners[vi % 3u];
    out.clip = frame.light_view_proj * vec4<f32>(p.xyz, 1.0);
    out.skin = p.w;
    out.z_frag = -(frame.light_view * vec4<f32>(p.xyz, 1.0)).z;
    return out;
}
