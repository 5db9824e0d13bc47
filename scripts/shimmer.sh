#!/usr/bin/env bash
# Shimmer of cascaded shadow maps: the cascades are refitted as if the camera slid
# sideways by STEP world units a frame over FRAMES frames (`--cascade-offset`), the image's
# camera unmoved, with and without snapping them to whole texels; for each, the mean
# |change| of the visibility per pixel between consecutive frames (0..255). The surfaces
# seen do not change: what changes is the shadow's texels swimming as the cascades move.
# docs/scale.md holds its output.
#
#   scripts/shimmer.sh [TECHNIQUE]    default hard
#
# Environment: SSHC (default target/release/sshc), CASCADES (default 4), SIDE (default
# 1024), STEP (default 0.01), FRAMES (default 8), SIZE (default 256x256).
set -euo pipefail
cd "$(dirname "$0")/.."
SSHC=${SSHC:-target/release/sshc}
[[ -x $SSHC ]] || cargo build --release -p sshc-lab --quiet
t=${1:-hard}
out=$(mktemp -d)
frames=${FRAMES:-8}
for snap in snapped unsnapped; do
    flag=()
    [[ $snap == unsnapped ]] && flag=(--no-snap)
    for ((i = 0; i < frames; i++)); do
        x=$(python3 -c "print($i * ${STEP:-0.01})")
        "$SSHC" render "techniques/$t.ron" --scene scenes/large/city.ron --cascade-offset "$x,0,0" --size "${SIZE:-256x256}" \
            --cascades "${CASCADES:-4}" --shadow-map "${SIDE:-1024}" "${flag[@]}" \
            -o "$out/$snap-$i.png" --visibility "$out/$snap-$i.pfm" >"$out/$snap-$i.txt" 2>&1
    done
done
python3 - "$out" "$frames" "$t" <<'PY'
import struct, sys
out, frames, t = sys.argv[1], int(sys.argv[2]), sys.argv[3]
def pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * (3 if kind == b"PF" else 1)
        data = struct.unpack(("<" if scale < 0 else ">") + "f" * n, f.read(4 * n))
    return data[:: (3 if kind == b"PF" else 1)]
print(f"| {t}, camera sliding | mean abs change per frame (0..255) |")
print("|---|---|")
for snap in ("snapped", "unsnapped"):
    frames_v = [pfm(f"{out}/{snap}-{i}.pfm") for i in range(frames)]
    changes = [sum(abs(a - b) for a, b in zip(p, q)) / len(p) * 255 for p, q in zip(frames_v, frames_v[1:])]
    print(f"| {snap} | {sum(changes) / len(changes):.3f} |")
PY
echo "scratch: $out" >&2
