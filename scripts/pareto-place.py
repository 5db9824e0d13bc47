#!/usr/bin/env python3
"""Place the configurations of one sweep against the Pareto fronts (penumbra RMS against
time ratio, and against peak memory) of another sweep of the same scenes and truth:
which configurations of the second sweep join the front and which dominate the rest.

Usage: scripts/pareto-place.py BASE/sweep.csv NEW/sweep.csv [TECHNIQUE ...]
The reference technique of NEW (timed again in its run) is left out. Standard library only."""
import csv
import sys


def load(path, skip_reference):
    rows = []
    for r in csv.DictReader(open(path)):
        if not r['time_ratio'] or (skip_reference and r['technique'] == 'hard'):
            continue
        rows.append((r['scene'], r['technique'], r['config'], float(r['time_ratio']),
                     float(r['rms_penumbra']), float(r['peak_bytes']) / 2**20))
    return rows


def dominated(r, rows, axis):
    return [o for o in rows if o is not r and o[axis] <= r[axis] and o[4] <= r[4]
            and (o[axis] < r[axis] or o[4] < r[4])]


def main():
    rows = load(sys.argv[1], False) + load(sys.argv[2], True)
    wanted = set(sys.argv[3:])
    for scene in sorted({r[0] for r in rows}):
        rs = [r for r in rows if r[0] == scene]
        for r in rs:
            if wanted and r[1] not in wanted:
                continue
            for axis, what, unit in ((3, 'time', 'x%.2f'), (5, 'memory', '%.1f MiB')):
                d = dominated(r, rs, axis)
                best = min(d, key=lambda o: o[axis]) if d else None
                where = 'on the front' if not d else (
                    f"dominated by {len(d)}, e.g. {best[1]} {best[2]} ({unit % best[axis]}, {best[4]:.1f})")
                print(f"{scene}: {r[1]} {r[2]} ({unit % r[axis]}, penumbra RMS {r[4]:.1f}) {what}: {where}")


if __name__ == '__main__':
    main()
