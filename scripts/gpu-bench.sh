#!/usr/bin/env bash
# Measures every bundled technique's passes under each schedule and against their memory
# bound, from a prebuilt `sshc` (no Rust toolchain needed: the GPU machines have none,
# docs/gpu-machine.md), and writes a Markdown report. Per technique and shadow-map size:
# each pass's median GPU time over the frames with its passes run as fragment and as
# compute (`--schedule '*=fragment'`, `'*=compute'`: Map, Filter and Mipmap passes as
# compute, the Shade deferred), their ratio, and the whole frame's wall time of both and of
# a third run with only the Shade deferred; the pass's compulsory
# bytes (sshc_graph::traffic) and the time the faster schedule takes over their bound at
# the device's bandwidth (measured once, by the first `sshc render`: a 64 MiB buffer copy).
# The light-sample techniques run on scenes/linear.ron's segment light, the others on
# scenes/bunny.ron.
#
# Usage: scripts/gpu-bench.sh [SSHC] [OUT] [CAMERA] [MAPS] [FRAMES]
#   SSHC    the binary (default target/release/sshc, or .gpu/sshc where that is missing)
#   OUT     the report (default docs/gpu.md)
#   CAMERA  camera size (default 1920x1080)
#   MAPS    shadow-map sizes, comma-separated (default 1024,2048)
#   FRAMES  frames per run (default 9)
# With AGREEMENT=<the agreement_timings bench binary> (built with `cargo bench -p sshc-tests
# --bench agreement_timings --no-run`: target/release/deps/agreement_timings-<hash>; it
# finds the repository through the CARGO_MANIFEST_DIR it was built with, so on another
# machine link that path to the checkout first), the report ends with the generated
# against hand-written timings at SSHC_TIMINGS_SHADOW x SSHC_TIMINGS_CAMERA (here default
# 2048 and 1024: large enough to time on a GPU).
set -euo pipefail
cd "$(dirname "$0")/.."
# a build here first; on a GPU machine (no toolchain, no target/) the carried copy
default_bin=target/release/sshc
[ -x "$default_bin" ] || default_bin=.gpu/sshc
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
        # the same technique under each schedule of its passes (`--schedule '*=...'`: Map,
        # Filter, Mipmap and Shade; a technique whose formats refuse compute runs the same code
        # twice), then with only its Shade deferred (`deferred`)
        for sch in fragment compute deferred; do
            case $sch in
                deferred) schedule=(--schedule '*=fragment' --schedule 'shade=compute') ;;
                *) schedule=(--schedule "*=$sch") ;;
            esac
            log=$("$bin" render "$t" --scene "$scene" --size "$camera" --shadow-map "$map" \
                --frames "$frames" "${schedule[@]}" -o "$tmp/$name.png" "${bw[@]}")
            if [ -z "$device" ]; then
                device="$(echo "$log" | sed -n 's/^device: //p'); $(echo "$log" | grep '^bandwidth:')"
                bw=(--bandwidth "$(echo "$log" | sed -n 's|^bandwidth: \([0-9.]*\) GB/s.*|\1|p')")
            fi
            echo "$log" | sed -n '/^| pass/,$p' | tail -n +3 > "$tmp/$sch.rows"
            echo "$log" | sed -n 's/^frame wall time: \([0-9.]*\) ms.*/\1/p' > "$tmp/$sch.wall"
        done
        {
            echo "### $name (on $(basename "$scene"))"
            echo
            echo "| pass | fragment ms | compute ms | compute / fragment | compulsory MB | bound ms | best / bound | schedule run by the compute row |"
            echo "|---|---|---|---|---|---|---|---|"
            # columns of render's table: 2 pass, 3 ms, 7 MB, 9 bound, 11 schedule
            paste -d'\n' "$tmp/fragment.rows" "$tmp/compute.rows" | awk -F'|' 'NR % 2 == 1 { f = $3 + 0; next }
                { c = $3 + 0; b = $9 + 0; best = (c < f ? c : f);
                  printf "|%s| %.3f | %.3f | %.2f |%s|%s| %.1f |%s|\n", $2, f, c, (f > 0 ? c / f : 0), $7, $9, (b > 0 ? best / b : 0), $11 }'
            # the whole frame by the wall clock: the comparison that holds on lavapipe,
            # whose compute passes' end timestamps do not wait for their dispatches
            f=$(cat "$tmp/fragment.wall"); c=$(cat "$tmp/compute.wall"); d=$(cat "$tmp/deferred.wall")
            awk -v f="$f" -v c="$c" 'BEGIN { printf "| **whole frame, wall clock** | %.3f | %.3f | %.2f | | | | |\n", f, c, (f > 0 ? c / f : 0) }'
            awk -v f="$f" -v d="$d" 'BEGIN { printf "| **whole frame, wall clock, only the Shade deferred** | %.3f | %.3f | %.2f | | | | |\n", f, d, (f > 0 ? d / f : 0) }'
            echo
        } >> "$body"
        echo "$name at ${map}^2: done ($(($(date +%s) - start)) s)" >&2
    done
done
agreement_status=""
if [ -n "${AGREEMENT:-}" ]; then
    set +e
    SSHC_TIMINGS_SHADOW=${SSHC_TIMINGS_SHADOW:-2048} SSHC_TIMINGS_CAMERA=${SSHC_TIMINGS_CAMERA:-1024} \
        "$AGREEMENT" --bench 2>"$tmp/agreement.err" | grep -E '^(\||Device)' > "$tmp/agreement.md"
    agreement_status=${PIPESTATUS[0]}
    set -e
    echo "agreement timings: done, status $agreement_status ($(($(date +%s) - start)) s)" >&2
fi
{
    echo "# Passes against their memory bound"
    echo
    echo "Produced by \`scripts/gpu-bench.sh $bin $out $camera $maps $frames\` on $(date -u +%Y-%m-%d)."
    echo "Camera $camera; median of $frames frames per run, in milliseconds, measured with"
    echo "timestamp queries. Each technique runs three times in turn: every pass as fragment (the Shade"
    echo "forward), then as compute (the Map, Filter and Mipmap passes whose formats allow it, and the"
    echo "Shade deferred: a G-buffer raster, then a compute step per pixel), then as fragment with only"
    echo "the Shade deferred (its own wall-clock row). *Compulsory MB*: the bytes any schedule of the pass"
    echo "must move at a perfect cache (docs/architecture.md section 6); *bound ms*: those bytes at"
    echo "the device's bandwidth; *best / bound*: how far the faster schedule is from it (1 is at the"
    echo "bound). A Shade's bytes are its writes only (what it reads depends on the view). The last"
    echo "row of each table is the whole frame's wall time (submission to completion, median): on"
    echo "lavapipe the end timestamp of a compute pass does not wait for its dispatches (measured in"
    echo "docs/agreement.md), so there a compute pass's own time reads too low (even below its bound)"
    echo "and the work shows up nowhere else in the timestamps: compare schedules on lavapipe by the"
    echo "wall-clock row."
    echo
    echo "Device: $device."
    echo
    cat "$body"
    if [ -n "${AGREEMENT:-}" ]; then
        echo "## Generated against hand-written (agreement timings)"
        echo
        echo "\`SSHC_TIMINGS_SHADOW=${SSHC_TIMINGS_SHADOW:-2048} SSHC_TIMINGS_CAMERA=${SSHC_TIMINGS_CAMERA:-1024} $AGREEMENT --bench\`"
        echo "(docs/agreement.md explains the table and its verdict; exit status $agreement_status)."
        echo
        cat "$tmp/agreement.md"
        echo
    fi
    echo "Took $(($(date +%s) - start)) s."
} > "$out"
echo "wrote $out"
