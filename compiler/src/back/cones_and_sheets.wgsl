// Library code of `primitive: ConesAndSheets` (penumbra maps, Wyman & Hansen 2003, section 3).
//
// From the light's centre, every silhouette edge gets a cone at each end point (tip at the
// vertex v, base on the far plane, radius C_r = (Z_far - Z_v) L_r / Z_v for a light of radius
// L_r; the paper's figure 4) and a sheet joining the two cones along their outer side (the
// outer penumbra). Z values are light-view distances along the view axis (world units), the
// quantity the Depth pass normalises: cones and far plane are built by similar triangles on
// that axis, as in the paper's figure 4. A distant light (orthographic view, w = 0) has no
// position: its cones grow by tan(angle / 2) per unit of distance (Lawlor 2006's distant disk).
//
// Compute entry `cs_cones_and_sheets`: one invocation per edge (see `Draw::Silhouettes`),
// classifies it (the silhouette rule of the runtime's adjacency module) and appends one
// record per silhouette edge. Vertex entry `vs_cones_and_sheets`: pulls the record of its
// vertex and emits the vertex's place on cone a, cone b or the sheet. The technique's
// fragment entry (generated) reads `ConesAndSheetsVarying`.
//
// Constants prepended by the compiler: CONE_SEGMENTS, SHEET_STRIPS, VERTICES_PER_RECORD.

struct Edge {
    a: vec3<f32>,
    first_face: u32,
    b: vec3<f32>,
    face_count: u32,
    // the end points' indices among the scene's welded vertices
    ia: u32,
    ib: u32,
    pad: vec2<u32>,
}

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

struct GeneratedRw {
    vertex_count: atomic<u32>,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
    records: array<ConeSheet>,
}

struct Generated {
    vertex_count: u32,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
    records: array<ConeSheet>,
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

// Light view space -> world, for a rigid light view (rotation and translation: how the
// scene's light views are built).
fn cs_to_world(p: vec3<f32>) -> vec3<f32> {
    let m = frame.light_view;
    let r = mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz);
    return transpose(r) * (p - m[3].xyz);
}

fn cs_to_view(p: vec3<f32>) -> vec3<f32> {
    return (frame.light_view * vec4<f32>(p, 1.0)).xyz;
}

fn cs_distant() -> bool {
    return frame.light_position.w == 0.0;
}

// The cone's radius at distance z for a silhouette vertex at distance zv (>= 0).
fn cs_radius(zv: f32, z: f32) -> f32 {
    let grow = select(frame.light_size.x / max(zv, 1e-30), tan(0.5 * frame.light_size.y), cs_distant());
    return max(z - zv, 0.0) * grow;
}

// The point where the light's ray through p (view space) meets the plane at distance z.
fn cs_along_ray(p: vec3<f32>, z: f32) -> vec3<f32> {
    if cs_distant() {
        return vec3<f32>(p.xy, -z);
    }
    return p * (z / max(-p.z, 1e-30));
}

fn cs_faces_light(plane: vec4<f32>) -> bool {
    return dot(plane.xyz, frame.light_position.xyz) + plane.w * frame.light_position.w > 0.0;
}

@compute @workgroup_size(64)
fn cs_cones_and_sheets(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * 64u * groups.x;
    if i >= arrayLength(&cs_edges) {
        return;
    }
    let e = cs_edges[i];
    if e.face_count == 0u {
        return;
    }
    // Silhouette: an open boundary, or faces on both sides of the light.
    let first = cs_faces_light(cs_planes[cs_edge_faces[e.first_face] >> 1u]);
    var silhouette = e.face_count == 1u;
    // The face whose interior tells which side is the shadow: the first facing the light
    // (its fold partner projects to the same side), else the first.
    var inner = cs_edge_faces[e.first_face];
    var found = first;
    for (var k = 1u; k < e.face_count; k++) {
        let f = cs_edge_faces[e.first_face + k];
        let facing = cs_faces_light(cs_planes[f >> 1u]);
        silhouette = silhouette || facing != first;
        if facing && !found {
            inner = f;
            found = true;
        }
    }
    if !silhouette {
        return;
    }
    let a = cs_to_view(e.a);
    let b = cs_to_view(e.b);
    let za = -a.z;
    let zb = -b.z;
    // Behind the light (a local light's view only sees z > 0).
    if !cs_distant() && (za <= 0.0 || zb <= 0.0) {
        return;
    }
    let far = frame.depth_range.y;
    let ra = cs_radius(za, far);
    let rb = cs_radius(zb, far);
    // The edge and the face's interior, projected onto the far plane.
    let pa = cs_along_ray(a, far).xy;
    let pb = cs_along_ray(b, far).xy;
    let edge = pb - pa;
    let len = length(edge);
    var normal = vec2<f32>(0.0);
    var sheet = 0.0;
    if len > 1e-6 * max(max(abs(pa.x), abs(pa.y)), max(max(abs(pb.x), abs(pb.y)), 1e-30)) {
        normal = vec2<f32>(-edge.y, edge.x) / len;
        // n x (q - p) for the winding's direction p -> q points into the face (adjacency)
        let plane = cs_planes[inner >> 1u];
        let dir = select(e.b - e.a, e.a - e.b, (inner & 1u) == 1u);
        let inward_world = cross(plane.xyz, dir);
        let inward = (frame.light_view * vec4<f32>(inward_world, 0.0)).xyz;
        // The projection's derivative along `inward` at the edge's middle.
        let m = 0.5 * (a + b);
        var moved = inward.xy;
        if !cs_distant() {
            moved = inward.xy * (-m.z) + m.xy * inward.z;
        }
        if dot(moved, normal) > 0.0 {
            normal = -normal;
        }
        sheet = 1.0;
    }
    var cones = 0u;
    if atomicAdd(&cs_claims[e.ia], 1u) == 0u {
        cones |= 1u;
    }
    if atomicAdd(&cs_claims[e.ib], 1u) == 0u {
        cones |= 2u;
    }
    let at = atomicAdd(&cs_out.vertex_count, VERTICES_PER_RECORD) / VERTICES_PER_RECORD;
    cs_out.records[at] = ConeSheet(vec4<f32>(a, ra), vec4<f32>(b, rb), vec4<f32>(normal, sheet, f32(cones)));
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
