//! A host's geometry: indexed meshes uploaded once, drawn as instances, each with its own
//! transform, every frame.
//!
//! The generated shaders read world-space positions and normals (`@location(0)` and `(1)`).
//! So that they stay as they are, a runtime compute step *places* the instances: for each
//! instance it writes its mesh's vertices, transformed, into a buffer of placed vertices
//! (`p' = M p`, `n' = N n` with `N` the inverse transpose of `M`'s upper 3 x 3, not
//! normalised: the shaders normalise the interpolated normal). The scene's draws then take
//! the mesh's index buffer with the instance's placed vertices as base vertex, one indexed
//! draw per instance; the light's draws take the casting instances only. Placement runs in
//! the frame after the transforms change ([`crate::gpu::Executor::set_transforms`]), so a
//! frame whose transforms did not move pays nothing for it.
//!
//! Geometry passes classify the edges of the casting instances. Each mesh's edge adjacency
//! ([`Adjacency`]) is built once, in object space, and the same step places it per casting
//! instance: edges (end points transformed, face and welded-vertex indices offset), face
//! planes (`(N n, d - (N n) . t)`, negated where `M` mirrors) and face references (plane
//! indices offset). A soup of the instance's triangles would give the same buffers.
//!
//! Memory: the meshes once (24 bytes a vertex and 4 an index) and the placed vertices
//! (24 bytes a vertex per instance), against a triangle soup's 72 bytes a triangle per
//! instance ([`Geometry::gpu_bytes`]).
//!
//! With an identity transform, placement is exact: each coordinate is `1 x + 0 y + 0 z +
//! 0`, so the placed vertices are the mesh's (up to the sign of a zero). Transforms whose
//! 3 x 3 holds only 0 and +-1 add one rounding (of the translation), the same one a CPU
//! computing `M p` in f32 makes.

use crate::adjacency::{Adjacency, AdjacencyCounts};
use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use crate::fit::Boxes;

/// An indexed triangle mesh in its object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// For errors.
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    /// One per position.
    pub normals: Vec<[f32; 3]>,
    /// Three per triangle, each below `positions.len()`.
    pub indices: Vec<u32>,
}

/// One placement of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// For errors.
    pub name: String,
    /// Index into [`Geometry::meshes`].
    pub mesh: usize,
    /// Column-major object-to-world matrix (affine: its last row is 0, 0, 0, 1).
    pub transform: [f32; 16],
    /// Drawn into the light's views (a shadow caster). Every instance is drawn by the camera.
    pub casts: bool,
    /// Receives shadows. An instance that does not (a sky dome, a light's own fixture, a
    /// marker) is drawn unshadowed and reads visibility 1 (runtime/src/receivers.rs).
    pub receives: bool,
}

/// A host's meshes and their instances, in draw order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    pub meshes: Vec<Mesh>,
    pub instances: Vec<Instance>,
}

/// The identity matrix, column-major.
pub const IDENTITY: [f32; 16] = [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.];

/// Most instances one geometry holds: each has a 256-byte placement record.
pub const MAX_INSTANCES: usize = 1 << 16;

/// Bytes of one instance's placement record (a uniform read at a dynamic offset, which
/// WebGPU aligns to 256 bytes).
const RECORD_BYTES: u64 = 256;

/// `M p` for a column-major affine `m`, as the placement shader computes it.
pub fn transform_point(m: &[f32; 16], p: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|r| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r])
}

/// The inverse transpose of `m`'s upper 3 x 3, column-major in a 4 x 4 (for normals);
/// `None` when it is singular.
pub fn normal_matrix(m: &[f32; 16]) -> Option<[f32; 16]> {
    let a = |r: usize, c: usize| f64::from(m[4 * c + r]);
    let cof = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)
    };
    let det = a(0, 0) * cof(0, 0) + a(0, 1) * cof(0, 1) + a(0, 2) * cof(0, 2);
    if !(det.is_finite() && det != 0.0) {
        return None;
    }
    // (M^-1)^T = cofactor matrix / det
    let mut n = [0.0f32; 16];
    for c in 0..3 {
        for r in 0..3 {
            n[4 * c + r] = (cof(r, c) / det) as f32;
        }
    }
    n[15] = 1.0;
    Some(n)
}

impl Geometry {
    /// Refuse what cannot be drawn, naming the mesh or instance: a normal count that is not
    /// the position count, an index count not a multiple of 3, an index out of range, a
    /// non-finite position, an instance of a mesh that does not exist, a transform that is
    /// not finite, not affine or singular, and counts over `limits`.
    pub fn check(&self, limits: &wgpu::Limits) -> Result<()> {
        self.check_contents()?;
        self.check_sizes(limits)
    }

    /// [`Geometry::check`] without the device's limits: every index in range, every
    /// instance of a mesh that exists, every value finite.
    pub fn check_contents(&self) -> Result<()> {
        let bad = |m: String| Err(RuntimeError::Param(m));
        for (i, m) in self.meshes.iter().enumerate() {
            let name = if m.name.is_empty() {
                format!("mesh {i}")
            } else {
                format!("mesh {i} (`{}`)", m.name)
            };
            if m.normals.len() != m.positions.len() {
                return bad(format!(
                    "{name} has {} normals for {} positions",
                    m.normals.len(),
                    m.positions.len()
                ));
            }
            if m.indices.len() % 3 != 0 {
                return bad(format!("{name} has {} indices, not a multiple of 3", m.indices.len()));
            }
            if let Some((k, ix)) = m.indices.iter().enumerate().find(|(_, ix)| **ix as usize >= m.positions.len()) {
                return bad(format!(
                    "{name}: index {k} is {ix}, out of range of its {} vertices",
                    m.positions.len()
                ));
            }
            if let Some(v) = m.positions.iter().chain(&m.normals).position(|p| !p.iter().all(|c| c.is_finite())) {
                return bad(format!("{name}: vertex {} is not finite", v % m.positions.len().max(1)));
            }
        }
        if self.instances.len() > MAX_INSTANCES {
            return Err(RuntimeError::Limit {
                what: "instances of one geometry".into(),
                needed: self.instances.len() as u64,
                limit: MAX_INSTANCES as u64,
            });
        }
        for (i, inst) in self.instances.iter().enumerate() {
            let name = if inst.name.is_empty() {
                format!("instance {i}")
            } else {
                format!("instance {i} (`{}`)", inst.name)
            };
            if inst.mesh >= self.meshes.len() {
                return bad(format!(
                    "{name} places mesh {}, but there are {} meshes",
                    inst.mesh,
                    self.meshes.len()
                ));
            }
            check_transform(&inst.transform, || name.clone())?;
        }
        Ok(())
    }

    /// The sizes against the device's limits.
    fn check_sizes(&self, limits: &wgpu::Limits) -> Result<()> {
        let storage = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let sizes = [
            ("the meshes' vertices (bytes)", self.mesh_vertices() * 24, storage),
            (
                "the meshes' indices (bytes)",
                self.meshes.iter().map(|m| m.indices.len() as u64).sum::<u64>() * 4,
                limits.max_buffer_size,
            ),
            (
                "the placed vertices of every instance (bytes)",
                self.placed_vertices() * 24,
                storage,
            ),
            (
                "the instances' placement records (bytes)",
                self.instances.len() as u64 * RECORD_BYTES,
                limits.max_buffer_size,
            ),
        ];
        for (what, needed, limit) in sizes {
            if needed > limit {
                return Err(RuntimeError::Limit {
                    what: what.into(),
                    needed,
                    limit,
                });
            }
        }
        Ok(())
    }

    fn mesh_vertices(&self) -> u64 {
        self.meshes.iter().map(|m| m.positions.len() as u64).sum()
    }

    fn placed_vertices(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes.get(i.mesh).map_or(0, |m| m.positions.len() as u64))
            .sum()
    }

    /// The instances' world-space boxes under their transforms, what
    /// [`crate::gpu::LightInputs::fit`] fits a light's view to (instances of a mesh that does
    /// not exist are left out: [`Geometry::check`] refuses them).
    pub fn boxes(&self) -> Boxes {
        let boxes: Vec<_> = self
            .instances
            .iter()
            .map(|i| self.meshes.get(i.mesh).and_then(|m| box_of(m.positions.iter().copied())))
            .collect();
        let casts: Vec<bool> = self.instances.iter().map(|i| i.casts).collect();
        let transforms: Vec<[f32; 16]> = self.instances.iter().map(|i| i.transform).collect();
        world_boxes(&boxes, &casts, &transforms)
    }

    /// Triangles drawn by the camera (every instance's).
    pub fn triangles(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes.get(i.mesh).map_or(0, |m| m.indices.len() as u64 / 3))
            .sum()
    }

    /// Bytes the GPU holds for this geometry: the meshes' vertices and indices, the placed
    /// vertices and the placement records.
    pub fn gpu_bytes(&self) -> u64 {
        let indices: u64 = self.meshes.iter().map(|m| m.indices.len() as u64).sum();
        self.mesh_vertices() * 24 + indices * 4 + self.placed_vertices() * 24 + self.instances.len() as u64 * RECORD_BYTES
    }

    /// The same triangles listed out, world space, casting instances first (in order),
    /// then the others: what [`crate::frame::SceneInputs::vertices`] holds for this geometry, its
    /// transforms applied on the CPU ([`transform_point`], and the normal matrix), and the
    /// number of casting vertices. Refused as [`Geometry::check_contents`] refuses.
    pub fn soup(&self) -> Result<(Vec<f32>, u32)> {
        self.check_contents()?;
        let mut out = Vec::new();
        let mut casting = 0;
        for pass in [true, false] {
            for inst in self.instances.iter().filter(|i| i.casts == pass) {
                let Some(m) = self.meshes.get(inst.mesh) else { continue };
                let n = normal_matrix(&inst.transform).unwrap_or(IDENTITY);
                for &ix in &m.indices {
                    let (p, q) = (m.positions[ix as usize], m.normals[ix as usize]);
                    out.extend(transform_point(&inst.transform, p));
                    out.extend([0, 1, 2].map(|r| n[r] * q[0] + n[4 + r] * q[1] + n[8 + r] * q[2]));
                }
            }
            if pass {
                casting = (out.len() / 6) as u32;
            }
        }
        Ok((out, casting))
    }

    /// The vertices of each instance that receives no shadow in [`Geometry::soup`]'s
    /// listing, as ranges of vertex indices ([`crate::frame::SceneInputs::unshadowed`]).
    pub fn soup_unshadowed(&self) -> Vec<std::ops::Range<u32>> {
        let mut out = Vec::new();
        let mut at = 0u32;
        for pass in [true, false] {
            for inst in self.instances.iter().filter(|i| i.casts == pass) {
                let n = self.meshes.get(inst.mesh).map_or(0, |m| m.indices.len() as u32);
                if !inst.receives {
                    out.push(at..at + n);
                }
                at += n;
            }
        }
        out
    }

    /// The triangles of each casting instance in [`Geometry::soup`]'s listing, as ranges
    /// of triangle indices ([`crate::frame::SceneInputs::meshes`]: Geometry passes find edges within
    /// each, as the host geometry's adjacency is built per instance's mesh).
    pub fn soup_meshes(&self) -> Vec<std::ops::Range<u32>> {
        let mut out = Vec::new();
        let mut at = 0u32;
        for inst in self.instances.iter().filter(|i| i.casts) {
            let n = self.meshes.get(inst.mesh).map_or(0, |m| m.indices.len() as u32 / 3);
            out.push(at..at + n);
            at += n;
        }
        out
    }
}

/// The world-space boxes of the instances (each mesh box, `boxes[i]` in object space, with
/// its corners transformed), split into casters and the others; instances of an empty mesh
/// have none.
fn world_boxes(boxes: &[Option<[[f32; 3]; 2]>], casts: &[bool], transforms: &[[f32; 16]]) -> Boxes {
    let mut out = Boxes::default();
    for ((b, &c), t) in boxes.iter().zip(casts).zip(transforms) {
        let Some(b) = b else { continue };
        let placed = box_of((0..8).map(|i| transform_point(t, [0, 1, 2].map(|a| b[(i >> a) & 1][a]))));
        if let Some(w) = placed {
            if c { &mut out.casters } else { &mut out.others }.push(w);
        }
    }
    out
}

/// The bounding box of the casting instances, world space: each instance's mesh box
/// (`boxes[i]`, object space) with its corners transformed; `None` without a casting vertex.
fn instances_bounds(boxes: &[Option<[[f32; 3]; 2]>], casts: &[bool], transforms: &[[f32; 16]]) -> Option<[[f32; 3]; 2]> {
    let corners = boxes
        .iter()
        .zip(casts)
        .zip(transforms)
        .filter(|((_, c), _)| **c)
        .filter_map(|((b, _), t)| b.map(|b| (b, t)))
        .flat_map(|(b, t)| (0..8).map(move |i| transform_point(t, [0, 1, 2].map(|a| b[(i >> a) & 1][a]))));
    box_of(corners)
}

pub(crate) fn box_of(points: impl Iterator<Item = [f32; 3]>) -> Option<[[f32; 3]; 2]> {
    points.fold(None, |b, p| {
        let [lo, hi] = b.unwrap_or([p, p]);
        Some([
            [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
            [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
        ])
    })
}

/// Refuse a transform that is not finite, not affine or singular, naming `what` (made only
/// for the error: this runs for every instance on every `set_transforms`).
pub(crate) fn check_transform(m: &[f32; 16], what: impl Fn() -> String) -> Result<()> {
    if !m.iter().all(|c| c.is_finite()) {
        return Err(RuntimeError::Param(format!("{}: its transform is not finite: {m:?}", what())));
    }
    if [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
        return Err(RuntimeError::Param(format!(
            "{}: its transform is not affine (last row {:?}, not [0, 0, 0, 1])",
            what(),
            [m[3], m[7], m[11], m[15]]
        )));
    }
    // the normal matrix's own condition (`normal_matrix`), without computing it
    let det = determinant3(m);
    if !(det.is_finite() && det != 0.0) {
        return Err(RuntimeError::Param(format!(
            "{}: its transform is singular (no normal matrix)",
            what()
        )));
    }
    Ok(())
}

/// The scene's edge adjacency on the GPU, for Geometry passes (group 3 of their
/// `Silhouettes` steps; layout in [`crate::adjacency`]).
#[derive(Clone)]
pub(crate) struct EdgeBuffers {
    pub edges: wgpu::Buffer,
    pub planes: wgpu::Buffer,
    pub edge_faces: wgpu::Buffer,
    /// One `u32` per welded vertex, cleared before each classification: the first edge
    /// to claim a vertex draws what is drawn once per silhouette vertex.
    pub claims: wgpu::Buffer,
    pub counts: AdjacencyCounts,
}

/// A host geometry as every light's resources take it: its draws, and its edges when a
/// graph classifies silhouettes.
pub(crate) struct HostScene {
    pub draw: SceneDraw,
    pub edges: Option<EdgeBuffers>,
}

/// One draw of the scene: a range of indices (or of vertices, without an index buffer)
/// with its base vertex, and whether the light's views draw it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DrawRange {
    pub elements: std::ops::Range<u32>,
    pub base_vertex: i32,
    pub casts: bool,
}

/// What a scene draw binds and draws: a triangle soup's vertex buffer (its casting
/// vertices first), or a host geometry's placed vertices with the meshes' index buffer.
#[derive(Clone)]
pub(crate) struct SceneDraw {
    pub vertices: wgpu::Buffer,
    pub indices: Option<wgpu::Buffer>,
    pub ranges: Vec<DrawRange>,
    /// The draws of the objects that receive no shadow, drawn again unshadowed
    /// ([`crate::receivers`]); empty when every object receives.
    pub unshadowed: Vec<DrawRange>,
}

impl SceneDraw {
    /// A soup of `count` vertices, the first `casting` drawn from the light, those in
    /// `unshadowed` (vertex ranges, clamped to the soup) receiving no shadow.
    pub fn soup(vertices: wgpu::Buffer, count: u32, casting: u32, unshadowed: &[std::ops::Range<u32>]) -> SceneDraw {
        let casting = casting.min(count);
        SceneDraw {
            unshadowed: unshadowed
                .iter()
                .map(|r| r.start.min(count)..r.end.min(count))
                .filter(|r| !r.is_empty())
                .map(|elements| DrawRange {
                    elements,
                    base_vertex: 0,
                    casts: false,
                })
                .collect(),
            vertices,
            indices: None,
            ranges: [(0..casting, true), (casting..count, false)]
                .into_iter()
                .filter(|(r, _)| !r.is_empty())
                .map(|(elements, casts)| DrawRange {
                    elements,
                    base_vertex: 0,
                    casts,
                })
                .collect(),
        }
    }

    /// Record the draws into `rp` (the casting ones only when `from_light`).
    pub fn record(&self, rp: &mut wgpu::RenderPass<'_>, from_light: bool) {
        self.draw(rp, self.ranges.iter().filter(|r| r.casts || !from_light));
    }

    /// Record the draws of the objects that receive no shadow.
    pub fn record_unshadowed(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.draw(rp, self.unshadowed.iter());
    }

    fn draw<'r>(&self, rp: &mut wgpu::RenderPass<'_>, ranges: impl Iterator<Item = &'r DrawRange>) {
        let mut ranges = ranges.peekable();
        if ranges.peek().is_none() {
            return;
        }
        rp.set_vertex_buffer(0, self.vertices.slice(..));
        match &self.indices {
            Some(indices) => {
                rp.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                for r in ranges {
                    rp.draw_indexed(r.elements.clone(), r.base_vertex, 0..1);
                }
            }
            None => {
                for r in ranges {
                    rp.draw(r.elements.clone(), 0..1);
                }
            }
        }
    }
}

const PLACE_WGSL: &str = "
// One instance's placement (a 256-byte record read at a dynamic offset): its matrix and
// normal matrix, then for vertices, edges, face planes and face references: where the
// instance's mesh's ones start, how many, and where the placed ones go; plus the first
// welded vertex (edges), whether the matrix mirrors (planes) and the first plane (faces).
struct Placement {
    model: mat4x4<f32>,
    normal: mat4x4<f32>,
    vertices: vec4<u32>,
    edges: vec4<u32>,
    planes: vec4<u32>,
    faces: vec4<u32>,
}
struct Edge {
    a: vec3<f32>,
    first_face: u32,
    b: vec3<f32>,
    face_count: u32,
    ia: u32,
    ib: u32,
    pad0: u32,
    pad1: u32,
}
@group(0) @binding(0) var<uniform> place: Placement;
@group(0) @binding(1) var<storage, read> meshes: array<f32>;
@group(0) @binding(2) var<storage, read_write> placed: array<f32>;
@group(0) @binding(3) var<storage, read> mesh_edges: array<Edge>;
@group(0) @binding(4) var<storage, read_write> edges: array<Edge>;
@group(0) @binding(5) var<storage, read> mesh_planes: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> planes: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> mesh_faces: array<u32>;
@group(0) @binding(8) var<storage, read_write> faces: array<u32>;

fn index(id: vec3<u32>) -> u32 {
    return id.x + id.y * 64u * 65535u;
}

@compute @workgroup_size(64)
fn place_vertices(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = index(id);
    if i >= place.vertices.y {
        return;
    }
    let s = (place.vertices.x + i) * 6u;
    let d = (place.vertices.z + i) * 6u;
    let p = place.model * vec4<f32>(meshes[s], meshes[s + 1u], meshes[s + 2u], 1.0);
    let n = place.normal * vec4<f32>(meshes[s + 3u], meshes[s + 4u], meshes[s + 5u], 0.0);
    placed[d] = p.x;
    placed[d + 1u] = p.y;
    placed[d + 2u] = p.z;
    placed[d + 3u] = n.x;
    placed[d + 4u] = n.y;
    placed[d + 5u] = n.z;
}

@compute @workgroup_size(64)
fn place_edges(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = index(id);
    if i >= place.edges.y {
        return;
    }
    var e = mesh_edges[place.edges.x + i];
    e.a = (place.model * vec4<f32>(e.a, 1.0)).xyz;
    e.b = (place.model * vec4<f32>(e.b, 1.0)).xyz;
    e.first_face = e.first_face + place.faces.z;
    e.ia = e.ia + place.edges.w;
    e.ib = e.ib + place.edges.w;
    edges[place.edges.z + i] = e;
}

// the plane n.x + d = 0 of x = M^-1 (x' - t): (N n).x' + d - (N n).t = 0, N the normal
// matrix; negated where M mirrors, so that the normal stays the winding's
@compute @workgroup_size(64)
fn place_planes(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = index(id);
    if i >= place.planes.y {
        return;
    }
    let q = mesh_planes[place.planes.x + i];
    let n = (place.normal * vec4<f32>(q.xyz, 0.0)).xyz;
    let side = select(1.0, -1.0, place.planes.w == 1u);
    planes[place.planes.z + i] = side * vec4<f32>(n, q.w - dot(n, place.model[3].xyz));
}

@compute @workgroup_size(64)
fn place_faces(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = index(id);
    if i >= place.faces.y {
        return;
    }
    let f = mesh_faces[place.faces.x + i];
    faces[place.faces.z + i] = (((f >> 1u) + place.faces.w) << 1u) | (f & 1u);
}
";

/// Where one instance's placed data start, and how many of each (the record's words).
#[derive(Clone, Copy, Default)]
struct Spans {
    /// (mesh's first, count, placed first) of vertices, edges, planes, face references.
    vertices: [u32; 3],
    edges: [u32; 3],
    planes: [u32; 3],
    faces: [u32; 3],
    /// The instance's first welded vertex among all placed ones.
    welded: u32,
}

/// The entry points of the placement shader, with the span each dispatches over.
const STEPS: [&str; 4] = ["place_vertices", "place_edges", "place_planes", "place_faces"];

/// A host geometry on the GPU: the meshes, the placed vertices (and, for graphs that
/// classify silhouettes, the placed edges, face planes and face references), the placement
/// step, and the draws. Shared by every light.
pub(crate) struct GeometryBuffers {
    pub scene: HostScene,
    records: wgpu::Buffer,
    pipelines: Vec<wgpu::ComputePipeline>,
    group: wgpu::BindGroup,
    spans: Vec<Spans>,
    /// Placement is due (the transforms changed since it last ran).
    pub dirty: bool,
    pub transforms: Vec<[f32; 16]>,
    /// Per instance: whether it casts, and its mesh's box (object space).
    casts: Vec<bool>,
    boxes: Vec<Option<[[f32; 3]; 2]>>,
    /// The instances' world-space boxes under `transforms`, made again when they change
    /// (what a light placed every frame is fitted to, without recomputing them).
    world: Boxes,
}

impl GeometryBuffers {
    /// Upload `g` (checked) and create its placement step; with `edges`, the edge adjacency
    /// of every mesh a casting instance places, built once per mesh in object space (the
    /// same welding and order as [`Adjacency::build`] of the instance's triangles listed out).
    pub fn new(gpu: &Gpu, g: &Geometry, edges: bool) -> Result<GeometryBuffers> {
        g.check(&gpu.limits)?;
        let words = |v: &mut Vec<u8>, x: &[u32]| v.extend(x.iter().flat_map(|w| w.to_le_bytes()));
        // the meshes, one after the other, and their adjacency
        let mut first = Vec::new(); // per mesh: first vertex, index, edge, plane, face reference
        let (mut vertex_data, mut index_data) = (Vec::new(), Vec::new());
        let (mut edge_data, mut plane_data, mut face_data) = (Vec::new(), Vec::new(), Vec::new());
        let mut adjacency: Vec<Option<Adjacency>> = Vec::new();
        for (mi, m) in g.meshes.iter().enumerate() {
            first.push([
                (vertex_data.len() / 24) as u32,
                (index_data.len() / 4) as u32,
                (edge_data.len() / 48) as u32,
                (plane_data.len() / 16) as u32,
                (face_data.len() / 4) as u32,
            ]);
            for (p, n) in m.positions.iter().zip(&m.normals) {
                for c in p.iter().chain(n) {
                    vertex_data.extend(c.to_le_bytes());
                }
            }
            words(&mut index_data, &m.indices);
            let cast = g.instances.iter().any(|i| i.mesh == mi && i.casts);
            let adj = (edges && cast).then(|| {
                let tris: Vec<[[f32; 3]; 3]> = m
                    .indices
                    .chunks_exact(3)
                    .map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize]))
                    .collect();
                Adjacency::build(&tris, std::iter::once(0..tris.len()))
            });
            if let Some(a) = &adj {
                edge_data.extend(a.edges.iter().flat_map(|e| e.to_bytes()));
                plane_data.extend(a.planes.iter().flatten().flat_map(|x| x.to_le_bytes()));
                words(&mut face_data, &a.edge_faces);
            }
            adjacency.push(adj);
        }
        // what the casting instances place, summed in u64 and bounded before the u32 spans
        // are laid out (many instances of a mesh of many edges could pass 2^32)
        let storage_limit = gpu.limits.max_storage_buffer_binding_size.min(gpu.limits.max_buffer_size);
        let mut totals = [0u64; 4];
        for inst in g.instances.iter().filter(|i| i.casts) {
            if let Some(a) = &adjacency[inst.mesh] {
                for (t, n) in totals
                    .iter_mut()
                    .zip([a.edges.len(), a.planes.len(), a.edge_faces.len(), a.vertices as usize])
                {
                    *t += n as u64;
                }
            }
        }
        for (what, needed) in [
            ("placed edges (bytes)", totals[0] * 48),
            ("placed face planes (bytes)", totals[1] * 16),
            ("placed face references (bytes)", totals[2] * 4),
            ("vertex claims (bytes)", totals[3] * 4 + 4),
        ] {
            if needed > storage_limit {
                return Err(RuntimeError::Limit {
                    what: what.into(),
                    needed,
                    limit: storage_limit,
                });
            }
        }
        // the instances, one after the other: draws, and spans of what they place
        let (mut ranges, mut spans, mut unshadowed) = (Vec::new(), Vec::new(), Vec::new());
        let mut placed = Spans::default();
        let mut counts = AdjacencyCounts::default();
        for inst in &g.instances {
            let m = &g.meshes[inst.mesh];
            let f = first[inst.mesh];
            ranges.push(DrawRange {
                elements: f[1]..f[1] + m.indices.len() as u32,
                base_vertex: i32::try_from(placed.vertices[2]).map_err(|_| RuntimeError::Limit {
                    what: "placed vertices (a base vertex is an i32)".into(),
                    needed: placed.vertices[2].into(),
                    limit: i32::MAX as u64,
                })?,
                casts: inst.casts,
            });
            if !inst.receives {
                unshadowed.extend(ranges.last().cloned());
            }
            let mut s = Spans {
                vertices: [f[0], m.positions.len() as u32, placed.vertices[2]],
                welded: placed.welded,
                ..Default::default()
            };
            placed.vertices[2] += m.positions.len() as u32;
            if let (true, Some(a)) = (inst.casts, &adjacency[inst.mesh]) {
                s.edges = [f[2], a.edges.len() as u32, placed.edges[2]];
                s.planes = [f[3], a.planes.len() as u32, placed.planes[2]];
                s.faces = [f[4], a.edge_faces.len() as u32, placed.faces[2]];
                placed.edges[2] += a.edges.len() as u32;
                placed.planes[2] += a.planes.len() as u32;
                placed.faces[2] += a.edge_faces.len() as u32;
                placed.welded += a.vertices;
                counts.meshes += 1;
                counts.edges += a.counts.edges;
                counts.boundary += a.counts.boundary;
                counts.manifold += a.counts.manifold;
                counts.non_manifold += a.counts.non_manifold;
                counts.degenerate_faces += a.counts.degenerate_faces;
            }
            spans.push(s);
        }
        gpu.scoped("uploading the host geometry", || {
            let device = &gpu.device;
            let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    // a binding may not be empty
                    size: size.max(48).next_multiple_of(16),
                    usage,
                    mapped_at_creation: false,
                })
            };
            let upload = |label: &str, data: &[u8], usage: wgpu::BufferUsages| {
                let b = buffer(label, data.len() as u64, usage | wgpu::BufferUsages::COPY_DST);
                if !data.is_empty() {
                    gpu.queue.write_buffer(&b, 0, data);
                }
                b
            };
            let storage = wgpu::BufferUsages::STORAGE;
            let meshes = upload("mesh vertices", &vertex_data, storage);
            let indices = upload("mesh indices", &index_data, wgpu::BufferUsages::INDEX);
            let mesh_edges = upload("mesh edges", &edge_data, storage);
            let mesh_planes = upload("mesh face planes", &plane_data, storage);
            let mesh_faces = upload("mesh face references", &face_data, storage);
            let placed_vertices = buffer(
                "placed vertices",
                u64::from(placed.vertices[2]) * 24,
                storage | wgpu::BufferUsages::VERTEX,
            );
            let placed_edges = buffer("placed edges", u64::from(placed.edges[2]) * 48, storage);
            let placed_planes = buffer("placed face planes", u64::from(placed.planes[2]) * 16, storage);
            let placed_faces = buffer("placed face references", u64::from(placed.faces[2]) * 4, storage);
            let claims = buffer(
                "vertex claims",
                4 * u64::from(placed.welded) + 4,
                storage | wgpu::BufferUsages::COPY_DST,
            );
            let records = buffer(
                "placement records",
                // at least one record: the binding is one record wide
                (g.instances.len() as u64).max(1) * RECORD_BYTES,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            );
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("place instances"),
                source: wgpu::ShaderSource::Wgsl(PLACE_WGSL.into()),
            });
            let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty,
                count: None,
            };
            let storage = |read_only| wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            };
            let record = wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(RECORD_BYTES),
            };
            let mut entries = vec![entry(0, record)];
            entries.extend((1..9).map(|b| entry(b, storage(b % 2 == 1))));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("place instances"),
                entries: &entries,
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("place instances"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipelines = STEPS
                .iter()
                .map(|entry| {
                    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&pipeline_layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                })
                .collect();
            let bound = [
                &meshes,
                &placed_vertices,
                &mesh_edges,
                &placed_edges,
                &mesh_planes,
                &placed_planes,
                &mesh_faces,
                &placed_faces,
            ];
            let mut group_entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &records,
                    offset: 0,
                    size: wgpu::BufferSize::new(RECORD_BYTES),
                }),
            }];
            group_entries.extend(bound.iter().enumerate().map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32 + 1,
                resource: b.as_entire_binding(),
            }));
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("place instances"),
                layout: &layout,
                entries: &group_entries,
            });
            let mut out = GeometryBuffers {
                scene: HostScene {
                    draw: SceneDraw {
                        vertices: placed_vertices,
                        indices: Some(indices),
                        ranges,
                        unshadowed,
                    },
                    edges: edges.then(|| EdgeBuffers {
                        edges: placed_edges,
                        planes: placed_planes,
                        edge_faces: placed_faces,
                        claims,
                        counts,
                    }),
                },
                records,
                pipelines,
                group,
                spans,
                dirty: true,
                transforms: g.instances.iter().map(|i| i.transform).collect(),
                casts: g.instances.iter().map(|i| i.casts).collect(),
                boxes: g
                    .instances
                    .iter()
                    .map(|i| box_of(g.meshes[i.mesh].positions.iter().copied()))
                    .collect(),
                world: Boxes::default(),
            };
            out.world = world_boxes(&out.boxes, &out.casts, &out.transforms);
            out.write_records(&gpu.queue);
            out
        })
    }

    /// Refuse a set of transforms: not one per instance, or one not finite, affine and
    /// invertible.
    pub fn check_transforms(&self, transforms: &[[f32; 16]]) -> Result<()> {
        if transforms.len() != self.transforms.len() {
            return Err(RuntimeError::Param(format!(
                "{} transforms for {} instances: a new instance set is a new binding",
                transforms.len(),
                self.transforms.len()
            )));
        }
        for (i, t) in transforms.iter().enumerate() {
            check_transform(t, || format!("instance {i}"))?;
        }
        Ok(())
    }

    /// Take a set of transforms ([`GeometryBuffers::check_transforms`] passed): the
    /// placement records are written and placement runs in the next frame.
    pub fn write_transforms(&mut self, queue: &wgpu::Queue, transforms: &[[f32; 16]]) {
        self.transforms.copy_from_slice(transforms);
        self.world = world_boxes(&self.boxes, &self.casts, &self.transforms);
        self.write_records(queue);
    }

    /// Write every placement record and mark placement due.
    fn write_records(&mut self, queue: &wgpu::Queue) {
        let mut bytes = vec![0u8; self.transforms.len() * RECORD_BYTES as usize];
        for (i, (t, s)) in self.transforms.iter().zip(&self.spans).enumerate() {
            let n = normal_matrix(t).unwrap_or(IDENTITY);
            // a mirroring matrix turns the winding: the planes are negated to follow it
            let mirrors = determinant3(t) < 0.0;
            let r = &mut bytes[i * RECORD_BYTES as usize..(i + 1) * RECORD_BYTES as usize];
            let values = t.iter().chain(&n).map(|c| c.to_le_bytes());
            let words = [
                s.vertices[0],
                s.vertices[1],
                s.vertices[2],
                0,
                s.edges[0],
                s.edges[1],
                s.edges[2],
                s.welded,
                s.planes[0],
                s.planes[1],
                s.planes[2],
                u32::from(mirrors),
                s.faces[0],
                s.faces[1],
                s.faces[2],
                s.planes[2],
            ]
            .map(|w| w.to_le_bytes());
            for (k, b) in values.chain(words).enumerate() {
                r[4 * k..4 * k + 4].copy_from_slice(&b);
            }
        }
        if !bytes.is_empty() {
            queue.write_buffer(&self.records, 0, &bytes);
        }
        self.dirty = true;
    }

    /// The instances' world-space boxes under the current transforms ([`Geometry::boxes`]).
    pub fn boxes(&self) -> &Boxes {
        &self.world
    }

    /// The casting instances' bounding box under `transforms` (one per instance).
    pub fn caster_bounds_at(&self, transforms: &[[f32; 16]]) -> Option<[[f32; 3]; 2]> {
        instances_bounds(&self.boxes, &self.casts, transforms)
    }

    /// Record the placement of every instance (its vertices, and its edges, planes and face
    /// references where it has them), when it is due.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if !self.dirty {
            return;
        }
        self.dirty = false;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("place instances"),
            timestamp_writes: None,
        });
        for (step, pipeline) in self.pipelines.iter().enumerate() {
            pass.set_pipeline(pipeline);
            for (i, s) in self.spans.iter().enumerate() {
                let count = [s.vertices, s.edges, s.planes, s.faces][step][1];
                if count == 0 {
                    continue;
                }
                pass.set_bind_group(0, &self.group, &[(i as u64 * RECORD_BYTES) as u32]);
                let groups = count.div_ceil(64);
                let (x, y) = if groups <= 65535 {
                    (groups, 1)
                } else {
                    (65535, groups.div_ceil(65535))
                };
                pass.dispatch_workgroups(x, y, 1);
            }
        }
    }
}

/// The determinant of the upper 3 x 3 of a column-major 4 x 4.
fn determinant3(m: &[f32; 16]) -> f64 {
    let a = |r: usize, c: usize| f64::from(m[4 * c + r]);
    a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
        + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0))
}
