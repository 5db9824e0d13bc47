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

phase "format"
cargo fmt --all -- --check

phase "lint"
cargo clippy --workspace --all-targets --quiet -- -D warnings

phase "dependency boundaries"
# The compiler library, the build-time embedding macro, the scene crate and the light crate carry no GPU, command line, image
# codec or measurement code: their trees must not contain these crates
# (docs/architecture.md section 2).
for pkg in sshc sshc-shaders-gen sshc-scene sshc-light; do
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

phase "fuzz (short run)"
# A workspace of its own (compiler/fuzz, excluded from the root one). scripts/fuzz.sh
# builds the four targets (front, expr, graph, scene) with libFuzzer's coverage
# instrumentation, no sanitizer (RUSTC_BOOTSTRAP=1 on stable; libfuzzer-sys's build script
# compiles libFuzzer's C++, so a C++ compiler is needed), then runs each on its seeds plus
# 20 s of mutation; a crash, a timeout or an out-of-memory fails the phase and leaves the
# input in compiler/fuzz/artifacts/<target>/. About 5 minutes on a 2-core machine from
# a clean compiler/fuzz/target, 1.5 with it warm (docs/fuzzing.md).
scripts/fuzz.sh ci 20

phase "tests"
if cargo nextest --version >/dev/null 2>&1; then
    cargo nextest run --workspace --no-fail-fast
else
    cargo test --workspace --no-fail-fast
fi

phase "done"
