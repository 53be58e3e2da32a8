//! A ray over the bilinear surface (CONVENTIONS.md "Height field"), for the ground truth
//! (`super::truth`, docs/accuracy.md §1): exact intersection by cells, and the older fixed-step
//! march kept for comparison.
//!
//! Exact: from receiver vertex `p` along the unit 2D direction `d`, the ray is split at every
//! crossing of an integer `x` or `y` line (a DDA over cells; it ends where it leaves
//! `[0, W−1] × [0, H−1]`, or after `max(W, H)` texels with `wrap`). Inside one cell the
//! bilinear height along the line, relative to the receiver's, is the exact quadratic
//! `F(t₀ + τ) = aτ² + bτ + c`. The horizon slope is `sup F(t)/t` (closed form per piece: its
//! ends and the stationary point `t* = √(c′/a)` of `F/t = a·t + b′ + c′/t`; the first piece
//! starts at `t = 0` with `c = 0`, where the limit `F/t → b` is the surface's own slope), and
//! the first hit of slope `k` is the smallest `t` with `F(t) ≥ k·t`, a root of the piece's
//! quadratic. `t` is in texels, `F` in world units, so slopes are world height per texel.

/// The heights a ray runs over (level 0, row-major, f64).
#[derive(Clone, Copy)]
pub struct Surface<'a> {
    pub heights: &'a [f64],
    pub width: usize,
    pub height: usize,
    pub wrap: bool,
}

/// The ray inside one cell: `t ∈ [t0, t1]` texels from the receiver, height relative to the
/// receiver `F(t0 + τ) = (a·τ + b)·τ + c`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    pub t0: f64,
    pub t1: f64,
    pub a: f64,
    pub b: f64,
    pub c: f64,
}

impl Piece {
    /// `F(t0 + τ)`.
    pub fn value(&self, tau: f64) -> f64 {
        (self.a * tau + self.b) * tau + self.c
    }

    /// `sup F(t)/t` over the piece (for the first piece the limit `t → 0` included) and the `τ`
    /// where it is reached.
    pub fn max_slope(&self) -> (f64, f64) {
        let len = self.t1 - self.t0;
        let end = (self.value(len) / self.t1, len);
        let start = if self.t0 > 0.0 { self.c / self.t0 } else { self.b };
        let mut best = if start >= end.0 { (start, 0.0) } else { end };
        // F/t = a·t + b′ + c′/t in absolute t has one stationary point t* = √(c′/a), a maximum
        // when a < 0 and c′ < 0.
        let cp = (self.a * self.t0 - self.b) * self.t0 + self.c;
        if self.a < 0.0 && cp < 0.0 {
            let ts = (cp / self.a).sqrt();
            if ts > self.t0 && ts < self.t1 {
                let tau = ts - self.t0;
                let s = self.value(tau) / ts;
                if s > best.0 {
                    best = (s, tau);
                }
            }
        }
        best
    }

    /// The smallest `τ ∈ [0, tau_max]` with `F(t0 + τ) ≥ k·(t0 + τ)`, given that `F < k·t`
    /// before the piece and `F ≥ k·t` at `tau_max` (the piece's [`Self::max_slope`] point). With
    /// `G(τ) = aτ² + (b − k)τ + (c − k·t0)`, `G(0) < 0 ≤ G(tau_max)`: the one root in between,
    /// the one where `G` rises, `(−b₂ + √D)/(2a)`, written without cancellation.
    pub fn first_reach(&self, k: f64, tau_max: f64) -> f64 {
        let b2 = self.b - k;
        let c2 = self.c - k * self.t0;
        if c2 >= 0.0 && (self.t0 > 0.0 || b2 >= 0.0) {
            return 0.0;
        }
        let sq = (b2 * b2 - 4.0 * self.a * c2).max(0.0).sqrt();
        let r = if b2 >= 0.0 {
            let den = -b2 - sq;
            if den < 0.0 {
                2.0 * c2 / den
            } else {
                0.0
            }
        } else if self.a != 0.0 {
            (sq - b2) / (2.0 * self.a)
        } else {
            tau_max
        };
        r.clamp(0.0, tau_max)
    }
}

/// Where a ray from vertex `(i, j)` along `d` stops: it leaves the domain, or (wrap) it has
/// covered `max(W, H)` texels.
pub fn ray_end(s: &Surface, i: usize, j: usize, d: [f64; 2]) -> f64 {
    if s.wrap {
        return s.width.max(s.height) as f64;
    }
    let axis = |p: f64, dp: f64, n: usize| {
        if dp > 0.0 {
            ((n - 1) as f64 - p) / dp
        } else if dp < 0.0 {
            p / -dp
        } else {
            f64::INFINITY
        }
    };
    axis(i as f64, d[0], s.width).min(axis(j as f64, d[1], s.height))
}

/// The pieces of the ray from vertex `(i, j)` along unit `d`, in order of `t`.
pub fn pieces(s: &Surface, i: usize, j: usize, d: [f64; 2]) -> Vec<Piece> {
    let t_end = ray_end(s, i, j, d);
    // Integer lines are crossed at t = k/|d_x| and t = k/|d_y| (p is a vertex).
    let inv = |c: f64| if c.abs() > 1e-12 { 1.0 / c.abs() } else { f64::INFINITY };
    let (ix, iy) = (inv(d[0]), inv(d[1]));
    let (mut kx, mut ky) = (1.0f64, 1.0f64);
    let mut out = Vec::new();
    let mut ta = 0.0;
    loop {
        let (tx, ty) = (kx * ix, ky * iy);
        let tb = tx.min(ty).min(t_end);
        if tb > ta {
            out.push(cell_piece(s, i, j, d, ta, tb));
        }
        if tb >= t_end {
            break;
        }
        if tx <= tb {
            kx += 1.0;
        }
        if ty <= tb {
            ky += 1.0;
        }
        ta = tb;
    }
    out
}

/// The quadratic of the ray on `[ta, tb]`, which lies in one cell (the one holding its middle).
fn cell_piece(s: &Surface, i: usize, j: usize, d: [f64; 2], ta: f64, tb: f64) -> Piece {
    let (px, py) = (i as f64, j as f64);
    let mid = 0.5 * (ta + tb);
    let cell = |p: f64, dp: f64, n: usize| {
        let c = (p + mid * dp).floor() as i64;
        if s.wrap {
            c
        } else {
            c.clamp(0, (n as i64 - 2).max(0))
        }
    };
    let (cx, cy) = (cell(px, d[0], s.width), cell(py, d[1], s.height));
    let idx = |c: i64, n: usize| if s.wrap { c.rem_euclid(n as i64) as usize } else { (c as usize).min(n - 1) };
    let h0 = s.heights[j * s.width + i];
    let g = |x: i64, y: i64| s.heights[idx(y, s.height) * s.width + idx(x, s.width)] - h0;
    let (g00, g10, g01, g11) = (g(cx, cy), g(cx + 1, cy), g(cx, cy + 1), g(cx + 1, cy + 1));
    let (ca, cb, cc) = (g10 - g00, g01 - g00, g00 - g10 - g01 + g11);
    let u0 = (px - cx as f64) + ta * d[0];
    let v0 = (py - cy as f64) + ta * d[1];
    let a = cc * d[0] * d[1];
    let b = ca * d[0] + cb * d[1] + cc * (u0 * d[1] + v0 * d[0]);
    let c = if ta > 0.0 { g00 + ca * u0 + cb * v0 + cc * u0 * v0 } else { 0.0 };
    Piece { t0: ta, t1: tb, a, b, c }
}

/// The horizon slope `sup F(t)/t` (world height per texel) of a ray's pieces; `None` when the
/// ray leaves the domain at once.
pub fn horizon_slope(pieces: &[Piece]) -> Option<f64> {
    pieces.iter().map(|p| p.max_slope().0).reduce(f64::max)
}

/// First hits of the ascending slopes `k` along the pieces: the `t` of each, in order, ending
/// with the first slope the ray never reaches (it and all above it escape).
pub fn first_hits(pieces: &[Piece], k: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(k.len());
    let mut running = f64::NEG_INFINITY;
    for p in pieces {
        if out.len() == k.len() {
            break;
        }
        let (m, tau) = p.max_slope();
        while out.len() < k.len() && k[out.len()] <= running.max(m) {
            out.push(p.t0 + p.first_reach(k[out.len()], tau));
        }
        running = running.max(m);
    }
    out
}

/// Bilinear surface (CONVENTIONS.md) of `data` (`w × h`) at level-0 position `(x, y)`.
pub fn bilinear(data: &[f64], w: usize, h: usize, x: f64, y: f64, wrap: bool) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (tx, ty) = (x - fx, y - fy);
    let idx = |i: i64, n: usize| if wrap { i.rem_euclid(n as i64) as usize } else { i.clamp(0, n as i64 - 1) as usize };
    let (x0, x1, y0, y1) = (idx(fx as i64, w), idx(fx as i64 + 1, w), idx(fy as i64, h), idx(fy as i64 + 1, h));
    let a = data[y0 * w + x0] * (1.0 - tx) + data[y0 * w + x1] * tx;
    let b = data[y1 * w + x0] * (1.0 - tx) + data[y1 * w + x1] * tx;
    a * (1.0 - ty) + b * ty
}

/// The fixed-step march (`TruthSettings::march`): blocking slope `F(t_k)/t_k` (world height
/// per texel) and position of every sample `t_k = k·step`, in order of distance.
pub fn march(s: &Surface, i: usize, j: usize, d: [f64; 2], step: f64) -> Vec<(f64, [f64; 2])> {
    let h0 = s.heights[j * s.width + i];
    let t_max = s.width.max(s.height) as f64;
    let mut out = Vec::new();
    let mut k = 1u32;
    loop {
        let t = k as f64 * step;
        let q = [i as f64 + t * d[0], j as f64 + t * d[1]];
        if s.wrap {
            if t > t_max {
                break;
            }
        } else if q[0] < 0.0 || q[1] < 0.0 || q[0] > (s.width - 1) as f64 || q[1] > (s.height - 1) as f64 {
            break;
        }
        let f = bilinear(s.heights, s.width, s.height, q[0], q[1], s.wrap);
        out.push(((f - h0) / t, q));
        k += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surf(data: &[f64], w: usize, h: usize, wrap: bool) -> Surface<'_> {
        Surface { heights: data, width: w, height: h, wrap }
    }

    #[test]
    fn pieces_follow_the_bilinear_surface() {
        let (w, h) = (7, 5);
        let data: Vec<f64> = (0..w * h).map(|k| ((k * 37 % 11) as f64 - 5.0) * 0.3).collect();
        for wrap in [false, true] {
            let s = surf(&data, w, h, wrap);
            for (i, j, phi) in [(2, 1, 0.3f64), (0, 0, 1.1), (6, 4, 3.7), (3, 2, 5.9), (1, 3, 2.2)] {
                let d = [phi.cos(), phi.sin()];
                let ps = pieces(&s, i, j, d);
                let mut last = 0.0;
                for p in &ps {
                    assert!((p.t0 - last).abs() < 1e-12 && p.t1 > p.t0);
                    last = p.t1;
                    for f in [0.0, 0.3, 0.77, 1.0] {
                        let t = p.t0 + f * (p.t1 - p.t0);
                        let want =
                            bilinear(&data, w, h, i as f64 + t * d[0], j as f64 + t * d[1], wrap) - data[j * w + i];
                        assert!((p.value(t - p.t0) - want).abs() < 1e-12, "{wrap} {i} {j} {phi} t={t}");
                    }
                }
                assert!((last - ray_end(&s, i, j, d)).abs() < 1e-12 || ps.is_empty());
            }
        }
    }

    #[test]
    fn horizon_and_hits_match_a_fine_march() {
        let (w, h) = (9, 9);
        let data: Vec<f64> = (0..w * h).map(|k| ((k * 53 % 13) as f64 - 6.0) * 0.5).collect();
        let s = surf(&data, w, h, false);
        for phi in [0.1f64, 0.9, 2.0, 4.4] {
            let d = [phi.cos(), phi.sin()];
            let ps = pieces(&s, 4, 4, d);
            let exact = horizon_slope(&ps).unwrap();
            let fine = march(&s, 4, 4, d, 1e-4).iter().fold(f64::NEG_INFINITY, |m, v| m.max(v.0));
            assert!(exact >= fine - 1e-9 && exact - fine < 1e-2, "{exact} {fine}");
            let ks = [exact - 1.0, exact - 0.3, exact - 1e-3];
            for (t, k) in first_hits(&ps, &ks).iter().zip(ks) {
                let m = march(&s, 4, 4, d, 1e-4);
                let t_march = m.iter().position(|v| v.0 >= k).unwrap() as f64 * 1e-4 + 1e-4;
                assert!((t - t_march).abs() < 2e-4, "k={k}: exact {t}, march {t_march}");
            }
        }
    }
}
