// Library code of `primitive: Ribbons` (penumbra limit maps, Lawlor 2006, section 3.1, step 2;
// smoothies as that section describes them).
//
// Every silhouette edge seen from the light's centre (`silhouettes.wgsl`) is extruded, in the
// far plane, into a ribbon: a rectangle along the edge, reaching h on each side of it and h
// past each end, h twice the penumbra's widest reach (at the far plane: `cs_radius` of the
// edge's nearer end point; twice, the penumbra's whole width, which smoothies place outside
// the edge, and where p_i reaches 2, the end of Lawlor's stored range p_i / 4 + 1/2) plus
// RIBBON_MARGIN texels, Lawlor's widening "over a few extra pixels" so that bilinear
// interpolation near a ribbon's border reads its values.
//
// Per fragment (`rb_inputs`), at along-edge coordinate t and signed across-edge distance s
// (positive outward, away from the edge's faces), both in far-plane units:
// - c (`occluder_depth`): the normalised depth of the edge point nearest the fragment (t
//   clamped to the edge; Z linear along the edge for a distant light, 1 / Z for a local one);
// - w: s beside the edge, the distance to the nearer end point past it (outside);
// - p_i (`penumbra_limit`) = w s r of section 3 in normalised depth units: for a distant disk,
//   r = 1 / tan(angle / 2) and eq. 1 reads l = 1/2 + 1/2 p_i / (z - c); for a local light of
//   radius L_r the depth is made projective (section 5: a perspective transform puts the
//   light at infinity), p_i = (w / Z_far) / (L_r (1 / near - 1 / far)), and eq. 1 holds with
//   z - c measured in (1 / near - 1 / Z) / (1 / near - 1 / far);
// - the penumbra-limit surface's normalised depth: k = c + |p_i| for a distant light; for a
//   local one k = (1/near - 1/C) / (1/near - 1/far) + |p_i| is projective, mapped back to
//   linear depth for `limit_depth` (clamped to [0, 1]). The fragment writes k / (1 + k) as
//   its depth (an order-preserving map into [0, 1), so that limits past the far plane
//   still win over the cleared depth): the depth test keeps the highest penumbra limit
//   ("highest penumbra limit wins").
// A light without size (angle 0, radius 0) has no penumbra: no ribbons are drawn.
//
// Constants prepended by the compiler: RIBBON_MARGIN, VERTICES_PER_RECORD; the generated
// buffer's structs (`GeneratedRw`, `Generated`) and the group 3 bindings follow (geometry.rs).

// One ribbon: the end points' far-plane positions (xy) and view distances (z), the unit
// outward direction (xy) and the half-width h (z), in far-plane units.
struct Ribbon {
    a: vec4<f32>,
    b: vec4<f32>,
    outward: vec4<f32>,
}

struct RibbonsVarying {
    @builtin(position) clip: vec4<f32>,
    // t along the edge from a, s across it (positive outward), far-plane units
    @location(0) along: f32,
    @location(1) across: f32,
    @location(2) @interpolate(flat) record: u32,
}

// The size of one shadow-map texel in far-plane units (`texel_world`: x per unit of view
// distance, y constant).
fn rb_texel() -> f32 {
    return frame.texel_world.x * frame.depth_range.y + frame.texel_world.y;
}

@compute @workgroup_size(64)
fn cs_ribbons(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * 64u * groups.x;
    if i >= arrayLength(&cs_edges) {
        return;
    }
    // A point light (or a distant one without size) casts no penumbra.
    if select(frame.light_size.x, frame.light_size.y, cs_distant()) <= 0.0 {
        return;
    }
    let s = cs_silhouette(i);
    if !s.found || !s.seen {
        return;
    }
    let far = frame.depth_range.y;
    let reach = cs_radius(min(-s.a.z, -s.b.z), far);
    let h = 2.0 * reach + f32(RIBBON_MARGIN) * rb_texel();
    let pa = cs_along_ray(s.a, far).xy;
    let pb = cs_along_ray(s.b, far).xy;
    let at = cs_claim();
    if at == NO_SLOT {
        return;
    }
    cs_out.records[at] = Ribbon(vec4<f32>(pa, -s.a.z, 0.0), vec4<f32>(pb, -s.b.z, 0.0), vec4<f32>(s.outward, h, 0.0));
    cs_commit(VERTICES_PER_RECORD);
}

@vertex
fn vs_ribbons(@builtin(vertex_index) vi: u32) -> RibbonsVarying {
    let index = vi / VERTICES_PER_RECORD;
    let r = cs_records.records[index];
    // Two triangles: (0, 0), (1, 0), (1, 1) and (0, 0), (1, 1), (0, 1) over (along, across).
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let k = corners[vi % VERTICES_PER_RECORD];
    let edge = r.b.xy - r.a.xy;
    let len = length(edge);
    let dir = edge / max(len, 1e-30);
    let h = r.outward.z;
    let t = mix(-h, len + h, k.x);
    let s = mix(-h, h, k.y);
    let p = r.a.xy + dir * t + r.outward.xy * s;
    let far = frame.depth_range.y;
    let clip = frame.light_view_proj * vec4<f32>(cs_to_world(vec3<f32>(p, -far)), 1.0);
    var out: RibbonsVarying;
    // No clipping against near or far: the depth is the fragment's (`rb_inputs`).
    out.clip = vec4<f32>(clip.xy, 0.5 * clip.w, clip.w);
    out.along = t;
    out.across = s;
    out.record = index;
    return out;
}

// c, p_i and the penumbra-limit depth of a ribbon fragment (see the top of this file).
struct RibbonInputs {
    c: f32,
    p: f32,
    limit: f32,
    // the fragment's depth
    depth: f32,
}

fn rb_inputs(in: RibbonsVarying) -> RibbonInputs {
    let r = cs_records.records[in.record];
    let len = length(r.b.xy - r.a.xy);
    let t = in.along;
    let tc = clamp(t, 0.0, len);
    var w = in.across;
    if t != tc {
        // past an end: outside, at the distance to the end point
        w = length(vec2<f32>(t - tc, in.across));
    }
    let f = tc / max(len, 1e-30);
    let near = frame.depth_range.x;
    let far = frame.depth_range.y;
    var out: RibbonInputs;
    // the order key of the penumbra limit (>= 0): its normalised depth, linear for a
    // distant light, projective for a local one (both grow with the limit's distance)
    var key: f32;
    if cs_distant() {
        let z = mix(r.a.z, r.b.z, f);
        out.c = (z - near) * frame.depth_range.z;
        out.p = w / max(tan(0.5 * frame.light_size.y) * (far - near), 1e-30);
        key = out.c + abs(out.p);
        out.limit = key;
    } else {
        let z = 1.0 / mix(1.0 / r.a.z, 1.0 / r.b.z, f);
        out.c = (z - near) * frame.depth_range.z;
        let k = 1.0 / near - 1.0 / far;
        out.p = (w / far) / max(frame.light_size.x * k, 1e-30);
        key = (1.0 / near - 1.0 / z) / k + abs(out.p);
        // at or past the far plane (key >= 1) the limit is the far plane
        let zl = 1.0 / max(1.0 / near - min(key, 1.0) * k, 1e-30);
        out.limit = (zl - near) * frame.depth_range.z;
    }
    key = max(key, 0.0);
    out.depth = key / (1.0 + key);
    out.limit = clamp(out.limit, 0.0, 1.0);
    return out;
}
