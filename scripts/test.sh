#!/usr/bin/env bash
# The whole test suite, on a fresh machine: installs what is missing, then runs every
# check CI runs. Usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
phase() { printf '\n== %s (at %ss)\n' "$1" "$(( $(date +%s) - start ))"; }

phase "set-up"
source scripts/setup.sh --test
echo "spirv-val: $(spirv-val --version 2>&1 | head -1)"
# Slurm and munge for the last phase (scripts/slurm-test.sh), installed where missing
# beside the build: the install waits on the network and the disk, not the cores.
slurm_install_log=$(mktemp)
scripts/slurm-local.sh install >"$slurm_install_log" 2>&1 &
slurm_install=$!

phase "format"
cargo fmt --all -- --check

# The fuzz targets' instrumented build (a workspace and target of its own) runs beside the
# lint: each build leaves cores idle while its last crates compile alone. The fuzz runs
# themselves wait for the lint to end, so that each has a core of its own.
# (In a session of its own, so that a failing suite stops the build with its cargo.)
fuzz_build_log=$(mktemp)
setsid scripts/fuzz.sh build --smoke >"$fuzz_build_log" 2>&1 &
fuzz_build=$!
trap 'kill -- -"$fuzz_build" 2>/dev/null || true; rm -f "$fuzz_build_log" "$slurm_install_log"' EXIT

# The lint runs inside the one build the tests use. `cargo clippy` is `cargo check` with
# clippy-driver wrapping rustc for the workspace's own crates; wrapping `cargo test
# --no-run` the same way lints the same targets (--all-targets: libraries, binaries, tests,
# benches, examples) while compiling them, so the dependencies are compiled once, in full,
# instead of once checked for the lint and once built for the tests. CLIPPY_ARGS is how
# cargo-clippy hands `-- -D warnings` to the driver (arguments joined by
# __CLIPPY_HACKERY__). Only the two cargo commands below get the wrapper: it is part of
# the workspace crates' fingerprints, so both must see the same one, and a nested cargo
# (the fuzz build, trybuild's) must not.
clippy_driver="$(rustc --print sysroot)/bin/clippy-driver"
if [ ! -x "$clippy_driver" ]; then
    echo "error: clippy-driver is missing; install it with: rustup component add clippy"
    exit 1
fi
linted() {
    RUSTC_WORKSPACE_WRAPPER="$clippy_driver" \
        CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" "$@"
}

# The canary: a clippy warning must fail a build under the wrapper, so that a toolchain
# whose driver reads its arguments another way stops the suite instead of linting nothing.
canary=$(mktemp -d)
printf 'fn main() {\n    let v = vec![1];\n    println!("{}", v.len());\n}\n' >"$canary/canary.rs"
if linted "$clippy_driver" rustc --edition 2024 --crate-type bin --emit=metadata \
    -o "$canary/canary.rmeta" "$canary/canary.rs" >"$canary/out" 2>&1 \
    || ! grep -q 'useless_vec' "$canary/out"; then
    cat "$canary/out"
    echo "error: clippy-driver under RUSTC_WORKSPACE_WRAPPER did not deny a clippy warning"
    exit 1
fi
rm -rf "$canary"

phase "lint and test build (clippy --all-targets -D warnings)"
linted cargo test --workspace --all-targets --no-run --quiet

phase "dependency boundaries"
# The compiler library, the build-time embedding macro, the scene crate and the light crate carry no GPU, command line, image
# codec or measurement code: their trees must not contain these crates
# (docs/architecture.md section 2).
for pkg in sshc sshc-shaders-gen sshc-scene sshc-light sshc-records; do
    tree=$(cargo tree -p "$pkg" -e normal --prefix none --format '{p}')
    for banned in wgpu clap image rayon sshc-runtime sshc-lab; do
        if grep -q "^$banned v" <<<"$tree"; then
            echo "error: \`$banned\` is in the dependency tree of \`$pkg\`:"
            cargo tree -p "$pkg" -e normal -i "$banned"
            exit 1
        fi
    done
    echo "$pkg: $(wc -l <<<"$tree") crates, none of wgpu clap image rayon sshc-runtime sshc-lab"
done

phase "docs (the extension costs of docs/extending.md against the code)"
# the places a new kind touches, counted in the code (scripts/extension-costs.py): a change
# that adds or removes one updates the table (`--check` prints the difference)
python3 scripts/extension-costs.py --check

phase "fuzz (short run)"
# A workspace of its own (compiler/fuzz, excluded from the root one). scripts/fuzz.sh
# builds the eight targets with libFuzzer's coverage instrumentation, no sanitizer, at
# opt-level 1 (its smoke build; RUSTC_BOOTSTRAP=1 on stable; libfuzzer-sys's build script
# compiles libFuzzer's C++, so a C++ compiler is needed), then runs each on its seeds plus
# 15 s of mutation; a crash, a timeout or an out-of-memory fails the phase and leaves the
# input in compiler/fuzz/artifacts/<target>/. The build ran beside the lint; the runs take
# the targets one per core (docs/fuzzing.md).
if ! wait "$fuzz_build"; then
    cat "$fuzz_build_log"
    echo "error: the fuzz targets did not build"
    exit 1
fi
scripts/fuzz.sh ci 15

phase "tests"
if cargo nextest --version >/dev/null 2>&1; then
    linted cargo nextest run --workspace --no-fail-fast
else
    linted cargo test --workspace --no-fail-fast
fi

phase "bevy (runtime/bevy: the Bevy 0.20 plugin, a workspace of its own)"
# Its own build (Bevy is large: only the features the plugin, its tests and its headless
# example need), lint, headless tests on lavapipe and the example's frames (docs/bevy.md).
scripts/bevy-test.sh

phase "slurm (a single-node cluster runs a sharded sweep)"
# A real Slurm cluster on this machine (scripts/slurm-local.sh): the job scripts of `sshc
# sweep --slurm` for 4 shards, submitted, waited for and merged, against the unsharded
# run (lab/tests/slurm.rs). The cluster is stopped whatever the outcome; a time limit.
if ! wait "$slurm_install"; then
    cat "$slurm_install_log"
    echo "error: slurm-wlm and munge are missing and could not be installed"
    exit 1
fi
scripts/slurm-test.sh

phase "done"
