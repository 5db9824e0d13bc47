//! The scene file's schema: what a scene file says, as serde types.

use glam::{Mat4, Quat, Vec2, Vec3};
use serde::{Deserialize, Serialize};
use sshc_light::Light;

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
    /// Cascaded shadow maps for the scene's light, which must be at infinity and alone:
    /// `cascades: (count: 4)`, with `lambda` (the practical split's weight, default 0.75)
    /// and `band` (the fraction of a slice mixed into the next, default 0.1). Absent: one
    /// map, fitted as `shadow_fit` says. `--cascades` and its options override it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cascades: Option<Cascades>,
}

/// A scene's cascaded shadow maps (see [`SceneDesc::cascades`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cascades {
    /// Cascades, 1 to `sshc_light::MAX_CASCADES`; each `shadow_map` texels wide.
    pub count: u32,
    /// The practical split scheme's weight in [0, 1]: 0 uniform, 1 logarithmic.
    #[serde(default = "default_lambda")]
    pub lambda: f32,
    /// The fraction of each slice, at its far end, mixed into the next, in [0, 1).
    #[serde(default = "default_band")]
    pub band: f32,
}

fn default_lambda() -> f32 {
    0.75
}

fn default_band() -> f32 {
    0.1
}

/// What the light's view, and so the shadow map, is fitted to.
///
/// - `Scene` (the default): the bounds of every object.
/// - `Casters`: laterally, the corners of the casting objects' triangles (`casts: true`),
///   padded on every side by the farthest reach of their penumbra ([`crate::Scene::penumbra_reach`])
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
    /// A glTF 2.0 file (`.gltf` with its buffers beside it, or `.glb`): every triangle
    /// primitive its default scene's nodes place, with their transforms (see the `gltf`
    /// module: materials are ignored, and here its camera and lights too).
    Gltf {
        /// Relative to the scene file's folder, and inside it; so are its buffers.
        path: String,
    },
    /// A procedural city of about `triangles` triangles (towers on a ground plane, a
    /// block apart, centred on the origin; `sshc scene city` writes the same as a GLB
    /// file). Built as glTF and read by the glTF importer; the same `seed` gives the same
    /// city everywhere.
    City {
        /// Triangles to reach, at most the scene limit.
        triangles: u32,
        /// Seed of the layout (default 1).
        #[serde(default = "one")]
        seed: u64,
    },
}

fn one() -> u64 {
    1
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
