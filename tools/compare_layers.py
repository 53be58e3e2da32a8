#!/usr/bin/env python3
"""Relative L2 error of shading EXRs against a reference, per layer (CONVENTIONS.md "Accuracy").

    tools/compare_layers.py REF.exr OTHER.exr [OTHER2.exr ...] [--names a,b,...] [--scale F]
    tools/compare_layers.py REF.exr OTHER.exr --bias   (adds the signed bias Σ(X − R)/ΣR per layer)
    tools/compare_layers.py --mean OUT.exr A.exr B.exr ...   (writes the per-channel mean)

err = ||X - R||_2 / ||R||_2 over all texels and the three channels, accumulated in float64,
for the layers direct (direct.R/G/B), indirect (indirect.R/G/B) and total (R, G, B). Prints a
Markdown table with one row per OTHER file (an empty reference layer prints its norm instead).
Reads the EXRs with Mitsuba's Bitmap (variant scalar_rgb; no LLVM needed), by channel name.
"""

import argparse
import math
import os
import sys

import numpy as np

LAYERS = {"direct": ("direct.R", "direct.G", "direct.B"),
          "indirect": ("indirect.R", "indirect.G", "indirect.B"),
          "total": ("R", "G", "B")}


def read_layers(path):
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    bmp = mi.Bitmap(path)
    names = [f.name for f in bmp.struct_()]
    arr = np.array(bmp, copy=False)
    if arr.ndim == 2:
        arr = arr[:, :, None]
    out = {}
    for layer, chans in LAYERS.items():
        if all(c in names for c in chans):
            out[layer] = np.stack([arr[:, :, names.index(c)] for c in chans], -1).astype(np.float64)
    out["_channels"] = names
    return out


def rel_l2(x, r):
    num = math.sqrt(float(np.sum((x - r) ** 2)))
    den = math.sqrt(float(np.sum(r ** 2)))
    return num / den if den > 0 else (0.0 if num == 0 else math.inf)


def write_mean(out, paths):
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    imgs = [read_layers(p) for p in paths]
    names = imgs[0]["_channels"]
    bmps = [np.array(mi.Bitmap(p), copy=False) for p in paths]
    for p, im in zip(paths, imgs):
        if im["_channels"] != names:
            sys.exit(f"{p}: channels {im['_channels']} differ from {names}")
    mean = np.mean(np.stack([b.astype(np.float64) for b in bmps]), axis=0).astype(np.float32)
    mi.Bitmap(np.ascontiguousarray(mean), pixel_format=mi.Bitmap.PixelFormat.MultiChannel,
              channel_names=names).write(out)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--mean":
        if len(sys.argv) < 4:
            sys.exit("usage: compare_layers.py --mean OUT.exr A.exr [B.exr ...]")
        write_mean(sys.argv[2], sys.argv[3:])
        return
    ap = argparse.ArgumentParser()
    ap.add_argument("ref")
    ap.add_argument("others", nargs="+")
    ap.add_argument("--names", help="semicolon-separated row labels (default: file names)")
    ap.add_argument("--no-header", action="store_true")
    ap.add_argument("--scale", type=float, default=1.0,
                    help="multiply the printed errors (0.5 turns two seeds' mutual distance into "
                         "the Monte Carlo error of their mean)")
    ap.add_argument("--bias", action="store_true",
                    help="print the signed bias Σ(X − R) / ΣR per layer after each error")
    ap.add_argument("--ref-label", help="header label of the reference (default: its file name)")
    args = ap.parse_args()
    names = args.names.split(";") if args.names else [os.path.basename(p) for p in args.others]
    ref = read_layers(args.ref)
    if not args.no_header:
        print(f"| vs {args.ref_label or os.path.basename(args.ref)} | direct | indirect | total |")
        print("|---|---|---|---|")
    bad = False
    for name, path in zip(names, args.others):
        x = read_layers(path)
        cells = []
        for layer in ("direct", "indirect", "total"):
            if layer not in ref or layer not in x:
                cells.append("missing")
                bad = True
                continue
            if ref[layer].shape != x[layer].shape:
                cells.append(f"shape {x[layer].shape} vs {ref[layer].shape}")
                bad = True
                continue
            if not np.any(ref[layer]):
                cells.append(f"ref = 0, ‖X‖₂ = {math.sqrt(float(np.sum(x[layer] ** 2))):.3g}")
                continue
            cell = f"{100 * args.scale * rel_l2(x[layer], ref[layer]):.3f}%"
            if args.bias:
                cell += f" ({100 * float(np.sum(x[layer] - ref[layer]) / np.sum(ref[layer])):+.1f}%)"
            cells.append(cell)
        print(f"| {name} | " + " | ".join(cells) + " |")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
