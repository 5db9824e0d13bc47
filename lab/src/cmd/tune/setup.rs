//! What a tune is set up with: the techniques taking part (named, or the bundled ones),
//! each with its search space; each scene's training and held-out views; the budget.

use super::MAX_SOURCE_BYTES;
use crate::scene::{Camera, Scene};
use crate::session::{read_capped, report as report_diags};
use std::path::{Path, PathBuf};

/// The folder of the bundled techniques: beside the executable's repository (a build in
/// `target/`), or the source tree this binary was built from, or `./techniques`.
pub fn bundled_dir() -> PathBuf {
    let has = |d: &Path| d.join("hard.ron").is_file();
    if let Ok(exe) = std::env::current_exe() {
        for a in exe.ancestors().skip(1) {
            let d = a.join("techniques");
            if has(&d) {
                return d;
            }
        }
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    if has(&built) {
        return built;
    }
    PathBuf::from("techniques")
}

/// A technique file that takes part: its path, source and search space.
pub struct Entry {
    pub path: PathBuf,
    pub source: String,
    pub space: sshc::tune::Space,
    /// The file's name in tables and records.
    pub label: String,
}

pub(super) fn load_technique(path: &Path, overrides: &[(String, String)]) -> Result<Entry, String> {
    let source = read_capped(path, MAX_SOURCE_BYTES)?;
    // `--axis` entries apply to the techniques that have the axis
    let has = |name: &str| sshc::tune::space(&source).is_ok_and(|s| s.axes.iter().any(|a| a.name == name));
    let mine: Vec<(String, String)> = overrides.iter().filter(|(n, _)| has(n)).cloned().collect();
    let space = sshc::tune::space_with(&source, &mine).map_err(|e| match e {
        sshc::tune::SpaceError::Source(d) => {
            report_diags(&d, path, &source);
            format!("error: {} cannot be tuned: it does not parse", path.display())
        }
        sshc::tune::SpaceError::Override { text, diagnostics } => {
            report_diags(&diagnostics, Path::new("--axis"), &text);
            format!("error: `--axis` does not fit {}", path.display())
        }
    })?;
    // the technique as written must compile (every check of `sshc check`: an empty declared
    // range, a default outside it), so that the search starts from a valid point
    sshc::compile_str(&source, &Default::default()).map_err(|d| {
        report_diags(&d, path, &source);
        format!("error: {} does not compile: fix it before tuning it (`sshc check`)", path.display())
    })?;
    Ok(Entry {
        label: path
            .file_stem()
            .map_or_else(|| space.technique.clone(), |s| s.to_string_lossy().into_owned()),
        path: path.to_path_buf(),
        source,
        space,
    })
}

/// A scene the tuner measures on: its training views (the scene's own first) and held-out
/// views.
pub struct SceneViews {
    pub path: PathBuf,
    pub name: String,
    pub train: Vec<Scene>,
    pub holdout: Vec<Scene>,
}

/// The camera orbited by `degrees` about its up axis through its target.
fn orbited(c: &Camera, degrees: f32) -> Camera {
    let turn = |position: glam::Vec3, target: glam::Vec3, up: glam::Vec3| {
        let q = glam::Quat::from_axis_angle(up.normalize_or(glam::Vec3::Y), degrees.to_radians());
        target + q * (position - target)
    };
    let mut c = c.clone();
    match &mut c {
        Camera::Perspective { position, target, up, .. } | Camera::Orthographic { position, target, up, .. } => {
            *position = turn(*position, *target, *up);
        }
    }
    c
}

/// The views of one scene: the scene's own camera, then `train` and `holdout` cameras
/// orbited about its target at angles spread over [-40, 40] degrees (held-out ones
/// interleaved with the training ones), each with the light moved by up to `jitter`.
pub(super) fn scene_views(path: &Path, scene: &Scene, train: usize, holdout: usize, jitter: f32, seed: u64) -> Result<SceneViews, String> {
    let mut rng = crate::visibility::Rng::new(seed ^ 0x7475_6e65);
    let total = train + holdout;
    let (mut tr, mut ho) = (vec![scene.clone()], Vec::new());
    // holdout views take every other slot first, so that they sit between training views
    let mut hold_left = holdout;
    for j in 0..total {
        let deg = -40.0 + 80.0 * (j as f32 + 0.5) / total as f32;
        let mut s = scene.clone();
        s.set_camera(orbited(&scene.camera, deg))
            .map_err(|e| format!("error: {}: view at {deg:.0} degrees: {e}", path.display()))?;
        if jitter > 0.0 {
            let mut d = || (rng.next_f64() as f32 * 2.0 - 1.0) * jitter;
            let by = glam::Vec3::new(d(), d(), d());
            let moved = s.lights[0].translated(by);
            s.set_light(0, moved)
                .map_err(|e| format!("error: {}: jittered light: {e}", path.display()))?;
        }
        if hold_left > 0 && j % 2 == 1 {
            hold_left -= 1;
            ho.push(s);
        } else if tr.len() < train + 1 {
            tr.push(s);
        } else {
            ho.push(s);
        }
    }
    Ok(SceneViews {
        path: path.to_path_buf(),
        name: path.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned()),
        train: tr,
        holdout: ho,
    })
}

/// The budget as the search sees it, and in words.
pub struct Budget {
    /// (reference technique, factor) or none with `--budget-ms`.
    pub reference: Option<(Entry, f64)>,
    pub ms: Option<f64>,
    pub memory: Option<u64>,
}

impl Budget {
    pub fn time_limit(&self) -> f64 {
        self.ms.or(self.reference.as_ref().map(|r| r.1)).unwrap_or(f64::INFINITY)
    }

    pub fn words(&self) -> String {
        let mut w = match (&self.reference, self.ms) {
            (_, Some(ms)) => format!("{ms} GPU ms per frame"),
            (Some((r, f)), None) => format!("{f} x the GPU time of {} (timed beside each configuration)", r.label),
            (None, None) => "no time limit".into(),
        };
        if let Some(m) = self.memory {
            w.push_str(&format!(", {:.2} MiB of textures and buffers", m as f64 / (1 << 20) as f64));
        }
        w
    }

    /// The unit of the time figures: `ms` or `x REF`.
    pub fn unit(&self) -> String {
        match (&self.reference, self.ms) {
            (Some((r, _)), None) => format!("x {}", r.label),
            _ => "ms".into(),
        }
    }
}
