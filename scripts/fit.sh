#!/usr/bin/env bash
# Measures the `View` fit of the light's view (issue 16) against the whole-scene fit on
# every bundled scene: the world size of a shadow-map texel at the receivers the camera
# sees, and each technique's error against the ground truth (`sshc compare`, RMS over the
# pixels facing the light and over the penumbra, 0..255) at the scene's own map size under
# both fits. Writes a Markdown report.
#
# Usage: scripts/fit.sh [SSHC] [OUT] [CAMERA]
#   SSHC    the binary (default target/release/sshc)
#   OUT     the report (default docs/fit.md)
#   CAMERA  camera size (default 128x128)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/sshc}
out=${2:-docs/fit.md}
camera=${3:-128x128}
[ -x "$bin" ] || { echo "no sshc binary at $bin: build it with cargo build --release -p sshc-lab"; exit 1; }
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
start=$(date +%s)
rows=$tmp/rows.md
: > "$rows"
declare -A tex rms pen
for s in scenes/*.ron; do
    scene=$(basename "$s" .ron)
    if grep -q 'Segment(' "$s"; then
        techniques="linear-light point-samples"
    elif grep -qE 'Triangle\(|Rectangle\(' "$s" && [[ $scene == linear-* ]]; then
        # the per-sample techniques need N a multiple of the edges: the map techniques here
        techniques="hard pcf pcss vsm"
    else
        techniques="hard pcf pcss vsm esm evsm msm csm cssm"
    fi
    for t in $techniques; do
        for fit in scene view; do
            "$bin" compare "techniques/$t.ron" --scene "$s" --fit "$fit" --size "$camera" \
                --stability-frames 0 -o "$tmp/c.png" > "$tmp/$fit.txt" 2>&1 || { cat "$tmp/$fit.txt"; exit 1; }
        done
        # the texel at the receivers, the RMS facing the light and in the penumbra, per fit
        for fit in scene view; do
            tex[$fit]=$(sed -n 's/.*(\([0-9.]*\) at the receivers.*/\1/p' "$tmp/$fit.txt" | head -n 1)
            rms[$fit]=$(sed -n 's/^error facing the light: RMS \([0-9.]*\),.*/\1/p' "$tmp/$fit.txt")
            pen[$fit]=$(sed -n 's/^error in penumbra.*: RMS \([0-9.]*\),.*/\1/p' "$tmp/$fit.txt")
        done
        awk -v sc="$scene" -v t="$t" -v ts="${tex[scene]}" -v tv="${tex[view]}" -v rs="${rms[scene]}" -v rv="${rms[view]}" \
            -v ps="${pen[scene]:-0}" -v pv="${pen[view]:-0}" \
            'BEGIN { printf "| %s | %s | %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f |\n", sc, t, ts, tv, rs, rv, (rs > 0 ? rv / rs : 0), ps, pv }' >> "$rows"
        echo "$t on $scene: done ($(($(date +%s) - start)) s)" >&2
    done
done
device=$("$bin" render techniques/hard.ron --scene scenes/contact.ron --size 8x8 -o "$tmp/d.png" | sed -n 's/^device: //p')
{
    echo "# Fitted light views: the whole-scene fit against the \`View\` fit"
    echo
    echo "Produced by \`scripts/fit.sh $bin $out $camera\` on $(date -u +%Y-%m-%d), device: $device."
    echo "Every bundled scene at its own shadow-map size, camera $camera, with the light's view fitted"
    echo "to the whole scene (\`--fit scene\`) and to what the camera sees (\`--fit view\`,"
    echo "scenes/README.md). *Texel*: the world size of one shadow-map texel at the receivers the"
    echo "camera sees (for a perspective light view, at their mean depth in it). *RMS*: \`sshc"
    echo "compare\`'s error against the ground truth over the pixels facing the light, 0..255;"
    echo "*penumbra RMS*: over the pixels whose truth is strictly between 0 and 1. The truth does not"
    echo "depend on the fit (it is computed once per scene and cached). Techniques whose filter is"
    echo "sized in texels (PCF, the blurs of VSM, ESM, CSM and CSSM) filter a narrower world region"
    echo "under the finer fit; those sized in world units (PCSS) get finer texels for the same kernel."
    echo
    echo "| scene | technique | texel, scene fit | texel, view fit | RMS scene | RMS view | view / scene | penumbra RMS scene | penumbra RMS view |"
    echo "|---|---|---|---|---|---|---|---|---|"
    cat "$rows"
} > "$out"
echo "wrote $out ($(($(date +%s) - start)) s)" >&2
