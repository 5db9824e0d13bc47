#!/usr/bin/env bash
# The Bevy plugin's phase of the suite (runtime/bevy: `bevy_sshc`, a workspace of its own,
# docs/bevy.md): format, then one build that lints (clippy-driver wrapping rustc for the
# crate's own targets, as scripts/test.sh does for the main workspace) and compiles the
# tests and the example, then the headless tests on lavapipe and the example's frames.
# Bevy 0.20 declares Rust 1.97.1; it builds on 1.95 with `--ignore-rust-version`, given
# to this crate's builds only. One build, with the example's window (feature `window`),
# serves the tests, the headless frames and the windowed run under a virtual X server.
# Usage: scripts/bevy-test.sh [output folder for the frames]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/target/bevy}"
source "$root/scripts/setup.sh" --test
cd "$root/runtime/bevy"
start=$(date +%s)
step() { printf -- '-- %s (at %ss)\n' "$1" "$(( $(date +%s) - start ))"; }

step "format"
cargo fmt -- --check

step "lint and build (clippy -D warnings; tests, example)"
clippy_driver="$(rustc --print sysroot)/bin/clippy-driver"
RUSTC_WORKSPACE_WRAPPER="$clippy_driver" CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" \
    cargo test --ignore-rust-version --features window --all-targets --no-run --quiet

step "headless tests"
# each capture is an app in a process of its own (the tests run this binary again), so
# plain `cargo test` works as well as nextest
runner=(nextest run)
cargo nextest --version >/dev/null 2>&1 || runner=(test)
RUSTC_WORKSPACE_WRAPPER="$clippy_driver" CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" \
    timeout 900 cargo "${runner[@]}" --ignore-rust-version --features window --no-fail-fast

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
step "sshc inside Bevy against \`sshc render\` of the scene the plugin exported"
# The example's frame with the sun still (turned 30 degrees: no face edge-on to it), its
# visibility and the scene as shaded (bevy_sshc::ExportScene); `sshc render` of that scene
# must give the same visibility, bit for bit (examples/against_truth.rs, `equal`).
sshc_bin="$root/target/debug/sshc"
if [ ! -x "$sshc_bin" ]; then
    (cd "$root" && cargo build -q -p sshc-lab --bin sshc)
fi
rm -rf "$out/still" "$out/still-scene"
timeout 300 target/debug/examples/shadows --frames 1 --still --sun-turn 30 --size 128 --technique pcss \
    --visibility --export "$out/still-scene" --out "$out/still"
"$sshc_bin" render "$root/techniques/pcss.ron" --scene "$out/still-scene/scene.ron" \
    --visibility "$out/still/render.pfm" -o "$out/still/render.png" >/dev/null
target/debug/examples/against_truth equal "$out/still/visibility-000.pfm" "$out/still/render.pfm"

step "the example in a window (xvfb): 60 frames, a screenshot, the title line"
# Under a virtual X server on lavapipe, as the viewer's window tests run; the title line
# names the technique and sshc's GPU time (Bevy's render diagnostics)
title=$(timeout 300 xvfb-run -a -s "-screen 0 1280x800x24" \
    target/debug/examples/shadows --window-frames 60 --screenshot "$out/window.png" | grep '^title: ' || true)
echo "$title"
test -s "$out/window.png" || { echo "error: the windowed example wrote no screenshot"; exit 1; }
if ! grep -Eq '^title: sshc: pcss, GPU [0-9]+\.[0-9]+ ms' <<<"$title"; then
    echo "error: the window's title line does not name the technique and sshc's GPU time"
    exit 1
fi
step "done"
