// Library code of `primitive: ConesAndSheets` (penumbra maps, Wyman & Hansen 2003, section 3).
//
// From the light's centre, every silhouette edge gets a cone at each end point (tip at the
// vertex v, base on the far plane, radius C_r = (Z_far - Z_v) L_r / Z_v for a light of radius
// L_r; the paper's figure 4) and a sheet joining the two cones along their outer side (the
// outer penumbra). Cones and far plane are built by similar triangles on the view axis, as in
// the paper's figure 4; the silhouettes and the helpers are `silhouettes.wgsl`'s.
//
// Compute entry `cs_cones_and_sheets`: one invocation per edge (see `Draw::Silhouettes`),
// classifies it (the silhouette rule of the runtime's adjacency module) and appends one
// record per silhouette edge. Vertex entry `vs_cones_and_sheets`: pulls the record of its
// vertex and emits the vertex's place on cone a, cone b or the sheet. The technique's
// fragment entry (generated) reads `ConesAndSheetsVarying`.
//
// Constants prepended by the compiler: CONE_SEGMENTS, SHEET_STRIPS, VERTICES_PER_RECORD; the generated
// buffer's structs (`GeneratedRw`, `Generated`) and the group 3 bindings follow (geometry.rs).

// One silhouette edge in light view space (the light looks down -z): the end points (xyz)
// with their cone radius on the far plane (w); `outward` the unit direction, in the far
// plane, from the edge's shadow towards its penumbra (xy), z = 1 when the sheet is drawn
// (0 for an edge seen end-on, whose cones cover its penumbra), w the cones this edge draws
// (bit 0: at a, bit 1: at b): the paper draws one cone per silhouette vertex, so of the
// silhouette edges meeting at a vertex exactly one (the first to claim it) draws its cone.
struct ConeSheet {
    a: vec4<f32>,
    b: vec4<f32>,
    outward: vec4<f32>,
}

struct ConesAndSheetsVarying {
    @builtin(position) clip: vec4<f32>,
    // Z_F: the fragment's light-view distance (interpolated along the cone or sheet)
    @location(0) z_frag: f32,
    // Z_v: the silhouette vertex's (constant on a cone, interpolated along a sheet)
    @location(1) z_vertex: f32,
    // the cone's radius at the fragment's distance: (Z_F - Z_v) L_r / Z_v
    @location(2) cone_radius: f32,
}

@compute @workgroup_size(64)
fn cs_cones_and_sheets(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * 64u * groups.x;
    if i >= arrayLength(&cs_edges) {
        return;
    }
    let s = cs_silhouette(i);
    if !s.found {
        return;
    }
    let e = cs_edges[i];
    let far = frame.depth_range.y;
    let ra = cs_radius(-s.a.z, far);
    let rb = cs_radius(-s.b.z, far);
    var cones = 0u;
    if atomicAdd(&cs_claims[e.ia], 1u) == 0u {
        cones |= 1u;
    }
    if atomicAdd(&cs_claims[e.ib], 1u) == 0u {
        cones |= 2u;
    }
    let at = cs_claim();
    if at == NO_SLOT {
        return;
    }
    cs_out.records[at] = ConeSheet(vec4<f32>(s.a, ra), vec4<f32>(s.b, rb), vec4<f32>(s.outward, select(0.0, 1.0, s.seen), f32(cones)));
    cs_commit(VERTICES_PER_RECORD);
}

// One vertex of a primitive, in view space, with its vertex distance.
fn cs_emit(p: vec3<f32>, zv: f32) -> ConesAndSheetsVarying {
    var out: ConesAndSheetsVarying;
    let clip = frame.light_view_proj * vec4<f32>(cs_to_world(p), 1.0);
    // No depth test (blending resolves overlaps) and no near or far clipping: every
    // primitive lies in front of the light and ends on the far plane.
    out.clip = vec4<f32>(clip.xy, 0.5 * clip.w, clip.w);
    out.z_frag = -p.z;
    out.z_vertex = zv;
    out.cone_radius = cs_radius(zv, -p.z);
    return out;
}

@vertex
fn vs_cones_and_sheets(@builtin(vertex_index) vi: u32) -> ConesAndSheetsVarying {
    let r = cs_records.records[vi / VERTICES_PER_RECORD];
    let local = vi % VERTICES_PER_RECORD;
    let far = frame.depth_range.y;
    let cone = 3u * CONE_SEGMENTS;
    if local < 2u * cone {
        // A cone: CONE_SEGMENTS triangles (tip, base k, base k + 1). The base polygon is
        // circumscribed about the circle of radius C_r, so it covers the whole cone.
        let end = select(r.a, r.b, local >= cone);
        let k = (local % cone) / 3u;
        let corner = local % 3u;
        let zv = -end.z;
        // a cone another edge draws: every corner at the tip, nothing rasterised
        let mine = (u32(r.outward.w) & select(1u, 2u, local >= cone)) != 0u;
        if corner == 0u || !mine {
            return cs_emit(end.xyz, zv);
        }
        let step = 6.283185307179586 / f32(CONE_SEGMENTS);
        let angle = f32(k + corner - 1u) * step;
        let radius = end.w / cos(0.5 * step);
        let centre = cs_along_ray(end.xyz, far);
        return cs_emit(centre + vec3<f32>(radius * cos(angle), radius * sin(angle), 0.0), zv);
    }
    // The sheet: SHEET_STRIPS quads along the edge, each from the tips' line to the outer
    // tangent line of the cones' bases (a non-planar quad, subdivided as the paper does).
    let s = local - 2u * cone;
    let strip = s / 6u;
    // Two triangles per strip: (t0 tip, t0 base, t1 base), (t0 tip, t1 base, t1 tip).
    var corners = array<vec2<u32>, 6>(
        vec2<u32>(0u, 0u), vec2<u32>(0u, 1u), vec2<u32>(1u, 1u),
        vec2<u32>(0u, 0u), vec2<u32>(1u, 1u), vec2<u32>(1u, 0u),
    );
    let c = corners[s % 6u];
    let t = f32(strip + c.x) / f32(SHEET_STRIPS);
    let tip = mix(r.a.xyz, r.b.xyz, t);
    let zv = -tip.z;
    if c.y == 0u || r.outward.z == 0.0 {
        // the tip line; an edge seen end-on draws nothing (all corners on the tip line)
        return cs_emit(tip, zv);
    }
    let base_a = cs_along_ray(r.a.xyz, far) + vec3<f32>(r.outward.xy * r.a.w, 0.0);
    let base_b = cs_along_ray(r.b.xyz, far) + vec3<f32>(r.outward.xy * r.b.w, 0.0);
    return cs_emit(mix(base_a, base_b, t), zv);
}
