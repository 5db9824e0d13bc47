//! Lights inside or on the geometry ([`Visibility::light_warnings`]): a light's centre on
//! a surface, an area light meeting a triangle, a light's centre inside a closed mesh.
//! Such a light has no defined shadow; the scene is warned of it, not refused.

use glam::{Vec2, Vec3, Vec3A};

use super::{MAX_BVH_DEPTH, RtTriangle, Visibility};
use crate::scene::{Light, Scene};

/// A light centre closer than this many ray offsets to a triangle lies on its surface
/// ([`Visibility::light_warnings`]).
pub const LIGHT_CONTACT_OFFSETS: f32 = 4.0;

/// Rays cast from a light's centre to tell whether it lies inside a closed mesh
/// ([`Visibility::light_warnings`]).
pub const INSIDE_RAYS: u32 = 64;

/// The point of triangle `t` nearest to `p` (Ericson, "Real-Time Collision Detection",
/// section 5.1.5, by the Voronoi regions of the corners and edges).
fn closest_on_triangle(p: Vec3, t: &[Vec3; 3]) -> Vec3 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// True when the area light meets triangle `t`: a sphere with the triangle within its
/// radius; a disk or rectangle whose plane cuts the triangle in a segment that meets the
/// light's outline; a segment light crossing it (the ray-triangle test); a triangle light
/// and the triangle crossing (an edge of either through the other, the ray-triangle test;
/// coplanar overlaps are not found).
fn light_meets(light: &Light, t: &[Vec3; 3]) -> bool {
    // The segment in which the plane (point `c`, unit normal `n`) cuts the triangle.
    let cut = |c: Vec3, n: Vec3| -> Option<(Vec3, Vec3)> {
        let d = t.map(|p| (p - c).dot(n));
        let mut pts = [Vec3::ZERO; 3];
        let mut k = 0;
        for i in 0..3 {
            let j = (i + 1) % 3;
            if d[i] == 0.0 {
                pts[k] = t[i];
                k += 1;
            } else if (d[i] < 0.0) != (d[j] < 0.0) && d[j] != 0.0 {
                pts[k] = t[i] + (t[j] - t[i]) * (d[i] / (d[i] - d[j]));
                k += 1;
            }
        }
        (k >= 2).then(|| (pts[0], pts[k - 1]))
    };
    // Nothing farther than the light's bounding sphere can meet it.
    if let Some(c) = light.center() {
        let r = light.bounding_radius();
        let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
        if c.clamp(lo, hi).distance(c) > r {
            return false;
        }
    }
    match light {
        Light::Sphere { center, radius } => *radius > 0.0 && closest_on_triangle(*center, t).distance(*center) < *radius,
        Light::Disk { center, normal, radius } => {
            let Some((p, q)) = cut(*center, normal.normalize_or(Vec3::Y)) else {
                return false;
            };
            // Distance from the centre to the segment pq.
            let pq = q - p;
            let s = if pq.length_squared() > 0.0 {
                ((*center - p).dot(pq) / pq.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p + pq * s).distance(*center) < *radius
        }
        Light::Rectangle {
            center,
            normal,
            u_axis,
            half_width,
            half_height,
        } => {
            let n = normal.normalize_or(Vec3::Y);
            let Some((p, q)) = cut(*center, n) else { return false };
            let u = u_axis.normalize_or(Vec3::X);
            let v = n.cross(u);
            // Liang–Barsky: clip the segment to |u| <= half_width, |v| <= half_height.
            let (p2, q2) = (
                Vec2::new((p - *center).dot(u), (p - *center).dot(v)),
                Vec2::new((q - *center).dot(u), (q - *center).dot(v)),
            );
            let d = q2 - p2;
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for (pk, qk) in [
                (-d.x, p2.x + half_width),
                (d.x, half_width - p2.x),
                (-d.y, p2.y + half_height),
                (d.y, half_height - p2.y),
            ] {
                if pk == 0.0 {
                    if qk < 0.0 {
                        return false;
                    }
                } else {
                    let r = qk / pk;
                    if pk < 0.0 {
                        lo = lo.max(r);
                    } else {
                        hi = hi.min(r);
                    }
                }
            }
            lo <= hi
        }
        Light::Segment { a, b } => {
            let d = *b - *a;
            let len = d.length();
            let tri = RtTriangle {
                v0: t[0].into(),
                e1: (t[1] - t[0]).into(),
                e2: (t[2] - t[0]).into(),
            };
            len > 0.0 && tri.hit(Vec3A::from(*a), Vec3A::from(d / len), 0.0, len).is_some()
        }
        Light::Triangle { a, b, c } => {
            let crosses = |tri: &[Vec3; 3], p: Vec3, q: Vec3| {
                let rt = RtTriangle {
                    v0: tri[0].into(),
                    e1: (tri[1] - tri[0]).into(),
                    e2: (tri[2] - tri[0]).into(),
                };
                let d = q - p;
                let len = d.length();
                len > 0.0 && rt.hit(Vec3A::from(p), Vec3A::from(d / len), 0.0, len).is_some()
            };
            let l = [*a, *b, *c];
            (0..3).any(|i| crosses(&l, t[i], t[(i + 1) % 3]) || crosses(t, l[i], l[(i + 1) % 3]))
        }
        Light::Point { .. } | Light::Directional { .. } | Light::DistantDisk { .. } => false,
    }
}

impl Visibility {
    /// Warnings about lights inside or on the geometry, each naming the light and the
    /// object (`scene` is the scene this query was built from). Such a light has no
    /// defined shadow: the techniques and the truth each read it their own way (a point
    /// light on the floor: csm 0.47 against a truth of 0.95). Warned:
    ///
    /// - a light's centre within [`LIGHT_CONTACT_OFFSETS`] = 4 ray offsets
    ///   ([`Visibility::offset_at`]) of a triangle (it lies on a surface);
    /// - an area light meeting a triangle: a sphere with a triangle within its radius, a
    ///   disk or rectangle crossed by one (exact tests), a segment through one (a ray);
    /// - a light's centre inside a closed mesh: of [`INSIDE_RAYS`] = 64 rays from it in
    ///   directions spread over the sphere (a Fibonacci lattice), more than half hit the
    ///   back (the side the winding does not face) of one object's triangles.
    pub fn light_warnings(&self, scene: &Scene) -> Vec<String> {
        let tris = scene.triangles();
        let object_of = |t: usize| (0..scene.objects().len()).find(|&i| scene.object_triangles(i).contains(&t));
        let name = |i: usize| match &scene.objects()[i].name {
            Some(n) => format!("objects[{i}] (\"{n}\")"),
            None => format!("objects[{i}]"),
        };
        let mut out = Vec::new();
        if self.flat {
            out.push(format!(
                "the scene's {} triangles could not be arranged in a BVH of at most {MAX_BVH_DEPTH} levels (many nearly coincident triangles?): the truth's rays test every triangle, which is slow on a large scene",
                self.triangles.len()
            ));
        }
        for (li, light) in scene.lights.iter().enumerate() {
            let Some(c) = light.center() else { continue };
            let what = format!("lights[{li}] ({})", light.kind_name());
            // The light's own depth range, said only where nothing more specific is: a
            // light on, through or inside a caster loses its near plane too (issue 49).
            let before = out.len();
            'specific: {
                // The nearest triangle to the centre.
                let nearest = tris
                    .iter()
                    .enumerate()
                    .map(|(i, t)| (i, closest_on_triangle(c, t).distance(c)))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                let Some((t, dist)) = nearest else { break 'specific };
                let contact = LIGHT_CONTACT_OFFSETS * self.offset_at(c);
                if dist <= contact {
                    if let Some(o) = object_of(t) {
                        out.push(format!(
                            "{what} has its centre {dist:e} from a surface of {}, within {contact:e} (4 ray offsets): a light on a surface has no defined shadow, and the techniques and the truth disagree there; move it off the surface",
                            name(o)
                        ));
                    }
                    break 'specific;
                }
                // Area lights meeting a triangle.
                if let Some(t) = tris.iter().position(|t| light_meets(light, t)) {
                    if let Some(o) = object_of(t) {
                        out.push(format!(
                            "{what} passes through {}: part of the light lies inside or behind its surface, which the techniques and the truth treat differently; move the light clear of it",
                            name(o)
                        ));
                    }
                    break 'specific;
                }
                // Inside a closed mesh: most rays hit back faces of one object.
                let mut back = vec![0u32; scene.objects().len()];
                for k in 0..INSIDE_RAYS {
                    // Fibonacci lattice on the sphere.
                    let z = 1.0 - (2.0 * k as f32 + 1.0) / INSIDE_RAYS as f32;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let phi = k as f32 * 2.399_963;
                    let dir = Vec3::new(r * phi.cos(), z, r * phi.sin());
                    if let Some((_, t)) = self.closest_hit(c, dir, f32::INFINITY) {
                        let [a, b, cc] = tris[t];
                        if (b - a).cross(cc - a).dot(dir) > 0.0
                            && let Some(o) = object_of(t)
                        {
                            back[o] += 1;
                        }
                    }
                }
                if let Some((o, &n)) = back.iter().enumerate().max_by_key(|(_, n)| **n)
                    && 2 * n > INSIDE_RAYS
                {
                    out.push(format!(
                        "{what} has its centre inside {} ({n} of {INSIDE_RAYS} rays from it hit the inside of its surface): its light cannot leave the mesh, which the techniques and the truth treat differently; move the light outside",
                        name(o)
                    ));
                }
            }
            if out.len() == before
                && let Some(w) = scene.light_view(light).depth_warning()
            {
                out.push(format!("{what}: {w}"));
            }
        }
        out
    }
}
