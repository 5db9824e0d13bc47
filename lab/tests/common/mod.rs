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

/// A fresh empty folder under the system's temporary folder, named after the test binary,
/// the process and `name`.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sshc-{}-{}-{name}", env!("CARGO_CRATE_NAME"), std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}
