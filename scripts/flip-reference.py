#!/usr/bin/env python3
"""Expected FLIP values for lab/tests/flip.rs, from NVIDIA's own implementation.

Writes three generated image pairs (reference and test, 64 x 48 RGB8 PNG) into
lab/tests/data/flip/ and, for each pair, the mean LDR-FLIP and a few pixels of the error
map that NVIDIA's Python package `flip-evaluator` computes at 67 pixels per degree, into
lab/tests/data/flip/expected.ron. Run once; its outputs are committed:

    pip install flip-evaluator==1.7 numpy pillow
    python3 scripts/flip-reference.py

The pairs are shadow-like: a soft penumbra ramp against a hard edge, a grey shading
against the same with a darker band, and a checker against it shifted by one pixel.
"""
import os

import numpy as np
from PIL import Image
import flip_evaluator

W, H = 64, 48
OUT = os.path.join(os.path.dirname(__file__), "..", "lab", "tests", "data", "flip")


def grey(v):
    """An RGB8 image from grey levels in [0, 1]."""
    g = np.clip(np.round(v * 255.0), 0, 255).astype(np.uint8)
    return np.stack([g, g, g], axis=-1)


def pairs():
    x = np.arange(W)[None, :].repeat(H, axis=0).astype(np.float64)
    y = np.arange(H)[:, None].repeat(W, axis=1).astype(np.float64)
    # a penumbra 16 pixels wide against a hard edge at its middle
    soft = 0.12 + 0.88 * np.clip((x - 24.0) / 16.0, 0.0, 1.0)
    hard = 0.12 + 0.88 * (x >= 32.0)
    yield "penumbra", grey(soft), grey(hard)
    # Lambert-like shading, and the same with a band 6 rows high at 40 % of it
    shade = 0.12 + 0.88 * (0.3 + 0.7 * x / (W - 1)) * (0.5 + 0.5 * y / (H - 1))
    band = np.where((y >= 20) & (y < 26), 0.12 + 0.4 * (shade - 0.12), shade)
    yield "band", grey(shade), grey(band)
    # a 4-pixel checker and the same one pixel to the right
    checker = ((np.floor(x / 4) + np.floor(y / 4)) % 2) * 0.76 + 0.12
    shifted = ((np.floor((x - 1) / 4) + np.floor(y / 4)) % 2) * 0.76 + 0.12
    yield "checker", grey(checker), grey(shifted)


def main():
    os.makedirs(OUT, exist_ok=True)
    lines = ["// written by scripts/flip-reference.py with flip-evaluator " + "1.7; do not edit", "["]
    for name, ref, test in pairs():
        rp, tp = os.path.join(OUT, f"{name}-reference.png"), os.path.join(OUT, f"{name}-test.png")
        Image.fromarray(ref).save(rp)
        Image.fromarray(test).save(tp)
        error_map, mean, params = flip_evaluator.evaluate(rp, tp, "LDR", applyMagma=False, parameters={"ppd": 67.0})
        error_map = np.asarray(error_map, dtype=np.float64).reshape(H, W)
        probes = [(0, 0), (31, 24), (32, 24), (40, 10), (63, 47), (5, 22)]
        samples = ", ".join(f"(({px}, {py}), {error_map[py, px]:.9g})" for px, py in probes)
        lines.append(f'    (name: "{name}", mean: {float(mean):.9g}, pixels: [{samples}]),')
    lines.append("]")
    with open(os.path.join(OUT, "expected.ron"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
