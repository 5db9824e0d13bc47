#!/usr/bin/env python3
"""Where penumbra limit maps' error on Lawlor's set-up sits: the RMS over the shadow on the
ground (ground pixels whose truth is below 1 or within the penumbra's reach of one), and
the same without the pixels within one shadow-map texel of the triangle's corners (the
corners Lawlor 2006, section 4 says a low-resolution map cannot capture).

Usage (PFMs from `sshc truth` and `sshc render --visibility/--positions` on
scenes/triangle-lawlor.ron):
  scripts/lawlor-corners.py TRUTH.pfm POSITIONS.pfm N:EXTENT=VIS.pfm [N:EXTENT=VIS.pfm ...]
N is the map's texels per side, EXTENT the world width of the fitted map (`sshc render`
prints it). Standard library only."""
import math
import struct
import sys

CORNERS = [(0.5, -0.5), (-0.5, -0.5), (0.0, 0.5)]  # the triangle's corners, (x, z)
REACH = 0.0525  # the penumbra's reach: 0.6 tan(5 degrees)


def pfm(path):
    with open(path, 'rb') as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        c = 3 if kind == b'PF' else 1
        v = struct.unpack(('<' if scale < 0 else '>') + 'f' * (w * h * c), f.read())
        return [v[i * c:(i + 1) * c] for i in range(w * h)], w


def main():
    truth, w = pfm(sys.argv[1])
    pos, _ = pfm(sys.argv[2])
    pixel = abs(pos[1][0] - pos[0][0])
    r = int(math.ceil(REACH / pixel))
    dark = {i for i, t in enumerate(truth) if t[0] < 1.0}
    ground = []
    for i in range(len(truth)):
        y, x = divmod(i, w)
        inside = i in dark or any(
            (y + dy) * w + (x + dx) in dark
            for dy in range(-r, r + 1)
            for dx in range(-r, r + 1)
            if 0 <= y + dy < w and 0 <= x + dx < w and (dx * dx + dy * dy) * pixel * pixel <= REACH * REACH
        )
        if inside:
            ground.append(i)
    for arg in sys.argv[3:]:
        size, path = arg.split('=')
        n, extent = size.split(':')
        vis, _ = pfm(path)
        texel = float(extent) / int(n)
        all_sq, far_sq, far = 0.0, 0.0, 0
        for i in ground:
            e = (vis[i][0] - truth[i][0]) * 255.0
            all_sq += e * e
            if min(math.hypot(pos[i][0] - a, pos[i][2] - b) for a, b in CORNERS) > texel:
                far_sq += e * e
                far += 1
        print(f"{n} texels: {len(ground)} px, RMS {math.sqrt(all_sq / len(ground)):.2f}; "
              f"beyond a texel ({texel:.4f}) of the corners: {far} px, RMS {math.sqrt(far_sq / far):.2f}")


if __name__ == '__main__':
    main()
