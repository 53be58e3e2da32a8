#!/usr/bin/env python3
"""Estimate of the error a sub-sampled later bounce would add (tools/later-bounce-estimate).

    tools/later_bounce_estimate.py DIR NAME [NAME ...]

Reads DIR/NAME/{ref,b1,b2,s2}.exr (exact reference; `default` with 1 and 2 bounces; 2 bounces
with gi.subsample=2). The second bounce is b2 − b1 (indirect layers). Sub-sampling it by s is
modelled as its s×s block means interpolated bilinearly back to the field (texel centres at
s·i + (s − 1)/2, clamped at the borders). This interpolates exit radiance, where a sub-sampled
scan would interpolate the incident SH vector and shade with the field's normals (NS09 fig. 7),
so it can overstate the error where normals change within a block; the last columns check it on
the whole frame: the same model applied to b2's whole indirect layer against the real
gi.subsample=2 render. Errors are CONVENTIONS.md's relative L2 in %.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare_layers as cl  # noqa: E402


def err(x, r):
    return 100.0 * cl.rel_l2(x, r)


def block_interp(img, s):
    """The s×s block means of img (H×W×3), interpolated bilinearly back to H×W."""
    h, w, _ = img.shape
    hw, ww = (h + s - 1) // s, (w + s - 1) // s
    acc = np.zeros((hw, ww, 3))
    cnt = np.zeros((hw, ww, 1))
    for dy in range(s):
        for dx in range(s):
            part = img[dy::s, dx::s]
            acc[:part.shape[0], :part.shape[1]] += part
            cnt[:part.shape[0], :part.shape[1]] += 1
    small = acc / cnt
    ys = np.clip((np.arange(h) - (s - 1) / 2) / s, 0, hw - 1)
    xs = np.clip((np.arange(w) - (s - 1) / 2) / s, 0, ww - 1)
    y0, x0 = np.floor(ys).astype(int), np.floor(xs).astype(int)
    y1, x1 = np.minimum(y0 + 1, hw - 1), np.minimum(x0 + 1, ww - 1)
    fy, fx = (ys - y0)[:, None, None], (xs - x0)[None, :, None]
    top = small[y0][:, x0] * (1 - fx) + small[y0][:, x1] * fx
    bottom = small[y1][:, x0] * (1 - fx) + small[y1][:, x1] * fx
    return top * (1 - fy) + bottom * fy


def main():
    root, names = sys.argv[1], sys.argv[2:]
    print("| field | 2nd bounce's share of the indirect norm | `default`: indirect / total | "
          "2nd bounce at 2×: indirect / total | at 4× | 1 bounce only: indirect | "
          "whole frame at 2×: measured / model (indirect) |")
    print("|---|---|---|---|---|---|---|")
    for n in names:
        d = os.path.join(root, n)
        ref, one, two, sub = (cl.read_layers(os.path.join(d, f + ".exr")) for f in ("ref", "b1", "b2", "s2"))
        second = two["indirect"] - one["indirect"]
        share = np.linalg.norm(second) / np.linalg.norm(two["indirect"])
        cells = []
        for s in (2, 4):
            ind = one["indirect"] + block_interp(second, s)
            tot = two["total"] - two["indirect"] + ind
            cells.append(f"{err(ind, ref['indirect']):.3f} / {err(tot, ref['total']):.3f}")
        model = err(block_interp(two["indirect"], 2), ref["indirect"])
        print(f"| {n} | {100 * share:.1f}% | {err(two['indirect'], ref['indirect']):.3f} / "
              f"{err(two['total'], ref['total']):.3f} | {cells[0]} | {cells[1]} | "
              f"{err(one['indirect'], ref['indirect']):.3f} | "
              f"{err(sub['indirect'], ref['indirect']):.3f} / {model:.3f} |")


if __name__ == "__main__":
    main()
