//! `sshc truth` and `sshc compare` end to end on a real adapter (lavapipe on machines
//! without a GPU), at tiny resolutions. They never skip: with no adapter the commands
//! fail, and so do these tests (`scripts/test.sh` installs lavapipe).
//!
//! One test binary (a binary of its own per command would link wgpu each time), a module
//! per command or concern: `compile`, `render`, `truth`, `compare`, `verify`, `refusals`
//! (inputs refused and their messages), `outputs` (where commands write). The helpers
//! they share are here.

use std::path::Path;
use std::process::{Command, Output};

#[path = "../common/mod.rs"]
mod common;
use common::root;

mod compare;
mod compile;
mod outputs;
mod refusals;
mod render;
mod truth;
mod verify;

/// `sshc ARGS` from the repository's root, on lavapipe's two threads.
fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sshc"));
    c.args(args)
        .current_dir(root())
        .env("LP_NUM_THREADS", std::env::var("LP_NUM_THREADS").unwrap_or_else(|_| "2".into()))
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
        );
    c
}

fn sshc(args: &[&str]) -> Output {
    command(args).output().expect("the sshc binary runs")
}

/// Runs `sshc` and returns its standard output; fails with its output when it fails.
fn ok(args: &[&str]) -> String {
    let out = sshc(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "sshc {} failed ({}):\n{stdout}\n{}",
        args.join(" "),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// The number printed right after `label` in `out`.
fn number_after(label: &str, out: &str) -> f64 {
    let rest = &out[out.find(label).unwrap_or_else(|| panic!("{label}: {out}")) + label.len()..];
    let token: String = rest.trim_start().chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
    token.parse().unwrap_or_else(|_| panic!("no number after `{label}` in:\n{out}"))
}

fn read_pfm(path: &Path) -> pxm::PFM {
    let mut f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pxm::PFM::read_from(&mut f).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs `sshc` expecting a refusal within `secs` seconds; returns its standard error.
fn refused(args: &[&str], secs: u64) -> String {
    let start = std::time::Instant::now();
    let out = sshc(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "sshc {} succeeded:\n{stderr}", args.join(" "));
    assert!(
        start.elapsed().as_secs() < secs,
        "sshc {} took {:?}",
        args.join(" "),
        start.elapsed()
    );
    stderr
}
