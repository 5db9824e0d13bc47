#!/usr/bin/env python3
"""Median time ratios over repeated runs of one sweep.

Timings on a shared machine drift between runs; a sweep's time ratios come from one run
(each configuration against the reference technique timed in the same run). Run the sweep
several times (`sshc sweep FILE -o DIR_i --fresh`) and give this script the runs' CSVs: it
writes, per row (scene, technique, config, light scale), the median ratio and the lowest
and highest, and the reference's own row where the sweep times it as a technique too.

    scripts/sweep-median.py RUN1/sweep.csv RUN2/sweep.csv RUN3/sweep.csv > medians.csv
"""
import csv
import statistics
import sys


def main(paths):
    if len(paths) < 2:
        sys.exit("give the sweep.csv of at least two runs of the same sweep")
    runs = [list(csv.DictReader(open(p, newline=""))) for p in paths]
    key = lambda r: (r["scene"], r["technique"], r["config"], r["light_scale"])
    keys = [key(r) for r in runs[0]]
    for p, rows in zip(paths[1:], runs[1:]):
        if [key(r) for r in rows] != keys:
            sys.exit(f"{p}: not the same rows as {paths[0]} (another sweep file or an unfinished run)")
    out = csv.writer(sys.stdout)
    out.writerow(["scene", "technique", "config", "light_scale", "runs", "median_ratio", "min_ratio", "max_ratio", "median_ms"])
    for i, k in enumerate(keys):
        ratios = [float(rows[i]["time_ratio"]) for rows in runs if rows[i]["time_ratio"]]
        ms = [float(rows[i]["gpu_ms"]) for rows in runs if rows[i]["gpu_ms"]]
        if not ratios:
            continue
        out.writerow([*k, len(ratios), f"{statistics.median(ratios):.3f}", f"{min(ratios):.3f}", f"{max(ratios):.3f}",
                      f"{statistics.median(ms):.3f}" if ms else ""])


if __name__ == "__main__":
    main(sys.argv[1:])
