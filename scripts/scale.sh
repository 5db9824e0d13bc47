#!/usr/bin/env bash
# How sshc grows with the scene: the generated city (`sshc scene city`) from 10 k to 4 M
# triangles under a low sun, each stage's wall time and resident memory, each pass's GPU
# time, the truth's rays per second; then the exponent of a power-law fit per stage.
# docs/scale.md holds its output.
#
#   scripts/scale.sh [SIZES...]      default: 10000 30000 100000 300000 1000000 4000000
#
# Environment: SSHC (the binary, default target/release/sshc, built if missing),
# TECHNIQUES (default: hard pcss penumbra-limit-maps), FRAMES (default 3),
# OUT (the scratch folder, default a fresh temporary one).
set -euo pipefail
cd "$(dirname "$0")/.."
SSHC=${SSHC:-target/release/sshc}
[[ -x $SSHC ]] || cargo build --release -p sshc-lab --quiet
read -r -a techniques <<<"${TECHNIQUES:-hard pcss penumbra-limit-maps}"
frames=${FRAMES:-3}
sizes=("$@")
[[ ${#sizes[@]} -gt 0 ]] || sizes=(10000 30000 100000 300000 1000000 4000000)
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
rows="$out/rows.tsv"
: >"$rows"
row() { printf '%s\t%s\t%s\t%s\t%s\n' "$@" >>"$rows"; }

for n in "${sizes[@]}"; do
    dir="$out/$n"
    mkdir -p "$dir"
    echo "== $n triangles" >&2
    start=$(date +%s.%N)
    "$SSHC" scene city --triangles "$n" --seed 1 -o "$dir/city.glb" >"$dir/generate.txt"
    row "$n" generate "$(echo "$(date +%s.%N) - $start" | bc)" - -
    # a camera framing the city (about sqrt(n / 1250) blocks across) from above one corner
    extent=$(python3 -c "import math; print(max(2.0, math.sqrt($n / 1250.0)))")
    python3 - "$extent" >"$dir/city.ron" <<'EOF'
import sys
e = float(sys.argv[1])
print(f"""Scene(
    camera: Perspective(position: ({-0.35 * e}, {0.45 * e}, {0.85 * e}), target: (0.0, 0.0, {0.05 * e}),
                        fov_y_degrees: 50.0, width: 512, height: 512),
    shadow_map: 2048,
    lights: [DistantDisk(direction: (0.77, 0.342, 0.54), angle_degrees: 0.53)],
    objects: [Object(name: "city", mesh: Gltf(path: "city.glb"))],
)""")
EOF
    for t in "${techniques[@]}"; do
        log="$dir/$t.txt"
        render() {
            /usr/bin/time -f "peak %M KB" "$SSHC" render "techniques/$t.ron" --scene "$dir/city.ron" --frames "$frames" \
                -o "$dir/$t.png" "$@" >"$log" 2>&1
        }
        # per-sample techniques look from points on the light (a linear light, by default
        # two samples: its ends): a segment light high above the city's centre instead
        local_light=$(python3 -c "e = $extent; print(f'Segment(a: ({-0.05 * e}, {3 * e}, 0.0), b: ({0.05 * e}, {3 * e}, 0.0))')")
        label=$t
        if ! render && grep -q "need a light at a finite position" "$log"; then
            render --light "$local_light" || true
            label="$t (segment light)"
            echo "  $t: the sun refused (per-sample views), rendered under $local_light" >&2
        fi
        if grep -q "^Command exited with non-zero status" "$log"; then
            # lavapipe prints an XDG_RUNTIME_DIR line on every start: not the reason
            reason=$(grep -v XDG_RUNTIME_DIR "$log" | grep -m1 -E "error" | cut -c1-200)
            row "$n" "$label refused" - - "$reason"
            echo "  $t: refused: $reason" >&2
            continue
        fi
        # stage lines: `stage NAME: S s, resident M MB`
        sed -n 's/^stage \(.*\): \([0-9.]*\) s, resident \([0-9-]*\) MB$/\1\t\2\t\3/p' "$log" | while IFS=$'\t' read -r name s mb; do
            case $name in
                "scene read"*) name="scene read" ;;
                *"frame(s)") name="frames" ;;
            esac
            row "$n" "$label: $name" "$s" "$mb" -
        done
        peak=$(sed -n 's/^peak \([0-9]*\) KB$/\1/p' "$log")
        row "$n" "$label: peak resident" - "$((peak / 1024))" -
        # per-pass GPU time (median of the frames): `| pass | ms | ...`
        awk -F'|' '/^\| pass \| GPU ms/ {on = 1; next} on && /^\|---/ {next} on && !/^\|/ {on = 0} on {p = $2; m = $3; gsub(/ /, "", p); gsub(/ /, "", m); print p "\t" m}' "$log" |
            while IFS=$'\t' read -r pass ms; do row "$n" "$label: pass $pass (GPU)" "$(echo "$ms / 1000" | bc -l)" - -; done
        echo "  $t: $(grep -c . "$log") lines, peak $((peak / 1024)) MB" >&2
    done
    # the truth: 16 samples x 2 runs, uncached; rays per second from its report
    tlog="$dir/truth.txt"
    /usr/bin/time -f "peak %M KB" "$SSHC" truth --scene "$dir/city.ron" --samples 16 --runs 2 --no-cache -o "$dir/truth.pfm" >"$tlog" 2>&1
    # `truth: S s on T threads: ... at least R M rays/s`
    secs=$(sed -n 's/^truth: \([0-9.]*\) s on .*/\1/p' "$tlog")
    rays=$(sed -n 's/.*at least \([0-9.]*\) M rays\/s.*/\1/p' "$tlog")
    row "$n" "truth (16 x 2 samples)" "${secs:--}" "$(($(sed -n 's/^peak \([0-9]*\) KB$/\1/p' "$tlog") / 1024))" "${rays:--} M rays/s"
done

# the table: one row per stage, one column per size; then the fit's exponent over the sizes
# of 100 k and up (below, fixed costs dominate)
python3 - "$rows" <<'EOF'
import math, sys, collections
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
sizes = sorted({int(r[0]) for r in rows})
# the scene's own stages once (the first technique's run); per technique the rest
shared = ("scene read", "light check", "scene inputs")
first = next((r[1].split(": ")[0] for r in rows if ": " in r[1]), "")
kept = []
for r in rows:
    name, _, stage = r[1].partition(": ")
    if stage.startswith(shared):
        if name != first:
            continue
        r[1] = stage
    kept.append(r)
rows = kept
stages = list(dict.fromkeys(r[1] for r in rows))
cell = collections.defaultdict(dict)
for n, stage, s, mb, note in rows:
    cell[stage][int(n)] = (s, mb, note)
def fmt(v):
    s, mb, note = v
    parts = []
    if s != "-": parts.append(f"{float(s):.3g} s")
    if mb != "-": parts.append(f"{mb} MB")
    if note != "-": parts.append(note)
    return ", ".join(parts) or "-"
def exponent(stage):
    pts = [(math.log(n), math.log(float(v[0]))) for n, v in cell[stage].items() if n >= 100000 and v[0] != "-" and float(v[0]) > 0]
    if len(pts) < 2: return "-"
    mx = sum(p[0] for p in pts) / len(pts); my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return f"{sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx:.2f}" if sxx > 0 else "-"
print("| stage | " + " | ".join(f"{n:,}" for n in sizes) + " | time exponent (100 k and up) |")
print("|---|" + "---|" * len(sizes) + "---|")
for st in stages:
    print(f"| {st} | " + " | ".join(fmt(cell[st][n]) if n in cell[st] else "-" for n in sizes) + f" | {exponent(st)} |")
EOF
echo "scratch: $out" >&2
