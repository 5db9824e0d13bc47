#!/usr/bin/env bash
# Measures techniques on a scene of several lights (issue 16): each light's frame wall
# time (`sshc render`, median of FRAMES frames; the graph runs once per light, that light
# alone), the cumulative time of the first 1, 2, ... lights, the memory peak (one light's
# textures, reused from light to light) and each light's error against the ground truth
# (`sshc compare`). Writes a Markdown report.
#
# Usage: scripts/lights.sh [SSHC] [OUT] [SCENE] [CAMERA] [FRAMES]
#   SSHC    the binary (default target/release/sshc)
#   OUT     the report (default docs/lights.md)
#   SCENE   the scene (default scenes/three-lights.ron)
#   CAMERA  camera size for the times (default 640x360; the errors use 128x128)
#   FRAMES  frames per light (default 9)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/sshc}
out=${2:-docs/lights.md}
scene=${3:-scenes/three-lights.ron}
camera=${4:-640x360}
frames=${5:-9}
[ -x "$bin" ] || { echo "no sshc binary at $bin: build it with cargo build --release -p sshc-lab"; exit 1; }
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
rows=$tmp/rows.md
: > "$rows"
device=""
kinds=""
for t in hard pcf pcss vsm esm evsm msm csm cssm; do
    log=$("$bin" render "techniques/$t.ron" --scene "$scene" --size "$camera" --frames "$frames" -o "$tmp/r.png" 2>/dev/null)
    [ -n "$device" ] || device=$(echo "$log" | sed -n 's/^device: //p')
    # `| i | Kind | ms |` rows of the per-light table
    times=$(echo "$log" | awk -F'|' '$2 ~ /^ [0-9]+ $/ && $3 ~ /[A-Za-z]/ { printf "%s ", $4 + 0 }')
    [ -n "$kinds" ] || kinds=$(echo "$log" | awk -F'|' '$2 ~ /^ [0-9]+ $/ && $3 ~ /[A-Za-z]/ { gsub(/ /, "", $3); printf "%s%s", sep, $3; sep = ", " }')
    peak=$(echo "$log" | sed -n 's/^| peak (all textures resident) | \([0-9]*\) |/\1/p')
    cmp=$("$bin" compare "techniques/$t.ron" --scene "$scene" --size 128x128 --stability-frames 0 -o "$tmp/c.png" 2>/dev/null)
    rms0=$(echo "$cmp" | sed -n 's/^error facing the light: RMS \([0-9.]*\),.*/\1/p')
    rmsk=$(echo "$cmp" | sed -n 's/^light [0-9]* ([A-Za-z]*): error facing the light: RMS \([0-9.]*\),.*/\1/p' | tr '\n' ' ')
    awk -v t="$t" -v times="$times" -v peak="$peak" -v rms="$rms0 $rmsk" 'BEGIN {
        n = split(times, ms, " "); split(rms, e, " "); sum = 0; cum = ""; per = ""; err = "";
        for (i = 1; i <= n; i++) { sum += ms[i]; cum = cum sprintf("%s%.2f", (i > 1 ? " / " : ""), sum);
            per = per sprintf("%s%.2f", (i > 1 ? " / " : ""), ms[i]); err = err sprintf("%s%.2f", (i > 1 ? " / " : ""), e[i]) }
        printf "| %s | %s | %s | %.2f | %s | %s |\n", t, per, cum, (ms[1] > 0 ? sum / ms[1] : 0), peak, err }' >> "$rows"
    echo "$t: done" >&2
done
{
    echo "# Several lights: time, memory and error per light"
    echo
    echo "Produced by \`scripts/lights.sh $bin $out $scene $camera $frames\` on $(date -u +%Y-%m-%d), device:"
    echo "$device. The scene's lights ($kinds) are rendered one at a time: the graph runs"
    echo "once per light with that light alone in the scene, on the same textures (\`sshc render\`;"
    echo "the image is the mean of the lights' shaded images). *Per light*: each light's frame wall"
    echo "time (submission to completion, median of $frames frames at $camera); *first 1, 2, 3*: the"
    echo "frame time with the first k lights, the sum; *3 / 1*: the three lights' time over the first's;"
    echo "*peak bytes*: the textures resident, the same for any number of lights since each light"
    echo "reuses them (a technique that kept every light's maps for a later combined Shade would"
    echo "grow linearly instead); *RMS*: each light's error against its own ground truth over the"
    echo "pixels facing it, 0..255 (\`sshc compare\` at 128x128)."
    echo
    echo "| technique | per light ms | first 1 / 2 / 3 lights ms | 3 / 1 | peak bytes | RMS per light |"
    echo "|---|---|---|---|---|---|"
    cat "$rows"
} > "$out"
echo "wrote $out" >&2
