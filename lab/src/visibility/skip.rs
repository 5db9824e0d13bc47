//! The skip test ("Skipping" in [`super`]'s docs): before sampling, whether any casting
//! object's bounds can lie between the ray origin and the light (the region that holds
//! the whole light, its [`Shaft`]); where none can, the answer is 1 without a ray, and a
//! light wholly behind the receiver's tangent plane gives 0. Conservative: it never changes
//! a result.

use glam::Vec3;

use super::Visibility;
use crate::scene::{Light, corners};

/// The region that holds every point of a light, seen from a receiver.
#[derive(Clone, Copy, Debug)]
pub(super) enum Shaft {
    /// All light points lie in the sphere (`centre`, `radius`).
    Local { centre: Vec3, radius: f32 },
    /// All light directions lie within `half_angle` of `direction` (unit).
    Distant { direction: Vec3, half_angle: f32 },
}

pub(super) fn shaft(light: &Light) -> Shaft {
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

impl Visibility {
    /// True when the whole light lies behind the plane through `o` with unit normal `n`
    /// (the receiver's tangent plane): every sample is blocked by the receiver's surface.
    pub(super) fn wholly_behind(&self, o: Vec3, n: Vec3, shaft: Shaft) -> bool {
        match shaft {
            Shaft::Local { centre, radius } => (centre - o).dot(n) <= -radius * (1.0 + 1e-4),
            Shaft::Distant { direction, half_angle } => direction.dot(n) <= -half_angle.sin() - 1e-4,
        }
    }

    /// True when no object can lie between `o` and the light (see the module docs).
    /// `normal` is the receiver's unit normal (the side it is seen from); a light not
    /// wholly in front of its tangent plane is partly blocked by the receiver itself, so
    /// the answer is then false.
    pub(super) fn nothing_between(&self, o: Vec3, normal: Option<Vec3>, shaft: Shaft) -> bool {
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
                if let Some(n) = normal {
                    if d.dot(n) <= radius * (1.0 + 1e-4) + self.epsilon {
                        return false;
                    }
                    planes[1] = Some(n);
                }
                (axis, (radius / dist).min(1.0).asin(), dist + radius)
            }
            Shaft::Distant { direction, half_angle } => {
                planes[0] = Some(direction);
                if let Some(n) = normal {
                    if direction.dot(n) <= half_angle.sin() + 1e-4 {
                        return false;
                    }
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
    use crate::scene::Scene;

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
        // triangle-lawlor: a ground that casts no shadow (left out of the possible occluders)
        for name in ["bunny", "contact", "fence", "edge", "triangle", "triangle-lawlor"] {
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
                Light::Triangle {
                    a: above - Vec3::X * 0.2 * size,
                    b: above + Vec3::X * 0.2 * size,
                    c: above + Vec3::Z * 0.2 * size,
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
                    skipped += usize::from(vis.nothing_between(x + n * vis.offset_at(x), Some(n), shaft(light)));
                }
            }
            // The edge scene's occluder hangs over every point the camera sees.
            assert!(skipped > 0 || name == "edge", "{name}: the skip test never fired");
        }
    }
}
