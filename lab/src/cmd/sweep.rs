//! `sshc sweep <sweep.ron>`: techniques x their own parameter axes x scenes, each
//! configuration rendered (axes: params by name, `shadow_map`, `light_scale`,
//! `precision:NAMES` and `schedule:PASS` or `schedule:*`, as the command line's
//! `--precision` and `--schedule`), timed (median of repeated frames, as a ratio to a reference
//! technique timed in the same run) and compared with the cached ground truth; a CSV, a
//! Markdown table and Pareto charts (error against time, error against memory:
//! [`report`]).
//!
//! `--shard i/n` runs every n-th configuration starting at i; every shard times the
//! reference technique on each of its scenes, so time ratios from separate shards (run on
//! separate machines by any batch scheduler) stay comparable. Every run, sharded or not,
//! keeps its folder resumable ([`shard`]): each configuration's row is written as it
//! finishes, and the same command run again carries on from there. `sshc sweep merge`
//! ([`merge`]) joins the shard folders into what an unsharded run writes; `--slurm`
//! ([`slurm`]) writes the job scripts that run the shards as a Slurm array and then the
//! merge (docs/cluster.md).

pub mod chart;
pub mod merge;
pub mod report;
pub mod shard;
pub mod slurm;

use crate::cmd::sweep::report::{Outputs, PixelSet, Row, split_entry, stem};
use crate::cmd::sweep::shard::{Done, Log, Manifest, Record};
use crate::metrics;
use crate::run::Bound;
use crate::scene::Light;
use crate::session::{TruthOpts, load_scene, positions_normals, rt, truth_at};
use crate::session::{read, report};
use indexmap::IndexMap;
use serde::Deserialize;
use sshc_runtime::gpu::{CameraOutput, Gpu};
use sshc_runtime::graph::cost;
use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `sshc sweep`: a sweep file run (or its Slurm scripts written), or `merge` of shards.
#[derive(clap::Args)]
#[command(
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    override_usage = "sshc sweep [OPTIONS] <SWEEP>\n       sshc sweep <SWEEP> --slurm --shards <N> -o <OUT> [OPTIONS]\n       sshc sweep merge <DIR>... -o <OUT>",
    after_help = "`sshc sweep merge` is the merge: a word first, before any option. A sweep file named `merge` is run as `sshc sweep ./merge`. (docs/cluster.md)"
)]
pub struct SweepCommand {
    #[command(subcommand)]
    action: Option<Action>,
    #[command(flatten)]
    run: SweepArgs,
}

#[derive(clap::Subcommand)]
enum Action {
    /// Merge the folders of a sweep's shards (`--shard i/n -o DIR`) into what an unsharded
    /// run writes: sweep.csv, sweep.md and the charts. Refuses, naming the shard, a missing
    /// or duplicate shard, shards of different sweeps or code, and an unfinished shard.
    Merge(merge::MergeArgs),
}

#[derive(clap::Args)]
pub struct SweepArgs {
    /// The sweep file (RON): scenes, a reference technique and techniques with their axes.
    #[arg(required = true)]
    sweep: Option<PathBuf>,
    /// Output folder: sweep.csv, sweep.md and the Pareto charts (SVG and PNG), and what
    /// resumes the run (shard.ron, records.ron).
    #[arg(short, long, default_value = "out/sweep")]
    out: PathBuf,
    /// Run one slice of the configurations: `i/n` runs those whose index is i modulo n.
    #[arg(long, value_parser = shard, default_value = "0/1")]
    shard: (usize, usize),
    /// Measure everything again: forget the rows of an earlier run in the output folder
    /// (by default a run carries on from them).
    #[arg(long)]
    fresh: bool,
    /// Measure nothing: write sweep.md and the charts again from the output folder's
    /// sweep.csv (after a change to how they are drawn, or to draw a sweep of an older
    /// version). Rows without the timings' spread are drawn without error bars.
    #[arg(long, conflicts_with = "fresh")]
    redraw: bool,
    #[command(flatten)]
    truth: TruthOpts,
    /// Cascades for every configuration (each scene file's `cascades:` otherwise): see
    /// `sshc render --help`. The reference technique is timed with them too.
    #[command(flatten)]
    cascading: crate::bind::Cascading,
    #[command(flatten)]
    slurm: slurm::SlurmArgs,
}

pub(crate) fn shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("expected i/n, found `{s}`"))?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|e| format!("`{i}`: {e}"))?,
        n.trim().parse().map_err(|e| format!("`{n}`: {e}"))?,
    );
    if n == 0 || i >= n {
        return Err(format!("`{s}`: need 0 <= i < n"));
    }
    if n > shard::MAX_SHARDS {
        return Err(format!("`{s}`: at most {} shards", shard::MAX_SHARDS));
    }
    Ok((i, n))
}

/// The sweep file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    /// Scene files, relative to the sweep file.
    scenes: Vec<String>,
    /// Camera size for every scene (default: each scene's own).
    #[serde(default)]
    camera: Option<(u32, u32)>,
    /// Frames timed per configuration (after one untimed frame that builds pipelines).
    #[serde(default = "default_frames")]
    frames: usize,
    /// The technique every shard times on each scene: time ratios are against it.
    reference: String,
    techniques: Vec<Entry>,
    /// CPU ray-traced baselines: this many light samples per pixel, one run (Lawlor's
    /// "16 samples" row). Not timed on the GPU.
    #[serde(default)]
    stochastic: Vec<u32>,
    /// The pixel set of the charts' error axis and the Markdown table's first error
    /// column: `Penumbra` (default: facing pixels with 0 < truth < 1) or `ShadowOnGround`
    /// (Lawlor 2006's "shadow on the ground plane", `metrics::shadow_on_ground`; every
    /// scene needs an object with `casts: false`). The CSV has every set's figures.
    #[serde(default)]
    pixels: PixelSet,
}

fn default_frames() -> usize {
    5
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    /// Technique file, relative to the sweep file.
    file: String,
    /// Name in tables and charts (default: the file stem).
    #[serde(default)]
    label: Option<String>,
    /// Axes: `shadow_map` (texels), `light_scale` (multiplies the light's size),
    /// `cascades` (1 to 4 cascades of a light at infinity), `precision:NAME` (a precision
    /// name) or a param name (a `--set` value).
    #[serde(default)]
    axes: IndexMap<String, Vec<ron::Value>>,
}

/// One configuration: a technique with one value on each of its axes, on one scene.
#[derive(Clone, Debug)]
pub(crate) struct Config {
    pub(crate) scene: usize,
    pub(crate) technique: usize,
    pub(crate) label: String,
    /// `name=value` on each axis, in the file's order.
    pub(crate) values: Vec<(String, String)>,
}

impl Config {
    fn describe(&self) -> String {
        self.values.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")
    }
}

fn value_text(v: &ron::Value) -> String {
    match v {
        ron::Value::String(s) => s.clone(),
        ron::Value::Number(n) => {
            let x = n.into_f64();
            if x.fract() == 0.0 && x.abs() < 1e15 {
                format!("{}", x as i64)
            } else {
                format!("{x}")
            }
        }
        ron::Value::Bool(b) => b.to_string(),
        other => ron::to_string(other).unwrap_or_default(),
    }
}

fn configs(file: &SweepFile) -> Vec<Config> {
    let mut out = Vec::new();
    for scene in 0..file.scenes.len() {
        for (ti, t) in file.techniques.iter().enumerate() {
            let label = t.label.clone().unwrap_or_else(|| stem(&t.file));
            let mut combos: Vec<Vec<(String, String)>> = vec![vec![]];
            for (axis, values) in &t.axes {
                combos = combos
                    .into_iter()
                    .flat_map(|c| {
                        values.iter().map(move |v| {
                            let mut c = c.clone();
                            c.push((axis.clone(), value_text(v)));
                            c
                        })
                    })
                    .collect();
            }
            for values in combos {
                out.push(Config {
                    scene,
                    technique: ti,
                    label: label.clone(),
                    values,
                });
            }
        }
    }
    out
}

/// What one configuration's axis values set.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Settings {
    /// The `shadow_map` axis (else the scene's own).
    pub(crate) shadow_map: Option<u32>,
    /// The `light_scale` axis (else 1).
    pub(crate) light_scale: f64,
    /// The `cascades` axis (else `--cascades` or the scene file's).
    pub(crate) cascades: Option<u32>,
    /// Params, compiled in as `--set` values: each configuration compiles its technique
    /// afresh, so a fixed param (an I32 `N` of light samples) takes its value there, and
    /// the binding reads the sample count from the compiled graph
    /// ([`crate::bind::scene_inputs_for`]).
    pub(crate) set: Vec<(String, String)>,
    /// `precision:NAME` axes.
    pub(crate) precision: Vec<(String, String)>,
    /// `schedule:PASS` axes (`schedule:*`: every Map, Filter and Mipmap pass).
    pub(crate) schedule: Vec<(String, String)>,
}

pub(crate) fn settings(c: &Config) -> Result<Settings, String> {
    let mut out = Settings {
        shadow_map: None,
        light_scale: 1.0,
        cascades: None,
        set: Vec::new(),
        precision: Vec::new(),
        schedule: Vec::new(),
    };
    for (k, v) in &c.values {
        match k.as_str() {
            "shadow_map" => out.shadow_map = Some(v.parse().map_err(|_| format!("error: shadow_map = `{v}` is not a whole number"))?),
            "light_scale" => out.light_scale = v.parse().map_err(|_| format!("error: light_scale = `{v}` is not a number"))?,
            "cascades" => out.cascades = Some(v.parse().map_err(|_| format!("error: cascades = `{v}` is not a whole number"))?),
            k if k.starts_with("precision:") => out.precision.push((k["precision:".len()..].to_string(), v.clone())),
            k if k.starts_with("schedule:") => out.schedule.push((k["schedule:".len()..].to_string(), v.clone())),
            k => out.set.push((k.to_string(), v.clone())),
        }
    }
    Ok(out)
}

/// Scale a light's extent (radius, half-extents, segment length about its midpoint,
/// triangle about its centroid, angular diameter).
fn scale_light(l: &mut Light, f: f32) {
    *l = l.scaled(f);
}

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

impl Settings {
    /// The axes that change the scene: the shadow map and the light's size; the precision
    /// budget checked again for them.
    pub(crate) fn apply(&self, scene: &mut crate::scene::Scene) -> Result<(), String> {
        if let Some(n) = self.shadow_map {
            scene.shadow_map = n;
        }
        if let Some(l) = scene.lights.first_mut() {
            scale_light(l, self.light_scale as f32);
        }
        scene.check_precision().map_err(|e| e.to_string())
    }
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
fn time_frames(ex: &mut Bound, frames: usize) -> Result<Option<Timing>, String> {
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

/// The most light samples per pixel of a `stochastic` baseline: 2^36 light samples
/// (`session::MAX_TRUTH_SAMPLES`) over a camera of up to 4096 x 4096 pixels.
pub const MAX_STOCHASTIC_SAMPLES: u32 = 4096;

/// Refuses empty axes, a `shadow_map` value below 1 texel or not whole, a `light_scale`
/// that is not finite or is negative, and a `stochastic` count above
/// [`MAX_STOCHASTIC_SAMPLES`], naming the technique and the axis.
fn check_axes(file: &SweepFile) -> Result<(), String> {
    for (i, t) in file.techniques.iter().enumerate() {
        let name = t.label.clone().unwrap_or_else(|| t.file.clone());
        for (axis, values) in &t.axes {
            let at = format!("techniques[{i}] (`{name}`), axis `{axis}`");
            if values.is_empty() {
                return Err(format!(
                    "{at}: the list of values is empty, so the sweep would run nothing; give at least one value"
                ));
            }
            for v in values {
                let x = match v {
                    ron::Value::Number(n) => Some(n.into_f64()),
                    _ => None,
                };
                match axis.as_str() {
                    "shadow_map" => match x {
                        Some(x) if x.fract() == 0.0 && x >= 1.0 && x <= f64::from(u32::MAX) => {}
                        _ => {
                            return Err(format!(
                                "{at}: `{}`: the shadow map needs a whole number of at least 1 texel",
                                value_text(v)
                            ));
                        }
                    },
                    "cascades" => match x {
                        Some(x) if x.fract() == 0.0 && (1.0..=f64::from(sshc_runtime::light::MAX_CASCADES)).contains(&x) => {}
                        _ => {
                            return Err(format!(
                                "{at}: `{}`: a light has 1 to {} cascades",
                                value_text(v),
                                sshc_runtime::light::MAX_CASCADES
                            ));
                        }
                    },
                    "light_scale" => match x {
                        Some(x) if x.is_finite() && x >= 0.0 => {}
                        _ => {
                            return Err(format!("{at}: `{}`: a light scale must be a finite number >= 0", value_text(v)));
                        }
                    },
                    _ => {}
                }
            }
        }
    }
    // the grid's size, before `configs` builds it: a few long axes multiply past memory
    let per_scene = file.techniques.iter().try_fold(0usize, |sum, t| {
        t.axes
            .values()
            .try_fold(1usize, |p, v| p.checked_mul(v.len()))
            .and_then(|p| sum.checked_add(p))
    });
    let rows = per_scene
        .and_then(|p| p.checked_mul(file.scenes.len()))
        .and_then(|c| c.checked_add(file.scenes.len().checked_mul(file.stochastic.len())?));
    if rows.is_none_or(|r| r > shard::MAX_ROWS) {
        return Err(format!(
            "the grid has {} configurations and baselines over its {} scenes; a sweep has at most {} (split it into several sweeps, or use `sshc tune` to search a large space)",
            rows.map_or_else(|| "more than 2^64".to_string(), |r| r.to_string()),
            file.scenes.len(),
            shard::MAX_ROWS
        ));
    }
    for (k, &n) in file.stochastic.iter().enumerate() {
        if n == 0 || n > MAX_STOCHASTIC_SAMPLES {
            return Err(format!(
                "stochastic[{k}] = {n} light samples per pixel is outside 1..={MAX_STOCHASTIC_SAMPLES} (the budget is 2^36 light samples over up to 4096x4096 pixels)"
            ));
        }
    }
    Ok(())
}

pub fn sweep(c: SweepCommand) -> Result<(), String> {
    match c.action {
        Some(Action::Merge(m)) => merge::merge(m),
        None if c.run.slurm.slurm => write_slurm(c.run),
        None => run(c.run),
    }
}

/// A sweep file read and checked, with its scenes as entries (`PATH#k` for each light of a
/// scene of several) and the files it pulls in.
struct Loaded {
    path: PathBuf,
    file: SweepFile,
    base: PathBuf,
    /// The sweep file, the reference, the techniques, the scene files and the meshes they
    /// load, each with the hash of its bytes.
    inputs: Vec<(String, String)>,
}

impl Loaded {
    fn resolve(&self, p: &str) -> PathBuf {
        self.base.join(p)
    }

    /// An entry's scene: the file, with light k alone for `PATH#k`.
    fn scene(&self, entry: &str) -> Result<crate::scene::Scene, String> {
        let (path, light) = split_entry(entry);
        let scene = load_scene(&self.resolve(path), self.file.camera, None)?;
        Ok(match light {
            Some(k) if k < scene.lights.len() => crate::session::single_light(&scene, k),
            _ => scene,
        })
    }
}

fn load(path: &Path) -> Result<Loaded, String> {
    if path == Path::new("merge") && !path.exists() {
        return Err(
            "error: cannot read the sweep file `merge`: the merge is `sshc sweep merge DIR... -o OUT`, the word `merge` before any option (a sweep file named merge is `./merge`)"
                .into(),
        );
    }
    let text = read(path)?;
    let file: SweepFile =
        ron::from_str(&text).map_err(|e| format!("error: {}:{}:{}: {}", path.display(), e.span.start.line, e.span.start.col, e.code))?;
    if file.scenes.is_empty() || (file.techniques.is_empty() && file.stochastic.is_empty()) {
        return Err(format!("error: {}: a sweep needs scenes and techniques", path.display()));
    }
    check_axes(&file).map_err(|e| format!("error: {}: {e}", path.display()))?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut inputs = vec![(
        path.file_name()
            .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned()),
        shard::hash_file(path)?,
    )];
    for t in std::iter::once(&file.reference).chain(file.techniques.iter().map(|t| &t.file)) {
        if !inputs.iter().any(|(n, _)| n == t) {
            inputs.push((t.clone(), shard::hash_file(&base.join(t))?));
        }
    }
    // Several lights: a scene of n lights becomes n entries `PATH#k`, each that
    // light alone (its own truth, metrics and rows).
    let mut file = file;
    let mut entries = Vec::new();
    for path in &file.scenes {
        let scene = load_scene(&base.join(path), file.camera, None)?;
        if !inputs.iter().any(|(n, _)| n == path) {
            inputs.push((path.clone(), shard::hash_file(&base.join(path))?));
        }
        for mesh in scene.files() {
            let name = mesh.strip_prefix(&base).unwrap_or(mesh).display().to_string();
            if !inputs.iter().any(|(n, _)| *n == name) {
                inputs.push((name, shard::hash_file(mesh)?));
            }
        }
        if scene.lights.len() > 1 {
            entries.extend((0..scene.lights.len()).map(|k| format!("{path}#{k}")));
        } else {
            entries.push(path.clone());
        }
    }
    file.scenes = entries;
    let loaded = Loaded {
        path: path.to_path_buf(),
        file,
        base,
        inputs,
    };
    if loaded.file.pixels == PixelSet::ShadowOnGround {
        for entry in &loaded.file.scenes {
            let scene = loaded.scene(entry)?;
            if (0..scene.objects().len()).all(|i| scene.casts(i)) {
                return Err(format!(
                    "error: {}: `pixels: ShadowOnGround` needs a ground that casts no shadow, but every object of `{entry}` casts; mark the ground `casts: false` or write `pixels: Penumbra`",
                    path.display()
                ));
            }
        }
    }
    Ok(loaded)
}

/// The options that change what a sweep measures, in words (part of a shard's identity).
fn measuring_options(t: &TruthOpts, c: &crate::bind::Cascading) -> String {
    format!(
        "samples={} runs={} target_se={:?} max_samples={} seed={} cascades={:?} cascade_lambda={:?} cascade_band={:?} no_snap={} cascade_offset={:?}",
        t.samples, t.runs, t.target_se, t.max_samples, t.seed, c.cascades, c.cascade_lambda, c.cascade_band, c.no_snap, c.cascade_offset
    )
}

/// Seconds in words: `42 s`, `12 min`, `3.5 h`.
pub(crate) fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// A shard's progress: a bar on a terminal, else (a cluster job's log) a plain line per
/// configuration with what is done and left and the estimated time left.
struct Progress {
    bar: indicatif::ProgressBar,
    plain: bool,
    shard: (usize, usize),
    total: usize,
    done: usize,
    ran: usize,
    start: Instant,
}

impl Progress {
    fn new(total: usize, done: usize, shard: (usize, usize)) -> Result<Progress, String> {
        let bar = indicatif::ProgressBar::new(total as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("sweep [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta}) {msg}")
                .map_err(|e| format!("error: {e}"))?
                .progress_chars("=> "),
        );
        bar.set_position(done as u64);
        Ok(Progress {
            bar,
            plain: !std::io::stderr().is_terminal(),
            shard,
            total,
            done,
            ran: 0,
            start: Instant::now(),
        })
    }

    fn doing(&self, what: &str) {
        self.bar.set_message(what.to_string());
    }

    fn did(&mut self, what: &str) {
        self.done += 1;
        self.ran += 1;
        self.bar.inc(1);
        if self.plain {
            let left = self.total.saturating_sub(self.done);
            let spent = self.start.elapsed().as_secs_f64();
            let eta = spent / self.ran as f64 * left as f64;
            eprintln!(
                "sweep {}/{}: {} of {} done, {left} left, {} so far, about {} to go ({what})",
                self.shard.0,
                self.shard.1,
                self.done,
                self.total,
                duration(spent),
                duration(eta)
            );
        }
    }
}

/// What the output folder holds for `new`, the manifest of the run about to start: the
/// rows done by an earlier run of the same shard (same sweep, code and device), or none
/// when it starts afresh (saying why). A folder of another shard is refused without
/// `--fresh`.
fn resume(out: &Path, new: &Manifest, fresh: bool) -> Result<(Done, Vec<shard::Run>), String> {
    let old = match shard::read_manifest(out) {
        Ok(m) => m,
        Err(e) if fresh => {
            eprintln!("sweep: {} (starting afresh: --fresh)", e.trim_start_matches("error: "));
            None
        }
        Err(e) => {
            return Err(format!(
                "{e}\nerror: pass --fresh to measure the sweep there afresh, or name another folder"
            ));
        }
    };
    let forget = || -> Result<(), String> {
        let records = out.join(shard::RECORDS);
        match std::fs::remove_file(&records) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(format!("error: {}: {e}", records.display())),
            _ => Ok(()),
        }
    };
    let Some(old) = old else {
        forget()?;
        return Ok((Done::default(), Vec::new()));
    };
    let (i, n) = new.shard;
    if old.shard != new.shard && !fresh {
        return Err(format!(
            "error: {} holds shard {}/{} of {}, not shard {i}/{n}: name another folder, or pass --fresh to measure shard {i}/{n} there instead",
            out.display(),
            old.shard.0,
            old.shard.1,
            old.sweep
        ));
    }
    if fresh {
        eprintln!("sweep: {}: forgetting the rows of its earlier runs (--fresh)", out.display());
        forget()?;
        return Ok((Done::default(), Vec::new()));
    }
    if let Some(why) = new.differs_from(&old) {
        eprintln!("sweep: {} holds shard {i}/{n} of {why}: starting afresh", out.display());
        forget()?;
        return Ok((Done::default(), Vec::new()));
    }
    let (done, cut) = shard::read_records(out, true, new)?;
    if cut {
        eprintln!("sweep: dropped the half-written last record of a stopped run");
    }
    Ok((done, old.runs))
}

fn run(a: SweepArgs) -> Result<(), String> {
    // the run's wall time, recorded in the manifest: from here (before the sweep file is
    // read and the device opened) to its outputs written
    let start = Instant::now();
    let sweep_path = a.sweep.clone().ok_or("error: name a sweep file")?;
    let l = load(&sweep_path)?;
    if a.redraw {
        return redraw(&a.out, &l);
    }
    let file = &l.file;
    let all = configs(file);
    let (si, sn) = a.shard;
    // (index in the whole sweep, configuration)
    let mine: Vec<(usize, Config)> = all.iter().cloned().enumerate().filter(|(i, _)| i % sn == si).collect();
    // CPU baselines, in shard 0: (index, scene entry, samples), after every configuration
    let baselines: Vec<(usize, usize, u32)> = if si == 0 {
        (0..file.scenes.len())
            .flat_map(|sc| file.stochastic.iter().map(move |&n| (sc, n)))
            .enumerate()
            .map(|(k, (sc, n))| (all.len() + k, sc, n))
            .collect()
    } else {
        Vec::new()
    };
    let gpu = Gpu::new().map_err(rt)?;
    let device = gpu.describe();
    // charts name the device briefly: the adapter's name
    let short = gpu.info.name.clone();
    std::fs::create_dir_all(&a.out).map_err(|e| format!("error: {}: {e}", a.out.display()))?;
    let options = measuring_options(&a.truth, &a.cascading);
    let mut manifest = Manifest {
        format: shard::FORMAT,
        sweep: sweep_path.display().to_string(),
        identity: shard::identity(&l.inputs, &options),
        inputs: l.inputs.clone(),
        options,
        code: shard::code()?,
        shard: a.shard,
        device: (device.clone(), short),
        reference: file.reference.clone(),
        pixels: file.pixels,
        scenes: file.scenes.clone(),
        configurations: all.len(),
        baselines: file.scenes.len() * file.stochastic.len(),
        rows: mine.len() + baselines.len(),
        finished: false,
        runs: Vec::new(),
    };
    let (done, runs) = resume(&a.out, &manifest, a.fresh)?;
    let todo: Vec<&(usize, Config)> = mine.iter().filter(|(i, _)| !done.rows.contains_key(i)).collect();
    let todo_baselines: Vec<&(usize, usize, u32)> = baselines.iter().filter(|(i, ..)| !done.rows.contains_key(i)).collect();
    let left = todo.len() + todo_baselines.len();
    // this shard's rows done (`records.ron` holds no others unless it was edited)
    let finished_rows = manifest.rows - left;
    if finished_rows == 0 {
        eprintln!(
            "sweep: {} configurations ({} in shard {si}/{sn}) on {device}",
            all.len(),
            mine.len()
        );
    } else {
        eprintln!(
            "sweep: resuming shard {si}/{sn} in {}: {} of its {} rows done by an earlier run, skipped; {} left, on {device}",
            a.out.display(),
            finished_rows,
            manifest.rows,
            left
        );
    }
    manifest.runs = runs;
    let nothing_left = left == 0;
    if nothing_left {
        manifest.finished = true;
        eprintln!("sweep: nothing left to measure (--fresh measures again); writing the outputs");
    } else {
        manifest.runs.push(shard::Run {
            host: crate::claim::host(),
            pid: std::process::id(),
            started: crate::claim::unix_now(),
            resumed_at: finished_rows,
            seconds: None,
        });
        shard::write_manifest(&a.out, &manifest)?;
        measure(&a, &l, &gpu, &todo, &todo_baselines, finished_rows, manifest.rows)?;
        manifest.finished = true;
    }
    // the outputs from what the folder holds, as the merge reads it
    let (done, _) = shard::read_records(&a.out, false, &manifest)?;
    if done.rows.len() != manifest.rows {
        return Err(format!(
            "error: {}: {} rows are recorded for the shard's {}: the file was changed; run again with --fresh",
            a.out.join(shard::RECORDS).display(),
            done.rows.len(),
            manifest.rows
        ));
    }
    report::write(
        &a.out,
        &Outputs {
            rows: &done.gathered(&manifest),
            scenes: &file.scenes,
            reference: &file.reference,
            pixels: file.pixels,
        },
    )?;
    if let (Some(r), false) = (manifest.runs.last_mut(), nothing_left) {
        r.seconds = Some(start.elapsed().as_secs_f64());
    }
    shard::write_manifest(&a.out, &manifest)
}

/// `--redraw`: sweep.md and the charts of `out` written again from its sweep.csv, with
/// the sweep file's scenes, reference and pixel set; nothing measured.
fn redraw(out: &Path, l: &Loaded) -> Result<(), String> {
    let path = out.join("sweep.csv");
    let text = crate::session::read_capped(&path, report::MAX_CSV_BYTES)?;
    let rows = report::read_csv(&path, &text)?;
    if rows.is_empty() {
        return Err(format!("error: {}: no rows to draw", path.display()));
    }
    let spread = rows.iter().filter(|r| r.ms_range.is_some()).count();
    eprintln!(
        "sweep: drawing the {} rows of {} again (nothing measured; {spread} with the timings' spread)",
        rows.len(),
        path.display()
    );
    report::write(
        out,
        &Outputs {
            rows: &rows,
            scenes: &l.file.scenes,
            reference: &l.file.reference,
            pixels: l.file.pixels,
        },
    )
}

/// Measures the configurations and CPU baselines `todo` (indices in the whole sweep),
/// appending each row to the folder's records as it is done, and each timing of the
/// reference.
fn measure(
    a: &SweepArgs,
    l: &Loaded,
    gpu: &Gpu,
    todo: &[&(usize, Config)],
    todo_baselines: &[&(usize, usize, u32)],
    done: usize,
    total: usize,
) -> Result<(), String> {
    let file = &l.file;
    let mut log = Log::open(&a.out)?;
    let sources: Vec<String> = file
        .techniques
        .iter()
        .map(|t| read(&l.resolve(&t.file)))
        .collect::<Result<_, _>>()?;
    let mut progress = Progress::new(total, done, a.shard)?;
    // truths by (scene, light scale)
    let mut truths: Vec<((usize, String), SceneTruth)> = Vec::new();
    // The reference is timed on each scene before the first configuration, after every
    // `RETIME` configurations and after the last; its time is the median of those, so that
    // a machine that speeds up or slows down during the shard moves the ratios less. Each
    // timing builds fresh stages, as every configuration does (long-lived ones keep
    // its memory warm and reads faster on a CPU driver). A resumed shard adds its timings
    // to those recorded before it stopped.
    const RETIME: usize = 12;
    let reference_source = read(&l.resolve(&file.reference))?;
    type ReferenceRun = (usize, sshc::Compiled, crate::scene::Scene);
    let mut reference_runs: Vec<ReferenceRun> = Vec::new();
    for (sc, entry) in file.scenes.iter().enumerate() {
        let touches = todo.iter().any(|(_, c)| c.scene == sc) || !file.stochastic.is_empty();
        if touches {
            let scene = l.scene(entry)?;
            crate::bind::check_cascades(&scene, &a.cascading)?;
            let c = compile(&l.resolve(&file.reference), &reference_source, &[], &[], &[])?;
            reference_runs.push((sc, c, scene));
        }
    }
    let time_references = |log: &mut Log| -> Result<(), String> {
        for (sc, c, scene) in &reference_runs {
            let loaded = crate::run::Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(rt)?;
            let (mut ex, _) = a.cascading.bind_or_scene(&loaded, scene, false)?;
            if let Some(t) = time_frames(&mut ex, file.frames)? {
                log.append(&Record::Reference { scene: *sc, ms: t.median })?;
            }
        }
        Ok(())
    };
    time_references(&mut log)?;
    for (ran, (index, c)) in todo.iter().map(|x| (x.0, &x.1)).enumerate() {
        if ran > 0 && ran % RETIME == 0 {
            time_references(&mut log)?;
        }
        let what = format!("{} {} {}", stem(&file.scenes[c.scene]), c.label, c.describe());
        progress.doing(&what);
        let mut scene = l.scene(&file.scenes[c.scene])?;
        let settings = settings(c)?;
        settings.apply(&mut scene)?;
        let path = l.resolve(&file.techniques[c.technique].file);
        let scene_path = l.resolve(split_entry(&file.scenes[c.scene]).0);
        let Ran {
            ex,
            ms,
            ms_range,
            peak,
            fetches,
            ops,
            visibility: vis,
        } = run_config(
            gpu,
            &path,
            &sources[c.technique],
            &scene,
            &scene_path,
            &settings,
            &a.cascading,
            file.frames,
        )?;
        let light_scale = settings.light_scale;
        let key = (c.scene, format!("{light_scale}"));
        let truth = match truths.iter().find(|(k, _)| *k == key) {
            Some((_, t)) => t.clone(),
            None => {
                let t = SceneTruth::at(&ex, &scene, &a.truth, |f| progress.bar.suspend(f))?;
                truths.push((key, t.clone()));
                t
            }
        };
        let acc = truth.score(&format!("the visibility of {}", c.label), &vis, &scene)?;
        let se = truth.se;
        let row = Row {
            scene: stem(&file.scenes[c.scene]),
            label: c.label.clone(),
            config: c.describe(),
            shadow_map: scene.shadow_map,
            light_scale,
            ms,
            ms_range,
            peak_bytes: peak,
            fetches,
            ops,
            acc,
            truth_se: se,
            reference_ms: None,
            shard: a.shard,
            device: Default::default(),
        };
        log.append(&Record::Row {
            index,
            scene: c.scene,
            row: Box::new(row),
        })?;
        progress.did(&what);
    }
    if !todo.is_empty() || !reference_runs.is_empty() {
        time_references(&mut log)?;
    }
    // CPU baselines: n light samples per pixel, one run, against the truth
    for &&(index, sc, n) in todo_baselines {
        let scene = l.scene(&file.scenes[sc])?;
        let c = compile(&l.resolve(&file.reference), &reference_source, &[], &[], &[])?;
        let loaded = crate::run::Loaded::new(gpu, c.graph, c.shaders).map_err(rt)?;
        let mut ex = crate::bind::bind_scene(&loaded, &scene, false)?;
        ex.run_frame().map_err(rt)?;
        let (p, nrm) = positions_normals(&ex)?;
        let (truth, _) = progress.bar.suspend(|| truth_at(&scene, &p, &nrm, &a.truth))?;
        let vis = crate::visibility::Visibility::new(&scene);
        // the visibility query takes samples per axis (an n x n stratified grid)
        let per_axis = crate::truth::strata(n);
        let n = per_axis * per_axis;
        let est = vis.visible_fractions_seeded(&p, &nrm, &scene.lights[0], per_axis, 0x5eed_0000 + n as u64);
        let est: Vec<f32> = est.iter().zip(&p).map(|(v, p)| if p.is_finite() { *v } else { 1.0 }).collect();
        let facing = metrics::facing_light(&p, &nrm, &scene.lights[0]).unwrap_or_default();
        let mut acc = metrics::accuracy(&est, &truth.visibility, &facing).map_err(|e| format!("error: {e}"))?;
        acc.flip = Some(
            metrics::flip(&est, &truth.visibility, &p, &nrm, &scene.lights[0], scene.camera_size(), &facing)
                .map_err(|e| format!("error: {e}"))?,
        );
        if let Some(g) = metrics::ground_set(&scene, &truth.visibility, &p, &facing).map_err(|e| format!("error: {e}"))? {
            acc.ground = Some(metrics::error_stats(&est, &truth.visibility, &g).map_err(|e| format!("error: {e}"))?);
        }
        let row = Row {
            scene: stem(&file.scenes[sc]),
            label: format!("{n} samples (CPU)"),
            config: format!("samples={n}"),
            shadow_map: 0,
            light_scale: 1.0,
            ms: None,
            ms_range: None,
            peak_bytes: 0,
            fetches: 0.0,
            ops: 0.0,
            acc,
            truth_se: truth.max_std_error() as f64,
            reference_ms: None,
            shard: a.shard,
            device: Default::default(),
        };
        let what = format!("{} {}", row.scene, row.label);
        log.append(&Record::Row {
            index,
            scene: sc,
            row: Box::new(row),
        })?;
        progress.did(&what);
    }
    progress.bar.finish_and_clear();
    Ok(())
}

/// `--slurm`: the job scripts of the sweep in `--shards` array tasks (after checking the
/// sweep file as a run would, so that a mistake shows before anything is submitted).
fn write_slurm(a: SweepArgs) -> Result<(), String> {
    let sweep_path = a.sweep.clone().ok_or("error: name a sweep file")?;
    // every path the scripts carry, before anything is read
    slurm::no_control_characters("the sweep file", &sweep_path.display().to_string())?;
    slurm::no_control_characters("the output folder", &a.out.display().to_string())?;
    slurm::no_control_characters("the truth cache", &a.truth.cache.display().to_string())?;
    if let Some(p) = &a.slurm.sshc {
        slurm::no_control_characters("--sshc", &p.display().to_string())?;
    }
    let n = a
        .slurm
        .shards
        .ok_or("error: --slurm needs --shards N, the number of array tasks (one shard each)")?;
    let l = load(&sweep_path)?;
    // what every task will check, checked here first: the cascades and the truth's budget
    // on each scene (issue 48, item 11)
    for entry in &l.file.scenes {
        let scene = l.scene(entry)?;
        crate::bind::check_cascades(&scene, &a.cascading)?;
        let (w, h) = scene.camera_size();
        a.truth.check(u64::from(w) * u64::from(h))?;
    }
    let rows = configs(&l.file).len();
    if n == 0 || n > rows.max(1) {
        return Err(format!(
            "error: --shards {n}: the sweep has {rows} configurations; give 1 to {} shards",
            rows.max(1)
        ));
    }
    let s = &a.slurm;
    let absolute = |p: &Path| std::path::absolute(p).map_err(|e| format!("error: {}: {e}", p.display()));
    let out = absolute(&a.out)?;
    slurm::check_options(s, &out)?;
    let out_text = out.display().to_string();
    let sshc = match &s.sshc {
        Some(p) => absolute(p)?,
        None => std::env::current_exe().map_err(|e| format!("error: cannot find this executable: {e}"))?,
    };
    let sweep = absolute(&sweep_path)?;
    // each shard's options: the truth's (the cache on the shared folder) and the cascades'
    let t = &a.truth;
    let mut options: Vec<String> = vec!["--samples".into(), t.samples.to_string(), "--runs".into(), t.runs.to_string()];
    if let Some(se) = t.target_se {
        options.extend([
            "--target-se".into(),
            se.to_string(),
            "--max-samples".into(),
            t.max_samples.to_string(),
        ]);
    }
    options.extend(["--seed".into(), t.seed.to_string()]);
    if t.no_cache {
        options.push("--no-cache".into());
    } else {
        let cache = if t.cache == Path::new(crate::truth::TruthCache::DEFAULT_DIR) {
            out.join("truth-cache")
        } else {
            absolute(&t.cache)?
        };
        options.extend([
            "--cache".into(),
            cache.display().to_string(),
            "--claim-stale".into(),
            t.claim_stale.to_string(),
        ]);
    }
    let c = &a.cascading;
    if let Some(n) = c.cascades {
        options.extend(["--cascades".into(), n.to_string()]);
    }
    if let Some(x) = c.cascade_lambda {
        options.extend(["--cascade-lambda".into(), x.to_string()]);
    }
    if let Some(x) = c.cascade_band {
        options.extend(["--cascade-band".into(), x.to_string()]);
    }
    if c.no_snap {
        options.push("--no-snap".into());
    }
    if let Some([x, y, z]) = c.cascade_offset {
        options.extend(["--cascade-offset".into(), format!("{x},{y},{z}")]);
    }
    let job = slurm::Job {
        sshc: &sshc,
        sweep: &sweep,
        out: &out,
        shards: n,
        options: &options,
        slurm: s,
    };
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| format!("error: {}: {e}", logs.display()))?;
    for (name, text) in slurm::scripts(&job) {
        let p = out.join(name);
        // a link planted in the folder is refused, not written through (and not made 0755)
        crate::session::write_new(&p, &text)?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).map_err(|e| format!("error: {}: {e}", p.display()))?;
        }
        println!("wrote {}", p.display());
    }
    println!(
        "{} configurations of {} in {n} shards; submit with {}/submit.sh (the merge writes {out_text}/sweep.csv)",
        rows,
        l.path.display(),
        out_text
    );
    Ok(())
}

fn compile(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_axes_and_huge_stochastic_counts_are_refused_with_the_axis_named() {
        let file = |axes: &str, stochastic: &str| -> SweepFile {
            ron::from_str(&format!(
                r#"(scenes: ["a.ron"], reference: "h.ron", stochastic: [{stochastic}], techniques: [(file: "p.ron", axes: {{ {axes} }})])"#
            ))
            .unwrap()
        };
        assert_eq!(check_axes(&file(r#""shadow_map": [16], "light_scale": [0.5, 2.0]"#, "16")), Ok(()));
        for (axes, want) in [
            (
                r#""light_scale": [NaN]"#,
                "axis `light_scale`: `NaN`: a light scale must be a finite number >= 0",
            ),
            (
                r#""light_scale": [-1.0]"#,
                "axis `light_scale`: `-1`: a light scale must be a finite number >= 0",
            ),
            (r#""cascades": [5]"#, "axis `cascades`: `5`: a light has 1 to 4 cascades"),
            (r#""cascades": [1.5]"#, "axis `cascades`: `1.5`: a light has 1 to 4 cascades"),
            (
                r#""shadow_map": [0]"#,
                "axis `shadow_map`: `0`: the shadow map needs a whole number of at least 1 texel",
            ),
            (r#""r": []"#, "axis `r`: the list of values is empty"),
        ] {
            let e = check_axes(&file(axes, "")).unwrap_err();
            assert!(e.contains("techniques[0] (`p.ron`)") && e.contains(want), "{axes}: {e}");
            assert!(!e.contains("device"), "{e}");
        }
        let e = check_axes(&file("", "4294967295")).unwrap_err();
        assert!(e.contains("stochastic[0] = 4294967295") && e.contains("1..=4096"), "{e}");
        // a grid past what a sweep holds is refused before it is built: five axes of 100
        // values (10^10 configurations), and twelve (a product past 2^64)
        let axis = format!("[{}]", (0..100).map(|v| v.to_string()).collect::<Vec<_>>().join(", "));
        for (k, want) in [(5, "10000000000 configurations"), (12, "more than 2^64 configurations")] {
            let axes: Vec<String> = (0..k).map(|i| format!(r#""a{i}": {axis}"#)).collect();
            let e = check_axes(&file(&axes.join(", "), "")).unwrap_err();
            assert!(e.contains(want) && e.contains("at most 1048576"), "{e}");
        }
        assert!(shard("0/65537").unwrap_err().contains("at most 65536 shards"));
    }

    #[test]
    fn axes_multiply_per_technique_and_scene() {
        let f: SweepFile = ron::from_str(
            r#"(scenes: ["a.ron", "b.ron"], reference: "h.ron", techniques: [
                (file: "p.ron", axes: { "shadow_map": [16, 32], "r": [1, 2, 3] }),
                (file: "c.ron", label: Some("csm"), axes: { "precision:f": ["Unorm8", "F16"] }),
            ])"#,
        )
        .unwrap();
        let c = configs(&f);
        assert_eq!(c.len(), 2 * (2 * 3 + 2));
        assert_eq!(c[0].describe(), "shadow_map=16 r=1");
        assert_eq!(c[6].label, "csm");
        assert_eq!(c[6].describe(), "precision:f=Unorm8");
        assert_eq!(shard("1/3"), Ok((1, 3)));
        assert!(shard("3/3").is_err());
    }

    /// sweeps/linear.ron: a fixed I32 param axis (`N`, light samples) gives one
    /// configuration per value, each compiling its technique with that value (`--set`),
    /// which a fixed param takes at compile time: the compiled graph's param holds it, and
    /// the binding reads the sample count from the graph.
    #[test]
    fn schedule_and_precision_axes_become_compile_options() {
        let c = Config {
            scene: 0,
            technique: 0,
            label: "vsm".into(),
            values: vec![
                ("schedule:*".into(), "compute".into()),
                ("precision:m1,m2".into(), "F16".into()),
                ("shadow_map".into(), "64".into()),
            ],
        };
        let s = settings(&c).unwrap();
        assert_eq!(s.schedule, [("*".to_string(), "compute".to_string())]);
        assert_eq!(s.precision, [("m1,m2".to_string(), "F16".to_string())]);
        assert_eq!((s.shadow_map, s.set.len()), (Some(64), 0));
    }

    #[test]
    fn a_fixed_param_axis_recompiles_each_value() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let f: SweepFile = ron::from_str(&std::fs::read_to_string(root.join("sweeps/linear.ron")).unwrap()).unwrap();
        assert_eq!(check_axes(&f), Ok(()));
        assert_eq!(f.scenes, ["../scenes/linear.ron"]);
        let c = configs(&f);
        let got: Vec<(String, Settings)> = c.iter().map(|c| (c.label.clone(), settings(c).unwrap())).collect();
        let want = |label: &str, n: &str| {
            (
                label.to_string(),
                Settings {
                    shadow_map: None,
                    light_scale: 1.0,
                    cascades: None,
                    set: vec![("N".to_string(), n.to_string())],
                    precision: vec![],
                    schedule: vec![],
                },
            )
        };
        assert_eq!(
            got,
            [
                want("linear-light", "2"),
                want("linear-light", "3"),
                want("linear-light", "5"),
                want("linear-light", "9"),
                want("point-samples", "2"),
                want("point-samples", "10"),
            ]
        );
        // A bundled technique with a fixed I32 param (PCSS's `N`), compiled per value as
        // the sweep does: the value is compiled in, so each configuration's graph differs.
        let pcss = root.join("techniques/pcss.ron");
        let source = std::fs::read_to_string(&pcss).unwrap();
        for n in ["4", "8"] {
            let g = compile(&pcss, &source, &[("N".to_string(), n.to_string())], &[], &[])
                .unwrap()
                .graph;
            let p = g.params.iter().find(|p| p.name == "N").unwrap();
            assert_eq!((p.value, p.offset), (n.parse::<f64>().unwrap(), None), "N = {n}");
        }
    }
}
