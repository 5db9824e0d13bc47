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
//! the frame after the transforms change ([`crate::gpu::Scene::set_transforms`]), so a
//! frame whose transforms did not move pays nothing for it.
//!
//! Geometry passes classify the edges of the casting instances. Each mesh's edge adjacency
//! ([`Adjacency`]) is built once, in object space, and the same step places it per casting
//! instance: edges (end points transformed, face and welded-vertex indices offset), face
//! planes (`(N n, d - (N n) . t)`, negated where `M` mirrors) and face references (plane
//! indices offset). A soup of the instance's triangles would give the same buffers.
//!
//! Instances that do not move under the identity are *in world space*
//! ([`Instance::in_world_space`]): drawn straight from their mesh's vertices, with no placed
//! copy, their edges written once at upload. Instances that do not move under another
//! transform (a glTF node's instance of a shared mesh) are *placed at upload*
//! ([`Instance::placed_at_upload`]): their placed vertices, edges, face planes and face
//! references are computed once on the CPU, with the arithmetic of [`Geometry::soup`]
//! (so they equal the soup's triangles bit for bit), and written with the rest; the
//! placement step never binds them, so they are free of its storage-binding limit. A
//! triangle soup binds as instances in world space, one per object ([`Geometry::from_soup`]), and a mesh listed out (indices 0, 1, 2, ...) is
//! drawn without an index buffer, so a soup keeps its 72 bytes a triangle.
//!
//! Memory: the meshes once (24 bytes a vertex and 4 an index) and the placed vertices
//! (24 bytes a vertex per instance not in world space), against a triangle soup's 72 bytes
//! a triangle per instance ([`Geometry::gpu_bytes`]).
//!
//! With an identity transform, placement is exact: each coordinate is `1 x + 0 y + 0 z +
//! 0`, so the placed vertices are the mesh's (up to the sign of a zero). Transforms whose
//! 3 x 3 holds only 0 and +-1 add one rounding (of the translation), the same one a CPU
//! computing `M p` in f32 makes.

use crate::adjacency::{Adjacency, AdjacencyCounts};
use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use crate::fit::Boxes;
use crate::pool::Pool;

mod changes;

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

impl Mesh {
    /// Its indices are 0, 1, 2, ... (its triangles listed out, as a soup's are): it is drawn
    /// without an index buffer, and none is uploaded for it.
    pub fn listed_out(&self) -> bool {
        self.indices.iter().enumerate().all(|(k, &i)| i as usize == k)
    }

    /// The indices uploaded for it: none when [`Mesh::listed_out`].
    fn uploaded_indices(&self) -> u64 {
        if self.listed_out() { 0 } else { self.indices.len() as u64 }
    }
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
    /// Its transform may change after binding ([`crate::gpu::Scene::set_transforms`]).
    /// One that does not keeps the transform it was bound with. With the identity transform
    /// (a mesh given in world space, as static level geometry or the lab's scenes are), it
    /// is *in world space*: drawn straight from its mesh's vertices, with no placed copy and
    /// no placement step, and its edges are written once at binding.
    pub moves: bool,
}

impl Instance {
    /// Drawn straight from its mesh: it does not move and its transform is the identity,
    /// bit for bit (a `-0.0` entry places it on the GPU like any other).
    pub fn in_world_space(&self) -> bool {
        !self.moves && self.transform.map(f32::to_bits) == IDENTITY.map(f32::to_bits)
    }

    /// Placed once, on the CPU, at upload: it does not move and its transform is not the
    /// identity. Its placed copy is drawn like a moving instance's, but the placement step
    /// has no work for it.
    pub fn placed_at_upload(&self) -> bool {
        !self.moves && !self.in_world_space()
    }
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
const _: () = assert!(sshc_graph::PLACEMENT_SIZE as u64 <= RECORD_BYTES);

/// `M p` for a column-major affine `m`, as the placement shader computes it.
pub fn transform_point(m: &[f32; 16], p: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|r| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r])
}

/// `N q` for a normal matrix `n` ([`normal_matrix`]) as [`Geometry::soup`] and the
/// placement at upload compute it (not normalised).
fn transform_normal(n: &[f32; 16], q: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|r| n[r] * q[0] + n[4 + r] * q[1] + n[8 + r] * q[2])
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
            check_mesh(i, m)?;
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

    /// The sizes against the device's limits. The vertices of a mesh some instance places
    /// on the GPU, and the placed vertices, are bound whole as storage by the placement
    /// step; a mesh drawn only in world space is a vertex buffer, under `max_buffer_size`.
    fn check_sizes(&self, limits: &wgpu::Limits) -> Result<()> {
        let storage = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let [placed_meshes, world_meshes] = self.mesh_vertices();
        let sizes = [
            ("the vertices of the meshes placed on the GPU (bytes)", placed_meshes * 24, storage),
            (
                "the vertices of the meshes in world space (bytes)",
                world_meshes * 24,
                limits.max_buffer_size,
            ),
            (
                "the meshes' indices (bytes)",
                self.meshes.iter().map(Mesh::uploaded_indices).sum::<u64>() * 4,
                limits.max_buffer_size,
            ),
            (
                "the placed vertices of every instance not in world space (bytes; bound whole by the placement step when an instance moves)",
                self.placed_vertices() * 24,
                if self.instances.iter().any(|i| i.moves) {
                    storage
                } else {
                    limits.max_buffer_size
                },
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

    /// Per mesh: whether an instance places it on the GPU (a moving one).
    fn placed_on_gpu(&self) -> Vec<bool> {
        let mut out = vec![false; self.meshes.len()];
        for i in self.instances.iter().filter(|i| i.moves) {
            if let Some(p) = out.get_mut(i.mesh) {
                *p = true;
            }
        }
        out
    }

    /// The vertices of the meshes placed on the GPU, and of those drawn in world space only.
    fn mesh_vertices(&self) -> [u64; 2] {
        let mut out = [0u64; 2];
        for (m, gpu) in self.meshes.iter().zip(self.placed_on_gpu()) {
            out[usize::from(!gpu)] += m.positions.len() as u64;
        }
        out
    }

    /// The placed copies' vertices: every instance not in world space has one.
    fn placed_vertices(&self) -> u64 {
        self.instances
            .iter()
            .filter(|i| !i.in_world_space())
            .map(|i| self.meshes.get(i.mesh).map_or(0, |m| m.positions.len() as u64))
            .sum()
    }

    /// Triangles of the casting instances (what their edge adjacency is bounded from).
    pub fn casting_triangles(&self) -> u64 {
        self.instances
            .iter()
            .filter(|i| i.casts)
            .map(|i| self.meshes.get(i.mesh).map_or(0, |m| m.indices.len() as u64 / 3))
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

    /// Bytes the GPU holds for this geometry: the meshes' vertices and indices (none for a
    /// mesh listed out), the placed vertices (of the instances not in world space) and the
    /// placement records.
    pub fn gpu_bytes(&self) -> u64 {
        let indices: u64 = self.meshes.iter().map(Mesh::uploaded_indices).sum();
        let [placed, world] = self.mesh_vertices();
        (placed + world) * 24 + indices * 4 + self.placed_vertices() * 24 + self.instances.len() as u64 * RECORD_BYTES
    }

    /// A triangle soup as geometry: the adapter [`crate::gpu::Scene::from_soup`] uploads a
    /// soup through ([`crate::frame::SceneInputs`]'s `vertices`, `meshes`,
    /// `casting_vertices` and `unshadowed`). Each object of the soup (a run of triangles
    /// with one mesh range, one side of the casting boundary and one receiving flag)
    /// becomes a mesh of its triangles listed out (`indices` 0, 1, 2, ...: drawn without an
    /// index buffer, [`Mesh::listed_out`]) and an instance in world space
    /// ([`Instance::in_world_space`]): drawn straight from its vertices, in the soup's
    /// order, so the draws and the edges are the soup's, bit for bit, in the soup's 72
    /// bytes a triangle. Casting triangles in no mesh range form objects of their own.
    ///
    /// Refused, saying where: a float count that is not whole triangles (18 floats each), a
    /// casting count or an unshadowed range that is not whole triangles, a mesh range that
    /// straddles the casting boundary, overlaps another or is split by an unshadowed range
    /// (a mesh casts, and receives, as a whole).
    pub fn from_soup(
        vertices: &[f32],
        meshes: &[std::ops::Range<u32>],
        casting_vertices: Option<u32>,
        unshadowed: &[std::ops::Range<u32>],
    ) -> Result<Geometry> {
        let bad = |m: String| Err(RuntimeError::Param(m));
        if !vertices.len().is_multiple_of(18) {
            return bad(format!(
                "the soup has {} floats, not whole triangles (18 floats each: three vertices of position and normal)",
                vertices.len()
            ));
        }
        let n = u32::try_from(vertices.len() / 6).map_err(|_| RuntimeError::Limit {
            what: "vertices of a triangle soup".into(),
            needed: (vertices.len() / 6) as u64,
            limit: u32::MAX.into(),
        })? / 3;
        let casting = casting_vertices.map_or(3 * n, |c| c.min(3 * n));
        if !casting.is_multiple_of(3) {
            return bad(format!("casting_vertices is {casting}, not whole triangles (3 vertices each)"));
        }
        let casting = casting / 3;
        let mut shade_free = Vec::new();
        for (k, r) in unshadowed.iter().enumerate() {
            if !r.start.is_multiple_of(3) || !r.end.is_multiple_of(3) {
                return bad(format!(
                    "unshadowed range {k} ({}..{}) is not whole triangles (3 vertices each)",
                    r.start, r.end
                ));
            }
            let r = (r.start / 3).min(n)..(r.end / 3).min(n);
            if !r.is_empty() {
                shade_free.push(r);
            }
        }
        let mut objects: Vec<std::ops::Range<u32>> = if meshes.is_empty() {
            std::iter::once(0..casting).collect()
        } else {
            meshes.iter().map(|r| r.start.min(n)..r.end.min(n)).collect()
        };
        objects.retain(|r| !r.is_empty());
        objects.sort_by_key(|r| r.start);
        for (k, r) in objects.iter().enumerate() {
            if r.start < casting && casting < r.end {
                return bad(format!(
                    "mesh triangles {}..{} straddle the casting boundary at triangle {casting}: a mesh casts, or does not, as a whole",
                    r.start, r.end
                ));
            }
            if let Some(next) = objects.get(k + 1)
                && next.start < r.end
            {
                return bad(format!(
                    "meshes of triangles {}..{} and {}..{} overlap",
                    r.start, r.end, next.start, next.end
                ));
            }
            if let Some(u) = shade_free.iter().flat_map(|u| [u.start, u.end]).find(|&u| r.start < u && u < r.end) {
                return bad(format!(
                    "an unshadowed range splits the mesh of triangles {}..{} at triangle {u}: a mesh receives shadows, or does not, as a whole",
                    r.start, r.end
                ));
            }
        }
        // the runs between every boundary: meshes, the casting one, the unshadowed ranges'
        let mut cuts: Vec<u32> = [0, n, casting]
            .into_iter()
            .chain(objects.iter().flat_map(|r| [r.start, r.end]))
            .chain(shade_free.iter().flat_map(|r| [r.start, r.end]))
            .collect();
        cuts.sort_unstable();
        cuts.dedup();
        let mut g = Geometry::default();
        for w in cuts.windows(2) {
            let (a, b) = (w[0] as usize, w[1] as usize);
            let corners = vertices[a * 18..b * 18].chunks_exact(6);
            g.meshes.push(Mesh {
                name: format!("soup triangles {a}..{b}"),
                positions: corners.clone().map(|v| [v[0], v[1], v[2]]).collect(),
                normals: corners.map(|v| [v[3], v[4], v[5]]).collect(),
                indices: (0..3 * (b - a) as u32).collect(),
            });
            g.instances.push(Instance {
                name: format!("soup triangles {a}..{b}"),
                mesh: g.meshes.len() - 1,
                transform: IDENTITY,
                casts: w[1] <= casting,
                receives: !shade_free.iter().any(|r| r.contains(&w[0])),
                moves: false,
            });
        }
        Ok(g)
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
                    out.extend(transform_normal(&n, q));
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
    write_world_boxes(&mut out, boxes, casts, transforms);
    out
}

/// [`world_boxes`] into `out`, in place (its vectors keep their capacity: this runs on every
/// `set_transforms`).
fn write_world_boxes(out: &mut Boxes, boxes: &[Option<[[f32; 3]; 2]>], casts: &[bool], transforms: &[[f32; 16]]) {
    out.casters.clear();
    out.others.clear();
    for ((b, &c), t) in boxes.iter().zip(casts).zip(transforms) {
        let Some(b) = b else { continue };
        let placed = box_of((0..8).map(|i| transform_point(t, [0, 1, 2].map(|a| b[(i >> a) & 1][a]))));
        if let Some(w) = placed {
            if c { &mut out.casters } else { &mut out.others }.push(w);
        }
    }
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
    /// Edges the classification runs over: up to the last in use, the holes left by
    /// removed instances included (their edges zeroed: an edge of no face is never a
    /// silhouette).
    pub extent: u32,
    pub counts: AdjacencyCounts,
}

/// A host geometry as every light's resources take it: its draws, and its edges when a
/// graph classifies silhouettes.
pub(crate) struct HostScene {
    pub draw: SceneDraw,
    pub edges: Option<EdgeBuffers>,
}

/// One draw of the scene: a range of indices (or of vertices, for a mesh listed out) from
/// one of the draw's vertex buffers, with its base vertex, and whether the light's views
/// draw it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DrawRange {
    /// Index into [`SceneDraw::buffers`].
    pub buffer: usize,
    pub elements: std::ops::Range<u32>,
    pub base_vertex: i32,
    /// `elements` are indices into the index buffer; else vertices ([`Mesh::listed_out`]).
    pub indexed: bool,
    pub casts: bool,
}

/// What a scene draw binds and draws: the vertex buffers (the placed vertices, the meshes'
/// vertices placed on the GPU, the world-space meshes' vertices) and the meshes' index
/// buffer, one draw per instance.
#[derive(Clone)]
pub(crate) struct SceneDraw {
    pub buffers: Vec<wgpu::Buffer>,
    pub indices: wgpu::Buffer,
    pub ranges: Vec<DrawRange>,
    /// The draws of the objects that receive no shadow, drawn again unshadowed
    /// ([`crate::receivers`]); empty when every object receives.
    pub unshadowed: Vec<DrawRange>,
}

impl SceneDraw {
    /// Record the draws into `rp`, a render pass or bundle (the casting ones only when
    /// `from_light`).
    pub fn record<'a>(&'a self, rp: &mut impl wgpu::util::RenderEncoder<'a>, from_light: bool) {
        self.draw(rp, self.ranges.iter().filter(|r| r.casts || !from_light));
    }

    /// Record the draws of the objects that receive no shadow.
    pub fn record_unshadowed<'a>(&'a self, rp: &mut impl wgpu::util::RenderEncoder<'a>) {
        self.draw(rp, self.unshadowed.iter());
    }

    fn draw<'a>(&'a self, rp: &mut impl wgpu::util::RenderEncoder<'a>, ranges: impl Iterator<Item = &'a DrawRange>) {
        let (mut bound, mut indices) = (None, false);
        for r in ranges {
            if bound != Some(r.buffer) {
                rp.set_vertex_buffer(0, Some(self.buffers[r.buffer].slice(..)));
                bound = Some(r.buffer);
            }
            if r.indexed {
                if !std::mem::replace(&mut indices, true) {
                    rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
                }
                rp.draw_indexed(r.elements.clone(), r.base_vertex, 0..1);
            } else {
                rp.draw(r.elements.clone(), 0..1);
            }
        }
    }
}

/// The edges, face planes and face references of a casting instance in world space (`m`
/// `None`) or placed at upload (`m` its transform), written into the placed buffers' bytes
/// (`out`: edges, planes, face references) at `at` (their first places) with `welded` its
/// first welded vertex: what [`place_wgsl`] writes, computed on the CPU. In world space, as
/// under the identity, with no arithmetic on the values (the face and welded-vertex indices
/// offset, the planes as they are, none mirrored); placed, the end points by
/// [`transform_point`] and the planes `(N n, d - (N n) . t)` with the normal matrix,
/// negated where `m` mirrors.
fn write_placed(a: &Adjacency, at: [u32; 3], welded: u32, m: Option<&[f32; 16]>, out: &mut [Vec<u8>; 3]) {
    let [edges, planes, faces] = at.map(|x| x as usize);
    let place = |p: [f32; 3]| m.map_or(p, |m| transform_point(m, p));
    for (k, e) in a.edges.iter().enumerate() {
        let placed = crate::adjacency::GpuEdge {
            a: place(e.a),
            b: place(e.b),
            first_face: e.first_face + faces as u32,
            ia: e.ia + welded,
            ib: e.ib + welded,
            ..*e
        };
        out[0][(edges + k) * 48..(edges + k + 1) * 48].copy_from_slice(&placed.to_bytes());
    }
    let normal = m.map(|m| {
        (
            normal_matrix(m).unwrap_or(IDENTITY),
            if determinant3(m) < 0.0 { -1.0f32 } else { 1.0 },
        )
    });
    for (k, p) in a.planes.iter().enumerate() {
        let plane = match (m, &normal) {
            (Some(m), Some((n, side))) => {
                let q = transform_normal(n, [p[0], p[1], p[2]]);
                let d = p[3] - (q[0] * m[12] + q[1] * m[13] + q[2] * m[14]);
                [q[0], q[1], q[2], d].map(|x| side * x)
            }
            _ => *p,
        };
        for (c, x) in plane.into_iter().enumerate() {
            let at = (planes + k) * 16 + 4 * c;
            out[1][at..at + 4].copy_from_slice(&x.to_le_bytes());
        }
    }
    for (k, f) in a.edge_faces.iter().enumerate() {
        let placed = (((f >> 1) + planes as u32) << 1) | (f & 1);
        out[2][(faces + k) * 4..(faces + k + 1) * 4].copy_from_slice(&placed.to_le_bytes());
    }
}

/// A mesh's vertices placed by `m` on the CPU, as [`Geometry::soup`] places them (position
/// and normal, 24 bytes a vertex).
fn placed_copy(mesh: &Mesh, m: &[f32; 16]) -> Vec<u8> {
    let n = normal_matrix(m).unwrap_or(IDENTITY);
    let mut out = Vec::with_capacity(mesh.positions.len() * 24);
    for (p, q) in mesh.positions.iter().zip(&mesh.normals) {
        let p = transform_point(m, *p);
        let q = transform_normal(&n, *q);
        for x in p.into_iter().chain(q) {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    out
}

/// The placement step's shaders: `Placement` and `Edge` are the schema's
/// (`sshc_graph::PLACEMENT_WGSL`, `EDGE_WGSL`: one definition each, checked against
/// naga's layout), then [`PLACE_BODY`].
fn place_wgsl() -> String {
    format!("{}{}{PLACE_BODY}", sshc_graph::PLACEMENT_WGSL, sshc_graph::EDGE_WGSL)
}

/// The placement step's bindings and entry points: each instance's `Placement` (a
/// 256-byte record read at a dynamic offset) moves its mesh's vertices, edges, face planes
/// and face references into the scene's world-space buffers.
const PLACE_BODY: &str = "
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

/// Refuse mesh `i` when it cannot be drawn: a normal count that is not the position count,
/// an index count not a multiple of 3, an index out of range, a value not finite.
pub(crate) fn check_mesh(i: usize, m: &Mesh) -> Result<()> {
    let bad = |m: String| Err(RuntimeError::Param(m));
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
    if !m.indices.len().is_multiple_of(3) {
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
    Ok(())
}

/// A mesh's edge adjacency in object space: [`Adjacency::build`] of its triangles listed
/// out, as one mesh.
fn adjacency_of(m: &Mesh) -> Adjacency {
    let tris: Vec<[[f32; 3]; 3]> = m
        .indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize]))
        .collect();
    Adjacency::build(&tris, std::iter::once(0..tris.len()))
}

/// An instance's draw: its placed vertices, or (in world space) its mesh's own, where the
/// mesh lies (among the world-space ones when it is there, else among the placed ones);
/// its indices, or its vertices listed out.
fn draw_range(m: &MeshSlot, s: &InstanceSlot, casts: bool) -> Result<DrawRange> {
    let (buffer, base) = match (s.vertices, m.at) {
        (Some(v), _) => (0, v),
        (None, [_, Some(v)]) => (2, v),
        (None, [Some(v), None]) => (1, v),
        (None, [None, None]) => {
            return Err(RuntimeError::NotFound(format!("instance of mesh {} with no vertices", s.mesh)));
        }
    };
    Ok(match m.first_index {
        None => DrawRange {
            buffer,
            elements: base..base + m.elements,
            base_vertex: 0,
            indexed: false,
            casts,
        },
        Some(first) => DrawRange {
            buffer,
            elements: first..first + m.elements,
            base_vertex: i32::try_from(base).map_err(|_| RuntimeError::Limit {
                what: "vertices of one vertex buffer (a base vertex is an i32)".into(),
                needed: base.into(),
                limit: i32::MAX as u64,
            })?,
            indexed: true,
            casts,
        },
    })
}

/// One instance's placement record: its matrix and normal matrix, then its spans (the
/// schema's `Placement`), padded to [`RECORD_BYTES`].
fn record_of(t: &[f32; 16], s: &Spans) -> [u8; RECORD_BYTES as usize] {
    let mut r = [0u8; RECORD_BYTES as usize];
    // a mirroring matrix turns the winding: the planes are negated to follow it
    let mirrors = determinant3(t) < 0.0;
    let placement = sshc_graph::PlacementUniform {
        model: *t,
        normal: normal_matrix(t).unwrap_or(IDENTITY),
        vertices: [s.vertices[0], s.vertices[1], s.vertices[2], 0],
        edges: [s.edges[0], s.edges[1], s.edges[2], s.welded],
        planes: [s.planes[0], s.planes[1], s.planes[2], u32::from(mirrors)],
        faces: [s.faces[0], s.faces[1], s.faces[2], s.planes[2]],
    };
    r[..sshc_graph::PLACEMENT_SIZE as usize].copy_from_slice(&placement.to_array());
    r
}

/// Where a mesh lies in a scene's buffers.
#[derive(Clone, Debug)]
pub(crate) struct MeshSlot {
    pub vertices: u32,
    /// Its indices (its vertices when listed out).
    pub elements: u32,
    /// Its first index in the index buffer; `None` when listed out ([`Mesh::listed_out`]).
    pub first_index: Option<u32>,
    /// Its first vertex among the meshes the placement step reads (0) and among those
    /// drawn in world space only (1): one at upload, both once an instance added later
    /// places a mesh uploaded for world space only.
    pub at: [Option<u32>; 2],
    /// Its adjacency where the placement step reads it: uploaded when a casting instance
    /// placed on the GPU needs it.
    pub edges: Option<EdgeSpan>,
    /// Its box in object space.
    pub bbox: Option<[[f32; 3]; 2]>,
}

/// Edges, face planes, face references and welded vertices: where the first of each lies
/// and how many, with the adjacency's counts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeSpan {
    pub first: [u32; 4],
    pub len: [u32; 4],
    pub counts: AdjacencyCounts,
}

impl EdgeSpan {
    pub fn of(a: &Adjacency, first: [u32; 4]) -> EdgeSpan {
        EdgeSpan {
            first,
            len: [a.edges.len() as u32, a.planes.len() as u32, a.edge_faces.len() as u32, a.vertices],
            counts: a.counts,
        }
    }
}

/// Where an instance's placed data lie.
#[derive(Clone, Debug)]
pub(crate) struct InstanceSlot {
    pub mesh: usize,
    /// Its placement record (the record's index in the records buffer).
    pub record: u32,
    /// Its first placed vertex; `None` in world space (drawn from its mesh).
    pub vertices: Option<u32>,
    /// Its placed edges, face planes, face references and welded vertices (a casting one).
    pub edges: Option<EdgeSpan>,
    pub receives: bool,
}

/// What changed in a scene since its upload, counted, so that the targets made on it know
/// what to take again ([`crate::gpu::Targets::set_scene`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Changes {
    /// Meshes or instances added or removed: the draws are recorded again.
    pub draws: u64,
    /// Buffers made again (a pool grew) or edges added or removed: the steps that bind the
    /// scene are bound again.
    pub bindings: u64,
    /// Times a buffer grew ([`Pools::grown`]).
    pub grown: u64,
    /// Bytes written by the changes (vertices, indices, adjacency, placement records).
    pub uploaded: u64,
}

/// A scene's buffers, each with its free space ([`Pool`]).
pub(crate) struct Pools {
    /// The vertices of the meshes the placement step reads (storage and vertex).
    pub meshes: Pool,
    /// The vertices of the meshes drawn in world space only (vertex).
    pub world: Pool,
    pub indices: Pool,
    pub mesh_edges: Pool,
    pub mesh_planes: Pool,
    pub mesh_faces: Pool,
    /// The placed vertices of the instances not in world space.
    pub placed: Pool,
    pub edges: Pool,
    pub planes: Pool,
    pub faces: Pool,
    pub claims: Pool,
    pub records: Pool,
}

impl Pools {
    /// The draw's vertex buffers, in [`DrawRange::buffer`]'s order: placed, meshes placed
    /// on the GPU, world-space meshes.
    pub fn vertex_buffers(&self) -> Vec<wgpu::Buffer> {
        vec![self.placed.buffer.clone(), self.meshes.buffer.clone(), self.world.buffer.clone()]
    }

    /// Times any buffer was made again.
    pub fn grown(&self) -> u64 {
        [
            &self.meshes,
            &self.world,
            &self.indices,
            &self.mesh_edges,
            &self.mesh_planes,
            &self.mesh_faces,
            &self.placed,
            &self.edges,
            &self.planes,
            &self.faces,
            &self.claims,
            &self.records,
        ]
        .iter()
        .map(|p| p.grown())
        .sum()
    }

    /// The placement step's group: the first record, the meshes' and the placed buffers.
    /// The buffers the placement step binds whole, in its bindings' order (1 to 8).
    pub fn bound(&self) -> [&Pool; 8] {
        [
            &self.meshes,
            &self.placed,
            &self.mesh_edges,
            &self.edges,
            &self.mesh_planes,
            &self.planes,
            &self.mesh_faces,
            &self.faces,
        ]
    }

    pub fn place_group(&self, device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::BindGroup {
        let bound = self.bound();
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &self.records.buffer,
                offset: 0,
                size: wgpu::BufferSize::new(RECORD_BYTES),
            }),
        }];
        entries.extend(bound.iter().enumerate().map(|(i, p)| wgpu::BindGroupEntry {
            binding: i as u32 + 1,
            resource: p.buffer.as_entire_binding(),
        }));
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("place instances"),
            layout,
            entries: &entries,
        })
    }
}

/// The entry points of the placement shader, with the span each dispatches over.
const STEPS: [&str; 4] = ["place_vertices", "place_edges", "place_planes", "place_faces"];

/// A host geometry on the GPU: the meshes, the placed vertices (and, for graphs that
/// classify silhouettes, the placed edges, face planes and face references), the placement
/// step, and the draws. Shared by every light.
pub(crate) struct GeometryBuffers {
    pub scene: HostScene,
    /// The buffers `scene` draws and classifies, with their free space.
    pools: Pools,
    /// The placement step's layout (its group is made again when a bound buffer grows).
    layout: wgpu::BindGroupLayout,
    /// Per mesh: where it lies (`None` once removed).
    meshes: Vec<Option<MeshSlot>>,
    /// Per instance, in draw order: where its placed data lie.
    slots: Vec<InstanceSlot>,
    /// The scene classifies silhouettes: every casting instance has placed edges.
    edges_on: bool,
    /// What changed since the upload (for the targets made on it).
    pub changes: Changes,
    /// The placement records' bytes as last written (their vector reused every frame).
    record_bytes: Vec<u8>,
    pipelines: Vec<wgpu::ComputePipeline>,
    group: Option<wgpu::BindGroup>,
    spans: Vec<Spans>,
    /// Some instance is placed on the GPU (its vertices, or its edges): the placement step
    /// has work.
    places: bool,
    /// Per instance: whether its transform may change ([`Instance::moves`]).
    moves: Vec<bool>,
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
    ///
    /// Instances in world space ([`Instance::in_world_space`]) are drawn from their mesh's
    /// vertices, and their edges, face planes and face references are written here, as the
    /// placement step writes them under the identity (offsets added, values as they are).
    /// The meshes' vertices are two buffers: those of meshes an instance places on the GPU
    /// (bound as storage by the placement step) and those drawn in world space only (a
    /// vertex buffer, free of the storage-binding limit).
    pub fn new(gpu: &Gpu, g: &Geometry, edges: bool) -> Result<GeometryBuffers> {
        g.check(&gpu.limits)?;
        let words = |v: &mut Vec<u8>, x: &[u32]| v.extend(x.iter().flat_map(|w| w.to_le_bytes()));
        let world: Vec<bool> = g.instances.iter().map(Instance::in_world_space).collect();
        let on_gpu = g.placed_on_gpu();
        // per mesh: whether a casting instance places it, and whether one places it on the GPU
        let (mut casts_any, mut casts_on_gpu) = (vec![false; g.meshes.len()], vec![false; g.meshes.len()]);
        for inst in g.instances.iter().filter(|i| i.casts) {
            casts_any[inst.mesh] = true;
            casts_on_gpu[inst.mesh] |= inst.moves;
        }
        // the meshes, one after the other, and their adjacency; per mesh: its vertex buffer
        // (0: placed on the GPU, 1: world space only), first vertex there, first index, and
        // (for meshes the placement step reads) first edge, plane and face reference
        let mut first = Vec::new();
        // vertices per buffer (written straight into the upload's staging memory, below:
        // no copy of every vertex is made here, a soup's would be as large as the soup)
        let (mut vertex_counts, mut index_data) = ([0u64; 2], Vec::new());
        let (mut edge_data, mut plane_data, mut face_data) = (Vec::new(), Vec::new(), Vec::new());
        let mut adjacency: Vec<Option<Adjacency>> = Vec::new();
        let mut listed = Vec::new();
        let mut mesh_slots = Vec::with_capacity(g.meshes.len());
        for (mi, m) in g.meshes.iter().enumerate() {
            let bucket = usize::from(!on_gpu[mi]);
            first.push([
                bucket as u32,
                vertex_counts[bucket] as u32,
                (index_data.len() / 4) as u32,
                (edge_data.len() / 48) as u32,
                (plane_data.len() / 16) as u32,
                (face_data.len() / 4) as u32,
            ]);
            vertex_counts[bucket] += m.positions.len() as u64;
            listed.push(m.listed_out());
            if !listed[mi] {
                words(&mut index_data, &m.indices);
            }
            let adj = (edges && casts_any[mi]).then(|| adjacency_of(m));
            let f = first[mi];
            let mut slot = MeshSlot {
                vertices: m.positions.len() as u32,
                elements: m.indices.len() as u32,
                first_index: (!listed[mi]).then_some(f[2]),
                at: [None; 2],
                edges: None,
                bbox: box_of(m.positions.iter().copied()),
            };
            slot.at[bucket] = Some(f[1]);
            if let (Some(a), true) = (&adj, casts_on_gpu[mi]) {
                edge_data.extend(a.edges.iter().flat_map(|e| e.to_bytes()));
                plane_data.extend(a.planes.iter().flatten().flat_map(|x| x.to_le_bytes()));
                words(&mut face_data, &a.edge_faces);
                slot.edges = Some(EdgeSpan::of(a, [f[3], f[4], f[5], 0]));
            }
            mesh_slots.push(Some(slot));
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
        // The classification binds the edges in chunks (`EdgeBuffers::chunks`): one buffer
        // holds them all. The placement step binds them whole, so instances placed on the
        // GPU keep their edges within one binding.
        let places_on_gpu = g.instances.iter().any(|i| i.moves);
        let edge_limit = if places_on_gpu { storage_limit } else { gpu.limits.max_buffer_size };
        if totals[0] * 48 > edge_limit {
            return Err(RuntimeError::Limit {
                what: if places_on_gpu {
                    "placed edges (bytes; instances placed on the GPU bind their edges whole)".into()
                } else {
                    "edges (bytes, in one buffer)".into()
                },
                needed: totals[0] * 48,
                limit: edge_limit,
            });
        }
        for (what, needed) in [
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
        // the edges of the casting instances in world space or placed at upload, written here
        let world_edges = g.instances.iter().any(|i| !i.moves && i.casts && adjacency[i.mesh].is_some());
        let mut placed_data = [Vec::new(), Vec::new(), Vec::new()];
        if world_edges {
            placed_data = [totals[0] * 48, totals[1] * 16, totals[2] * 4].map(|n| vec![0u8; n as usize]);
        }
        // the instances, one after the other: draws, and spans of what they place
        let (mut ranges, mut spans, mut unshadowed) = (Vec::new(), Vec::new(), Vec::new());
        let mut placed = Spans::default();
        let mut counts = AdjacencyCounts::default();
        // the instances placed at upload and the first of their placed vertices
        let mut at_upload = Vec::new();
        let mut slots = Vec::with_capacity(g.instances.len());
        for (i, (inst, &w)) in g.instances.iter().zip(&world).enumerate() {
            let m = &g.meshes[inst.mesh];
            let f = first[inst.mesh];
            let mut s = Spans {
                welded: placed.welded,
                ..Default::default()
            };
            if inst.moves {
                s.vertices = [f[1], m.positions.len() as u32, placed.vertices[2]];
            }
            if inst.placed_at_upload() {
                at_upload.push((inst, placed.vertices[2]));
            }
            let mut slot = InstanceSlot {
                mesh: inst.mesh,
                record: i as u32,
                vertices: (!w).then_some(placed.vertices[2]),
                edges: None,
                receives: inst.receives,
            };
            if let Some(mesh) = &mesh_slots[inst.mesh] {
                let r = draw_range(mesh, &slot, inst.casts)?;
                if !inst.receives {
                    unshadowed.push(r.clone());
                }
                ranges.push(r);
            }
            if !w {
                placed.vertices[2] += m.positions.len() as u32;
            }
            if let (true, Some(a)) = (inst.casts, &adjacency[inst.mesh]) {
                let at = [placed.edges[2], placed.planes[2], placed.faces[2]];
                slot.edges = Some(EdgeSpan::of(a, [at[0], at[1], at[2], placed.welded]));
                if !inst.moves {
                    // in world space as it is, else placed here under its transform
                    write_placed(a, at, placed.welded, (!w).then_some(&inst.transform), &mut placed_data);
                } else {
                    s.edges = [f[3], a.edges.len() as u32, at[0]];
                    s.planes = [f[4], a.planes.len() as u32, at[1]];
                    s.faces = [f[5], a.edge_faces.len() as u32, at[2]];
                }
                placed.edges[2] += a.edges.len() as u32;
                placed.planes[2] += a.planes.len() as u32;
                placed.faces[2] += a.edge_faces.len() as u32;
                placed.welded += a.vertices;
                counts.add(&a.counts, 1);
            }
            spans.push(s);
            slots.push(slot);
        }
        let places = spans
            .iter()
            .any(|s| s.vertices[1] > 0 || s.edges[1] > 0 || s.planes[1] > 0 || s.faces[1] > 0);
        gpu.scoped("uploading the host geometry", || {
            let device = &gpu.device;
            let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    // a binding may not be empty
                    size: crate::pool::buffer_bytes(size, 1),
                    // written and grown later: a mesh or an instance added (`Pool`)
                    usage: usage | Pool::COPIES,
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
            let vertex = wgpu::BufferUsages::VERTEX;
            let vertices_of = |label: &str, bucket: usize, usage: wgpu::BufferUsages| {
                let b = buffer(label, vertex_counts[bucket] * 24, usage | wgpu::BufferUsages::COPY_DST);
                let meshes = g.meshes.iter().zip(&first).filter(|(_, f)| f[0] as usize == bucket);
                if let Some(size) = wgpu::BufferSize::new(vertex_counts[bucket] * 24)
                    && let Some(mut view) = gpu.queue.write_buffer_with(&b, 0, size)
                {
                    // in pieces of 1 MiB: the view is write-only memory, written in slices
                    let floats = meshes
                        .flat_map(|(m, _)| m.positions.iter().zip(&m.normals))
                        .flat_map(|(p, n)| p.iter().chain(n));
                    let (mut piece, mut at) = (Vec::with_capacity(1 << 20), 0);
                    for c in floats {
                        piece.extend(c.to_le_bytes());
                        if piece.len() == 1 << 20 {
                            view.slice(at..at + piece.len()).copy_from_slice(&piece);
                            at += piece.len();
                            piece.clear();
                        }
                    }
                    view.slice(at..at + piece.len()).copy_from_slice(&piece);
                }
                b
            };
            let meshes = vertices_of("mesh vertices", 0, storage | vertex);
            let world_vertices = vertices_of("world-space mesh vertices", 1, vertex);
            let indices = upload("mesh indices", &index_data, wgpu::BufferUsages::INDEX);
            let mesh_edges = upload("mesh edges", &edge_data, storage);
            let mesh_planes = upload("mesh face planes", &plane_data, storage);
            let mesh_faces = upload("mesh face references", &face_data, storage);
            let placed_vertices = buffer(
                "placed vertices",
                u64::from(placed.vertices[2]) * 24,
                storage | vertex | wgpu::BufferUsages::COPY_DST,
            );
            for &(inst, first) in &at_upload {
                let bytes = placed_copy(&g.meshes[inst.mesh], &inst.transform);
                if !bytes.is_empty() {
                    gpu.queue.write_buffer(&placed_vertices, u64::from(first) * 24, &bytes);
                }
            }
            let placed_of = |label: &str, k: usize, bytes: u64| {
                if world_edges {
                    upload(label, &placed_data[k], storage)
                } else {
                    buffer(label, bytes, storage)
                }
            };
            let placed_edges = placed_of("placed edges", 0, u64::from(placed.edges[2]) * 48);
            let placed_planes = placed_of("placed face planes", 1, u64::from(placed.planes[2]) * 16);
            let placed_faces = placed_of("placed face references", 2, u64::from(placed.faces[2]) * 4);
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
                source: wgpu::ShaderSource::Wgsl(place_wgsl().into()),
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
            let limit = gpu.limits.max_buffer_size;
            let storage_limit = gpu.limits.max_storage_buffer_binding_size.min(limit);
            let vertex = wgpu::BufferUsages::VERTEX;
            let storage = wgpu::BufferUsages::STORAGE;
            let pools = Pools {
                meshes: Pool::adopt(meshes, "mesh vertices", storage | vertex, 24, vertex_counts[0], storage_limit),
                world: Pool::adopt(world_vertices, "world-space mesh vertices", vertex, 24, vertex_counts[1], limit),
                indices: Pool::adopt(
                    indices,
                    "mesh indices",
                    wgpu::BufferUsages::INDEX,
                    4,
                    index_data.len() as u64 / 4,
                    limit,
                ),
                mesh_edges: Pool::adopt(mesh_edges, "mesh edges", storage, 48, edge_data.len() as u64 / 48, storage_limit),
                mesh_planes: Pool::adopt(
                    mesh_planes,
                    "mesh face planes",
                    storage,
                    16,
                    plane_data.len() as u64 / 16,
                    storage_limit,
                ),
                mesh_faces: Pool::adopt(
                    mesh_faces,
                    "mesh face references",
                    storage,
                    4,
                    face_data.len() as u64 / 4,
                    storage_limit,
                ),
                placed: Pool::adopt(
                    placed_vertices,
                    "placed vertices",
                    storage | vertex,
                    24,
                    placed.vertices[2].into(),
                    storage_limit,
                ),
                edges: Pool::adopt(placed_edges, "placed edges", storage, 48, placed.edges[2].into(), storage_limit),
                planes: Pool::adopt(
                    placed_planes,
                    "placed face planes",
                    storage,
                    16,
                    placed.planes[2].into(),
                    storage_limit,
                ),
                faces: Pool::adopt(
                    placed_faces,
                    "placed face references",
                    storage,
                    4,
                    placed.faces[2].into(),
                    storage_limit,
                ),
                // one more than the welded vertices: never empty
                claims: Pool::adopt(claims, "vertex claims", storage, 4, u64::from(placed.welded) + 1, storage_limit),
                records: Pool::adopt(
                    records,
                    "placement records",
                    wgpu::BufferUsages::UNIFORM,
                    RECORD_BYTES,
                    g.instances.len() as u64,
                    limit,
                ),
            };
            // bound only when some instance is placed on the GPU: world-space edges may
            // exceed one binding (they are classified in chunks)
            let group = places.then(|| pools.place_group(device, &layout));
            let mut out = GeometryBuffers {
                scene: HostScene {
                    draw: SceneDraw {
                        buffers: pools.vertex_buffers(),
                        indices: pools.indices.buffer.clone(),
                        ranges,
                        unshadowed,
                    },
                    edges: edges.then(|| EdgeBuffers {
                        edges: pools.edges.buffer.clone(),
                        planes: pools.planes.buffer.clone(),
                        edge_faces: pools.faces.buffer.clone(),
                        claims: pools.claims.buffer.clone(),
                        extent: placed.edges[2],
                        counts,
                    }),
                },
                pools,
                layout,
                pipelines,
                group,
                spans,
                places,
                meshes: mesh_slots,
                slots,
                edges_on: edges,
                changes: Changes::default(),
                moves: g.instances.iter().map(|i| i.moves).collect(),
                dirty: true,
                transforms: g.instances.iter().map(|i| i.transform).collect(),
                casts: g.instances.iter().map(|i| i.casts).collect(),
                boxes: g
                    .instances
                    .iter()
                    .map(|i| box_of(g.meshes[i.mesh].positions.iter().copied()))
                    .collect(),
                world: Boxes::default(),
                record_bytes: Vec::new(),
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
            if !self.moves[i] && t.map(f32::to_bits) != self.transforms[i].map(f32::to_bits) {
                return Err(RuntimeError::Param(format!(
                    "instance {i} does not move (`Instance::moves` is false): its transform stays the one it was bound with"
                )));
            }
        }
        Ok(())
    }

    /// Take a set of transforms ([`GeometryBuffers::check_transforms`] passed): the
    /// placement records are written and placement runs in the next frame.
    pub fn write_transforms(&mut self, queue: &wgpu::Queue, transforms: &[[f32; 16]]) {
        self.transforms.copy_from_slice(transforms);
        write_world_boxes(&mut self.world, &self.boxes, &self.casts, &self.transforms);
        self.write_records(queue);
    }

    /// Write every placement record and mark placement due.
    fn write_records(&mut self, queue: &wgpu::Queue) {
        // kept from one frame to the next: nothing is allocated per frame
        let mut bytes = std::mem::take(&mut self.record_bytes);
        let records = self.slots.iter().map(|s| s.record as usize + 1).max().unwrap_or(0);
        bytes.resize(records * RECORD_BYTES as usize, 0);
        for ((t, s), slot) in self.transforms.iter().zip(&self.spans).zip(&self.slots) {
            let i = slot.record as usize * RECORD_BYTES as usize;
            bytes[i..i + RECORD_BYTES as usize].copy_from_slice(&record_of(t, s));
        }
        if !bytes.is_empty() {
            queue.write_buffer(&self.pools.records.buffer, 0, &bytes);
        }
        self.record_bytes = bytes;
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

    /// Whether the next frame places the instances (their transforms changed since the
    /// last frame was prepared); the question clears the flag.
    pub fn take_due(&mut self) -> bool {
        std::mem::take(&mut self.dirty) && self.places
    }

    /// Record the placement of every instance (its vertices, and its edges, planes and face
    /// references where it has them): where [`GeometryBuffers::take_due`] said so for the
    /// frame. Placing twice gives the same world-space copies.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let Some(group) = &self.group else { return };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("place instances"),
            timestamp_writes: None,
        });
        for (step, pipeline) in self.pipelines.iter().enumerate() {
            pass.set_pipeline(pipeline);
            for (s, slot) in self.spans.iter().zip(&self.slots) {
                let count = [s.vertices, s.edges, s.planes, s.faces][step][1];
                if count == 0 {
                    continue;
                }
                pass.set_bind_group(0, group, &[(u64::from(slot.record) * RECORD_BYTES) as u32]);
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

#[cfg(test)]
// lists of one range are meant: a soup's mesh and unshadowed ranges
#[allow(clippy::single_range_in_vec_init)]
mod tests {
    use super::*;

    /// `n` triangles of a soup, each corner's position `(t, k, 0)` and normal up.
    fn soup(n: u32) -> Vec<f32> {
        (0..n)
            .flat_map(|t| (0..3).flat_map(move |k| [t as f32, k as f32, 0.0, 0.0, 1.0, 0.0]))
            .collect()
    }

    #[test]
    fn a_soup_becomes_one_world_space_instance_per_object_in_its_order() {
        // casters: meshes 0..2 and 2..3; triangle 3 casts in no mesh; 4..6 do not cast,
        // and 5 receives no shadow
        let v = soup(6);
        let g = Geometry::from_soup(&v, &[0..2, 2..3], Some(12), &[15..18]).unwrap();
        let objects: Vec<(usize, bool, bool)> = g
            .instances
            .iter()
            .map(|i| (g.meshes[i.mesh].indices.len() / 3, i.casts, i.receives))
            .collect();
        assert_eq!(
            objects,
            [
                (2, true, true),
                (1, true, true),
                (1, true, true),
                (1, false, true),
                (1, false, false)
            ]
        );
        assert!(g.instances.iter().all(Instance::in_world_space));
        // listed out again, the soup is the same, float for float, and so are its ranges
        let (again, casting) = g.soup().unwrap();
        assert_eq!(
            again.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(casting, 12);
        assert_eq!(g.soup_unshadowed(), [15..18]);
        // no mesh given: the casters are one object, the rest another
        let g = Geometry::from_soup(&v, &[], Some(9), &[]).unwrap();
        let sizes: Vec<usize> = g.meshes.iter().map(|m| m.positions.len() / 3).collect();
        assert_eq!(sizes, [3, 3]);
        // an empty soup is an empty geometry
        assert_eq!(Geometry::from_soup(&[], &[], None, &[]).unwrap(), Geometry::default());
    }

    #[test]
    fn a_soup_whose_ranges_split_an_object_is_refused_saying_where() {
        let v = soup(4);
        let refused = |meshes: &[std::ops::Range<u32>], casting: Option<u32>, unshadowed: &[std::ops::Range<u32>]| {
            Geometry::from_soup(&v, meshes, casting, unshadowed).unwrap_err().to_string()
        };
        let e = Geometry::from_soup(&v[..20], &[], None, &[]).unwrap_err().to_string();
        assert!(e.contains("20 floats, not whole triangles"), "{e}");
        assert!(refused(&[], Some(4), &[]).contains("casting_vertices is 4"));
        assert!(refused(&[], None, &[1..3]).contains("unshadowed range 0 (1..3)"));
        let e = refused(&[0..3], Some(6), &[]);
        assert!(e.contains("0..3 straddle the casting boundary at triangle 2"), "{e}");
        let e = refused(&[0..2, 1..3], None, &[]);
        assert!(e.contains("0..2 and 1..3 overlap"), "{e}");
        let e = refused(&[0..4], None, &[3..6]);
        assert!(e.contains("splits the mesh of triangles 0..4 at triangle 1"), "{e}");
    }
}
