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
//!
//! The files: `file.rs` the sweep file, read and checked, and its configurations;
//! `measure.rs` one configuration measured and a scene's truth (the one measuring step of
//! `sshc sweep` and `sshc tune`); `run.rs` a shard's run, resumed where an earlier one
//! stopped, and its outputs; `write_slurm.rs` `--slurm`; besides [`report`], [`shard`],
//! [`merge`], [`slurm`] and [`chart`] (the Pareto charts, shared with `sshc tune`).

pub mod chart;
mod file;
mod measure;
pub mod merge;
pub mod report;
mod run;
pub mod shard;
pub mod slurm;
mod write_slurm;

pub use file::MAX_STOCHASTIC_SAMPLES;
pub(crate) use file::{Config, Settings, settings};
pub(crate) use measure::{Ran, SceneTruth, run_config};
pub(crate) use run::duration;
use run::run;
use write_slurm::write_slurm;

use crate::session::TruthOpts;
use std::path::PathBuf;

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

pub fn sweep(c: SweepCommand) -> Result<(), String> {
    match c.action {
        Some(Action::Merge(m)) => merge::merge(m),
        None if c.run.slurm.slurm => write_slurm(c.run),
        None => run(c.run),
    }
}
