#!/usr/bin/env bash
# The Bevy plugin's phase of the suite (runtime/bevy: `bevy_sshc`, a workspace of its own,
# docs/bevy.md): format, then one build that lints (clippy-driver wrapping rustc for the
# crate's own targets, as scripts/test.sh does for the main workspace) and compiles the
# tests and the example, then the headless tests on lavapipe and the example's frames.
# Bevy 0.20 declares Rust 1.97.1; it builds on 1.95 with `--ignore-rust-version`, given
# to this crate's builds only. Usage: scripts/bevy-test.sh [output folder for the frames]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/target/bevy}"
cd "$root/runtime/bevy"
start=$(date +%s)
step() { printf -- '-- %s (at %ss)\n' "$1" "$(( $(date +%s) - start ))"; }

step "format"
cargo fmt -- --check

step "lint and build (clippy -D warnings; tests, example)"
clippy_driver="$(rustc --print sysroot)/bin/clippy-driver"
RUSTC_WORKSPACE_WRAPPER="$clippy_driver" CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" \
    cargo test --ignore-rust-version --all-targets --no-run --quiet

step "headless tests"
# each capture is an app in a process of its own (the tests run this binary again), so
# plain `cargo test` works as well as nextest
runner=(nextest run)
cargo nextest --version >/dev/null 2>&1 || runner=(test)
RUSTC_WORKSPACE_WRAPPER="$clippy_driver" CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" \
    timeout 900 cargo "${runner[@]}" --ignore-rust-version --no-fail-fast

step "the example, headless: four frames under the orbiting sun"
rm -rf "$out"
timeout 300 target/debug/examples/shadows --frames 4 --out "$out" --size 128
for f in 0 1 2 3; do
    test -s "$out/frame-00$f.png" || { echo "error: the example wrote no $out/frame-00$f.png"; exit 1; }
done
if cmp -s "$out/frame-000.png" "$out/frame-003.png"; then
    echo "error: the first and last frames are the same: the sun's shadow did not move"
    exit 1
fi
step "done"
