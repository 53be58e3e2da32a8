#!/usr/bin/env python3
"""Error maps of the two diffuse lobes against the exact reference (docs/accuracy.md §6).

    tools/lobe_error_maps.py OUT.png DIR [DIR ...]

Each DIR is a `tools/knob-errors` output with `reference.exr`, `gi_quality_default.exr` (the
clamped-cosine ZH) and `gi_diffuse_lobe_exact_gi_sh_order_5.exr` (the exact lobe at order 5).
One row per DIR: the reference's total layer (tone-mapped), then |X − R| of the total layer for
the clamped and the exact lobe, then the same of the indirect layer; each error is the texel's
luminance difference over the layer's mean reference luminance, on a black–red–yellow–white scale
clamped at 10% (total) and 30% (indirect). Needs numpy and Mitsuba's Python package
(tools/mitsuba-deps.sh) for reading EXRs and writing the PNG.
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import compare_layers as cl  # noqa: E402

LUM = np.array([0.2126, 0.7152, 0.0722])
SH = "gi_quality_default.exr"
EXACT = "gi_diffuse_lobe_exact_gi_sh_order_5.exr"


def hot(x):
    """x in [0, 1] → RGB: black, red, yellow, white."""
    stops = np.array([0.0, 1 / 3, 2 / 3, 1.0])
    r = np.interp(x, stops, [0, 1, 1, 1])
    g = np.interp(x, stops, [0, 0, 1, 1])
    b = np.interp(x, stops, [0, 0, 0, 1])
    return np.stack([r, g, b], -1)


def error_tile(x, ref, clamp):
    err = np.abs((x - ref) @ LUM) / max((ref @ LUM).mean(), 1e-30)
    return hot(np.clip(err / clamp, 0.0, 1.0))


def tone(ref):
    lum = ref @ LUM
    return np.clip(ref / max(np.percentile(lum, 99), 1e-30), 0.0, 1.0) ** (1 / 2.2)


def row(d):
    ref, sh, ex = (cl.read_layers(str(Path(d) / f)) for f in ("reference.exr", SH, EXACT))
    return [
        tone(ref["total"]),
        error_tile(sh["total"], ref["total"], 0.10),
        error_tile(ex["total"], ref["total"], 0.10),
        error_tile(sh["indirect"], ref["indirect"], 0.30),
        error_tile(ex["indirect"], ref["indirect"], 0.30),
    ]


def main():
    if len(sys.argv) < 3:
        print(__doc__.strip(), file=sys.stderr)
        sys.exit(2)
    rows = [row(d) for d in sys.argv[2:]]
    size = max(max(t.shape[0], t.shape[1]) for r in rows for t in r)
    gap = 4
    h = len(rows) * (size + gap) - gap
    w = 5 * (size + gap) - gap
    img = np.ones((h, w, 3))
    for i, r in enumerate(rows):
        for j, t in enumerate(r):
            y, x = i * (size + gap), j * (size + gap)
            img[y : y + t.shape[0], x : x + t.shape[1]] = t
    img = np.repeat(np.repeat(img, 2, 0), 2, 1)  # nearest 2× so single texels stay visible
    import mitsuba as mi

    mi.Bitmap(img.astype(np.float32)).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=False
    ).write(sys.argv[1])
    print(f"wrote {sys.argv[1]} ({img.shape[1]}×{img.shape[0]})")


if __name__ == "__main__":
    main()
