//! CPU (f64) twin of the swept horizons (`gi.visibility = "sweep"`, docs/direct.md §7). The GPU
//! version is `glsl/visibility/sweep.comp.glsl` (far field) and `hfgi_near_slope` in
//! `glsl/visibility/visibility.comp.glsl` (near field); both follow this description.
//!
//! A receiver's horizon along `d` is `ω = max(ω_near, ω_far)`:
//!
//! - **Near field**, `t ∈ (0, R]` texels, `R = gi.sweep_near`: along the receiver's own ray, one
//!   piece per cell of the level-0 grid (split where the ray crosses an integer `x` or `y`), each
//!   the quadratic through the surface at the piece's start, middle and end (exact on the bilinear
//!   surface, where the height along a line inside a cell *is* quadratic), and the largest `F(t)/t`
//!   of each piece in closed form (its ends and the stationary point `t* = √(c′/a)`; the first
//!   piece starts with the surface's own slope `F′(0)`). The ray ends where it leaves the field.
//! - **Far field**, beyond `R` (Timonen & Westerholm 2010, "Scalable Height Field
//!   Self-Shadowing"): the axis along which `|d|` is larger is the *major* axis `X`, the other
//!   the minor axis `Y`, `s = d_Y / d_X`. Sweep line `j` is `Y = j + s·X`, lines one texel apart,
//!   parallel to `d`. Each is walked from its far end toward its near end, pushing in order of
//!   decreasing `u = X·d_X + Y·d_Y` the surface points where it crosses an integer `X` and,
//!   between two of them, an integer `Y` (a row of the field), onto a stack that keeps their
//!   upper convex hull: entries less than `1e-5` texels ahead of the new point are the same point
//!   and dropped; then, while two entries are left and the slope from the new point to the one
//!   below the top is at least the slope to the top, the top is popped (it lies under the hull
//!   and is no later point's tangent either). Points whose minor coordinate is outside
//!   `[−1, N_Y]` are not pushed (reads in `[−1, 0)` and `(N_Y − 1, N_Y]` are clamped, so that
//!   a receiver on the border has a line on each side).
//!   At each receiver column `X_r` the line's own point `q` there (on the surface) is queried
//!   just before the sweep pushes a point with `u ≤ u_q + R + 1e-5`: its far horizon is the
//!   tangent from `q` to the hull of everything more than `R` ahead, found by binary search.
//!   A receiver at `(X_r, Y_r)` has `rel = Y_r − s·X_r`; lines `⌊rel⌋` and `⌊rel⌋ + 1` pass on
//!   either side of it and it takes `(1 − f)·ω_⌊rel⌋ + f·ω_⌊rel⌋+1`, `f = rel − ⌊rel⌋`.
//!
//! Why both: lines pass up to a texel beside a receiver, and the bilinear surface has a kink at
//! every texel (where receivers sit): the two lines beside a receiver at the foot of a one-texel
//! cliff see a ramp that its own ray does not, or the reverse. Without the near field
//! (`R = 0`, Timonen's scheme alone) the direct error on one-texel terraces at 128² was 3.2× the
//! ladder's; with `R = 16` it is 0.29× the ladder's and, at 64², within 10% of the floor that
//! exact horizons leave (docs/direct.md §7, docs/performance.md §2). Beyond `R` a lateral offset
//! of at most a texel changes the azimuth by at most `atan(1/R)`.
//!
//! Work per azimuth: O(W·H) hull operations and one O(log) query per receiver for the far field,
//! ≤ 2R + 2 pieces per receiver for the near field (the ladder reads ~40 samples per receiver at
//! the `default` preset). Periodic fields are not supported (a typed error; use "ladder").

use std::f64::consts::FRAC_PI_2;

use super::direct::Scan;
use super::pyramid::rescale;

/// Points closer than this (texels along `d`) to the next one are the same point.
pub const SAME_POINT: f64 = 1e-5;

/// The sweep's frame for one azimuth: major/minor axes and the receiver grid along them.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// The major axis is `y` (else `x`).
    pub swap: bool,
    /// Direction along major and minor axis.
    pub d: [f64; 2],
    /// `d_Y / d_X`.
    pub s: f64,
    /// Level-0 size along major and minor axis.
    pub n: [usize; 2],
    /// Receiver grid along major and minor axis.
    pub work: [usize; 2],
}

impl Frame {
    /// The frame of direction `(dx, dy)` on a `w × h` field with a `work` receiver grid.
    pub fn new(dx: f64, dy: f64, n0: (usize, usize), work: (usize, usize)) -> Self {
        let swap = dy.abs() > dx.abs();
        let (d, n, wk) =
            if swap { ([dy, dx], [n0.1, n0.0], [work.1, work.0]) } else { ([dx, dy], [n0.0, n0.1], [work.0, work.1]) };
        Self { swap, d, s: d[1] / d[0], n, work: wk }
    }

    /// Receiver coordinate along axis `k` (0 major, 1 minor) of grid index `i`.
    pub fn receiver(&self, k: usize, i: usize) -> f64 {
        rescale(i as f64, self.work[k], self.n[k])
    }

    /// `rel = Y_r − s·X_r` of receiver `(a, b)` (major, minor grid indices).
    pub fn rel(&self, a: usize, b: usize) -> f64 {
        self.receiver(1, b) - self.s * self.receiver(0, a)
    }

    /// The lines `j0 ..= j1` that pass next to some receiver (one spare line each side).
    pub fn lines(&self) -> (i64, i64) {
        let corners = [(0, 0), (0, self.work[1] - 1), (self.work[0] - 1, 0), (self.work[0] - 1, self.work[1] - 1)];
        let rels = corners.map(|(a, b)| self.rel(a, b));
        let lo = rels.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = rels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo.floor() as i64 - 1, hi.floor() as i64 + 1)
    }

    /// Field receiver index of grid indices `(a, b)` along (major, minor).
    pub fn index(&self, a: usize, b: usize) -> usize {
        if self.swap {
            a * self.work[1] + b
        } else {
            b * self.work[0] + a
        }
    }

    /// Field position of `(X, Y)`.
    pub fn field(&self, x: f64, y: f64) -> (f64, f64) {
        if self.swap {
            (y, x)
        } else {
            (x, y)
        }
    }
}

/// One point of a line: its distance `u` along `d` and its height.
#[derive(Clone, Copy, Debug)]
struct Point {
    u: f64,
    h: f64,
}

fn slope(a: &Point, b: &Point) -> f64 {
    (b.h - a.h) / (b.u - a.u)
}

/// Pushes `p` onto the hull `stack` (every entry ahead of it), popping what it hides.
fn push(stack: &mut Vec<Point>, p: Point) {
    while stack.last().is_some_and(|t| t.u - p.u <= SAME_POINT) {
        stack.pop();
    }
    while stack.len() >= 2 && slope(&p, &stack[stack.len() - 2]) >= slope(&p, &stack[stack.len() - 1]) {
        stack.pop();
    }
    stack.push(p);
}

/// The horizon angle from `q` (behind every entry) to the hull `stack`, by binary search for
/// the largest `i` with `slope(q, st[i]) ≥ slope(st[i], st[i−1])` (true at 0, false past the
/// tangent); `−π/2` for an empty stack.
fn tangent(stack: &[Point], q: Point, texel_size: f64) -> f64 {
    if stack.is_empty() {
        return -FRAC_PI_2;
    }
    let (mut lo, mut hi) = (0usize, stack.len() - 1);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if slope(&q, &stack[mid]) >= slope(&stack[mid], &stack[mid - 1]) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    (slope(&q, &stack[lo]) / texel_size).atan()
}

/// Adds line `j`'s far horizon `omega` at receiver column `a` to the receivers beside it.
fn contribute(fr: &Frame, j: i64, a: usize, omega: f64, out: &mut [f64]) {
    let y = j as f64 + fr.s * fr.receiver(0, a);
    let (wy, ny) = (fr.work[1] as f64, fr.n[1] as f64);
    let lo = (((y - 0.5) * wy / ny - 0.5).ceil() as i64 - 1).max(0);
    let hi = (((y + 1.5) * wy / ny - 0.5).floor() as i64 + 1).min(fr.work[1] as i64 - 1);
    for b in lo..=hi {
        let rel = fr.rel(a, b as usize);
        let weight = if rel.floor() as i64 == j {
            1.0 - (rel - j as f64)
        } else if rel.floor() as i64 == j - 1 {
            rel - (j - 1) as f64
        } else {
            continue;
        };
        out[fr.index(a, b as usize)] += weight * omega;
    }
}

/// Walks line `j`, adding its far horizons (beyond `reach` texels) to `out`.
fn sweep_line(scan: &Scan, fr: &Frame, j: i64, reach: f64, stack: &mut Vec<Point>, out: &mut [f64]) {
    stack.clear();
    let sx = fr.d[0].signum();
    let far = if sx > 0.0 { (fr.n[0] - 1) as f64 } else { 0.0 };
    let at = |x: f64| {
        let y = j as f64 + fr.s * x;
        let (fx, fy) = fr.field(x, y);
        (y, Point { u: x * fr.d[0] + y * fr.d[1], h: scan.height0(fx, fy) })
    };
    // Receiver columns in sweep order; `next` is the one whose query is pending.
    let cols: Vec<usize> = if sx > 0.0 { (0..fr.work[0]).rev().collect() } else { (0..fr.work[0]).collect() };
    let mut next = 0;
    let mut visit = |x: f64, stack: &mut Vec<Point>, out: &mut [f64]| {
        let (y, p) = at(x);
        while let Some(&a) = cols.get(next) {
            let q = at(fr.receiver(0, a)).1;
            if p.u > q.u + reach + SAME_POINT {
                break;
            }
            contribute(fr, j, a, tangent(stack, q, scan.texel_size), out);
            next += 1;
        }
        if (-1.0..=fr.n[1] as f64).contains(&y) {
            push(stack, p);
        }
    };
    for k in 0..fr.n[0] {
        let x = far - sx * k as f64;
        if k > 0 {
            // The row crossing between the previous column and this one, if any.
            let xp = x + sx;
            let (ya, yb) = (j as f64 + fr.s * xp, j as f64 + fr.s * x);
            if ya.floor() != yb.floor() {
                let yc = ya.floor().max(yb.floor());
                let xc = (yc - j as f64) / fr.s;
                let lam = sx * (xp - xc);
                if yc >= 0.0 && yc <= (fr.n[1] - 1) as f64 && lam > 1e-6 && lam < 1.0 - 1e-6 {
                    visit(xc, stack, out);
                }
            }
        }
        visit(x, stack, out);
    }
    // Queries still pending see nothing farther than `reach`.
    while let Some(&a) = cols.get(next) {
        contribute(fr, j, a, tangent(stack, at(fr.receiver(0, a)).1, scan.texel_size), out);
        next += 1;
    }
}

/// The far-field horizon angle (beyond `reach` texels) of every receiver (receiver-grid order)
/// along azimuth `(dx, dy)`.
pub fn far_horizons(scan: &Scan, work: (usize, usize), dx: f64, dy: f64, reach: f64) -> Vec<f64> {
    let l0 = scan.pyr.layout.levels[0];
    let fr = Frame::new(dx, dy, (l0.width as usize, l0.height as usize), work);
    let mut out = vec![0.0; work.0 * work.1];
    let (j0, j1) = fr.lines();
    let mut stack = Vec::with_capacity(2 * fr.n[0]);
    for j in j0..=j1 {
        sweep_line(scan, &fr, j, reach, &mut stack, &mut out);
    }
    out
}

/// Largest `F(t)/t` of the piece `F(t0 + τ) = aτ² + bτ + c`, `τ ∈ [0, t1 − t0]` (at `t0 = 0`,
/// `c = 0` and the limit is `b`).
fn piece_max(t0: f64, t1: f64, a: f64, b: f64, c: f64) -> f64 {
    let len = t1 - t0;
    let start = if t0 > 0.0 { c / t0 } else { b };
    let mut best = start.max(((a * len + b) * len + c) / t1);
    // F/t = a·t + b′ + c′/t in absolute t: one stationary point t* = √(c′/a), a maximum when
    // a < 0 and c′ < 0.
    let cp = (a * t0 - b) * t0 + c;
    if a < 0.0 && cp < 0.0 {
        let ts = (cp / a).sqrt();
        if ts > t0 && ts < t1 {
            let tau = ts - t0;
            best = best.max(((a * tau + b) * tau + c) / ts);
        }
    }
    best
}

/// The near-field horizon slope `sup F(t)/t`, `t ∈ (0, reach]` (world height per texel) along
/// unit `d` from level-0 position `p`; None where the ray leaves the field at once.
pub fn near_slope(scan: &Scan, p: [f64; 2], d: [f64; 2], reach: f64) -> Option<f64> {
    let l0 = scan.pyr.layout.levels[0];
    near_slope_on([l0.width as f64, l0.height as f64], p, d, reach, |x, y| scan.height0(x, y))
}

/// [`near_slope`] over any surface `height(x, y)` of a field of `n` texels per axis (the
/// local lights read the raw bilinear heights: `reference::local`). One quadratic per level-0
/// cell the ray crosses, exact on a bilinear surface.
pub fn near_slope_on(
    n: [f64; 2],
    p: [f64; 2],
    d: [f64; 2],
    reach: f64,
    height: impl Fn(f64, f64) -> f64,
) -> Option<f64> {
    let exit = |k: usize| {
        if d[k] > 0.0 {
            (n[k] - 1.0 - p[k]) / d[k]
        } else if d[k] < 0.0 {
            p[k] / -d[k]
        } else {
            f64::INFINITY
        }
    };
    let t_end = reach.min(exit(0)).min(exit(1));
    if t_end <= 0.0 {
        return None;
    }
    // Distance to the first integer line ahead per axis, then one per 1/|d|.
    let step = |k: usize| if d[k].abs() > 1e-6 { 1.0 / d[k].abs() } else { f64::INFINITY };
    let first = |k: usize| {
        let dist = if d[k] > 0.0 { p[k].floor() + 1.0 - p[k] } else { p[k] - p[k].ceil() + 1.0 };
        dist * step(k)
    };
    let base = height(p[0], p[1]);
    let f = |t: f64| height(p[0] + t * d[0], p[1] + t * d[1]) - base;
    let (mut tx, mut ty) = (first(0), first(1));
    let (mut ta, mut fa) = (0.0, 0.0);
    let mut best = f64::NEG_INFINITY;
    loop {
        let tb = tx.min(ty).min(t_end);
        if tb > ta + 1e-6 {
            let len = tb - ta;
            let (fm, fb) = (f(ta + 0.5 * len), f(tb));
            let a = 2.0 * (fb - 2.0 * fm + fa) / (len * len);
            let b = (fb - fa) / len - a * len;
            best = best.max(piece_max(ta, tb, a, b, fa));
            fa = fb;
            ta = tb;
        }
        if tb >= t_end {
            break;
        }
        if tx <= tb {
            tx += step(0);
        }
        if ty <= tb {
            ty += step(1);
        }
    }
    Some(best)
}

/// The swept horizon angle `ω = max(ω_near, ω_far)` of every receiver (receiver-grid order)
/// along azimuth `(dx, dy)` with near reach `reach` texels.
pub fn horizons(scan: &Scan, work: (usize, usize), dx: f64, dy: f64, reach: f64) -> Vec<f64> {
    let l0 = scan.pyr.layout.levels[0];
    let (w, h) = (l0.width as usize, l0.height as usize);
    let mut out = far_horizons(scan, work, dx, dy, reach);
    if reach > 0.0 {
        for (r, o) in out.iter_mut().enumerate() {
            let p = [rescale((r % work.0) as f64, work.0, w), rescale((r / work.0) as f64, work.1, h)];
            if let Some(k) = near_slope(scan, p, [dx, dy], reach) {
                *o = o.max((k / scan.texel_size).atan());
            }
        }
    }
    out
}
