#!/usr/bin/env bash
# Measures every bundled technique's passes against their memory bound, from a prebuilt
# `sshc` (no Rust toolchain needed: the GPU machines have none, docs/gpu-machine.md), and
# writes a Markdown report. Per technique and shadow-map size: each pass's median GPU time
# over the frames, its compulsory bytes (sshc_graph::traffic), the GB/s they imply and the
# time over the bound at the device's bandwidth (measured once, by the first `sshc render`:
# a 64 MiB buffer copy). The light-sample techniques run on scenes/linear.ron's segment light, the
# others on scenes/bunny.ron.
#
# Usage: scripts/gpu-bench.sh [SSHC] [OUT] [CAMERA] [MAPS] [FRAMES]
#   SSHC    the binary (default target/release/sshc, or .gpu/sshc where it exists)
#   OUT     the report (default docs/gpu.md)
#   CAMERA  camera size (default 1920x1080)
#   MAPS    shadow-map sizes, comma-separated (default 1024,2048)
#   FRAMES  frames per run (default 9)
# Issue 15 adds a schedule axis (fragment against compute) and the agreement timings.
set -euo pipefail
cd "$(dirname "$0")/.."
default_bin=target/release/sshc
[ -x .gpu/sshc ] && default_bin=.gpu/sshc
bin=${1:-$default_bin}
out=${2:-docs/gpu.md}
camera=${3:-1920x1080}
maps=${4:-1024,2048}
frames=${5:-9}
[ -x "$bin" ] || { echo "no sshc binary at $bin: build it with cargo build --release -p sshc-lab"; exit 1; }
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
start=$(date +%s)
body=$tmp/body.md
device=""
# the first run measures the bandwidth; the others are given it, so that every bound
# is taken at the same figure
bw=()
: > "$body"
for map in ${maps//,/ }; do
    echo "## Shadow map ${map}^2" >> "$body"
    echo >> "$body"
    for t in techniques/*.ron; do
        name=$(basename "$t" .ron)
        scene=scenes/bunny.ron
        grep -q 'light_samples' "$t" && scene=scenes/linear.ron
        log=$("$bin" render "$t" --scene "$scene" --size "$camera" --shadow-map "$map" \
            --frames "$frames" -o "$tmp/$name.png" "${bw[@]}")
        if [ -z "$device" ]; then
            device="$(echo "$log" | sed -n 's/^device: //p'); $(echo "$log" | grep '^bandwidth:')"
            bw=(--bandwidth "$(echo "$log" | sed -n 's|^bandwidth: \([0-9.]*\) GB/s.*|\1|p')")
        fi
        {
            echo "### $name (on $(basename "$scene"))"
            echo
            echo "| pass | GPU ms | compulsory MB | GB/s | bound ms | ms / bound |"
            echo "|---|---|---|---|---|---|"
            echo "$log" | sed -n '/^| pass/,$p' | tail -n +3 | awk -F'|' '{printf "|%s|%s|%s|%s|%s|%s|\n", $2, $3, $7, $8, $9, $10}'
            echo
        } >> "$body"
        echo "$name at ${map}^2: done ($(($(date +%s) - start)) s)" >&2
    done
done
{
    echo "# Passes against their memory bound"
    echo
    echo "Produced by \`scripts/gpu-bench.sh $bin $out $camera $maps $frames\` on $(date -u +%Y-%m-%d)."
    echo "Camera $camera; median of $frames frames per run, in milliseconds, measured with"
    echo "timestamp queries. *Compulsory MB*: the bytes any schedule of the pass must move at a"
    echo "perfect cache (docs/architecture.md section 7); *bound ms*: those bytes at the device's"
    echo "bandwidth; *ms / bound*: how far the pass is from it (1 is at the bound). A Shade's"
    echo "bytes are its writes only (what it reads depends on the view)."
    echo
    echo "Device: $device."
    echo
    cat "$body"
    echo "Took $(($(date +%s) - start)) s."
} > "$out"
echo "wrote $out"
