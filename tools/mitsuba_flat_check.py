#!/usr/bin/env python3
"""Sanity check of tools/mitsuba_check.py against closed form, on a flat (or tilted) plane.

Writes a synthetic export (constant heights, N = +z everywhere; environment SH and one key
light copied from SOURCE_EXPORT/scene.toml if given, else made up), runs mitsuba_check.py on it
and compares with
    direct = rho/pi * ( sum_l L_{l(l+1)} z_l  +  L_key * pi sin^2(alpha) * d_z )
(z = clamped-cosine ZH {0.886227, 1.023327, 0.495416, 0, ...}; a cap wholly above the horizon
has integral of cos over it = pi sin^2(alpha) d_z), and indirect = 0 (every ray escapes).
Every texel is an independent estimate of the same number, so their spread measures the Monte
Carlo error; exits non-zero when the mean over texels is more than 4 standard errors (+ --tol,
relative) off the closed form in any channel, or indirect != 0.

With --slope AX AY the plane is H = 3.25 + AX x + AY y: the same with N = normalize(-AX, -AY, 1),
E = sum_k L_k c_k(N) and the cap's pi sin^2(alpha) (d.N).

Usage: tools/mitsuba_flat_check.py [SOURCE_EXPORT] [--size N] [--spp N] [--slope AX AY] [--tol T] [--work DIR]
"""

import argparse
import math
import os
import subprocess
import sys
import tomllib

import numpy as np


def zh_clamped_cosine(l):
    """z_l = integral of y_l^0 max(cos theta, 0) over the sphere (exact)."""
    # z_l = 2 pi sqrt((2l+1)/(4 pi)) int_0^1 P_l(t) t dt
    x, wts = np.polynomial.legendre.leggauss(64)
    t = 0.5 * (x + 1)
    P = np.polynomial.legendre.legval(t, [0] * l + [1])
    return 2 * math.pi * math.sqrt((2 * l + 1) / (4 * math.pi)) * 0.5 * np.sum(wts * P * t)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("source", nargs="?")
    ap.add_argument("--size", type=int, default=16)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--tol", type=float, default=1e-5, help="allowed bias beyond 4 standard errors (relative)")
    ap.add_argument("--work", default="/tmp/mitsuba-flat")
    ap.add_argument("--slope", type=float, nargs=2, default=(0.0, 0.0), metavar=("AX", "AY"),
                    help="a tilted plane H = AX x + AY y instead (N constant, nothing blocks the "
                         "directions above it): checks the SH rotation and the cap's cosine")
    args = ap.parse_args()

    if args.source:
        with open(os.path.join(args.source, "scene.toml"), "rb") as f:
            src = tomllib.load(f)
        env = np.asarray(src["environment_sh"], dtype=np.float64)
        keys = src.get("key_light", [])
        albedo = src["albedo"]
    else:
        rng = np.random.default_rng(3)
        env = rng.normal(size=(16, 3)) * 0.3
        env[0] += 2.0
        keys = [{"direction": [-0.6123724357, -0.6123724357, 0.5], "angular_radius": 0.0349066,
                 "radiance": [1100.0, 1020.0, 880.0]}]
        albedo = [0.55, 0.53, 0.5]
    keys = keys[:1]
    os.makedirs(args.work, exist_ok=True)
    exp = os.path.join(args.work, "export")
    os.makedirs(exp, exist_ok=True)
    n = args.size
    ax, ay = args.slope
    jj, ii = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    (3.25 + ax * ii + ay * jj).astype("<f4").ravel().tofile(os.path.join(exp, "heights.f32"))
    N = np.array([-ax, -ay, 1.0])
    N /= np.linalg.norm(N)
    with open(os.path.join(exp, "scene.toml"), "w") as f:
        f.write(f"width = {n}\nheight = {n}\ntexel_size = 1.0\nwrap = false\n")
        f.write(f"albedo = [{', '.join(repr(float(a)) for a in albedo)}]\n")
        f.write(f"sh_order = {int(round(math.sqrt(len(env))))}\nbounces = 2\nenvironment_sh = [\n")
        for row in env:
            f.write(f"  [{', '.join(repr(float(v)) for v in row)}],\n")
        f.write("]\n")
        for k in keys:
            f.write(f"\n[[key_light]]\ndirection = {list(map(float, k['direction']))}\n"
                    f"angular_radius = {float(k['angular_radius'])!r}\nradiance = {list(map(float, k['radiance']))}\n")

    out = os.path.join(args.work, "mitsuba.exr")
    here = os.path.dirname(os.path.abspath(__file__))
    subprocess.run([sys.executable, os.path.join(here, "mitsuba_check.py"), exp, "--out", out,
                    "--spp", str(args.spp)], check=True)

    sys.path.insert(0, here)
    sys.dont_write_bytecode = True  # no __pycache__ in tools/
    from mitsuba_check import sh_eval_rgb  # noqa: E402

    order = int(round(math.sqrt(len(env))))
    z = [zh_clamped_cosine(l) for l in range(order)]
    # Clamped cosine about N as SH: c_l^m = sqrt(4 pi/(2l+1)) z_l y_l^m(N); E = sum_k L_k c_k.
    Y = sh_eval_rgb(np.eye(order * order), N[None, :])[0]
    cc = np.array([math.sqrt(4 * math.pi / (2 * l + 1)) * z[l] * Y[l * l + q]
                   for l in range(order) for q in range(2 * l + 1)])
    E = cc @ env
    for k in keys:
        d = np.asarray(k["direction"], dtype=np.float64)
        d /= np.linalg.norm(d)
        a = float(k["angular_radius"])
        assert d @ N > math.sin(a), "the check needs the cap wholly above the tangent plane"
        E = E + np.asarray(k["radiance"]) * math.pi * math.sin(a) ** 2 * (d @ N)
    want = np.asarray(albedo) / math.pi * E

    from compare_layers import read_layers  # noqa: E402

    got = read_layers(out)
    dmean = got["direct"].reshape(-1, 3).astype(np.float64)
    rel = np.abs(dmean - want[None, :]) / np.abs(want[None, :])
    ind = np.abs(got["indirect"]).max()
    print(f"z_l = {[round(float(v), 6) for v in z]}")
    print(f"analytic direct (plane, N={N.round(6).tolist()}) = {want}")
    print(f"mitsuba  direct: mean {dmean.mean(0)}, min {dmean.min(0)}, max {dmean.max(0)}")
    # Every texel is an independent estimate of the same value: their spread is the
    # per-texel Monte Carlo error, and spread/sqrt(texels) that of their mean.
    sd = dmean.std(0, ddof=1)
    se = sd / math.sqrt(dmean.shape[0])
    dev = np.abs(dmean.mean(0) - want)
    print(f"per-texel MC error (rel. sd over texels): {sd / want}")
    print(f"mean over texels vs analytic: rel. error {dev / want}, = {dev / se} standard errors")
    print(f"worst texel rel. error {rel.max():.3g}; max |indirect| = {ind:.3g}")
    ok = bool(np.all(dev <= 4 * se + args.tol * np.abs(want))) and ind == 0.0
    print("PASS" if ok else "FAIL")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
