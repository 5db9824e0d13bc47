#!/usr/bin/env bash
# The whole test suite, on a fresh machine: installs what is missing, then runs every
# check CI runs. Usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
phase() { printf '\n== %s (at %ss)\n' "$1" "$(( $(date +%s) - start ))"; }

phase "set-up"
missing=()
command -v spirv-val >/dev/null 2>&1 || missing+=(spirv-tools)
# The Vulkan loader and Mesa's lavapipe (a CPU Vulkan driver), for GPU work without a GPU.
if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1'; then missing+=(libvulkan1); fi
if ! ls /usr/share/vulkan/icd.d/*.json >/dev/null 2>&1; then missing+=(mesa-vulkan-drivers); fi
if [ ${#missing[@]} -gt 0 ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "installing: ${missing[*]}"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
    else
        echo "missing system packages: ${missing[*]}"
        echo "install them with: sudo apt-get install -y ${missing[*]}"
        exit 1
    fi
fi
if ! command -v naga >/dev/null 2>&1; then
    echo "installing the naga command-line validator (naga-cli 30.0.1)"
    cargo install naga-cli --version 30.0.1 --locked --quiet
fi
echo "naga: $(naga --version 2>&1 | head -1); spirv-val: $(spirv-val --version 2>&1 | head -1)"

phase "format"
cargo fmt --all -- --check

phase "lint"
cargo clippy --workspace --all-targets --quiet -- -D warnings

phase "the compiler library builds without wgpu"
cargo build -p sshc --no-default-features --quiet
if cargo tree -p sshc --no-default-features -e normal | grep -q '\bwgpu'; then
    echo "error: wgpu is a dependency of the sshc library without the gpu feature"
    exit 1
fi

phase "tests"
export LP_NUM_THREADS=${LP_NUM_THREADS:-2}
if cargo nextest --version >/dev/null 2>&1; then
    cargo nextest run --workspace --no-fail-fast
else
    cargo test --workspace --no-fail-fast
fi

phase "done"
