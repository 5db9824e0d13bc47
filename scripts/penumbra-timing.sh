#!/usr/bin/env bash
# A Geometry-pass technique's passes against the triangle count: a sphere of 32 to 320
# segments (1.4k to 153k edges) over a floor under a sphere light, rendered at a 1024 shadow
# map, 9 frames (median GPU ms per pass). Prints the edges, the silhouettes the last frame
# generated and the per-pass rows of `sshc render`.
# Usage: scripts/penumbra-timing.sh [sshc binary] [technique, default penumbra maps]
set -euo pipefail
cd "$(dirname "$0")/.."
sshc=${1:-target/release/sshc}
technique=${2:-techniques/penumbra-maps.ron}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
for s in 32 64 112 160 224 320; do
    cat > "$dir/sphere$s.ron" <<SCENE
Scene(
    camera: Perspective(position: (0.0, 3.0, 4.0), target: (0.0, 0.5, 0.0), fov_y_degrees: 40.0, width: 256, height: 256),
    shadow_map: 1024,
    lights: [Sphere(center: (0.6, 4.0, 0.4), radius: 0.3)],
    objects: [
        Object(name: "floor", mesh: Plane(size: (6.0, 6.0))),
        Object(name: "ball", mesh: Sphere(radius: 0.6, segments: $s), transform: (translate: (0.0, 0.9, 0.0))),
    ],
)
SCENE
    echo "== sphere of $s segments"
    "$sshc" render "$technique" --scene "$dir/sphere$s.ron" -o "$dir/sphere$s.png" --frames 9 \
        | grep -E "^edges:|silhouettes:|^\| [a-z_]+ \| [0-9.]+ \| [0-9.]+e[0-9]+ \|"
done
