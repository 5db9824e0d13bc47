#!/usr/bin/env bash
# The main job on bundled defaults: compile a bundled technique, render a bundled scene to
# PNG (with its visibility buffer), and describe the compiled technique. A fresh machine's
# first run builds `sshc` without the viewer at the `quick` profile (unoptimised: about
# 100 s on 2 cores; Cargo.toml says why); `cargo build --release -p sshc-lab` builds the
# optimised `sshc` with `sshc view`.
# Usage: scripts/run.sh [technique.ron] [scene.ron] [output folder]
set -euo pipefail
cd "$(dirname "$0")/.."
technique=${1:-techniques/pcf.ron}
scene=${2:-scenes/bunny.ron}
out=${3:-out}
source scripts/setup.sh
cargo build --profile quick -p sshc-lab --no-default-features --quiet
sshc=./target/quick/sshc
"$sshc" compile "$technique" -o "$out"
name=$(basename "$technique" .ron)
"$sshc" render "$technique" --scene "$scene" -o "$out/$name.png" --visibility "$out/$name.visibility.pfm" --frames 5
"$sshc" explain "$technique"
