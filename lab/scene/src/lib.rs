//! Scenes: a camera, lights, objects and the shadow-map resolution, read from RON.
//!
//! A scene file is one `Scene(...)` value (the format is documented in scenes/README.md and docs/truth.md). Reading it builds the
//! world-space triangle list once; the GPU executor takes it as [`Scene::vertex_data`],
//! the CPU ground truth (`sshc_lab::visibility`) as [`Scene::triangles`].
//!
//! ```ron
//! Scene(
//!     camera: Perspective(
//!         position: (0.0, 2.0, 4.0),
//!         target: (0.0, 0.3, 0.0),
//!         fov_y_degrees: 40.0,
//!         width: 256,
//!         height: 256,
//!     ),
//!     shadow_map: 512,
//!     shadow_fit: Scene, // or Casters: fitted to the objects that cast (see `ShadowFit`)
//!     lights: [
//!         Rectangle(center: (1.0, 3.0, 0.5), normal: (0.0, -1.0, 0.0), u_axis: (1.0, 0.0, 0.0),
//!                   half_width: 0.4, half_height: 0.4),
//!     ],
//!     objects: [
//!         Object(name: "floor", mesh: Plane(size: (6.0, 6.0)), casts: false), // receives only
//!         Object(mesh: Box(size: (1.0, 1.0, 1.0)), transform: (translate: (0.0, 0.5, 0.0))),
//!         Object(mesh: Obj(path: "bunny.obj"), transform: (scale: (0.1, 0.1, 0.1))),
//!     ],
//! )
//! ```
//!
//! Conventions: right-handed world, +Y up, lengths in scene units, angles in degrees in
//! the file (radians in the API where named so). Vectors are RON tuples `(x, y, z)`.
//! `Option` fields may be written bare (`near: 0.1`; the `implicit_some` extension is on).
//! Unknown fields are errors. Semantic errors (a negative radius, a zero normal) name the
//! value's path in the file, such as `lights[0] (Disk).radius`; syntax and type errors
//! name the line and column that `ron` reports.
//!
//! Surfaces are two-sided: a triangle occludes light from both sides, and a receiver is
//! the side of its surface that the camera sees, which blocks every light direction behind
//! its tangent plane (the back of an open mesh is in its own shadow, in the techniques and
//! the ground truth alike; scenes/README.md).
//!
//! OBJ paths are relative to the folder of the scene file and must stay inside it: an
//! absolute path, a `..` component or a symbolic link leading out is refused. Material
//! libraries named by an OBJ file are never opened.

#![deny(clippy::wildcard_enum_match_arm)]

use std::fmt;
use std::ops::Range;
use std::path::{Component, Path, PathBuf};

use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// The lights a scene file names and the views fitted to them live in `sshc-light`, which
/// the runtime shares (a host's lights are fitted by the same code).
pub use sshc_light::{Light, LightView, corners, fit_guard, look_at, orthographic, perspective};
use sshc_light::{any_perpendicular_up, bounds_of, depth_range, enclosing_axis, ortho_light_view, padded, perspective_light_view};

// ---------------------------------------------------------------------------------------
// File schema
// ---------------------------------------------------------------------------------------

/// The scene file's top-level value, as written: `Scene(camera: ..., shadow_map: ...,
/// lights: [...], objects: [...])`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
pub struct SceneDesc {
    /// The viewpoint of the shaded image.
    pub camera: Camera,
    /// Side of the (square) shadow map, in texels, for every light view. At least 1.
    pub shadow_map: u32,
    /// The lights; visibility is computed for each. May be empty.
    #[serde(default)]
    pub lights: Vec<Light>,
    /// The geometry. May be empty.
    #[serde(default)]
    pub objects: Vec<Object>,
    /// What the light's view (the shadow map) is fitted to: `Scene` (default, every
    /// object) or `Casters` (the objects with `casts: true`, padded by the reach of their
    /// penumbra; see [`ShadowFit`]).
    #[serde(default)]
    pub shadow_fit: ShadowFit,
}

/// What the light's view, and so the shadow map, is fitted to.
///
/// - `Scene` (the default): the bounds of every object.
/// - `Casters`: laterally, the corners of the casting objects' triangles (`casts: true`),
///   padded on every side by the farthest reach of their penumbra ([`Scene::penumbra_reach`])
///   and then by one guard texel (so that the map's outermost texels never hold a caster
///   and a lookup clamped to the map's edge reads no occluder); in depth, the bounds of
///   every object, so that near and far still cover every receiver (depth is normalised
///   between them). This is how Lawlor 2006 frames his figure 11: the map fitted to the
///   occluder, not to the ground. At least one object must cast.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ShadowFit {
    /// Fitted to the bounds of the whole scene.
    #[default]
    Scene,
    /// Fitted to the casting objects, padded by their penumbra's reach.
    Casters,
    /// Fitted to what the camera sees: laterally, the receivers inside the
    /// camera's frustum (every triangle clipped to it), padded by the casters' penumbra
    /// reach and one guard texel; in depth, from the nearest caster (or visible receiver)
    /// inside that footprint to the farthest visible receiver. A light at a finite
    /// position looks along the axis of the narrowest cone holding the visible receivers;
    /// a light at infinity along its direction. Falls back to `Scene` when the camera sees
    /// no triangle.
    View,
}

/// The camera of the shaded image. `position` looks at `target`; `up` (default +Y) picks
/// the roll and must not be parallel to the view direction. `width` x `height` is the
/// image size in pixels. `near`/`far` (view-space distances along the view axis) default
/// to a fit around the scene bounds: far just past the farthest corner, near just before
/// the nearest corner in front of the camera but at least far * 1e-3.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Camera {
    /// A pinhole camera with a vertical field of view.
    Perspective {
        /// Eye position, world space.
        position: Vec3,
        /// The point the camera looks at, world space.
        target: Vec3,
        /// Approximate up direction (default (0, 1, 0)).
        #[serde(default = "default_up")]
        up: Vec3,
        /// Full vertical field of view in degrees, in (0, 180).
        fov_y_degrees: f32,
        /// Image width in pixels, at least 1.
        width: u32,
        /// Image height in pixels, at least 1.
        height: u32,
        /// Near plane distance; fitted to the scene when absent.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        near: Option<f32>,
        /// Far plane distance; fitted to the scene when absent.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        far: Option<f32>,
    },
    /// A parallel projection; the view volume is `half_height` above and below the view
    /// axis and `half_height * width / height` to either side.
    Orthographic {
        /// Eye position, world space. Geometry behind it (closer than `near`) is clipped,
        /// which lets a camera sit between an occluder and the surface it shades.
        position: Vec3,
        /// The point the camera looks at, world space.
        target: Vec3,
        /// Approximate up direction (default (0, 1, 0)).
        #[serde(default = "default_up")]
        up: Vec3,
        /// Half the height of the view volume, in scene units, > 0.
        half_height: f32,
        /// Image width in pixels, at least 1.
        width: u32,
        /// Image height in pixels, at least 1.
        height: u32,
        /// Near plane distance; fitted to the scene when absent.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        near: Option<f32>,
        /// Far plane distance; fitted to the scene when absent.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        far: Option<f32>,
    },
}

fn default_up() -> Vec3 {
    Vec3::Y
}

/// One piece of geometry: a mesh placed by a transform.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Object", deny_unknown_fields)]
pub struct Object {
    /// Optional name, used in error messages only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The mesh, in object space.
    pub mesh: Mesh,
    /// Object-to-world placement (default: identity).
    #[serde(default)]
    pub transform: Transform,
    /// Use each triangle's face normal even where the mesh has smooth normals
    /// (default false).
    #[serde(default)]
    pub flat_normals: bool,
    /// Whether the object casts shadows (default true). A non-caster (a ground plane) is
    /// seen by the camera and receives shadows, but is not drawn from the light (not in
    /// Depth passes nor in the edges of Geometry passes) and blocks no shadow ray of the
    /// ground truth.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub casts: bool,
    /// Whether the object receives shadows (default true). One that does not (a marker, a
    /// light's fixture, a backdrop) is drawn unshadowed: it reads visibility 1, in the
    /// techniques and the ground truth alike. It still casts, unless `casts: false`.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub receives: bool,
}

fn yes() -> bool {
    true
}

fn is_true(b: &bool) -> bool {
    *b
}

/// A mesh in object space. Triangles are counter-clockwise seen from their front side,
/// which gives the default normals; every surface is two-sided (see the module docs):
/// shadow rays hit both sides, and either side can be a receiver.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Mesh {
    /// A rectangle in the XZ plane centred at the origin, facing +Y; `size` = (x, z).
    Plane {
        /// Extent along X and Z.
        size: Vec2,
    },
    /// An axis-aligned box centred at the origin (12 triangles, flat normals).
    Box {
        /// Extent along X, Y, Z.
        size: Vec3,
    },
    /// A UV sphere centred at the origin with smooth normals.
    Sphere {
        /// Radius, > 0.
        radius: f32,
        /// Segments around the Y axis, at least 3; it has `max(2, segments / 2)` rings.
        segments: u32,
    },
    /// One triangle.
    Triangle {
        /// First corner.
        a: Vec3,
        /// Second corner.
        b: Vec3,
        /// Third corner.
        c: Vec3,
    },
    /// A quadrilateral given by its corners in order, split into (a, b, c) and (a, c, d).
    Quad {
        /// First corner.
        a: Vec3,
        /// Second corner.
        b: Vec3,
        /// Third corner.
        c: Vec3,
        /// Fourth corner.
        d: Vec3,
    },
    /// A Wavefront OBJ file (every model in it), triangulated; its normals are used when
    /// it has them, else smooth normals are computed (area-weighted).
    Obj {
        /// Relative to the scene file's folder, and inside it.
        path: String,
    },
}

/// Object-to-world placement: scale, then rotate, then translate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Transform {
    /// Translation (default 0).
    pub translate: Vec3,
    /// Rotation (default none).
    pub rotate: Rotation,
    /// Scale per axis (default 1); a negative product mirrors and keeps triangles facing
    /// out.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            translate: Vec3::ZERO,
            rotate: Rotation::None,
            scale: Vec3::ONE,
        }
    }
}

/// A rotation.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Rotation {
    /// No rotation.
    #[default]
    None,
    /// Degrees about the world X, then Y, then Z axes: `R = Rz * Ry * Rx`.
    Euler(f32, f32, f32),
    /// `degrees` about `axis` (right-hand rule; the axis is normalised).
    AxisAngle {
        /// Axis of rotation, non-zero.
        axis: Vec3,
        /// Angle in degrees.
        degrees: f32,
    },
}

impl Transform {
    /// The object-to-world matrix.
    pub fn matrix(&self) -> Mat4 {
        let q = match &self.rotate {
            Rotation::None => Quat::IDENTITY,
            Rotation::Euler(x, y, z) => {
                Quat::from_rotation_z(z.to_radians()) * Quat::from_rotation_y(y.to_radians()) * Quat::from_rotation_x(x.to_radians())
            }
            Rotation::AxisAngle { axis, degrees } => Quat::from_axis_angle(axis.normalize_or(Vec3::Y), degrees.to_radians()),
        };
        Mat4::from_scale_rotation_translation(self.scale, q, self.translate)
    }
}

// ---------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------

/// What went wrong reading a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneErrorKind {
    /// A file could not be read.
    Io,
    /// RON syntax, or a value of the wrong shape (unknown field, missing field, ...).
    Syntax,
    /// A value out of its range (negative radius, zero normal, ...).
    Invalid,
    /// An OBJ mesh could not be used (bad path, parse error).
    Mesh,
}

/// An error reading a scene: where (file, line:column where known, or the value's path),
/// what, and a hint at the fix.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError(Box<ErrorInfo>);

#[derive(Clone, Debug, PartialEq)]
struct ErrorInfo {
    kind: SceneErrorKind,
    file: Option<PathBuf>,
    position: Option<(usize, usize)>,
    at: Option<String>,
    message: String,
    hint: Option<String>,
}

impl SceneError {
    fn new(kind: SceneErrorKind, message: impl Into<String>) -> Self {
        SceneError(Box::new(ErrorInfo {
            kind,
            file: None,
            position: None,
            at: None,
            message: message.into(),
            hint: None,
        }))
    }

    fn invalid(at: impl Into<String>, message: impl Into<String>, hint: impl Into<String>) -> Self {
        SceneError::new(SceneErrorKind::Invalid, message).with_at(at).with_hint(hint)
    }

    fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.0.hint = Some(hint.into());
        self
    }

    fn with_at(mut self, at: impl Into<String>) -> Self {
        self.0.at = Some(at.into());
        self
    }

    fn with_position(mut self, position: (usize, usize)) -> Self {
        self.0.position = Some(position);
        self
    }

    /// Names the scene file unless a file is already named.
    fn with_file(mut self, file: Option<&Path>) -> Self {
        if self.0.file.is_none() {
            self.0.file = file.map(Path::to_path_buf);
        }
        self
    }

    /// The kind of error.
    pub fn kind(&self) -> SceneErrorKind {
        self.0.kind
    }
    /// The scene file, when read from a file.
    pub fn file(&self) -> Option<&Path> {
        self.0.file.as_deref()
    }
    /// 1-based line and column, where known (syntax and type errors).
    pub fn line_col(&self) -> Option<(usize, usize)> {
        self.0.position
    }
    /// The path of the offending value in the file (`lights[0] (Disk).radius`), for
    /// semantic errors.
    pub fn at(&self) -> Option<&str> {
        self.0.at.as_deref()
    }
    /// What is wrong.
    pub fn message(&self) -> &str {
        &self.0.message
    }
    /// What would fix it.
    pub fn hint(&self) -> Option<&str> {
        self.0.hint.as_deref()
    }
}

impl fmt::Display for SceneError {
    /// `FILE:LINE:COL: error: MESSAGE` (parts that are unknown are left out; `<scene>`
    /// stands for a scene read from a string), then `at VALUE` and `hint: ...` lines.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0.file {
            Some(p) => write!(f, "{}", p.display())?,
            None => f.write_str("<scene>")?,
        }
        if let Some((line, col)) = self.0.position {
            write!(f, ":{line}:{col}")?;
        }
        write!(f, ": error: {}", self.0.message)?;
        if let Some(at) = &self.0.at {
            write!(f, "\n  at: {at}")?;
        }
        if let Some(hint) = &self.0.hint {
            write!(f, "\n  hint: {hint}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}

fn syntax_error(e: &ron::error::SpannedError) -> SceneError {
    use ron::Error as E;
    // ron's error has dozens of variants (and may gain more): the ones with a specific
    // fix are named, the rest point at the format's reference
    #[allow(clippy::wildcard_enum_match_arm)]
    let hint = match &e.code {
        E::NoSuchStructField { expected, .. } => format!("the fields allowed here are: {}", expected.join(", ")),
        E::MissingStructField { field, outer } => match outer {
            Some(outer) => format!("add `{field}: ...` to this `{outer}`"),
            None => format!("add `{field}: ...`"),
        },
        E::NoSuchEnumVariant { expected, .. } => format!("write one of: {}", expected.join(", ")),
        E::DuplicateStructField { field, .. } => format!("remove one of the `{field}` fields"),
        E::ExpectedComma => "separate fields and list items with `,`".to_string(),
        _ => "see scenes/README.md for the scene format".to_string(),
    };
    SceneError::new(SceneErrorKind::Syntax, e.code.to_string())
        .with_position((e.span.start.line, e.span.start.col))
        .with_hint(hint)
}

// ---------------------------------------------------------------------------------------
// The loaded scene
// ---------------------------------------------------------------------------------------

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
    objects: Vec<Object>,
    source: Option<PathBuf>,
    triangles: Vec<[Vec3; 3]>,
    normals: Vec<[Vec3; 3]>,
    object_triangles: Vec<Range<usize>>,
    bounds: (Vec3, Vec3),
}

impl Scene {
    /// Reads a scene file. OBJ paths resolve against the file's folder.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| {
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

    fn build(mut desc: SceneDesc, base: &Path) -> Result<Scene, SceneError> {
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
        let mut triangles = Vec::new();
        let mut normals = Vec::new();
        let mut object_triangles = Vec::with_capacity(desc.objects.len());
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
            let mesh = build_mesh(i, object, base)?;
            if start.saturating_add(mesh.triangles.len()) > MAX_SCENE_TRIANGLES {
                return Err(too_many(start.saturating_add(mesh.triangles.len())));
            }
            place(&mesh, object, &mut triangles, &mut normals);
            object_triangles.push(start..triangles.len());
        }
        let bounds = bounds_of(triangles.iter().flatten().copied());
        let scene = Scene {
            camera: desc.camera,
            shadow_map: desc.shadow_map,
            lights: desc.lights,
            shadow_fit: desc.shadow_fit,
            objects: desc.objects,
            source: None,
            triangles,
            normals,
            object_triangles,
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
        let vp = self.camera_view_proj();
        // the six planes of WebGPU's clip volume: -w <= x, y <= w, 0 <= z <= w
        let planes: [fn(Vec4) -> f32; 6] = [|c| c.w + c.x, |c| c.w - c.x, |c| c.w + c.y, |c| c.w - c.y, |c| c.z, |c| c.w - c.z];
        let mut out = Vec::new();
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
            out.extend(poly.iter().map(|p| p.1));
        }
        out
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
            let field = match light {
                Light::Point { .. } => "position",
                Light::Segment { .. } | Light::Triangle { .. } => "a",
                Light::Sphere { .. } | Light::Disk { .. } | Light::Rectangle { .. } => "center",
                // distant lights have no distance (the loop skips them)
                Light::Directional { .. } | Light::DistantDisk { .. } => "direction",
            };
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

// ---------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------

/// Most segments of a `Sphere` mesh (it has `segments * max(2, segments / 2) * 2`
/// triangles: 1,048,576 at this limit).
pub const MAX_SPHERE_SEGMENTS: u32 = 1024;
/// Most triangles in a scene, all objects together (checked before allocating).
pub const MAX_SCENE_TRIANGLES: usize = 1 << 24;
/// Largest OBJ file read, in bytes (256 MiB).
pub const MAX_OBJ_BYTES: u64 = 256 << 20;
/// Smallest magnitude of a scale component: below it the object's triangles underflow f32.
pub const MIN_SCALE: f32 = 1e-10;
/// Largest camera `near`, `far` and position-to-target distance: the projection multiplies
/// near by far, which must stay within f32.
pub const MAX_CAMERA_DISTANCE: f32 = 1e15;
/// Most pixels of the scene's camera (4096 x 4096).
pub const MAX_CAMERA_PIXELS: u64 = 4096 * 4096;
/// Smallest object size (bounds' diagonal) relative to the scene's largest coordinate
/// magnitude: 2^-16, the ground truth's ray offset relative to a point's coordinates
/// (128 to 256 ulp); see [`Scene::check_precision`].
pub const PRECISION_RATIO: f32 = 1.0 / 65536.0;
/// f32 ulps of a local light's distance allowed per shadow-map texel of the scene: the
/// light view's coordinates must resolve 1/16 of a texel; see [`Scene::check_precision`].
pub const LIGHT_PRECISION_MARGIN: f32 = 16.0;

fn finite3(v: Vec3) -> bool {
    v.is_finite()
}

/// Checks ranges and normalises directions in place.
fn validate(desc: &mut SceneDesc) -> Result<(), SceneError> {
    if desc.shadow_map == 0 {
        return Err(SceneError::invalid(
            "shadow_map",
            "the shadow map has no texels",
            "write a resolution of at least 1, such as 512",
        ));
    }
    validate_camera(&desc.camera)?;
    for (i, light) in desc.lights.iter_mut().enumerate() {
        let name = light.kind_name();
        let at = |field: &str| format!("lights[{i}] ({name}).{field}");
        validate_light(light, &at)?;
    }
    for (i, object) in desc.objects.iter().enumerate() {
        let at = |field: &str| match &object.name {
            Some(n) => format!("objects[{i}] (\"{n}\").{field}"),
            None => format!("objects[{i}].{field}"),
        };
        validate_object(object, &at)?;
    }
    Ok(())
}

fn validate_camera(camera: &Camera) -> Result<(), SceneError> {
    let (name, position, target, up, width, height, near, far) = match camera {
        Camera::Perspective {
            position,
            target,
            up,
            width,
            height,
            near,
            far,
            ..
        } => ("Perspective", position, target, up, width, height, near, far),
        Camera::Orthographic {
            position,
            target,
            up,
            width,
            height,
            near,
            far,
            ..
        } => ("Orthographic", position, target, up, width, height, near, far),
    };
    let at = |f: &str| format!("camera ({name}).{f}");
    for (field, v) in [("position", position), ("target", target), ("up", up)] {
        if !finite3(*v) {
            return Err(SceneError::invalid(at(field), "the vector is not finite", "write finite numbers"));
        }
    }
    let dir = *target - *position;
    if dir.length_squared() == 0.0 {
        return Err(SceneError::invalid(
            at("target"),
            "the camera looks at its own position",
            "move `target` away from `position`",
        ));
    }
    let distance = (target.as_dvec3() - position.as_dvec3()).length();
    if distance > f64::from(MAX_CAMERA_DISTANCE) {
        return Err(SceneError::invalid(
            at("target"),
            format!("`target` is {distance:e} from `position`, beyond the limit of {MAX_CAMERA_DISTANCE:e} (f32 cannot hold the view)"),
            "bring the camera closer to its target, or scale the scene down",
        ));
    }
    if up.length_squared() == 0.0 || dir.normalize().cross(up.normalize()).length() < 1e-4 {
        return Err(SceneError::invalid(
            at("up"),
            "`up` is zero or parallel to the view direction",
            "choose an `up` not parallel to `target - position` (looking straight down, use (0.0, 0.0, -1.0))",
        ));
    }
    if *width == 0 || *height == 0 {
        return Err(SceneError::invalid(
            at("width"),
            "the image has no pixels",
            "write a width and height of at least 1",
        ));
    }
    let pixels = u64::from(*width) * u64::from(*height);
    if pixels > MAX_CAMERA_PIXELS {
        return Err(SceneError::invalid(
            at("width"),
            format!("{width} x {height} is {pixels} pixels, above the limit of {MAX_CAMERA_PIXELS} (4096 x 4096)"),
            "write a smaller camera size: the read-backs hold several float images of this size",
        ));
    }
    match camera {
        Camera::Perspective { fov_y_degrees, .. } if !(*fov_y_degrees > 0.0 && *fov_y_degrees < 180.0) => {
            return Err(SceneError::invalid(
                at("fov_y_degrees"),
                format!("field of view {fov_y_degrees} is outside (0, 180) degrees"),
                "write a field of view such as 45.0",
            ));
        }
        Camera::Orthographic { half_height, .. } if !(*half_height > 0.0 && half_height.is_finite()) => {
            return Err(SceneError::invalid(
                at("half_height"),
                format!("half height {half_height} is not positive"),
                "write a positive half height",
            ));
        }
        Camera::Perspective { .. } | Camera::Orthographic { .. } => {}
    }
    if let Some(n) = near
        && !(*n > 0.0 && n.is_finite())
    {
        return Err(SceneError::invalid(
            at("near"),
            format!("near {n} is not positive"),
            "write a positive near distance or leave it out",
        ));
    }
    for (field, v) in [("near", near), ("far", far)] {
        if let Some(v) = v
            && *v > MAX_CAMERA_DISTANCE
        {
            return Err(SceneError::invalid(
                at(field),
                format!(
                    "{field} {v:e} is beyond the limit of {MAX_CAMERA_DISTANCE:e}: the projection multiplies near by far, which overflows f32"
                ),
                "write near and far of at most 1e15, or leave them out to fit the scene",
            ));
        }
    }
    if let Some(f) = far
        && !(*f > near.unwrap_or(0.0) && f.is_finite())
    {
        return Err(SceneError::invalid(
            at("far"),
            format!("far {f} is not positive and beyond near"),
            "write far > near > 0 or leave them out",
        ));
    }
    Ok(())
}

fn check_unit(v: &mut Vec3, at: String) -> Result<(), SceneError> {
    if !(finite3(*v) && v.length_squared() > 0.0) {
        return Err(SceneError::invalid(
            at,
            "the direction is zero or not finite",
            "write a non-zero direction such as (0.0, -1.0, 0.0)",
        ));
    }
    *v = v.normalize();
    Ok(())
}

fn check_point(v: &Vec3, at: String) -> Result<(), SceneError> {
    if finite3(*v) {
        Ok(())
    } else {
        Err(SceneError::invalid(at, "the position is not finite", "write finite numbers"))
    }
}

fn check_size(x: f32, at: String, what: &str) -> Result<(), SceneError> {
    if x >= 0.0 && x.is_finite() {
        Ok(())
    } else {
        Err(SceneError::invalid(
            at,
            format!("{what} {x} is negative or not finite"),
            format!("write a {what} >= 0"),
        ))
    }
}

fn validate_light(light: &mut Light, at: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    match light {
        Light::Point { position } => check_point(position, at("position")),
        Light::Directional { direction } => check_unit(direction, at("direction")),
        Light::Sphere { center, radius } => {
            check_point(center, at("center"))?;
            check_size(*radius, at("radius"), "radius")
        }
        Light::Disk { center, normal, radius } => {
            check_point(center, at("center"))?;
            check_unit(normal, at("normal"))?;
            check_size(*radius, at("radius"), "radius")
        }
        Light::Rectangle {
            center,
            normal,
            u_axis,
            half_width,
            half_height,
        } => {
            check_point(center, at("center"))?;
            check_unit(normal, at("normal"))?;
            check_size(*half_width, at("half_width"), "half width")?;
            check_size(*half_height, at("half_height"), "half height")?;
            let u = *u_axis - *normal * u_axis.dot(*normal);
            if !(u.is_finite() && u.length() > 1e-4 * u_axis.length()) {
                return Err(SceneError::invalid(
                    at("u_axis"),
                    "`u_axis` is zero or parallel to `normal`",
                    "write an axis that lies in the rectangle's plane, perpendicular to `normal`",
                ));
            }
            *u_axis = u.normalize();
            Ok(())
        }
        Light::Segment { a, b } => {
            check_point(a, at("a"))?;
            check_point(b, at("b"))
        }
        Light::Triangle { a, b, c } => {
            check_point(a, at("a"))?;
            check_point(b, at("b"))?;
            check_point(c, at("c"))
        }
        Light::DistantDisk { direction, angle_degrees } => {
            check_unit(direction, at("direction"))?;
            if !(*angle_degrees >= 0.0 && *angle_degrees < 180.0) {
                return Err(SceneError::invalid(
                    at("angle_degrees"),
                    format!("angular diameter {angle_degrees} is outside [0, 180) degrees"),
                    "write the full angular diameter in degrees, such as 0.53 for the sun",
                ));
            }
            Ok(())
        }
    }
}

fn validate_object(object: &Object, at: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    let t = &object.transform;
    if !(t.translate.is_finite() && t.scale.is_finite()) {
        return Err(SceneError::invalid(
            at("transform"),
            "the transform is not finite",
            "write finite numbers",
        ));
    }
    let s = t.scale;
    if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
        return Err(SceneError::invalid(
            at("transform.scale"),
            format!("a scale of 0 flattens the object (scale ({}, {}, {}))", s.x, s.y, s.z),
            "write non-zero scales",
        ));
    }
    if s.abs().min_element() < MIN_SCALE {
        return Err(SceneError::invalid(
            at("transform.scale"),
            format!(
                "scale ({:e}, {:e}, {:e}) is too small: below {MIN_SCALE:e} the object degenerates in f32 (its triangles lose their area)",
                s.x, s.y, s.z
            ),
            "write scales of at least 1e-10 in magnitude, or change the scene's units",
        ));
    }
    match &t.rotate {
        Rotation::AxisAngle { axis, degrees } if !(axis.is_finite() && axis.length_squared() > 0.0 && degrees.is_finite()) => {
            return Err(SceneError::invalid(
                at("transform.rotate"),
                "the rotation axis is zero or not finite",
                "write a non-zero axis",
            ));
        }
        Rotation::Euler(x, y, z) if !(x.is_finite() && y.is_finite() && z.is_finite()) => {
            return Err(SceneError::invalid(
                at("transform.rotate"),
                "the angles are not finite",
                "write finite angles",
            ));
        }
        Rotation::None | Rotation::Euler(..) | Rotation::AxisAngle { .. } => {}
    }
    match &object.mesh {
        Mesh::Plane { size } if !(size.is_finite() && size.cmpgt(Vec2::ZERO).all()) => Err(SceneError::invalid(
            at("mesh.size"),
            "a plane needs a positive size",
            "write (x, z) sizes > 0",
        )),
        Mesh::Box { size } if !(size.is_finite() && size.cmpgt(Vec3::ZERO).all()) => Err(SceneError::invalid(
            at("mesh.size"),
            "a box needs a positive size",
            "write (x, y, z) sizes > 0",
        )),
        Mesh::Sphere { radius, .. } if !(*radius > 0.0 && radius.is_finite()) => Err(SceneError::invalid(
            at("mesh.radius"),
            format!("radius {radius} is not positive"),
            "write a radius > 0",
        )),
        Mesh::Sphere { segments, .. } if *segments < 3 => Err(SceneError::invalid(
            at("mesh.segments"),
            format!("{segments} segments cannot make a sphere"),
            "write at least 3 segments",
        )),
        Mesh::Sphere { segments, .. } if *segments > MAX_SPHERE_SEGMENTS => Err(SceneError::invalid(
            at("mesh.segments"),
            format!("{segments} segments is above the limit of {MAX_SPHERE_SEGMENTS}"),
            format!("write at most {MAX_SPHERE_SEGMENTS} segments (a sphere of {MAX_SPHERE_SEGMENTS} segments has 1,048,576 triangles)"),
        )),
        Mesh::Triangle { a, b, c } if !(a.is_finite() && b.is_finite() && c.is_finite()) => {
            Err(SceneError::invalid(at("mesh"), "a corner is not finite", "write finite numbers"))
        }
        Mesh::Quad { a, b, c, d } if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) => {
            Err(SceneError::invalid(at("mesh"), "a corner is not finite", "write finite numbers"))
        }
        Mesh::Plane { .. } | Mesh::Box { .. } | Mesh::Sphere { .. } | Mesh::Triangle { .. } | Mesh::Quad { .. } | Mesh::Obj { .. } => {
            Ok(())
        }
    }
}

// ---------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------

/// Object-space triangles with per-corner normals (`None`: use face normals).
struct MeshData {
    triangles: Vec<[Vec3; 3]>,
    normals: Option<Vec<[Vec3; 3]>>,
}

fn build_mesh(index: usize, object: &Object, base: &Path) -> Result<MeshData, SceneError> {
    let flat = |triangles| MeshData { triangles, normals: None };
    Ok(match &object.mesh {
        Mesh::Plane { size } => {
            let (x, z) = (0.5 * size.x, 0.5 * size.y);
            let (a, b, c, d) = (
                Vec3::new(-x, 0.0, -z),
                Vec3::new(-x, 0.0, z),
                Vec3::new(x, 0.0, z),
                Vec3::new(x, 0.0, -z),
            );
            flat(vec![[a, b, c], [a, c, d]])
        }
        Mesh::Box { size } => flat(box_triangles(*size * 0.5)),
        Mesh::Sphere { radius, segments } => sphere(*radius, *segments),
        Mesh::Triangle { a, b, c } => flat(vec![[*a, *b, *c]]),
        Mesh::Quad { a, b, c, d } => flat(vec![[*a, *b, *c], [*a, *c, *d]]),
        Mesh::Obj { path } => {
            let at = match &object.name {
                Some(n) => format!("objects[{index}] (\"{n}\").mesh.path"),
                None => format!("objects[{index}].mesh.path"),
            };
            load_obj(path, base).map_err(|e| e.with_at(at))?
        }
    })
}

/// Triangles an analytic mesh makes (`None` for OBJ files, counted once read).
fn analytic_triangles(mesh: &Mesh) -> Option<usize> {
    match mesh {
        Mesh::Plane { .. } | Mesh::Quad { .. } => Some(2),
        Mesh::Box { .. } => Some(12),
        Mesh::Triangle { .. } => Some(1),
        Mesh::Sphere { segments, .. } => {
            let s = *segments as usize;
            Some(s.saturating_mul((s / 2).max(2)).saturating_mul(2))
        }
        Mesh::Obj { .. } => None,
    }
}

fn box_triangles(h: Vec3) -> Vec<[Vec3; 3]> {
    let mut out = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // u x v = n, so (c-u-v, c+u-v, c+u+v, c-u+v) runs counter-clockwise around n.
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u);
            let c = n * h;
            let (u, v) = (u * h, v * h);
            let q = [c - u - v, c + u - v, c + u + v, c - u + v];
            out.push([q[0], q[1], q[2]]);
            out.push([q[0], q[2], q[3]]);
        }
    }
    out
}

fn sphere(radius: f32, segments: u32) -> MeshData {
    let rings = (segments / 2).max(2);
    // The poles are exact points (f32's sin(pi) is not 0), so that their triangles share
    // one vertex and the mesh is closed: edge adjacency (silhouettes) welds by position.
    let point = |ring: u32, seg: u32| {
        if ring == 0 || ring == rings {
            return Vec3::new(0.0, if ring == 0 { 1.0 } else { -1.0 }, 0.0);
        }
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (seg % segments) as f32 / segments as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
    };
    let mut triangles = Vec::new();
    let mut normals = Vec::new();
    for ring in 0..rings {
        for seg in 0..segments {
            let p00 = point(ring, seg);
            let p01 = point(ring, seg + 1);
            let p10 = point(ring + 1, seg);
            let p11 = point(ring + 1, seg + 1);
            for tri in [[p00, p10, p11], [p00, p11, p01]] {
                // Face outwards: flip where the winding points in.
                let centroid = tri[0] + tri[1] + tri[2];
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                let tri = if n.dot(centroid) < 0.0 { [tri[0], tri[2], tri[1]] } else { tri };
                normals.push(tri);
                triangles.push(tri.map(|p| p * radius));
            }
        }
    }
    MeshData {
        triangles,
        normals: Some(normals),
    }
}

/// Resolves `rel` inside `base`, refusing absolute paths, `..` and links leading out.
fn resolve_inside(rel: &str, base: &Path) -> Result<PathBuf, SceneError> {
    let escape = |what: &str| {
        SceneError::new(SceneErrorKind::Mesh, format!("the OBJ path `{rel}` {what}"))
            .with_hint("write a path relative to the scene file's folder, without `..`, and put the mesh beside the scene")
    };
    let p = Path::new(rel);
    if rel.is_empty() {
        return Err(escape("is empty"));
    }
    if p.is_absolute() || p.has_root() {
        return Err(escape("is absolute"));
    }
    for c in p.components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            Component::ParentDir => return Err(escape("leaves the scene's folder (`..`)")),
            Component::RootDir | Component::Prefix(_) => return Err(escape("is absolute")),
        }
    }
    let joined = base.join(p);
    let canon_base = base.canonicalize().map_err(|e| {
        SceneError::new(
            SceneErrorKind::Io,
            format!("cannot open the scene's folder `{}`: {e}", base.display()),
        )
        .with_hint("load the scene from an existing folder")
    })?;
    let canon = joined.canonicalize().map_err(|e| {
        SceneError::new(SceneErrorKind::Io, format!("cannot open the OBJ file `{}`: {e}", joined.display()))
            .with_hint("check that the mesh file is beside the scene file")
    })?;
    if !canon.starts_with(&canon_base) {
        return Err(escape("leads out of the scene's folder through a link"));
    }
    Ok(canon)
}

fn load_obj(rel: &str, base: &Path) -> Result<MeshData, SceneError> {
    let path = resolve_inside(rel, base)?;
    let bytes = read_capped(&path, MAX_OBJ_BYTES).map_err(|e| {
        SceneError::new(SceneErrorKind::Io, format!("cannot read the OBJ file `{}`: {e}", path.display())).with_hint(format!(
            "give a regular file (not a pipe or device) of at most {} MiB",
            MAX_OBJ_BYTES >> 20
        ))
    })?;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    // Material libraries are never opened: they could name files outside the folder.
    let (models, _materials) =
        tobj::load_obj_buf(&mut bytes.as_slice(), &options, |_| Err(tobj::LoadError::OpenFileFailed)).map_err(|e| {
            SceneError::new(SceneErrorKind::Mesh, format!("cannot parse the OBJ file `{rel}`: {e}"))
                .with_hint("check that the file is a Wavefront OBJ with `v` and `f` lines")
        })?;
    let mut triangles = Vec::new();
    let mut normals = Vec::new();
    let mut all_have_normals = true;
    let mut computed = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let vertex = |i: u32| {
            let i = i as usize * 3;
            m.positions.get(i..i + 3).map(|s| Vec3::new(s[0], s[1], s[2]))
        };
        let has_normals = m.normals.len() == m.positions.len() && !m.normals.is_empty();
        all_have_normals &= has_normals;
        // Area-weighted smooth normals by vertex index, for meshes without normals.
        let mut smooth = vec![Vec3::ZERO; m.positions.len() / 3];
        let mut tris = Vec::with_capacity(m.indices.len() / 3);
        for f in m.indices.chunks_exact(3) {
            let (Some(a), Some(b), Some(c)) = (vertex(f[0]), vertex(f[1]), vertex(f[2])) else {
                return Err(
                    SceneError::new(SceneErrorKind::Mesh, format!("the OBJ file `{rel}` has a face index out of range"))
                        .with_hint("check the face indices of the OBJ file"),
                );
            };
            let n = (b - a).cross(c - a);
            if n.is_finite() {
                for &k in f {
                    smooth[k as usize] += n;
                }
            }
            tris.push([a, b, c]);
            if has_normals {
                let nr = |i: u32| {
                    let i = i as usize * 3;
                    Vec3::new(m.normals[i], m.normals[i + 1], m.normals[i + 2])
                };
                normals.push([nr(f[0]), nr(f[1]), nr(f[2])]);
            }
        }
        computed.extend(
            m.indices
                .chunks_exact(3)
                .map(|f| [smooth[f[0] as usize], smooth[f[1] as usize], smooth[f[2] as usize]]),
        );
        triangles.extend(tris);
    }
    let normals = if all_have_normals { normals } else { computed };
    Ok(MeshData {
        triangles,
        normals: Some(normals),
    })
}

/// Reads a regular file of at most `cap` bytes; anything else (a FIFO, a device, a folder,
/// a larger file) is refused without reading it (or, if it grows, past `cap + 1` bytes).
fn read_capped(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::other("it is not a regular file"));
    }
    if meta.len() > cap {
        return Err(std::io::Error::other(format!(
            "it has {} bytes, above the limit of {cap}",
            meta.len()
        )));
    }
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(std::io::Error::other(format!("it grew above the limit of {cap} bytes")));
    }
    Ok(bytes)
}

/// Transforms a mesh to world space, drops degenerate triangles, and appends it.
fn place(mesh: &MeshData, object: &Object, triangles: &mut Vec<[Vec3; 3]>, normals: &mut Vec<[Vec3; 3]>) {
    let m = object.transform.matrix();
    let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
    let mirrored = Mat3::from_mat4(m).determinant() < 0.0;
    for (i, tri) in mesh.triangles.iter().enumerate() {
        let mut w = tri.map(|p| m.transform_point3(p));
        let e1 = w[1] - w[0];
        let e2 = w[2] - w[0];
        let e3 = w[2] - w[1];
        let cross = e1.cross(e2);
        let longest = e1.length_squared().max(e2.length_squared()).max(e3.length_squared());
        // Zero area up to f32 rounding of the cross product (about 1.2e-7 * |e1| |e2|).
        if !(w.iter().all(|p| p.is_finite()) && cross.is_finite() && cross.length() > 1e-6 * longest) {
            continue;
        }
        let face = cross.normalize();
        let mut n = match (&mesh.normals, object.flat_normals) {
            (Some(ns), false) => ns[i].map(|n| {
                let n = normal_matrix * n;
                if n.is_finite() && n.length_squared() > 0.0 {
                    n.normalize()
                } else {
                    face
                }
            }),
            _ => [face; 3],
        };
        if mirrored {
            w.swap(1, 2);
            n.swap(1, 2);
        }
        if mesh.normals.is_none() || object.flat_normals {
            // Recompute after a possible swap so the face normal matches the winding.
            let f = (w[1] - w[0]).cross(w[2] - w[0]).normalize();
            n = [f; 3];
        }
        triangles.push(w);
        normals.push(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene file names a light by its kind's name, the name technique files use.
    /// The fingerprint hashes the vertex data in place: the same value as hashing
    /// `vertex_data()` (so truth caches keep their keys), without its copy.
    #[test]
    fn the_fingerprint_is_the_hash_of_the_vertex_data() {
        let scene = Scene::from_str(
            "Scene(camera: Perspective(position: (0.0, 1.0, 4.0), target: (0.0, 0.0, 0.0), fov_y_degrees: 40.0, width: 8, height: 8),
             shadow_map: 16, lights: [Point(position: (0.0, 5.0, 0.0))],
             objects: [Object(mesh: Sphere(radius: 1.0, segments: 8)), Object(mesh: Plane(size: (2.0, 2.0)))])",
            ".",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for b in bytes {
                h ^= u64::from(*b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for v in scene.vertex_data() {
            eat(&v.to_bits().to_le_bytes());
        }
        eat(ron::to_string(&(&scene.camera, scene.shadow_map, &scene.lights))
            .unwrap_or_default()
            .as_bytes());
        assert_eq!(scene.fingerprint(), h);
    }

    #[test]
    fn light_variants_are_named_by_their_kind() {
        let (p, d) = (Vec3::ONE, Vec3::Y);
        let lights = [
            Light::Point { position: p },
            Light::Directional { direction: d },
            Light::Sphere { center: p, radius: 1.0 },
            Light::Disk {
                center: p,
                normal: d,
                radius: 1.0,
            },
            Light::Rectangle {
                center: p,
                normal: d,
                u_axis: Vec3::X,
                half_width: 1.0,
                half_height: 1.0,
            },
            Light::Segment { a: p, b: d },
            Light::DistantDisk {
                direction: d,
                angle_degrees: 1.0,
            },
            Light::Triangle { a: p, b: d, c: Vec3::X },
        ];
        let kinds: Vec<sshc_graph::LightKind> = lights.iter().map(Light::kind).collect();
        assert_eq!(kinds, sshc_graph::LightKind::ALL);
        for l in &lights {
            let ron = ron::to_string(l).unwrap();
            assert!(ron.starts_with(&format!("{}(", l.kind_name())), "{ron}");
            assert_eq!(l.is_distant(), l.direction().is_some());
        }
    }
}
