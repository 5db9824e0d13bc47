//! CPU visibility query: the fraction of a light that a point sees, by ray casting with
//! stratified samples (the ground truth of docs/truth.md).
//!
//! A compressed wide BVH (CWBVH, from the `obvhs` crate) over the scene's world-space
//! triangles is built once by [`Visibility::new`]; shadow rays use it with a
//! Möller–Trumbore test of our own, so the hit rules are ours: a hit counts only for
//! `t_min < t < t_max`, both sides of a triangle block, and barycentric coordinates get a
//! tolerance of 1e-6 so that a ray through the edge shared by two triangles cannot slip
//! between them through f32 rounding (this grows each triangle by 1e-6 of its size).
//!
//! Sampling, with `n x n` stratified samples (one jittered sample per cell of an `n x n`
//! grid on the unit square, mapped to the light):
//!
//! | light | samples |
//! |---|---|
//! | point, directional | one ray (the answer is 0 or 1) |
//! | rectangle | uniform over its area (the grid maps linearly) |
//! | disk | uniform over its area (Shirley–Chiu concentric map, which keeps strata compact) |
//! | segment | uniform over its length, `n^2` strata along it |
//! | sphere | uniform in solid angle over the cone it subtends; a ray ends where it meets the sphere; a receiver inside the sphere sees all of it |
//! | distant disk | uniform over its disk in the tangent plane: direction `d + tan(angle/2) p` with `p` uniform in the unit disk (concentric map), i.e. within the cone of half-angle `angle/2` |
//!
//! Ray origins (Wächter and Binder, "A Fast and Robust Method for Avoiding
//! Self-Intersection", Ray Tracing Gems, chapter 6: an offset scaled to the point's own
//! floating-point precision, and no distance threshold along the ray). The offset at a
//! point `x` is [`OFFSET_RELATIVE`] = 2^-16 of its largest coordinate magnitude (128 to 256
//! ulp of it), and at least [`OFFSET_SCENE`] = 2^-19 of the scene's largest coordinate
//! magnitude (8 to 16 ulp: the error of a point interpolated on a triangle whose corners
//! are larger than the point, near the origin). With the receiver's normal, the origin
//! moves by that offset along the normal and rays count every hit at `t > 0`; without one,
//! hits within the offset of `x` are ignored instead. A ray to a point on a light ends the
//! light point's own offset short of it. Under a distant light at elevation `e` the offset
//! moves a shadow edge by `offset / tan e` (1.1e-4 at 5 degrees for a point at 1 unit from
//! the origin; the former 1e-4 of the scene's diagonal moved it by 100 times that).
//!
//! Two-sided surfaces (the scene format's convention, scenes/README.md): every triangle
//! blocks light from both sides, and a receiver is the side of its surface that the camera
//! sees. The normal given with a point is that side's normal (the camera pass writes it
//! turned towards the camera); light arriving from behind its tangent plane is blocked by
//! the surface itself: a sample direction `w` with `w . n <= 0` counts as blocked.
//!
//! Objects marked `casts: false` (a ground plane) block no shadow ray: their triangles are
//! in the BVH (the camera's rays, [`Visibility::closest_hit`], see them) but the shadow
//! rays' hit test skips them, and the skip test leaves them out of the possible occluders.
//! A non-caster still shadows itself by the tangent-plane rule above.

//! Skipping: before sampling, each object's bounding box is tested against the region
//! where an occluder could be. An object cannot occlude if it lies entirely on or behind a
//! plane through the ray origin that has the whole light strictly in front (the plane
//! towards the light's centre, and the receiver's tangent plane when the light lies wholly
//! above it), or if its bounding sphere misses the cone from the origin that holds the
//! whole light (and, for a light at a finite position, lies beyond it). When no object
//! can occlude, the answer is 1 without casting a ray; it is tried only when the whole
//! light lies in front of the receiver's tangent plane (a light wholly behind it gives 0
//! without a ray). The test is conservative: it never changes a result.
//!
//! The files: `mod.rs` the query (the BVH, its rays, and each light's sampling),
//! `skip.rs` the skip test, `sampling.rs` the generator and the maps from the unit square,
//! `warnings.rs` the lights inside or on the geometry ([`Visibility::light_warnings`]).

use std::f32::consts::TAU;
use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use crate::scene::{Light, Scene};

mod sampling;
mod skip;
mod warnings;

pub(crate) use sampling::Rng;
use sampling::{concentric, mix, stratified};
use skip::shaft;
pub use warnings::{INSIDE_RAYS, LIGHT_CONTACT_OFFSETS};

/// Barycentric tolerance of the ray-triangle test (see the module docs).
pub const BARY_TOLERANCE: f32 = 1e-6;

/// The ray origin's offset at a point, relative to the point's largest coordinate
/// magnitude: 2^-16, 128 to 256 ulp of it (see the module docs).
pub const OFFSET_RELATIVE: f32 = 1.0 / 65536.0;

/// The smallest ray origin offset, relative to the scene's largest coordinate magnitude:
/// 2^-19, 8 to 16 ulp of it (see the module docs).
pub const OFFSET_SCENE: f32 = 1.0 / 524288.0;

/// A triangle prepared for Möller–Trumbore: a corner and the two edges from it.
#[derive(Clone, Copy, Debug)]
struct RtTriangle {
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
}

impl RtTriangle {
    /// Distance `t` along `dir` from `origin` to the triangle when `t_min < t < t_max`.
    #[inline(always)]
    fn hit(&self, origin: Vec3A, dir: Vec3A, t_min: f32, t_max: f32) -> Option<f32> {
        let p = dir.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - self.v0;
        let u = s.dot(p) * inv;
        if !(-BARY_TOLERANCE..=1.0 + BARY_TOLERANCE).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = dir.dot(q) * inv;
        if v < -BARY_TOLERANCE || u + v > 1.0 + BARY_TOLERANCE {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        (t > t_min && t < t_max).then_some(t)
    }
}

/// Bounds of one object, for the skip test.
#[derive(Clone, Copy, Debug)]
struct ObjectBounds {
    lo: Vec3,
    hi: Vec3,
    centre: Vec3,
    radius: f32,
}

/// The deepest BVH that `obvhs`'s traversal walks whole: its stack holds 32 entries
/// (`TRAVERSAL_STACK_SIZE` in obvhs 0.4) and past that overwrites its last entry, so a
/// deeper tree would silently miss triangles. Its own check is a debug assertion.
pub const MAX_BVH_DEPTH: usize = 31;

/// The first of each set of coincident triangles (the same three corners in any order,
/// compared bit for bit), in scene order, and whether any of its set casts.
fn distinct(tris: &[[Vec3; 3]], casting: &[bool]) -> (Vec<u32>, Vec<bool>) {
    let key = |t: &[Vec3; 3]| {
        let mut k = t.map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]);
        k.sort_unstable();
        k
    };
    let mut first: std::collections::HashMap<[[u32; 3]; 3], usize> = std::collections::HashMap::with_capacity(tris.len());
    let (mut unique, mut casts) = (Vec::with_capacity(tris.len()), Vec::with_capacity(tris.len()));
    for (i, t) in tris.iter().enumerate() {
        let c = casting.get(i).copied().unwrap_or(true);
        match first.entry(key(t)) {
            std::collections::hash_map::Entry::Occupied(e) => casts[*e.get()] |= c,
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(unique.len());
                unique.push(i as u32);
                casts.push(c);
            }
        }
    }
    (unique, casts)
}

/// `d` with each -0.0 component made +0.0. obvhs's traversal picks the ray's octant from
/// the sign bits and divides by the components: a direction of (-0, -1, -0) (what `-Vec3::Y`
/// is, or a light direction written `-0.0`) missed every triangle.
fn positive_zeros(d: Vec3) -> Vec3A {
    // IEEE 754: -0 + +0 is +0 in round-to-nearest; every other value is unchanged
    Vec3A::from(d) + Vec3A::ZERO
}

/// The depth of `bvh`'s deepest inner node (the root at 0), walked with a stack of its
/// own.
fn bvh_depth(bvh: &CwBvh) -> usize {
    let mut deepest = 0;
    let mut todo = vec![(0usize, 0usize)];
    while let Some((n, depth)) = todo.pop() {
        deepest = deepest.max(depth);
        let Some(node) = bvh.nodes.get(n) else { continue };
        for ch in 0..8 {
            if !node.is_child_empty(ch) && !node.is_leaf(ch) {
                todo.push((node.child_node_index(ch) as usize, depth + 1));
            }
        }
    }
    deepest
}

/// Ray casting against a scene's triangles.
pub struct Visibility {
    bvh: Option<CwBvh>,
    /// The BVH could not be kept within [`MAX_BVH_DEPTH`]: rays test every triangle (slow,
    /// but no triangle is missed). [`Visibility::light_warnings`] says so.
    flat: bool,
    /// Triangles in the BVH's primitive order.
    triangles: Vec<RtTriangle>,
    /// For each of `triangles`, its index in [`Scene::triangles`].
    original: Vec<u32>,
    /// For each of `triangles`, whether its object casts shadows (`casts` in the scene):
    /// shadow rays pass through the others; camera rays ([`Visibility::closest_hit`]) do not.
    casts: Vec<bool>,
    objects: Vec<ObjectBounds>,
    /// The smallest offset (see [`OFFSET_SCENE`]).
    floor: f32,
    /// The largest offset anywhere in the scene's bounds.
    epsilon: f32,
}

impl std::fmt::Debug for Visibility {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Visibility")
            .field("triangles", &self.triangles.len())
            .field("epsilon", &self.epsilon)
            .finish()
    }
}

impl Visibility {
    /// Builds the BVH over the scene's triangles (once; the query is read-only after).
    pub fn new(scene: &Scene) -> Visibility {
        let tris = scene.triangles();
        let (lo, hi) = scene.bounds();
        let largest = lo.abs().max(hi.abs()).max_element();
        let floor = (OFFSET_SCENE * largest).max(f32::MIN_POSITIVE);
        let epsilon = (OFFSET_RELATIVE * largest).max(floor);
        // The skip test's possible occluders: the objects that cast.
        let objects = (0..scene.objects().len())
            .filter_map(|i| {
                let range = scene.object_triangles(i);
                if range.is_empty() || !scene.casts(i) {
                    return None;
                }
                let (lo, hi) = tris[range]
                    .iter()
                    .flatten()
                    .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
                Some(ObjectBounds {
                    lo,
                    hi,
                    centre: (lo + hi) * 0.5,
                    radius: 0.5 * (hi - lo).length(),
                })
            })
            .collect();
        if tris.is_empty() {
            return Visibility {
                bvh: None,
                flat: false,
                triangles: Vec::new(),
                original: Vec::new(),
                casts: Vec::new(),
                objects,
                floor,
                epsilon,
            };
        }
        // Coincident triangles (the same three corners, in any order) answer every ray
        // alike: the BVH gets the first of each, casting if any of them casts. The
        // builder cannot separate identical boxes (PLOC's distances tie): 90 k copies of
        // one triangle took 82 s and built a tree deeper than its traversal walks
        // (issue 48, item 3).
        let casting = scene.casting_triangles();
        let (unique, casts_any) = distinct(tris, &casting);
        let input: Vec<Triangle> = unique
            .iter()
            .map(|&i| {
                let t = &tris[i as usize];
                Triangle {
                    v0: t[0].into(),
                    v1: t[1].into(),
                    v2: t[2].into(),
                }
            })
            .collect();
        let bvh = build_cwbvh_from_tris(&input, BvhBuildParams::medium_build(), &mut Duration::default());
        let order: Vec<u32> = bvh.primitive_indices.clone();
        let triangles = order
            .iter()
            .map(|&i| {
                let t = &input[i as usize];
                RtTriangle {
                    v0: t.v0,
                    e1: t.v1 - t.v0,
                    e2: t.v2 - t.v0,
                }
            })
            .collect();
        let original = order.iter().map(|&i| unique[i as usize]).collect();
        let casts = order.iter().map(|&i| casts_any[i as usize]).collect();
        let flat = bvh_depth(&bvh) > MAX_BVH_DEPTH;
        Visibility {
            bvh: Some(bvh),
            flat,
            triangles,
            original,
            casts,
            objects,
            floor,
            epsilon,
        }
    }

    /// Whether rays test every triangle because no BVH shallow enough for the traversal
    /// could be built ([`MAX_BVH_DEPTH`]).
    pub fn is_flat(&self) -> bool {
        self.flat
    }

    /// The largest ray origin offset anywhere within the scene's bounds (that of the
    /// bounds' largest coordinate): a point moved by a few times this off a surface is
    /// clear of it.
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// The ray origin offset at `x` (see the module docs): [`OFFSET_RELATIVE`] of its
    /// largest coordinate magnitude, at least [`OFFSET_SCENE`] of the scene's.
    pub fn offset_at(&self, x: Vec3) -> f32 {
        (OFFSET_RELATIVE * x.abs().max_element()).max(self.floor)
    }

    /// Number of triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// True when a triangle of a casting object crosses the segment from `origin` to `target`, ignoring
    /// each end's offset ([`Visibility::offset_at`]) at either end.
    pub fn occluded(&self, origin: Vec3, target: Vec3) -> bool {
        let d = target - origin;
        let len = d.length();
        let (a, b) = (self.offset_at(origin), self.offset_at(target));
        if !(len.is_finite() && len > a + b) {
            return false;
        }
        self.ray_blocked(origin, d / len, a, len - b)
    }

    /// What the camera of `scene` (the scene this query was built from) sees through the
    /// image point `(u, v)` (0..1 across, 0..1 down; pixel centres at `(x + 0.5) / width`):
    /// the nearest surface point on the ray between the near and far planes and the face
    /// normal of its triangle turned towards the camera (the side it sees, as the camera
    /// pass writes it), or `None` where the ray meets nothing. A CPU G-buffer, for checking
    /// what the GPU shaded.
    pub fn seen_by_camera(&self, scene: &Scene, u: f32, v: f32) -> Option<(Vec3, Vec3)> {
        let inv = scene.camera_view_proj().inverse();
        let at = |z| {
            let p = inv * glam::Vec4::new(u * 2.0 - 1.0, 1.0 - v * 2.0, z, 1.0);
            p.truncate() / p.w
        };
        let (p0, p1) = (at(0.0), at(1.0));
        let d = (p1 - p0).normalize();
        let (t, i) = self.closest_hit(p0, d, (p1 - p0).length())?;
        let [a, b, c] = *scene.triangles().get(i)?;
        let n = (b - a).cross(c - a).normalize();
        Some((p0 + d * t, if n.dot(d) > 0.0 { -n } else { n }))
    }

    /// The object whose surface the camera of `scene` (the scene this query was built
    /// from) shows at world position `p` (a point of the camera pass's position image):
    /// the first triangle met by the camera's ray through `p`, cast from `16 *
    /// epsilon()` before `p` to as far beyond it ([`Visibility::epsilon`]: positions the
    /// camera pass interpolates lie on their triangle's plane to within a few ulps, far
    /// inside that). `None` for a non-finite `p` or no triangle there.
    pub fn object_seen(&self, scene: &Scene, p: Vec3) -> Option<usize> {
        if !p.is_finite() {
            return None;
        }
        let dir = match &scene.camera {
            crate::scene::Camera::Perspective { position, .. } => (p - *position).try_normalize()?,
            crate::scene::Camera::Orthographic { position, target, .. } => (*target - *position).try_normalize()?,
        };
        let s = 16.0 * self.epsilon;
        let (_, t) = self.closest_hit(p - dir * s, dir, 2.0 * s)?;
        scene.object_of_triangle(t)
    }

    /// For each of `positions`, whether the camera shows there an object that casts no
    /// shadow (`casts: false`; [`Visibility::object_seen`]), in parallel.
    pub fn on_non_casters(&self, scene: &Scene, positions: &[Vec3]) -> Vec<bool> {
        positions
            .par_iter()
            .map(|&p| self.object_seen(scene, p).is_some_and(|o| !scene.casts(o)))
            .collect()
    }

    /// For each of `positions`, whether the camera shows there an object that receives no
    /// shadow (`receives: false`; [`Visibility::object_seen`]), in parallel.
    pub fn on_non_receivers(&self, scene: &Scene, positions: &[Vec3]) -> Vec<bool> {
        positions
            .par_iter()
            .map(|&p| self.object_seen(scene, p).is_some_and(|o| !scene.receives(o)))
            .collect()
    }

    /// The nearest triangle along the ray from `origin` in unit direction `dir` with
    /// `0 < t < t_max`: its distance `t` and its index in [`Scene::triangles`].
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(f32, usize)> {
        let bvh = self.bvh.as_ref()?;
        if !(origin.is_finite() && dir.is_finite() && t_max > 0.0) {
            return None;
        }
        if self.flat {
            let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
            return self
                .triangles
                .iter()
                .enumerate()
                .filter_map(|(k, t)| Some((t.hit(o, d, 0.0, t_max)?, k)))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(t, k)| (t, self.original[k] as usize));
        }
        let ray = Ray::new(Vec3A::from(origin), positive_zeros(dir), 0.0, t_max);
        let mut hit = RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |ray, id| {
            self.triangles[id]
                .hit(ray.origin, ray.direction, ray.tmin, ray.tmax)
                .unwrap_or(f32::INFINITY)
        })
        .then(|| (hit.t, self.original[hit.primitive_id as usize] as usize))
    }

    /// True when a triangle of a casting object lies along the ray at distance `t` with
    /// `t_min < t < t_max` (`dir` a unit vector).
    fn ray_blocked(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        if t_max.partial_cmp(&t_min) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        let (o, d) = (Vec3A::from(origin), positive_zeros(dir));
        if self.flat {
            return self
                .triangles
                .iter()
                .zip(&self.casts)
                .any(|(t, &c)| c && t.hit(o, d, t_min, t_max).is_some());
        }
        let ray = Ray::new(o, d, t_min, t_max);
        !bvh.ray_traverse_miss(ray, |ray, id| {
            if !self.casts[id] {
                return f32::INFINITY;
            }
            self.triangles[id]
                .hit(ray.origin, ray.direction, ray.tmin, ray.tmax)
                .unwrap_or(f32::INFINITY)
        })
    }

    /// The fraction of `light` visible from `x` (1 = fully lit), with `samples x samples`
    /// stratified samples drawn from a generator seeded by `seed` (deterministic). A
    /// non-finite `x` (no surface) gives 1. See the module docs for how each light is
    /// sampled.
    pub fn visible_fraction(&self, x: Vec3, light: &Light, samples: u32, seed: u64) -> f32 {
        self.fraction(x, None, light, samples, seed, true)
    }

    /// As [`Visibility::visible_fraction`], with the receiver's surface normal on the side
    /// it is seen from (the camera's side; see the module docs on two-sided surfaces): the
    /// ray origin moves off the surface along it, light behind its tangent plane is
    /// blocked, and the surface's own half-space is excluded from the skip test, so that
    /// most lit points cost no ray at all. A zero or non-finite normal is ignored.
    pub fn visible_fraction_at(&self, x: Vec3, normal: Vec3, light: &Light, samples: u32, seed: u64) -> f32 {
        self.fraction(x, Some(normal), light, samples, seed, true)
    }

    /// [`Visibility::visible_fraction_at`] for many points in parallel (rayon), with seed 0.
    /// `normals` is empty (unknown) or has one normal per point; point `i` uses a seed
    /// derived from `i`, so results do not depend on the thread count.
    pub fn visible_fractions(&self, points: &[Vec3], normals: &[Vec3], light: &Light, samples: u32) -> Vec<f32> {
        self.visible_fractions_seeded(points, normals, light, samples, 0)
    }

    /// [`Visibility::visible_fractions`] with a seed: different seeds give independent
    /// estimates (for measuring convergence).
    ///
    /// # Panics
    /// When `normals` is neither empty nor as long as `points`.
    pub fn visible_fractions_seeded(&self, points: &[Vec3], normals: &[Vec3], light: &Light, samples: u32, seed: u64) -> Vec<f32> {
        assert!(
            normals.is_empty() || normals.len() == points.len(),
            "visible_fractions: {} normals for {} points",
            normals.len(),
            points.len()
        );
        let base = mix(seed);
        points
            .par_iter()
            .enumerate()
            .map(|(i, &x)| {
                let n = normals.get(i).copied();
                self.fraction(x, n, light, samples, base ^ mix(i as u64), true)
            })
            .collect()
    }

    /// The visible fraction; `skip` enables the test that answers 1 without casting rays.
    fn fraction(&self, x: Vec3, normal: Option<Vec3>, light: &Light, samples: u32, seed: u64, skip: bool) -> f32 {
        if !x.is_finite() || self.bvh.is_none() {
            return 1.0;
        }
        let shaft = shaft(light);
        // The normal of the side the receiver is seen from; the origin moves along it and
        // every hit at t > 0 counts. Without one, hits within the offset are ignored.
        let normal = normal.filter(|n| n.is_finite() && n.length_squared() > 0.0).map(Vec3::normalize);
        let offset = self.offset_at(x);
        let (o, t_min) = match normal {
            Some(n) => (x + n * offset, 0.0),
            None => (x, offset),
        };
        if let Some(n) = normal
            && self.wholly_behind(o, n, shaft)
        {
            return 0.0;
        }
        if skip && self.nothing_between(o, normal, shaft) {
            return 1.0;
        }
        // Light from behind the receiver's tangent plane is blocked by its own surface.
        let in_front = |w: Vec3| normal.is_none_or(|n| w.dot(n) > 0.0);
        let n = samples.max(1);
        let total = n * n;
        let mut rng = Rng::new(seed);
        let to_point = |l: Vec3| {
            let d = l - o;
            let len = d.length();
            let end = self.offset_at(l);
            if len.is_nan() || len <= t_min + end {
                return true;
            }
            let w = d / len;
            in_front(w) && !self.ray_blocked(o, w, t_min, len - end)
        };
        let along = |dir: Vec3| in_front(dir) && !self.ray_blocked(o, dir, t_min, f32::INFINITY);
        match light {
            Light::Point { position } => f32::from(u8::from(to_point(*position))),
            Light::Directional { direction } => f32::from(u8::from(along(direction.normalize_or(Vec3::Y)))),
            Light::Rectangle {
                center,
                normal,
                u_axis,
                half_width,
                half_height,
            } => {
                let u_dir = u_axis.normalize_or(Vec3::X);
                let v_dir = normal.normalize_or(Vec3::Y).cross(u_dir);
                let (cu, cv) = (u_dir * *half_width, v_dir * *half_height);
                stratified(n, &mut rng, |u, v| to_point(*center + cu * (2.0 * u - 1.0) + cv * (2.0 * v - 1.0)))
            }
            Light::Triangle { a, b, c } => {
                // uniform over the area: the square-root warp of the unit square onto the
                // triangle (Shirley and Chiu's; barycentrics (1 - sqrt u, sqrt u (1 - v),
                // sqrt u v))
                stratified(n, &mut rng, |u, v| {
                    let su = u.sqrt();
                    to_point(*a * (1.0 - su) + *b * (su * (1.0 - v)) + *c * (su * v))
                })
            }
            Light::Disk { center, normal, radius } => {
                let (t, b) = normal.normalize_or(Vec3::Y).any_orthonormal_pair();
                stratified(n, &mut rng, |u, v| {
                    let p = concentric(u, v) * *radius;
                    to_point(*center + t * p.x + b * p.y)
                })
            }
            Light::Segment { a, b } => {
                // n^2 strata along the length.
                let mut lit = 0u32;
                for k in 0..total {
                    let s = ((k as f32 + rng.next_f32()) / total as f32).min(1.0);
                    lit += u32::from(to_point(a.lerp(*b, s)));
                }
                lit as f32 / total as f32
            }
            Light::Sphere { center, radius } => {
                let d = *center - o;
                let dist = d.length();
                if *radius <= 0.0 {
                    return f32::from(u8::from(to_point(*center)));
                }
                if dist <= *radius {
                    return 1.0;
                }
                let axis = d / dist;
                let (t, b) = axis.any_orthonormal_pair();
                let sin_max = radius / dist;
                let cos_max = (1.0 - sin_max * sin_max).max(0.0).sqrt();
                stratified(n, &mut rng, |u, v| {
                    let cos_t = 1.0 - u * (1.0 - cos_max);
                    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                    let phi = TAU * v;
                    let w = (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize();
                    // Distance to the near side of the sphere along w.
                    let disc = (radius * radius - dist * dist * sin_t * sin_t).max(0.0);
                    let t_hit = dist * cos_t - disc.sqrt();
                    in_front(w) && !self.ray_blocked(o, w, t_min, t_hit - self.offset_at(o + w * t_hit))
                })
            }
            Light::DistantDisk { direction, angle_degrees } => {
                let dir = direction.normalize_or(Vec3::Y);
                let k = (0.5 * angle_degrees.to_radians()).tan();
                if k <= 0.0 {
                    return f32::from(u8::from(along(dir)));
                }
                let (t, b) = dir.any_orthonormal_pair();
                stratified(n, &mut rng, |u, v| {
                    let p = concentric(u, v) * k;
                    along((dir + t * p.x + b * p.y).normalize())
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {

    use super::*;

    /// Issue 48, item 3: copies of one triangle (90 k of them took 82 s to build and made a
    /// tree deeper than obvhs's traversal walks) go into the BVH once, casting if any copy
    /// casts; nearly coincident ones that still build too deep a tree make every ray test
    /// every triangle, with a warning, rather than miss some.
    #[test]
    fn coincident_triangles_build_once_and_a_tree_too_deep_is_never_walked() {
        let scene = |copies: usize, jitter: f32| {
            let tris: Vec<String> = (0..copies)
                .map(|k| {
                    format!(
                        "Object(casts: {}, mesh: Triangle(a: ({}, 1.0, -0.5), b: (-0.5, 1.0, -0.5), c: (0.0, 1.0, 0.5)))",
                        k > 0,
                        0.5 + k as f32 * jitter
                    )
                })
                .collect();
            Scene::from_str(
                &format!(
                    "Scene(camera: Perspective(position: (0.0, 3.0, 3.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 8, height: 8),
                     shadow_map: 16, lights: [Point(position: (0.0, 3.0, 0.0))],
                     objects: [Object(mesh: Plane(size: (3.0, 3.0))), {}])",
                    tris.join(", ")
                ),
                ".",
            )
            .unwrap()
        };
        let under = Vec3::new(0.0, 0.0, -0.1);
        let beside = Vec3::new(1.2, 0.0, 1.2);
        let light = Vec3::new(0.0, 3.0, 0.0);
        let down = Vec3::new(0.01, -1.0, 0.02).normalize();
        let same = scene(3000, 0.0);
        let vis = Visibility::new(&same);
        assert_eq!(vis.triangle_count(), 2 + 1, "the plane's two and one copy");
        assert!(!vis.is_flat() && vis.light_warnings(&same).is_empty());
        // the first copy casts nothing, the others do: the one kept casts
        assert!(vis.occluded(under, light) && !vis.occluded(beside, light));
        // the camera sees the first copy (the plane's two triangles come first)
        let (_, t) = vis.closest_hit(Vec3::new(0.01, 2.0, -0.1), down, 5.0).unwrap();
        assert_eq!(t, 2);
        // a direction with negative zeros hits as its positive twin (it missed everything)
        for o in [Vec3::new(0.2, 2.0, 0.7), Vec3::new(0.0, 2.0, -0.1)] {
            assert_eq!(
                vis.closest_hit(o, -Vec3::Y, 5.0),
                vis.closest_hit(o, Vec3::new(0.0, -1.0, 0.0), 5.0)
            );
            assert!(vis.closest_hit(o, -Vec3::Y, 5.0).is_some());
            assert!(vis.occluded(Vec3::new(o.x, 1.5, o.z), Vec3::new(o.x, -1.0, o.z)));
        }
        // copies 1e-7 apart: distinct, and a tree too deep for the traversal
        let near = scene(3000, 1e-7);
        let vis = Visibility::new(&near);
        assert_eq!(vis.triangle_count(), 2 + 3000);
        assert!(vis.is_flat(), "a BVH of depth {}", vis.bvh.as_ref().map_or(0, bvh_depth));
        assert!(vis.occluded(under, light) && !vis.occluded(beside, light));
        let (_, t) = vis.closest_hit(Vec3::new(0.01, 2.0, -0.1), down, 5.0).unwrap();
        assert!((2..3002).contains(&t), "{t}");
        let w = vis.light_warnings(&near);
        assert!(
            w.len() == 1 && w[0].contains("could not be arranged in a BVH of at most 31 levels"),
            "{w:?}"
        );
    }

    /// A triangle light is sampled uniformly over its area: the right triangle x, z >= 0,
    /// x + z <= 1 at height 2 over a receiver at the origin, behind a half-plane at height 1
    /// that covers x > 0.25 (so it hides the light's points with x > 0.5: a quarter of the
    /// area, (0.5^2 / 2) / (1 / 2)). The exact visibility is 0.75; sampling the barycentrics
    /// without the square-root warp would give 0.5 + 0.5 ln 2 = 0.847.
    #[test]
    fn a_triangle_light_is_sampled_uniformly_over_its_area() {
        let scene = Scene::from_str(
            "Scene(camera: Perspective(position: (0.0, 3.0, 3.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 8, height: 8),
             shadow_map: 16, lights: [Triangle(a: (0.0, 2.0, 0.0), b: (1.0, 2.0, 0.0), c: (0.0, 2.0, 1.0))],
             objects: [Object(mesh: Quad(a: (0.25, 1.0, -5.0), b: (0.25, 1.0, 5.0), c: (5.0, 1.0, 5.0), d: (5.0, 1.0, -5.0)))])",
            ".",
        )
        .unwrap();
        let vis = Visibility::new(&scene);
        // 128 x 128 jittered strata: the blocked region's boundary (u (1 - v) = 1/4 in the
        // unit square, after the warp) crosses at most 2 x 128 strata, each off by at most
        // 1 / 128^2: the estimate is within 2 / 128 = 0.016 of 0.75 whatever the jitter.
        let n = 128;
        for seed in 0..4 {
            let v = vis.fraction(Vec3::ZERO, Some(Vec3::Y), &scene.lights[0], n, seed, false);
            assert!((v - 0.75).abs() <= 2.0 / n as f32, "seed {seed}: {v}");
        }
    }
}
