#!/usr/bin/env python3
"""Writes a UV sphere as exporters write it: its seam duplicated (the column at longitude
2 pi computed again, a few ulps from the one at 0, in f32), and each pole a vertex per
segment. With `--slit K` the duplicated column is moved K welding tolerances
(2^-17 of the extent) along the longitude: a real opening, not a seam.

    python3 scripts/seam-sphere.py scenes/seams/seam-sphere.obj
    python3 scripts/seam-sphere.py scenes/seams/slit-sphere.obj --slit 10
"""
import math
import struct
import sys


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def main():
    args = sys.argv[1:]
    if not args or len(args) not in (1, 3) or (len(args) == 3 and args[1] != "--slit"):
        sys.exit("usage: seam-sphere.py OUT.obj [--slit K]")
    out = args[0]
    slit = float(args[2]) if len(args) == 3 else 0.0
    rings, segments, radius = 24, 48, 0.5
    tolerance = 2 * radius / 131072.0
    lines = ["# UV sphere, radius 0.5, its seam duplicated (scripts/seam-sphere.py)"]
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            # the last column a few ulps from the first (f32 of cos and sin of 2 pi), or
            # moved `slit` tolerances along the longitude
            if s == segments and slit:
                phi = 2 * math.pi + slit * tolerance / max(radius * math.sin(theta), 1e-6)
            x = f32(radius * math.sin(theta) * math.cos(phi))
            y = f32(radius * math.cos(theta))
            z = f32(radius * math.sin(theta) * math.sin(phi))
            lines.append(f"v {x!r} {y!r} {z!r}")
    row = segments + 1
    for r in range(rings):
        for s in range(segments):
            a, b = r * row + s + 1, r * row + s + 2
            c, d = a + row, b + row
            if r > 0:
                lines.append(f"f {a} {c} {b}")
            if r < rings - 1:
                lines.append(f"f {b} {c} {d}")
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
