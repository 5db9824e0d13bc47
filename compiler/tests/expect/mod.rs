//! Fixtures with expected output, shared by errors.rs and warnings.rs: every `DIR/*.ron`
//! is rendered and compared with `DIR/*.stderr`; `UPDATE_EXPECT=1` rewrites the expected
//! files after a change has been reviewed.

use std::path::{Path, PathBuf};

/// The `.ron` fixtures of `dir` (relative to the compiler crate), sorted.
pub fn fixtures(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut fixtures: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    fixtures.sort();
    fixtures
}

/// Renders every fixture with `render(path, file name)` and compares it with its
/// `.stderr`, or rewrites that under `UPDATE_EXPECT`; fails listing every difference.
pub fn check(fixtures: &[PathBuf], what: &str, render: impl Fn(&Path, &str) -> String) {
    let update = std::env::var_os("UPDATE_EXPECT").is_some();
    let mut failures = Vec::new();
    for f in fixtures {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let got = render(f, &name);
        let expected_path = f.with_extension("stderr");
        if update {
            std::fs::write(&expected_path, &got).unwrap();
            continue;
        }
        match std::fs::read_to_string(&expected_path) {
            Ok(want) if want == got => {}
            Ok(want) => failures.push(format!("{name}: {what} changed\n--- expected\n{want}\n--- got\n{got}")),
            Err(_) => failures.push(format!("{name}: no expected file {}; got\n{got}", expected_path.display())),
        }
    }
    assert!(failures.is_empty(), "{}\n(run with UPDATE_EXPECT=1 to accept)", failures.join("\n"));
}
