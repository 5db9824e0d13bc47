//! `sshc sweep` end to end on a sweep of under 20 configurations (tests/sweep.ron): the
//! CSV and Markdown hold one row per configuration with finite figures, the shards of a
//! split sweep together hold exactly the configurations of the whole, and the Pareto
//! charts are written as SVG and PNG. Shards merged by `sshc sweep merge` equal the
//! unsharded sweep, a shard stopped by a signal resumes, and every bad merge is refused
//! (docs/cluster.md). Runs on the GPU (lavapipe without one).
//!
//! One test binary, a module per job: `runs` (whole sweeps), `shards` (sharding, merging,
//! resuming), `slurm` (the job scripts). The helpers they share are here.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../common/mod.rs"]
mod common;

mod runs;
mod shards;
mod slurm;

fn run(out: &Path, extra: &[&str]) -> String {
    run_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweep.ron"), out, extra)
}

fn run_file(sweep: &Path, out: &Path, extra: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .arg("sweep")
        .arg(sweep)
        .arg("-o")
        .arg(out)
        .args(["--samples", "16", "--runs", "2", "--cache"])
        .arg(out.join("cache"))
        .args(extra)
        .env("LP_NUM_THREADS", "2")
        .output()
        .expect("sshc runs");
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "sshc sweep failed:\n{text}");
    std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv written")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sshc-sweep-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn sweep_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join(name)
}

/// `sshc ARGS`, its status and its standard output and error together.
fn sshc(args: &[&std::ffi::OsStr]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sshc"))
        .args(args)
        .env("LP_NUM_THREADS", "2")
        .output()
        .expect("sshc runs");
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    (o.status.success(), text)
}
