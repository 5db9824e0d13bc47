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

mod error;
pub mod generate;
mod gltf;
pub mod memory;
mod mesh;
mod scene;
mod schema;
mod source;
mod validate;

pub use error::*;
pub use gltf::{CAMERA_HEIGHT as GLTF_CAMERA_HEIGHT, DEFAULT_RADIUS_FRACTION, DEFAULT_SUN_DEGREES, MAX_GLTF_BYTES};
pub use scene::*;
pub use schema::*;
pub use source::{Instancing, MAX_TEXT_BYTES, SharedMesh, read_capped, read_text};
pub use validate::*;

/// The lights a scene file names and the views fitted to them live in `sshc-light`, which
/// the runtime shares (a host's lights are fitted by the same code).
pub use sshc_light::{Light, LightView, MAX_LIGHTS, corners, fit_guard, look_at, orthographic, perspective};

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
