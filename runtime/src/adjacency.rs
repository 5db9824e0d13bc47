//! Edge adjacency of a scene's meshes, built once on the CPU when a scene is bound: the
//! input of the silhouette classification that Geometry passes run on the GPU every frame.
//!
//! Penumbra maps (Wyman & Hansen 2003, section 3) draw a cone at every silhouette vertex
//! and a sheet along every silhouette edge "as seen from the center of the light"; penumbra
//! limit maps and smoothies (Lawlor 2006; Chan & Durand 2003) draw ribbons along the same
//! edges. An edge is a silhouette when the faces around it do not all face the light the
//! same way. Meshes in scenes are not always closed manifolds (the bunny has holes; a
//! plane is a single quad; a fin may share one edge among three faces), so the rule is
//! stated for any number of faces per edge:
//!
//! - 1 face (an open boundary): always a silhouette;
//! - 2 faces (manifold): a silhouette when one faces the light and the other does not;
//! - 3 or more faces (non-manifold): a silhouette when the faces are not all on the same
//!   side, i.e. the 2-face rule applied to every pair.
//!
//! A face faces a point light at `L` when `L` lies strictly in front of its plane
//! (`n . L + d > 0`), and a distant light of direction `D` (towards the light) when
//! `n . D > 0`. An edge-on face counts as facing away, so a silhouette seen edge-on is
//! still classified, never both or neither.
//!
//! Vertices are welded within one mesh by position, within [`WELD_TOLERANCE`] of the
//! mesh's extent (the scene's triangles are a soup; vertices that an indexed mesh shares
//! transform to bit-identical positions, but a mesh exported with its seam duplicated,
//! such as a UV sphere's, has seam vertices a few ulps apart, and welding them only when
//! bit-identical opened the seam into a boundary whose silhouette edges drew ribbons and
//! holes across the sphere; issue 49); meshes are never welded to each other, so a box
//! resting on the floor stays two meshes.
//! Degenerate triangles (two equal welded vertices, zero area or a non-finite vertex)
//! are skipped and counted: they have no plane and cannot cast a silhouette.
//!
//! Sizes are known from the triangle count before anything is allocated: at most
//! `3 t` edges, `t` planes and `3 t` face references for `t` triangles
//! ([`Adjacency::max_bytes`]). Triangle indices are below 2^31 (a scene holds at most
//! 2^24 triangles), so a face reference fits a `u32` with its direction bit.

use std::collections::HashMap;
use std::ops::Range;

/// Vertices of one mesh this close, in every coordinate, as a fraction of the mesh's
/// extent (its bounding box's largest side), are one vertex. 2^-17 of the extent: a seam
/// computed twice in f32 (`cos 0` against `cos 2 pi`) differs by a few ulps, about 2^-23
/// of the coordinate, far inside it; a detail smaller than a 100,000th of its mesh is far
/// below any shadow map's texel (16,384 at most), so no true edge is welded away.
pub const WELD_TOLERANCE: f32 = 1.0 / 131_072.0;

/// The welded vertices of one mesh: exact positions first (a hash of their bits), then a
/// grid of cells [`CELLS_PER_TOLERANCE`] tolerances wide, each a chain of its vertices,
/// searched in the point's cell and in the neighbours it lies within the tolerance of.
struct Weld {
    tolerance: f32,
    cell: f32,
    exact: HashMap<[u32; 3], u32>,
    /// First vertex of each occupied cell; `chain[v]` the next in `v`'s cell (`u32::MAX`: none).
    cells: HashMap<[i64; 3], u32>,
    chain: Vec<u32>,
    welded: Vec<[f32; 3]>,
    /// Vertices joined to another within the tolerance, not bit-identical to it.
    near: u32,
}

/// A grid cell's width in tolerances: wide enough that most points are more than a
/// tolerance from every side of their cell (searched alone), narrow enough that a cell
/// holds few vertices.
const CELLS_PER_TOLERANCE: f32 = 8.0;

impl Weld {
    /// A weld for the triangles of one mesh (its extent from their finite vertices).
    fn new(triangles: &[[[f32; 3]; 3]]) -> Weld {
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in triangles.iter().flatten().filter(|p| p.iter().all(|c| c.is_finite())) {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
        let tolerance = if extent.is_finite() { extent * WELD_TOLERANCE } else { 0.0 };
        Weld {
            tolerance,
            cell: tolerance * CELLS_PER_TOLERANCE,
            exact: HashMap::new(),
            cells: HashMap::new(),
            chain: Vec::new(),
            welded: Vec::new(),
            near: 0,
        }
    }

    /// The cell of `p`, where the grid applies (a finite point, a mesh of some extent).
    fn cell_of(&self, p: [f32; 3]) -> Option<[i64; 3]> {
        let cell = f64::from(self.cell);
        (cell > 0.0 && p.iter().all(|c| c.is_finite())).then(|| p.map(|c| (f64::from(c) / cell).floor() as i64))
    }

    /// The index of `p`'s welded vertex, added when no vertex lies within the tolerance.
    fn id(&mut self, p: [f32; 3]) -> u32 {
        // -0.0 and 0.0 are one position (`+ 0.0` turns the first into the second)
        let key = p.map(|c| (c + 0.0).to_bits());
        if let Some(&i) = self.exact.get(&key) {
            return i;
        }
        let cell = self.cell_of(p);
        let i = match cell.and_then(|c| self.nearby(p, c)) {
            Some(i) => {
                self.near += 1;
                i
            }
            None => {
                let i = self.welded.len() as u32;
                self.welded.push(p);
                let head = cell.and_then(|c| self.cells.insert(c, i));
                self.chain.push(head.unwrap_or(u32::MAX));
                i
            }
        };
        self.exact.insert(key, i);
        i
    }

    /// A welded vertex within the tolerance of `p` in every coordinate, in `p`'s cell `c`
    /// or a neighbour that `p` lies within the tolerance of.
    fn nearby(&self, p: [f32; 3], c: [i64; 3]) -> Option<u32> {
        let cell = f64::from(self.cell);
        let tol = f64::from(self.tolerance);
        // per axis: the neighbour offsets worth searching (0, and -1 or +1 near a side)
        let offsets = |a: usize| {
            let x = f64::from(p[a]) - c[a] as f64 * cell;
            [(x < tol).then_some(-1i64), Some(0), (cell - x < tol).then_some(1)]
        };
        let (ox, oy, oz) = (offsets(0), offsets(1), offsets(2));
        for dx in ox.iter().flatten() {
            for dy in oy.iter().flatten() {
                for dz in oz.iter().flatten() {
                    let mut v = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]).copied().unwrap_or(u32::MAX);
                    while v != u32::MAX {
                        let q = self.welded[v as usize];
                        if (0..3).all(|a| (q[a] - p[a]).abs() <= self.tolerance) {
                            return Some(v);
                        }
                        v = self.chain[v as usize];
                    }
                }
            }
        }
        None
    }
}

/// One edge as the GPU reads it (std430, 48 bytes): the one definition, shared with the
/// compiler's silhouette library and checked against naga's layout, is the schema's.
pub use sshc_graph::GpuEdge;

/// What [`Adjacency::build`] found, for `sshc render` and the tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdjacencyCounts {
    pub meshes: u32,
    pub edges: u32,
    /// Edges with one face.
    pub boundary: u32,
    /// Edges with two faces.
    pub manifold: u32,
    /// Edges with three or more faces.
    pub non_manifold: u32,
    /// Triangles skipped: repeated welded vertex, zero area or non-finite.
    pub degenerate_faces: u32,
    /// Vertex positions joined to another within [`WELD_TOLERANCE`], not bit-identical.
    pub welded_near: u32,
}

impl AdjacencyCounts {
    /// Every count of `other` added (`sign` 1) or taken away (-1): a casting instance
    /// added to or removed from a scene.
    pub(crate) fn add(&mut self, other: &AdjacencyCounts, sign: i32) {
        let f = |x: &mut u32, y: u32| *x = if sign < 0 { x.saturating_sub(y) } else { x.saturating_add(y) };
        f(&mut self.meshes, other.meshes);
        f(&mut self.edges, other.edges);
        f(&mut self.boundary, other.boundary);
        f(&mut self.manifold, other.manifold);
        f(&mut self.non_manifold, other.non_manifold);
        f(&mut self.degenerate_faces, other.degenerate_faces);
        f(&mut self.welded_near, other.welded_near);
    }
}

/// The edge adjacency of every mesh of a scene, in the layout the GPU reads.
#[derive(Clone, Debug, Default)]
pub struct Adjacency {
    pub edges: Vec<GpuEdge>,
    /// One plane per triangle of the input (degenerate ones all zero): unit normal `xyz`
    /// (by the triangle's winding, `(v1 - v0) x (v2 - v0)`) and offset `w = -n . p` for a
    /// point `p` of the triangle.
    pub planes: Vec<[f32; 4]>,
    /// Per edge, its face references (see [`GpuEdge::first_face`]): the triangle's index
    /// into [`Adjacency::planes`] times 2, plus 1 when the triangle's winding runs along
    /// the edge from `b` to `a`. The triangle's interior lies along `n x (q - p)` for the
    /// winding's direction `p -> q`: `n x (b - a)` without the bit, `n x (a - b)` with it.
    pub edge_faces: Vec<u32>,
    /// Number of welded vertices over all meshes.
    pub vertices: u32,
    pub counts: AdjacencyCounts,
}

impl Adjacency {
    /// Bytes of the storage buffers for `triangles` triangles, at most, known before
    /// building: every triangle contributes at most 3 edges, 1 plane, 3 face references
    /// and 3 welded vertices (a `u32` each where something is claimed per vertex).
    pub const fn max_bytes(triangles: u64) -> u64 {
        triangles * (3 * size_of::<GpuEdge>() as u64 + size_of::<[f32; 4]>() as u64 + 3 * 4 + 3 * 4)
    }

    /// Build the adjacency of `meshes`, each a range of triangles of `triangles` (world
    /// space). Ranges outside `triangles` are clipped to it.
    pub fn build(triangles: &[[[f32; 3]; 3]], meshes: impl IntoIterator<Item = Range<usize>>) -> Adjacency {
        let mut out = Adjacency::default();
        // (lo vertex, hi vertex, face reference), per mesh
        let mut faces_of: Vec<(u32, u32, u32)> = Vec::new();
        out.planes = vec![[0.0; 4]; triangles.len()];
        for range in meshes {
            let range = range.start.min(triangles.len())..range.end.min(triangles.len());
            out.counts.meshes += 1;
            let mut weld = Weld::new(&triangles[range.clone()]);
            faces_of.clear();
            for (t, tri) in triangles[range.clone()].iter().enumerate() {
                let t = range.start + t;
                let ids = tri.map(|p| weld.id(p));
                let Some(plane) = plane(tri).filter(|_| ids[0] != ids[1] && ids[1] != ids[2] && ids[0] != ids[2]) else {
                    out.counts.degenerate_faces += 1;
                    continue;
                };
                out.planes[t] = plane;
                for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                    // The winding runs ids[i] -> ids[j]: from b to a when ids[i] is the higher.
                    let (lo, hi, back) = if ids[i] < ids[j] {
                        (ids[i], ids[j], 0)
                    } else {
                        (ids[j], ids[i], 1)
                    };
                    faces_of.push((lo, hi, ((t as u32) << 1) | back));
                }
            }
            // Group the face references by edge: sorting keeps the result independent of
            // hash order, so the buffers are the same on every run.
            faces_of.sort_unstable();
            for group in faces_of.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
                let (lo, hi, _) = group[0];
                let first_face = out.edge_faces.len() as u32;
                out.edge_faces.extend(group.iter().map(|g| g.2));
                let face_count = group.len() as u32;
                match face_count {
                    1 => out.counts.boundary += 1,
                    2 => out.counts.manifold += 1,
                    _ => out.counts.non_manifold += 1,
                }
                out.edges.push(GpuEdge {
                    a: weld.welded[lo as usize],
                    first_face,
                    b: weld.welded[hi as usize],
                    face_count,
                    ia: out.vertices + lo,
                    ib: out.vertices + hi,
                    pad: [0; 2],
                });
            }
            out.vertices += weld.welded.len() as u32;
            out.counts.welded_near += weld.near;
        }
        out.counts.edges = out.edges.len() as u32;
        out
    }

    /// The face references of edge `e` (see [`Adjacency::edge_faces`]).
    pub fn faces(&self, e: &GpuEdge) -> &[u32] {
        let start = e.first_face as usize;
        &self.edge_faces[start..start + e.face_count as usize]
    }

    /// Whether edge `e` is a silhouette from a light at `light`: `xyz` a position with
    /// `w = 1`, or a direction towards the light with `w = 0` (the module's rule). The
    /// CPU statement of what the GPU classification computes.
    pub fn is_silhouette(&self, e: &GpuEdge, light: [f32; 4]) -> bool {
        let faces = self.faces(e);
        if faces.len() == 1 {
            return true;
        }
        let facing = |f: &u32| {
            let [nx, ny, nz, d] = self.planes[(*f >> 1) as usize];
            nx * light[0] + ny * light[1] + nz * light[2] + d * light[3] > 0.0
        };
        let first = facing(&faces[0]);
        faces[1..].iter().any(|f| facing(f) != first)
    }

    /// Number of silhouette edges from `light` (see [`Adjacency::is_silhouette`]).
    pub fn silhouette_count(&self, light: [f32; 4]) -> usize {
        self.edges.iter().filter(|e| self.is_silhouette(e, light)).count()
    }
}

/// The plane of a triangle (unit normal, offset), or `None` when it has no area or a
/// non-finite vertex.
fn plane(t: &[[f32; 3]; 3]) -> Option<[f32; 4]> {
    let sub = |p: [f32; 3], q: [f32; 3]| [f64::from(p[0] - q[0]), f64::from(p[1] - q[1]), f64::from(p[2] - q[2])];
    let (e1, e2) = (sub(t[1], t[0]), sub(t[2], t[0]));
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if !(len.is_finite() && len > 0.0) {
        return None;
    }
    let n = n.map(|c| c / len);
    let p = t[0].map(f64::from);
    let d = -(n[0] * p[0] + n[1] * p[1] + n[2] * p[2]);
    let plane = [n[0] as f32, n[1] as f32, n[2] as f32, d as f32];
    plane.iter().all(|c| c.is_finite()).then_some(plane)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::iter::once;

    /// An axis-aligned unit cube centred on the origin, 12 outward-facing triangles.
    fn cube() -> Vec<[[f32; 3]; 3]> {
        let mut tris = Vec::new();
        for axis in 0..3 {
            for sign in [-0.5f32, 0.5] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |a: f32, b: f32| {
                    let mut p = [0.0; 3];
                    p[axis] = sign;
                    p[u] = a;
                    p[v] = b;
                    p
                };
                let (p00, p10, p11, p01) = (corner(-0.5, -0.5), corner(0.5, -0.5), corner(0.5, 0.5), corner(-0.5, 0.5));
                // Counter-clockwise seen from outside: u x v points along +axis.
                if sign > 0.0 {
                    tris.push([p00, p10, p11]);
                    tris.push([p00, p11, p01]);
                } else {
                    tris.push([p00, p11, p10]);
                    tris.push([p00, p01, p11]);
                }
            }
        }
        tris
    }

    #[test]
    fn a_closed_cube_is_manifold_and_its_silhouette_from_above_is_the_top_square() {
        let tris = cube();
        // Outward normals: the plane offset puts the centre behind every face.
        let adj = Adjacency::build(&tris, once(0..tris.len()));
        for p in &adj.planes {
            assert!(p[3] < 0.0, "face {p:?} does not face outwards");
        }
        let c = adj.counts;
        assert_eq!(
            (c.edges, c.manifold, c.boundary, c.non_manifold, c.degenerate_faces),
            (18, 18, 0, 0, 0)
        );
        // A point light straight above the top face sees the top face only: its 4 outer
        // edges are silhouettes, its diagonal is not.
        assert_eq!(adj.silhouette_count([0.0, 10.0, 0.0, 1.0]), 4);
        // A light off a corner sees three faces: the silhouette is a hexagon.
        assert_eq!(adj.silhouette_count([10.0, 10.0, 10.0, 1.0]), 6);
        // A distant light from above, and from below (w = 0): the same square.
        assert_eq!(adj.silhouette_count([0.0, 1.0, 0.0, 0.0]), 4);
        assert_eq!(adj.silhouette_count([0.0, -1.0, 0.0, 0.0]), 4);
        // Inside the cube every face faces away: no silhouette.
        assert_eq!(adj.silhouette_count([0.0, 0.0, 0.0, 1.0]), 0);
    }

    #[test]
    fn direction_bits_point_each_face_reference_at_its_interior() {
        let mut tris = cube();
        let q = [[-1.0, 2.0, -1.0], [1.0, 2.0, -1.0], [1.0, 2.0, 1.0]];
        tris.push(q);
        let adj = Adjacency::build(&tris, [0..12, 12..13]);
        let (sub, dot) = (
            |p: [f32; 3], q: [f32; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]],
            |p: [f32; 3], q: [f32; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2],
        );
        let cross = |u: [f32; 3], v: [f32; 3]| [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let mut checked = 0;
        for e in &adj.edges {
            let bits: Vec<u32> = adj.faces(e).iter().map(|f| f & 1).collect();
            if bits.len() == 2 {
                assert_ne!(bits[0], bits[1], "a consistently wound closed mesh runs each edge both ways");
            }
            for f in adj.faces(e) {
                let t = tris[(f >> 1) as usize];
                let n = adj.planes[(f >> 1) as usize];
                let dir = if f & 1 == 1 { sub(e.a, e.b) } else { sub(e.b, e.a) };
                let inward = cross([n[0], n[1], n[2]], dir);
                // The triangle's vertex off the edge lies on the inward side.
                let third = t.iter().find(|p| **p != e.a && **p != e.b).expect("a vertex off the edge");
                assert!(dot(inward, sub(*third, e.a)) > 0.0, "edge {e:?}, face {f}");
                checked += 1;
            }
        }
        assert_eq!(checked, 3 * 13);
    }

    #[test]
    fn open_boundaries_are_always_silhouettes() {
        let q = [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]];
        let quad = vec![[q[0], q[2], q[1]], [q[0], q[3], q[2]]];
        let adj = Adjacency::build(&quad, once(0..2));
        let c = adj.counts;
        assert_eq!((c.edges, c.boundary, c.manifold), (5, 4, 1));
        for light in [[0.0, 3.0, 0.0, 1.0], [0.0, -3.0, 0.0, 1.0], [0.3, 1.0, 0.2, 0.0]] {
            assert_eq!(adj.silhouette_count(light), 4, "light {light:?}");
        }
        // The cube with its top face removed: the top square becomes a boundary.
        let open: Vec<_> = cube().into_iter().filter(|t| t.iter().any(|p| p[1] < 0.5)).collect();
        let adj = Adjacency::build(&open, once(0..open.len()));
        assert_eq!((adj.counts.boundary, adj.counts.manifold), (4, 13));
        assert_eq!(adj.silhouette_count([0.0, 10.0, 0.0, 1.0]), 4);
    }

    #[test]
    fn an_edge_shared_by_three_faces_is_non_manifold_and_classified_by_all_of_them() {
        // Three fins around the edge x = 0, z = 0, y in [0, 1].
        let (a, b) = ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let fins = vec![[a, b, [1.0, 0.0, 0.0]], [a, b, [-0.5, 0.0, 0.8]], [b, a, [-0.5, 0.0, -0.8]]];
        let adj = Adjacency::build(&fins, once(0..3));
        assert_eq!(adj.counts.non_manifold, 1);
        let shared = adj.edges.iter().find(|e| e.face_count == 3).expect("the shared edge");
        // Around the edge, the light is on the front of some fins and the back of others, or
        // (in some sectors) on the same side of all three. The side of each fin, from its
        // vertices by a triple product (not from the stored planes):
        let side = |t: &[[f32; 3]; 3], l: [f32; 3]| {
            let sub = |p: [f32; 3], q: [f32; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
            let (u, v, w) = (sub(t[1], t[0]), sub(t[2], t[0]), sub(l, t[0]));
            u[0] * (v[1] * w[2] - v[2] * w[1]) + u[1] * (v[2] * w[0] - v[0] * w[2]) + u[2] * (v[0] * w[1] - v[1] * w[0]) > 0.0
        };
        let mut seen = [false; 2];
        for angle in 0..72 {
            let t = angle as f32 * std::f32::consts::TAU / 72.0 + 0.01;
            let l = [3.0 * t.cos(), 0.5, 3.0 * t.sin()];
            let sides: Vec<bool> = fins.iter().map(|f| side(f, l)).collect();
            let split = sides.iter().any(|&s| s != sides[0]);
            assert_eq!(adj.is_silhouette(shared, [l[0], l[1], l[2], 1.0]), split, "angle {t}");
            seen[usize::from(split)] = true;
        }
        assert_eq!(seen, [true, true], "both cases occur around a three-fin edge");
    }

    #[test]
    fn meshes_are_not_welded_to_each_other_and_degenerate_faces_are_counted() {
        let mut tris = cube();
        let n = tris.len();
        tris.extend(cube()); // a second cube at the same place: a separate mesh
        tris.push([[0.0; 3], [0.0; 3], [1.0, 0.0, 0.0]]); // repeated vertex
        tris.push([[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]); // zero area
        tris.push([[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]); // non-finite
        let adj = Adjacency::build(&tris, [0..n, n..tris.len()]);
        assert_eq!(adj.counts.meshes, 2);
        // A signed zero welds with zero: two triangles meeting at (0, 0, -0) and (0, 0, 0).
        let z = [
            [[0.0, 0.0, -0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
        ];
        assert_eq!(Adjacency::build(&z, once(0..2)).counts.manifold, 1);
        assert_eq!(adj.counts.manifold, 36, "two closed cubes, no edge shared between them");
        assert_eq!(adj.counts.degenerate_faces, 3);
        assert_eq!(adj.edges.len(), 36);
        // Within the bound computed before building.
        let bytes = (adj.edges.len() * size_of::<GpuEdge>() + adj.planes.len() * 16 + adj.edge_faces.len() * 4) as u64;
        assert!(bytes <= Adjacency::max_bytes(tris.len() as u64));
        assert_eq!(size_of::<GpuEdge>(), 48, "std430 layout of the GPU's edge struct");
        // 8 welded corners per cube (not shared between the meshes), and the degenerate
        // triangles' 5 distinct points (welded before their degeneracy shows).
        assert_eq!(adj.vertices, 8 + 8 + 5);
        assert!(adj.edges.iter().all(|e| e.ia < adj.vertices && e.ib < adj.vertices && e.ia != e.ib));
    }

    #[test]
    fn out_of_range_meshes_are_clipped_and_empty_input_is_empty() {
        let adj = Adjacency::build(&[], once(0..10));
        assert_eq!(adj.counts.edges, 0);
        let tris = cube();
        let adj = Adjacency::build(&tris, once(6..100));
        assert_eq!(adj.counts.edges as usize, adj.edges.len());
        assert!(adj.counts.boundary > 0);
    }

    /// A UV sphere of `rings` x `segments` quads, its seam duplicated as exporters write
    /// it: the last column of vertices computed at angle 2 pi, a few ulps from the first
    /// column's at 0. The poles' fans carry one degenerate triangle per quad.
    fn seam_sphere(rings: u32, segments: u32) -> Vec<[[f32; 3]; 3]> {
        let at = |r: u32, s: u32| {
            let (theta, phi) = (
                std::f32::consts::PI * r as f32 / rings as f32,
                std::f32::consts::TAU * s as f32 / segments as f32,
            );
            [theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()]
        };
        let mut tris = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r + 1, s));
                tris.push([a, c, b]);
                tris.push([a, d, c]);
            }
        }
        tris
    }

    /// Issue 49: a sphere whose seam vertices are not bit-identical is closed once welded
    /// within the tolerance (no open boundary, so no silhouette along the seam), and the
    /// seam's welds are counted; points ten tolerances apart stay two vertices (a slit
    /// stays open).
    #[test]
    fn a_seam_a_few_ulps_apart_is_welded_and_a_real_slit_is_not() {
        let tris = seam_sphere(12, 24);
        let seam_differs = (1..12).any(|r| {
            let theta = std::f32::consts::PI * r as f32 / 12.0;
            (theta.sin() * std::f32::consts::TAU.cos()).to_bits() != theta.sin().to_bits()
                || (theta.sin() * std::f32::consts::TAU.sin()).to_bits() != 0.0f32.to_bits()
        });
        assert!(seam_differs, "the seam's two columns differ in their bits");
        let adj = Adjacency::build(&tris, once(0..tris.len()));
        assert_eq!(adj.counts.boundary, 0, "{:?}", adj.counts);
        assert_eq!(adj.counts.non_manifold, 0, "{:?}", adj.counts);
        assert!(adj.counts.welded_near >= 11, "{:?}", adj.counts);
        // 11 rings of 24 vertices and the two poles
        assert_eq!(adj.vertices, 11 * 24 + 2);
        // a slit: two quads side by side whose shared side is split by ten tolerances
        let gap = 10.0 * WELD_TOLERANCE * 2.0;
        let quad = |x0: f32, x1: f32| {
            [
                [[x0, 0.0, 0.0], [x1, 0.0, 0.0], [x1, 0.0, 1.0]],
                [[x0, 0.0, 0.0], [x1, 0.0, 1.0], [x0, 0.0, 1.0]],
            ]
        };
        let [a, b] = quad(-1.0, 0.0);
        let [c, d] = quad(gap, 1.0);
        let slit = Adjacency::build(&[a, b, c, d], once(0..4));
        assert_eq!(slit.counts.boundary, 8, "{:?}", slit.counts);
        assert_eq!(slit.counts.welded_near, 0);
        // and the same quads meeting within the tolerance are one sheet
        let [c, d] = quad(0.1 * WELD_TOLERANCE, 1.0);
        let sheet = Adjacency::build(&[a, b, c, d], once(0..4));
        assert_eq!(sheet.counts.boundary, 6, "{:?}", sheet.counts);
        assert_eq!(sheet.counts.manifold, 3, "{:?}", sheet.counts);
    }
}
