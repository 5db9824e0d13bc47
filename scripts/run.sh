#!/usr/bin/env bash
# The main job on bundled defaults: compile a bundled technique, render a bundled scene to
# PNG (with its visibility buffer), and describe the compiled technique.
# Usage: scripts/run.sh [technique.ron] [scene.ron] [output folder]
set -euo pipefail
cd "$(dirname "$0")/.."
technique=${1:-techniques/pcf.ron}
scene=${2:-scenes/bunny.ron}
out=${3:-out}
source scripts/setup.sh
cargo build --release -p sshc-lab --quiet
./target/release/sshc compile "$technique" -o "$out"
name=$(basename "$technique" .ron)
./target/release/sshc render "$technique" --scene "$scene" -o "$out/$name.png" --visibility "$out/$name.visibility.pfm" --frames 5
./target/release/sshc explain "$technique"
