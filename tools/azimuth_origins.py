#!/usr/bin/env python3
"""Renders of one configuration with its azimuth set rotated, combined (docs/accuracy.md §6,
"What limits spikes").

    tools/azimuth_origins.py REF.exr D0/F.exr D1/F.exr D2/F.exr D3/F.exr [--name NAME]

Di/F.exr is the shading EXR of one configuration rendered with every environment azimuth
rotated by i/4 of a wedge (`φ_j = (j + i/4)·2π/m`; docs/bench-lobe/azimuth-origin.patch adds the
rotation as the variable HFGI_PHI0_FRAC). Prints the relative L2 error (CONVENTIONS.md) of each
layer against REF for:
  - each rotation alone;
  - "interleaved": texel (x, y) takes rotation (x mod 2) + 2·(y mod 2) — interleaved sampling
    (every texel still scans m azimuths, neighbours scan different ones), no filter;
  - "interleaved, 3×3 tent": that image filtered by the tent [1 2 1]ᵀ[1 2 1]/16, which gives
    each of the four rotations a quarter of the weight — the reconstruction interleaved
    sampling needs to be worth anything (here on the shaded layers, an upper bound on what a
    filter of U and V with each texel's own normal would do on smooth ground);
  - "mean of the four": ≈ the same configuration at 4m azimuths (what the filter aims at).
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare_layers import read_layers, rel_l2  # noqa: E402

LAYERS = ("direct", "indirect", "total")


def tent(a):
    p = np.pad(a, ((1, 1), (1, 1), (0, 0)), mode="edge")
    w = (1.0, 2.0, 1.0)
    out = np.zeros_like(a)
    for dy in range(3):
        for dx in range(3):
            out += w[dy] * w[dx] * p[dy:dy + a.shape[0], dx:dx + a.shape[1]]
    return out / 16.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("ref")
    ap.add_argument("rotated", nargs=4)
    ap.add_argument("--name", default="")
    a = ap.parse_args()
    ref = read_layers(a.ref)
    ims = [read_layers(p) for p in a.rotated]
    h, w = ref["total"].shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    pattern = (xx % 2) + 2 * (yy % 2)
    rows = [(f"rotation {i}/4", [im[layer] for layer in LAYERS]) for i, im in enumerate(ims)]
    inter = []
    for layer in LAYERS:
        c = np.zeros_like(ims[0][layer])
        for k in range(4):
            c[pattern == k] = ims[k][layer][pattern == k]
        inter.append(c)
    rows.append(("interleaved", inter))
    rows.append(("interleaved, 3×3 tent", [tent(c) for c in inter]))
    rows.append(("mean of the four (≈ 4m azimuths)", [sum(im[layer] for im in ims) / 4.0 for layer in LAYERS]))
    for label, layers in rows:
        errs = " | ".join(f"{100 * rel_l2(x, ref[layer]):.3f}%" for x, layer in zip(layers, LAYERS))
        print(f"| {a.name} | {label} | {errs} |")


if __name__ == "__main__":
    main()
