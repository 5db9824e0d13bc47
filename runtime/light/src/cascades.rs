//! Cascaded shadow maps for a light at infinity: the camera's view depth split into `n`
//! slices, each with its own orthographic light view fitted to its slice of the view
//! frustum.
//!
//! - **Splits** ([`practical_splits`]): the practical scheme of Zhang, Sun, Xu and Lun,
//!   "Parallel-split shadow maps for large-scale virtual environments" (VRCIA 2006),
//!   equation 6: `C_i = lambda C_log + (1 - lambda) C_uni`, with
//!   `C_log = near (far / near)^(i / n)` and `C_uni = near + (far - near) i / n`.
//!   `lambda = 0` is uniform, `1` logarithmic.
//! - **Fit** ([`cascade_views`]): each slice's eight corners, bounded by their sphere
//!   (centre at the corners' mean, radius the farthest corner), so that the cascade's
//!   extent does not change when the camera turns; the light view looks along the light's
//!   direction at the sphere's centre with a fixed up vector ([`any_perpendicular_up`]),
//!   padded by the casters' penumbra reach; depth covers every object along the light's
//!   direction, so that casters outside the slice still cast into it.
//! - **Snapping**: the sphere's centre is moved, in the light view's plane, to a whole
//!   number of texels (Valient, "Stable rendering of cascaded shadow maps", ShaderX6,
//!   2008): a camera that moves shifts each cascade's texel grid by whole texels, so a
//!   shadow edge's texels do not swim (shimmer) from frame to frame. For the grid to hold,
//!   the texel's size must hold too: the extent is rounded up to a power of `2^(1/16)`, and
//!   the depth range is the scene's, the same for every camera.

use glam::{Mat4, Vec2, Vec3};

use crate::{LightView, any_perpendicular_up, look_at, ortho_light_view};

/// `x > 0` rounded up to the next power of `2^(1/16)`.
fn quantised(x: f32) -> f32 {
    2f32.powf((16.0 * x.log2()).ceil() / 16.0)
}

/// Most cascades a light may have.
pub const MAX_CASCADES: u32 = 4;

/// The `n + 1` view distances that bound `n` cascades between `near` and `far` (the first
/// `near`, the last `far`, increasing), by the practical split scheme with weight
/// `lambda` in [0, 1] (Zhang et al. 2006, eq. 6). `None` for `n = 0`, a range that is not
/// `0 < near < far` (finite), or a `lambda` outside [0, 1].
pub fn practical_splits(near: f32, far: f32, n: u32, lambda: f32) -> Option<Vec<f32>> {
    if n == 0 || !(near.is_finite() && far.is_finite() && 0.0 < near && near < far) || !(0.0..=1.0).contains(&lambda) {
        return None;
    }
    let (near64, far64, lambda64) = (f64::from(near), f64::from(far), f64::from(lambda));
    let mut out: Vec<f32> = (0..=n)
        .map(|i| {
            let t = f64::from(i) / f64::from(n);
            let log = near64 * (far64 / near64).powf(t);
            let uni = near64 + (far64 - near64) * t;
            (lambda64 * log + (1.0 - lambda64) * uni) as f32
        })
        .collect();
    // exact ends (the powers round)
    out[0] = near;
    out[n as usize] = far;
    Some(out)
}

/// What a cascade fit needs of the camera: its position and axes, and the half-extents of
/// its view at unit distance (a perspective camera: `tan` of the half angles) or at any
/// distance (an orthographic one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrustum {
    pub eye: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit right and up axes of the image.
    pub right: Vec3,
    pub up: Vec3,
    /// Half width and height of the view: at unit distance for a perspective camera
    /// (`tan(fov_x / 2)`, `tan(fov_y / 2)`), in world units for an orthographic one.
    pub half: Vec2,
    pub orthographic: bool,
}

impl CameraFrustum {
    /// From a camera's world-to-view matrix (right-handed, looking down -Z) and its
    /// projection (glam's right-handed perspective or orthographic, WebGPU's depth).
    /// `None` when the view is not invertible or the projection not one of those.
    pub fn from_matrices(view: Mat4, proj: Mat4) -> Option<CameraFrustum> {
        let inv = view.inverse();
        if !inv.is_finite() {
            return None;
        }
        let orthographic = proj.w_axis.w == 1.0 && proj.z_axis.w == 0.0;
        let (sx, sy) = (proj.x_axis.x, proj.y_axis.y);
        if !(sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0) {
            return None;
        }
        Some(CameraFrustum {
            eye: inv.transform_point3(Vec3::ZERO),
            forward: inv.transform_vector3(Vec3::NEG_Z).normalize_or_zero(),
            right: inv.transform_vector3(Vec3::X).normalize_or_zero(),
            up: inv.transform_vector3(Vec3::Y).normalize_or_zero(),
            half: Vec2::new(1.0 / sx, 1.0 / sy),
            orthographic,
        })
    }

    /// The four corners of the view's cross-section at view distance `d`.
    pub fn section(&self, d: f32) -> [Vec3; 4] {
        let h = if self.orthographic { self.half } else { self.half * d };
        let c = self.eye + self.forward * d;
        [
            c - self.right * h.x - self.up * h.y,
            c + self.right * h.x - self.up * h.y,
            c + self.right * h.x + self.up * h.y,
            c - self.right * h.x + self.up * h.y,
        ]
    }
}

/// One cascade: the slice of view distances it covers and its light view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cascade {
    /// View distances (along the camera's forward axis) of the slice: `[near, far]`.
    pub split: (f32, f32),
    pub view: LightView,
    /// World units per texel of its map.
    pub texel: f32,
}

/// The light views of the cascades of a light at infinity shining from `direction`
/// (towards the light) over `camera`'s slices bounded by `splits` (as
/// [`practical_splits`] gives them), for square maps of `size` texels: each fitted to its
/// slice's bounding sphere padded by `reach` (the casters' penumbra reach, world units),
/// its depth covering `bounds` (every object) along the light's direction, and, with
/// `snap`, its centre on a whole texel. `None` for a zero direction, fewer than two splits
/// or a zero size.
pub fn cascade_views(
    direction: Vec3,
    camera: &CameraFrustum,
    splits: &[f32],
    size: u32,
    reach: f32,
    bounds: (Vec3, Vec3),
    snap: bool,
) -> Option<Vec<Cascade>> {
    let dir = direction.normalize_or_zero();
    if dir == Vec3::ZERO || splits.len() < 2 || size == 0 {
        return None;
    }
    let up = any_perpendicular_up(dir);
    // a rotation only, fixed for the light: the cascades' grids differ by translation
    let basis = look_at(Vec3::ZERO, -dir, up);
    // depth: every object, measured along the light's direction from a plane beyond them
    // all; the same for every cascade and every camera, so that a stored depth does not
    // change as the camera moves
    let (mut zmin, mut zmax) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in crate::corners(bounds) {
        let z = basis.transform_point3(p).z;
        (zmin, zmax) = (zmin.min(z), zmax.max(z));
    }
    let margin = 1e-3 * (zmax - zmin).max(1e-6);
    let eye_z = zmax + margin;
    let (near, far) = (0.5 * margin, zmax - zmin + 2.0 * margin);
    let mut out = Vec::with_capacity(splits.len() - 1);
    for w in splits.windows(2) {
        let corners: Vec<Vec3> = camera.section(w[0]).into_iter().chain(camera.section(w[1])).collect();
        let centre = corners.iter().copied().sum::<Vec3>() / corners.len() as f32;
        let radius = corners.iter().map(|c| c.distance(centre)).fold(0.0f32, f32::max);
        // the extent rounded up to a step of 2^(1/16) (4.4 %): the slice's sphere changes
        // as its splits follow the view, and a texel whose size changed every frame would
        // move every shadow edge
        let half = quantised((radius + reach.max(0.0)).max(1e-6));
        let texel = 2.0 * half / size as f32;
        // the centre in the light's rotated frame, moved to a whole texel
        let c = basis.transform_point3(centre);
        let (mut cx, mut cy) = (c.x, c.y);
        if snap {
            cx = (cx / texel).round() * texel;
            cy = (cy / texel).round() * texel;
        }
        let view = Mat4::from_translation(-Vec3::new(cx, cy, eye_z)) * basis;
        out.push(Cascade {
            split: (w[0], w[1]),
            view: ortho_light_view(view, dir, half, near, far),
            texel,
        });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(eye: Vec3, target: Vec3) -> CameraFrustum {
        let view = look_at(eye, target, Vec3::Y);
        let proj = crate::perspective(50f32.to_radians(), 1.5, 0.1, 100.0);
        CameraFrustum::from_matrices(view, proj).unwrap_or_else(|| panic!("camera"))
    }

    /// Zhang et al. 2006, eq. 6 at its two ends: lambda 0 spaces the splits evenly, lambda 1
    /// by a constant ratio; between, each split lies between the two.
    #[test]
    fn practical_splits_run_from_uniform_to_logarithmic() {
        let uni = practical_splits(1.0, 81.0, 4, 0.0).unwrap_or_default();
        assert_eq!(uni, [1.0, 21.0, 41.0, 61.0, 81.0]);
        let log = practical_splits(1.0, 81.0, 4, 1.0).unwrap_or_default();
        for (got, want) in log.iter().zip([1.0, 3.0, 9.0, 27.0, 81.0]) {
            assert!((got - want).abs() <= 4.0 * f32::EPSILON * want, "{log:?}");
        }
        let mid = practical_splits(1.0, 81.0, 4, 0.5).unwrap_or_default();
        for i in 0..5 {
            assert!(log[i] <= mid[i] && mid[i] <= uni[i], "{mid:?}");
        }
        assert!(mid.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(practical_splits(1.0, 81.0, 1, 0.7).unwrap_or_default(), [1.0, 81.0]);
        for bad in [
            (0.0, 1.0, 2, 0.5),
            (2.0, 1.0, 2, 0.5),
            (1.0, 2.0, 0, 0.5),
            (1.0, 2.0, 2, 1.5),
            (1.0, f32::NAN, 2, 0.5),
        ] {
            assert!(practical_splits(bad.0, bad.1, bad.2, bad.3).is_none(), "{bad:?}");
        }
    }

    /// Every corner of a cascade's slice lies inside its light view (clip x, y in [-1, 1]),
    /// and every point of the scene in depth (in [0, 1]).
    #[test]
    fn each_cascade_holds_its_slice_and_the_scene_in_depth() {
        let cam = camera(Vec3::new(-3.0, 4.0, 12.0), Vec3::new(1.0, 0.0, 0.0));
        let splits = practical_splits(0.5, 40.0, 4, 0.75).unwrap_or_default();
        let bounds = (Vec3::new(-20.0, 0.0, -20.0), Vec3::new(20.0, 6.0, 20.0));
        let dir = Vec3::new(0.77, 0.342, 0.54);
        let cascades = cascade_views(dir, &cam, &splits, 1024, 0.2, bounds, true).unwrap_or_default();
        assert_eq!(cascades.len(), 4);
        for c in &cascades {
            let corners = cam.section(c.split.0).into_iter().chain(cam.section(c.split.1));
            for p in corners {
                let q = c.view.view_proj.project_point3(p);
                assert!(q.x.abs() <= 1.0 && q.y.abs() <= 1.0, "{q} for {p}");
                // depth covers the scene: the slice's part inside it
                let inside = p.clamp(bounds.0, bounds.1);
                let z = c.view.view_proj.project_point3(inside).z;
                assert!((0.0..=1.0).contains(&z), "{z} for {inside}");
            }
            for p in crate::corners(bounds) {
                let z = c.view.view_proj.project_point3(p).z;
                assert!((0.0..=1.0).contains(&z), "scene corner {p} at depth {z}");
            }
        }
        // nearer cascades are finer
        assert!(
            cascades.windows(2).all(|w| w[0].texel < w[1].texel),
            "{:?}",
            cascades.iter().map(|c| c.texel).collect::<Vec<_>>()
        );
    }

    /// Snapped, a camera that moves shifts every cascade's texel grid by whole texels: a
    /// fixed world point keeps its position within its texel. Unsnapped, it does not.
    #[test]
    fn snapped_cascades_move_by_whole_texels() {
        let splits = practical_splits(0.5, 30.0, 3, 0.5).unwrap_or_default();
        let bounds = (Vec3::splat(-30.0), Vec3::splat(30.0));
        let dir = Vec3::new(0.3, 1.0, 0.2);
        let size = 512;
        let point = Vec3::new(0.37, 0.0, -1.91);
        // the fraction of a texel at which `point` falls, per cascade
        let phase = |eye: Vec3, snap: bool| -> Vec<Vec2> {
            let cam = camera(eye, eye + Vec3::new(0.0, -0.5, -1.0));
            cascade_views(dir, &cam, &splits, size, 0.0, bounds, snap)
                .unwrap_or_default()
                .iter()
                .map(|c| {
                    let q = c.view.view_proj.project_point3(point);
                    let t = (q.truncate() * 0.5 + 0.5) * size as f32;
                    t - t.floor()
                })
                .collect()
        };
        let start = Vec3::new(0.0, 3.0, 4.0);
        let (a, b) = (phase(start, true), phase(start + Vec3::new(0.123, 0.0457, -0.0711), true));
        for (p, q) in a.iter().zip(&b) {
            // a few f32 roundings of coordinates near 30 world units, in texels of at most
            // 2 * 30 / 512: well below a hundredth of a texel
            assert!((*p - *q).abs().max_element() < 1e-2, "snapped: {p} then {q}");
        }
        let (a, b) = (phase(start, false), phase(start + Vec3::new(0.123, 0.0457, -0.0711), false));
        assert!(
            a.iter().zip(&b).any(|(p, q)| (*p - *q).abs().max_element() > 0.05),
            "unsnapped: {a:?} then {b:?}"
        );
    }

    /// The cascade's extent is its slice's bounding sphere: it does not change when the
    /// camera turns in place.
    #[test]
    fn a_turning_camera_keeps_each_cascade_the_same_size() {
        let splits = practical_splits(0.5, 30.0, 3, 0.5).unwrap_or_default();
        let bounds = (Vec3::splat(-30.0), Vec3::splat(30.0));
        let eye = Vec3::new(0.0, 3.0, 4.0);
        let texels = |target: Vec3| -> Vec<f32> {
            cascade_views(Vec3::Y, &camera(eye, target), &splits, 512, 0.0, bounds, true)
                .unwrap_or_default()
                .iter()
                .map(|c| c.texel)
                .collect()
        };
        let (a, b) = (texels(Vec3::ZERO), texels(Vec3::new(5.0, 1.0, 2.0)));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-5 * x, "{a:?} then {b:?}");
        }
    }
}
