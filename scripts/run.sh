#!/usr/bin/env bash
# The main job on bundled defaults: compile a bundled technique and describe the result.
# Usage: scripts/run.sh [technique.ron] [output folder]
set -euo pipefail
cd "$(dirname "$0")/.."
technique=${1:-techniques/csm.ron}
out=${2:-out}
cargo build --release -p sshc --quiet
./target/release/sshc compile "$technique" -o "$out"
./target/release/sshc explain "$technique"
