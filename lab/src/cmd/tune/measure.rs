//! The tuner's measurements ([`Tuner`]): a configuration measured on the views of a
//! fidelity, timed beside the reference (the sweep's measuring step), memoised with the
//! records resumed and each new one logged; with `--shard`, a batch's configurations shared
//! out between the shards; and what the work model lets the search skip before running it.

use super::TuneArgs;
use super::records::{Record, read_records, records_files, records_name};
use super::search::{self, Candidate, Measured};
use super::setup::{Budget, Entry, SceneViews};
use crate::cmd::sweep::{Config, Ran, SceneTruth, run_config, settings};
use crate::scene::Scene;
use crate::session::TruthOpts;
use sshc_runtime::gpu::Gpu;
use std::cell::RefCell;
use std::collections::HashMap;
use std::time::Instant;

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
    pub(super) truths: RefCell<HashMap<(usize, usize, bool, u32), SceneTruth>>,
    /// Measurements by (technique, config, rung): those of this run and those resumed.
    pub done: RefCell<HashMap<(String, String, usize), Record>>,
    pub(super) log: RefCell<Option<std::fs::File>>,
    /// (technique, cost class, fetches, operations, fastest time figure) of every measured
    /// configuration: the fastest rates of fetches and operations a technique's cost class
    /// reached on this device, from which [`Tuner::skip`] bounds an unmeasured one's time.
    pub(super) rates: RefCell<Vec<Rate>>,
    /// Rates measured since the last batch: they join `rates` at the next, so that no
    /// measurement in a batch decides a skip in the same batch (shards agree on skips).
    pub(super) pending: RefCell<Vec<Rate>>,
    /// Fetches, operations and shadow-map bytes per frame of each candidate's graph (the
    /// compiler's counts at the first scene's sizes), by technique and configuration.
    pub(super) work: RefCell<HashMap<(usize, String), Option<Work>>>,
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
