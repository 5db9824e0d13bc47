//! The loaded scene: its description, the world-space triangles built from it, the camera
//! and the light views fitted to it.

use crate::error::{SceneError, SceneErrorKind, syntax_error};
use crate::mesh::{Reads, analytic_triangles, build_mesh, place};
use crate::schema::{Camera, Object, SceneDesc, ShadowFit};
use crate::source::MeshData;
use crate::validate::{
    LIGHT_PRECISION_MARGIN, MAX_DEPTH_RATIO, MAX_SCENE_TRIANGLES, PRECISION_RATIO, validate, validate_camera, validate_light,
};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3, Vec4};
use sshc_light::{
    Light, LightView, any_perpendicular_up, bounds_of, depth_range, enclosing_axis, fit_guard, look_at, ortho_light_view, orthographic,
    padded, perspective, perspective_light_view,
};

/// A loaded scene: its description plus the world-space triangles built from it.
///
/// `camera`, `shadow_map` and `lights` may be changed after loading (a test can shrink
/// the image); the geometry is fixed once loaded.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera (may be changed, e.g. by [`Scene::set_camera_size`]).
    pub camera: Camera,
    /// Side of the square shadow map in texels.
    pub shadow_map: u32,
    /// The lights.
    pub lights: Vec<Light>,
    shadow_fit: ShadowFit,
    cascades: Option<crate::schema::Cascades>,
    objects: Vec<Object>,
    source: Option<PathBuf>,
    notes: Vec<String>,
    files: Vec<PathBuf>,
    placements: (usize, usize),
    triangles: Vec<[Vec3; 3]>,
    normals: Vec<[Vec3; 3]>,
    object_triangles: Vec<Range<usize>>,
    /// Per object: the glTF instancing its triangles were placed from, where kept.
    instancing: Vec<Option<crate::source::Instancing>>,
    bounds: (Vec3, Vec3),
}

/// Side of the shadow map of a scene read from a glTF file.
pub const GLTF_SHADOW_MAP: u32 = 2048;

/// Whether `path` names a glTF file (`.gltf` or `.glb`, any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// `light` checked and its directions normalised as a scene file's light `i` is (checking
/// a checked light changes nothing).
pub fn checked_light(i: usize, mut light: Light) -> Result<Light, SceneError> {
    let name = light.kind_name();
    validate_light(&mut light, &|field: &str| format!("lights[{i}] ({name}).{field}"))?;
    Ok(light)
}

impl Scene {
    /// Reads a scene file. OBJ paths resolve against the file's folder. A `.gltf` or `.glb`
    /// file is read as a scene of its own ([`Scene::load_gltf`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        if is_gltf(path) {
            return Scene::load_gltf(path);
        }
        let text = crate::source::read_text(path, crate::source::MAX_TEXT_BYTES).map_err(|e| {
            SceneError::new(SceneErrorKind::Io, format!("cannot read the scene: {e}"))
                .with_file(Some(path))
                .with_hint("check the path of the scene file")
        })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let base = if base.as_os_str().is_empty() { PathBuf::from(".") } else { base };
        let mut scene = Scene::parse(&text, &base, Some(path))?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Reads a glTF 2.0 file as a scene: its triangles as one object that casts and
    /// receives, its first camera (else one framing the scene, 512 x 512), its
    /// `KHR_lights_punctual` lights (else a sun from above, with a note), a
    /// [`GLTF_SHADOW_MAP`]-texel shadow map fitted to the scene. What was ignored is in
    /// [`Scene::notes`].
    pub fn load_gltf(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let folder = if folder.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            folder
        };
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let imported = crate::gltf::load(&name, &folder).map_err(|e| e.with_file(Some(path)))?;
        let mut scene = Scene::from_imported(imported, &name, &folder).map_err(|e| e.with_file(Some(path)))?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// [`Scene::load_gltf`] of glTF bytes (JSON or GLB) held in memory: only the GLB chunk
    /// and data URIs can hold its buffers.
    pub fn from_gltf_slice(bytes: &[u8]) -> Result<Scene, SceneError> {
        let imported = crate::gltf::import(bytes, "<memory>", None)?;
        Scene::from_imported(imported, "<memory>", Path::new("."))
    }

    fn from_imported(imported: crate::gltf::Imported, name: &str, folder: &Path) -> Result<Scene, SceneError> {
        let crate::gltf::Imported {
            mesh,
            camera,
            lights,
            mut notes,
            files,
            placements,
        } = imported;
        let bounds = bounds_of(mesh.triangles.iter().flatten().copied());
        let camera = camera.unwrap_or_else(|| {
            notes.push("it has no camera: a camera framing the scene is used".into());
            crate::gltf::framing_camera(bounds)
        });
        let lights = if lights.is_empty() {
            notes.push(format!(
                "it has no light (KHR_lights_punctual): a sun from above, {} degrees wide, is used",
                crate::gltf::DEFAULT_SUN_DEGREES
            ));
            vec![crate::gltf::default_sun()]
        } else {
            lights
        };
        let desc = SceneDesc {
            camera,
            shadow_map: GLTF_SHADOW_MAP,
            lights,
            objects: vec![Object {
                name: Some(name.to_string()),
                mesh: crate::schema::Mesh::Gltf { path: name.to_string() },
                transform: Default::default(),
                flat_normals: false,
                casts: true,
                receives: true,
            }],
            shadow_fit: ShadowFit::Scene,
            cascades: None,
        };
        let mut scene = Scene::build_with(desc, folder, vec![Some(mesh)])?;
        scene.notes = notes.into_iter().map(|n| format!("{name}: {n}")).collect();
        scene.files = files;
        scene.placements = placements;
        Ok(scene)
    }

    /// Reads a scene from RON text; OBJ paths resolve against `base_dir`.
    pub fn from_str(text: &str, base_dir: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::parse(text, base_dir.as_ref(), None)
    }

    /// Builds a scene from a description (OBJ paths resolve against `base_dir`).
    pub fn from_desc(desc: SceneDesc, base_dir: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::build(desc, base_dir.as_ref()).map_err(|e| e.with_file(None))
    }

    fn parse(text: &str, base: &Path, file: Option<&Path>) -> Result<Scene, SceneError> {
        let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let desc: SceneDesc = options.from_str(text).map_err(|e| syntax_error(&e).with_file(file))?;
        Scene::build(desc, base).map_err(|e| e.with_file(file))
    }

    fn build(desc: SceneDesc, base: &Path) -> Result<Scene, SceneError> {
        Scene::build_with(desc, base, Vec::new())
    }

    /// Builds the scene; `built[i]`, where given, is object `i`'s mesh already read.
    fn build_with(mut desc: SceneDesc, base: &Path, mut built: Vec<Option<MeshData>>) -> Result<Scene, SceneError> {
        validate(&mut desc)?;
        // The analytic meshes' triangles, all counted before any is built.
        let mut planned = 0usize;
        for (i, object) in desc.objects.iter().enumerate() {
            planned = planned.saturating_add(analytic_triangles(&object.mesh).unwrap_or(0));
            if planned > MAX_SCENE_TRIANGLES {
                return Err(SceneError::invalid(
                    format!("objects[{i}].mesh"),
                    format!("the scene's meshes reach {planned} triangles by this object, above the limit of {MAX_SCENE_TRIANGLES}"),
                    "use coarser meshes (fewer sphere segments) or fewer objects",
                ));
            }
        }
        // the memory the analytic meshes (and what is already read) will take, before any
        // is built
        let read: usize = built.iter().flatten().map(|m| m.triangles.len()).sum();
        crate::memory::check(planned.saturating_add(read))
            .map_err(|why| SceneError::invalid("objects", why, "use coarser meshes, or a machine with more memory"))?;
        let mut triangles = Vec::new();
        let mut normals = Vec::new();
        let mut object_triangles = Vec::with_capacity(desc.objects.len());
        let mut instancing = Vec::with_capacity(desc.objects.len());
        let mut reads = Reads::default();
        for (i, object) in desc.objects.iter().enumerate() {
            let start = triangles.len();
            let too_many = |count: usize| {
                let at = match &object.name {
                    Some(n) => format!("objects[{i}] (\"{n}\").mesh"),
                    None => format!("objects[{i}].mesh"),
                };
                SceneError::invalid(
                    at,
                    format!("the scene reaches {count} triangles with this object, above the limit of {MAX_SCENE_TRIANGLES}"),
                    "use coarser meshes or fewer objects",
                )
            };
            if let Some(n) = analytic_triangles(&object.mesh)
                && start.saturating_add(n) > MAX_SCENE_TRIANGLES
            {
                return Err(too_many(start.saturating_add(n)));
            }
            let mut mesh = match built.get_mut(i).and_then(Option::take) {
                Some(mesh) => mesh,
                None => build_mesh(i, object, base, &mut reads)?,
            };
            if start.saturating_add(mesh.triangles.len()) > MAX_SCENE_TRIANGLES {
                return Err(too_many(start.saturating_add(mesh.triangles.len())));
            }
            place(&mesh, object, &mut triangles, &mut normals);
            object_triangles.push(start..triangles.len());
            // kept where the triangles are its instances' exactly: the object's transform
            // adds none, its normals are the file's, and no triangle was dropped
            let identity =
                object.transform.matrix().to_cols_array().map(f32::to_bits) == glam::Mat4::IDENTITY.to_cols_array().map(f32::to_bits);
            let placed = triangles.len() - start;
            instancing.push(
                mesh.instancing
                    .take()
                    .filter(|s| identity && !object.flat_normals && s.triangles() == placed),
            );
        }
        let bounds = bounds_of(triangles.iter().flatten().copied());
        let scene = Scene {
            camera: desc.camera,
            shadow_map: desc.shadow_map,
            lights: desc.lights,
            shadow_fit: desc.shadow_fit,
            cascades: desc.cascades,
            objects: desc.objects,
            source: None,
            notes: reads.notes,
            files: reads.files,
            placements: (0, 0),
            triangles,
            normals,
            object_triangles,
            instancing,
            bounds,
        };
        scene.check_precision()?;
        scene.check_fit(scene.shadow_fit)?;
        Ok(scene)
    }

    /// Refuses `Casters` when no object casts a triangle.
    fn check_fit(&self, fit: ShadowFit) -> Result<(), SceneError> {
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

    /// Replaces the camera, checked as a scene file's is.
    pub fn set_camera(&mut self, camera: Camera) -> Result<(), SceneError> {
        validate_camera(&camera)?;
        self.camera = camera;
        Ok(())
    }

    /// Replaces light `i` (or adds it, at `i` = the number of lights), checked and its
    /// directions normalised as a scene file's are.
    pub fn set_light(&mut self, i: usize, light: Light) -> Result<(), SceneError> {
        let light = checked_light(i, light)?;
        match i.cmp(&self.lights.len()) {
            std::cmp::Ordering::Less => self.lights[i] = light,
            std::cmp::Ordering::Equal => self.lights.push(light),
            std::cmp::Ordering::Greater => {
                return Err(SceneError::invalid(
                    format!("lights[{i}]"),
                    format!("the scene has {} light(s): light {i} would leave a gap", self.lights.len()),
                    "replace an existing light or add the next one",
                ));
            }
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

    /// Whether object `i` casts shadows (`casts` in the file; default true).
    pub fn casts(&self, i: usize) -> bool {
        self.objects[i].casts
    }

    /// Whether object `i` receives shadows (`receives` in the file; default true).
    pub fn receives(&self, i: usize) -> bool {
        self.objects[i].receives
    }

    /// For each triangle of [`Scene::triangles`], whether its object casts shadows.
    pub fn casting_triangles(&self) -> Vec<bool> {
        let mut out = vec![true; self.triangles.len()];
        for (i, o) in self.objects.iter().enumerate() {
            if !o.casts {
                out[self.object_triangles[i].clone()].fill(false);
            }
        }
        out
    }

    /// Number of triangles of casting objects.
    pub fn caster_triangles(&self) -> usize {
        (0..self.objects.len())
            .filter(|&i| self.objects[i].casts)
            .map(|i| self.object_triangles[i].len())
            .sum()
    }

    /// The object that triangle `t` of [`Scene::triangles`] belongs to.
    pub fn object_of_triangle(&self, t: usize) -> Option<usize> {
        // object ranges are in file order and do not overlap
        let i = self.object_triangles.partition_point(|r| r.end <= t);
        (i < self.object_triangles.len() && self.object_triangles[i].contains(&t)).then_some(i)
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

    /// What loading noted: what a glTF file had that was ignored or assumed. Each says its
    /// file; a command prints them once.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The mesh files read (OBJ, glTF and its buffers), besides the scene file itself.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// For a scene loaded from a glTF file: how many nodes place a mesh, and how many
    /// distinct meshes they place (the instancing the file holds); (0, 0) otherwise.
    pub fn placements(&self) -> (usize, usize) {
        self.placements
    }

    /// The scene file this scene was loaded from, if any.
    pub fn source(&self) -> Option<&Path> {
        self.source.as_deref()
    }

    /// The objects as written in the file.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// World-space triangles after transforms, object by object in file order;
    /// degenerate triangles (zero area, non-finite corners) are dropped.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// World-space unit normals of the three corners of each triangle of
    /// [`Scene::triangles`] (smooth where the mesh has smooth normals).
    pub fn normals(&self) -> &[[Vec3; 3]] {
        &self.normals
    }

    /// The range of [`Scene::triangles`] that object `i` produced.
    pub fn object_triangles(&self, i: usize) -> Range<usize> {
        self.object_triangles[i].clone()
    }

    /// Object `i`'s meshes and instances, where a glTF file shares meshes between nodes
    /// (read once, each node's instance placed by its matrix): its triangles
    /// ([`Scene::object_triangles`]) are these instances placed, in order. `None` for
    /// other objects, and where the scene's triangles are not exactly the instances' (the
    /// object has a transform of its own or flat normals, a node's matrix mirrors, or a
    /// degenerate triangle was dropped).
    pub fn instancing(&self, i: usize) -> Option<&crate::source::Instancing> {
        self.instancing.get(i)?.as_ref()
    }

    /// Vertex buffer for the GPU: 3 vertices per triangle, each 6 `f32`: world position
    /// xyz, then world unit normal xyz (stride 24 bytes).
    pub fn vertex_data(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.triangles.len() * 18);
        for (tri, nrm) in self.triangles.iter().zip(&self.normals) {
            for k in 0..3 {
                out.extend_from_slice(&tri[k].to_array());
                out.extend_from_slice(&nrm[k].to_array());
            }
        }
        out
    }

    /// Axis-aligned bounds (min, max) of all triangles; (0, 0) for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Replaces the camera's image size (e.g. a small image in tests).
    pub fn set_camera_size(&mut self, width: u32, height: u32) {
        match &mut self.camera {
            Camera::Perspective { width: w, height: h, .. } | Camera::Orthographic { width: w, height: h, .. } => {
                *w = width.max(1);
                *h = height.max(1);
            }
        }
    }

    /// The camera's image size (width, height) in pixels.
    pub fn camera_size(&self) -> (u32, u32) {
        match &self.camera {
            Camera::Perspective { width, height, .. } | Camera::Orthographic { width, height, .. } => (*width, *height),
        }
    }

    /// The camera's eye position, world space.
    pub fn camera_position(&self) -> Vec3 {
        match &self.camera {
            Camera::Perspective { position, .. } | Camera::Orthographic { position, .. } => *position,
        }
    }

    /// World to camera view (right-handed, looking down -Z).
    pub fn camera_view(&self) -> Mat4 {
        match &self.camera {
            Camera::Perspective { position, target, up, .. } | Camera::Orthographic { position, target, up, .. } => {
                look_at(*position, *target, *up)
            }
        }
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

    /// The camera's (near, far) distances along the view axis: as written, or fitted to
    /// the bounds (far 1% past the farthest corner, near 1% before the nearest corner in
    /// front of the camera, at least far * 1e-3).
    pub fn camera_near_far(&self) -> (f32, f32) {
        let (near, far) = match &self.camera {
            Camera::Perspective { near, far, .. } | Camera::Orthographic { near, far, .. } => (*near, *far),
        };
        let view = self.camera_view();
        let (lo, hi) = depth_range(&view, self.bounds);
        let far = far.unwrap_or_else(|| (hi * 1.01).max(1e-3));
        let near = near.unwrap_or_else(|| (lo * 0.99).max(far * 1e-3));
        (near, far.max(near * (1.0 + 1e-4)))
    }

    /// Camera view to clip space (right-handed, depth range [0, 1] as WebGPU expects).
    pub fn camera_proj(&self) -> Mat4 {
        let (near, far) = self.camera_near_far();
        let (w, h) = self.camera_size();
        let aspect = w.max(1) as f32 / h.max(1) as f32;
        match &self.camera {
            Camera::Perspective { fov_y_degrees, .. } => perspective(fov_y_degrees.to_radians(), aspect, near, far),
            Camera::Orthographic { half_height, .. } => {
                let hw = half_height * aspect;
                orthographic(-hw, hw, -half_height, *half_height, near, far)
            }
        }
    }

    /// `camera_proj() * camera_view()`.
    pub fn camera_view_proj(&self) -> Mat4 {
        self.camera_proj() * self.camera_view()
    }

    /// A 64-bit FNV-1a hash of everything that determines a ground-truth image: the
    /// world-space triangles and normals, the camera and the lights (not the file's text or
    /// paths). A key for caches.
    pub fn fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for b in bytes {
                h ^= u64::from(*b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        // The vertex data's values in its order, without building it (at the triangle limit
        // that copy doubled the scene's memory).
        for (tri, nrm) in self.triangles.iter().zip(&self.normals) {
            for k in 0..3 {
                for v in tri[k].to_array().into_iter().chain(nrm[k].to_array()) {
                    eat(&v.to_bits().to_le_bytes());
                }
            }
        }
        let rest = ron::to_string(&(&self.camera, self.shadow_map, &self.lights)).unwrap_or_default();
        eat(rest.as_bytes());
        // Which objects cast (only when some does not, so that the keys of scenes where
        // every object casts stay as they were).
        if self.objects.iter().any(|o| !o.casts) {
            eat(b"casts");
            for o in &self.objects {
                eat(&[u8::from(o.casts)]);
            }
        }
        // and which receive (only when some does not, likewise)
        if self.objects.iter().any(|o| !o.receives) {
            eat(b"receives");
            for o in &self.objects {
                eat(&[u8::from(o.receives)]);
            }
        }
        h
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
