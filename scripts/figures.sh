#!/usr/bin/env bash
# Renders every bundled technique on scenes/bunny.ron (the light-sample ones, whose rectangle
# light would need N a multiple of 4, on scenes/linear.ron's segment light) into
# docs/images/ and measures per-pass GPU times (median of repeated frames) into
# docs/gpu-times.md.
# Usage: scripts/figures.sh [frames]
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-15}
source scripts/setup.sh
cargo build --release -p sshc-lab --quiet
mkdir -p docs/images
out=docs/gpu-times.md
{
    echo "# GPU time per pass"
    echo
    echo "Each bundled technique on \`scenes/bunny.ron\` (256 x 256 camera, 512 x 512 shadow map),"
    echo "median of $frames frames measured with timestamp queries, in milliseconds."
    echo "Produced by \`scripts/figures.sh $frames\` on $(date -u +%Y-%m-%d)."
    echo "On lavapipe (Mesa's CPU Vulkan driver) these times rank CPU rasterisation and texture"
    echo "filtering on this 2-core machine, not GPUs; compare techniques only as ratios taken in"
    echo "one run. The first frame of each run compiles pipelines and is included in the median's"
    echo "population but not its middle. Running the same on a machine with a GPU but no Rust"
    echo "toolchain: [gpu-machine.md](gpu-machine.md)."
    echo
} > "$out"
# render technique $1 on scene $2 into docs/images/$3.png; its per-pass table under heading $4
figure() {
    local log device
    log=$(./target/release/sshc render "techniques/$1.ron" --scene "scenes/$2.ron" -o "docs/images/$3.png" --frames "$frames")
    device=$(echo "$log" | sed -n 's/^device: //p')
    {
        echo "## $4"
        echo
        echo "Device: $device"
        echo
        echo "$log" | sed -n '/^| pass/,$p'
        echo
    } >> "$out"
}
for t in hard pcf vsm esm evsm msm csm cssm pcss penumbra-maps penumbra-limit-maps smoothies single-sample; do
    figure "$t" bunny "bunny-$t" "$t"
done
for t in point-samples linear-light; do
    figure "$t" linear "linear-$t" "$t (on \`scenes/linear.ron\`, 2 light samples, 512 x 512 maps)"
done
echo "wrote docs/images/bunny-*.png, docs/images/linear-*.png and $out"
