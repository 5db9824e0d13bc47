#!/usr/bin/env bash
# Measures scene specialisation (issue 16) for every bundled technique on every bundled
# scene whose light its `light:` list admits: the work per invocation of each pass in the
# generic and the specialised build (`sshc explain --scene`), and the GPU time of both
# (`sshc render`, then `sshc render --generic`, in turn, median of FRAMES frames), and writes
# a Markdown report. Pairs the technique cannot render (a per-sample technique on a light it
# cannot sample) are listed as such.
#
# Usage: scripts/specialisation.sh [SSHC] [OUT] [CAMERA] [MAP] [FRAMES]
#   SSHC    the binary (default target/release/sshc)
#   OUT     the report (default docs/specialisation.md)
#   CAMERA  camera size (default 640x360)
#   MAP     shadow-map size (default 1024)
#   FRAMES  frames per run (default 9)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/sshc}
out=${2:-docs/specialisation.md}
camera=${3:-640x360}
map=${4:-1024}
frames=${5:-9}
[ -x "$bin" ] || { echo "no sshc binary at $bin: build it with cargo build --release -p sshc-lab"; exit 1; }
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
start=$(date +%s)
rows=$tmp/rows.md
refused=$tmp/refused.md
: > "$rows"
: > "$refused"
device=""
for t in techniques/*.ron; do
    name=$(basename "$t" .ron)
    for s in scenes/*.ron; do
        scene=$(basename "$s" .ron)
        if ! "$bin" check "$t" --scene "$s" > /dev/null 2> "$tmp/check.err"; then
            light=$(sed -n 's/.*does not admit the \([A-Za-z]*\) light.*/\1/p' "$tmp/check.err" | head -n 1)
            echo "$name|$scene|$light" >> "$refused"
            continue
        fi
        explain=$("$bin" explain "$t" --scene "$s")
        light=$(echo "$explain" | sed -n 's/^Specialised for scene .* (a \([A-Za-z]*\) light;.*/\1/p')
        # passes whose work changed: `pass g -> s` operations (and fetches where they moved)
        work=$(echo "$explain" | awk -F'|' '/^  \| [a-z_0-9]+ \| [0-9]/ {
                gsub(/ /, "", $2); fg = $3 + 0; fs = $4 + 0; og = $5 + 0; os = $6 + 0;
                if (og != os || fg != fs) { printf "%s%s %d -> %d ops", sep, $2, og, os; if (fg != fs) printf " (%d -> %d fetches)", fg, fs; sep = "; " } }')
        [ -n "$work" ] || work="none"
        folded=$(echo "$explain" | sed -n '/^Specialised for scene/,/^$/p' | grep -c 'folded' || true)
        ok=1
        for kind in specialised generic; do
            flag=()
            [ "$kind" = generic ] && flag=(--generic)
            if ! log=$("$bin" render "$t" --scene "$s" --size "$camera" --shadow-map "$map" --frames "$frames" \
                "${flag[@]}" -o "$tmp/r.png" 2> "$tmp/render.err"); then
                ok=0
                break
            fi
            [ -n "$device" ] || device=$(echo "$log" | sed -n 's/^device: //p')
            echo "$log" | sed -n 's/^frame wall time: \([0-9.]*\) ms.*/\1/p' > "$tmp/$kind.wall"
            echo "$log" | awk -F'|' '$2 ~ /^ shade / { print $3 + 0 }' > "$tmp/$kind.shade"
        done
        if [ "$ok" = 0 ]; then
            echo "$name|$scene|cannot render: $(head -n 1 "$tmp/render.err")" >> "$refused"
            continue
        fi
        awk -v t="$name" -v sc="$scene" -v l="$light" -v f="$folded" -v w="$work" \
            -v gs="$(cat "$tmp/generic.shade")" -v ss="$(cat "$tmp/specialised.shade")" \
            -v gw="$(cat "$tmp/generic.wall")" -v sw="$(cat "$tmp/specialised.wall")" \
            'BEGIN { printf "| %s | %s | %s | %d | %s | %.3f | %.3f | %.2f | %.2f |\n", t, sc, l, f, w, gs, ss, (gs > 0 ? ss / gs : 0), (gw > 0 ? sw / gw : 0) }' >> "$rows"
        echo "$name on $scene: done ($(($(date +%s) - start)) s)" >&2
    done
done
{
    echo "# Scene specialisation: the generic build against the specialised one"
    echo
    echo "Produced by \`scripts/specialisation.sh $bin $out $camera $map $frames\` on $(date -u +%Y-%m-%d),"
    echo "device: $device. Every bundled technique on every bundled scene whose light its \`light:\`"
    echo "list admits, compiled for any scene (\`--generic\`) and for the scene (the default of"
    echo "\`sshc render\`; \`sshc compile --scene\`). *Folded*: the light inputs that are 0 for the scene's"
    echo "light kind and that the technique reads (\`sshc explain --scene\` lists them; the Shade's"
    echo "local or distant form is folded besides in every pair). *Work*: the passes whose operations"
    echo "or fetches per invocation changed, generic -> specialised (\`sshc explain --scene\`). *Shade"
    echo "ms*: the Shade pass's GPU time, median of $frames frames, the two builds run in turn at"
    echo "${camera} with a ${map}^2 map; *frame*: the whole frame's wall time, specialised over"
    echo "generic. Both builds give the same visibility bit for bit on every pair"
    echo "(\`specialised_builds_give_the_generic_visibility_bit_for_bit\` in tests/tests/gpu.rs)."
    echo
    echo "| technique | scene | light | folded | work (ops per invocation) | shade ms generic | shade ms specialised | shade ratio | frame ratio |"
    echo "|---|---|---|---|---|---|---|---|---|"
    cat "$rows"
    echo
    echo "Refused or not rendered (\`sshc compile --scene\` refuses a light the technique's \`light:\` list"
    echo "does not admit; \`sshc render\` warns and renders such a pair generic):"
    echo
    echo "| technique | scene | why |"
    echo "|---|---|---|"
    awk -F'|' '{ if ($3 ~ /^cannot/) printf "| %s | %s | %s |\n", $1, $2, $3; else printf "| %s | %s | its `light:` list does not admit the %s light |\n", $1, $2, $3 }' "$refused"
} > "$out"
echo "wrote $out ($(($(date +%s) - start)) s)" >&2
