#!/usr/bin/env bash
# Bevy's shadows and sshc's inside Bevy, each against sshc's truth at Bevy's pixels
# (docs/bevy.md, "Against the truth"): the example's frames in linear light with the sun
# still, the scene as the plugin shades it (`bevy_sshc::ExportScene`), `sshc truth` of that
# scene, then `against_truth` (each shadow's visibility measured from its frame).
# Usage: scripts/bevy-truth.sh [output folder] [frame size] [sun degrees]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$(realpath -m "${1:-$root/target/bevy-truth}")"
size="${2:-256}"
sun="${3:-3}"
[[ "$size" =~ ^[0-9]+$ ]] || { echo "error: the frame size \`$size\` is not a whole number"; exit 2; }
[[ "$sun" =~ ^[0-9]+(\.[0-9]+)?$ ]] || { echo "error: the sun's degrees \`$sun\` is not a number"; exit 2; }
source "$root/scripts/setup.sh"

echo "-- building sshc (the truth) and the Bevy examples (with Bevy's experimental PCSS)"
(cd "$root" && cargo build -q -p sshc-lab --bin sshc)
cd "$root/runtime/bevy"
cargo build -q --ignore-rust-version --features pcss --examples
shadows=target/debug/examples/shadows
rm -rf "$out"
mkdir -p "$out"
common=(--frames 1 --still --float --size "$size" --sun-degrees "$sun")
run() {
    local name="$1"
    shift
    echo "-- $name"
    timeout 600 "$shadows" "${common[@]}" --out "$out/$name" "$@" >"$out/$name.log" 2>&1 \
        || { tail -20 "$out/$name.log"; echo "error: the example failed for $name"; exit 1; }
}
run unshadowed --light unshadowed
run off --light off
run sshc-pcss --technique pcss --visibility --export "$out/scene"
run sshc-mssm --technique mssm --visibility
run sshc-plm --technique penumbra-limit-maps --visibility
run bevy-pcf --bevy
# Bevy's soft_shadow_size has no stated unit for a directional light (its shader scales
# the blocker distance by it in the cascade's depth units): a range of sizes
bevy_pcss=(0.5 1 2 4 8)
for s in "${bevy_pcss[@]}"; do
    run "bevy-pcss-$s" --bevy --bevy-pcss "$s"
done

echo "-- the truth at the example's pixels (sshc truth)"
"$root/target/debug/sshc" truth --scene "$out/scene/scene.ron" -o "$out/truth.pfm" --cache "$out/truth-cache"

echo "-- the errors"
shadows_args=(
    "Bevy PCF=$out/bevy-pcf/frame-000.pfm"
)
for s in "${bevy_pcss[@]}"; do
    shadows_args+=("Bevy PCSS $s=$out/bevy-pcss-$s/frame-000.pfm")
done
shadows_args+=(
    "sshc PCSS=$out/sshc-pcss/frame-000.pfm"
    "sshc MSSM=$out/sshc-mssm/frame-000.pfm"
    "sshc PLM=$out/sshc-plm/frame-000.pfm"
)
target/debug/examples/against_truth measure --truth "$out/truth.pfm" \
    --unshadowed "$out/unshadowed/frame-000.pfm" --off "$out/off/frame-000.pfm" --out "$out" \
    --check "sshc PCSS=$out/sshc-pcss/visibility-000.pfm" \
    --check "sshc MSSM=$out/sshc-mssm/visibility-000.pfm" \
    --check "sshc PLM=$out/sshc-plm/visibility-000.pfm" \
    "${shadows_args[@]}"
