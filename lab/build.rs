//! The code a sweep's shards are checked against (`sshc sweep merge`): the git commit the
//! binary is built from, as `SSHC_GIT_COMMIT`, when every file compiled into it is as that
//! commit has it; empty otherwise (not a git checkout, no `git`, or changes not committed),
//! and the binary then names its code by a hash of its own executable.
//!
//! The files watched are those compiled into the `sshc` binary: the `src` folders of this
//! crate and of the workspace crates it builds on, the bundled techniques it embeds, the
//! manifests and the lock file. A change to any of them runs this script again, so the
//! commit is never read from a tree older than the code.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Watched paths, relative to the workspace root.
const CODE: &[&str] = &[
    "Cargo.toml",
    "Cargo.lock",
    "graph/Cargo.toml",
    "graph/src",
    "compiler/Cargo.toml",
    "compiler/src",
    "runtime/Cargo.toml",
    "runtime/src",
    "runtime/light/Cargo.toml",
    "runtime/light/src",
    "lab/Cargo.toml",
    "lab/build.rs",
    "lab/src",
    "lab/scene/Cargo.toml",
    "lab/scene/src",
    // embedded by `include_str!` in lab/src and the compiler
    "techniques/hard.ron",
    "techniques/cssm.ron",
    "techniques/esm.ron",
    "techniques/penumbra-maps.ron",
    "techniques/point-samples.ron",
    "techniques/vsm.ron",
];

fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git").arg("-C").arg(root).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into()));
    let root = manifest.parent().unwrap_or(&manifest).to_path_buf();
    for p in CODE {
        println!("cargo:rerun-if-changed={}", root.join(p).display());
    }
    let mut commit = String::new();
    if let (Some(head), Some(dir), Some(common)) = (
        git(&root, &["rev-parse", "HEAD"]),
        git(&root, &["rev-parse", "--absolute-git-dir"]),
        git(&root, &["rev-parse", "--git-common-dir"]),
    ) {
        // a commit or a checkout moves these: HEAD, and the branch it names (a loose ref,
        // else in packed-refs); not the index, which every `git add` touches, nor other
        // branches
        let common = if Path::new(&common).is_absolute() {
            PathBuf::from(&common)
        } else {
            root.join(&common)
        };
        let mut watched = vec![Path::new(&dir).join("HEAD"), common.join("packed-refs")];
        if let Some(branch) = git(&root, &["symbolic-ref", "-q", "HEAD"]) {
            watched.push(common.join(branch));
        }
        for p in watched {
            // (a path that does not exist would run this script at every build)
            if p.exists() {
                println!("cargo:rerun-if-changed={}", p.display());
            }
        }
        let mut args = vec!["status", "--porcelain", "--untracked-files=normal", "--"];
        args.extend(CODE);
        if git(&root, &args).is_some_and(|changes| changes.is_empty()) {
            commit = head;
        }
    }
    println!("cargo:rustc-env=SSHC_GIT_COMMIT={commit}");
}
