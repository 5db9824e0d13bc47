#!/usr/bin/env bash
# The figures of docs/viewer.md, from scripted `sshc view` runs in a real window on a
# virtual X server:
#   1. the screenshots (docs/viewer/*.png);
#   2. sshc's per-pass GPU time in the viewer against `sshc render` on the same
#      configuration, as a ratio taken in one run, repeated (truth paused: no truth view on);
#   3. the time from saving a technique to the first frame of the recompiled technique, for
#      every bundled technique, split into compile, pipeline creation, binding and the rest;
#   4. the truth's refinement: mean and largest standard error against time.
# Writes target/viewer-figures/*.md (pasted into docs/viewer.md) and docs/viewer/*.png.
# Usage: scripts/viewer-figures.sh [REPEATS]   (about 10 minutes on 2 cores with lavapipe)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-3}
source scripts/setup.sh --test
# the dev profile (dependencies optimised, the workspace crates not): what the suite builds
cargo build -q -p sshc-lab --bin sshc
sshc=target/debug/sshc
out=target/viewer-figures
rm -rf "$out" && mkdir -p "$out" docs/viewer
view() { xvfb-run -a -s "-screen 0 1280x1024x24" "$sshc" view "$@"; }

# 1. Screenshots: panels open (a window at least 600 wide opens them).
cat > "$out/shots.ron" <<EOF
[
    Wait(3),
    Screenshot("docs/viewer/shaded.png"),
    Show(Texture(name: "shadow", layer: 0, level: 0, channel: 0, lo: 0.3, hi: 1.0, map: Viridis)),
    Wait(2),
    Screenshot("docs/viewer/shadow-map.png"),
    Show(Error(range: 0.25)),
    WaitTruth(8),
    Screenshot("docs/viewer/error.png"),
]
EOF
view techniques/pcss.ron --scene scenes/contact.ron --size 720x480 --script "$out/shots.ron" --log "$out/shots.jsonl" >/dev/null
rm -f docs/viewer/*.visibility.pfm

# 2. GPU time, viewer against render, same configuration, in one run.
{
    echo "| technique | run | viewer: sshc's passes, GPU ms (median of 60 frames) | render: the same | ratio | viewer: panels CPU ms | viewer: frame interval ms |"
    echo "|---|---|---|---|---|---|---|"
} > "$out/gpu.md"
for t in hard pcss vsm penumbra-maps; do
    for r in $(seq 1 "$repeats"); do
        cat > "$out/gpu.ron" <<EOF
[ Wait(70), Screenshot("$out/gpu.png") ]
EOF
        view techniques/$t.ron --scene scenes/contact.ron --size 480x360 --shadow-map 1024 --script "$out/gpu.ron" --log "$out/gpu.jsonl" >/dev/null
        python3 - "$out" "$t" "$r" "$sshc" <<'PY' >> "$out/gpu.md"
import json, subprocess, sys, shlex, statistics
out, t, r, sshc = sys.argv[1:]
shot = [json.loads(l) for l in open(f"{out}/gpu.jsonl") if '"screenshot"' in l][-1]
viewer = sum(shot["pass_ms"].values())
words = shlex.split(shot["command"])[1:]
words[words.index("--out") + 1] = f"{out}/render.png"
text = subprocess.run([sshc] + words + ["--frames", "60"], capture_output=True, text=True, check=True).stdout
render = 0.0
for line in text.splitlines():
    cells = [c.strip() for c in line.strip("|").split("|")]
    if len(cells) > 2 and cells[0] in shot["pass_ms"]:
        render += float(cells[1])
print(f"| {t} | {r} | {viewer:.3f} | {render:.3f} | {viewer / render:.3f} | {shot['ui_ms']:.2f} | {shot['frame_ms']:.1f} |")
PY
    done
done

# 3. Save to first frame, every bundled technique (a copy of each, saved unchanged), on
# the contact scene's sphere light, or the linear light's scene for the two that sample a
# light's edges.
mkdir -p "$out/techniques"
: > "$out/reload.jsonl"
for scene in contact linear; do
    script="$out/reload-$scene.ron"
    echo "[" > "$script"
    for f in techniques/*.ron; do
        case "$(basename "$f" .ron)" in
            linear-light|point-samples) want=linear ;;
            *) want=contact ;;
        esac
        [ "$want" = "$scene" ] || continue
        cp "$f" "$out/techniques/"
        c="$out/techniques/$(basename "$f")"
        cat >> "$script" <<EOF
    Technique("$c"), WaitReady, Wait(2), Edit(path: "$c", from: "(", to: "("), WaitCompiled, Wait(2),
EOF
    done
    echo "]" >> "$script"
    first=$(grep -o '"[^"]*"' "$script" | head -1 | tr -d '"')
    view "$first" --scene scenes/$scene.ron --size 480x360 --script "$script" --log "$out/reload-$scene.jsonl" >/dev/null
    cat "$out/reload-$scene.jsonl" >> "$out/reload.jsonl"
done
python3 - "$out" <<'PY' > "$out/reload.md"
import json, sys, os
out = sys.argv[1]
rows = [json.loads(l) for l in open(f"{out}/reload.jsonl") if '"first frame"' in l]
print("| technique | save to first frame, ms | compile | pipelines | binding | the rest (watch, first frame) | under 1 s |")
print("|---|---|---|---|---|---|---|")
for e in rows:
    if e.get("save_to_frame_ms") is None:
        continue
    total = e["save_to_frame_ms"]
    rest = total - e["compile_ms"] - e["pipelines_ms"] - e["bind_ms"]
    ok = "yes" if total < 1000 else ("no (pipelines alone over 1 s)" if e["pipelines_ms"] >= 1000 else "**no**")
    name = os.path.basename(e["technique"])
    print(f"| {name} | {total:.0f} | {e['compile_ms']:.0f} | {e['pipelines_ms']:.0f} | {e['bind_ms']:.0f} | {rest:.0f} | {ok} |")
PY

# 4. The truth's refinement at the scene's own camera size.
cat > "$out/truth.ron" <<EOF
[ Show(StdError(range: 0.05)), WaitTruth(16) ]
EOF
view techniques/pcss.ron --scene scenes/contact.ron --script "$out/truth.ron" --log "$out/truth.jsonl" >/dev/null
python3 - "$out" <<'PY' > "$out/truth.md"
import json, sys
out = sys.argv[1]
rows = [json.loads(l) for l in open(f"{out}/truth.jsonl") if '"truth"' in l]
print("| rounds | light samples per pixel | seconds | mean std. error | largest std. error | RMS error of PCSS (surface, penumbra) |")
print("|---|---|---|---|---|---|")
for e in rows:
    print(f"| {e['rounds']} | {32 * e['rounds']} | {e['seconds']:.2f} | {e['mean_std_error']:.5f} | {e['max_std_error']:.4f} | {e['rms']:.4f}, {e['rms_penumbra']:.4f} |")
PY
head -100 "$out"/*.md
