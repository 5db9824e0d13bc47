//! What `sshc tune` writes: `tuned.ron` (and a file per tier with `--ladder`, and
//! `tiers.ron`), `tune.csv` (every measurement), `tune.md` (the choice, its region split,
//! the generalisation gap, runners-up, the Pareto fronts with the chosen point marked,
//! each axis's sensitivity), the charts and the error images.

use super::search::{self, Candidate, Found, Measured, Outcome, Plan, Verdict, median};
use super::{Detail, Tuner};
use crate::cmd::sweep::chart::{Chart, Point, chart};
use crate::cmd::sweep::{SceneTruth, run_config};
use std::fmt::Write as _;
use std::path::Path;

/// Creates the output folder (and its parents).
pub(crate) fn create_out(out: &Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("error: cannot create `{}`: {e}", out.display()))
}

pub(crate) use crate::session::{writable, write_new};

/// What the tuner's time charts' error bars span: its repeated timings at the final rung
/// (`--repeats`), each the median of its frames.
const TUNE_SPREAD: &str = "error bars: fastest to slowest of the repeated timings (--repeats; the point: their median)";

/// The command line as typed, each word quoted where the shell would need it.
fn command_line() -> String {
    std::env::args()
        .map(|w| {
            if !w.is_empty() && w.chars().all(|c| c.is_ascii_alphanumeric() || "/._-+=:,@".contains(c)) {
                w
            } else {
                format!("'{}'", w.replace('\'', "'\\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A tier's result: the chosen configuration and what was measured of it afterwards.
struct Chosen {
    candidate: Candidate,
    measured: Measured,
    detail: Detail,
    /// The mean error on the held-out views (none without any).
    holdout: Option<f64>,
    /// The technique's defaults at the final fidelity, and on the held-out views.
    default: Option<(Measured, Detail)>,
    default_holdout: Option<f64>,
    /// (axis, value, error) of the chosen point's neighbours at the final fidelity.
    sensitivity: Vec<(String, String, f64)>,
}

fn detail_of(t: &Tuner, c: &Candidate, rung: usize) -> Option<(Measured, Detail)> {
    let e = &t.entries[c.technique];
    t.done
        .borrow()
        .get(&(e.label.clone(), c.describe(), rung))
        .and_then(|r| r.result.clone().ok())
}

/// The configuration that came closest to the budget, in words.
fn closest(t: &Tuner, found: &Found, plan: &Plan) -> String {
    // the final fidelity decides: a cheaper rung's single timing is only named where
    // nothing reached the final one
    let last = plan.rungs - 1;
    let at_last = found.steps.iter().any(|s| s.rung == last && s.measured().is_some());
    let best = found
        .steps
        .iter()
        .filter(|s| !at_last || s.rung == last)
        .filter_map(|s| Some((s, s.measured()?)))
        .min_by(|a, b| {
            let over = |m: &Measured| {
                let time = median(&m.times) / plan.time_limit;
                let mem = plan.memory_limit.map_or(0.0, |l| m.bytes as f64 / l as f64);
                time.max(mem)
            };
            over(a.1).total_cmp(&over(b.1))
        });
    match best {
        Some((s, m)) => {
            let mut w = format!(
                "the closest was {} {}: {:.3} {} against the budget's {:.3}",
                t.entries[s.candidate.technique].label,
                s.candidate.describe(),
                median(&m.times),
                t.budget.unit(),
                plan.time_limit
            );
            if !at_last {
                let _ = write!(w, " (a timing at a cheaper fidelity: nothing reached the final one)");
            }
            if let Some(l) = plan.memory_limit {
                let _ = write!(
                    w,
                    ", {:.2} MiB against {:.2} MiB",
                    m.bytes as f64 / (1 << 20) as f64,
                    l as f64 / (1 << 20) as f64
                );
            }
            let over = median(&m.times) / plan.time_limit;
            if over > 1.0 {
                let _ = write!(w, " ({:.0} % over)", (over - 1.0) * 100.0);
            }
            w
        }
        None => {
            let skipped = found.steps.iter().filter(|s| matches!(s.outcome, Outcome::Skipped(_))).count();
            let failed: Vec<String> = found
                .steps
                .iter()
                .filter_map(|s| match &s.outcome {
                    Outcome::Failed(e) => Some(e.clone()),
                    _ => None,
                })
                .take(3)
                .collect();
            format!(
                "nothing was measured: {skipped} configurations cannot meet the memory budget from their graphs alone{}",
                if failed.is_empty() {
                    String::new()
                } else {
                    format!("; failures: {}", failed.join("; "))
                }
            )
        }
    }
}

fn finish(t: &Tuner, plan: &Plan, candidate: Candidate, measured: Measured) -> Result<Chosen, String> {
    let last = plan.rungs - 1;
    let samples = t.samples(last);
    let detail = detail_of(t, &candidate, last).map(|(_, d)| d).unwrap_or_default();
    let holdout = if t.a.holdout > 0 {
        Some(t.measure_on(&candidate, 0, true, samples, 1)?.0.error)
    } else {
        None
    };
    let default_c = Candidate {
        technique: candidate.technique,
        values: vec![],
    };
    let default = match detail_of(t, &default_c, last) {
        Some(d) => Some(d),
        None => t.measure_on(&default_c, t.a.views + 1, false, samples, t.a.repeats.max(1)).ok(),
    };
    let default_holdout = if t.a.holdout > 0 && default.is_some() {
        t.measure_on(&default_c, 0, true, samples, 1).ok().map(|(m, _)| m.error)
    } else {
        None
    };
    // each axis's sensitivity: the neighbours at the final fidelity (measured by the
    // refinement, or here)
    let axes = super::search::varying(
        &t.entries[candidate.technique].space,
        t.scenes.iter().all(|s| s.train[0].lights[0].is_distant()),
    );
    let mut sensitivity = Vec::new();
    for n in super::search::neighbours(&candidate, &axes) {
        let (axis, value) = n
            .values
            .iter()
            .find(|kv| !candidate.values.contains(kv))
            .cloned()
            .or_else(|| {
                candidate.values.iter().find(|kv| !n.values.contains(kv)).map(|(k, _)| {
                    (
                        k.clone(),
                        axes.iter()
                            .find(|a| a.name == *k)
                            .and_then(|a| a.default.clone())
                            .unwrap_or_default(),
                    )
                })
            })
            .unwrap_or_default();
        let m = match detail_of(t, &n, last) {
            Some((m, _)) => Ok(m),
            None => t.measure(&n, last),
        };
        if let Ok(m) = m {
            sensitivity.push((axis, value, m.error));
        }
    }
    Ok(Chosen {
        candidate,
        measured,
        detail,
        holdout,
        default,
        default_holdout,
        sensitivity,
    })
}

/// The chosen configuration's values for `tuned.ron`: its own, with the shadow-map size
/// always recorded (the first scene's where the search left it).
fn tuned_values(t: &Tuner, c: &Candidate) -> Vec<(String, String)> {
    let mut v = c.values.clone();
    if c.value("shadow_map").is_none() {
        let n = t.entries[c.technique].space.shadow_map.unwrap_or(t.scenes[0].train[0].shadow_map);
        v.push(("shadow_map".into(), n.to_string()));
    }
    v
}

fn tuned_file(t: &Tuner, plan: &Plan, ch: &Chosen, tier: Option<&str>) -> Result<String, String> {
    let e = &t.entries[ch.candidate.technique];
    let mut header = vec![
        format!(
            "Tuned by `sshc tune`{}: {} ({}) {}",
            tier.map(|t| format!(" ({t} tier)")).unwrap_or_default(),
            e.label,
            e.path.display(),
            ch.candidate.describe()
        ),
        format!(
            "budget: {} (this tier: {:.3} {})",
            t.budget.words(),
            plan.time_limit,
            t.budget.unit()
        ),
        format!(
            "scenes: {} ({} training views each, {} held out, light jitter {})",
            t.scenes.iter().map(|s| s.path.display().to_string()).collect::<Vec<_>>().join(", "),
            t.a.views + 1,
            t.a.holdout,
            t.a.light_jitter
        ),
        format!(
            "measured: {} {:.4} (FLIP {:.4}, RMS facing {:.2}, RMS penumbra {:.2}; lit mean {:+.2}, umbra mean {:+.2}, 0..255), time {:.3} {} (timings {}), {:.2} MiB",
            t.a.metric,
            ch.measured.error,
            ch.detail.flip,
            ch.detail.rms_facing,
            ch.detail.rms_penumbra,
            ch.detail.lit_mean,
            ch.detail.umbra_mean,
            median(&ch.measured.times),
            t.budget.unit(),
            ch.measured.times.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>().join(" "),
            ch.measured.bytes as f64 / (1 << 20) as f64
        ),
        format!("on: {}", t.gpu.describe()),
        format!("command: {}", command_line()),
    ];
    if let Some(c) = ch.candidate.value("cascades") {
        header.push(format!(
            "cascades: {c} (a host's or command's `--cascades {c}`; a technique file does not hold it)"
        ));
    }
    header.push(String::new());
    let text = sshc::tune::rewrite(&e.source, &tuned_values(t, &ch.candidate), &header).map_err(|d| {
        crate::session::report(&d, &e.path, &e.source);
        format!("error: internal: the tuned values of {} do not make a technique file", e.label)
    })?;
    // what every part of sshc loads: it must compile
    sshc::compile_str(&text, &Default::default()).map_err(|d| {
        crate::session::report(&d, Path::new("tuned.ron"), &text);
        "error: internal: tuned.ron does not compile".to_string()
    })?;
    Ok(text)
}

/// The error images of the chosen configuration and of its technique's defaults on the
/// first scene's own view, in one colour range.
fn error_images(t: &Tuner, ch: &Chosen) -> Result<(), String> {
    let e = &t.entries[ch.candidate.technique];
    let sv = &t.scenes[0];
    let mut runs = Vec::new();
    for c in [
        ch.candidate.clone(),
        Candidate {
            technique: ch.candidate.technique,
            values: vec![],
        },
    ] {
        let s = t.settings_of(&c)?;
        let mut scene = sv.train[0].clone();
        s.apply(&mut scene)?;
        let ran = run_config(t.gpu, &e.path, &e.source, &scene, &sv.path, &s, &Default::default(), 1)?;
        runs.push((ran, scene));
    }
    let opts = crate::session::TruthOpts {
        samples: t.samples(t.a.rungs - 1),
        ..t.a.truth.clone()
    };
    let truth = SceneTruth::at(&runs[0].0.ex, &runs[0].1, &opts, |f| f())?;
    let range = runs
        .iter()
        .map(|(r, _)| crate::metrics::error_range(&r.visibility, &truth.visibility, &truth.facing))
        .collect::<Result<Vec<f64>, _>>()
        .map_err(|e| format!("error: {e}"))?
        .into_iter()
        .fold(4.0f64, f64::max);
    let (w, h) = runs[0].1.camera_size();
    for ((r, _), name) in runs.iter().zip(["error-chosen.png", "error-default.png"]) {
        let img = crate::metrics::error_image(&r.visibility, &truth.visibility, Some(&truth.facing), w, h, range)
            .map_err(|e| format!("error: {e}"))?;
        let p = t.a.out.join(name);
        crate::session::save_image(&img, &p)?;
    }
    Ok(())
}

fn csv(t: &Tuner, tiers: &[(f64, Plan, Found)]) -> String {
    let mut s = String::from(
        "tier,budget,technique,config,rung,samples,views,outcome,error,flip,rms_facing,rms_penumbra,lit_mean,penumbra_mean,umbra_mean,time_median,time_min,time_max,mib,fetches,ops,verdict,chosen\n",
    );
    for (k, (limit, plan, found)) in tiers.iter().enumerate() {
        for st in &found.steps {
            let e = &t.entries[st.candidate.technique];
            let head = format!("{k},{limit},{},\"{}\",{},", e.label, st.candidate.describe(), st.rung);
            match &st.outcome {
                Outcome::Measured(m) => {
                    let d = detail_of(t, &st.candidate, st.rung).map(|(_, d)| d).unwrap_or_default();
                    let lo = m.times.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = m.times.iter().copied().fold(0.0, f64::max);
                    let _ = writeln!(
                        s,
                        "{head}{},{},measured,{:.6},{:.6},{:.4},{:.4},{:.4},{:.4},{:.4},{:.5},{lo:.5},{hi:.5},{:.4},{:.4e},{:.4e},{:?},{}",
                        d.samples,
                        d.views,
                        m.error,
                        d.flip,
                        d.rms_facing,
                        d.rms_penumbra,
                        d.lit_mean,
                        d.penumbra_mean,
                        d.umbra_mean,
                        median(&m.times),
                        m.bytes as f64 / (1 << 20) as f64,
                        d.fetches,
                        d.ops,
                        plan.verdict(m),
                        st.rung + 1 == plan.rungs && found.best.as_ref().is_some_and(|(c, _)| *c == st.candidate)
                    );
                }
                Outcome::Skipped(why) | Outcome::Failed(why) => {
                    let what = if matches!(st.outcome, Outcome::Skipped(_)) {
                        "skipped"
                    } else {
                        "failed"
                    };
                    let _ = writeln!(s, "{head},,{what}: {},,,,,,,,,,,,,,,false", why.replace([',', '"', '\n'], " "));
                }
            }
        }
    }
    s
}

fn tier_name(k: usize, n: usize) -> &'static str {
    const NAMES: [&str; 8] = ["low", "medium", "high", "ultra", "extreme", "tier6", "tier7", "tier8"];
    if n == 1 { "tuned" } else { NAMES[k.min(7)] }
}

/// Writes every output; an error (after writing the CSV and Markdown) where a tier's
/// budget is met by no configuration, naming the closest.
pub(crate) fn write(t: &Tuner, tiers: &[(f64, Plan, Found)]) -> Result<(), String> {
    let out = &t.a.out;
    write_new(&out.join("tune.csv"), csv(t, tiers))?;
    let mut md = String::new();
    let _ = writeln!(md, "# sshc tune\n");
    let _ = writeln!(md, "Command: `{}`\n", command_line());
    let _ = writeln!(md, "Device: {}\n", t.gpu.describe());
    let _ = writeln!(
        md,
        "Budget: {}. Metric: {} (FLIP over the pixels facing the light, RMS 0..255 otherwise). Scenes: {}.\n",
        t.budget.words(),
        t.a.metric,
        t.scenes
            .iter()
            .map(|s| format!("`{}`", s.path.display()))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut unmet = Vec::new();
    let mut tier_rows = Vec::new();
    for (k, (limit, plan, found)) in tiers.iter().enumerate() {
        let name = tier_name(k, tiers.len());
        let measured = found.evaluations();
        let skipped = found.steps.iter().filter(|s| matches!(s.outcome, Outcome::Skipped(_))).count();
        let failed = found.steps.iter().filter(|s| matches!(s.outcome, Outcome::Failed(_))).count();
        let _ = writeln!(md, "## {} (budget {:.3} {})\n", name, limit, t.budget.unit());
        let _ = writeln!(
            md,
            "{measured} measurements ({} at the final fidelity: {} truth samples per run, {} views per scene), {skipped} skipped before running (over the memory budget from the graph, or dominated by a configuration over the time budget), {failed} that do not compile or bind.\n",
            found
                .steps
                .iter()
                .filter(|s| s.rung + 1 == plan.rungs && s.measured().is_some())
                .count(),
            t.samples(plan.rungs - 1),
            t.a.views + 1
        );
        let Some((c, m)) = found.best.clone() else {
            let why = closest(t, found, plan);
            let _ = writeln!(md, "No configuration meets this budget: {why}.\n");
            unmet.push(format!(
                "{name}: no configuration meets the budget of {limit:.3} {}: {why}",
                t.budget.unit()
            ));
            continue;
        };
        let before = *t.measured_now.borrow();
        let ch = finish(t, plan, c, m)?;
        let extra = *t.measured_now.borrow() - before;
        let _ = writeln!(
            md,
            "The report measured {extra} more configurations at the final fidelity (the chosen point's neighbours, for the sensitivity{}), and the chosen configuration and its technique's defaults on the {} held-out views.\n",
            if ch.default.is_some() { ", and the defaults" } else { "" },
            t.a.holdout
        );
        let e = &t.entries[ch.candidate.technique];
        let file = if tiers.len() == 1 {
            "tuned.ron".to_string()
        } else {
            format!("tier-{name}.ron")
        };
        let text = tuned_file(t, plan, &ch, (tiers.len() > 1).then_some(name))?;
        write_new(&out.join(&file), &text)?;
        if tiers.len() > 1 && k + 1 == tiers.len() {
            // the highest tier is also `tuned.ron`
            write_new(&out.join("tuned.ron"), &text)?;
        }
        let verdict = match plan.verdict(&ch.measured) {
            Verdict::Within => "within the budget at every timing",
            Verdict::Noise => "within the budget by its median, but its timings straddle it (marked: within the noise)",
            Verdict::Over => "over the budget",
        };
        let _ = writeln!(
            md,
            "**Chosen**: `{}` {} → [`{file}`]({file}), {verdict}.\n",
            e.label,
            ch.candidate.describe()
        );
        let _ = writeln!(
            md,
            "| | {} | FLIP | RMS facing | RMS penumbra | lit mean | penumbra mean | umbra mean | time ({}) | MiB | held-out {} | gap |",
            t.a.metric,
            t.budget.unit(),
            t.a.metric
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|");
        let row = |md: &mut String, what: &str, m: &Measured, d: &Detail, h: Option<f64>| {
            let _ = writeln!(
                md,
                "| {what} | {:.4} | {:.4} | {:.2} | {:.2} | {:+.2} | {:+.2} | {:+.2} | {:.3} ({}) | {:.2} | {} | {} |",
                m.error,
                d.flip,
                d.rms_facing,
                d.rms_penumbra,
                d.lit_mean,
                d.penumbra_mean,
                d.umbra_mean,
                median(&m.times),
                m.times.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>().join(", "),
                m.bytes as f64 / (1 << 20) as f64,
                h.map_or("-".into(), |h| format!("{h:.4}")),
                h.map_or("-".into(), |h| format!("{:+.4}", h - m.error)),
            );
        };
        row(&mut md, "chosen", &ch.measured, &ch.detail, ch.holdout);
        if let Some((m, d)) = &ch.default {
            row(&mut md, &format!("{} defaults", e.label), m, d, ch.default_holdout);
        }
        let _ = writeln!(
            md,
            "\nErrors are means over the scenes and training views (0..255 but FLIP); the region means are signed (technique − truth): a negative lit mean is acne or darkening, a positive umbra or penumbra mean is light leaking or peter-panning. The gap is the held-out views' error less the training views'.\n"
        );
        // runners-up
        let finals = found.finals(plan);
        let _ = writeln!(md, "Runners-up at the final fidelity:\n");
        let _ = writeln!(
            md,
            "| technique | configuration | {} | time ({}) | MiB | verdict |\n|---|---|---|---|---|---|",
            t.a.metric,
            t.budget.unit()
        );
        for (c, m) in finals.iter().filter(|(c, _)| **c != ch.candidate).take(6) {
            let _ = writeln!(
                md,
                "| {} | {} | {:.4} | {:.3} | {:.2} | {:?} |",
                t.entries[c.technique].label,
                c.describe(),
                m.error,
                median(&m.times),
                m.bytes as f64 / (1 << 20) as f64,
                plan.verdict(m)
            );
        }
        // sensitivity
        let _ = writeln!(md, "\nSensitivity at the chosen point (one axis moved, the rest kept):\n");
        let _ = writeln!(md, "| axis | value | {} | change |\n|---|---|---|---|", t.a.metric);
        for (axis, value, err) in &ch.sensitivity {
            let _ = writeln!(md, "| {axis} | {value} | {err:.4} | {:+.4} |", err - ch.measured.error);
        }
        // charts of the final fidelity, the chosen point marked
        let point = |c: &Candidate, x: f64, m: &Measured, spread: bool| Point {
            technique: t.entries[c.technique].label.clone(),
            config: c.describe(),
            x,
            y: m.error,
            spread: spread.then(|| search::spread(&m.times)).flatten(),
        };
        let pts: Vec<Point> = finals.iter().map(|(c, m)| point(c, median(&m.times), m, true)).collect();
        let mem: Vec<Point> = finals
            .iter()
            .map(|(c, m)| point(c, m.bytes as f64 / (1 << 20) as f64, m, false))
            .collect();
        let label = format!("chosen: {}", e.label);
        let time_chart = format!("pareto-{name}-time.png");
        let mem_chart = format!("pareto-{name}-memory.png");
        writable(&out.join(&time_chart))?;
        writable(&out.join(&mem_chart))?;
        chart(
            &out.join(&time_chart),
            &pts,
            &Chart {
                title: &format!("sshc tune: the final fidelity's configurations ({name})"),
                x_label: &format!("GPU time ({}, log)", t.budget.unit()),
                y_label: &t.a.metric,
                spread: TUNE_SPREAD,
                mark: Some((median(&ch.measured.times), ch.measured.error, &label)),
            },
        )?;
        chart(
            &out.join(&mem_chart),
            &mem,
            &Chart {
                title: &format!("sshc tune: error against memory ({name})"),
                x_label: "texture and buffer MiB (log)",
                y_label: &t.a.metric,
                spread: TUNE_SPREAD,
                mark: Some((ch.measured.bytes as f64 / (1 << 20) as f64, ch.measured.error, &label)),
            },
        )?;
        let _ = writeln!(md, "\n![error against time]({time_chart})\n![error against memory]({mem_chart})\n");
        if k + 1 == tiers.len() {
            error_images(t, &ch)?;
            let _ = writeln!(
                md,
                "| chosen: signed error | {} defaults: signed error |\n|---|---|\n| ![chosen](error-chosen.png) | ![defaults](error-default.png) |\n\n(first scene's own view, one colour range: red too bright, blue too dark)\n",
                e.label
            );
        }
        tier_rows.push(format!(
            "        (name: \"{name}\", budget: {limit}, file: \"{file}\", technique: \"{}\", config: \"{}\", error: {:.6}, time: {:.4}),",
            e.label,
            ch.candidate.describe(),
            ch.measured.error,
            median(&ch.measured.times)
        ));
        println!(
            "tune: {name}: {} {}: {} {:.4} (FLIP {:.4}, RMS facing {:.2}; lit mean {:+.2}, umbra mean {:+.2}), time {:.3} {}, {:.2} MiB; held-out gap {}",
            e.label,
            ch.candidate.describe(),
            t.a.metric,
            ch.measured.error,
            ch.detail.flip,
            ch.detail.rms_facing,
            ch.detail.lit_mean,
            ch.detail.umbra_mean,
            median(&ch.measured.times),
            t.budget.unit(),
            ch.measured.bytes as f64 / (1 << 20) as f64,
            ch.holdout.map_or("-".into(), |h| format!("{:+.4}", h - ch.measured.error))
        );
    }
    if tiers.len() > 1 {
        let text = format!(
            "// Quality tiers tuned by `sshc tune` ({}), low to high.\n// command: {}\n(\n    unit: \"{}\",\n    tiers: [\n{}\n    ],\n)\n",
            t.budget.words(),
            command_line(),
            t.budget.unit(),
            tier_rows.join("\n")
        );
        write_new(&out.join("tiers.ron"), &text)?;
    }
    write_new(&out.join("tune.md"), &md)?;
    println!("wrote {}", out.join("tune.md").display());
    if unmet.is_empty() {
        Ok(())
    } else {
        Err(format!("error: {}", unmet.join("\nerror: ")))
    }
}
