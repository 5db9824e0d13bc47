#!/usr/bin/env bash
# The memory a scene of many triangles needs (docs/reliability.md, issue 48 item 14;
# lab/scene/src/memory.rs): peak resident memory of `sshc truth` and `sshc render` on the
# generated city at 1 M and 2 M triangles, 64 x 64 pixels, a 512-texel shadow map. The
# slope between the two is the bytes a triangle costs.
#
#   scripts/memory-figures.sh [SSHC]      (default: target/debug/sshc)
set -euo pipefail
cd "$(dirname "$0")/.."
sshc=${1:-target/debug/sshc}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
export LP_NUM_THREADS=${LP_NUM_THREADS:-2} XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
for n in 1000000 2000000; do
    "$sshc" scene city --triangles "$n" -o "$dir/c$n.glb" >/dev/null
    cat >"$dir/c$n.ron" <<RON
Scene(camera: Perspective(position: (-6.0, 5.0, 15.0), target: (1.0, 0.0, 2.0), fov_y_degrees: 50.0, width: 64, height: 64),
      shadow_map: 512, lights: [DistantDisk(direction: (0.77, 0.342, 0.54), angle_degrees: 0.53)],
      objects: [Object(name: "city", mesh: Gltf(path: "c$n.glb"))])
RON
    for cmd in truth render; do
        if [[ $cmd == truth ]]; then
            args=(truth --scene "$dir/c$n.ron" --samples 4 --runs 2 --no-cache -o "$dir/t.pfm")
        else
            args=(render techniques/hard.ron --scene "$dir/c$n.ron" -o "$dir/r.png")
        fi
        # /usr/bin/time writes the peak (KiB) as the last line of standard error
        /usr/bin/time -f "%M" "$sshc" "${args[@]}" >/dev/null 2>"$dir/err"
        echo "$cmd $n triangles: peak $(( $(tail -1 "$dir/err") / 1024 )) MiB"
    done
done
