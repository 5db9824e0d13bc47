#!/bin/bash
# Every bundled technique on every bundled scene rendered by two `sshc` binaries (say, a
# build of an earlier commit and this one), the visibility PFM and the PNG compared byte
# for byte. Prints each pair that differs or that only one binary renders, then the counts.
#
#   scripts/compare-renders.sh OLD_SSHC NEW_SSHC OUT_DIR
#
# Issue 49 ran it with OLD_SSHC built from commit a6ce2b0 (the last executor) in a worktree
# with a target of its own: 372 pairs byte-identical, 42 refused by both (docs/embedding.md).
set -u
if [ $# -ne 3 ]; then
    echo "usage: scripts/compare-renders.sh OLD_SSHC NEW_SSHC OUT_DIR" >&2
    exit 2
fi
old=$1 new=$2 out=$3
cd "$(dirname "$0")/.."
mkdir -p "$out/old" "$out/new"
same=0 differ=0 one_side=0 both_fail=0
for t in techniques/*.ron; do
    for s in scenes/*.ron; do
        n="$(basename "$t" .ron)_$(basename "$s" .ron)"
        run() {
            LP_NUM_THREADS=1 timeout 120 "$1" render "$t" --scene "$s" --size 48x48 --shadow-map 128 \
                --visibility "$out/$2/$n.pfm" -o "$out/$2/$n.png" >/dev/null 2>&1
        }
        run "$old" old; a=$?
        run "$new" new; b=$?
        if [ $a -ne 0 ] && [ $b -ne 0 ]; then both_fail=$((both_fail + 1)); continue; fi
        if [ $a -ne 0 ] || [ $b -ne 0 ]; then
            one_side=$((one_side + 1))
            echo "renders on one side only: $n (old exit $a, new exit $b)"
            continue
        fi
        if cmp -s "$out/old/$n.pfm" "$out/new/$n.pfm" && cmp -s "$out/old/$n.png" "$out/new/$n.png"; then
            same=$((same + 1))
        else
            differ=$((differ + 1))
            echo "differs: $n"
        fi
    done
done
echo "byte-identical $same, differ $differ, one side only $one_side, refused by both $both_fail"
[ "$differ" -eq 0 ] && [ "$one_side" -eq 0 ]
