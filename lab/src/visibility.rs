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
//! Ray origins: rays start at the receiver and hits closer than [`Visibility::epsilon`]
//! (1e-4 of the scene bounds' diagonal, at least 32 ulp of the largest coordinate) are
//! ignored. When the receiver's normal is known, the origin is also moved by epsilon
//! along the normal, to the side of the light's centre. Both only affect occluders within
//! epsilon of the receiver (contact shadows narrower than epsilon).
//!
//! Skipping: before sampling, each object's bounding box is tested against the region
//! where an occluder could be. An object cannot occlude if it lies entirely on or behind a
//! plane through the ray origin that has the whole light strictly in front (the plane
//! towards the light's centre, and the receiver's tangent plane when the light lies wholly
//! above it), or if its bounding sphere misses the cone from the origin that holds the
//! whole light (and, for a light at a finite position, lies beyond it). When no object
//! can occlude, the answer is 1 without casting a ray. The test is conservative: it never
//! changes a result.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, TAU};
use std::time::Duration;

use glam::{Vec2, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use crate::scene::{Light, Scene, corners};

/// Barycentric tolerance of the ray-triangle test (see the module docs).
const BARY_TOLERANCE: f32 = 1e-6;

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

/// The region that holds every point of a light, seen from a receiver.
#[derive(Clone, Copy, Debug)]
enum Shaft {
    /// All light points lie in the sphere (`centre`, `radius`).
    Local { centre: Vec3, radius: f32 },
    /// All light directions lie within `half_angle` of `direction` (unit).
    Distant { direction: Vec3, half_angle: f32 },
}

fn shaft(light: &Light) -> Shaft {
    match (light.center(), light.direction()) {
        (Some(centre), _) => Shaft::Local {
            centre,
            radius: light.bounding_radius(),
        },
        (None, direction) => Shaft::Distant {
            direction: direction.unwrap_or(Vec3::Y),
            half_angle: 0.5 * light.angle(),
        },
    }
}

/// A small deterministic generator (SplitMix64).
#[derive(Clone, Debug)]
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(mix(seed ^ 0x243f_6a88_85a3_08d3))
    }
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix(self.0)
    }
    /// Uniform in [0, 1).
    fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// SplitMix64's finaliser: a 64-bit mixing function.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Fraction of `n x n` jittered samples `(u, v)` of the unit square (one per cell) for
/// which `visible(u, v)` holds.
fn stratified(n: u32, rng: &mut Rng, mut visible: impl FnMut(f32, f32) -> bool) -> f32 {
    let mut lit = 0u32;
    for i in 0..n {
        for j in 0..n {
            let u = (i as f32 + rng.next_f32()) / n as f32;
            let v = (j as f32 + rng.next_f32()) / n as f32;
            lit += u32::from(visible(u.min(1.0), v.min(1.0)));
        }
    }
    lit as f32 / (n * n) as f32
}

/// Shirley–Chiu concentric map from the unit square to the unit disk (area-preserving).
fn concentric(u: f32, v: f32) -> Vec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Ray casting against a scene's triangles.
pub struct Visibility {
    bvh: Option<CwBvh>,
    /// Triangles in the BVH's primitive order.
    triangles: Vec<RtTriangle>,
    /// For each of `triangles`, its index in [`Scene::triangles`].
    original: Vec<u32>,
    objects: Vec<ObjectBounds>,
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
        let epsilon = (1e-4 * (hi - lo).length())
            .max(32.0 * f32::EPSILON * largest)
            .max(f32::MIN_POSITIVE);
        let objects = (0..scene.objects().len())
            .filter_map(|i| {
                let range = scene.object_triangles(i);
                if range.is_empty() {
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
                triangles: Vec::new(),
                original: Vec::new(),
                objects,
                epsilon,
            };
        }
        let input: Vec<Triangle> = tris
            .iter()
            .map(|t| Triangle {
                v0: t[0].into(),
                v1: t[1].into(),
                v2: t[2].into(),
            })
            .collect();
        let bvh = build_cwbvh_from_tris(&input, BvhBuildParams::medium_build(), &mut Duration::default());
        let triangles = bvh
            .primitive_indices
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
        let original = bvh.primitive_indices.clone();
        Visibility {
            bvh: Some(bvh),
            triangles,
            original,
            objects,
            epsilon,
        }
    }

    /// The ray offset: hits closer than this to the receiver are ignored (1e-4 of the
    /// scene bounds' diagonal, at least 32 ulp of the largest coordinate).
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// Number of triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// True when a triangle crosses the segment from `origin` to `target`, ignoring
    /// epsilon at either end.
    pub fn occluded(&self, origin: Vec3, target: Vec3) -> bool {
        let d = target - origin;
        let len = d.length();
        if !(len.is_finite() && len > 2.0 * self.epsilon) {
            return false;
        }
        self.ray_blocked(origin, d / len, self.epsilon, len - self.epsilon)
    }

    /// What the camera of `scene` (the scene this query was built from) sees through the
    /// image point `(u, v)` (0..1 across, 0..1 down; pixel centres at `(x + 0.5) / width`):
    /// the nearest surface point on the ray between the near and far planes and the face
    /// normal of its triangle, or `None` where the ray meets nothing. A CPU G-buffer, for
    /// checking what the GPU shaded.
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
        Some((p0 + d * t, (b - a).cross(c - a).normalize()))
    }

    /// The nearest triangle along the ray from `origin` in unit direction `dir` with
    /// `epsilon < t < t_max`: its distance `t` and its index in [`Scene::triangles`].
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(f32, usize)> {
        let bvh = self.bvh.as_ref()?;
        if !(origin.is_finite() && dir.is_finite() && t_max > self.epsilon) {
            return None;
        }
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), self.epsilon, t_max);
        let mut hit = RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |ray, id| {
            self.triangles[id]
                .hit(ray.origin, ray.direction, ray.tmin, ray.tmax)
                .unwrap_or(f32::INFINITY)
        })
        .then(|| (hit.t, self.original[hit.primitive_id as usize] as usize))
    }

    /// True when a triangle lies along the ray at distance `t` with `t_min < t < t_max`
    /// (`dir` a unit vector).
    fn ray_blocked(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        if t_max.partial_cmp(&t_min) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        let ray = Ray::new(o, d, t_min, t_max);
        !bvh.ray_traverse_miss(ray, |ray, id| {
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

    /// As [`Visibility::visible_fraction`], with the receiver's surface normal: the ray
    /// origin moves epsilon off the surface, and the surface's own half-space is excluded
    /// from the skip test, so that most lit points cost no ray at all. A zero or
    /// non-finite normal is ignored.
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
        let eps = self.epsilon;
        let shaft = shaft(light);
        let towards = match shaft {
            Shaft::Local { centre, .. } => centre - x,
            Shaft::Distant { direction, .. } => direction,
        };
        // The normal, turned to the side of the light's centre; the origin moves along it.
        let normal = normal.filter(|n| n.is_finite() && n.length_squared() > 0.0).map(|n| {
            let n = n.normalize();
            if n.dot(towards) < 0.0 { -n } else { n }
        });
        let o = match normal {
            Some(n) => x + n * eps,
            None => x,
        };
        if skip && self.nothing_between(o, normal, shaft) {
            return 1.0;
        }
        let n = samples.max(1);
        let total = n * n;
        let mut rng = Rng::new(seed);
        let to_point = |l: Vec3| {
            let d = l - o;
            let len = d.length();
            len.is_nan() || len <= 2.0 * eps || !self.ray_blocked(o, d / len, eps, len - eps)
        };
        let along = |dir: Vec3| !self.ray_blocked(o, dir, eps, f32::INFINITY);
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
                    !self.ray_blocked(o, w, eps, t_hit - eps)
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

    /// True when no object can lie between `o` and the light (see the module docs).
    /// `normal` is the receiver's unit normal turned towards the light's centre.
    fn nothing_between(&self, o: Vec3, normal: Option<Vec3>, shaft: Shaft) -> bool {
        // Planes through `o` with the whole light strictly in front.
        let mut planes: [Option<Vec3>; 2] = [None, None];
        // The cone from `o` holding the light: axis, half-angle, and length (infinite for
        // distant lights).
        let (axis, half_angle, length) = match shaft {
            Shaft::Local { centre, radius } => {
                let d = centre - o;
                let dist = d.length();
                if dist.is_nan() || dist <= radius * (1.0 + 1e-4) + self.epsilon {
                    return false;
                }
                let axis = d / dist;
                planes[0] = Some(axis);
                if let Some(n) = normal
                    && d.dot(n) > radius * (1.0 + 1e-4) + self.epsilon
                {
                    planes[1] = Some(n);
                }
                (axis, (radius / dist).min(1.0).asin(), dist + radius)
            }
            Shaft::Distant { direction, half_angle } => {
                planes[0] = Some(direction);
                if let Some(n) = normal
                    && direction.dot(n) > half_angle.sin() + 1e-4
                {
                    planes[1] = Some(n);
                }
                (direction, half_angle, f32::INFINITY)
            }
        };
        self.objects.iter().all(|ob| {
            let behind = planes
                .iter()
                .flatten()
                .any(|p| corners((ob.lo, ob.hi)).iter().all(|c| (*c - o).dot(*p) <= 0.0));
            if behind {
                return true;
            }
            let v = ob.centre - o;
            let dist = v.length();
            if dist <= ob.radius * (1.0 + 1e-4) + self.epsilon {
                return false;
            }
            if dist - ob.radius > length {
                return true;
            }
            let gamma = (v.dot(axis) / dist).clamp(-1.0, 1.0).acos();
            gamma > half_angle + (ob.radius / dist).min(1.0).asin() + 1e-4
        })
    }
}

#[cfg(test)]
mod tests {

    use super::*;

    /// Surface points and normals the camera sees on a `k x k` grid of pixels.
    fn camera_points(scene: &Scene, vis: &Visibility, k: u32) -> Vec<(Vec3, Vec3)> {
        (0..k * k)
            .filter_map(|i| vis.seen_by_camera(scene, ((i % k) as f32 + 0.5) / k as f32, ((i / k) as f32 + 0.5) / k as f32))
            .collect()
    }

    /// The skip test is conservative: with it and without it, every light kind gives the
    /// same answers (same samples, same seed) at the points each bundled scene shows.
    #[test]
    fn skipping_never_changes_a_result() {
        for name in ["bunny", "contact", "fence", "edge", "triangle"] {
            let path = format!("{}/../scenes/{name}.ron", env!("CARGO_MANIFEST_DIR"));
            let scene = Scene::load(&path).unwrap();
            let vis = Visibility::new(&scene);
            let (lo, hi) = scene.bounds();
            let (mid, size) = ((lo + hi) * 0.5, (hi - lo).length());
            let above = mid + Vec3::new(0.3, 1.0, 0.2) * size;
            let mut lights = scene.lights.clone();
            lights.extend([
                Light::Point { position: above },
                Light::Directional {
                    direction: Vec3::new(0.3, 1.0, 0.2).normalize(),
                },
                Light::Sphere {
                    center: above,
                    radius: 0.1 * size,
                },
                Light::Disk {
                    center: above,
                    normal: -Vec3::Y,
                    radius: 0.1 * size,
                },
                Light::Segment {
                    a: above - Vec3::X * 0.2 * size,
                    b: above + Vec3::X * 0.2 * size,
                },
                Light::DistantDisk {
                    direction: Vec3::new(-0.2, 1.0, 0.1).normalize(),
                    angle_degrees: 20.0,
                },
            ]);
            let points = camera_points(&scene, &vis, 20);
            assert!(points.len() > 100, "{name}: the camera sees too little");
            let mut skipped = 0;
            for light in &lights {
                for (k, &(x, n)) in points.iter().enumerate() {
                    for normal in [Some(n), None] {
                        let with = vis.fraction(x, normal, light, 3, k as u64, true);
                        let without = vis.fraction(x, normal, light, 3, k as u64, false);
                        assert_eq!(with, without, "{name}: {light:?} at {x} (normal {normal:?})");
                    }
                    let towards = light.center().map_or_else(|| light.direction().unwrap(), |c| c - x);
                    let n = if n.dot(towards) < 0.0 { -n } else { n };
                    skipped += usize::from(vis.nothing_between(x + n * vis.epsilon(), Some(n), shaft(light)));
                }
            }
            // The edge scene's occluder hangs over every point the camera sees.
            assert!(skipped > 0 || name == "edge", "{name}: the skip test never fired");
        }
    }

    #[test]
    fn concentric_map_stays_in_the_disk_and_keeps_halves() {
        for i in 0..=64 {
            for j in 0..=64 {
                let (u, v) = (i as f32 / 64.0, j as f32 / 64.0);
                let p = concentric(u, v);
                assert!(p.length() <= 1.0 + 1e-6);
                // Left half of the square -> left half of the disk (exact half splits).
                if u < 0.5 {
                    assert!(p.x <= 0.0, "{u} {v} -> {p}");
                }
                if u > 0.5 {
                    assert!(p.x >= 0.0, "{u} {v} -> {p}");
                }
            }
        }
    }
}
