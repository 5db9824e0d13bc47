//! An independent f64 CPU reference of penumbra maps (Wyman & Hansen 2003, section 3),
//! written from the paper alone, without the compiler's code generator.
//!
//! The technique has three passes (section 3): a shadow map rendered from the centre of the
//! light, a penumbra map drawn from cones and sheets at the silhouette "as seen from the
//! center of the light", and the final lookup. This module computes each in f64:
//!
//! 1. [`silhouettes`]: silhouette vertices `V` and edges `E` from the light's centre. Vertices
//!    are welded by exact position within a mesh (never across meshes). An edge is a
//!    silhouette when its faces do not all face the light the same way: 1 face (an open
//!    boundary) always, 2 faces when one faces the light and the other does not, 3 or more
//!    (non-manifold) when they are not all on the same side. A face faces a perspective
//!    light when the light's centre lies strictly in front of its plane, a distant light
//!    when its normal points towards the light; an edge-on face counts as facing away.
//!    Degenerate triangles (a repeated welded vertex, zero area, non-finite) are skipped.
//! 2. [`shadow_map`]: per texel centre, the view depth `Z_P` of the nearest triangle along
//!    the light ray through the centre (ray casting, not rasterisation), within
//!    `[near, far]`; `far` where the ray meets nothing. The Depth pass stores it as
//!    `z = (Z_P - near) / (far - near)` (docs/language.md section 7).
//! 3. [`penumbra_map`]: per texel, every cone and sheet the texel's ray meets, each
//!    intersection a fragment `F` at light depth `Z_F`:
//!    - a **cone** (figure 4, left) per silhouette vertex `v` at depth `Z_v`, tip at `v`,
//!      base on the far plane with radius `C_r = (Z_far - Z_v) L_r / Z_v` (section 3) for a
//!      sphere light of radius `L_r`, or `(Z_far - Z_v) tan(angle / 2)` for a distant disk
//!      of full angular diameter `angle`. The cone's axis is the light ray through `v` (from
//!      the light's centre for a perspective light, along the view direction for an
//!      orthographic one) and its cross-sections at constant depth are circles centred on
//!      that ray, of radius growing linearly from 0 at `Z_v` to `C_r` at `Z_far` (the
//!      paper's triangles "with one vertex at v_i and two on the far plane"). Only the
//!      lateral surface is drawn.
//!    - a **sheet** (figure 4, right) per silhouette edge `(v0, v1)` and per side of the
//!      plane through the light ray and the edge on which no face of the edge lies (the
//!      outer penumbra; both sides for a lone edge-on face, none when faces lie on both):
//!      the ruled surface (bilinear patch) whose rulings join `e(t) = (1 - t) v0 + t v1` to
//!      `T(t) = (1 - t) T0 + t T1`, `T0`, `T1` the points where the outer common tangent of
//!      the two cones' base circles (on that side) touches them; the paper's quad
//!      `v0 v1 T1 T0`, which "may be non-planar". No sheet when one base circle contains the
//!      other (no outer tangent) or the edge is seen end-on (the cones cover it).
//!
//!    `Z_v` of a sheet fragment is interpolated along the edge, `(1 - t) Z_v0 + t Z_v1` at
//!    the ruling `t` the ray meets ("for sheets we use the rasterizer to interpolate between
//!    the Z_vi values of the two adjacent cones"). A fragment is discarded when
//!    `Z_F > Z_P` (pseudocode line 4) and kept otherwise with (equation 1)
//!    `I = (Z_F - Z_v) / (Z_P - Z_v)` and `s = 3 I^2 - 2 I^3` (the Bernstein interpolant
//!    of Parker et al.). Since `Z_v <= Z_F <= Z_P`, `I` lies in `[0, 1]`; when
//!    `Z_P - Z_v <= 0` (a receiver at the silhouette vertex itself) `I = 0` (contact hardens
//!    the shadow). The fragments of a texel are combined by the resolve rule ([`Resolve`],
//!    section 4 and figure 6): `KeepMin` (the darkest wins, the paper's `GL_LESS` depth
//!    test on the intensity), `KeepMax`, `Add` (`1 - sum(1 - s)`) or `Multiply`
//!    (`prod s`); a texel no fragment reaches reads 1 (the map is "cleared to white"), and
//!    the result is clamped to `[0, 1]`.
//! 4. [`visibility`]: the hard shadow-map test (0 when the receiver's normalised depth less
//!    the bias exceeds the stored `z`) times the penumbra map at the receiver's texel
//!    (nearest, clamped to the edge), clamped to `[0, 1]`.
//!
//! Cones and sheets are exact here: analytic oblique cones and ruled surfaces met by rays
//! in f64. The GPU tessellates them: a cone drawn as a `K`-segment polygon inscribed in its
//! base circle misses up to `1 - cos(pi / K)` of the radius between two segment vertices
//! (1.9 % of the penumbra width at K = 16, 0.48 % at K = 32), so its penumbra ends that much
//! early there and `I` reaches 1 a little sooner; a non-planar sheet drawn as two triangles
//! departs from the bilinear patch by up to a quarter of its twist, and the rasteriser
//! interpolates `Z_v` perspective-correctly over those triangles rather than by the ruling
//! parameter `t` used here (equal where `Z_v0 = Z_v1`). Primitives of zero width (a light of
//! radius 0) have no area and draw no fragment, so the map is then all 1.
//!
//! Conventions: everything is computed in the light's view space (world -> view by the
//! column-major `view` matrix, glam's `to_cols_array`; the light looks down `-z`, depths
//! are `-z`). Texel `(i, j)` of the `N x N` map (row-major, row 0 first) has its centre at
//! uv `((i + 0.5) / N, (j + 0.5) / N)`, NDC `x = 2u - 1`, `y = 1 - 2v` (WebGPU: row 0 is
//! the top of the image). A perspective light's ray through NDC `(x, y)` has direction
//! `(x / f, y / f, -1)` from the light's centre, `f = 1 / tan(fov / 2)` (square map); an
//! orthographic light's starts at `(x h, y h, 0)` with direction `(0, 0, -1)`, `h` the half
//! height. Both rays have `d.z = -1` and start at `z = 0`, so the ray parameter is the depth.

use std::collections::HashMap;
use std::ops::Range;

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V3, k: f64) -> V3 {
    [a[0] * k, a[1] * k, a[2] * k]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn len(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn lerp(a: V3, b: V3, t: f64) -> V3 {
    add(a, scale(sub(b, a), t))
}
fn finite(a: V3) -> bool {
    a.iter().all(|c| c.is_finite())
}

/// The light's projection (the square shadow map covers the same extent along x and y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightProjection {
    /// Perspective from the light's centre, `f = 1 / tan(fov / 2)`.
    Perspective { f: f64 },
    /// Orthographic, the map covering `[-half_height, half_height]` along x and y.
    Orthographic { half_height: f64 },
}

/// The area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaLight {
    /// A sphere of radius `radius` (world units) centred on the perspective light's eye: the
    /// paper's `L_r`, cones of radius `(Z_far - Z_v) L_r / Z_v` at the far plane.
    Sphere { radius: f64 },
    /// A distant disk of full angular diameter `angle` radians (orthographic light): cones
    /// grow by `tan(angle / 2)` per unit of depth.
    DistantDisk { angle: f64 },
}

/// How the fragments of one penumbra-map texel combine (section 4, figure 6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolve {
    /// The darkest fragment wins (the paper's default).
    KeepMin,
    /// The brightest fragment wins.
    KeepMax,
    /// `1 - sum(1 - s)`: the shadow contributions summed.
    Add,
    /// `prod s`.
    Multiply,
}

impl Resolve {
    pub const ALL: [Resolve; 4] = [Resolve::KeepMin, Resolve::KeepMax, Resolve::Add, Resolve::Multiply];

    /// Combine the intensities `s` of a texel's fragments: 1 without any, clamped to `[0, 1]`.
    pub fn combine(self, s: &[f64]) -> f64 {
        if s.is_empty() {
            return 1.0;
        }
        let v = match self {
            Resolve::KeepMin => s.iter().copied().fold(f64::INFINITY, f64::min),
            Resolve::KeepMax => s.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Resolve::Add => 1.0 - s.iter().map(|s| 1.0 - s).sum::<f64>(),
            Resolve::Multiply => s.iter().product(),
        };
        if v.is_nan() { 1.0 } else { v.clamp(0.0, 1.0) }
    }
}

/// Everything the reference needs about the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PenumbraSetup {
    /// World -> light view (column-major, glam's `to_cols_array`); the light looks down -z.
    pub view: [f64; 16],
    pub projection: LightProjection,
    /// World distances along the view axis of the depth range (`0 < near < far`).
    pub near: f64,
    pub far: f64,
    /// Shadow- and penumbra-map size `N` (texels per side).
    pub size: usize,
    pub light: AreaLight,
    pub resolve: Resolve,
}

impl PenumbraSetup {
    /// Check ranges: a finite view, `0 < near < far`, `1 <= size <= 4096`, a positive `f` or
    /// half height, a light radius `>= 0` or angle in `[0, pi)`, a sphere light with a
    /// perspective projection and a distant disk with an orthographic one.
    pub fn check(&self) -> Result<(), String> {
        if !self.view.iter().all(|v| v.is_finite()) {
            return Err("the light view matrix must be finite".into());
        }
        if !(self.near.is_finite() && self.far.is_finite() && self.near > 0.0 && self.far > self.near) {
            return Err(format!("need 0 < near < far (near {}, far {})", self.near, self.far));
        }
        if !(1..=4096).contains(&self.size) {
            return Err(format!("the map size {} must lie in 1..=4096", self.size));
        }
        match (self.projection, self.light) {
            (LightProjection::Perspective { f }, AreaLight::Sphere { radius }) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(format!("a perspective light needs f = 1 / tan(fov / 2) > 0, not {f}"));
                }
                if !(radius.is_finite() && radius >= 0.0) {
                    return Err(format!("the light radius {radius} must be finite and >= 0"));
                }
            }
            (LightProjection::Orthographic { half_height }, AreaLight::DistantDisk { angle }) => {
                if !(half_height.is_finite() && half_height > 0.0) {
                    return Err(format!("an orthographic light needs a half height > 0, not {half_height}"));
                }
                if !(angle.is_finite() && (0.0..std::f64::consts::PI).contains(&angle)) {
                    return Err(format!("the distant disk's angle {angle} must lie in [0, pi)"));
                }
            }
            (p, l) => {
                return Err(format!(
                    "a {l:?} needs the matching projection (Sphere: Perspective, DistantDisk: Orthographic), not {p:?}"
                ));
            }
        }
        Ok(())
    }

    fn perspective(&self) -> bool {
        matches!(self.projection, LightProjection::Perspective { .. })
    }

    /// A world point in the light's view space.
    pub fn to_view(&self, p: V3) -> V3 {
        let m = &self.view;
        [
            m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12],
            m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
            m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14],
        ]
    }

    /// The ray through the centre of texel `(i, j)` in view space: origin (at `z = 0`) and
    /// direction (with `z = -1`, so the ray parameter is the depth).
    pub fn texel_ray(&self, i: usize, j: usize) -> (V3, V3) {
        let n = self.size as f64;
        let x = 2.0 * (i as f64 + 0.5) / n - 1.0;
        let y = 1.0 - 2.0 * (j as f64 + 0.5) / n;
        match self.projection {
            LightProjection::Perspective { f } => ([0.0; 3], [x / f, y / f, -1.0]),
            LightProjection::Orthographic { half_height: h } => ([x * h, y * h, 0.0], [0.0, 0.0, -1.0]),
        }
    }

    /// The texel `(i, j)` whose area holds a world point (clamped to the edge), and its view
    /// depth; `None` for a non-finite point or one at or behind a perspective light's eye.
    pub fn texel_of(&self, p: V3) -> Option<(usize, usize, f64)> {
        let q = self.to_view(p);
        let depth = -q[2];
        if !finite(q) {
            return None;
        }
        let (x, y) = match self.projection {
            LightProjection::Perspective { f } => {
                if depth <= 0.0 {
                    return None;
                }
                (q[0] * f / depth, q[1] * f / depth)
            }
            LightProjection::Orthographic { half_height: h } => (q[0] / h, q[1] / h),
        };
        let n = self.size as f64;
        let (u, v) = (0.5 + 0.5 * x, 0.5 - 0.5 * y);
        let last = self.size as i64 - 1;
        let ti = ((u * n).floor().clamp(-1.0, n) as i64).clamp(0, last) as usize;
        let tj = ((v * n).floor().clamp(-1.0, n) as i64).clamp(0, last) as usize;
        Some((ti, tj, depth))
    }

    /// How fast cone cross-sections widen per unit of depth behind a vertex at depth `z_v`:
    /// `L_r / Z_v` (so that the radius is `C_r` at the far plane) or `tan(angle / 2)`.
    pub fn spread(&self, z_v: f64) -> f64 {
        match self.light {
            AreaLight::Sphere { radius } => radius / z_v,
            AreaLight::DistantDisk { angle } => (0.5 * angle).tan(),
        }
    }

    /// The (x, y) of the light ray through the view-space point `v` at depth `z`.
    fn axis_at(&self, v: V3, z: f64) -> [f64; 2] {
        if self.perspective() {
            let k = z / -v[2];
            [v[0] * k, v[1] * k]
        } else {
            [v[0], v[1]]
        }
    }

    /// The normal of the plane holding the light ray(s) through the view-space points `a`
    /// and `b`; side of `x`: the sign of `m . x` (perspective) or `m . (x - a)`
    /// (orthographic), see [`PenumbraSetup::side`].
    fn edge_plane(&self, a: V3, b: V3) -> V3 {
        if self.perspective() {
            cross(a, b)
        } else {
            cross(sub(b, a), [0.0, 0.0, 1.0])
        }
    }

    fn side(&self, m: V3, a: V3, x: V3) -> f64 {
        if self.perspective() { dot(m, x) } else { dot(m, sub(x, a)) }
    }
}

/// A silhouette vertex: its mesh, view-space position and depth `Z_v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SilhouetteVertex {
    pub mesh: usize,
    pub position: V3,
    pub depth: f64,
}

/// A silhouette edge between vertices `a` and `b` (indices into
/// [`Silhouettes::vertices`]), the number of faces around it, and on which sides of the
/// plane through the light ray(s) and the edge a sheet is drawn: `outer[0]` the side where
/// `m . x > 0`, `outer[1]` where `m . x < 0`, with `m = a x b` for a perspective light
/// (view space, the light's centre at the origin) and `m = (b - a) x z` for an orthographic
/// one (measured from `a`). A side is outer when no face of the edge lies on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SilhouetteEdge {
    pub mesh: usize,
    pub a: usize,
    pub b: usize,
    pub faces: usize,
    pub outer: [bool; 2],
}

/// The silhouette from the light's centre.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Silhouettes {
    pub vertices: Vec<SilhouetteVertex>,
    pub edges: Vec<SilhouetteEdge>,
    /// Triangles skipped as degenerate.
    pub degenerate: usize,
    /// Edges (after welding), silhouettes or not.
    pub all_edges: usize,
}

fn weld_key(p: V3) -> [u64; 3] {
    // +0.0 turns -0.0 into +0.0: equal positions weld.
    p.map(|c| (c + 0.0).to_bits())
}

/// Silhouette vertices and edges from the light's centre (see the module documentation).
/// `meshes` are ranges of `triangles`; triangles are in world space.
pub fn silhouettes(triangles: &[[V3; 3]], meshes: &[Range<usize>], setup: &PenumbraSetup) -> Result<Silhouettes, String> {
    setup.check()?;
    let mut out = Silhouettes::default();
    for (mesh, range) in meshes.iter().enumerate() {
        if range.start > range.end || range.end > triangles.len() {
            return Err(format!(
                "mesh {mesh}'s range {range:?} lies outside the {} triangles",
                triangles.len()
            ));
        }
        let mut ids: HashMap<[u64; 3], usize> = HashMap::new();
        let mut view: Vec<V3> = Vec::new();
        // edge (lo, hi) -> faces: (facing, third vertex)
        let mut edges: HashMap<(usize, usize), Vec<(bool, usize)>> = HashMap::new();
        for tri in &triangles[range.clone()] {
            if !tri.iter().all(|p| finite(*p)) {
                out.degenerate += 1;
                continue;
            }
            let t = tri.map(|p| {
                let next = view.len();
                let id = *ids.entry(weld_key(p)).or_insert(next);
                if id == next {
                    view.push(setup.to_view(p));
                }
                id
            });
            let [a, b, c] = t.map(|i| view[i]);
            let n = cross(sub(b, a), sub(c, a));
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || n == [0.0; 3] || !finite(n) {
                out.degenerate += 1;
                continue;
            }
            let facing = if setup.perspective() { -dot(n, a) > 0.0 } else { n[2] > 0.0 };
            for k in 0..3 {
                let (p, q, r) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                edges.entry((p.min(q), p.max(q))).or_default().push((facing, r));
            }
        }
        out.all_edges += edges.len();
        let mut keys: Vec<(usize, usize)> = edges.keys().copied().collect();
        keys.sort_unstable();
        let mut vertex_index: HashMap<usize, usize> = HashMap::new();
        for key in keys {
            let faces = &edges[&key];
            let silhouette = faces.len() == 1 || faces.iter().any(|f| f.0 != faces[0].0);
            if !silhouette {
                continue;
            }
            let (pa, pb) = (view[key.0], view[key.1]);
            let m = setup.edge_plane(pa, pb);
            let mut occupied = [false; 2];
            for &(_, w) in faces {
                let s = setup.side(m, pa, view[w]);
                if s > 0.0 {
                    occupied[0] = true;
                } else if s < 0.0 {
                    occupied[1] = true;
                }
            }
            let outer = if m == [0.0; 3] { [false; 2] } else { [!occupied[0], !occupied[1]] };
            let mut vertex = |id: usize| {
                *vertex_index.entry(id).or_insert_with(|| {
                    out.vertices.push(SilhouetteVertex {
                        mesh,
                        position: view[id],
                        depth: -view[id][2],
                    });
                    out.vertices.len() - 1
                })
            };
            let (a, b) = (vertex(key.0), vertex(key.1));
            out.edges.push(SilhouetteEdge {
                mesh,
                a,
                b,
                faces: faces.len(),
                outer,
            });
        }
    }
    Ok(out)
}

/// The shadow map: per texel, the view depth `Z_P` of the nearest surface (world units),
/// `far` where the texel's ray meets nothing within `[near, far]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowMap {
    pub size: usize,
    pub depth: Vec<f64>,
    /// Whether the ray met a triangle.
    pub hit: Vec<bool>,
}

impl ShadowMap {
    /// The Depth pass's stored value at texel index `k`: `(Z_P - near) / (far - near)`.
    pub fn z(&self, setup: &PenumbraSetup, k: usize) -> f64 {
        (self.depth[k] - setup.near) / (setup.far - setup.near)
    }
}

/// Ray-triangle intersection (Moller-Trumbore, both sides, edges included): the ray
/// parameter, `None` for a miss or a triangle seen edge-on (`linear::ray_hit` without the
/// barycentrics).
pub(crate) fn ray_triangle(o: V3, d: V3, tri: &[V3; 3]) -> Option<f64> {
    crate::reference::linear::ray_hit(o, d, tri).map(|(t, _)| t)
}

/// The shadow map of world-space `triangles` (first pass of section 3), by ray casting.
pub fn shadow_map(triangles: &[[V3; 3]], setup: &PenumbraSetup) -> Result<ShadowMap, String> {
    setup.check()?;
    let tris: Vec<[V3; 3]> = triangles
        .iter()
        .map(|t| t.map(|p| setup.to_view(p)))
        .filter(|t| t.iter().all(|p| finite(*p)))
        .collect();
    let n = setup.size;
    let mut depth = vec![setup.far; n * n];
    let mut hit = vec![false; n * n];
    for j in 0..n {
        for i in 0..n {
            let (o, d) = setup.texel_ray(i, j);
            for t in &tris {
                // the ray parameter is the depth (d.z = -1, o.z = 0)
                if let Some(z) = ray_triangle(o, d, t)
                    && z >= setup.near
                    && z <= setup.far
                    && (!hit[j * n + i] || z < depth[j * n + i])
                {
                    depth[j * n + i] = z;
                    hit[j * n + i] = true;
                }
            }
        }
    }
    Ok(ShadowMap { size: n, depth, hit })
}

/// A cone at a silhouette vertex (section 3, figure 4 left).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Index into [`Silhouettes::vertices`].
    pub vertex: usize,
    pub tip: V3,
    /// `Z_v`.
    pub z_v: f64,
    /// Radius growth per unit of depth (see [`PenumbraSetup::spread`]).
    pub spread: f64,
    /// `C_r`, the radius at the far plane.
    pub base_radius: f64,
}

/// A sheet along a silhouette edge (figure 4 right): the bilinear patch
/// `(1 - s) e(t) + s T(t)`, `e(t) = (1 - t) v0 + t v1`, `T(t) = (1 - t) t0 + t t1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sheet {
    /// Index into [`Silhouettes::edges`].
    pub edge: usize,
    pub v0: V3,
    pub v1: V3,
    /// The outer-tangent points on the far plane.
    pub t0: V3,
    pub t1: V3,
    pub z_v0: f64,
    pub z_v1: f64,
}

/// The primitives the penumbra pass draws.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Primitives {
    pub cones: Vec<Cone>,
    pub sheets: Vec<Sheet>,
}

fn usable_depth(setup: &PenumbraSetup, z: f64) -> bool {
    // a perspective cone needs its tip in front of the light; nothing lies past far
    z.is_finite() && z < setup.far && (!setup.perspective() || z > 0.0)
}

/// Cones and sheets of a silhouette. Zero-width primitives (spread 0) are left out.
pub fn primitives(sil: &Silhouettes, setup: &PenumbraSetup) -> Primitives {
    let mut out = Primitives::default();
    let far = setup.far;
    for (k, v) in sil.vertices.iter().enumerate() {
        if !usable_depth(setup, v.depth) {
            continue;
        }
        let spread = setup.spread(v.depth);
        if !(spread > 0.0 && spread.is_finite()) {
            continue;
        }
        out.cones.push(Cone {
            vertex: k,
            tip: v.position,
            z_v: v.depth,
            spread,
            base_radius: (far - v.depth) * spread,
        });
    }
    for (k, e) in sil.edges.iter().enumerate() {
        let (a, b) = (sil.vertices[e.a], sil.vertices[e.b]);
        if !(usable_depth(setup, a.depth) && usable_depth(setup, b.depth)) {
            continue;
        }
        let (k0, k1) = (setup.spread(a.depth), setup.spread(b.depth));
        if !(k0 > 0.0 && k1 > 0.0 && k0.is_finite() && k1.is_finite()) {
            continue;
        }
        let (r0, r1) = ((far - a.depth) * k0, (far - b.depth) * k1);
        let (c0, c1) = (setup.axis_at(a.position, far), setup.axis_at(b.position, far));
        let du = [c1[0] - c0[0], c1[1] - c0[1]];
        let l = du[0].hypot(du[1]);
        let m = setup.edge_plane(a.position, b.position);
        if !(l > 0.0 && l.is_finite()) || m == [0.0; 3] {
            continue;
        }
        let sin = (r0 - r1) / l;
        if sin.is_nan() || sin.abs() >= 1.0 {
            continue; // one base circle holds the other: no outer tangent
        }
        let cos = (1.0 - sin * sin).sqrt();
        let u = [du[0] / l, du[1] / l];
        let perp = [-u[1], u[0]];
        // moving within the far plane by `perp` changes m . x by m.xy . perp
        let towards_positive = m[0] * perp[0] + m[1] * perp[1];
        if towards_positive == 0.0 || !towards_positive.is_finite() {
            continue;
        }
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            if !e.outer[side] {
                continue;
            }
            let p = if towards_positive * sign > 0.0 {
                perp
            } else {
                [-perp[0], -perp[1]]
            };
            let nrm = [u[0] * sin + p[0] * cos, u[1] * sin + p[1] * cos];
            let t0 = [c0[0] + r0 * nrm[0], c0[1] + r0 * nrm[1], -far];
            let t1 = [c1[0] + r1 * nrm[0], c1[1] + r1 * nrm[1], -far];
            if !(finite(t0) && finite(t1)) {
                continue;
            }
            out.sheets.push(Sheet {
                edge: k,
                v0: a.position,
                v1: b.position,
                t0,
                t1,
                z_v0: a.depth,
                z_v1: b.depth,
            });
        }
    }
    out
}

/// Which primitive a fragment comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primitive {
    /// Index into [`Primitives::cones`].
    Cone(usize),
    /// Index into [`Primitives::sheets`].
    Sheet(usize),
}

/// One kept (not discarded) fragment of a penumbra-map texel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    pub primitive: Primitive,
    /// `Z_F`, `Z_v`, `Z_P` (view depths, world units).
    pub z_f: f64,
    pub z_v: f64,
    pub z_p: f64,
    /// Equation 1.
    pub intensity: f64,
    /// `3 I^2 - 2 I^3`.
    pub s: f64,
}

/// Equation 1 and the Bernstein interpolant: `(I, s)`; `I = 0` when `Z_P - Z_v <= 0`.
pub fn intensity(z_f: f64, z_v: f64, z_p: f64) -> (f64, f64) {
    let den = z_p - z_v;
    let i = if den > 0.0 { ((z_f - z_v) / den).clamp(0.0, 1.0) } else { 0.0 };
    let i = if i.is_nan() { 0.0 } else { i };
    (i, i * i * (3.0 - 2.0 * i))
}

/// The depth at which the texel ray `(o, d)` enters the cone (its only crossing of the
/// lateral surface), when that lies within the cone (`<= far`).
fn cone_hit(setup: &PenumbraSetup, c: &Cone, o: V3, d: V3) -> Option<f64> {
    let v = c.tip;
    let k = c.spread;
    if setup.perspective() {
        // ray at depth z: z d.xy; axis: z v.xy / Z_v; |z (d.xy - v.xy / Z_v)| <= (z - Z_v) k
        let g = [d[0] - v[0] / c.z_v, d[1] - v[1] / c.z_v];
        let g = g[0].hypot(g[1]);
        let den = k - g;
        // z = Z_v k / (k - |g|), kept when <= far (compared without dividing)
        if den.is_nan() || den <= 0.0 || c.z_v * k > setup.far * den {
            return None;
        }
        Some((c.z_v * k / den).max(c.z_v))
    } else {
        // ray at depth z: o.xy; |o.xy - v.xy| <= (z - Z_v) k
        let a = (o[0] - v[0]).hypot(o[1] - v[1]);
        if a > (setup.far - c.z_v) * k {
            return None;
        }
        Some(c.z_v + a / k)
    }
}

/// The intersections of the ray `(o, d)` with a bilinear sheet: `(depth, t)` for each.
fn sheet_hits(sh: &Sheet, o: V3, d: V3) -> Vec<(f64, f64)> {
    // two planes through the ray: normals n1, n2 perpendicular to d
    let dn = scale(d, 1.0 / len(d));
    let helper = if dn[0].abs() < 0.6 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let n1 = cross(dn, helper);
    let n1 = scale(n1, 1.0 / len(n1));
    let n2 = cross(dn, n1);
    let (a0, a1, b0, b1) = (sh.v0, sh.v1, sh.t0, sh.t1);
    let big_b = sub(a1, a0);
    let big_c = sub(b0, a0);
    let big_d = add(sub(sub(b1, b0), a1), a0);
    let rel = sub(a0, o);
    let coef = |n: V3| (dot(n, rel), dot(n, big_b), dot(n, big_c), dot(n, big_d));
    let (a1_, b1_, c1_, d1_) = coef(n1);
    let (a2_, b2_, c2_, d2_) = coef(n2);
    let qa = b2_ * d1_ - d2_ * b1_;
    let qb = a2_ * d1_ + b2_ * c1_ - c2_ * b1_ - d2_ * a1_;
    let qc = a2_ * c1_ - c2_ * a1_;
    let sc = qa.abs().max(qb.abs()).max(qc.abs());
    if !(sc > 0.0 && sc.is_finite()) {
        return Vec::new(); // the ray lies in the sheet: seen edge-on, no fragment
    }
    let (qa, qb, qc) = (qa / sc, qb / sc, qc / sc);
    const EPS: f64 = 1e-12;
    let mut roots: Vec<f64> = Vec::with_capacity(2);
    if qa.abs() <= EPS {
        if qb.abs() > EPS {
            roots.push(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= -EPS {
            let sq = disc.max(0.0).sqrt();
            let q = -0.5 * (qb + if qb >= 0.0 { sq } else { -sq });
            if q != 0.0 {
                roots.push(q / qa);
                roots.push(qc / q);
            } else {
                roots.push(0.0);
            }
        }
    }
    let mut hits: Vec<(f64, f64)> = Vec::new();
    for t in roots {
        if !t.is_finite() || !(-EPS..=1.0 + EPS).contains(&t) {
            continue;
        }
        let t = t.clamp(0.0, 1.0);
        let (e1, e2) = (c1_ + d1_ * t, c2_ + d2_ * t);
        let s = if e1.abs() >= e2.abs() {
            -(a1_ + b1_ * t) / e1
        } else {
            -(a2_ + b2_ * t) / e2
        };
        if e1 == 0.0 && e2 == 0.0 || !s.is_finite() || !(-EPS..=1.0 + EPS).contains(&s) {
            continue;
        }
        let s = s.clamp(0.0, 1.0);
        let p = lerp(lerp(a0, a1, t), lerp(b0, b1, t), s);
        let z = dot(sub(p, o), d) / dot(d, d);
        if z.is_finite() && !hits.iter().any(|h| (h.1 - t).abs() <= 1e-9) {
            hits.push((z, t));
        }
    }
    hits
}

/// The kept fragments of texel `(i, j)`: every cone and sheet the texel's ray meets within
/// `[near, far]`, those with `Z_F > Z_P` discarded (pseudocode line 4).
pub fn fragments(prims: &Primitives, shadow: &ShadowMap, setup: &PenumbraSetup, i: usize, j: usize) -> Vec<Fragment> {
    let (o, d) = setup.texel_ray(i, j);
    let z_p = shadow.depth[j * shadow.size + i];
    let mut out = Vec::new();
    let mut keep = |primitive: Primitive, z_f: f64, z_v: f64| {
        if !(z_f >= setup.near && z_f <= setup.far && z_f <= z_p) {
            return;
        }
        let z_f = z_f.max(z_v);
        let (intensity, s) = intensity(z_f, z_v, z_p);
        out.push(Fragment {
            primitive,
            z_f,
            z_v,
            z_p,
            intensity,
            s,
        });
    };
    for (k, c) in prims.cones.iter().enumerate() {
        if let Some(z) = cone_hit(setup, c, o, d) {
            keep(Primitive::Cone(k), z, c.z_v);
        }
    }
    for (k, sh) in prims.sheets.iter().enumerate() {
        for (z, t) in sheet_hits(sh, o, d) {
            keep(Primitive::Sheet(k), z, (1.0 - t) * sh.z_v0 + t * sh.z_v1);
        }
    }
    out
}

/// The penumbra map: per texel the resolved intensity and the number of kept fragments.
#[derive(Clone, Debug, PartialEq)]
pub struct PenumbraMap {
    pub size: usize,
    pub value: Vec<f64>,
    pub fragments: Vec<u32>,
}

/// The penumbra map (second pass of section 3) from primitives and the shadow map.
pub fn penumbra_map(prims: &Primitives, shadow: &ShadowMap, setup: &PenumbraSetup) -> PenumbraMap {
    let n = shadow.size;
    let mut value = vec![1.0; n * n];
    let mut count = vec![0u32; n * n];
    for j in 0..n {
        for i in 0..n {
            let f = fragments(prims, shadow, setup, i, j);
            let s: Vec<f64> = f.iter().map(|f| f.s).collect();
            value[j * n + i] = setup.resolve.combine(&s);
            count[j * n + i] = f.len() as u32;
        }
    }
    PenumbraMap {
        size: n,
        value,
        fragments: count,
    }
}

/// Final visibility of a world-space receiver (third pass of section 3): the hard test
/// (0 when `d - bias > z`, `d` the receiver's normalised depth `(depth - near) / (far -
/// near)`, `z` the stored shadow-map value, `bias` in the same normalised units as the
/// techniques' `d - bias`) times the penumbra map, both at the receiver's texel (nearest,
/// clamped to the edge), clamped to `[0, 1]`. A receiver the light cannot project (non-finite,
/// at or behind a perspective light's eye) reads 1.
pub fn visibility(setup: &PenumbraSetup, shadow: &ShadowMap, penumbra: &PenumbraMap, p: V3, bias: f64) -> f64 {
    let Some((i, j, depth)) = setup.texel_of(p) else {
        return 1.0;
    };
    let k = j * shadow.size + i;
    let d = (depth - setup.near) / (setup.far - setup.near);
    let hard = if d - bias > shadow.z(setup, k) { 0.0 } else { 1.0 };
    let v = hard * penumbra.value[k];
    if v.is_nan() { 1.0 } else { v.clamp(0.0, 1.0) }
}

/// All passes of one light.
#[derive(Clone, Debug, PartialEq)]
pub struct PenumbraReference {
    pub silhouettes: Silhouettes,
    pub primitives: Primitives,
    pub shadow: ShadowMap,
    pub penumbra: PenumbraMap,
}

impl PenumbraReference {
    /// Silhouettes, shadow map, primitives and penumbra map of world-space `triangles`
    /// grouped into `meshes` (ranges of triangle indices).
    pub fn new(triangles: &[[V3; 3]], meshes: &[Range<usize>], setup: &PenumbraSetup) -> Result<Self, String> {
        let silhouettes = silhouettes(triangles, meshes, setup)?;
        let shadow = shadow_map(triangles, setup)?;
        let primitives = primitives(&silhouettes, setup);
        let penumbra = penumbra_map(&primitives, &shadow, setup);
        Ok(PenumbraReference {
            silhouettes,
            primitives,
            shadow,
            penumbra,
        })
    }

    /// [`visibility`] of a world-space receiver.
    pub fn visibility(&self, setup: &PenumbraSetup, p: V3, bias: f64) -> f64 {
        visibility(setup, &self.shadow, &self.penumbra, p, bias)
    }
}

/// Scenes and lights the reference's tests and the WGSL reference's tests share: quads in
/// the light's view space (the light at the origin looking down -z, the view the identity).
pub mod fixtures {
    use super::{AreaLight, LightProjection, PenumbraSetup, Resolve, V3};
    use std::ops::Range;

    const IDENTITY: [f64; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];

    /// A closed axis-aligned box from corner `lo` to corner `hi`, wound outwards.
    pub fn cuboid(lo: V3, hi: V3) -> Vec<[V3; 3]> {
        let c = |i: usize| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        };
        // faces as quads of corner indices wound outwards
        let faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let mut tris = Vec::new();
        for f in faces {
            tris.push([c(f[0]), c(f[1]), c(f[2])]);
            tris.push([c(f[0]), c(f[2]), c(f[3])]);
        }
        tris
    }

    /// An axis-aligned quad at height z (two triangles wound towards +z, the light).
    pub fn quad(x0: f64, x1: f64, y0: f64, y1: f64, z: f64) -> Vec<[V3; 3]> {
        vec![[[x0, y0, z], [x1, y0, z], [x1, y1, z]], [[x0, y0, z], [x1, y1, z], [x0, y1, z]]]
    }

    /// One mesh per list of triangles.
    pub fn scene<T: AsRef<[[V3; 3]]>>(parts: &[T]) -> (Vec<[V3; 3]>, Vec<Range<usize>>) {
        let mut tris = Vec::new();
        let mut meshes = Vec::new();
        for p in parts {
            let start = tris.len();
            tris.extend_from_slice(p.as_ref());
            meshes.push(start..tris.len());
        }
        (tris, meshes)
    }

    /// Perspective light at the origin looking down -z, covering [-5, 5] at depth 10.
    pub fn sphere(radius: f64, size: usize, resolve: Resolve) -> PenumbraSetup {
        PenumbraSetup {
            view: IDENTITY,
            projection: LightProjection::Perspective { f: 2.0 },
            near: 1.0,
            far: 12.0,
            size,
            light: AreaLight::Sphere { radius },
            resolve,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::{quad, scene, sphere};
    use super::*;

    const IDENTITY: [f64; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];

    fn all_valid(r: &PenumbraReference) {
        for (k, v) in r.penumbra.value.iter().enumerate() {
            assert!(v.is_finite() && (0.0..=1.0).contains(v), "texel {k}: {v}");
        }
        for z in &r.shadow.depth {
            assert!(z.is_finite());
        }
    }

    #[test]
    fn radius_zero_is_the_hard_shadow_map() {
        let floor = quad(-6.0, 6.0, -6.0, 6.0, -10.0);
        let square = quad(-1.0, 1.0, -1.0, 1.0, -5.0);
        let (tris, meshes) = scene(&[&floor, &square]);
        for rule in Resolve::ALL {
            let setup = sphere(0.0, 64, rule);
            let r = PenumbraReference::new(&tris, &meshes, &setup).unwrap();
            assert_eq!(r.silhouettes.edges.len(), 8, "4 floor + 4 square boundary edges");
            assert!(r.primitives.cones.is_empty() && r.primitives.sheets.is_empty());
            assert!(r.penumbra.value.iter().all(|&v| v == 1.0));
            assert!(r.penumbra.fragments.iter().all(|&c| c == 0));
            // visibility on the floor is exactly the hard test, and the analytic hard
            // shadow (|x|, |y| <= 2 on the floor) away from its edges
            let texel = 10.0 / 64.0;
            for a in 0..41 {
                for b in 0..41 {
                    let p = [-4.9 + a as f64 * 0.245, -4.9 + b as f64 * 0.245, -10.0];
                    let (i, j, _) = setup.texel_of(p).unwrap();
                    let hard = if r.shadow.depth[j * 64 + i] < 9.9 { 0.0 } else { 1.0 };
                    let v = r.visibility(&setup, p, 1e-4);
                    assert_eq!(v, hard, "{p:?}");
                    let inside = p[0].abs().max(p[1].abs());
                    if (inside - 2.0).abs() > 1.5 * texel {
                        assert_eq!(v, if inside < 2.0 { 0.0 } else { 1.0 }, "{p:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn square_over_floor_outer_penumbra_width() {
        // occluder at Z_v = 5, floor at 10, L_r = 1: w = (10 - 5) 1 / 5 = 1 world unit on
        // the floor, the hard shadow's edge at x = 2.
        let (zv, zfloor, lr, n) = (5.0, 10.0, 1.0, 128usize);
        let floor = quad(-6.0, 6.0, -6.0, 6.0, -zfloor);
        let square = quad(-1.0, 1.0, -1.0, 1.0, -zv);
        let (tris, meshes) = scene(&[&floor, &square]);
        let setup = sphere(lr, n, Resolve::KeepMin);
        let r = PenumbraReference::new(&tris, &meshes, &setup).unwrap();
        all_valid(&r);
        assert_eq!(r.primitives.cones.len(), 8);
        // the square's 4 edges, one sheet each (outside); the floor's 4 edges
        assert_eq!(r.primitives.sheets.len(), 8);
        let texel = 10.0 / n as f64; // world size of a texel on the floor
        let w = (zfloor - zv) * lr / zv;
        assert!((w - 1.0).abs() < 1e-12);
        let x_of = |i: usize| 10.0 * ((i as f64 + 0.5) / n as f64 - 0.5);
        for j in [n / 2, n / 2 - 10, n / 2 + 7] {
            let y = -10.0 * ((j as f64 + 0.5) / n as f64 - 0.5);
            assert!(y.abs() < 1.0);
            let mut covered = Vec::new();
            for i in n / 2..n {
                let k = j * n + i;
                let x = x_of(i);
                if x <= 2.0 {
                    assert!(r.shadow.depth[k] == zv, "inside the hard shadow");
                    continue;
                }
                if r.penumbra.fragments[k] > 0 {
                    covered.push(i);
                    // the closed form: the ray meets the sheet where its offset from the
                    // edge in the occluder's plane, a = x zv / zfloor - 1, equals
                    // (Z_F - Z_v) L_r / Z_v, so Z_F = Z_v L_r / (L_r - a)
                    let a = x * zv / zfloor - 1.0;
                    let zf = zv * lr / (lr - a);
                    let i_exp = (zf - zv) / (zfloor - zv);
                    let s_exp = 3.0 * i_exp * i_exp - 2.0 * i_exp.powi(3);
                    assert!(
                        (r.penumbra.value[k] - s_exp).abs() < 1e-9,
                        "x {x}: {} vs {s_exp}",
                        r.penumbra.value[k]
                    );
                } else {
                    assert_eq!(r.penumbra.value[k], 1.0);
                }
            }
            // contiguous, starting right at the silhouette
            assert!(covered.windows(2).all(|p| p[1] == p[0] + 1));
            let measured = covered.len() as f64 * texel;
            assert!((measured - w).abs() <= texel + 1e-9, "row {j}: {measured} vs {w}");
            let first = covered[0];
            let last = *covered.last().unwrap();
            assert!(x_of(first) - 2.0 <= texel);
            assert!(2.0 + w - x_of(last) <= texel);
            // I -> 0 at the silhouette, -> 1 at the penumbra's outer edge
            let fi = fragments(&r.primitives, &r.shadow, &setup, first, j);
            let fl = fragments(&r.primitives, &r.shadow, &setup, last, j);
            let imin = fi.iter().map(|f| f.intensity).fold(1.0, f64::min);
            let imax = fl.iter().map(|f| f.intensity).fold(1.0, f64::min);
            // within one texel of the ends of the closed form I(x) = a / (L_r - a)
            let i_at = |x: f64| {
                let a = x * zv / zfloor - 1.0;
                a / (lr - a)
            };
            assert!(imin <= i_at(2.0 + texel) && imin < 0.05, "I at the silhouette {imin}");
            assert!(imax >= i_at(2.0 + w - texel) && imax > 0.85, "I at the outer edge {imax}");
            assert_eq!(r.penumbra.fragments[j * n + last + 1], 0);
        }
        // beyond a corner only the cone covers: Z_F = Z_v L_r / (L_r - rho), rho the distance
        // from the corner in the occluder's plane
        let (i, j) = (n / 2 + 28, n / 2 - 29); // x > 2, y > 2 on the floor
        let (x, y) = (x_of(i), -10.0 * ((j as f64 + 0.5) / n as f64 - 0.5));
        assert!(x > 2.0 && y > 2.0);
        let rho = (x * zv / zfloor - 1.0).hypot(y * zv / zfloor - 1.0);
        let f = fragments(&r.primitives, &r.shadow, &setup, i, j);
        assert_eq!(f.len(), 1);
        assert!(matches!(f[0].primitive, Primitive::Cone(_)));
        let zf = zv * lr / (lr - rho);
        assert!((f[0].z_f - zf).abs() < 1e-9);
        assert!((f[0].intensity - (zf - zv) / (zfloor - zv)).abs() < 1e-9);
        // the final visibility: 0 in the umbra, the map in the penumbra, 1 outside
        let p_in = [1.0, 0.05, -zfloor];
        let p_pen = [2.5, 0.05, -zfloor];
        let p_out = [3.5, 0.05, -zfloor];
        assert_eq!(r.visibility(&setup, p_in, 1e-4), 0.0);
        let (pi, pj, _) = setup.texel_of(p_pen).unwrap();
        let v = r.visibility(&setup, p_pen, 1e-4);
        assert_eq!(v, r.penumbra.value[pj * n + pi]);
        assert!(v > 0.0 && v < 1.0);
        assert_eq!(r.visibility(&setup, p_out, 1e-4), 1.0);
    }

    #[test]
    fn resolve_rules_combine_single_occluder_maps() {
        // two squares at depth 5 whose penumbrae (1 wide on the floor) overlap on a strip
        // 0.3 wide between their hard shadows (0.7 apart on the floor)
        let floor = quad(-6.0, 6.0, -6.0, 6.0, -10.0);
        let a = quad(-2.175, -0.175, -1.0, 1.0, -5.0);
        let b = quad(0.175, 2.175, -1.0, 1.0, -5.0);
        let n = 160;
        let mut overlap_seen = 0;
        for rule in Resolve::ALL {
            let setup = sphere(0.5, n, rule);
            let run = |parts: &[&[[V3; 3]]]| {
                let (tris, meshes) = scene(parts);
                PenumbraReference::new(&tris, &meshes, &setup).unwrap()
            };
            let (ra, rb, both) = (run(&[&floor, &a]), run(&[&floor, &b]), run(&[&floor, &a, &b]));
            all_valid(&both);
            let mut overlap = 0;
            let mut compared = 0;
            for k in 0..n * n {
                let same = ra.shadow.depth[k] == both.shadow.depth[k] && rb.shadow.depth[k] == both.shadow.depth[k];
                if !same {
                    continue;
                }
                compared += 1;
                let (va, vb, v) = (ra.penumbra.value[k], rb.penumbra.value[k], both.penumbra.value[k]);
                let (ca, cb) = (ra.penumbra.fragments[k], rb.penumbra.fragments[k]);
                assert_eq!(both.penumbra.fragments[k], ca + cb, "the fragments are the union");
                if ca > 0 && cb > 0 {
                    overlap += 1;
                }
                let want = match rule {
                    Resolve::KeepMin => va.min(vb),
                    Resolve::Multiply => va * vb,
                    // clamping at 0 commutes: a single map at 0 already has sum(1 - s) >= 1
                    Resolve::Add => (va + vb - 1.0).max(0.0),
                    // texels a map has no fragment in take no part in the maximum
                    Resolve::KeepMax => match (ca > 0, cb > 0) {
                        (true, true) => va.max(vb),
                        (true, false) => va,
                        (false, true) => vb,
                        (false, false) => 1.0,
                    },
                };
                assert!((v - want).abs() < 1e-12, "{rule:?} texel {k}: {v} vs {want} ({va}, {vb})");
            }
            assert!(compared > n * n / 2);
            assert!(overlap >= 3 * 6, "{rule:?}: only {overlap} texels in both penumbrae");
            overlap_seen = overlap;
        }
        assert!(overlap_seen > 0);
    }

    #[test]
    fn open_quad_and_three_fins_stay_finite() {
        let floor = quad(-6.0, 6.0, -6.0, 6.0, -10.0);
        // a tilted single quad (open boundary)
        let tilted: [[V3; 3]; 2] = [
            [[-1.0, -1.0, -4.0], [1.5, -0.5, -5.0], [1.0, 1.0, -6.0]],
            [[-1.0, -1.0, -4.0], [1.0, 1.0, -6.0], [-1.2, 0.8, -5.0]],
        ];
        // three fins sharing one edge (non-manifold), the first facing the light, the others not
        let (p, q) = ([-0.5, -1.5, -5.0], [0.5, 1.5, -5.5]);
        let fins: [[V3; 3]; 3] = [[q, p, [2.0, 0.0, -5.0]], [q, p, [-2.0, 0.3, -4.5]], [p, q, [0.2, -0.1, -7.0]]];
        // a face seen edge-on (its plane holds the light's centre) and an edge seen end-on
        let edge_on: [[V3; 3]; 2] = [
            [[0.0, 0.0, -3.0], [0.0, 1.0, -6.0], [0.0, 0.0, -6.0]],
            [[1.0, 1.0, -3.0], [2.0, 2.0, -6.0], [2.5, 1.0, -5.0]],
        ];
        let fin_mesh = scene(&[&fins]);
        let setup = sphere(0.4, 32, Resolve::KeepMin);
        let sil = silhouettes(&fin_mesh.0, &fin_mesh.1, &setup).unwrap();
        let shared = sil
            .edges
            .iter()
            .find(|e| e.faces == 3)
            .expect("the shared edge is a silhouette: its faces do not all face the light");
        assert!(shared.outer.iter().filter(|&&o| o).count() <= 1);
        for parts in [
            vec![&tilted[..]],
            vec![&floor[..], &tilted[..]],
            vec![&fins[..]],
            vec![&floor[..], &fins[..]],
            vec![&floor[..], &edge_on[..], &fins[..], &tilted[..]],
        ] {
            let (tris, meshes) = scene(&parts);
            for rule in Resolve::ALL {
                let setup = sphere(0.4, 48, rule);
                let r = PenumbraReference::new(&tris, &meshes, &setup).unwrap();
                all_valid(&r);
                assert!(r.penumbra.fragments.iter().any(|&c| c > 0));
                for a in 0..25 {
                    for b in 0..25 {
                        for z in [-4.5, -5.0, -10.0, -11.0, 1.0, 0.0] {
                            let pt = [-6.0 + a as f64 * 0.5, -6.0 + b as f64 * 0.5, z];
                            let v = r.visibility(&setup, pt, 1e-3);
                            assert!(v.is_finite() && (0.0..=1.0).contains(&v));
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn closed_box_silhouette_is_its_top_outline() {
        // a closed cube under the light: the silhouette is the top face's outline, each edge
        // with one outer side, away from the cube
        let (lo, hi) = ([-1.0, -1.0, -6.0], [1.0, 1.0, -4.0]);
        let tris = fixtures::cuboid(lo, hi);
        let setup = sphere(0.3, 32, Resolve::KeepMin);
        let sil = silhouettes(&tris, std::slice::from_ref(&(0..tris.len())), &setup).unwrap();
        assert_eq!(sil.all_edges, 18);
        assert_eq!(sil.edges.len(), 4);
        for e in &sil.edges {
            let (a, b) = (sil.vertices[e.a].position, sil.vertices[e.b].position);
            assert!(a[2] == -4.0 && b[2] == -4.0);
            assert_eq!(e.outer.iter().filter(|&&o| o).count(), 1);
        }
        let prims = primitives(&sil, &setup);
        assert_eq!(prims.sheets.len(), 4);
        for sh in &prims.sheets {
            // the sheet leaves the cube: its far points lie outside the cube's projection
            let mid = [(sh.t0[0] + sh.t1[0]) / 2.0, (sh.t0[1] + sh.t1[1]) / 2.0];
            assert!(mid[0].abs().max(mid[1].abs()) > 12.0 / 4.0);
        }
    }

    #[test]
    fn view_matrix_moves_nothing() {
        // the same scene moved rigidly, seen through the matching view, gives the same maps
        let floor = quad(-6.0, 6.0, -6.0, 6.0, -10.0);
        let square = quad(-1.0, 0.7, -1.3, 1.0, -5.0);
        let (tris, meshes) = scene(&[&floor, &square]);
        let base = sphere(0.6, 40, Resolve::KeepMin);
        let r0 = PenumbraReference::new(&tris, &meshes, &base).unwrap();
        // world = R view + t, R a rotation about (1, 2, 2) / 3 by 0.7 rad
        let (axis, ang) = ([1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0], 0.7f64);
        let (s, c) = ang.sin_cos();
        let rot = |v: V3| add(add(scale(v, c), scale(cross(axis, v), s)), scale(axis, dot(axis, v) * (1.0 - c)));
        let t = [3.0, -2.0, 7.5];
        let world: Vec<[V3; 3]> = tris.iter().map(|tr| tr.map(|p| add(rot(p), t))).collect();
        // view = R^T (p - t), column-major: column k holds R^T e_k
        let rinv = |v: V3| add(add(scale(v, c), scale(cross(axis, v), -s)), scale(axis, dot(axis, v) * (1.0 - c)));
        let cols = [rinv([1.0, 0.0, 0.0]), rinv([0.0, 1.0, 0.0]), rinv([0.0, 0.0, 1.0])];
        let tr = rinv(scale(t, -1.0));
        let mut view = [0.0; 16];
        for k in 0..3 {
            view[4 * k..4 * k + 3].copy_from_slice(&cols[k]);
        }
        view[12..15].copy_from_slice(&tr);
        view[15] = 1.0;
        let moved = PenumbraSetup { view, ..base };
        let r1 = PenumbraReference::new(&world, &meshes, &moved).unwrap();
        assert_eq!(r0.penumbra.fragments, r1.penumbra.fragments);
        for k in 0..40 * 40 {
            assert!((r0.shadow.depth[k] - r1.shadow.depth[k]).abs() < 1e-9);
            assert!((r0.penumbra.value[k] - r1.penumbra.value[k]).abs() < 1e-7);
        }
    }

    #[test]
    fn distant_disk_widens_linearly() {
        // orthographic light down -z covering [-4, 4]; tan(angle / 2) = 0.1; occluder at 5
        let (zv, n, k) = (5.0, 128usize, 0.1f64);
        let angle = 2.0 * k.atan();
        let texel = 8.0 / n as f64;
        let square = quad(-1.0, 1.0, -1.0, 1.0, -zv);
        let mut widths = Vec::new();
        for zfloor in [9.0, 13.0, 17.0] {
            let floor = quad(-6.0, 6.0, -6.0, 6.0, -zfloor);
            let (tris, meshes) = scene(&[&floor, &square]);
            let setup = PenumbraSetup {
                view: IDENTITY,
                projection: LightProjection::Orthographic { half_height: 4.0 },
                near: 1.0,
                far: 20.0,
                size: n,
                light: AreaLight::DistantDisk { angle },
                resolve: Resolve::KeepMin,
            };
            let r = PenumbraReference::new(&tris, &meshes, &setup).unwrap();
            all_valid(&r);
            let w = (zfloor - zv) * k;
            let j = n / 2;
            let mut count = 0;
            for i in n / 2..n {
                let x = 8.0 * ((i as f64 + 0.5) / n as f64 - 0.5);
                let kk = j * n + i;
                if x > 1.0 && r.penumbra.fragments[kk] > 0 {
                    count += 1;
                    // I is linear across an orthographic penumbra: I = (x - 1) / w
                    let f = fragments(&r.primitives, &r.shadow, &setup, i, j);
                    let imin = f.iter().map(|f| f.intensity).fold(1.0, f64::min);
                    assert!((imin - (x - 1.0) / w).abs() < 1e-9, "{imin} vs {}", (x - 1.0) / w);
                }
            }
            let measured = count as f64 * texel;
            assert!((measured - w).abs() <= texel + 1e-9, "floor {zfloor}: {measured} vs {w}");
            widths.push(measured);
        }
        // equal steps of floor distance widen the penumbra by equal steps (0.4 each)
        assert!(((widths[2] - widths[1]) - (widths[1] - widths[0])).abs() <= 2.0 * texel);
        assert!((widths[2] - widths[0] - 0.8).abs() <= 2.0 * texel);
    }

    #[test]
    fn random_soup_stays_finite() {
        let mut state = 0x9e3779b97f4a7c15u64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut tris = Vec::new();
        let mut meshes = Vec::new();
        for _ in 0..4 {
            let start = tris.len();
            let pts: Vec<V3> = (0..6).map(|_| [rnd() * 6.0 - 3.0, rnd() * 6.0 - 3.0, -2.0 - rnd() * 9.0]).collect();
            for _ in 0..8 {
                let pick = |r: f64| pts[(r * 6.0) as usize % 6];
                tris.push([pick(rnd()), pick(rnd()), pick(rnd())]);
            }
            meshes.push(start..tris.len());
        }
        for rule in Resolve::ALL {
            let setup = sphere(0.8, 24, rule);
            let r = PenumbraReference::new(&tris, &meshes, &setup).unwrap();
            all_valid(&r);
            let ortho = PenumbraSetup {
                projection: LightProjection::Orthographic { half_height: 4.0 },
                light: AreaLight::DistantDisk { angle: 0.3 },
                ..setup
            };
            all_valid(&PenumbraReference::new(&tris, &meshes, &ortho).unwrap());
        }
        // mismatched light and projection, bad ranges
        let bad = PenumbraSetup {
            light: AreaLight::DistantDisk { angle: 0.1 },
            ..sphere(0.1, 8, Resolve::Add)
        };
        assert!(bad.check().is_err());
        assert!(
            PenumbraSetup {
                near: 0.0,
                ..sphere(0.1, 8, Resolve::Add)
            }
            .check()
            .is_err()
        );
    }
}
