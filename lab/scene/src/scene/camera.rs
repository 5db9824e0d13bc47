//! The scene's camera: replacing it, its image size, and its view and projection (near and
//! far fitted to the scene where the file leaves them out).

use super::Scene;
use crate::error::SceneError;
use crate::schema::Camera;
use crate::validate::validate_camera;

use glam::{Mat4, Vec3};
use sshc_light::{depth_range, look_at, orthographic, perspective};

impl Scene {
    /// Replaces the camera, checked as a scene file's is.
    pub fn set_camera(&mut self, camera: Camera) -> Result<(), SceneError> {
        validate_camera(&camera)?;
        self.camera = camera;
        Ok(())
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
}
