//! The viewer's whole state as one value: what a script sets, the log records and "copy as
//! command" prints. Everything that changes the image is here; nothing else is.

use crate::scene::{Camera, Light};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// What the window shows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Mode {
    /// The shaded image (the Shade pass's colour; every light's combination).
    Shaded,
    /// Light 0's visibility, 0 black to 1 white.
    Visibility,
    /// Which cascade each pixel takes (`--cascades` or the scene's `cascades:`): the
    /// cascade's index through viridis, dark blue for the nearest, yellow for the farthest,
    /// blended across the band where two mix. One colour without cascades.
    Cascades,
    /// The ray-traced truth of light 0, refined while the view stands still.
    Truth,
    /// The visibility less the truth, blue below, red above, white where they agree;
    /// `range` is the error at full colour.
    Error { range: f32 },
    /// The truth's standard error, 0 to `range` (viridis).
    StdError { range: f32 },
    /// One channel of one layer and level of a texture of the graph, mapped from
    /// `[lo, hi]` through a colour map.
    Texture {
        name: String,
        layer: u32,
        level: u32,
        /// 0 to 3: r, g, b, a.
        channel: u32,
        lo: f32,
        hi: f32,
        map: ColourMap,
    },
}

/// How a value in `[0, 1]` becomes a colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ColourMap {
    Grey,
    /// Perceptually ordered, dark blue to yellow (a polynomial fit of matplotlib's viridis).
    Viridis,
    /// Blue below the middle, white at it, red above: for signed values.
    Diverging,
}

impl ColourMap {
    pub const ALL: [ColourMap; 3] = [ColourMap::Grey, ColourMap::Viridis, ColourMap::Diverging];

    pub fn name(self) -> &'static str {
        match self {
            ColourMap::Grey => "grey",
            ColourMap::Viridis => "viridis",
            ColourMap::Diverging => "diverging",
        }
    }

    /// The index the present shader switches on.
    pub fn index(self) -> u32 {
        match self {
            ColourMap::Grey => 0,
            ColourMap::Viridis => 1,
            ColourMap::Diverging => 2,
        }
    }
}

/// The camera and lights, the technique's settings and what is shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewState {
    /// The technique file.
    pub technique: PathBuf,
    /// The scene file.
    pub scene: PathBuf,
    /// The scene's camera as it is now (its size is the window's).
    pub camera: Camera,
    /// The scene's lights as they are now.
    pub lights: Vec<Light>,
    /// Runtime params moved from their defaults (uniforms: no recompile).
    pub params: BTreeMap<String, f64>,
    /// Fixed params set at compile time (`--set`: a recompile).
    pub fixed: BTreeMap<String, String>,
    /// Precision overrides (`--precision`).
    pub precisions: BTreeMap<String, String>,
    /// Schedule overrides (`--schedule`).
    pub schedules: BTreeMap<String, String>,
    pub shadow_map: u32,
    pub mode: Mode,
    /// A second technique or setting on the right half of the window, on the same camera
    /// and lights (the left half is the one above).
    #[serde(default)]
    pub split: Option<Split>,
}

/// The right half of a split view: its technique and settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Split {
    pub technique: PathBuf,
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    #[serde(default)]
    pub fixed: BTreeMap<String, String>,
    #[serde(default)]
    pub precisions: BTreeMap<String, String>,
    #[serde(default)]
    pub schedules: BTreeMap<String, String>,
}

impl ViewState {
    /// The split's own state: this one with the split's technique and settings.
    pub fn right(&self) -> Option<ViewState> {
        let s = self.split.as_ref()?;
        Some(ViewState {
            technique: s.technique.clone(),
            params: s.params.clone(),
            fixed: s.fixed.clone(),
            precisions: s.precisions.clone(),
            schedules: s.schedules.clone(),
            split: None,
            ..self.clone()
        })
    }

    /// The settings of this view as a split's (to compare them with others).
    pub fn as_split(&self) -> Split {
        Split {
            technique: self.technique.clone(),
            params: self.params.clone(),
            fixed: self.fixed.clone(),
            precisions: self.precisions.clone(),
            schedules: self.schedules.clone(),
        }
    }

    /// The `sshc render` line that renders this view: the same technique, settings,
    /// camera (with the window's size) and lights, bit for bit where the arithmetic is the
    /// same. Arguments are quoted for a POSIX shell.
    pub fn command(&self, out: &str) -> String {
        let mut words = vec![
            "sshc".to_string(),
            "render".to_string(),
            quote(&self.technique.display().to_string()),
            "--scene".to_string(),
            quote(&self.scene.display().to_string()),
            "--shadow-map".to_string(),
            self.shadow_map.to_string(),
            // the viewer's lights move: its graph is compiled for any scene
            "--generic".to_string(),
            "--camera".to_string(),
            quote(&ron_line(&self.camera)),
        ];
        for l in &self.lights {
            words.push("--light".to_string());
            words.push(quote(&ron_line(l)));
        }
        for (k, v) in &self.fixed {
            words.push("--set".to_string());
            words.push(quote(&format!("{k}={v}")));
        }
        for (k, v) in &self.params {
            words.push("--set".to_string());
            words.push(quote(&format!("{k}={}", param_literal(*v))));
        }
        for (k, v) in &self.precisions {
            words.push("--precision".to_string());
            words.push(quote(&format!("{k}={v}")));
        }
        for (k, v) in &self.schedules {
            words.push("--schedule".to_string());
            words.push(quote(&format!("{k}={v}")));
        }
        words.push("--out".to_string());
        words.push(quote(out));
        words.join(" ")
    }
}

/// A param's value as `--set` takes it: the shortest text that reads back as the same f64.
pub fn param_literal(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.1}")
    } else {
        format!("{v}")
    }
}

/// A value as one line of RON (what `--camera` and `--light` read).
pub fn ron_line<T: Serialize>(v: &T) -> String {
    ron::to_string(v).unwrap_or_default()
}

/// `s` quoted for a POSIX shell where it needs it.
fn quote(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

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

/// The light's size: radius, half extent, half length or angle; `None` for a light with
/// no extent.
pub fn size(light: &Light) -> Option<f32> {
    match light {
        Light::Point { .. } | Light::Directional { .. } => None,
        Light::Sphere { radius, .. } | Light::Disk { radius, .. } => Some(*radius),
        Light::Rectangle { half_width, .. } => Some(*half_width),
        Light::Segment { a, b } => Some(0.5 * (*b - *a).length()),
        Light::Triangle { a, b, c } => {
            let m = (*a + *b + *c) / 3.0;
            Some((*a - m).length())
        }
        Light::DistantDisk { angle_degrees, .. } => Some(*angle_degrees),
    }
}

/// The light with its size set to `s` (its shape kept: [`Light::scaled`] about its
/// centre by the ratio of the sizes).
pub fn resized(light: &Light, s: f32) -> Light {
    let s = s.max(0.0);
    match size(light).filter(|&old| old > 0.0) {
        Some(old) => light.scaled(s / old),
        // a light of size 0 grows from nothing: set its size itself
        None => {
            let mut l = light.clone();
            match &mut l {
                Light::Sphere { radius, .. } | Light::Disk { radius, .. } => *radius = s,
                Light::Rectangle { half_width, .. } => *half_width = s,
                Light::DistantDisk { angle_degrees, .. } => *angle_degrees = s.min(179.0),
                Light::Point { .. } | Light::Directional { .. } | Light::Segment { .. } | Light::Triangle { .. } => {}
            }
            l
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(size(&m), Some(1.0));
        let r = resized(&m, 2.0);
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
