#!/usr/bin/env bash
# Measures techniques on a scene of several lights (issue 16): with the scene's first 1, 2
# and 3 lights (`sshc render --lights K`), the frame's wall time (median of FRAMES frames;
# every light's passes run in one frame on its own textures, and the GPU combines them), the
# textures resident, and each light's GPU time (its passes); and each light's error against
# the ground truth (`sshc compare`). Writes a Markdown report.
#
# Usage: scripts/lights.sh [SSHC] [OUT] [SCENE] [CAMERA] [FRAMES]
#   SSHC    the binary (default target/release/sshc)
#   OUT     the report (default docs/lights.md)
#   SCENE   the scene (default scenes/three-lights.ron)
#   CAMERA  camera size for the times (default 640x360; the errors use 128x128)
#   FRAMES  frames per run (default 9)
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
refused=$tmp/refused.md
: > "$refused"
for f in techniques/*.ron; do
    t=$(basename "$f" .ron)
    # a technique that cannot render every light of the scene is listed with its reason
    if ! "$bin" render "$f" --scene "$scene" --size 16x16 --shadow-map 64 -o "$tmp/r.png" > /dev/null 2> "$tmp/err"; then
        echo "| $t | $(grep -m 1 '^error' "$tmp/err" | sed 's/^error: //; s/|/\\|/g') |" >> "$refused"
        echo "$t: cannot render the scene" >&2
        continue
    fi
    walls=""
    peaks=""
    per=""
    for k in 1 2 3; do
        log=$("$bin" render "$f" --scene "$scene" --lights "$k" --size "$camera" --frames "$frames" -o "$tmp/r.png" 2>/dev/null)
        [ -n "$device" ] || device=$(echo "$log" | sed -n 's/^device: //p')
        walls="$walls $(echo "$log" | sed -n 's/^frame wall time: \([0-9.]*\) ms.*/\1/p')"
        peaks="$peaks $(echo "$log" | sed -n 's/^| peak (all textures resident) | \([0-9]*\) |/\1/p')"
        if [ "$k" = 3 ]; then
            # `| i | Kind | ms |` rows of the per-light table
            per=$(echo "$log" | awk -F'|' '$2 ~ /^ [0-9]+ $/ && $3 ~ /[A-Za-z]/ { printf "%s%.2f", sep, $4 + 0; sep = " / " }')
            [ -n "$kinds" ] || kinds=$(echo "$log" | awk -F'|' '$2 ~ /^ [0-9]+ $/ && $3 ~ /[A-Za-z]/ { gsub(/ /, "", $3); printf "%s%s", sep, $3; sep = ", " }')
        fi
    done
    cmp=$("$bin" compare "$f" --scene "$scene" --size 128x128 --stability-frames 0 -o "$tmp/c.png" 2>/dev/null)
    rms0=$(echo "$cmp" | sed -n 's/^error facing the light: RMS \([0-9.]*\),.*/\1/p')
    rmsk=$(echo "$cmp" | sed -n 's/^light [0-9]* ([A-Za-z]*): error facing the light: RMS \([0-9.]*\),.*/\1/p' | tr '\n' ' ')
    awk -v t="$t" -v walls="$walls" -v peaks="$peaks" -v per="$per" -v rms="$rms0 $rmsk" 'BEGIN {
        split(walls, w, " "); split(peaks, m, " "); n = split(rms, e, " "); err = "";
        for (i = 1; i <= n; i++) err = err sprintf("%s%.2f", (i > 1 ? " / " : ""), e[i]);
        printf "| %s | %.2f / %.2f / %.2f | %.2f | %d / %d / %d | %.2f | %s | %s |\n", t, w[1], w[2], w[3],
            (w[1] > 0 ? w[3] / w[1] : 0), m[1], m[2], m[3], (m[1] > 0 ? m[3] / m[1] : 0), per, err }' >> "$rows"
    echo "$t: done" >&2
done
{
    echo "# Several lights: time, memory and error per light"
    echo
    echo "Produced by \`scripts/lights.sh $bin $out $scene $camera $frames\` on $(date -u +%Y-%m-%d), device:"
    echo "$device. The scene's lights ($kinds): each light has its own passes and textures,"
    echo "all run in one frame, and a compute step combines the lights' shaded images on the GPU"
    echo "(\`sshc render\`; the image is their mean, \`--visibility\` one channel per light)."
    echo "*Frame ms*: the frame's wall time (submission to completion, median of $frames frames at"
    echo "$camera) with the scene's first 1, 2 and 3 lights (\`--lights K\`); *3 / 1*: three lights'"
    echo "over one's; *bytes*: the graph's textures resident (each light's, plus the combining"
    echo "step's with two lights or more: 8 bytes a pixel per light and 20 for the results; the"
    echo "camera outputs, 36 bytes a pixel per light, are not counted, as for one light);"
    echo "*GPU ms per light*: each light's passes by"
    echo "timestamps, with all three; *RMS*: each light's error against its own ground truth over"
    echo "the pixels facing it, 0..255 (\`sshc compare\` at 128x128, which renders the lights one at"
    echo "a time)."
    echo
    echo "| technique | frame ms, 1 / 2 / 3 lights | 3 / 1 | bytes, 1 / 2 / 3 lights | 3 / 1 | GPU ms per light | RMS per light |"
    echo "|---|---|---|---|---|---|---|"
    cat "$rows"
    if [ -s "$refused" ]; then
        echo
        echo "Techniques that cannot render the scene, with the first error \`sshc render\` gives:"
        echo
        echo "| technique | error |"
        echo "|---|---|"
        cat "$refused"
    fi
} > "$out"
echo "wrote $out" >&2
