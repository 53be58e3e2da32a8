#!/usr/bin/env python3
"""Independent peer check of hfgi's ground truth, with Mitsuba 3 as the ray tracer.

Reads an `hfgi export` folder (heights.f32 + scene.toml) and computes the shading layers that
/work/shared/CONVENTIONS.md ("Shading and exported values") defines, by Monte Carlo over the
hemisphere, sharing no code with hfgi:

  mesh       the bilinear surface refined R x R per texel (vertices at ((i+a/R)s, (j+b/R)s,
             bilinear height), two triangles per sub-quad); domain [0,W-1]x[0,H-1]*s, nothing
             outside it, so rays that leave it escape. wrap=true is not supported (exit 2).
  receivers  every texel sample (i s, j s, H[j][i]) with the CONVENTIONS.md normal (central
             differences, one-sided at the border).
  direct     E = pi/n sum_k V(w_k) L_env(w_k) over n stratified cosine-weighted directions about
             N (L_env = the SH environment as given, not clamped), plus for each key light
             Omega_cap/n sum_k V(w_k) max(N.w_k,0) L_key over n stratified directions uniform in
             the cap (solid angle). V = 1 iff the ray escapes. L_o = rho/pi E.
             Local lights ([[local_light]]: centre c, radius r, radiance L): from the receiver P,
             d = |c - P|, n stratified directions uniform by solid angle in the cap of
             half-angle asin(r/d) about (c - P)/d, Omega = 2 pi (1 - cos), the estimate
             Omega/n sum_k V_k max(N.w_k,0) L; V_k = 1 iff Mitsuba's first hit (height field or
             sphere blocker) lies beyond the light's entry distance (near root of
             |P + t w - c| = r, analytic, numpy f64), or the ray escapes. A receiver inside the
             light (d <= r) follows hfgi's documented rule (docs/local-lights.md §2): the limit
             at d = r, the hemisphere toward c (+z when d = 0), nothing blocks it (neither
             terrain nor blocker); only max(N.w, 0) applies.
  spheres    [[sphere]] blockers are Mitsuba `sphere` shapes in the same scene: they block the
             visibility rays of every light. In the bounces a ray whose first hit is a sphere
             carries 0 (spheres do not reflect; which shape was hit is Mitsuba's shape pointer,
             cross-checked against an analytic ray-sphere test in numpy, disagreements logged).
             A receiver inside a blocker gets nothing, direct and indirect (docs/blockers.md
             §1; explicit, since from inside a sphere the terrain within it may be hit first).
  indirect   bounce b >= 1: L_o,b = rho/n sum_k L_o,b-1(hit_k) with fresh cosine directions;
             L_o,b-1 is bilinearly interpolated from the texel grid at (x/s, y/s) of the first
             hit; escaping rays give 0. indirect = sum over b = 1..bounces. total = direct +
             indirect. glossy = 0. Light spheres are not geometry: they block nothing.

Refinement. Near a local light the direct layer varies steeply from texel to texel, so the
refined mesh's deviation from the bilinear surface shows in the indirect layer: on the 48²
lanterns check, refine 4 put the texel under a light 1.2 units above a 1.9-unit step 3.9% high
(refine 16: 0.4%), 0.65% rel-L2 over the indirect layer. Use --refine 16 with local lights.

Near field. Directions are sampled about the CONVENTIONS.md normal N, which is not the normal
of the surface around the receiver (a crease, the foot or top of a cliff), so some directions
above N's tangent plane go into the surface at once. Those are found exactly, without tracing:
the ray enters the quad that its horizontal direction points into, and goes in iff d_z is below
the bilinear patch's directional derivative at that corner. By the definition ("the first
height-field point the ray hits") such a ray is blocked (direct) and its first hit is the
receiver itself (indirect: it sees L_o,b-1 of the receiver). Every other ray is traced from the
receiver lifted straight up by eps (default: 1e-4 x the larger of the texel size and the
largest height step between neighbouring texels, and at least 64 float32 ulps of the largest
coordinate); lifting along +z always lands on the open side of a height field (a graph over
xy), unlike a lift along N. A border receiver's directions that leave the domain escape.
(Without the exact test, i.e. --no-local-test, the lift alone decides those rays: on a 64²
one-texel cliff that put the indirect term of the cliff-foot column 0.3% high at the default
eps and 1.4% at 10x, and tiny eps (1e-6 relative) leaked rays through the cliff face. With
it, 10x / 0.1x eps move the indirect layer by 0.10% / 0.03% rel-L2 there.)

Everything but the intersection (sampling, SH, interpolation, sums) is numpy in float64;
Mitsuba (variant llvm_ad_rgb; scalar_rgb only as a loud fallback) intersects float32 rays
with the float32 mesh. Deterministic for a given --seed, whatever --chunk and --threads are.

Usage: tools/mitsuba_check.py EXPORT_DIR --out FILE.exr [--spp N] [--key-spp N] [--local-spp N] [--bounce-spp N]
                              [--refine R] [--seed S] [--threads T] [--chunk RAYS] [--eps E]
"""

import argparse
import glob
import math
import os
import sys
import time
import tomllib

import numpy as np


def log(msg):
    print(f"[mitsuba_check] {msg}", file=sys.stderr, flush=True)


def find_libllvm():
    """The newest libLLVM >= 16 on the usual Debian paths (Dr.Jit needs >= 16)."""
    best = None
    for path in glob.glob("/usr/lib/*/libLLVM*.so*") + glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"):
        name = os.path.basename(path)
        digits = "".join(c if c.isdigit() else " " for c in name).split()
        if not digits:
            continue
        major = int(digits[0])
        if major >= 16 and (best is None or major > best[0]):
            best = (major, path)
    return best[1] if best else None


def llvm_major(path):
    digits = "".join(c if c.isdigit() else " " for c in os.path.basename(os.path.realpath(path))).split()
    return int(digits[0]) if digits else None


_PROBE = ("import drjit as dr, mitsuba as mi; dr.set_thread_count(1); mi.set_variant('llvm_ad_rgb'); "
          "x = dr.arange(mi.Float, 8); print(dr.maximum(x, 3.0).numpy().sum())")


_INITIALISED = {}


def init_mitsuba(threads, force_scalar=False):
    """llvm_ad_rgb when a working libLLVM >= 16 is there, else scalar_rgb, said loudly; once per
    process and (threads, force_scalar).

    LLVM 15 (Debian 12's default) aborts the whole process inside LLVM ("Cannot select:
    fmaximum") on the first dr.maximum, which no try/except catches, so the backend is probed in
    a child process first."""
    key = (threads, force_scalar)
    if key not in _INITIALISED:
        _INITIALISED[key] = _init_mitsuba(threads, force_scalar)
    return _INITIALISED[key]


def _init_mitsuba(threads, force_scalar):
    import subprocess

    cuda = os.environ.get("MITSUBA_VARIANT", "")
    if cuda:
        # A GPU run (tools/gpu-bench): Dr.Jit's CUDA backend and OptiX from the driver; no
        # LLVM probe, and no fallback -- a failure here is reported, not hidden.
        if not cuda.startswith("cuda_"):
            sys.exit(f"MITSUBA_VARIANT={cuda}: only cuda_* variants are chosen this way")
        import drjit as dr
        import mitsuba as mi

        mi.set_variant(cuda)
        log(f"mitsuba {mi.__version__}, variant {cuda} (MITSUBA_VARIANT)")
        return dr, mi, cuda
    reason = None
    if not force_scalar:
        lib = os.environ.get("DRJIT_LIBLLVM_PATH")
        if lib and (llvm_major(lib) or 0) < 16:
            log(f"DRJIT_LIBLLVM_PATH={lib} is LLVM {llvm_major(lib)} (< 16, breaks Dr.Jit); looking for a newer one")
            lib = None
        if not lib:
            lib = find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
            probe = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=300)
            if probe.returncode != 0 or probe.stdout.strip() != "34.0":
                reason = f"probe with {lib} failed (rc {probe.returncode}): {(probe.stderr or probe.stdout).strip()[-300:]}"
        else:
            reason = "no libLLVM >= 16 found (tools/mitsuba-deps.sh installs one)"
    import drjit as dr
    import mitsuba as mi

    variant = "scalar_rgb"
    if not force_scalar and reason is None:
        if threads > 0:
            dr.set_thread_count(threads)
        mi.set_variant("llvm_ad_rgb")
        variant = "llvm_ad_rgb"
    else:
        if reason:
            log("!" * 72)
            log(f"!!! llvm_ad_rgb UNAVAILABLE: {reason}")
            log("!!! FALLING BACK TO scalar_rgb: one ray per Python call, far too slow past tiny fields.")
            log("!" * 72)
        mi.set_variant("scalar_rgb")
    log(f"mitsuba {mi.__version__}, variant {variant}, Dr.Jit threads {dr.thread_count()}, "
        f"DRJIT_LIBLLVM_PATH={os.environ.get('DRJIT_LIBLLVM_PATH', '(unset)')}")
    return dr, mi, variant


# ---------------------------------------------------------------------------------------------
# Export


def load_export(d):
    with open(os.path.join(d, "scene.toml"), "rb") as f:
        sc = tomllib.load(f)
    w, h = int(sc["width"]), int(sc["height"])
    heights = np.fromfile(os.path.join(d, "heights.f32"), dtype="<f4")
    if heights.size != w * h:
        sys.exit(f"heights.f32 has {heights.size} values, expected {w}x{h}")
    sc["H"] = heights.reshape(h, w).astype(np.float64)
    sc["environment_sh"] = np.asarray(sc["environment_sh"], dtype=np.float64).reshape(-1, 3)
    sc["albedo"] = np.asarray(sc["albedo"], dtype=np.float64)
    sc.setdefault("key_light", [])
    sc.setdefault("local_light", [])
    sc.setdefault("sphere", [])
    return sc


def normals(H, s):
    h, w = H.shape
    i = np.arange(w)
    j = np.arange(h)
    i0, i1 = np.maximum(i - 1, 0), np.minimum(i + 1, w - 1)
    j0, j1 = np.maximum(j - 1, 0), np.minimum(j + 1, h - 1)
    dx = (H[:, i1] - H[:, i0]) / ((i1 - i0) * s)[None, :]
    dy = (H[j1, :] - H[j0, :]) / ((j1 - j0) * s)[:, None]
    n = np.stack([-dx, -dy, np.ones_like(H)], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def build_mesh(mi, H, s, R, spheres=()):
    """The bilinear surface, refined R x R per texel, as a Mitsuba mesh, plus each sphere
    blocker as a Mitsuba `sphere` shape (ids "blocker0", ...). Returns (scene, mesh)."""
    h, w = H.shape
    nx, ny = (w - 1) * R + 1, (h - 1) * R + 1
    u = np.arange(nx) / R  # texel coordinates
    v = np.arange(ny) / R
    i0 = np.minimum(np.floor(u).astype(int), w - 2)
    j0 = np.minimum(np.floor(v).astype(int), h - 2)
    fu = (u - i0)[None, :]
    fv = (v - j0)[:, None]
    h00 = H[j0][:, i0]
    h10 = H[j0][:, i0 + 1]
    h01 = H[j0 + 1][:, i0]
    h11 = H[j0 + 1][:, i0 + 1]
    z = (1 - fv) * ((1 - fu) * h00 + fu * h10) + fv * ((1 - fu) * h01 + fu * h11)
    # Exact heights at the texel vertices (the receivers sit on them).
    z[::R, ::R] = H
    X, Y = np.meshgrid(u * s, v * s)
    pos = np.stack([X, Y, z], axis=-1).reshape(-1, 3).astype(np.float32)
    idx = np.arange(nx * ny, dtype=np.uint32).reshape(ny, nx)
    a = idx[:-1, :-1].ravel()
    b = idx[:-1, 1:].ravel()
    c = idx[1:, :-1].ravel()
    d = idx[1:, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]).astype(np.uint32)
    mesh = mi.Mesh("heightfield", nx * ny, faces.shape[0], has_vertex_normals=False,
                   has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    # The buffers' own array types (mi.Float / mi.UInt32 under llvm, dynamic arrays under scalar).
    params["vertex_positions"] = type(params["vertex_positions"])(pos.ravel())
    params["faces"] = type(params["faces"])(faces.ravel())
    params.update()
    desc = {"type": "scene", "heightfield": mesh}
    for k, sp in enumerate(spheres):
        desc[f"blocker{k}"] = {"type": "sphere", "center": [float(v) for v in sp["center"]],
                               "radius": float(sp["radius"])}
    scene = mi.load_dict(desc)
    log(f"mesh: {nx}x{ny} vertices, {faces.shape[0]} triangles (refine {R}); {len(spheres)} sphere blocker(s)")
    return scene, mesh


# ---------------------------------------------------------------------------------------------
# Spherical harmonics (real, orthonormal, no Condon-Shortley phase, k = l(l+1)+m)


def sh_eval_rgb(coeffs, d):
    """sum_k coeffs[k] y_k(d) for unit directions d (N x 3); coeffs n^2 x C. Any order n."""
    n = int(round(math.sqrt(coeffs.shape[0])))
    assert n * n == coeffs.shape[0]
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    out = np.zeros((d.shape[0], coeffs.shape[1]))
    # P~_l^m = P_l^m / sin^m(theta), a polynomial in z; (x + i y)^m = sin^m e^{i m phi}.
    cm = np.ones_like(x)  # Re (x+iy)^m
    sm = np.zeros_like(x)  # Im (x+iy)^m
    dfact = 1.0  # (2m-1)!!
    for m in range(n):
        if m > 0:
            cm, sm = cm * x - sm * y, cm * y + sm * x
            dfact *= 2 * m - 1
        p_prev = None
        p = np.full_like(z, dfact)  # P~_m^m
        for l in range(m, n):
            if l == m + 1:
                p_prev, p = p, z * (2 * m + 1) * p
            elif l > m + 1:
                p_prev, p = p, ((2 * l - 1) * z * p - (l + m - 1) * p_prev) / (l - m)
            K = math.sqrt((2 * l + 1) / (4 * math.pi) * math.factorial(l - m) / math.factorial(l + m))
            if m == 0:
                out += np.outer(K * p, coeffs[l * (l + 1)])
            else:
                out += np.outer(math.sqrt(2) * K * cm * p, coeffs[l * (l + 1) + m])
                out += np.outer(math.sqrt(2) * K * sm * p, coeffs[l * (l + 1) - m])
    return out


def sh_basis_order4_cartesian(d):
    """The CONVENTIONS.md order-4 Cartesian list, for the self-test only."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    return np.stack([
        0.282095 * np.ones_like(x),
        0.488603 * y, 0.488603 * z, 0.488603 * x,
        1.092548 * x * y, 1.092548 * y * z, 0.315392 * (3 * z * z - 1), 1.092548 * x * z,
        0.546274 * (x * x - y * y),
        0.590044 * y * (3 * x * x - y * y), 2.890611 * x * y * z, 0.457046 * y * (5 * z * z - 1),
        0.373176 * z * (5 * z * z - 3), 0.457046 * x * (5 * z * z - 1),
        1.445306 * z * (x * x - y * y), 0.590044 * x * (x * x - 3 * y * y),
    ], axis=1)


def self_test():
    rng = np.random.default_rng(1)
    d = rng.normal(size=(1000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    B = sh_basis_order4_cartesian(d)
    for k in range(16):
        c = np.zeros((16, 3))
        c[k] = 1.0
        err = np.abs(sh_eval_rgb(c, d)[:, 0] - B[:, k]).max()
        assert err < 2e-5, (k, err)
    # Orthonormality of order 6 by quadrature (Fibonacci sphere).
    m = 50000
    t = (np.arange(m) + 0.5) / m
    zz = 1 - 2 * t
    ph = math.pi * (1 + 5 ** 0.5) * np.arange(m)
    r = np.sqrt(1 - zz * zz)
    d = np.stack([r * np.cos(ph), r * np.sin(ph), zz], 1)
    Y = sh_eval_rgb(np.eye(36), d)
    G = Y.T @ Y * (4 * math.pi / m)
    assert np.abs(G - np.eye(36)).max() < 1e-3, np.abs(G - np.eye(36)).max()
    log("self-test: SH matches the CONVENTIONS.md order-4 table and is orthonormal to order 6")


# ---------------------------------------------------------------------------------------------
# Sampling


def onb(n):
    """Orthonormal tangent frame (Duff et al. 2017) for unit normals n (N x 3)."""
    sign = np.where(n[:, 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    t = np.stack([1 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], 1)
    bt = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], 1)
    return t, bt


def _splitmix64(x):
    x = x + np.uint64(0x9E3779B97F4A7C15)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def stratified(key, texels, m):
    """m x m jittered grid per texel: (len(texels)*m*m) x 2 in [0,1)^2, texel-major.

    The jitter is a counter-based hash of (key, texel, sample, dimension), so the result does
    not depend on how texels are chunked."""
    n = m * m
    g = np.arange(n, dtype=np.uint64)
    ctr = (texels.astype(np.uint64)[:, None] * np.uint64(n) + g[None, :]).ravel() * np.uint64(2)
    k = _splitmix64(np.asarray([key], dtype=np.uint64))[0]
    ju = (_splitmix64(ctr ^ k) >> np.uint64(11)).astype(np.float64) * 2.0 ** -53
    jv = (_splitmix64((ctr + np.uint64(1)) ^ k) >> np.uint64(11)).astype(np.float64) * 2.0 ** -53
    ga = np.tile((np.arange(n) % m).astype(np.float64), len(texels))
    gb = np.tile((np.arange(n) // m).astype(np.float64), len(texels))
    return np.stack([(ga + ju) / m, (gb + jv) / m], -1)


def cosine_local(uv):
    """Concentric (Shirley-Chiu) map + Malley: cosine-weighted local directions."""
    a = 2 * uv[:, 0] - 1
    b = 2 * uv[:, 1] - 1
    big = np.abs(a) > np.abs(b)
    r = np.where(big, a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = np.where(big, (math.pi / 4) * (b / a), (math.pi / 2) - (math.pi / 4) * (a / b))
    phi = np.where((a == 0) & (b == 0), 0.0, phi)
    x = r * np.cos(phi)
    y = r * np.sin(phi)
    z = np.sqrt(np.maximum(0.0, 1 - x * x - y * y))
    return np.stack([x, y, z], 1)


def cap_local(uv, cos_alpha):
    """Uniform by solid angle in a cap of half-angle alpha about +z."""
    ct = 1 - uv[:, 0] * (1 - cos_alpha)
    st = np.sqrt(np.maximum(0.0, 1 - ct * ct))
    ph = 2 * math.pi * uv[:, 1]
    return np.stack([st * np.cos(ph), st * np.sin(ph), ct], 1)


def to_world(local, n, t, b):
    return local[:, 0:1] * t + local[:, 1:2] * b + local[:, 2:3] * n


def bilinear(grid, fx, fy):
    """grid (H, W, 3) sampled at texel coordinates (fx, fy), clamped to the domain."""
    h, w, _ = grid.shape
    fx = np.clip(fx, 0, w - 1)
    fy = np.clip(fy, 0, h - 1)
    i0 = np.minimum(np.floor(fx).astype(np.int64), w - 2)
    j0 = np.minimum(np.floor(fy).astype(np.int64), h - 2)
    ax = (fx - i0)[:, None]
    ay = (fy - j0)[:, None]
    return ((1 - ay) * ((1 - ax) * grid[j0, i0] + ax * grid[j0, i0 + 1])
            + ay * ((1 - ax) * grid[j0 + 1, i0] + ax * grid[j0 + 1, i0 + 1]))


def sphere_entry(o, d, c, r):
    """Distance along unit rays (o, d) (N x 3) to where they first meet the sphere (c, r):
    the near root of |o + t d - c| = r, without cancellation (q / (b + sqrt(b^2 - q)), b = d.C,
    q = |C|^2 - r^2, C = c - o); 0 when o is inside (q <= 0); inf when the ray misses or the
    sphere is behind it. float64, numpy."""
    C = c[None, :] - o
    b = np.einsum("ij,ij->i", d, C)
    q = np.einsum("ij,ij->i", C, C) - r * r
    disc = b * b - q
    with np.errstate(divide="ignore", invalid="ignore"):
        t = q / (b + np.sqrt(np.maximum(disc, 0.0)))
    t = np.where((disc >= 0) & (b > 0), t, np.inf)
    return np.where(q <= 0, 0.0, t)


# ---------------------------------------------------------------------------------------------


class Tracer:
    """Batches of rays through Mitsuba: one wavefront (llvm_ad_rgb) or a Python loop (scalar_rgb)."""

    def __init__(self, mi, scene, variant, mesh=None):
        self.mi = mi
        self.scene = scene
        self.mesh = mesh
        self.scalar = variant.startswith("scalar")
        self.rays = 0
        self.seconds = 0.0

    def _ray(self, o, d):
        mi = self.mi
        o = o.astype(np.float32)
        d = d.astype(np.float32)
        return mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))

    def _scalar_rays(self, o, d):
        mi = self.mi
        for a, b in zip(o.astype(np.float32).tolist(), d.astype(np.float32).tolist()):
            yield mi.Ray3f(mi.Point3f(*a), mi.Vector3f(*b))

    def escapes(self, o, d):
        t0 = time.time()
        if self.scalar:
            hit = np.fromiter((bool(self.scene.ray_test(r)) for r in self._scalar_rays(o, d)), bool, len(o))
        else:
            hit = self.scene.ray_test(self._ray(o, d)).numpy().astype(bool)
        self.seconds += time.time() - t0
        self.rays += len(o)
        return ~hit

    def hit_t(self, o, d):
        """Distance to the first hit (inf where the ray escapes)."""
        t0 = time.time()
        if self.scalar:
            t = np.full(len(o), np.inf)
            for k, r in enumerate(self._scalar_rays(o, d)):
                pi = self.scene.ray_intersect_preliminary(r)
                if pi.is_valid():
                    t[k] = float(pi.t)
        else:
            pi = self.scene.ray_intersect_preliminary(self._ray(o, d))
            valid = pi.is_valid().numpy().astype(bool)
            t = np.where(valid, pi.t.numpy().astype(np.float64), np.inf)
        self.seconds += time.time() - t0
        self.rays += len(o)
        return t

    def hit_t_shape(self, o, d):
        """(distance to the first hit, inf where the ray escapes; True where that hit is on the
        height-field mesh, False where it is on a sphere blocker or there is none), from
        Mitsuba's own shape pointer of the hit."""
        t0 = time.time()
        if self.scalar:
            t = np.full(len(o), np.inf)
            terr = np.zeros(len(o), dtype=bool)
            for k, r in enumerate(self._scalar_rays(o, d)):
                pi = self.scene.ray_intersect_preliminary(r)
                if pi.is_valid():
                    t[k] = float(pi.t)
                    terr[k] = pi.shape.id() == "heightfield"
        else:
            pi = self.scene.ray_intersect_preliminary(self._ray(o, d))
            valid = pi.is_valid().numpy().astype(bool)
            t = np.where(valid, pi.t.numpy().astype(np.float64), np.inf)
            terr = valid & (pi.shape == self.mi.ShapePtr(self.mesh)).numpy().astype(bool)
        self.seconds += time.time() - t0
        self.rays += len(o)
        return t, terr


class PeerRenderer:
    """One exported field in Mitsuba: the mesh and receivers, built once (`setup_seconds`); then
    the direct layer at given sample counts, and the indirect bounces from a direct layer.
    tools/peer_ratio.py drives it in-process, so that repeated runs reuse the mesh and Dr.Jit's
    compiled kernels."""

    def __init__(self, export_dir, refine=4, threads=1, eps=None, no_local_test=False, scalar=False):
        sc = load_export(export_dir)
        if sc.get("wrap", False):
            log("wrap = true is not supported by this check (periodic fields need an infinite tiling)")
            sys.exit(2)
        self.export_dir = export_dir
        self.sc = sc
        H, s = sc["H"], float(sc["texel_size"])
        self.H, self.s = H, s
        self.h, self.w = H.shape
        self.rho = sc["albedo"]
        self.env = sc["environment_sh"]
        self.bounces = int(sc.get("bounces", 0))
        self.keys = sc["key_light"]
        self.lights = sc["local_light"]
        self.spheres = sc["sphere"]
        self.no_local_test = no_local_test
        dz = max(np.abs(np.diff(H, axis=0)).max(initial=0.0), np.abs(np.diff(H, axis=1)).max(initial=0.0))
        extent = max((self.w - 1) * s, (self.h - 1) * s, np.abs(H).max(),
                     *(np.abs(np.asarray(sp["center"], dtype=np.float64)).max() + float(sp["radius"])
                       for sp in self.spheres))
        self.eps = eps if eps is not None else max(1e-4 * max(s, dz), 64 * float(np.spacing(np.float32(extent))))
        self.dr, self.mi, self.variant = init_mitsuba(threads, scalar)
        t0 = time.time()
        self.scene, self.mesh = build_mesh(self.mi, H, s, refine, self.spheres)
        self.tracer = Tracer(self.mi, self.scene, self.variant, self.mesh)
        self.N = normals(H, s).reshape(-1, 3)
        self.T, self.B = onb(self.N)
        jj, ii = np.meshgrid(np.arange(self.h), np.arange(self.w), indexing="ij")
        P = np.stack([ii.ravel() * s, jj.ravel() * s, H.ravel()], 1)
        self.P = P
        self.O = P + np.array([0.0, 0.0, self.eps])
        # Receivers inside a sphere blocker (|P - c| <= r) see nothing (docs/blockers.md §1):
        # their rays hit the sphere from inside in Mitsuba too; for local lights it is explicit.
        self.in_blocker = np.zeros(len(P), dtype=bool)
        for sp in self.spheres:
            c = np.asarray(sp["center"], dtype=np.float64)
            self.in_blocker |= np.linalg.norm(P - c[None, :], axis=1) <= float(sp["radius"])
        self.sphere_hits_checked = 0
        self.sphere_hits_disagree = 0
        self.ntex = self.w * self.h
        self.Hf = H.ravel()
        self.setup_seconds = time.time() - t0

    def enters_below(self, tex, d):
        """True where the ray from receiver `tex` along d goes into the bilinear surface at
        t = 0+: its slope d_z is below the surface's one-sided directional derivative into the
        quad it enters, (H[j][i±1]-H[j][i])|d_x|/s + (H[j±1][i]-H[j][i])|d_y|/s (the bilinear
        uv term has no first-order part at a corner). A ray that leaves the domain at once
        never does."""
        if self.no_local_test:
            return np.zeros(len(d), dtype=bool)
        w, h, Hf = self.w, self.h, self.Hf
        i, j = tex % w, tex // w
        i1 = np.where(d[:, 0] >= 0, i + 1, i - 1)
        j1 = np.where(d[:, 1] >= 0, j + 1, j - 1)
        inside = (i1 >= 0) & (i1 < w) & (j1 >= 0) & (j1 < h)
        i1c, j1c = np.clip(i1, 0, w - 1), np.clip(j1, 0, h - 1)
        h0 = Hf[tex]
        slope = ((Hf[j * w + i1c] - h0) * np.abs(d[:, 0]) + (Hf[j1c * w + i] - h0) * np.abs(d[:, 1])) / self.s
        return inside & (d[:, 2] < slope)

    def passes(self, label, pass_id, per_texel, fn, seed, chunk, quiet=False):
        """Run fn(texel_slice, key) over chunks of texels; fn returns a (len, 3) array."""
        out = np.zeros((self.ntex, 3))
        tpc = max(1, chunk // per_texel)
        nch = (self.ntex + tpc - 1) // tpc
        t0 = time.time()
        for c in range(nch):
            sl = slice(c * tpc, min(self.ntex, (c + 1) * tpc))
            key = (seed * 1000003 + pass_id) & ((1 << 63) - 1)
            out[sl] = fn(sl, key)
            if not quiet and (c == nch - 1 or (c % max(1, nch // 10)) == 0):
                log(f"{label}: chunk {c + 1}/{nch}, {time.time() - t0:.1f} s")
        return out

    def direct(self, spp, key_spp=None, seed=0, chunk=1 << 20, quiet=False, local_spp=None):
        """The direct layer L_o = rho/pi E, (ntex, 3): the environment over m x m stratified
        cosine directions (m = round(sqrt(spp))), each key light over mk x mk directions uniform
        in its cap, each local light over ml x ml directions uniform in the cap it subtends
        (default: as key lights)."""
        m = max(1, int(round(math.sqrt(spp))))
        mk = max(1, int(round(math.sqrt(key_spp if key_spp else spp))))
        ml = max(1, int(round(math.sqrt(local_spp if local_spp else (key_spp if key_spp else spp)))))
        nspp, kspp = m * m, mk * mk
        N, T, B, O = self.N, self.T, self.B, self.O

        def env_chunk(sl, key):
            nt = sl.stop - sl.start
            loc = cosine_local(stratified(key, np.arange(sl.start, sl.stop), m))
            rep = lambda a: np.repeat(a[sl], nspp, axis=0)  # noqa: E731
            d = to_world(loc, rep(N), rep(T), rep(B))
            tex = np.repeat(np.arange(sl.start, sl.stop), nspp)
            vis = ~self.enters_below(tex, d)
            vis[vis] = self.tracer.escapes(rep(O)[vis], d[vis])
            L = sh_eval_rgb(self.env, d) * vis[:, None]
            return math.pi * L.reshape(nt, nspp, 3).mean(1)

        E = self.passes("direct/environment", 0, nspp, env_chunk, seed, chunk, quiet)
        for kidx, kl in enumerate(self.keys):
            E += self.passes(f"direct/key light {kidx}", 100 + kidx, kspp, self._key_chunk(kl, mk), seed, chunk, quiet)
        for lidx, ll in enumerate(self.lights):
            E += self.passes(f"direct/local light {lidx}", 300 + lidx, ml * ml, self._local_chunk(ll, ml), seed, chunk,
                             quiet)
        # A receiver inside a sphere blocker sees nothing (docs/blockers.md §1): explicit, since
        # from inside a sphere the height field within it can be hit before the sphere.
        E[self.in_blocker] = 0.0
        return self.rho[None, :] / math.pi * E

    def _local_chunk(self, ll, ml):
        """The chunk function of one local light (CONVENTIONS.md "Lighting": a sphere of centre c,
        radius r, uniform radiance L seen from outside), ml x ml samples per receiver.

        Receiver P (the texel sample, not lifted), C = c - P, d = |C|: directions uniform by
        solid angle in the cap of half-angle asin(r/d) about C/d, Omega = 2 pi (1 - cos), the
        estimate Omega/n sum_k V_k max(N.w_k, 0) L. V_k = 1 iff the ray (from the lifted origin,
        Mitsuba, height field and sphere blockers) has its first hit beyond the light's entry
        distance tau (the near root of |P + t w - c| = r, analytic in numpy, f64), or escapes;
        a ray that goes into the surface at t = 0+ (enters_below) is blocked.
        Receiver inside the light (d <= r): hfgi's documented rule (docs/local-lights.md §2,
        src/reference/local_truth.rs), the limit at d = r: the cap is the hemisphere toward c
        (sin = 1, cos = 0; toward +z when d = 0) and nothing blocks it (tau = 0: neither the
        terrain nor a blocker), only directions below N's tangent plane count 0. A receiver
        inside a sphere blocker sees no local light."""
        c = np.asarray(ll["position"], dtype=np.float64)
        r = float(ll["radius"])
        Ll = np.asarray(ll["radiance"], dtype=np.float64)
        lspp = ml * ml

        def local_chunk(sl, key):
            nt = sl.stop - sl.start
            tex = np.arange(sl.start, sl.stop)
            P = self.P[sl]
            C = c[None, :] - P
            dist = np.linalg.norm(C, axis=1)
            inside = dist <= r
            safe = np.where(dist > 0, dist, 1.0)
            l = np.where((dist > 0)[:, None], C / safe[:, None], np.array([0.0, 0.0, 1.0]))
            cos_a = np.where(inside, 0.0, np.sqrt(np.maximum((dist - r) * (dist + r), 0.0)) / safe)
            omega = 2 * math.pi * (1 - cos_a)
            lt, lb = onb(l)
            rep = lambda a: np.repeat(a, lspp, axis=0)  # noqa: E731
            loc = cap_local(stratified(key, tex, ml), rep(cos_a))
            d = to_world(loc, rep(l), rep(lt), rep(lb))
            cos = np.einsum("ij,ij->i", rep(self.N[sl]), d)
            up = cos > 0
            ins = rep(inside)
            trace = up & ~ins
            trace &= ~self.enters_below(rep(tex), d)
            vis = up & ins
            if trace.any():
                dt = d[trace]
                t_hit = self.tracer.hit_t(rep(self.O[sl])[trace], dt)
                # Entry distance from the receiver; the direction is in the cap by construction,
                # so a negative discriminant is rounding at the rim (clamped to a tangent ray).
                Cr = rep(C)[trace]
                b = np.einsum("ij,ij->i", dt, Cr)
                q = rep((dist - r) * (dist + r))[trace]
                tau = q / (b + np.sqrt(np.maximum(b * b - q, 0.0)))
                vis[trace] = t_hit > tau
            vis &= ~rep(self.in_blocker[sl])
            wgt = np.where(vis, cos, 0.0)
            return (omega * wgt.reshape(nt, lspp).mean(1))[:, None] * Ll[None, :]

        return local_chunk

    def _key_chunk(self, kl, mk):
        """The chunk function of one key light (a true cap of directions), mk x mk samples."""
        kd = np.asarray(kl["direction"], dtype=np.float64)
        kd /= np.linalg.norm(kd)
        Lk = np.asarray(kl["radiance"], dtype=np.float64)
        ca = math.cos(float(kl["angular_radius"]))
        omega = 2 * math.pi * (1 - ca)
        kt, kb = onb(kd[None, :])
        kspp = mk * mk

        def key_chunk(sl, key):
            nt = sl.stop - sl.start
            loc = cap_local(stratified(key, np.arange(sl.start, sl.stop), mk), ca)
            d = to_world(loc, kd[None, :], kt, kb)
            Nr = np.repeat(self.N[sl], kspp, axis=0)
            cos = np.einsum("ij,ij->i", Nr, d)
            up = cos > 0
            up &= ~self.enters_below(np.repeat(np.arange(sl.start, sl.stop), kspp), d)
            vis = np.zeros(len(d), dtype=bool)
            if up.any():
                vis[up] = self.tracer.escapes(np.repeat(self.O[sl], kspp, axis=0)[up], d[up])
            wgt = np.where(vis, cos, 0.0)
            return omega * wgt.reshape(nt, kspp).mean(1)[:, None] * Lk[None, :]

        return key_chunk

    def indirect(self, direct, bounce_spp, bounces=None, seed=0, chunk=1 << 20, quiet=False):
        """The indirect layer (sum of bounces 1..bounces, default the export's), fresh
        mb x mb cosine directions per bounce, from the direct layer `direct`."""
        mb = max(1, int(round(math.sqrt(bounce_spp))))
        bspp = mb * mb
        s, rho = self.s, self.rho
        grid = direct.reshape(self.h, self.w, 3)
        indirect = np.zeros_like(direct)
        for b in range(1, (self.bounces if bounces is None else bounces) + 1):
            prev = grid

            def ind_chunk(sl, key, prev=prev):
                nt = sl.stop - sl.start
                loc = cosine_local(stratified(key, np.arange(sl.start, sl.stop), mb))
                rep = lambda a: np.repeat(a[sl], bspp, axis=0)  # noqa: E731
                d = to_world(loc, rep(self.N), rep(self.T), rep(self.B))
                o = rep(self.O)
                tex = np.repeat(np.arange(sl.start, sl.stop), bspp)
                below = self.enters_below(tex, d)
                t = np.full(len(d), np.inf)
                if self.spheres:
                    # A first hit on a sphere blocker carries nothing (spheres do not reflect).
                    terr = np.zeros(len(d), dtype=bool)
                    t[~below], terr[~below] = self.tracer.hit_t_shape(o[~below], d[~below])
                    self._check_sphere_hits(o[~below], d[~below], t[~below], terr[~below])
                    hit = np.isfinite(t) & terr
                else:
                    t[~below] = self.tracer.hit_t(o[~below], d[~below])
                    hit = np.isfinite(t)
                Lin = np.zeros((len(d), 3))
                # Into the surface at t = 0+: the first hit is the receiver itself.
                Lin[below] = prev.reshape(-1, 3)[tex[below]]
                if hit.any():
                    p = o[hit] + t[hit, None] * d[hit]
                    Lin[hit] = bilinear(prev, p[:, 0] / s, p[:, 1] / s)
                return rho[None, :] * Lin.reshape(nt, bspp, 3).mean(1)

            Lb = self.passes(f"indirect/bounce {b}", 200 + b, bspp, ind_chunk, seed, chunk, quiet)
            Lb[self.in_blocker] = 0.0  # inside a sphere blocker: nothing (as in direct())
            indirect += Lb
            grid = Lb.reshape(self.h, self.w, 3)
        return indirect

    def _check_sphere_hits(self, o, d, t, terr):
        """Cross-check of Mitsuba's shape of the first hit against an analytic ray-sphere test
        in numpy (rays from outside every blocker): a sphere hit must lie at the nearest
        sphere entry, a height-field hit no farther than it. Counts disagreements."""
        ts = np.full(len(o), np.inf)
        for sp in self.spheres:
            ts = np.minimum(ts, sphere_entry(o, d, np.asarray(sp["center"], dtype=np.float64), float(sp["radius"])))
        ok = ts > 0
        tol = 1e-4 * np.maximum(1.0, np.where(np.isfinite(t), t, 0.0)) + 10 * self.eps
        sph = np.isfinite(t) & ~terr
        bad = ok & ((sph & (np.abs(t - ts) > tol)) | (terr & (t > ts + tol)))
        self.sphere_hits_checked += int(ok.sum())
        self.sphere_hits_disagree += int(bad.sum())

    def write(self, path, direct, indirect):
        """The layers as `hfgi render --shading-exr` names them (glossy = 0)."""
        h, w = self.h, self.w
        total = direct + indirect
        img = np.concatenate([total, direct, np.zeros_like(direct), indirect], axis=1).reshape(h, w, 12)
        names = ["R", "G", "B", "direct.R", "direct.G", "direct.B", "glossy.R", "glossy.G", "glossy.B",
                 "indirect.R", "indirect.G", "indirect.B"]
        bmp = self.mi.Bitmap(np.ascontiguousarray(img.astype(np.float32)),
                             pixel_format=self.mi.Bitmap.PixelFormat.MultiChannel, channel_names=names)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        # Mitsuba 3.9.1's EXR writer deadlocks on a one-thread Dr.Jit pool (it waits on a task
        # that it queued behind itself): give it a second thread for the write.
        threads = self.dr.thread_count()
        if threads < 2:
            self.dr.set_thread_count(2)
        bmp.write(path)
        if threads < 2:
            self.dr.set_thread_count(threads)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("export_dir", nargs="?")
    ap.add_argument("--out", help="output EXR (layers direct, indirect, glossy, total in R,G,B)")
    ap.add_argument("--spp", type=int, default=1024, help="cosine samples per texel and pass (rounded to a square)")
    ap.add_argument("--key-spp", type=int, default=None, help="samples per texel per key light (default: --spp)")
    ap.add_argument("--local-spp", type=int, default=None,
                    help="samples per texel per local light (default: --key-spp)")
    ap.add_argument("--bounce-spp", type=int, default=None,
                    help="cosine samples per texel per indirect bounce (default: --spp)")
    ap.add_argument("--refine", type=int, default=4, help="mesh sub-quads per texel edge")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=int(os.environ.get("MITSUBA_CHECK_THREADS", "1")),
                    help="Dr.Jit threads (0: all cores; default 1 or $MITSUBA_CHECK_THREADS)")
    ap.add_argument("--chunk", type=int, default=1 << 20, help="rays per wavefront (bounds memory)")
    ap.add_argument("--eps", type=float, default=None, help="vertical lift of ray origins (world units)")
    ap.add_argument("--no-local-test", action="store_true",
                    help="trace every ray, also those that go into the surface at t = 0+ (for testing)")
    ap.add_argument("--scalar", action="store_true", help="force the scalar_rgb variant (slow)")
    ap.add_argument("--self-test", action="store_true", help="check the SH code and exit")
    args = ap.parse_args()

    if args.self_test:
        self_test()
        return
    if not args.export_dir or not args.out:
        ap.error("EXPORT_DIR and --out are required")
    self_test()

    pr = PeerRenderer(args.export_dir, args.refine, args.threads, args.eps, args.no_local_test, args.scalar)
    sq = lambda n: max(1, int(round(math.sqrt(n)))) ** 2  # noqa: E731
    spp, kspp = sq(args.spp), sq(args.key_spp if args.key_spp else args.spp)
    bspp = sq(args.bounce_spp if args.bounce_spp else args.spp)
    lspp = sq(args.local_spp if args.local_spp else kspp)
    log(f"{args.export_dir}: {pr.w}x{pr.h}, s={pr.s}, bounces={pr.bounces}, {len(pr.keys)} key light(s), "
        f"{len(pr.lights)} local light(s), {len(pr.spheres)} sphere blocker(s), SH order "
        f"{int(round(math.sqrt(pr.env.shape[0])))}, spp={spp} (stratified), key spp={kspp}, local spp={lspp}, "
        f"bounce spp={bspp}, eps={pr.eps:.3g}, seed={args.seed}")
    if pr.lights:
        P = pr.P
        for k, ll in enumerate(pr.lights):
            dd = np.linalg.norm(P - np.asarray(ll["position"], dtype=np.float64)[None, :], axis=1)
            n_in = int((dd <= float(ll["radius"])).sum())
            if n_in:
                log(f"local light {k}: {n_in} receiver(s) inside it (hemisphere toward the centre, unblocked)")
    if pr.in_blocker.any():
        log(f"{int(pr.in_blocker.sum())} receiver(s) inside a sphere blocker (they see nothing)")
    direct = pr.direct(spp, kspp, args.seed, args.chunk, local_spp=lspp)
    indirect = pr.indirect(direct, bspp, seed=args.seed, chunk=args.chunk)
    pr.write(args.out, direct, indirect)
    t = pr.tracer
    log(f"traced {t.rays / 1e6:.1f} M rays in {t.seconds:.1f} s "
        f"({t.rays / max(t.seconds, 1e-9) / 1e6:.2f} M rays/s, variant {pr.variant})")
    if pr.spheres:
        log(f"sphere-hit cross-check (Mitsuba's shape vs analytic ray-sphere): {pr.sphere_hits_disagree} of "
            f"{pr.sphere_hits_checked} bounce rays disagree")
    log(f"means: direct {direct.mean(0)}, indirect {indirect.mean(0)}")
    log(f"wrote {args.out}")


if __name__ == "__main__":
    main()
