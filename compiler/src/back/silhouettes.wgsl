// Library code shared by the primitives of Geometry passes: the silhouette edges seen from
// the light's centre. Z values are light-view distances along the view axis (world units),
// the quantity the Depth pass normalises. A distant light (orthographic view, w = 0) has no
// position: its penumbrae grow by tan(angle / 2) per unit of distance (Lawlor 2006's
// distant disk).
//
// `cs_silhouette(i)` classifies edge i by the silhouette rule of the runtime's adjacency
// module: an open boundary, or faces on both sides of the light. A primitive's compute
// entry calls it once per edge (see `Draw::Silhouettes`) and appends its own record.


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

// A silhouette edge: its end points in light view space and the unit direction, in the far
// plane, from the edge's shadow towards its penumbra (`outward`; zero, with `seen` false,
// for an edge seen end-on, whose projection has no length).
struct Silhouette {
    found: bool,
    a: vec3<f32>,
    b: vec3<f32>,
    outward: vec2<f32>,
    seen: bool,
}

fn cs_silhouette(i: u32) -> Silhouette {
    var out: Silhouette;
    out.found = false;
    let e = cs_edges[i];
    if e.face_count == 0u {
        return out;
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
        return out;
    }
    let a = cs_to_view(e.a);
    let b = cs_to_view(e.b);
    // Behind the light (a local light's view only sees z > 0).
    if !cs_distant() && (a.z >= 0.0 || b.z >= 0.0) {
        return out;
    }
    out.found = true;
    out.a = a;
    out.b = b;
    out.outward = vec2<f32>(0.0);
    out.seen = false;
    // The edge and the face's interior, projected onto the far plane.
    let far = frame.depth_range.y;
    let pa = cs_along_ray(a, far).xy;
    let pb = cs_along_ray(b, far).xy;
    let edge = pb - pa;
    let len = length(edge);
    if len > 1e-6 * max(max(abs(pa.x), abs(pa.y)), max(max(abs(pb.x), abs(pb.y)), 1e-30)) {
        var normal = vec2<f32>(-edge.y, edge.x) / len;
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
        out.outward = normal;
        out.seen = true;
    }
    return out;
}
