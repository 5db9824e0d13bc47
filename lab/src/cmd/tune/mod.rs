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
//!
//! The files: `setup.rs` what takes part (the techniques and their search spaces, each
//! scene's views, the budget), `measure.rs` the tuner's measurements (a configuration
//! measured on the views beside the reference, memoised and logged; the shards' batches;
//! what the work model lets the search skip), `records.rs` the records read back and a run
//! resumed, [`search`] the successive halving apart from the GPU, [`report`] the outputs,
//! [`slurm`] the `--slurm` array script.

mod measure;
mod records;
pub mod report;
pub mod search;
mod setup;
pub mod slurm;

pub use measure::Detail;
pub(crate) use measure::Tuner;
use records::resume;
pub use setup::{Budget, Entry, SceneViews, bundled_dir};
use setup::{load_technique, scene_views};

use crate::cmd::sweep::duration;
use crate::session::{TruthOpts, load_scene, read_capped, rt};
use search::Plan;
use sshc_runtime::gpu::Gpu;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

/// The largest technique or scene file the tuner reads (bytes).
const MAX_SOURCE_BYTES: u64 = 4 << 20;

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
