//! The first camera of a glTF scene as the scene's camera, and the camera framing a scene
//! that has none.

use super::fail;
use crate::error::SceneError;
use crate::schema::Camera;

use glam::{Mat4, Vec3};

/// Pixels of an imported camera's image height; its width follows the aspect ratio.
pub const CAMERA_HEIGHT: u32 = 512;

pub(super) fn map_camera(camera: &gltf::Camera, world: &Mat4, node: usize, file: &str) -> Result<Camera, SceneError> {
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if !(position.is_finite() && forward != Vec3::ZERO && up != Vec3::ZERO) {
        return Err(fail(
            file,
            format_args!("camera {} of node {node} has a transform that collapses its view", camera.index()),
            "give the camera's node an invertible transform",
        ));
    }
    let target = position + forward;
    let size = |aspect: f32| {
        let w = (CAMERA_HEIGHT as f32 * aspect).round();
        if w.is_finite() && w >= 1.0 {
            (w.min(4096.0) as u32, CAMERA_HEIGHT)
        } else {
            (CAMERA_HEIGHT, CAMERA_HEIGHT)
        }
    };
    Ok(match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            // glTF's yfov is in radians: said so here, not as the scene format's degrees
            let yfov = p.yfov();
            if !(yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI) {
                return Err(fail(
                    file,
                    format_args!(
                        "camera {}'s yfov is {yfov} radians ({:.1} degrees), outside (0, pi)",
                        camera.index(),
                        yfov.to_degrees()
                    ),
                    "write `yfov` in radians, such as 0.8 (46 degrees)",
                ));
            }
            let (width, height) = size(p.aspect_ratio().unwrap_or(1.0));
            Camera::Perspective {
                position,
                target,
                up,
                fov_y_degrees: p.yfov().to_degrees(),
                width,
                height,
                near: Some(p.znear()),
                far: p.zfar(),
            }
        }
        gltf::camera::Projection::Orthographic(o) => {
            let (width, height) = size(o.xmag() / o.ymag());
            Camera::Orthographic {
                position,
                target,
                up,
                half_height: o.ymag(),
                width,
                height,
                near: Some(o.znear()),
                far: Some(o.zfar()),
            }
        }
    })
}

/// A camera framing `bounds`: 40 degrees, from above and in front (+Y, +Z), the bounding
/// sphere filling the view's height, 512 x 512 pixels.
pub(crate) fn framing_camera(bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let (centre, radius) = if lo.is_finite() && hi.is_finite() {
        ((lo + hi) * 0.5, (0.5 * (hi - lo).length()).max(1e-3))
    } else {
        (Vec3::ZERO, 1.0)
    };
    let fov = 40.0f32;
    let distance = radius / (0.5 * fov).to_radians().sin();
    let from = Vec3::new(0.35, 0.55, 1.0).normalize();
    Camera::Perspective {
        position: centre + from * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_degrees: fov,
        width: CAMERA_HEIGHT,
        height: CAMERA_HEIGHT,
        near: None,
        far: None,
    }
}
