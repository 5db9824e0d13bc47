//! The scene against what f32 resolves: its extent against its smallest object, its
//! camera's depth range, and lights at a finite position far beyond it.

use super::Scene;
use crate::error::SceneError;
use crate::schema::{Camera, ShadowFit};
use crate::validate::{LIGHT_PRECISION_MARGIN, MAX_DEPTH_RATIO, PRECISION_RATIO};

use sshc_light::bounds_of;

impl Scene {
    /// Checks the scene's precision budget in f32 (called when the scene is built; call
    /// it again after changing `shadow_map` or `lights`):
    ///
    /// - **Extent against objects.** At the scene's largest coordinate magnitude `M`, f32
    ///   resolves `M * 2^-23` (one ulp); the ground truth moves ray origins by up to
    ///   2^-16 of a point's coordinates (`sshc_lab::visibility`) and the light views
    ///   quantise depth over the whole extent. An object smaller (bounds' diagonal) than
    ///   [`PRECISION_RATIO`] `* M` = 2^-16 `* M` (128 to 256 ulp at `M`) cannot be resolved
    ///   beside it: the scene is refused, naming the object that reaches `M` and the
    ///   smallest object.
    /// - **Local lights far beyond the scene.** A light at a finite position (point,
    ///   sphere, disk, rectangle, segment, triangle) at distance `d` from the centre of the
    ///   scene's bounds (radius `R`) sees the scene through a view whose coordinates are about `d`:
    ///   f32 resolves them to `d * 2^-23`, while one shadow-map texel covers about
    ///   `2 R / N` (`N` = `shadow_map`). Past [`LIGHT_PRECISION_MARGIN`] = 16 ulp per
    ///   texel, `d * 2^-23 * 16 > 2 R / N`, depth tests and light-space positions are
    ///   coarser than a texel, and every technique loses the shadows: the light is
    ///   refused, with its distant equivalent as the hint (`Directional`, or `DistantDisk`
    ///   with `angle_degrees = 2 atan(r / d)` for a light of radius `r`).
    pub fn check_precision(&self) -> Result<(), SceneError> {
        if self.triangles.is_empty() {
            return Ok(());
        }
        let (lo, hi) = self.bounds;
        let name = |i: usize| match &self.objects[i].name {
            Some(n) => format!("objects[{i}] (\"{n}\")"),
            None => format!("objects[{i}]"),
        };
        // Extent against the smallest object.
        let largest = lo.abs().max(hi.abs()).max_element();
        // Each object's size and reach (largest coordinate magnitude).
        let sized: Vec<(usize, f32, f32)> = (0..self.objects.len())
            .filter(|&i| !self.object_triangles[i].is_empty())
            .map(|i| {
                let (olo, ohi) = bounds_of(self.triangles[self.object_triangles[i].clone()].iter().flatten().copied());
                (i, (ohi - olo).length(), olo.abs().max(ohi.abs()).max_element())
            })
            .collect();
        // The object that reaches farthest, and the smallest of the others (itself when alone).
        let reaching = sized.iter().copied().max_by(|a, b| a.2.total_cmp(&b.2)).map(|(i, _, r)| (i, r));
        let smallest = sized
            .iter()
            .copied()
            .filter(|(i, ..)| sized.len() == 1 || Some(*i) != reaching.map(|r| r.0))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, s, _)| (i, s));
        if let (Some((small, size)), Some((far, _))) = (smallest, reaching)
            && size < PRECISION_RATIO * largest
        {
            return Err(SceneError::invalid(
                name(far),
                format!(
                    "the scene reaches {largest:e} here, where f32 resolves {:e} (the ground truth's ray offset is {:e}), but {} is only {size:e} across: the scene's extent leaves it unresolved (an object must be at least 2^-16 = 1.5e-5 of the largest coordinate)",
                    largest * f32::EPSILON,
                    PRECISION_RATIO * largest,
                    name(small),
                ),
                "move the far object nearer the others, or remove it; objects far apart belong in separate scenes",
            ));
        }
        self.check_camera_depth()?;
        // Local lights against the light view's resolution.
        let centre = (lo + hi) * 0.5;
        let radius = (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE);
        let texel = 2.0 * radius / self.shadow_map.max(1) as f32;
        for (i, light) in self.lights.iter().enumerate() {
            let Some(c) = light.center() else { continue };
            // In f64: the square of 1e30 overflows f32.
            let (c, centre) = (c.as_dvec3(), centre.as_dvec3());
            let d = c.distance(centre);
            // Under `shadow_fit: Casters` or `View` the map's texels are the fitted view's,
            // finer than the whole scene's when what it is fitted to is small: the smaller one decides (a
            // non-finite fitted size, from a view no map resolves, leaves the scene's).
            let texel = match self.shadow_fit {
                ShadowFit::Scene => texel,
                ShadowFit::Casters | ShadowFit::View => {
                    let v = self.light_view(light);
                    let per_unit = 2.0 / (v.proj.y_axis.y * self.shadow_map.max(1) as f32);
                    let fitted = if v.orthographic { per_unit } else { per_unit * d as f32 };
                    texel.min(fitted)
                }
            };
            let (eps, texel) = (f64::from(f32::EPSILON), f64::from(texel));
            let margin = f64::from(LIGHT_PRECISION_MARGIN);
            if d * eps * margin <= texel {
                continue;
            }
            let field = light.placing_field();
            let dir = (c - centre) / d;
            let dir = format!("({}, {}, {})", dir.x, dir.y, dir.z);
            let r = light.bounding_radius();
            let hint = if r > 0.0 {
                let angle = 2.0 * f64::from(r).atan2(d).to_degrees();
                format!(
                    "a light this far acts as a distant one: write `DistantDisk(direction: {dir}, angle_degrees: {:e})` (2 atan(r / d) for its radius {r:e}), or `Directional(direction: {dir})`",
                    angle as f32
                )
            } else {
                format!("a light this far acts as a distant one: write `Directional(direction: {dir})`")
            };
            return Err(SceneError::invalid(
                format!("lights[{i}] ({}).{field}", light.kind_name()),
                format!(
                    "the light is {:e} from the centre of the scene (radius {radius:e}): its view resolves positions to {:e}, coarser than 1/{LIGHT_PRECISION_MARGIN} of a shadow-map texel ({:e} at {} texels), so no shadow map can resolve the scene (the limit is {:e})",
                    d as f32,
                    (d * eps) as f32,
                    texel as f32,
                    self.shadow_map,
                    (texel / (eps * margin)) as f32
                ),
                hint,
            ));
        }
        Ok(())
    }

    /// The camera against what f32 resolves (issue 48, item 12): a perspective camera's
    /// far / near at most [`MAX_DEPTH_RATIO`], and an orthographic camera's pixel wider than
    /// f32's step at the camera's coordinates.
    fn check_camera_depth(&self) -> Result<(), SceneError> {
        let (near, far) = self.camera_near_far();
        let kind = match &self.camera {
            Camera::Perspective { .. } => "Perspective",
            Camera::Orthographic { .. } => "Orthographic",
        };
        if let Camera::Perspective { .. } = &self.camera
            && far / near > MAX_DEPTH_RATIO
        {
            return Err(SceneError::invalid(
                format!("camera ({kind}).near"),
                format!(
                    "far / near is {:e} ({far:e} / {near:e}), above the limit of {MAX_DEPTH_RATIO:e}: the f32 depth test orders surfaces at the far plane only {:.0} % of their distance apart at the limit, and not at all beyond it",
                    far / near,
                    100.0 * MAX_DEPTH_RATIO * 2f32.powi(-24)
                ),
                "write a larger near, or leave near and far out to fit the scene",
            ));
        }
        if let Camera::Orthographic {
            half_height,
            position,
            target,
            height,
            ..
        } = &self.camera
        {
            let reach = position.abs().max(target.abs()).max_element().max(1.0);
            let pixel = 2.0 * half_height / (*height).max(1) as f32;
            if pixel < 4.0 * f32::EPSILON * reach {
                return Err(SceneError::invalid(
                    format!("camera ({kind}).half_height"),
                    format!(
                        "a pixel is {pixel:e} wide, where f32 resolves {:e} at the camera's coordinates ({reach:e}): the view cannot place its pixels",
                        f32::EPSILON * reach
                    ),
                    "write a larger half height",
                ));
            }
        }
        Ok(())
    }
}
