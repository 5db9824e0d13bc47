//! The light views fitted to the scene (`shadow_fit`: the whole scene, the casters, or
//! what the camera sees), the report of a fit, and the scene as the `Occluders` the light
//! crate fits its views to.

use super::Scene;
use crate::error::SceneError;
use crate::schema::ShadowFit;
use std::fmt;

use glam::{Mat4, Vec3, Vec4};
use sshc_light::{
    Light, LightView, any_perpendicular_up, bounds_of, enclosing_axis, fit_guard, look_at, ortho_light_view, padded, perspective,
    perspective_light_view,
};

impl Scene {
    /// Refuses `Casters` when no object casts a triangle.
    pub(super) fn check_fit(&self, fit: ShadowFit) -> Result<(), SceneError> {
        if fit == ShadowFit::Casters && self.caster_triangles() == 0 {
            let why = if self.objects.iter().any(|o| o.casts) {
                "every object with `casts: true` has no triangle (all were degenerate)"
            } else {
                "every object has `casts: false`"
            };
            return Err(SceneError::invalid(
                "shadow_fit",
                format!("`shadow_fit: Casters` fits the shadow map to the casting objects, but {why}"),
                "mark at least one object `casts: true` (the default), or write `shadow_fit: Scene`",
            ));
        }
        Ok(())
    }

    /// The scene file's cascades ([`crate::schema::SceneDesc::cascades`]), checked.
    pub fn cascades(&self) -> Option<crate::schema::Cascades> {
        self.cascades
    }

    /// What the light's view is fitted to (see [`ShadowFit`]).
    pub fn shadow_fit(&self) -> ShadowFit {
        self.shadow_fit
    }

    /// Changes what the light's view is fitted to; `Casters` is refused when no object
    /// casts a triangle.
    pub fn set_shadow_fit(&mut self, fit: ShadowFit) -> Result<(), SceneError> {
        self.check_fit(fit)?;
        self.shadow_fit = fit;
        Ok(())
    }

    /// The corners of the casting objects' triangles.
    fn caster_points(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.objects.len())
            .filter(|&i| self.objects[i].casts)
            .flat_map(|i| self.triangles[self.object_triangles[i].clone()].iter().flatten().copied())
    }

    /// The farthest reach of the casters' penumbra under `light`, in world units
    /// ([`sshc_light::penumbra_reach`] over the scene's vertices).
    pub fn penumbra_reach(&self, light: &Light) -> f32 {
        sshc_light::penumbra_reach(light, self)
    }

    /// The view of `light` for rasterising the shadow map, fitted as [`Scene::shadow_fit`]
    /// says: [`Light::view`] of the whole scene's bounds for `Scene`; for `Casters`, see
    /// [`ShadowFit`] (an orthographic view centred on the casters for a light at infinity;
    /// a perspective view along the axis of the narrowest cone holding the casters for a
    /// light at a finite position, its half-angle tangent that of the casters plus the
    /// penumbra's reach in tangent units).
    pub fn light_view(&self, light: &Light) -> LightView {
        if self.shadow_fit == ShadowFit::View {
            return match self.view_fit(light) {
                Some(v) => light.with_extent(v),
                None => light.view(self.bounds),
            };
        }
        if self.shadow_fit == ShadowFit::Scene || self.caster_triangles() == 0 {
            return light.view(self.bounds);
        }
        sshc_light::casters_view(light, self, self.shadow_map)
    }

    /// The points of the scene the camera sees: every triangle clipped to the camera's
    /// frustum (Sutherland-Hodgman in clip space, where world positions interpolate
    /// linearly), its clipped polygon's corners in world space.
    pub fn visible_points(&self) -> Vec<Vec3> {
        let mut out = Vec::new();
        self.for_each_visible_point(|p| out.push(p));
        out
    }

    /// [`Scene::visible_points`] one by one, collecting nothing (what a refit every frame
    /// reads: the cascades' depth range).
    pub fn for_each_visible_point(&self, mut f: impl FnMut(Vec3)) {
        let vp = self.camera_view_proj();
        // the six planes of WebGPU's clip volume: -w <= x, y <= w, 0 <= z <= w
        let planes: [fn(Vec4) -> f32; 6] = [|c| c.w + c.x, |c| c.w - c.x, |c| c.w + c.y, |c| c.w - c.y, |c| c.z, |c| c.w - c.z];
        let mut poly: Vec<(Vec4, Vec3)> = Vec::with_capacity(9);
        let mut next: Vec<(Vec4, Vec3)> = Vec::with_capacity(9);
        for tri in &self.triangles {
            poly.clear();
            poly.extend(tri.iter().map(|p| (vp * p.extend(1.0), *p)));
            for plane in planes {
                next.clear();
                for i in 0..poly.len() {
                    let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                    let (da, db) = (plane(a.0), plane(b.0));
                    if da >= 0.0 {
                        next.push(a);
                    }
                    if (da >= 0.0) != (db >= 0.0) {
                        let t = da / (da - db);
                        next.push((a.0.lerp(b.0, t), a.1.lerp(b.1, t)));
                    }
                }
                std::mem::swap(&mut poly, &mut next);
                if poly.is_empty() {
                    break;
                }
            }
            for p in &poly {
                f(p.1);
            }
        }
    }

    /// The corners, in `view`'s space, of every caster triangle clipped to the region where
    /// each of `planes` (given `k`) is >= 0.
    fn caster_points_clipped(&self, view: &Mat4, planes: &[fn(Vec3, f32) -> f32], k: f32) -> Vec<Vec3> {
        let mut out = Vec::new();
        let (mut poly, mut next): (Vec<Vec3>, Vec<Vec3>) = (Vec::with_capacity(9), Vec::with_capacity(9));
        for i in (0..self.objects.len()).filter(|&i| self.objects[i].casts) {
            for tri in &self.triangles[self.object_triangles[i].clone()] {
                poly.clear();
                poly.extend(tri.iter().map(|p| view.transform_point3(*p)));
                for plane in planes {
                    next.clear();
                    for j in 0..poly.len() {
                        let (a, b) = (poly[j], poly[(j + 1) % poly.len()]);
                        let (da, db) = (plane(a, k), plane(b, k));
                        if da >= 0.0 {
                            next.push(a);
                        }
                        if (da >= 0.0) != (db >= 0.0) {
                            next.push(a.lerp(b, da / (da - db)));
                        }
                    }
                    std::mem::swap(&mut poly, &mut next);
                    if poly.is_empty() {
                        break;
                    }
                }
                out.extend_from_slice(&poly);
            }
        }
        out
    }

    /// The `View` fit ([`ShadowFit::View`]); None when the camera sees nothing.
    fn view_fit(&self, light: &Light) -> Option<LightView> {
        let seen = self.visible_points();
        if seen.is_empty() {
            return None;
        }
        let guard = fit_guard(self.shadow_map.max(1));
        let scene = padded(self.bounds);
        let radius = 0.5 * (scene.1 - scene.0).length();
        let margin = radius * 1e-3;
        let v = match light.center() {
            None => {
                let dir = light.direction().unwrap_or(Vec3::Y);
                let up = any_perpendicular_up(dir);
                let sb = bounds_of(seen.iter().copied());
                let sc = (sb.0 + sb.1) * 0.5;
                let v0 = look_at(sc + dir, sc, up);
                let (mut x0, mut x1, mut y0, mut y1) = (f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY);
                for p in &seen {
                    let q = v0.transform_point3(*p);
                    (x0, x1, y0, y1) = (x0.min(q.x), x1.max(q.x), y0.min(q.y), y1.max(q.y));
                }
                let reach = self.penumbra_reach(light);
                let (right, upv) = (v0.row(0).truncate(), v0.row(1).truncate());
                let centre = sc + right * (0.5 * (x0 + x1)) + upv * (0.5 * (y0 + y1));
                let half = ((0.5 * (x1 - x0)).max(0.5 * (y1 - y0)) + reach) * guard;
                let half = half.max(radius * 1e-4);
                let eye = centre + dir * (2.0 * radius + centre.distance((scene.0 + scene.1) * 0.5));
                let view = look_at(eye, centre, up);
                // depth: the visible receivers and the casters over the footprint (caster
                // triangles clipped to it: a large one's corners may all lie outside)
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for p in &seen {
                    let d = -view.transform_point3(*p).z;
                    (lo, hi) = (lo.min(d), hi.max(d));
                }
                let box_planes = [
                    |q: Vec3, h: f32| h + q.x,
                    |q: Vec3, h: f32| h - q.x,
                    |q: Vec3, h: f32| h + q.y,
                    |q: Vec3, h: f32| h - q.y,
                ];
                for q in self.caster_points_clipped(&view, &box_planes, half) {
                    lo = lo.min(-q.z);
                }
                let far = hi + margin;
                let near = (lo - margin).max(far * 1e-4);
                ortho_light_view(view, dir, half, near, far)
            }
            Some(eye) => {
                let forward = enclosing_axis(eye, padded(bounds_of(seen.iter().copied())));
                let view = look_at(eye, eye + forward, any_perpendicular_up(forward));
                // the receivers' cone, its depth range, then the casters' reach into it
                let (mut tan, mut dr, mut dmin) = (0.0f32, 0.0f32, f32::INFINITY);
                for p in &seen {
                    let q = view.transform_point3(*p);
                    let depth = (-q.z).max(radius * 1e-6);
                    tan = tan.max(q.x.abs() / depth).max(q.y.abs() / depth);
                    dr = dr.max(depth);
                    dmin = dmin.min(depth);
                }
                let s = light.bounding_radius();
                // casters in the cone padded by the light's size at their depth (caster
                // triangles clipped to it), in front of the light
                let cone_planes = [
                    |q: Vec3, t: f32| t * -q.z + q.x,
                    |q: Vec3, t: f32| t * -q.z - q.x,
                    |q: Vec3, t: f32| t * -q.z + q.y,
                    |q: Vec3, t: f32| t * -q.z - q.y,
                    |q: Vec3, _: f32| -q.z,
                ];
                let mut dc = dmin;
                // the cone through the light's rim: tan at the receivers' depth plus the
                // light's size over the nearest visible depth
                let wide = tan + s / dmin.max(radius * 1e-6);
                for q in self.caster_points_clipped(&view, &cone_planes, wide) {
                    dc = dc.min((-q.z).max(0.0));
                }
                let far = (dr * 1.001).max(1e-6);
                let near = (dc * 0.999).max(far * 1e-4);
                let reach = s * (1.0 / near.max(far * 1e-4) - 1.0 / dr);
                let tan = ((tan + reach) * guard).clamp(1e-6, 80f32.to_radians().tan());
                perspective_light_view(view, perspective(2.0 * tan.atan(), 1.0, near, far), eye, near, far)
            }
        };
        Some(v)
    }

    /// How the shadow map of `light` is fitted, for reports: the fit, the penumbra's reach
    /// it was padded by (0 for `Scene`), and the world size of one texel (for a
    /// perspective view, at the distance of the fitted bounds' centre along its axis).
    pub fn fit_report(&self, light: &Light) -> FitReport {
        let v = self.light_view(light);
        let n = self.shadow_map.max(1);
        let casters = self.shadow_fit == ShadowFit::Casters && self.caster_triangles() > 0;
        let seen = self.visible_points();
        let view = self.shadow_fit == ShadowFit::View && !seen.is_empty();
        let span = 2.0 / (v.proj.y_axis.y * n as f32);
        let texel = if v.orthographic {
            span
        } else {
            let b = if casters { bounds_of(self.caster_points()) } else { self.bounds };
            span * (-v.view.transform_point3((b.0 + b.1) * 0.5).z).max(v.near)
        };
        // at the receivers the camera sees (their mean depth in the light's view)
        let at_receivers = if v.orthographic || seen.is_empty() {
            texel
        } else {
            let mean = seen.iter().map(|p| -v.view.transform_point3(*p).z).sum::<f32>() / seen.len() as f32;
            span * mean.max(v.near)
        };
        FitReport {
            fit: if casters {
                ShadowFit::Casters
            } else if view {
                ShadowFit::View
            } else {
                ShadowFit::Scene
            },
            at_receivers,
            reach: if casters || view { self.penumbra_reach(light) } else { 0.0 },
            texel,
            texels: n,
            width: texel * n as f32,
            near: v.near,
            far: v.far,
            casters: (0..self.objects.len()).filter(|&i| self.objects[i].casts).count(),
            objects: self.objects.len(),
        }
    }
}

/// How a light's shadow map is fitted ([`Scene::fit_report`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitReport {
    /// What the view was fitted to (`Scene` when `Casters` was asked but nothing casts).
    pub fit: ShadowFit,
    /// The penumbra's reach the `Casters` fit padded by, world units; 0 for `Scene`.
    pub reach: f32,
    /// World size of one texel (for a perspective view, at the fitted bounds' centre).
    pub texel: f32,
    /// World size of one texel at the receivers the camera sees (for a perspective view,
    /// at their mean depth; `texel` when the camera sees nothing).
    pub at_receivers: f32,
    /// Texels per side.
    pub texels: u32,
    /// World width of the map (`texel * texels`).
    pub width: f32,
    /// Near and far distances of the view (depth is normalised between them).
    pub near: f32,
    pub far: f32,
    /// Objects that cast, of all objects.
    pub casters: usize,
    pub objects: usize,
}

impl fmt::Display for FitReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.fit {
            ShadowFit::Scene => write!(f, "shadow map fitted to the whole scene ({} objects)", self.objects)?,
            ShadowFit::Casters => write!(
                f,
                "shadow map fitted to the casters ({} of {} objects), padded by the penumbra's reach {:.4} and one guard texel",
                self.casters, self.objects, self.reach
            )?,
            ShadowFit::View => write!(
                f,
                "shadow map fitted to what the camera sees, padded by the penumbra's reach {:.4} and one guard texel",
                self.reach
            )?,
        }
        write!(
            f,
            ": {} x {} texels over {:.4} world units, one texel = {:.4} world units ({:.4} at the receivers the camera sees); depth from {:.4} to {:.4}",
            self.texels, self.texels, self.width, self.texel, self.at_receivers, self.near, self.far
        )
    }
}

/// The `Casters` fit over the scene's vertices: the tightest fit the points allow.
impl sshc_light::Occluders for Scene {
    fn casters(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.caster_points()
    }
    fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.triangles.iter().flatten().copied()
    }
    fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
    fn has_casters(&self) -> bool {
        self.caster_triangles() > 0
    }
}
