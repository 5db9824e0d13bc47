//! `sshc sweep <sweep.ron>`: techniques x their own parameter axes x scenes, each
//! configuration rendered (axes: params by name, `shadow_map`, `light_scale`,
//! `precision:NAMES` and `schedule:PASS` or `schedule:*`, as the command line's
//! `--precision` and `--schedule`), timed (median of repeated frames, as a ratio to a reference
//! technique timed in the same run) and compared with the cached ground truth; a CSV, a
//! Markdown table and Pareto charts (error against time, error against memory).
//!
//! `--shard i/n` runs every n-th configuration starting at i; every shard times the
//! reference technique on each of its scenes, so time ratios from separate shards (run on
//! separate machines by any batch scheduler) stay comparable, and their CSVs merge by
//! concatenation (drop the header lines after the first).

use crate::metrics;
use crate::scene::Light;
use crate::session::{TruthOpts, load_scene, positions_normals, rt, truth_at};
use crate::session::{read, report};
use indexmap::IndexMap;
use plotters::prelude::*;
use serde::Deserialize;
use sshc_runtime::gpu::{CameraOutput, Executor, Gpu};
use sshc_runtime::graph::PassGraph;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct SweepArgs {
    /// The sweep file (RON): scenes, a reference technique and techniques with their axes.
    sweep: PathBuf,
    /// Output folder: sweep.csv, sweep.md and the Pareto charts (SVG and PNG).
    #[arg(short, long, default_value = "out/sweep")]
    out: PathBuf,
    /// Run one slice of the configurations: `i/n` runs those whose index is i modulo n.
    #[arg(long, value_parser = shard, default_value = "0/1")]
    shard: (usize, usize),
    #[command(flatten)]
    truth: TruthOpts,
    /// Cascades for every configuration (each scene file's `cascades:` otherwise): see
    /// `sshc render --help`. The reference technique is timed with them too.
    #[command(flatten)]
    cascading: crate::bind::Cascading,
}

fn shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("expected i/n, found `{s}`"))?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|e| format!("`{i}`: {e}"))?,
        n.trim().parse().map_err(|e| format!("`{n}`: {e}"))?,
    );
    if n == 0 || i >= n {
        return Err(format!("`{s}`: need 0 <= i < n"));
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

/// The pixel set a sweep's charts rank by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
enum PixelSet {
    #[default]
    Penumbra,
    ShadowOnGround,
}

impl PixelSet {
    /// The RMS error of `r` over this set.
    fn rms(self, r: &Row) -> f64 {
        match self {
            PixelSet::Penumbra => r.acc.penumbra.rms,
            PixelSet::ShadowOnGround => r.acc.ground.map_or(f64::NAN, |g| g.rms),
        }
    }

    fn describe(self) -> &'static str {
        match self {
            PixelSet::Penumbra => "RMS error in penumbra (0..255)",
            PixelSet::ShadowOnGround => "RMS error, shadow on the ground (0..255)",
        }
    }
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
struct Config {
    scene: usize,
    technique: usize,
    label: String,
    /// `name=value` on each axis, in the file's order.
    values: Vec<(String, String)>,
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
struct Settings {
    /// The `shadow_map` axis (else the scene's own).
    shadow_map: Option<u32>,
    /// The `light_scale` axis (else 1).
    light_scale: f64,
    /// The `cascades` axis (else `--cascades` or the scene file's).
    cascades: Option<u32>,
    /// Params, compiled in as `--set` values: each configuration compiles its technique
    /// afresh, so a fixed param (an I32 `N` of light samples) takes its value there, and
    /// the binding reads the sample count from the compiled graph
    /// ([`crate::bind::scene_inputs_for`]).
    set: Vec<(String, String)>,
    /// `precision:NAME` axes.
    precision: Vec<(String, String)>,
    /// `schedule:PASS` axes (`schedule:*`: every Map, Filter and Mipmap pass).
    schedule: Vec<(String, String)>,
}

fn settings(c: &Config) -> Result<Settings, String> {
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

fn stem(p: &str) -> String {
    let (path, light) = split_entry(p);
    let s = Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().trim_end_matches(".graph").to_string())
        .unwrap_or_else(|| path.to_string());
    match light {
        Some(k) => format!("{s} light {k}"),
        None => s,
    }
}

/// A scene entry `PATH` or `PATH#k` (light k alone): the path and the light.
fn split_entry(entry: &str) -> (&str, Option<usize>) {
    match entry.rsplit_once('#') {
        Some((path, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => (path, k.parse().ok()),
        _ => (entry, None),
    }
}

/// Scale a light's extent (radius, half-extents, segment length about its midpoint,
/// triangle about its centroid, angular diameter).
fn scale_light(l: &mut Light, f: f32) {
    *l = l.scaled(f);
}

/// The truth of one scene at one light scale: visibility, its largest standard error,
/// which pixels face the light, and the shadow on the ground (`metrics::ground_set`;
/// `None` where every object casts).
type SceneTruth = (Vec<f32>, f64, Vec<bool>, Option<Vec<bool>>);

/// One measured row.
#[derive(Clone, Debug)]
struct Row {
    scene: String,
    label: String,
    config: String,
    shadow_map: u32,
    light_scale: f64,
    /// Median GPU ms per frame (all passes), or none for CPU baselines.
    ms: Option<f64>,
    reference_ms: Option<f64>,
    peak_bytes: u64,
    fetches: f64,
    ops: f64,
    acc: metrics::Accuracy,
    truth_se: f64,
}

impl Row {
    fn ratio(&self) -> Option<f64> {
        Some(self.ms? / self.reference_ms?)
    }
}

/// Median of per-frame GPU times (sum over passes) over `frames` frames after a warm-up.
fn time_frames(ex: &mut Executor, frames: usize) -> Result<Option<f64>, String> {
    ex.run_frame().map_err(rt)?;
    let mut t = Vec::new();
    for _ in 0..frames.max(1) {
        let f = ex.run_frame().map_err(rt)?;
        let ms: Option<f64> = f.passes.iter().map(|(_, ms)| *ms).sum();
        if let Some(ms) = ms {
            t.push(ms);
        }
    }
    t.sort_by(f64::total_cmp);
    Ok(t.get(t.len() / 2).copied())
}

/// Fetches and operations per frame, summed over the passes of [`crate::cmd::render::pass_work`].
fn work(graph: &PassGraph, shadow: u32, camera: (u32, u32), edges: u64) -> (f64, f64) {
    crate::cmd::render::pass_work(graph, shadow, camera, edges)
        .iter()
        .fold((0.0, 0.0), |(f, o), w| (f + w.fetches, o + w.ops))
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
    for (k, &n) in file.stochastic.iter().enumerate() {
        if n == 0 || n > MAX_STOCHASTIC_SAMPLES {
            return Err(format!(
                "stochastic[{k}] = {n} light samples per pixel is outside 1..={MAX_STOCHASTIC_SAMPLES} (the budget is 2^36 light samples over up to 4096x4096 pixels)"
            ));
        }
    }
    Ok(())
}

pub fn sweep(a: SweepArgs) -> Result<(), String> {
    let text = read(&a.sweep)?;
    let file: SweepFile = ron::from_str(&text).map_err(|e| {
        format!(
            "error: {}:{}:{}: {}",
            a.sweep.display(),
            e.span.start.line,
            e.span.start.col,
            e.code
        )
    })?;
    if file.scenes.is_empty() || (file.techniques.is_empty() && file.stochastic.is_empty()) {
        return Err(format!("error: {}: a sweep needs scenes and techniques", a.sweep.display()));
    }
    check_axes(&file).map_err(|e| format!("error: {}: {e}", a.sweep.display()))?;
    let base = a.sweep.parent().unwrap_or(Path::new(".")).to_path_buf();
    let resolve = |p: &str| -> PathBuf { base.join(p) };
    // Several lights: a scene of n lights becomes n entries `PATH#k`, each that
    // light alone (its own truth, metrics and rows).
    let mut file = file;
    let mut entries = Vec::new();
    for path in &file.scenes {
        let scene = load_scene(&resolve(path), file.camera, None)?;
        if scene.lights.len() > 1 {
            entries.extend((0..scene.lights.len()).map(|k| format!("{path}#{k}")));
        } else {
            entries.push(path.clone());
        }
    }
    file.scenes = entries;
    // an entry's scene: the file, with light k alone for `PATH#k`
    let load_entry = |entry: &str, camera: Option<(u32, u32)>| -> Result<crate::scene::Scene, String> {
        let (path, light) = split_entry(entry);
        let scene = load_scene(&resolve(path), camera, None)?;
        Ok(match light {
            Some(k) if k < scene.lights.len() => crate::session::single_light(&scene, k),
            _ => scene,
        })
    };
    if file.pixels == PixelSet::ShadowOnGround {
        for scene_path in &file.scenes {
            let scene = load_entry(scene_path, file.camera)?;
            if (0..scene.objects().len()).all(|i| scene.casts(i)) {
                return Err(format!(
                    "error: {}: `pixels: ShadowOnGround` needs a ground that casts no shadow, but every object of `{scene_path}` casts; mark the ground `casts: false` or write `pixels: Penumbra`",
                    a.sweep.display()
                ));
            }
        }
    }
    let all = configs(&file);
    let (si, sn) = a.shard;
    let mine: Vec<Config> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| i % sn == si)
        .map(|(_, c)| c.clone())
        .collect();
    let gpu = Gpu::new().map_err(rt)?;
    let device = gpu.describe();
    // charts name the device briefly: the adapter's name
    let short = gpu.info.name.clone();
    eprintln!(
        "sweep: {} configurations ({} in shard {si}/{sn}) on {device}",
        all.len(),
        mine.len()
    );
    let sources: Vec<String> = file.techniques.iter().map(|t| read(&resolve(&t.file))).collect::<Result<_, _>>()?;
    let bar = indicatif::ProgressBar::new((mine.len() + file.scenes.len() * file.stochastic.len()) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("sweep [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta}) {msg}")
            .map_err(|e| format!("error: {e}"))?
            .progress_chars("=> "),
    );
    let mut rows = Vec::new();
    // the scene index of each row
    let mut row_scenes: Vec<usize> = Vec::new();
    // truths by (scene, light scale)
    let mut truths: Vec<((usize, String), SceneTruth)> = Vec::new();
    // The reference is timed on each scene before the first configuration, after every
    // `RETIME` configurations and after the last; its time is the median of those, so that
    // a machine that speeds up or slows down during the shard moves the ratios less. Each
    // timing builds a fresh executor, as every configuration does (a long-lived one keeps
    // its memory warm and reads faster on a CPU driver).
    const RETIME: usize = 12;
    let reference_source = read(&resolve(&file.reference))?;
    type ReferenceRun = (sshc::Compiled, Vec<f64>, crate::scene::Scene);
    let mut reference_runs: Vec<Option<ReferenceRun>> = Vec::new();
    for (si_, scene_path) in file.scenes.iter().enumerate() {
        let touches = mine.iter().any(|c| c.scene == si_) || !file.stochastic.is_empty();
        if !touches {
            reference_runs.push(None);
            continue;
        }
        let scene = load_entry(scene_path, file.camera)?;
        crate::bind::check_cascades(&scene, &a.cascading)?;
        let c = compile(&resolve(&file.reference), &reference_source, &[], &[], &[])?;
        reference_runs.push(Some((c, Vec::new(), scene)));
    }
    let time_references = |runs: &mut Vec<Option<ReferenceRun>>| -> Result<(), String> {
        for (c, times, scene) in runs.iter_mut().flatten() {
            let mut ex = Executor::new(&gpu, c.graph.clone(), c.shaders.clone()).map_err(rt)?;
            a.cascading.bind_or_scene(&mut ex, scene, false)?;
            times.extend(time_frames(&mut ex, file.frames)?);
        }
        Ok(())
    };
    time_references(&mut reference_runs)?;
    for (ci, c) in mine.iter().enumerate() {
        if ci > 0 && ci % RETIME == 0 {
            time_references(&mut reference_runs)?;
        }
        bar.set_message(format!("{} {} {}", stem(&file.scenes[c.scene]), c.label, c.describe()));
        let mut scene = load_entry(&file.scenes[c.scene], file.camera)?;
        let Settings {
            shadow_map,
            light_scale,
            cascades,
            set,
            precision,
            schedule,
        } = settings(c)?;
        // the `cascades` axis over `--cascades` (the reference is timed with the latter)
        let cascading = crate::bind::Cascading {
            cascades: cascades.or(a.cascading.cascades),
            ..a.cascading
        };
        if let Some(n) = shadow_map {
            scene.shadow_map = n;
        }
        if let Some(l) = scene.lights.first_mut() {
            scale_light(l, light_scale as f32);
        }
        // The axes change the shadow map and the light: the precision budget again.
        scene.check_precision().map_err(|e| e.to_string())?;
        let path = resolve(&file.techniques[c.technique].file);
        // specialised for the scene's light where the technique admits it
        let scene_path = resolve(split_entry(&file.scenes[c.scene]).0);
        // (generic under cascades: their views are not the scene's)
        let facts = crate::session::scene_facts(&scene_path, &scene)
            .filter(|f| sshc::admits(&sources[c.technique], f.light) && !cascading.on(&scene));
        let compiled = compile_for(&path, &sources[c.technique], &set, &precision, &schedule, facts)?;
        let mut ex = Executor::new(&gpu, compiled.graph, compiled.shaders).map_err(rt)?;
        crate::bind::check_cascades(&scene, &cascading)?;
        cascading.bind_or_scene(&mut ex, &scene, false)?;
        let edges = ex.edge_counts().map_err(rt)?.map_or(0, |c| u64::from(c.edges));
        let (fetches, ops) = work(&ex.graph, scene.shadow_map, scene.camera_size(), edges);
        let ms = time_frames(&mut ex, file.frames)?;
        let vis = ex.read_camera(CameraOutput::Visibility).map_err(rt)?.channel(0);
        let peak = ex.memory().map_err(rt)?.iter().map(|(_, b)| b).sum();
        let key = (c.scene, format!("{light_scale}"));
        let (truth, se, facing, ground) = match truths.iter().find(|(k, _)| *k == key) {
            Some((_, t)) => t.clone(),
            None => {
                let (p, n) = positions_normals(&ex)?;
                let (t, _) = bar.suspend(|| truth_at(&scene, &p, &n, &a.truth))?;
                let facing = metrics::facing_light(&p, &n, &scene.lights[0]).unwrap_or_default();
                let ground = metrics::ground_set(&scene, &t.visibility, &p, &facing).map_err(|e| format!("error: {e}"))?;
                (t.visibility.clone(), t.max_std_error() as f64, facing, ground)
            }
        };
        if !truths.iter().any(|(k, _)| *k == key) {
            truths.push((key, (truth.clone(), se, facing.clone(), ground.clone())));
        }
        metrics::check_visibility(&format!("the visibility of {}", c.label), &vis, &facing).map_err(|e| format!("error: {e}"))?;
        let mut acc = metrics::accuracy(&vis, &truth, &facing).map_err(|e| format!("error: {e}"))?;
        if let Some(g) = &ground {
            acc.ground = Some(metrics::error_stats(&vis, &truth, g).map_err(|e| format!("error: {e}"))?);
        }
        rows.push(Row {
            scene: stem(&file.scenes[c.scene]),
            label: c.label.clone(),
            config: c.describe(),
            shadow_map: scene.shadow_map,
            light_scale,
            ms,
            reference_ms: None,
            peak_bytes: peak,
            fetches,
            ops,
            acc,
            truth_se: se,
        });
        row_scenes.push(c.scene);
        bar.inc(1);
    }
    time_references(&mut reference_runs)?;
    // CPU baselines: n light samples per pixel, one run, against the truth
    if si == 0 {
        for (sc, scene_path) in file.scenes.iter().enumerate() {
            for &n in &file.stochastic {
                let scene = load_entry(scene_path, file.camera)?;
                let c = compile(&resolve(&file.reference), &reference_source, &[], &[], &[])?;
                let mut ex = Executor::new(&gpu, c.graph, c.shaders).map_err(rt)?;
                crate::bind::bind_scene(&mut ex, &scene, false)?;
                ex.run_frame().map_err(rt)?;
                let (p, nrm) = positions_normals(&ex)?;
                let (truth, _) = bar.suspend(|| truth_at(&scene, &p, &nrm, &a.truth))?;
                let vis = crate::visibility::Visibility::new(&scene);
                // the visibility query takes samples per axis (an n x n stratified grid)
                let per_axis = crate::truth::strata(n);
                let n = per_axis * per_axis;
                let est = vis.visible_fractions_seeded(&p, &nrm, &scene.lights[0], per_axis, 0x5eed_0000 + n as u64);
                let est: Vec<f32> = est.iter().zip(&p).map(|(v, p)| if p.is_finite() { *v } else { 1.0 }).collect();
                let facing = metrics::facing_light(&p, &nrm, &scene.lights[0]).unwrap_or_default();
                let mut acc = metrics::accuracy(&est, &truth.visibility, &facing).map_err(|e| format!("error: {e}"))?;
                if let Some(g) = metrics::ground_set(&scene, &truth.visibility, &p, &facing).map_err(|e| format!("error: {e}"))? {
                    acc.ground = Some(metrics::error_stats(&est, &truth.visibility, &g).map_err(|e| format!("error: {e}"))?);
                }
                rows.push(Row {
                    scene: stem(&file.scenes[sc]),
                    label: format!("{n} samples (CPU)"),
                    config: format!("samples={n}"),
                    shadow_map: 0,
                    light_scale: 1.0,
                    ms: None,
                    reference_ms: None,
                    peak_bytes: 0,
                    fetches: 0.0,
                    ops: 0.0,
                    acc,
                    truth_se: truth.max_std_error() as f64,
                });
                row_scenes.push(sc);
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    let medians: Vec<Option<f64>> = reference_runs
        .iter()
        .map(|r| {
            r.as_ref().and_then(|(_, t, _)| {
                let mut t = t.clone();
                t.sort_by(f64::total_cmp);
                t.get(t.len() / 2).copied()
            })
        })
        .collect();
    for (row, &sc) in rows.iter_mut().zip(&row_scenes) {
        row.reference_ms = medians[sc];
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("error: {}: {e}", a.out.display()))?;
    let write = |name: &str, text: &str| -> Result<(), String> {
        let p = a.out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("error: {}: {e}", p.display()))?;
        println!("wrote {}", p.display());
        Ok(())
    };
    write("sweep.csv", &csv(&rows, &device, a.shard))?;
    write("sweep.md", &markdown(&rows, &device, &file.reference, file.pixels))?;
    for scene in file.scenes.iter().map(|s| stem(s)) {
        let these: Vec<&Row> = rows.iter().filter(|r| r.scene == scene).collect();
        if these.iter().all(|r| r.ms.is_none()) {
            continue;
        }
        for (what, x_of, x_label) in [
            (
                "time",
                (|r: &Row| r.ratio()) as fn(&Row) -> Option<f64>,
                "GPU time per frame / reference technique's",
            ),
            (
                "memory",
                |r: &Row| (r.ms.is_some()).then_some(r.peak_bytes as f64 / (1 << 20) as f64),
                "peak memory (MiB)",
            ),
        ] {
            for ext in ["svg", "png"] {
                let p = a.out.join(format!("pareto-{scene}-{what}.{ext}"));
                let set = match file.pixels {
                    PixelSet::Penumbra => "penumbra",
                    PixelSet::ShadowOnGround => "shadow-on-ground",
                };
                pareto(
                    &p,
                    &these,
                    x_of,
                    x_label,
                    file.pixels,
                    &format!("{scene}: RMS {set} error vs {what} on {short}"),
                )?;
                println!("wrote {}", p.display());
            }
        }
    }
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

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).unwrap_or_default()
}

fn csv(rows: &[Row], device: &str, (si, sn): (usize, usize)) -> String {
    let mut s = String::from(
        "shard,device,scene,technique,config,shadow_map,light_scale,gpu_ms,reference_ms,time_ratio,peak_bytes,fetches,ops,rms_facing,max_facing,rms_penumbra,max_penumbra,facing_pixels,penumbra_pixels,truth_max_se,rms_ground,max_ground,ground_pixels\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{si}/{sn},\"{device}\",{},{},\"{}\",{},{},{},{},{},{},{:.0},{:.0},{:.3},{:.3},{:.3},{:.3},{},{},{:.5},{},{},{}",
            r.scene,
            r.label,
            r.config,
            r.shadow_map,
            r.light_scale,
            opt(r.ms, 4),
            opt(r.reference_ms, 4),
            opt(r.ratio(), 4),
            r.peak_bytes,
            r.fetches,
            r.ops,
            r.acc.facing.rms,
            r.acc.facing.max,
            r.acc.penumbra.rms,
            r.acc.penumbra.max,
            r.acc.facing.pixels,
            r.acc.penumbra.pixels,
            r.truth_se,
            opt(r.acc.ground.map(|g| g.rms), 3),
            opt(r.acc.ground.map(|g| g.max), 3),
            r.acc.ground.map(|g| g.pixels.to_string()).unwrap_or_default(),
        );
    }
    s
}

fn markdown(rows: &[Row], device: &str, reference: &str, pixels: PixelSet) -> String {
    let mut s = format!(
        "Device: {device}. Errors in 0..255 units against the ground truth (RMS over pixels facing the light, and over penumbra pixels{}); time as a ratio to `{reference}` timed in the same run (median of repeated frames).\n\n",
        match pixels {
            PixelSet::Penumbra => "",
            PixelSet::ShadowOnGround => ", first over Lawlor's shadow on the ground plane",
        }
    );
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let _ = writeln!(s, "### {scene}\n");
        let ground = pixels == PixelSet::ShadowOnGround;
        if ground {
            s.push_str("| technique | config | RMS shadow on ground | ");
        } else {
            s.push_str("| technique | config | ");
        }
        s.push_str("RMS facing | RMS penumbra | max penumbra | time ratio | GPU ms | peak MiB | fetches/frame | ops/frame |\n|---|---|---|---|---|---|---|---|---|---|");
        s.push_str(if ground { "---|\n" } else { "\n" });
        for r in rows.iter().filter(|r| r.scene == scene) {
            let first = if ground {
                format!(" {} |", opt(r.acc.ground.map(|g| g.rms), 2))
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "| {} | {} |{first} {:.2} | {:.2} | {:.1} | {} | {} | {:.2} | {:.3e} | {:.3e} |",
                r.label,
                r.config,
                r.acc.facing.rms,
                r.acc.penumbra.rms,
                r.acc.penumbra.max,
                opt(r.ratio(), 2),
                opt(r.ms, 2),
                r.peak_bytes as f64 / (1 << 20) as f64,
                r.fetches,
                r.ops
            );
        }
        s.push('\n');
    }
    s
}

/// The configurations no other one beats on both axes (lower x and lower error).
fn pareto_front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if front.last().is_none_or(|l| q.1 < l.1) {
            front.push(q);
        }
    }
    front
}

const FONT: &str = "sshc-sweep";

fn pareto(path: &Path, rows: &[&Row], x_of: fn(&Row) -> Option<f64>, x_label: &str, set: PixelSet, title: &str) -> Result<(), String> {
    let pts: Vec<(String, f64, f64)> = rows
        .iter()
        .filter_map(|r| Some((r.label.clone(), x_of(r)?, set.rms(r))))
        .filter(|(_, x, y)| x.is_finite() && y.is_finite() && *x > 0.0)
        .collect();
    if pts.is_empty() {
        return Err(format!("error: {}: nothing to plot", path.display()));
    }
    let svg = path.extension().is_some_and(|e| e == "svg");
    let size = (900, 600);
    // text is measured with the bundled font in both backends
    plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR)
        .map_err(|_| "error: the bundled font cannot be read".to_string())?;
    if svg {
        let root = SVGBackend::new(path, size).into_drawing_area();
        draw(&root, &pts, x_label, set.describe(), title, FONT)
    } else {
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
            draw(&root, &pts, x_label, set.describe(), title, FONT)?;
        }
        image::RgbImage::from_raw(size.0, size.1, buf)
            .ok_or_else(|| "error: chart buffer of the wrong size".to_string())?
            .save(path)
            .map_err(|e| format!("error: {}: {e}", path.display()))
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    pts: &[(String, f64, f64)],
    x_label: &str,
    y_label: &str,
    title: &str,
    font: &str,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("error: drawing a chart: {e}");
    root.fill(&WHITE).map_err(e)?;
    let (x0, x1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let y1 = pts.iter().fold(0.0f64, |a, p| a.max(p.2));
    let mut chart = ChartBuilder::on(root)
        .caption(title, (font, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(56)
        .build_cartesian_2d((x0 * 0.8..x1 * 1.25).log_scale(), 0.0..y1 * 1.1 + 1e-3)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((font, 13))
        .draw()
        .map_err(e)?;
    let mut labels: Vec<&str> = pts.iter().map(|p| p.0.as_str()).collect();
    labels.sort();
    labels.dedup();
    for (i, l) in labels.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let mine: Vec<(f64, f64)> = pts.iter().filter(|p| p.0 == *l).map(|p| (p.1, p.2)).collect();
        chart
            .draw_series(mine.iter().map(|&(x, y)| Circle::new((x, y), 5, colour.filled())))
            .map_err(e)?
            .label(*l)
            .legend(move |(x, y)| Circle::new((x, y), 5, colour.filled()));
    }
    let all: Vec<(f64, f64)> = pts.iter().map(|p| (p.1, p.2)).collect();
    chart
        .draw_series(LineSeries::new(pareto_front(&all), BLACK.stroke_width(1)))
        .map_err(e)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
    chart
        .configure_series_labels()
        // low error at low cost is the corner no technique reaches: the legend hides least there
        .position(SeriesLabelPosition::LowerLeft)
        .label_font((font, 13))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let f = pareto_front(&[(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (0.5, 9.0)]);
        assert_eq!(f, vec![(0.5, 9.0), (1.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
    }

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
