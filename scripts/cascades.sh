#!/usr/bin/env bash
# Cascaded shadow maps against the truth: RMS over facing pixels and over the penumbra
# with 1 to 4 cascades at the same total texel count (cascade side = SIDE / sqrt(N)), and
# the GPU time per frame, for hard, PCF, PCSS and CSSM on the large city under a low sun;
# one cascade is the scene file's own fit, and a first row per technique fits the one map
# to the whole scene instead.
# docs/scale.md holds its output.
#
#   scripts/cascades.sh [SCENE]      default scenes/large/city.ron
#
# Environment: SSHC (default target/release/sshc, built if missing), SIDE (the one
# cascade's side, default 2048), SIZE (camera, default 256x256), TECHNIQUES (default
# hard pcf pcss cssm), SAMPLES x RUNS of the truth (default 64 x 2; cached after the
# first technique).
set -euo pipefail
cd "$(dirname "$0")/.."
SSHC=${SSHC:-target/release/sshc}
[[ -x $SSHC ]] || cargo build --release -p sshc-lab --quiet
scene=${1:-scenes/large/city.ron}
side=${SIDE:-2048}
read -r -a techniques <<<"${TECHNIQUES:-hard pcf pcss cssm}"
out=$(mktemp -d)
echo "| technique | cascades | side (texels) | RMS facing (0..255) | RMS penumbra (0..255) | GPU ms per frame |"
echo "|---|---|---|---|---|---|"
for t in "${techniques[@]}"; do
    # one map fitted to the whole scene (`--fit scene`), as an engine's single sun map
    log="$out/$t-scene.txt"
    if "$SSHC" compare "techniques/$t.ron" --scene "$scene" --size "${SIZE:-256x256}" --samples "${SAMPLES:-64}" \
        --runs "${RUNS:-2}" --shadow-map "$side" --fit scene --stability-frames 0 -o "$out/$t-scene.png" >"$log" 2>&1; then
        echo "| $t | 1, fitted to the whole scene | $side | $(sed -n 's/^error facing the light: RMS \([0-9.]*\).*/\1/p' "$log") | $(sed -n 's/^error in penumbra.*: RMS \([0-9.]*\).*/\1/p' "$log") | $(sed -n 's/^GPU time per frame: \([0-9.]*\) ms.*/\1/p' "$log") |"
    fi
    for n in 1 2 3 4; do
        s=$(python3 -c "import math; print(int($side / math.sqrt($n)))")
        log="$out/$t-$n.txt"
        "$SSHC" compare "techniques/$t.ron" --scene "$scene" --size "${SIZE:-256x256}" --samples "${SAMPLES:-64}" \
            --runs "${RUNS:-2}" --shadow-map "$s" --cascades "$n" --stability-frames 0 -o "$out/$t-$n.png" >"$log" 2>&1 ||
            { echo "| $t | $n | $s | refused: $(grep -v XDG_RUNTIME_DIR "$log" | grep -m1 error | cut -c1-120) | | |"; continue; }
        facing=$(sed -n 's/^error facing the light: RMS \([0-9.]*\).*/\1/p' "$log")
        pen=$(sed -n 's/^error in penumbra.*: RMS \([0-9.]*\).*/\1/p' "$log")
        ms=$(sed -n 's/^GPU time per frame: \([0-9.]*\) ms.*/\1/p' "$log")
        echo "| $t | $n | $s | $facing | $pen | $ms |"
    done
done
echo "scratch: $out" >&2
