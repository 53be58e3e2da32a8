#!/usr/bin/env python3
"""Where a layer's error sits relative to a field's peaks (docs/accuracy.md §6, "What limits spikes").

    tools/error_by_distance.py HEIGHTS.png REF.exr OTHER.exr [OTHER2.exr ...]
        [--layer indirect] [--rise 40] [--names a;b;...]

HEIGHTS.png is `hfgi render --heights-png` of the same scene (grey, black = lowest). A texel is a
peak when its grey level exceeds the mean of its four neighbours by more than --rise (the
one-texel spikes of scenes/hard/spikes.toml rise by far more; its gentle ground by less than 1).
Each texel is binned by its distance (texels) to the nearest peak, and per bin the tool prints
the texel count, the bin's share of the layer's squared error Σ|X − R|² (so the shares of a
file sum to 1; the file's relative L2 error, CONVENTIONS.md, is printed above them), the bin's
signed bias Σ(X − R)/ΣR and its mean reference value. Reads EXRs as tools/compare_layers.py does.
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare_layers import read_layers, rel_l2  # noqa: E402

BINS = [(0.0, 0.5), (0.5, 1.5), (1.5, 2.5), (2.5, 4.5), (4.5, 8.5), (8.5, float("inf"))]


def peaks(path, rise):
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    h = np.array(mi.Bitmap(path), copy=False).astype(np.float64)
    if h.ndim == 3:
        h = h[:, :, 0]
    p = np.pad(h, 1, mode="edge")
    around = (p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:]) / 4.0
    return h > around + rise


def distance_to(mask):
    ys, xs = np.nonzero(mask)
    if len(ys) == 0:
        sys.exit("no peaks found: lower --rise")
    yy, xx = np.mgrid[0:mask.shape[0], 0:mask.shape[1]]
    dist = np.full(mask.shape, np.inf)
    for y, x in zip(ys, xs):
        dist = np.minimum(dist, np.hypot(yy - y, xx - x))
    return dist


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("heights")
    ap.add_argument("ref")
    ap.add_argument("others", nargs="+")
    ap.add_argument("--layer", default="indirect", choices=["direct", "indirect", "total"])
    ap.add_argument("--rise", type=float, default=40.0)
    ap.add_argument("--names", default=None, help="names of the OTHER files, separated by ';'")
    a = ap.parse_args()
    names = a.names.split(";") if a.names else [os.path.basename(p) for p in a.others]
    if len(names) != len(a.others):
        sys.exit(f"--names has {len(names)} entries for {len(a.others)} files")
    mask = peaks(a.heights, a.rise)
    dist = distance_to(mask)
    ref = read_layers(a.ref)[a.layer]
    if ref.shape[:2] != dist.shape:
        sys.exit(f"{a.ref}: {ref.shape[1]}×{ref.shape[0]} texels, {a.heights}: {dist.shape[1]}×{dist.shape[0]}")
    print(f"{int(mask.sum())} peaks (rise > {a.rise:g} grey levels); layer {a.layer}\n")
    print("| file | distance to a peak (texels) | texels | share of Σ error² | bias | mean reference |")
    print("|---|---|---|---|---|---|")
    for name, path in zip(names, a.others):
        x = read_layers(path)[a.layer]
        err2 = ((x - ref) ** 2).sum(-1)
        print(f"| {name} | all | {dist.size} | 1 (relative L2 {100 * rel_l2(x, ref):.3f}%) | "
              f"{100 * (x - ref).sum() / ref.sum():+.1f}% | {ref.mean():.4f} |")
        for lo, hi in BINS:
            m = (dist >= lo) & (dist < hi)
            if not m.any():
                continue
            bias = (x - ref)[m].sum() / ref[m].sum()
            print(f"| | [{lo:g}, {hi:g}) | {int(m.sum())} | {err2[m].sum() / err2.sum():.2f} | "
                  f"{100 * bias:+.1f}% | {ref[m].mean():.4f} |")


if __name__ == "__main__":
    main()
