//! `sshc tune`: the most accurate configuration a budget allows, chosen on the user's own
//! scenes against the ray-traced truth (docs/tune.md).
//!
//! Every technique that admits the scenes' lights (or those named) competes over its
//! search space ([`sshc::tune::space`]: declared param ranges, precisions, schedules, the
//! shadow-map size, cascades for lights at infinity, as the file's `tune:` block narrows
//! them). [`search::search`] runs successive halving: every candidate is measured with a
//! cheap truth on the scene's own view, the best third of those inside the budget again
//! with more samples and every training view, and so on; then the neighbours of the best
//! along each axis. Each measurement is the sweep's ([`crate::cmd::sweep::run_config`],
//! [`crate::cmd::sweep::SceneTruth`]): one measuring step for both commands. Times are
//! budgeted against the reference timed beside each configuration, repeated at the final
//! rung, and a configuration whose repeated timings straddle the budget is marked.
//!
//! The output folder holds `tuned.ron` (the technique with the chosen values as its
//! defaults), `tune.md`, `tune.csv`, the Pareto charts with the chosen point marked, and
//! the error images of the chosen configuration and of the technique's defaults; with
//! `--ladder`, one technique file per budget and `tiers.ron`. Each measurement is appended
//! to `records.ron` as it is made, so that the same command run again after a kill
//! carries on (the search is deterministic given `--seed`).

pub mod report;
pub mod search;
pub mod slurm;

use crate::cmd::sweep::{Config, Ran, SceneTruth, duration, run_config, settings};
use crate::scene::{Camera, Scene};
use crate::session::{TruthOpts, load_scene, read_capped, report as report_diags, rt};
use search::{Candidate, Measured, Plan};
use sshc_runtime::gpu::Gpu;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The largest technique or scene file the tuner reads (bytes).
const MAX_SOURCE_BYTES: u64 = 4 << 20;
/// The largest `records.ron` a resumed run reads (bytes): about 100,000 records.
const MAX_RECORDS_BYTES: u64 = 64 << 20;

#[derive(clap::Args)]
pub struct TuneArgs {
    /// A scene to tune on (RON); repeatable: the error is the mean over the scenes, and the
    /// time budget must hold on each.
    #[arg(long = "scene", required = true)]
    pub scenes: Vec<PathBuf>,
    /// A technique that competes; repeatable. Default: every bundled technique whose light
    /// kinds admit every scene's light.
    #[arg(long = "technique")]
    pub techniques: Vec<PathBuf>,
    /// Output folder: tuned.ron, tune.md, tune.csv, charts, error images, records.ron.
    #[arg(short, long, default_value = "out/tune")]
    pub out: PathBuf,
    /// Budget: GPU milliseconds per frame on this device (median of the repeated timings).
    #[arg(long, value_name = "MS", conflicts_with = "budget_vs")]
    pub budget_ms: Option<f64>,
    /// Budget: at most F times the GPU time of technique REF, timed beside each configuration
    /// in the same run (default `hard.ron=3`; REF is a path, or a bundled technique's file name).
    #[arg(long, value_name = "REF.ron=F", value_parser = budget_vs)]
    pub budget_vs: Option<(PathBuf, f64)>,
    /// Budget: texture and buffer bytes, in MiB (exact, from the graph and the targets).
    #[arg(long, value_name = "MB")]
    pub memory_mb: Option<f64>,
    /// The error ranked by: `flip` (mean FLIP over the pixels facing the light), `facing`
    /// (RMS over them) or `penumbra` (RMS over their penumbra). The others are printed beside.
    #[arg(long, default_value = "flip", value_parser = ["flip", "facing", "penumbra"])]
    pub metric: String,
    /// Training views besides the scene's own camera: cameras orbited about its target.
    #[arg(long, default_value_t = 2)]
    pub views: usize,
    /// Held-out views, never used to choose: the chosen configuration is measured there
    /// at the end, and the difference is the generalisation gap.
    #[arg(long, default_value_t = 2)]
    pub holdout: usize,
    /// Move the light by up to this much (world units, each axis, seeded) in every view but
    /// the scene's own, so that the choice does not fit one light position.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub light_jitter: f32,
    /// Candidates drawn per technique (its defaults among them).
    #[arg(long, default_value_t = 18)]
    pub candidates: usize,
    /// Fidelities of the successive halving (the truth's samples quadruple from one to the
    /// next up to `--samples`; the first uses the scene's own view only).
    #[arg(long, default_value_t = 3)]
    pub rungs: usize,
    /// Keep one candidate in ETA after each rung.
    #[arg(long, default_value_t = 3)]
    pub eta: usize,
    /// Rounds of refinement around the best at the final fidelity, at most (it stops at
    /// the first round that finds nothing better).
    #[arg(long, default_value_t = 4)]
    pub refine: usize,
    /// Before the final rung, a configuration is dropped, and those of more work skipped,
    /// only when its one timing exceeds the time budget by this factor (the final rung's
    /// repeated timings decide by their median and mark their spread).
    #[arg(long, default_value_t = 1.25)]
    pub noise: f64,
    /// Interleaved timings of a configuration and the reference at the final rung (their
    /// spread marks configurations within the noise of the budget).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Frames timed per timing (the median).
    #[arg(long, default_value_t = 5)]
    pub frames: usize,
    /// Camera size for every scene and view, WIDTHxHEIGHT (default: each scene's own).
    #[arg(long, value_parser = crate::session::size)]
    pub size: Option<(u32, u32)>,
    /// Budgets as multiples of the reference (or, with --budget-ms, milliseconds): one
    /// configuration per budget, sharing measurements; writes tiers.ron and a technique
    /// file per tier.
    #[arg(long, value_delimiter = ',', value_name = "B1,B2,...")]
    pub ladder: Vec<f64>,
    /// Narrow or freeze an axis of every technique that has it, as a `tune:` entry would:
    /// `N=[3, 6, 9]`, `bias=(0.0, 0.01)`, `precision:z=Frozen`. Repeatable.
    #[arg(long = "axis", value_name = "NAME=CHOICE", value_parser = crate::session::pair)]
    pub axes: Vec<(String, String)>,
    /// Measure every combination of each axis's grid values (every choice, up to five values
    /// of a param) at the final fidelity instead of searching: the exhaustive grid a sweep
    /// would measure, to compare the search with (docs/tune.md). Implies one rung and no
    /// refinement.
    #[arg(long)]
    pub grid: bool,
    /// Measure everything again: forget the records of an earlier run in the folder.
    #[arg(long)]
    pub fresh: bool,
    /// Measure one slice of each rung, `i/n`, beside n - 1 more processes running the same
    /// command with the same `-o` (a cluster's shared folder): each measures its part of a
    /// rung, waits for the others' (their records in the folder), and goes on; shard 0
    /// writes the outputs. The choice is the unsharded run's.
    #[arg(long, value_parser = crate::cmd::sweep::shard, default_value = "0/1")]
    pub shard: (usize, usize),
    /// With --shard: seconds to wait for another shard's part of a rung; past it this shard
    /// measures that part itself (a shard lost does not stop the tune).
    #[arg(long, value_name = "SECONDS", default_value_t = 3600.0)]
    pub wait: f64,
    #[command(flatten)]
    pub slurm: crate::cmd::sweep::slurm::SlurmArgs,
    /// The truth's options (`--samples` is the final rung's; `--seed` also seeds the search).
    #[command(flatten)]
    pub truth: TruthOpts,
}

fn budget_vs(s: &str) -> Result<(PathBuf, f64), String> {
    let (p, f) = s.rsplit_once('=').ok_or_else(|| format!("expected REF.ron=F, found `{s}`"))?;
    let f: f64 = f.trim().parse().map_err(|_| format!("`{f}` is not a number"))?;
    if !(f.is_finite() && f > 0.0) {
        return Err(format!("the factor {f} must be a finite number above 0"));
    }
    Ok((PathBuf::from(p), f))
}

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

fn load_technique(path: &Path, overrides: &[(String, String)]) -> Result<Entry, String> {
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
fn scene_views(path: &Path, scene: &Scene, train: usize, holdout: usize, jitter: f32, seed: u64) -> Result<SceneViews, String> {
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

/// The mean figures of one configuration over the scenes and views of a fidelity (0..255
/// units but FLIP, 0..1).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Detail {
    pub flip: f64,
    pub rms_facing: f64,
    pub rms_penumbra: f64,
    /// Signed means and RMS by region (`metrics::regions`).
    pub lit_mean: f64,
    pub lit_rms: f64,
    pub penumbra_mean: f64,
    pub umbra_mean: f64,
    pub umbra_rms: f64,
    /// Median GPU ms per frame (the largest over the scenes).
    pub ms: f64,
    pub fetches: f64,
    pub ops: f64,
    pub samples: u32,
    pub views: usize,
}

/// One line of `records.ron`: a configuration measured at a rung, or why it was not.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Record {
    technique: String,
    config: String,
    rung: usize,
    pub(crate) result: Result<(Measured, Detail), String>,
}

impl Record {
    /// Refuses records a run could not have written: non-finite or negative figures.
    fn check(&self) -> Result<(), String> {
        if let Ok((m, d)) = &self.result {
            let finite = [m.error, d.flip, d.rms_facing, d.rms_penumbra, d.ms]
                .iter()
                .chain(&m.times)
                .all(|x| x.is_finite() && *x >= 0.0);
            if !finite || m.times.is_empty() {
                return Err(format!(
                    "the record of {} {} at rung {} holds a figure that is not a finite number >= 0",
                    self.technique, self.config, self.rung
                ));
            }
        }
        Ok(())
    }
}

const RECORDS: &str = "records.ron";
const IDENTITY: &str = "tune.id";

/// The records file of shard `(i, n)`: `records.ron` unsharded, else `records-I-of-N.ron`.
fn records_name((i, n): (usize, usize)) -> String {
    if n <= 1 {
        RECORDS.to_string()
    } else {
        format!("records-{i}-of-{n}.ron")
    }
}

/// The records in one file. A last line that does not parse is a record being written (by
/// another shard) or cut short by a kill: left out, and reported as `true`. A line before
/// it that does not parse, or a record with a figure a run cannot write, is refused with
/// its line.
fn read_records(path: &Path) -> Result<(Vec<Record>, bool), String> {
    let text = read_capped(path, MAX_RECORDS_BYTES)?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        match ron::from_str::<Record>(line) {
            Ok(r) => {
                r.check()
                    .map_err(|e| format!("error: {}:{}: {e}; run again with --fresh", path.display(), i + 1))?;
                out.push(r);
            }
            Err(_) if i + 1 == lines.len() => return Ok((out, true)),
            Err(e) => {
                return Err(format!(
                    "error: {}:{}: not a record ({}); run again with --fresh",
                    path.display(),
                    i + 1,
                    e.code
                ));
            }
        }
    }
    Ok((out, false))
}

/// Every shard's records files in `out` (`records.ron`, `records-I-of-N.ron`).
fn records_files(out: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(out)
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("records") && n.ends_with(".ron"))
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// The records of an earlier run of the same tune in `out`, every shard's, by (technique,
/// config, rung): none where the folder is new, `--fresh` is given, or the run differs (its
/// identity, the hash of its inputs and options, says so). Starting afresh, a shard
/// forgets its own records only.
fn resume(out: &Path, identity: &str, fresh: bool, shard: (usize, usize)) -> Result<HashMap<(String, String, usize), Record>, String> {
    let id_path = out.join(IDENTITY);
    let mine = out.join(records_name(shard));
    let old = read_capped(&id_path, 4096).ok();
    let mut found = HashMap::new();
    if !fresh && old.as_deref() == Some(identity) {
        for path in records_files(out) {
            let (records, cut) = read_records(&path)?;
            if cut && path == mine {
                // cut short by a kill: dropped, and the file rewritten without it so that
                // the next record starts a line of its own
                eprintln!("tune: dropped the half-written last record of a stopped run");
                let kept: Result<Vec<String>, String> = records
                    .iter()
                    .map(|r| ron::to_string(r).map_err(|e| format!("error: a record: {e}")))
                    .collect();
                let kept: String = kept?.iter().map(|l| format!("{l}\n")).collect();
                crate::cmd::tune::report::write_new(&mine, &kept)?;
            }
            for r in records {
                found.insert((r.technique.clone(), r.config.clone(), r.rung), r);
            }
        }
        if !found.is_empty() {
            eprintln!(
                "tune: resuming in {}: {} measurements of an earlier run",
                out.display(),
                found.len()
            );
        }
    } else {
        if old.is_some() && !fresh {
            eprintln!("tune: {} holds another tune's records: starting afresh", out.display());
        }
        match std::fs::remove_file(&mine) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(format!("error: {}: {e}", mine.display())),
            _ => {}
        }
        crate::cmd::tune::report::write_new(&id_path, identity)?;
    }
    Ok(found)
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

/// A measured configuration's (technique, cost class, fetches, operations, fastest time
/// figure).
type Rate = (usize, String, f64, f64, f64);
/// A configuration's (fetches, operations, shadow-map bytes) per frame, from its graph.
type Work = (f64, f64, f64);

/// Shared state of a tune's measurements.
pub(crate) struct Tuner<'a> {
    pub gpu: &'a Gpu,
    pub a: &'a TuneArgs,
    pub entries: &'a [Entry],
    pub scenes: &'a [SceneViews],
    pub budget: &'a Budget,
    /// Truths by (scene, view, holdout, samples).
    truths: RefCell<HashMap<(usize, usize, bool, u32), SceneTruth>>,
    /// Measurements by (technique, config, rung): those of this run and those resumed.
    pub done: RefCell<HashMap<(String, String, usize), Record>>,
    log: RefCell<Option<std::fs::File>>,
    /// (technique, cost class, fetches, operations, fastest time figure) of every measured
    /// configuration: the fastest rates of fetches and operations a technique's cost class
    /// reached on this device, from which [`Tuner::skip`] bounds an unmeasured one's time.
    rates: RefCell<Vec<Rate>>,
    /// Rates measured since the last batch: they join `rates` at the next, so that no
    /// measurement in a batch decides a skip in the same batch (shards agree on skips).
    pending: RefCell<Vec<Rate>>,
    /// Fetches, operations and shadow-map bytes per frame of each candidate's graph (the
    /// compiler's counts at the first scene's sizes), by technique and configuration.
    work: RefCell<HashMap<(usize, String), Option<Work>>>,
    pub started: Instant,
    pub measured_now: RefCell<usize>,
}

impl Tuner<'_> {
    /// The truth's samples at `rung`: `--samples` at the last, a quarter of that at each
    /// rung before (at least 16).
    pub fn samples(&self, rung: usize) -> u32 {
        let down = (self.a.rungs.max(1) - 1 - rung.min(self.a.rungs.max(1) - 1)) as u32;
        (self.a.truth.samples >> (2 * down).min(30)).max(16)
    }

    pub(crate) fn settings_of(&self, c: &Candidate) -> Result<crate::cmd::sweep::Settings, String> {
        let mut s = settings(&Config {
            scene: 0,
            technique: c.technique,
            label: String::new(),
            values: c.values.clone(),
        })?;
        // a technique that names its map size (a tuned file) runs at it
        if s.shadow_map.is_none() {
            s.shadow_map = self.entries.get(c.technique).and_then(|e| e.space.shadow_map);
        }
        Ok(s)
    }

    fn truth(&self, scene: usize, view: usize, holdout: bool, samples: u32, ran: &Ran, s: &Scene) -> Result<SceneTruth, String> {
        let key = (scene, view, holdout, samples);
        if let Some(t) = self.truths.borrow().get(&key) {
            return Ok(t.clone());
        }
        let opts = TruthOpts {
            samples,
            ..self.a.truth.clone()
        };
        let t = SceneTruth::at(&ran.ex, s, &opts, |f| f())?;
        self.truths.borrow_mut().insert(key, t.clone());
        Ok(t)
    }

    fn metric(&self, acc: &crate::metrics::Accuracy) -> f64 {
        match self.a.metric.as_str() {
            "facing" => acc.facing.rms,
            "penumbra" => acc.penumbra.rms,
            _ => acc.flip.unwrap_or(f64::NAN),
        }
    }

    /// One configuration on the views given (per scene: training views up to `views`, or
    /// the held-out ones), timed `repeats` times on each scene's own view beside the
    /// reference: its error, timings and bytes, and the figures in detail.
    pub fn measure_on(
        &self,
        c: &Candidate,
        views: usize,
        holdout: bool,
        samples: u32,
        repeats: usize,
    ) -> Result<(Measured, Detail), String> {
        let e = &self.entries[c.technique];
        let s = self.settings_of(c)?;
        let mut errors = Vec::new();
        let mut accs: Vec<crate::metrics::Accuracy> = Vec::new();
        // per repeat, the largest time figure over the scenes
        let mut times = vec![0.0f64; repeats.max(1)];
        let (mut bytes, mut ms, mut fetches, mut ops) = (0u64, 0.0f64, 0.0f64, 0.0f64);
        let mut nviews = 0;
        for (si, sv) in self.scenes.iter().enumerate() {
            let list: Vec<&Scene> = if holdout {
                sv.holdout.iter().collect()
            } else {
                sv.train.iter().take(views.max(1)).collect()
            };
            for (vi, scene) in list.into_iter().enumerate() {
                let mut scene = scene.clone();
                s.apply(&mut scene)?;
                let timed = vi == 0 && !holdout;
                let frames = if timed { self.a.frames } else { 1 };
                let mut ran = run_config(self.gpu, &e.path, &e.source, &scene, &sv.path, &s, &Default::default(), frames)?;
                if timed {
                    let mut mss = Vec::new();
                    for (k, t) in times.iter_mut().enumerate() {
                        if k > 0 {
                            ran = run_config(self.gpu, &e.path, &e.source, &scene, &sv.path, &s, &Default::default(), frames)?;
                        }
                        let ms_c = ran
                            .ms
                            .ok_or("error: the device has no timestamp queries: a time budget cannot be measured")?;
                        mss.push(ms_c);
                        let figure = match &self.budget.reference {
                            Some((r, _)) if self.budget.ms.is_none() => {
                                // the reference at its own defaults on the scene as written
                                let rs = &self.scenes[si].train[0];
                                let reference = run_config(
                                    self.gpu,
                                    &r.path,
                                    &r.source,
                                    rs,
                                    &sv.path,
                                    &self.settings_of(&Candidate {
                                        technique: 0,
                                        values: vec![],
                                    })?,
                                    &Default::default(),
                                    self.a.frames,
                                )?;
                                let ms_r = reference.ms.ok_or("error: the device has no timestamp queries")?;
                                ms_c / ms_r.max(1e-9)
                            }
                            _ => ms_c,
                        };
                        *t = t.max(figure);
                    }
                    ms = ms.max(search::median(&mss));
                    bytes = bytes.max(ran.peak);
                    fetches = fetches.max(ran.fetches);
                    ops = ops.max(ran.ops);
                }
                let truth = self.truth(si, vi, holdout, samples, &ran, &scene)?;
                let acc = truth.score(&format!("the visibility of {} {}", e.label, c.describe()), &ran.visibility, &scene)?;
                errors.push(self.metric(&acc));
                accs.push(acc);
                nviews += 1;
            }
        }
        let n = accs.len().max(1) as f64;
        let mean = |f: &dyn Fn(&crate::metrics::Accuracy) -> f64| accs.iter().map(f).sum::<f64>() / n;
        let detail = Detail {
            flip: mean(&|a| a.flip.unwrap_or(f64::NAN)),
            rms_facing: mean(&|a| a.facing.rms),
            rms_penumbra: mean(&|a| a.penumbra.rms),
            lit_mean: mean(&|a| a.lit.mean),
            lit_rms: mean(&|a| a.lit.rms),
            penumbra_mean: mean(&|a| a.penumbra.mean),
            umbra_mean: mean(&|a| a.umbra.mean),
            umbra_rms: mean(&|a| a.umbra.rms),
            ms,
            fetches,
            ops,
            samples,
            views: nviews,
        };
        let m = Measured {
            error: errors.iter().sum::<f64>() / n,
            times: if holdout { vec![] } else { times },
            bytes,
        };
        Ok((m, detail))
    }

    /// The search's measuring step at `rung`: memoised (resumed records included), logged.
    pub fn measure(&self, c: &Candidate, rung: usize) -> Result<Measured, String> {
        let e = &self.entries[c.technique];
        let key = (e.label.clone(), c.describe(), rung);
        let known = self.done.borrow().get(&key).map(|r| r.result.clone());
        if let Some(result) = known {
            // a resumed (or shared) measurement counts towards the rates as it did when it
            // was made, so that a resumed search skips what the first one skipped
            self.note_rate(c, &result);
            return result.map(|(m, _)| m);
        }
        let last = rung + 1 == self.a.rungs.max(1);
        // the cheap rungs' first on the scene's own view alone; the final one on every
        // training view (a single-rung search, the grid, is all final)
        let views = if rung == 0 && !last { 1 } else { self.a.views + 1 };
        let repeats = if last { self.a.repeats.max(1) } else { 1 };
        let result = self.measure_on(c, views, false, self.samples(rung), repeats);
        self.note_rate(c, &result);
        let record = Record {
            technique: e.label.clone(),
            config: c.describe(),
            rung,
            result: result.clone(),
        };
        self.append(&record)?;
        self.done.borrow_mut().insert(key, record);
        *self.measured_now.borrow_mut() += 1;
        result.map(|(m, _)| m)
    }

    /// Adds a measured configuration's rates of fetches and operations (per unit of its
    /// fastest time figure) to those [`Tuner::skip`] bounds times with.
    fn note_rate(&self, c: &Candidate, result: &Result<(Measured, Detail), String>) {
        if let Ok((m, _)) = result
            && let Some((f, o, _)) = self.work_of(c)
        {
            let fastest = m.times.iter().copied().fold(f64::INFINITY, f64::min);
            if fastest.is_finite() && fastest > 0.0 {
                self.pending.borrow_mut().push((c.technique, kinds(c), f, o, fastest));
            }
        }
    }

    /// Before a rung or a round of refinement: the rates measured since the last batch join
    /// those skips are decided on; with `--shard i/n`, this shard measures its part of the
    /// configurations the batch will measure (every n-th, from the i-th, of those not
    /// skipped nor measured yet) and waits until the other shards' records hold the rest,
    /// measuring here what `--wait` seconds did not bring.
    pub fn batch(&self, cands: &[Candidate], rung: usize, time_limit: f64) {
        let pending: Vec<Rate> = self.pending.borrow_mut().drain(..).collect();
        self.rates.borrow_mut().extend(pending);
        let (i, n) = self.a.shard;
        if n <= 1 {
            return;
        }
        let key = |c: &Candidate| (self.entries[c.technique].label.clone(), c.describe(), rung);
        // the parts are dealt over the whole batch, not over what is left of it: a shard
        // that reaches the batch later finds some of the others' part done already, and
        // dealing what was left gave it other parts than theirs (both then waited `--wait`
        // seconds for configurations neither would measure)
        let batch: Vec<&Candidate> = cands.iter().filter(|c| self.skip(c, time_limit).is_none()).collect();
        for c in batch.iter().skip(i).step_by(n) {
            if self.done.borrow().contains_key(&key(c)) {
                continue;
            }
            // a failure is a record too: every shard reads it
            let _ = self.measure(c, rung);
        }
        let todo: Vec<&Candidate> = batch.into_iter().filter(|c| !self.done.borrow().contains_key(&key(c))).collect();
        let start = Instant::now();
        let mut said = false;
        loop {
            for path in records_files(&self.a.out) {
                if path == self.a.out.join(records_name(self.a.shard)) {
                    continue;
                }
                match read_records(&path) {
                    Ok((records, _)) => {
                        let mut done = self.done.borrow_mut();
                        for r in records {
                            done.entry((r.technique.clone(), r.config.clone(), r.rung)).or_insert(r);
                        }
                    }
                    Err(e) => eprintln!("tune {i}/{n}: {}", e.trim_start_matches("error: ")),
                }
            }
            let missing = todo.iter().filter(|c| !self.done.borrow().contains_key(&key(c))).count();
            if missing == 0 {
                return;
            }
            if start.elapsed().as_secs_f64() > self.a.wait {
                eprintln!(
                    "tune {i}/{n}: {missing} configurations of rung {} not measured by the other shards after {} s: measuring them here",
                    rung + 1,
                    self.a.wait
                );
                return;
            }
            if !said {
                eprintln!(
                    "tune {i}/{n}: waiting for the other shards' {missing} configurations of rung {}",
                    rung + 1
                );
                said = true;
            }
            std::thread::sleep(std::time::Duration::from_millis(250));
        }
    }

    fn append(&self, r: &Record) -> Result<(), String> {
        use std::io::Write as _;
        let path = self.a.out.join(records_name(self.a.shard));
        let mut log = self.log.borrow_mut();
        if log.is_none() {
            *log = Some(crate::session::append_to(&path)?);
        }
        let line = ron::to_string(r).map_err(|e| format!("error: a record: {e}"))?;
        if let Some(f) = log.as_mut() {
            writeln!(f, "{line}").map_err(|e| format!("error: {}: {e}", path.display()))?;
        }
        Ok(())
    }

    /// The fetches, operations and shadow-map bytes per frame of `c`'s graph, from the
    /// compiler's counts through the cost model (`sshc_graph::cost`: `work::total`,
    /// `Cost::shadow_map_bytes`) at the first scene's camera and `c`'s map size: known
    /// before running it. None where it does not compile.
    fn work_of(&self, c: &Candidate) -> Option<Work> {
        let key = (c.technique, c.describe());
        if let Some(w) = self.work.borrow().get(&key) {
            return *w;
        }
        let e = &self.entries[c.technique];
        let w = self.settings_of(c).ok().and_then(|s| {
            let opts = sshc::CompileOptions {
                set: s.set.clone(),
                precision: s.precision.clone(),
                schedule: s.schedule.clone(),
                ..Default::default()
            };
            let compiled = sshc::compile_str(&e.source, &opts).ok()?;
            let scene = &self.scenes[0].train[0];
            let n = s.shadow_map.unwrap_or(scene.shadow_map);
            let bytes = compiled.cost.shadow_map_bytes(n);
            let sizes = sshc_runtime::graph::cost::Sizes {
                shadow: n,
                camera: scene.camera_size(),
            };
            let (f, o) = sshc_runtime::graph::cost::work::total(&compiled.graph, sizes, 0);
            Some((f, o, bytes))
        });
        self.work.borrow_mut().insert(key, w);
        w
    }

    /// Why `c` cannot meet the budget, known before running it: the bytes of its
    /// shadow-map textures (from its graph, exact) over the memory budget, or a time that
    /// must exceed the budget beyond its noise: its fetches (and operations) per frame at
    /// the fastest rate of fetches (operations) any measured configuration of the same
    /// technique and cost class (precisions, schedules, cascades) reached. That bound holds
    /// as long as the device never runs the technique's work faster than it was seen to;
    /// the grid and configurations already measured inside the budget are never skipped.
    pub fn skip(&self, c: &Candidate, time_limit: f64) -> Option<String> {
        let e = &self.entries[c.technique];
        let (fetches, ops, map_bytes) = self.work_of(c)?;
        if let Some(limit) = self.budget.memory
            && map_bytes > limit as f64
        {
            return Some(format!(
                "its shadow-map textures alone take {:.2} MiB (from the graph), over the {:.2} MiB budget",
                map_bytes / (1 << 20) as f64,
                limit as f64 / (1 << 20) as f64
            ));
        }
        // a measurement outranks the model: a configuration measured inside the budget at
        // any fidelity is measured again
        let within = self.done.borrow().values().any(|r| {
            r.technique == e.label
                && r.config == c.describe()
                && r.result.as_ref().is_ok_and(|(m, _)| m.times.iter().any(|&t| t <= time_limit))
        });
        if within || self.a.grid {
            // the grid measures every configuration its memory allows, as a sweep would
            return None;
        }
        let k = kinds(c);
        let rates = self.rates.borrow();
        let mine: Vec<&Rate> = rates.iter().filter(|r| r.0 == c.technique && r.1 == k).collect();
        if mine.is_empty() {
            return None;
        }
        let fastest_fetches = mine.iter().map(|r| r.2 / r.4).fold(0.0, f64::max);
        let fastest_ops = mine.iter().map(|r| r.3 / r.4).fold(0.0, f64::max);
        let bound = [(fetches, fastest_fetches), (ops, fastest_ops)]
            .iter()
            .filter(|(_, rate)| *rate > 0.0)
            .map(|(w, rate)| w / rate)
            .fold(0.0, f64::max);
        let limit = time_limit * self.a.noise;
        (bound > limit).then(|| {
            format!(
                "{fetches:.3e} fetches and {ops:.3e} operations per frame need at least {bound:.3} {} at the fastest rates measured for its technique and cost class, over the budget beyond its noise ({limit:.3})",
                self.budget.unit()
            )
        })
    }
}

/// The values of a candidate the work model (fetches and operations per frame of its
/// graph) does not see: precisions and schedules change the cost of a fetch, cascades
/// the number of views.
fn kinds(c: &Candidate) -> String {
    c.values
        .iter()
        .filter(|(k, _)| k.starts_with("precision:") || k.starts_with("schedule:") || k == "cascades")
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(" ")
}

pub fn tune(mut a: TuneArgs) -> Result<(), String> {
    if a.grid {
        a.rungs = 1;
        a.refine = 0;
    }
    if a.rungs == 0 || a.rungs > 6 {
        return Err(format!("error: `--rungs {}`: give 1 to 6 fidelities", a.rungs));
    }
    if a.candidates == 0 || a.candidates > 10_000 {
        return Err(format!("error: `--candidates {}`: give 1 to 10000 per technique", a.candidates));
    }
    if !(a.wait.is_finite() && a.wait >= 0.0) {
        return Err(format!("error: `--wait {}`: need a finite number of seconds >= 0", a.wait));
    }
    if !(a.noise.is_finite() && (1.0..=10.0).contains(&a.noise)) {
        return Err(format!("error: `--noise {}`: give a factor from 1 to 10", a.noise));
    }
    if a.views > 64 || a.holdout > 64 {
        return Err("error: `--views` and `--holdout` take at most 64 views each".into());
    }
    if !(a.light_jitter.is_finite() && a.light_jitter >= 0.0) {
        return Err(format!("error: `--light-jitter {}`: need a finite distance >= 0", a.light_jitter));
    }
    if let Some(ms) = a.budget_ms
        && !(ms.is_finite() && ms > 0.0)
    {
        return Err(format!("error: `--budget-ms {ms}`: need a finite number of milliseconds above 0"));
    }
    let memory = match a.memory_mb {
        Some(m) if m.is_finite() && m > 0.0 && m < 1e9 => Some((m * (1 << 20) as f64) as u64),
        Some(m) => return Err(format!("error: `--memory-mb {m}`: need a finite number of MiB above 0")),
        None => None,
    };
    if a.ladder.iter().any(|b| !(b.is_finite() && *b > 0.0)) || a.ladder.len() > 8 {
        return Err("error: `--ladder`: give up to 8 budgets, each a finite number above 0".into());
    }
    // the scenes and their views
    let mut scenes = Vec::new();
    for p in &a.scenes {
        let mut scene = load_scene(p, a.size, None)?;
        if scene.lights.len() > 1 {
            eprintln!("note: {}: tuning for its first light of {}", p.display(), scene.lights.len());
            scene = crate::session::single_light(&scene, 0);
        }
        scenes.push(scene_views(p, &scene, a.views, a.holdout, a.light_jitter, a.truth.seed)?);
    }
    let kinds_of: Vec<sshc_graph::LightKind> = scenes.iter().map(|s| s.train[0].lights[0].kind()).collect();
    let distant = scenes.iter().all(|s| s.train[0].lights[0].is_distant());
    // the techniques
    let bundled = bundled_dir();
    let named = !a.techniques.is_empty();
    let paths: Vec<PathBuf> = if named {
        a.techniques.clone()
    } else {
        let mut v: Vec<PathBuf> = std::fs::read_dir(&bundled)
            .map_err(|e| format!("error: the bundled techniques at {}: {e}", bundled.display()))?
            .filter_map(|d| d.ok().map(|d| d.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "ron") && p.is_file())
            .collect();
        v.sort();
        v
    };
    let mut entries = Vec::new();
    let mut left_out = Vec::new();
    for (name, _) in &a.axes {
        if !paths.iter().any(|p| {
            read_capped(p, MAX_SOURCE_BYTES)
                .ok()
                .and_then(|s| sshc::tune::space(&s).ok())
                .is_some_and(|s| s.axes.iter().any(|x| x.name == *name))
        }) {
            return Err(format!(
                "error: `--axis {name}=...`: no technique taking part has the axis `{name}`"
            ));
        }
    }
    for p in &paths {
        let e = load_technique(p, &a.axes)?;
        let refused: Vec<usize> = (0..scenes.len()).filter(|&i| !sshc::admits(&e.source, kinds_of[i])).collect();
        if let Some(&i) = refused.first() {
            if named {
                return Err(format!(
                    "error: {} does not admit the {} light of {} (its `light:` list names the kinds it is made for); name a technique that does, or another scene",
                    p.display(),
                    kinds_of[i].name(),
                    scenes[i].path.display()
                ));
            }
            left_out.push(e.label.clone());
            continue;
        }
        entries.push(e);
    }
    if !left_out.is_empty() {
        eprintln!(
            "tune: left out (their `light:` lists do not admit the scenes' lights): {}",
            left_out.join(", ")
        );
    }
    if entries.is_empty() {
        return Err("error: no technique admits the scenes' lights".into());
    }
    // the budget
    let reference = if a.budget_ms.is_some() {
        None
    } else {
        let (p, f) = a.budget_vs.clone().unwrap_or((PathBuf::from("hard.ron"), 3.0));
        let p = if p.is_file() { p } else { bundled.join(&p) };
        // (timed compiled generic where its `light:` list does not name a scene's light,
        // as the sweep times its reference)
        let r = load_technique(&p, &[])?;
        Some((r, f))
    };
    let budget = Budget {
        reference,
        ms: a.budget_ms,
        memory,
    };
    // the search space; the map size's default is the technique's own, else the first scene's
    for e in &mut entries {
        let own = e.space.shadow_map.unwrap_or(scenes[0].train[0].shadow_map).to_string();
        for axis in e.space.axes.iter_mut().filter(|a| a.name == "shadow_map") {
            axis.default = Some(own.clone());
        }
    }
    let axes: Vec<Vec<&sshc::tune::Axis>> = entries.iter().map(|e| search::varying(&e.space, distant)).collect();
    let mut candidates = Vec::new();
    for (t, ax) in axes.iter().enumerate() {
        if a.grid {
            candidates.extend(search::grid(t, ax));
        } else {
            candidates.extend(search::draw_candidates(t, ax, a.candidates, a.truth.seed));
        }
    }
    const MAX_GRID: usize = 20_000;
    if candidates.len() > MAX_GRID {
        return Err(format!(
            "error: --grid: {} configurations, above the limit of {MAX_GRID}; narrow the axes with a `tune:` block",
            candidates.len()
        ));
    }
    // the run's identity: what it measures and how
    let mut id = format!(
        "format=1 noise={} axes={:?} grid={} metric={} views={} holdout={} jitter={} candidates={} rungs={} eta={} refine={} repeats={} frames={} size={:?} samples={} runs={} seed={} budget={}",
        a.noise,
        a.axes,
        a.grid,
        a.metric,
        a.views,
        a.holdout,
        a.light_jitter,
        a.candidates,
        a.rungs,
        a.eta,
        a.refine,
        a.repeats,
        a.frames,
        a.size,
        a.truth.samples,
        a.truth.runs,
        a.truth.seed,
        budget.words()
    );
    for e in &entries {
        id.push_str(&format!(" {}:{:016x}", e.label, xxhash_rust::xxh3::xxh3_64(e.source.as_bytes())));
    }
    for s in &a.scenes {
        let text = read_capped(s, MAX_SOURCE_BYTES)?;
        id.push_str(&format!(" {}:{:016x}", s.display(), xxhash_rust::xxh3::xxh3_64(text.as_bytes())));
    }
    if a.slurm.slurm {
        return slurm::write(&a);
    }
    report::create_out(&a.out)?;
    let done = resume(&a.out, &id, a.fresh, a.shard)?;
    let gpu = Gpu::new().map_err(rt)?;
    eprintln!(
        "tune: {} techniques ({}), {} candidates, {} rungs, budget {}, on {}",
        entries.len(),
        entries.iter().map(|e| e.label.as_str()).collect::<Vec<_>>().join(", "),
        candidates.len(),
        a.rungs,
        budget.words(),
        gpu.describe()
    );
    let tuner = Tuner {
        gpu: &gpu,
        a: &a,
        entries: &entries,
        scenes: &scenes,
        budget: &budget,
        truths: RefCell::new(HashMap::new()),
        done: RefCell::new(done),
        log: RefCell::new(None),
        rates: RefCell::new(Vec::new()),
        pending: RefCell::new(Vec::new()),
        work: RefCell::new(HashMap::new()),
        started: Instant::now(),
        measured_now: RefCell::new(0),
    };
    // the planned measurements: every candidate, a third of them, ..., then refinement
    let mut planned = 0usize;
    let mut n = candidates.len();
    for _ in 0..a.rungs {
        planned += n;
        n = n.div_ceil(a.eta.max(2));
    }
    // each refinement round tries about two neighbours per axis of the best
    planned += a.refine * 2 * axes.iter().map(Vec::len).max().unwrap_or(0);
    let ladder: Vec<f64> = if a.ladder.is_empty() {
        vec![budget.time_limit()]
    } else {
        a.ladder.clone()
    };
    let mut tiers = Vec::new();
    for (li, limit) in ladder.iter().enumerate() {
        let plan = Plan {
            rungs: a.rungs,
            eta: a.eta,
            time_limit: *limit,
            memory_limit: memory,
            refine: a.refine,
            noise: a.noise,
        };
        let count = RefCell::new(0usize);
        let found = search::search(
            &plan,
            candidates.clone(),
            &axes,
            |c| tuner.skip(c, *limit),
            |c, rung| {
                *count.borrow_mut() += 1;
                tuner.measure(c, rung)
            },
            |cands, rung| tuner.batch(cands, rung, *limit),
            |stage, best| {
                let done = *count.borrow();
                let ran = *tuner.measured_now.borrow();
                let spent = tuner.started.elapsed().as_secs_f64();
                let left = planned.saturating_sub(done);
                let eta = if ran > 0 { spent / ran as f64 * left as f64 } else { 0.0 };
                let best = best.map_or("none inside the budget yet".to_string(), |(c, m)| {
                    format!(
                        "{} {} error {:.4} time {:.3} {}",
                        entries[c.technique].label,
                        c.describe(),
                        m.error,
                        search::median(&m.times),
                        budget.unit()
                    )
                });
                let tier = if ladder.len() > 1 {
                    format!("tier {}/{}, ", li + 1, ladder.len())
                } else {
                    String::new()
                };
                eprintln!(
                    "tune: {tier}{stage}: {done} of about {planned} measured, {} so far, about {} left; best: {best}",
                    duration(spent),
                    duration(eta)
                );
            },
        );
        tiers.push((*limit, plan, found));
    }
    if a.shard.0 != 0 {
        eprintln!(
            "tune {}/{}: done ({} measured here); shard 0 writes the outputs",
            a.shard.0,
            a.shard.1,
            tuner.measured_now.borrow()
        );
        return Ok(());
    }
    report::write(&tuner, &tiers)
}
