//! `sshc sweep merge DIR... -o OUT`: the shards of one sweep, run anywhere (the tasks of
//! a Slurm array, several machines), into what an unsharded run writes: `sweep.csv`,
//! `sweep.md` and the charts. Each shard folder holds all the merge reads (its
//! `shard.ron` and `records.ron`, [`crate::cmd::sweep::shard`]); the sweep file and its
//! inputs need not be there.
//!
//! Refused, each shard named with the reason (every problem is listed, not the first
//! alone): a folder that is not a shard; shards of different sweeps (the sweep file, a
//! file it pulls in or the measurement options differ), of different code, or of
//! different counts; two folders of the same shard; a missing shard; an unfinished shard.
//! Devices may differ: the outputs say which shard ran where, and each row's time ratio
//! is against the reference its own shard timed.

use crate::cmd::sweep::report::{self, Outputs, Row};
use crate::cmd::sweep::shard::{self, Done, Manifest};
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// Shard folders (`sshc sweep S.ron --shard i/n -o DIR`): every shard of one sweep,
    /// once each, in any order.
    #[arg(required = true, value_name = "DIR")]
    pub shards: Vec<PathBuf>,
    /// Output folder: sweep.csv, sweep.md and the Pareto charts, as an unsharded run writes.
    #[arg(short, long)]
    pub out: PathBuf,
}

/// One shard read.
struct Shard {
    dir: PathBuf,
    manifest: Manifest,
    done: Done,
}

fn name(dir: &Path) -> String {
    dir.display().to_string()
}

/// The shard folders' problems, if any (each a line naming the shard), else the shards
/// in index order.
fn check(shards: Vec<Shard>) -> Result<Vec<Shard>, Vec<String>> {
    // each manifest holds a split some run writes (`Manifest::impossible`, at read)
    let mut problems = Vec::new();
    let first = &shards[0];
    let (a, am) = (name(&first.dir), &first.manifest);
    for s in &shards[1..] {
        let (b, bm) = (name(&s.dir), &s.manifest);
        if bm.format != am.format {
            problems.push(format!(
                "{b} is a shard of format {}, {a} of format {}: written by different versions of sshc",
                bm.format, am.format
            ));
        } else if bm.identity != am.identity {
            problems.push(format!(
                "{b} is a shard of another sweep than {a} ({} there, {} here): {}",
                am.sweep,
                bm.sweep,
                shard::input_changes(am, bm)
            ));
        } else if bm.code != am.code {
            problems.push(format!(
                "{b} was run by other code than {a} ({} against {}): run every shard with one build",
                bm.code, am.code
            ));
        } else if (bm.configurations, bm.baselines, &bm.scenes) != (am.configurations, am.baselines, &am.scenes) {
            problems.push(format!(
                "{b} counts {} configurations, {} baselines and {} scenes, {a} {}, {} and {}: one sweep has one count; a shard.ron was changed",
                bm.configurations,
                bm.baselines,
                bm.scenes.len(),
                am.configurations,
                am.baselines,
                am.scenes.len()
            ));
        } else if bm.shard.1 != am.shard.1 {
            problems.push(format!(
                "{b} is shard {}/{}, but {a} is one of {}: the shards of one split have one count",
                bm.shard.0, bm.shard.1, am.shard.1
            ));
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    let n = am.shard.1;
    let mut by_index: std::collections::BTreeMap<usize, Vec<&Shard>> = Default::default();
    for s in &shards {
        by_index.entry(s.manifest.shard.0).or_default().push(s);
    }
    // the missing ones, named up to a few
    const NAMED: usize = 8;
    let missing: Vec<usize> = (0..n).filter(|i| !by_index.contains_key(i)).take(NAMED + 1).collect();
    for &i in missing.iter().take(NAMED) {
        problems.push(format!(
            "shard {i}/{n} is missing: no folder given holds it (run `sshc sweep {} --shard {i}/{n} -o DIR` and name DIR)",
            am.sweep
        ));
    }
    if missing.len() > NAMED {
        problems.push(format!("and {} more of the {n} shards are missing", n - by_index.len() - NAMED));
    }
    for (i, these) in &by_index {
        if these.len() > 1 {
            let dirs: Vec<String> = these.iter().map(|s| name(&s.dir)).collect();
            problems.push(format!("{} all hold shard {i}/{n}: give each shard once", dirs.join(" and ")));
        }
    }
    for s in &shards {
        let m = &s.manifest;
        let (what, fix) = if !m.finished {
            ("is unfinished:", "run its command again to resume it")
        } else if s.done.rows.len() != m.rows {
            (
                "says it finished but holds",
                "its records.ron was changed; run the shard again with --fresh",
            )
        } else {
            continue;
        };
        problems.push(format!(
            "{} (shard {}/{}) {what} {} of its {} rows done; {fix}",
            name(&s.dir),
            m.shard.0,
            m.shard.1,
            s.done.rows.len(),
            m.rows
        ));
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    let mut shards = shards;
    shards.sort_by_key(|s| s.manifest.shard.0);
    Ok(shards)
}

pub fn merge(a: MergeArgs) -> Result<(), String> {
    let mut shards = Vec::new();
    let mut problems = Vec::new();
    for dir in &a.shards {
        match shard::read_manifest(dir) {
            Ok(Some(manifest)) => match shard::read_records(dir, false, &manifest) {
                Ok((done, _)) => shards.push(Shard {
                    dir: dir.clone(),
                    manifest,
                    done,
                }),
                Err(e) => problems.push(e.trim_start_matches("error: ").to_string()),
            },
            Ok(None) => problems.push(format!(
                "{} is not a shard folder: it has no {} (written by `sshc sweep S.ron --shard i/n -o DIR`)",
                dir.display(),
                shard::MANIFEST
            )),
            Err(e) => problems.push(e.trim_start_matches("error: ").to_string()),
        }
    }
    if problems.is_empty() {
        match check(shards) {
            Ok(s) => shards = s,
            Err(p) => {
                problems = p;
                shards = Vec::new();
            }
        }
    }
    if !problems.is_empty() {
        let lines: Vec<String> = problems.iter().map(|p| format!("error: {p}")).collect();
        return Err(format!("{}\nerror: nothing merged", lines.join("\n")));
    }
    let m0 = shards[0].manifest.clone();
    // the rows of every shard, in the order of the sweep's configurations
    let mut rows: Vec<(usize, Row)> = Vec::new();
    for s in &shards {
        let gathered = s.done.gathered(&s.manifest);
        rows.extend(s.done.rows.keys().copied().zip(gathered));
    }
    rows.sort_by_key(|(i, _)| *i);
    let expected = m0.configurations + m0.baselines;
    if rows.len() != expected || rows.iter().enumerate().any(|(k, (i, _))| k != *i) {
        // each shard holds its own rows, as many as its split gives it (checked at read and
        // above): only shards of one sweep disagreeing on it reach here
        return Err(format!(
            "error: the shards hold {} rows where the sweep has {expected} (configurations and baselines), each once: their records.ron were changed; run them again with --fresh\nerror: nothing merged",
            rows.len()
        ));
    }
    let rows: Vec<Row> = rows.into_iter().map(|(_, r)| r).collect();
    print_summary(&shards, &rows);
    report::write(
        &a.out,
        &Outputs {
            rows: &rows,
            scenes: &m0.scenes,
            reference: &m0.reference,
            pixels: m0.pixels,
        },
    )
}

/// Per shard: its device, rows, runs and wall times, and its reference times; then the
/// devices.
fn print_summary(shards: &[Shard], rows: &[Row]) {
    let m0 = &shards[0].manifest;
    println!(
        "merge: {} shards of {} ({} rows, code {})",
        shards.len(),
        m0.sweep,
        rows.len(),
        m0.code
    );
    for s in shards {
        let m = &s.manifest;
        let runs: Vec<String> = m
            .runs
            .iter()
            .map(|r| match r.seconds {
                Some(t) => format!("{:.1} s on {} (from row {})", t, r.host, r.resumed_at),
                None => format!("stopped on {} (from row {})", r.host, r.resumed_at),
            })
            .collect();
        let reference: Vec<String> = s
            .done
            .reference
            .iter()
            .map(|(scene, t)| {
                let mut t = t.clone();
                t.sort_by(f64::total_cmp);
                let name = m.scenes.get(*scene).map_or_else(|| scene.to_string(), |e| report::stem(e));
                format!("{name} {:.4} ms (median of {})", t[t.len() / 2], t.len())
            })
            .collect();
        println!(
            "  shard {}/{}: {} row{} on {}; runs: {}; reference {}",
            m.shard.0,
            m.shard.1,
            s.done.rows.len(),
            if s.done.rows.len() == 1 { "" } else { "s" },
            m.device.1,
            runs.join(", "),
            if reference.is_empty() {
                "not timed".to_string()
            } else {
                reference.join(", ")
            }
        );
    }
    let devices = report::devices(rows);
    if devices.len() > 1 {
        println!(
            "merge: {} devices; each row's time ratio is against the reference timed on its own shard's device:",
            devices.len()
        );
        for (d, s) in devices {
            let s: Vec<String> = s.iter().map(|(i, n)| format!("{i}/{n}")).collect();
            println!("  {} (shards {})", d.0, s.join(", "));
        }
    } else if let Some((d, _)) = devices.first() {
        println!("merge: one device, {}", d.0);
    }
}
