//! The viewer's whole state as one value: what a script sets, the log records and "copy as
//! command" prints. Everything that changes the image is here; nothing else is.

use crate::scene::{Camera, Light};
use glam::Vec3;

/// What the window shows, the state a script sets and the lines it copies (in
/// `sshc-records`, with the scripts' reading, where the fuzz target `script` reaches them).
pub use sshc_records::script::{ColourMap, Mode, Split, ViewState, param_literal, ron_line};

/// A camera orbiting its target: what the mouse moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    /// Around +Y, radians.
    pub yaw: f32,
    /// Above the horizontal plane, radians, within (-pi/2, pi/2).
    pub pitch: f32,
    pub distance: f32,
}

impl Orbit {
    /// The orbit through a camera's position and target.
    pub fn of(camera: &Camera) -> Orbit {
        let (position, target) = match camera {
            Camera::Perspective { position, target, .. } | Camera::Orthographic { position, target, .. } => (*position, *target),
        };
        let d = position - target;
        let distance = d.length().max(1e-4);
        Orbit {
            target,
            yaw: d.x.atan2(d.z),
            pitch: (d.y / distance).clamp(-1.0, 1.0).asin(),
            distance,
        }
    }

    pub fn position(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Turn by `dx`, `dy` radians (pitch kept off the poles, where `up` would be parallel
    /// to the view direction).
    pub fn turn(&mut self, dx: f32, dy: f32) {
        self.yaw += dx;
        let limit = std::f32::consts::FRAC_PI_2 - 0.01;
        self.pitch = (self.pitch + dy).clamp(-limit, limit);
    }

    /// Move the target by `dx`, `dy` in the view plane, in units of the distance.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let forward = (self.target - self.position()).normalize_or_zero();
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        let up = right.cross(forward);
        self.target += (right * -dx + up * dy) * self.distance;
    }

    /// Scale the distance by `factor` (> 0).
    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance * factor).clamp(1e-3, 1e6);
    }

    /// `camera` moved onto this orbit (its projection and size kept, `up` +Y).
    pub fn apply(&self, camera: &mut Camera) {
        let p = self.position();
        match camera {
            Camera::Perspective { position, target, up, .. } | Camera::Orthographic { position, target, up, .. } => {
                *position = p;
                *target = self.target;
                *up = Vec3::Y;
            }
        }
    }
}

/// The camera with its image size replaced.
pub fn with_size(camera: &Camera, w: u32, h: u32) -> Camera {
    let mut c = camera.clone();
    match &mut c {
        Camera::Perspective { width, height, .. } | Camera::Orthographic { width, height, .. } => {
            *width = w.max(1);
            *height = h.max(1);
        }
    }
    c
}

/// The light moved by `by` (every point of it), or for a light at infinity, its direction
/// turned by `by.x` radians around +Y and `by.y` radians up.
pub fn moved(light: &Light, by: Vec3) -> Light {
    let turn = |d: Vec3| {
        let len = d.length().max(1e-6);
        let yaw = d.x.atan2(d.z) + by.x;
        let limit = std::f32::consts::FRAC_PI_2 - 0.01;
        let pitch = ((d.y / len).clamp(-1.0, 1.0).asin() + by.y).clamp(-limit, limit);
        Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos())
    };
    light.translated(by).turned(turn)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn camera() -> Camera {
        Camera::Perspective {
            position: Vec3::new(3.0, 2.0, 4.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 40.0,
            width: 64,
            height: 48,
            near: None,
            far: None,
        }
    }

    #[test]
    fn an_orbit_goes_through_the_camera_it_was_made_from() {
        let c = camera();
        let o = Orbit::of(&c);
        let Camera::Perspective { position, .. } = c else { unreachable!() };
        // f32 trigonometry: a few ulps of a distance of about 5
        assert!((o.position() - position).length() < 5.0 * 8.0 * f32::EPSILON, "{:?}", o.position());
        let mut back = camera();
        o.apply(&mut back);
        let Camera::Perspective { position: p2, .. } = back else {
            unreachable!()
        };
        assert!((p2 - position).length() < 5.0 * 8.0 * f32::EPSILON);
    }

    #[test]
    fn a_moved_light_keeps_its_size_and_a_resized_one_its_place() {
        let l = Light::Segment {
            a: Vec3::new(-1.0, 4.0, 0.0),
            b: Vec3::new(1.0, 4.0, 0.0),
        };
        let m = moved(&l, Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(m.size(), Some(1.0));
        let r = m.resized(2.0);
        assert_eq!(
            r,
            Light::Segment {
                a: Vec3::new(-1.5, 4.0, 0.0),
                b: Vec3::new(2.5, 4.0, 0.0)
            }
        );
        let d = moved(&Light::Directional { direction: Vec3::Y }, Vec3::new(0.3, -0.2, 0.0));
        let Light::Directional { direction } = d else { unreachable!() };
        assert!((direction.length() - 1.0).abs() < 4.0 * f32::EPSILON && direction.y < 1.0);
    }

    #[test]
    fn the_command_quotes_what_a_shell_would_split_and_reads_back_the_same_values() {
        let s = ViewState {
            technique: "techniques/pcss.ron".into(),
            scene: "scenes/my scene.ron".into(),
            camera: camera(),
            lights: vec![Light::Sphere {
                center: Vec3::new(0.1, 4.0, 1.0 / 3.0),
                radius: 0.25,
            }],
            params: BTreeMap::from([("bias".to_string(), 0.1 + 0.2)]),
            fixed: BTreeMap::new(),
            precisions: BTreeMap::from([("depth".to_string(), "f16".to_string())]),
            schedules: BTreeMap::new(),
            shadow_map: 512,
            mode: Mode::Shaded,
            split: None,
        };
        let cmd = s.command("out.png");
        assert!(cmd.contains("'scenes/my scene.ron'"), "{cmd}");
        assert!(cmd.contains("--set bias=0.30000000000000004"), "{cmd}");
        assert!(cmd.contains("--precision depth=f16"), "{cmd}");
        // the camera and light read back bit for bit
        let light = cmd.split("--light '").nth(1).and_then(|r| r.split('\'').next()).unwrap();
        let back: Light = ron::from_str(light).unwrap();
        assert_eq!(back, s.lights[0]);
        let cam = cmd.split("--camera '").nth(1).and_then(|r| r.split('\'').next()).unwrap();
        let back: Camera = ron::from_str(cam).unwrap();
        assert_eq!(back, s.camera);
    }
}
