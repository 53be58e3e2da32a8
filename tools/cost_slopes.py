#!/usr/bin/env python3
"""Cost-scaling slopes (issue 12 item 6): log-log fits of the frame time against the field's
texels, the azimuths m, the bounces and the sub-sampling, from `hfgi bench --timing` runs made
one after the other on one machine (lavapipe: CPU times, compared only within this run).

  runs   `hfgi bench --timing --size S` for every --sizes S (table 1's grid of sub-sampling
         4x/2x/1x x 1-3 bounces at each size), then `--size --m-size --set gi.azimuths=M` for
         every --azimuths M; each writes OUT/<run>/timing.csv.
  fits   least squares of log(time) on log(x), per stage and for the frame:
           texels      x = field texels, at each (sub-sampling, bounces)
           azimuths    x = m, at each (sub-sampling, bounces), field --m-size
           sub-sampling x = working texels (texels / s^2), at each (size, bounces)
           bounces     x = bounces (1-3), at each (size, sub-sampling)
         and prints the median slope over the groups with its range.
Writes OUT/slopes.md and OUT/slopes.csv.

Usage: tools/cost_slopes.py [--sizes 32,64,128] [--azimuths 8,16,32,64] [--m-size 64]
                            [--frames 3] [--scene scenes/default.toml] [--out DIR] [--reuse]
HFGI=path picks the hfgi binary (default target/release/hfgi).
"""

import argparse
import csv
import math
import os
import shlex
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STAGES = ("frame", "visibility.environment", "shade.direct", "indirect.scan", "radiance.synthesize")


def log(msg):
    print(f"[cost_slopes] {msg}", file=sys.stderr, flush=True)


def read(path, extra):
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            stages = {}
            for kv in r["stages"].split(";"):
                k, v = kv.split("=")
                stages[k] = stages.get(k, 0.0) + float(v)
            stages["frame"] = float(r["total_ms"])
            rows.append(dict(size=int(r["size"]), sub=int(r["subsample"]), bounces=int(r["bounces"]),
                             stages=stages, device=r["device"], driver=r["driver"], **extra))
    return rows


def fit(points):
    """Slope of log y on log x (least squares); None with fewer than two distinct x."""
    pts = [(math.log(x), math.log(y)) for x, y in points if x > 0 and y > 0]
    if len({p[0] for p in pts}) < 2:
        return None
    mx = statistics.fmean(p[0] for p in pts)
    my = statistics.fmean(p[1] for p in pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def slopes(rows, group_keys, x_of, stage):
    groups = {}
    for r in rows:
        if stage in r["stages"]:
            groups.setdefault(tuple(r[k] for k in group_keys), []).append((x_of(r), r["stages"][stage]))
    return {g: s for g, pts in groups.items() if (s := fit(pts)) is not None}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="32,64,128")
    ap.add_argument("--azimuths", default="8,16,32,64")
    ap.add_argument("--m-size", type=int, default=64)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--scene", default="scenes/default.toml")
    ap.add_argument("--out", default="out/slopes")
    ap.add_argument("--reuse", action="store_true", help="keep runs whose timing.csv exists")
    args = ap.parse_args()
    hfgi = os.environ.get("HFGI", os.path.join(ROOT, "target/release/hfgi"))
    out = os.path.abspath(args.out)
    cmds = []

    def bench(name, extra):
        d = os.path.join(out, name)
        if not (args.reuse and os.path.exists(os.path.join(d, "timing.csv"))):
            cmd = [hfgi, "bench", "--timing", "--budget", "100000", "--frames", str(args.frames), "--scenes",
                   args.scene, *extra, "--out", d]
            cmds.append(" ".join(shlex.quote(c) for c in cmd))
            log("+ " + cmds[-1])
            subprocess.run(cmd, check=True, cwd=ROOT)
        return os.path.join(d, "timing.csv")

    size_rows, m_rows = [], []
    for s in [int(x) for x in args.sizes.split(",")]:
        size_rows += read(bench(f"size-{s}", ["--size", str(s)]), {"m": None})
    for m in [int(x) for x in args.azimuths.split(",")]:
        m_rows += read(bench(f"m-{m}", ["--size", str(args.m_size), "--set", f"gi.azimuths={m}"]), {"m": m})

    fits = [
        ("texels", size_rows, ("sub", "bounces"), lambda r: r["size"] ** 2),
        ("azimuths m", m_rows, ("sub", "bounces"), lambda r: r["m"]),
        ("working texels (sub-sampling)", size_rows, ("size", "bounces"), lambda r: (r["size"] / r["sub"]) ** 2),
        ("bounces", size_rows, ("size", "sub"), lambda r: r["bounces"]),
    ]
    dev = size_rows[0]
    md = [f"Cost-scaling slopes: d log(time) / d log(x), least squares per group, median [min, max] over the "
          f"groups. Device: {dev['device']} ({dev['driver']}); lavapipe: CPU times, median of {args.frames} "
          f"frames after a warm-up, one run; scene {args.scene}, sizes {args.sizes}, azimuths {args.azimuths} "
          f"at {args.m_size}².", "",
          "| x (groups held fixed) | " + " | ".join(STAGES) + " |", "|---|" + "---|" * len(STAGES)]
    lines = ["x,group,stage,slope"]
    for label, rows, keys, x_of in fits:
        cells = []
        for st in STAGES:
            sl = slopes(rows, keys, x_of, st)
            for g, v in sorted(sl.items()):
                lines.append(f"{label},{'/'.join(map(str, g))},{st},{v:.4f}")
            vals = sorted(sl.values())
            cells.append(f"{statistics.median(vals):.2f} [{vals[0]:.2f}, {vals[-1]:.2f}]" if vals else "—")
        md.append(f"| {label} ({', '.join(keys)}) | " + " | ".join(cells) + " |")
    md += ["", "Commands:", "", "```", f"tools/cost_slopes.py {' '.join(shlex.quote(a) for a in sys.argv[1:])}",
           *cmds, "```", ""]
    os.makedirs(out, exist_ok=True)
    for name, text in (("slopes.md", "\n".join(md)), ("slopes.csv", "\n".join(lines) + "\n")):
        tmp = os.path.join(out, f".{name}.tmp")
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, os.path.join(out, name))
    print("\n".join(md))


if __name__ == "__main__":
    main()
