//! One configuration measured, the one measuring step of `sshc sweep` and `sshc tune`
//! ([`run_config`]: compiled with its settings, bound to its scene, timed over repeated
//! frames, its visibility read), and the truth of a scene it is scored against
//! ([`SceneTruth`]).

use super::file::Settings;
use crate::metrics;
use crate::run::Bound;
use crate::session::{TruthOpts, positions_normals, report, rt, truth_at};
use sshc_runtime::gpu::{CameraOutput, Gpu};
use sshc_runtime::graph::cost;
use std::path::Path;

/// The truth of one scene as the sweep and the tuner score against it: visibility, its
/// largest standard error, which pixels face the light, the shadow on the ground
/// (`metrics::ground_set`; `None` where every object casts), and the camera's positions
/// and normals (what FLIP shades with).
#[derive(Clone)]
pub(crate) struct SceneTruth {
    pub visibility: Vec<f32>,
    pub se: f64,
    pub facing: Vec<bool>,
    pub ground: Option<Vec<bool>>,
    pub positions: Vec<glam::Vec3>,
    pub normals: Vec<glam::Vec3>,
}

impl SceneTruth {
    /// The truth at the pixels `ex` (bound to `scene`) sees, ray-traced with `opts` (or
    /// read from the cache they name); `quiet` runs the tracing with the progress bar
    /// hidden.
    pub(crate) fn at(
        ex: &Bound,
        scene: &crate::scene::Scene,
        opts: &TruthOpts,
        quiet: impl FnOnce(&dyn Fn() -> Result<crate::truth::Truth, String>) -> Result<crate::truth::Truth, String>,
    ) -> Result<SceneTruth, String> {
        let (p, n) = positions_normals(ex)?;
        let t = quiet(&|| truth_at(scene, &p, &n, opts).map(|(t, _)| t))?;
        let facing = metrics::facing_light(&p, &n, &scene.lights[0]).unwrap_or_default();
        let ground = metrics::ground_set(scene, &t.visibility, &p, &facing).map_err(|e| format!("error: {e}"))?;
        Ok(SceneTruth {
            se: t.max_std_error() as f64,
            visibility: t.visibility,
            facing,
            ground,
            positions: p,
            normals: n,
        })
    }

    /// `vis` against this truth: RMS facing and by region, FLIP, the shadow on the ground.
    /// `what` names the visibility in the refusal of a non-finite or out-of-range value.
    pub(crate) fn score(&self, what: &str, vis: &[f32], scene: &crate::scene::Scene) -> Result<metrics::Accuracy, String> {
        let m = |e: metrics::MetricsError| format!("error: {e}");
        metrics::check_visibility(what, vis, &self.facing).map_err(m)?;
        let mut acc = metrics::accuracy(vis, &self.visibility, &self.facing).map_err(m)?;
        acc.flip = Some(
            metrics::flip(
                vis,
                &self.visibility,
                &self.positions,
                &self.normals,
                &scene.lights[0],
                scene.camera_size(),
                &self.facing,
            )
            .map_err(m)?,
        );
        if let Some(g) = &self.ground {
            acc.ground = Some(metrics::error_stats(vis, &self.visibility, g).map_err(m)?);
        }
        Ok(acc)
    }
}

/// One configuration run on one scene, as the sweep and the tuner measure it.
pub(crate) struct Ran {
    pub ex: Bound,
    /// Median GPU ms per frame (none where the device has no timestamps).
    pub ms: Option<f64>,
    /// The fastest and the slowest of those frames.
    pub ms_range: Option<(f64, f64)>,
    /// Bytes of every texture the targets hold.
    pub peak: u64,
    pub fetches: f64,
    pub ops: f64,
    pub visibility: Vec<f32>,
}

/// Compiles `source` with the settings' params, precisions and schedules (specialised for
/// the scene's light where the technique admits it and no cascades are on), binds `scene`
/// (already [`Settings::apply`]'d), times `frames` frames and reads the visibility: the one
/// measuring step of `sshc sweep` and `sshc tune`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_config(
    gpu: &Gpu,
    path: &Path,
    source: &str,
    scene: &crate::scene::Scene,
    scene_path: &Path,
    s: &Settings,
    cascading: &crate::bind::Cascading,
    frames: usize,
) -> Result<Ran, String> {
    // the `cascades` axis over `--cascades` (the reference is timed with the latter)
    let cascading = crate::bind::Cascading {
        cascades: s.cascades.or(cascading.cascades),
        ..*cascading
    };
    // (generic under cascades: their views are not the scene's)
    let facts = crate::session::scene_facts(scene_path, scene).filter(|f| sshc::admits(source, f.light) && !cascading.on(scene));
    let compiled = compile_for(path, source, &s.set, &s.precision, &s.schedule, facts)?;
    let loaded = crate::run::Loaded::new(gpu, compiled.graph, compiled.shaders).map_err(rt)?;
    crate::bind::check_cascades(scene, &cascading)?;
    let (mut ex, _) = cascading.bind_or_scene(&loaded, scene, false)?;
    let edges = ex.scene.edge_counts().map_or(0, |c| u64::from(c.edges));
    let sizes = cost::Sizes {
        shadow: scene.shadow_map,
        camera: scene.camera_size(),
    };
    let (fetches, ops) = cost::work::total(ex.graph(), sizes, edges);
    let timing = time_frames(&mut ex, frames)?;
    let visibility = ex.inspect().read_camera(CameraOutput::Visibility).map_err(rt)?.channel(0);
    let peak = ex.inspect().memory().iter().map(|(_, b)| b).sum();
    Ok(Ran {
        ex,
        ms: timing.map(|t| t.median),
        ms_range: timing.map(|t| (t.min, t.max)),
        peak,
        fetches,
        ops,
        visibility,
    })
}

/// The per-frame GPU times (sum over passes) of `frames` frames: their median, fastest and
/// slowest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Timing {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Timing {
    /// The timing of `t` (none for no frame timed).
    pub(crate) fn of(mut t: Vec<f64>) -> Option<Timing> {
        t.sort_by(f64::total_cmp);
        Some(Timing {
            median: *t.get(t.len() / 2)?,
            min: *t.first()?,
            max: *t.last()?,
        })
    }
}

/// The per-frame GPU times over `frames` frames after a warm-up (none where the device has
/// no timestamps).
pub(super) fn time_frames(ex: &mut Bound, frames: usize) -> Result<Option<Timing>, String> {
    ex.run_frame().map_err(rt)?;
    let mut t = Vec::new();
    for _ in 0..frames.max(1) {
        let f = ex.run_frame().map_err(rt)?;
        let ms: Option<f64> = f.passes.iter().map(|(_, ms)| *ms).sum();
        if let Some(ms) = ms {
            t.push(ms);
        }
    }
    Ok(Timing::of(t))
}

pub(super) fn compile(
    path: &Path,
    source: &str,
    set: &[(String, String)],
    precision: &[(String, String)],
    schedule: &[(String, String)],
) -> Result<sshc::Compiled, String> {
    compile_for(path, source, set, precision, schedule, None)
}

/// [`compile`], specialised for `scene` where given.
fn compile_for(
    path: &Path,
    source: &str,
    set: &[(String, String)],
    precision: &[(String, String)],
    schedule: &[(String, String)],
    scene: Option<sshc::SceneFacts>,
) -> Result<sshc::Compiled, String> {
    let opts = sshc::CompileOptions {
        set: set.to_vec(),
        precision: precision.to_vec(),
        schedule: schedule.to_vec(),
        scene,
        ..Default::default()
    };
    sshc::compile_str(source, &opts).map_err(|d| {
        report(&d, path, source);
        format!("error: {} does not compile with {set:?} {precision:?} {schedule:?}", path.display())
    })
}
