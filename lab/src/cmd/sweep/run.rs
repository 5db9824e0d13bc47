//! A sweep's run of one shard (the whole sweep unsharded): its configurations and CPU
//! baselines, what an earlier run of the same shard left in the output folder carried on
//! from ([`resume`]), each row appended to the folder's records as it is measured beside
//! the reference's timings, the progress shown, and the outputs written from the folder as
//! the merge reads it; `--redraw` draws them again from `sweep.csv`.

use super::SweepArgs;
use super::file::{Config, Loaded, configs, load, settings};
use super::measure::{Ran, SceneTruth, compile, run_config, time_frames};
use crate::cmd::sweep::report::{self, Outputs, Row, split_entry, stem};
use crate::cmd::sweep::shard::{self, Done, Log, Manifest, Record};
use crate::metrics;
use crate::session::{TruthOpts, positions_normals, read, rt, truth_at};
use sshc_runtime::gpu::Gpu;
use std::io::IsTerminal as _;
use std::path::Path;
use std::time::Instant;

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

pub(super) fn run(a: SweepArgs) -> Result<(), String> {
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
    let run_first = "help: --redraw draws what a run of this sweep wrote into -o; run the sweep there first (without --redraw)";
    let text = crate::session::read_capped(&path, report::MAX_CSV_BYTES).map_err(|e| format!("{e}\n{run_first}"))?;
    let rows = report::read_csv(&path, &text)?;
    if rows.is_empty() {
        return Err(format!("error: {}: no rows to draw\n{run_first}", path.display()));
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
