//! What the lab's test binaries share: the repository root and fresh scratch folders.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The repository's root (scenes/, techniques/).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The names of every bundled scene (`scenes/*.ron`, without the extension), sorted: the
/// tests that walk them all follow the folder.
pub fn bundled_scenes() -> Vec<String> {
    let dir = root().join("scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok())
        .filter_map(|e| e.path().file_name()?.to_str()?.strip_suffix(".ron").map(str::to_string))
        .collect();
    names.sort();
    names
}

/// The names of every bundled technique (`techniques/*.ron`) and authoring example
/// (`techniques/examples/*.ron`, named `examples/NAME`), sorted: the tests that walk them
/// all follow the folders, so a technique added there is tested without being listed
/// (issue 52), each kind told apart by what its compiled graph holds.
pub fn bundled_techniques() -> Vec<String> {
    let mut names = Vec::new();
    for (dir, prefix) in [("techniques", ""), ("techniques/examples", "examples/")] {
        let dir = root().join(dir);
        names.extend(
            std::fs::read_dir(&dir)
                .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
                .filter_map(|e| e.ok())
                .filter_map(|e| e.path().file_name()?.to_str()?.strip_suffix(".ron").map(|n| format!("{prefix}{n}"))),
        );
    }
    names.sort();
    names
}

/// Whether bundled technique `name` ([`bundled_techniques`]) has a Geometry pass: its
/// shadow comes from meshes, not from a depth map alone.
pub fn has_geometry_pass(name: &str) -> bool {
    let path = root().join("techniques").join(format!("{name}.ron"));
    let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let compiled = sshc::compile_str(&source, &Default::default()).unwrap_or_else(|d| panic!("{}", d.render(name, &source)));
    compiled.graph.passes.iter().any(|p| p.kind == sshc_graph::PassKind::Geometry)
}

/// Runs the `sshc` binary at `exe` (a test's `env!("CARGO_BIN_EXE_sshc")`) with `args` from
/// the repository's root, on lavapipe's two threads, and returns what it did.
pub fn sshc(exe: &str, args: &[&str]) -> std::process::Output {
    std::process::Command::new(exe)
        .args(args)
        .current_dir(root())
        .env("LP_NUM_THREADS", std::env::var("LP_NUM_THREADS").unwrap_or_else(|_| "2".into()))
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
        )
        .output()
        .expect("the sshc binary runs")
}

/// A fresh empty folder under the system's temporary folder, named after the test binary,
/// the process and `name`.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sshc-{}-{}-{name}", env!("CARGO_CRATE_NAME"), std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

// Sweeps: the CSV that `sshc sweep` and `sshc sweep merge` write (tests/sweep/, tests/slurm.rs).

/// The rows of a sweep's CSV, each a list of fields.
pub fn csv_rows(csv: &str) -> Vec<Vec<String>> {
    csv::Reader::from_reader(csv.as_bytes())
        .records()
        .map(|r| r.expect("a CSV record").iter().map(str::to_string).collect())
        .collect()
}

/// The columns a merged sweep must have exactly as the unsharded run has them: every
/// accuracy, memory and count column (the time columns are measured again by each shard).
pub const SAME_COLUMNS: &[&str] = &[
    "scene",
    "technique",
    "config",
    "shadow_map",
    "light_scale",
    "peak_bytes",
    "fetches",
    "ops",
    "rms_facing",
    "max_facing",
    "rms_penumbra",
    "max_penumbra",
    "facing_pixels",
    "penumbra_pixels",
    "truth_max_se",
    "rms_ground",
    "max_ground",
    "ground_pixels",
];

/// Asserts that `merged` has `whole`'s rows, in its order, with every [`SAME_COLUMNS`]
/// equal, a time ratio on every GPU row and each row's shard `i/n` for configuration i.
pub fn assert_merged_equals(whole: &str, merged: &str, n: usize) {
    let header: Vec<&str> = whole.lines().next().unwrap().split(',').collect();
    assert_eq!(merged.lines().next(), whole.lines().next(), "the same columns");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let (a, b) = (csv_rows(whole), csv_rows(merged));
    assert_eq!(a.len(), b.len(), "{merged}");
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        for c in SAME_COLUMNS {
            assert_eq!(x[col(c)], y[col(c)], "row {k}, column {c}: {x:?} against {y:?}");
        }
        if !y[col("technique")].contains("(CPU)") {
            let ratio: f64 = y[col("time_ratio")].parse().unwrap_or_else(|_| panic!("row {k}: {y:?}"));
            assert!(ratio.is_finite() && ratio > 0.0, "row {k}: {y:?}");
            assert_eq!(y[col("shard")], format!("{}/{n}", k % n), "row {k}: {y:?}");
        }
    }
}
