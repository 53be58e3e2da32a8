#!/usr/bin/env python3
"""The peer ratio (issue 12 item 6): how long Mitsuba 3 takes to reach each hfgi preset's error.

For every scene and preset, on the same fields and the same CPU:
  1. `hfgi bench --sweep presets --save-references --no-sh-visibility` renders each preset
     (median of --frames warm frames, every stage, lavapipe) and its error per layer against
     the exact reference (`hfgi reference`, 256 azimuths), and writes that reference as an EXR.
  2. `hfgi export` writes the field for tools/mitsuba_check.py, which is then driven in-process
     (PeerRenderer: mesh refined --refine x per texel, stratified m x m samples per texel, Dr.Jit
     LLVM backend with --threads threads).
  3. The direct layer: the smallest m (a ladder of about x1.2 per step, then bisection between
     its last failing and first passing steps) whose direct error against the same reference is
     <= the preset's; then, with that direct layer, the smallest bounce m whose indirect error
     is <= the preset's (and the total's too, else the direct m steps up).
  4. That configuration is timed afresh (warm: Dr.Jit's kernels are compiled by then): the mesh
     build (BVH included) + direct + indirect, median of 3 runs (1 when a run takes > 20 s).
  ratio = Mitsuba seconds / hfgi frame seconds; >= 1 means hfgi is at least as fast.

A search that would need a single run longer than --max-seconds stops there: the row then says
"> T s" and the ratio is a lower bound. Writes OUT/peer.csv and OUT/peer.md (with the commands,
the CPU, the device and driver, and the Mitsuba version).

Usage: tools/peer_ratio.py [--scenes A.toml,B.toml] [--presets paper,draft,default,high]
                           [--size 0] [--bounces 2] [--frames 3] [--out DIR] [--threads T]
                           [--refine R] [--max-seconds S] [--reuse-bench]
Needs tools/mitsuba-deps.sh once; HFGI=path picks the hfgi binary (default target/release/hfgi).
MITSUBA_VARIANT=cuda_ad_rgb runs Mitsuba on the GPU (Dr.Jit CUDA + OptiX; tools/gpu-bench).
"""

import argparse
import csv
import math
import os
import platform
import shlex
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import mitsuba_check as mc  # noqa: E402

# Stratified m per side: about x1.2 per step (x1.44 in samples).
LADDER = [1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 17, 20, 24, 29, 35, 42, 50, 60, 72, 86, 103, 124, 149, 179, 215, 258]
LAYERS = ("direct", "indirect", "total")


def log(msg):
    print(f"[peer_ratio] {msg}", file=sys.stderr, flush=True)


def run(cmd, cmds):
    cmds.append(" ".join(shlex.quote(c) for c in cmd))
    log("+ " + cmds[-1])
    subprocess.run(cmd, check=True, cwd=ROOT)


def read_exr_layers(mi, path):
    bmp = mi.Bitmap(path)
    names = [f.name for f in bmp.struct_()]
    arr = np.array(bmp, copy=False)
    chans = {"direct": ("direct.R", "direct.G", "direct.B"), "indirect": ("indirect.R", "indirect.G", "indirect.B"),
             "total": ("R", "G", "B")}
    return {k: np.stack([arr[:, :, names.index(c)] for c in v], -1).reshape(-1, 3).astype(np.float64)
            for k, v in chans.items()}


def rel_l2(x, r):
    """CONVENTIONS.md's error: ||X - R||_2 / ||R||_2 over every texel and channel."""
    return float(np.linalg.norm(x - r) / np.linalg.norm(r))


def errors(direct, indirect, ref):
    got = {"direct": direct, "indirect": indirect, "total": direct + indirect}
    return {k: rel_l2(got[k], ref[k]) for k in LAYERS}


class Search:
    """The ladder searches of one (scene, preset) against its targets."""

    def __init__(self, pr, ref, max_seconds):
        self.pr, self.ref, self.max_seconds = pr, ref, max_seconds

    def first_passing(self, start, err_of, target, label):
        """The smallest ladder m >= 1 with err_of(m) <= target, walking down from `start` while
        it passes and up while it fails. Returns (m, err) or (None, last err) when a run would
        take longer than max_seconds."""
        i = LADDER.index(start)
        cache = {}

        def ev(k):
            if k not in cache:
                t0 = time.time()
                e = err_of(LADDER[k])
                cache[k] = (e, time.time() - t0)
                log(f"  {label} m={LADDER[k]} ({LADDER[k] ** 2} spp): {100 * cache[k][0]:.3f}% "
                    f"(target {100 * target:.3f}%), {cache[k][1]:.1f} s")
            return cache[k]

        e, _ = ev(i)
        if e <= target:
            while i > 0 and ev(i - 1)[0] <= target:
                i -= 1
        else:
            while True:
                e, secs = ev(i)
                if e <= target:
                    break
                nxt = secs * (LADDER[i + 1] / LADDER[i]) ** 2 if i + 1 < len(LADDER) else math.inf
                if nxt > self.max_seconds:
                    return None, e
                i += 1
        # Bisection over the integers between the last failing ladder step and the passing one
        # (the error falls with m, up to noise), so Mitsuba is charged no more than it needs.
        lo, hi = (LADDER[i - 1] if i > 0 else 0), LADDER[i]
        best = ev(i)[0]
        while hi - lo > 1:
            mid = (lo + hi) // 2
            t0 = time.time()
            em = err_of(mid)
            log(f"  {label} m={mid} ({mid * mid} spp): {100 * em:.3f}%, {time.time() - t0:.1f} s")
            if em <= target:
                hi, best = mid, em
            else:
                lo = mid
        return hi, best

    def start(self, e_pilot, m_pilot, target):
        """A ladder start from a pilot error, assuming error ~ 1/m (1/sqrt(spp)); stratified
        sampling converges faster, so start a third of the way there and walk."""
        guess = m_pilot * e_pilot / max(target, 1e-12) / 3.0
        return max(m for m in LADDER if m <= max(1.0, guess))

    def total_only(self, targets):
        """The smallest common m (direct and per bounce) whose total error is <= the preset's
        total error alone (the other layers may be worse). Returns (m, errors) or None."""
        pr, ref = self.pr, self.ref

        def err(m):
            d = pr.direct(m * m, quiet=True)
            return errors(d, pr.indirect(d, m * m, quiet=True), ref)["total"]

        m, _ = self.first_passing(self.start(err(4), 4, targets["total"]), err, targets["total"], "total only")
        if m is None:
            return None
        d = pr.direct(m * m, quiet=True)
        return m, errors(d, pr.indirect(d, m * m, quiet=True), ref)

    def run(self, targets):
        """Every layer <= the preset's: returns (m_d, m_b, errors) or None."""
        pr, ref = self.pr, self.ref
        d4 = pr.direct(16, quiet=True)
        m_d, e_d = self.first_passing(
            self.start(rel_l2(d4, ref["direct"]), 4, targets["direct"]),
            lambda m: rel_l2(pr.direct(m * m, quiet=True), ref["direct"]),
            targets["direct"], "direct",
        )
        if m_d is None:
            return None
        while True:
            direct = pr.direct(m_d * m_d, quiet=True)
            i4 = pr.indirect(direct, 16, quiet=True)
            m_b, _ = self.first_passing(
                self.start(rel_l2(i4, ref["indirect"]), 4, targets["indirect"]),
                lambda m: rel_l2(pr.indirect(direct, m * m, quiet=True), ref["indirect"]),
                targets["indirect"], "indirect",
            )
            if m_b is None:
                return None
            e = errors(direct, pr.indirect(direct, m_b * m_b, quiet=True), ref)
            if e["total"] <= targets["total"] or m_d >= LADDER[-1]:
                return m_d, m_b, e
            log(f"  total {100 * e['total']:.3f}% > {100 * targets['total']:.3f}%: direct m steps up")
            m_d += 1


def time_config(export_dir, refine, threads, m_d, m_b):
    """Seconds of a fresh mesh build + direct + indirect at (m_d, m_b): median of 3 (1 if slow)."""
    runs = []
    while len(runs) < 3:
        fresh = mc.PeerRenderer(export_dir, refine, threads)
        setup = fresh.setup_seconds
        t1 = time.time()
        d = fresh.direct(m_d * m_d, quiet=True)
        fresh.indirect(d, m_b * m_b, quiet=True)
        render = time.time() - t1
        runs.append((setup + render, setup, render, fresh.tracer.rays, fresh.tracer.seconds))
        if setup + render > 20:
            break
    runs.sort()
    return runs[len(runs) // 2]


def timed(export_dir, args, m_d, m_b, e):
    secs, setup, render, rays, ray_s = time_config(export_dir, args.refine, args.threads, m_d, m_b)
    return dict(m_d=m_d, m_b=m_b, errors=e, seconds=secs, setup=setup, render=render, rays=rays, ray_s=ray_s)


def hfgi_rows(bench_csv):
    with open(bench_csv, newline="") as f:
        return list(csv.DictReader(f))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="scenes/hard/terraces.toml,scenes/hard/spikes.toml,scenes/hard/steep.toml")
    ap.add_argument("--presets", default="paper,draft,default,high")
    ap.add_argument("--size", type=int, default=0, help="heightfield.size (0: each scene's own)")
    ap.add_argument("--bounces", type=int, default=2)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--out", default="out/peer")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1, help="Dr.Jit threads (default: all cores)")
    ap.add_argument("--refine", type=int, default=4)
    ap.add_argument("--max-seconds", type=float, default=600.0)
    ap.add_argument("--reuse-bench", action="store_true", help="keep OUT/bench if it has results.csv")
    args = ap.parse_args()
    hfgi = os.environ.get("HFGI", os.path.join(ROOT, "target/release/hfgi"))
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    scenes = args.scenes.split(",")
    presets = args.presets.split(",")
    cmds = []

    bench_dir = os.path.join(out, "bench")
    if not (args.reuse_bench and os.path.exists(os.path.join(bench_dir, "results.csv"))):
        only = ",".join(f"quality={p}" for p in presets if p != "paper")
        run([hfgi, "bench", "--sweep", "presets", "--only", only, "--size", str(args.size), "--bounces",
             str(args.bounces), "--frames", str(args.frames), "--save-references", "--no-sh-visibility",
             "--scenes", ",".join(scenes), "--out", bench_dir], cmds)
    rows = hfgi_rows(os.path.join(bench_dir, "results.csv"))

    results = []
    first = True
    for path in scenes:
        name = os.path.splitext(os.path.basename(path))[0]
        for preset in presets:
            knob = "paper" if preset == "paper" else f"quality={preset}"
            row = next((r for r in rows if r["scene"] == name and r["knob"] == knob), None)
            if row is None:
                log(f"{name} {preset}: not in the bench results, skipped")
                continue
            n = int(row["sh_order"])
            export_dir = os.path.join(out, f"export-{name}-n{n}")
            sets = ["--set", f"gi.bounces={args.bounces}", "--set", f"gi.sh_order={n}"]
            if args.size > 0:
                sets += ["--set", f"heightfield.size={args.size}"]
            if not os.path.exists(os.path.join(export_dir, "scene.toml")):
                run([hfgi, "export", path, *sets, "--out", export_dir], cmds)
            pr = mc.PeerRenderer(export_dir, args.refine, args.threads)
            if first:
                first = False
                pr.direct(16, quiet=True)  # Dr.Jit compiles its kernels once, here
            ref = read_exr_layers(pr.mi, os.path.join(bench_dir, f"reference-{name}-n{n}.exr"))
            targets = {k: float(row[f"exact_{k}"]) for k in LAYERS}
            log(f"{name} {preset}: hfgi {float(row['total_ms']):.1f} ms, errors "
                + " / ".join(f"{100 * targets[k]:.3f}%" for k in LAYERS))
            search = Search(pr, ref, args.max_seconds)
            res = {"scene": name, "preset": preset, "hfgi_ms": float(row["total_ms"]), "targets": targets,
                   "device": row["device"], "driver": row["driver"], "size": (pr.w, pr.h)}
            found = search.run(targets)
            res["mitsuba"] = None if found is None else timed(export_dir, args, found[0], found[1], found[2])
            found = search.total_only(targets)
            res["total_only"] = None if found is None else timed(export_dir, args, found[0], found[0], found[1])
            results.append(res)
            write_outputs(out, results, args, cmds, pr)
    log(f"wrote {out}/peer.md and {out}/peer.csv")


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def write_outputs(out, results, args, cmds, pr):
    pct = lambda e: f"{100 * e:.2f}%"  # noqa: E731
    cols = ("spp_direct", "spp_bounce", "direct", "indirect", "total", "s", "setup_s", "rays", "ray_s", "ratio")
    lines = ["scene,preset,width,height,hfgi_ms,hfgi_direct,hfgi_indirect,hfgi_total,"
             + ",".join(f"{c}_{k}" for c in ("every_layer", "total_only") for k in cols)]
    threads = "" if pr.variant.startswith("cuda") else f", {args.threads} Dr.Jit threads"
    md = [f"Peer ratio: Mitsuba {pr.mi.__version__} ({pr.variant}{threads}, mesh refined "
          f"{args.refine}x per texel) against hfgi on {results[0]['device']} ({results[0]['driver']}"
          f"{'; lavapipe: CPU time' if 'llvmpipe' in results[0]['device'] else ''}), {cpu_model()}, {os.cpu_count()} cores; {args.bounces} bounces; hfgi: median of "
          f"{args.frames} warm frames, every stage; Mitsuba: mesh build + direct + indirect, warm. "
          "Ratio = Mitsuba time / hfgi time (≥ 1: hfgi at least as fast). *Every layer*: Mitsuba's "
          "direct, indirect and total errors each ≤ hfgi's; *total only*: its total error ≤ hfgi's, "
          "same samples per texel for the direct pass and each bounce. *rays*: the seconds inside Mitsuba's "
          "ray queries alone (the rest is the script's numpy sampling and shading); 'rays only' divides "
          "those by hfgi's frame, a bound for a path tracer whose sampling and shading cost nothing.", "",
          "| field | preset | hfgi frame (s) | hfgi error: direct / indirect / total | every layer: Mitsuba spp "
          "(direct, per bounce), errors, time (s) | ratio | total only: spp, total error, time (s) | ratio |",
          "|---|---|---|---|---|---|---|---|"]
    ratios = {"mitsuba": [], "total_only": []}
    for r in results:
        t = r["targets"]
        hs = r["hfgi_ms"] / 1000
        w, h = r["size"]
        row_md = [f"{r['scene']} {w}×{h}", r["preset"], f"{hs:.3f}", " / ".join(pct(t[k]) for k in LAYERS)]
        row_csv = [r["scene"], r["preset"], str(w), str(h), f"{r['hfgi_ms']:.3f}"] + [f"{t[k]:.6e}" for k in LAYERS]
        for key in ("mitsuba", "total_only"):
            m = r[key]
            if m is None:
                row_md += [f"not reached within {args.max_seconds:.0f} s per run", f"> {args.max_seconds / hs:.2f}"]
                row_csv += [""] * 5 + [f">{args.max_seconds}", "", "", "", ""]
                continue
            e = m["errors"]
            ratio = m["seconds"] / hs
            ratios[key].append(ratio)
            errs = " / ".join(pct(e[k]) for k in LAYERS) if key == "mitsuba" else pct(e["total"])
            row_md += [f"{m['m_d'] ** 2}, {m['m_b'] ** 2}; {errs}; {m['seconds']:.3f} (rays {m['ray_s']:.3f})",
                       f"**{ratio:.3f}** (rays only {m['ray_s'] / hs:.3f})"]
            row_csv += [str(m["m_d"] ** 2), str(m["m_b"] ** 2)] + [f"{e[k]:.6e}" for k in LAYERS] + [
                f"{m['seconds']:.4f}", f"{m['setup']:.4f}", str(m["rays"]), f"{m['ray_s']:.4f}", f"{ratio:.4f}"]
        md.append("| " + " | ".join(row_md) + " |")
        lines.append(",".join(row_csv))
    for key, label in (("mitsuba", "every layer"), ("total_only", "total only")):
        if ratios[key]:
            g = math.exp(statistics.fmean(math.log(x) for x in ratios[key]))
            md += ["", f"Geometric mean of the ratios ({label}): {g:.3f}."]
    md += ["", "Commands:", "", "```", f"tools/peer_ratio.py {' '.join(shlex.quote(a) for a in sys.argv[1:])}",
           *cmds, "```", ""]
    for name, text in (("peer.csv", "\n".join(lines) + "\n"), ("peer.md", "\n".join(md))):
        tmp = os.path.join(out, f".{name}.tmp")
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, os.path.join(out, name))


if __name__ == "__main__":
    main()
