//! Moment-matched log-ZH of a sphere blocker's cap (`gi.blocker_log_cap = "matched"`,
//! docs/blockers.md §2).
//!
//! Seed 001's log-ZH of a sphere (eq. 24–26) is `ln ε` times the cap's ZH: its exponential is
//! `ε` inside the cap only at infinite order; truncated to order n it rings, and `ε > 0` lets
//! light through (docs/blockers.md §4 measures both: no `ε` and order ≤ 8 reaches 1e-3 on one
//! sphere). The matched log-ZH instead asks for what the shading uses: the zonal function
//! `g(t) = Σ_{l<n} λ_l P̂_l(t)` (`t` the cosine to the sphere's centre, `P̂_l` the orthonormal
//! Legendre polynomials of CONVENTIONS.md) whose exponential has the **same n first Legendre
//! moments as the true visibility** `1 − cap`:
//!
//! `∫_{−1}^{1} e^{g(t)} P̂_k(t) dt = ∫_{−1}^{cos Θ} P̂_k(t) dt`,  `k = 0..n−1`.
//!
//! `e^g` is the maximum-entropy density with those moments; it exists and is unique for every
//! cap of half-angle `Θ < π/2` (the moments are interior: `1 − cap` is positive on an open
//! set), and is the minimiser of the convex `Φ(λ) = ∫ e^g − λ·μ`, found by damped Newton.
//! Exact exponentiation of one sphere's matched log-ZH then gives exactly the order-n
//! projection of its visibility — the primal path's vector — and several spheres still add in
//! log space (the product of their `e^g`).
//!
//! The solutions are tabulated per order at `u = 1 − cos Θ = i/K` ([`MATCHED_INTERVALS`] = K)
//! as `z_l(u)/u` (finite at `u = 0`: `−√(π(2l+1))`), from `u = 0` to 1 by continuation, and
//! interpolated by Catmull–Rom ([`MatchedCaps::zh`]); the GPU reads the same table in f32.

use std::f64::consts::PI;
use std::sync::OnceLock;

use super::legendre::legendre;
use super::quadrature::gauss_legendre_on;
use super::{check_order, zh};

/// Intervals of the table in `u = 1 − cos Θ` (shared with the shader).
pub const MATCHED_INTERVALS: usize = crate::constants::MATCHED_INTERVALS as usize;

/// The log-SH constant of a receiver inside a sphere with the matched log-ZH: `f_0 = −30·√4π`,
/// i.e. `e^{−30} ≈ 1e-13` everywhere (fully blocked; shared with the shader).
pub const MATCHED_INSIDE_LOG: f64 = -(crate::constants::MATCHED_BLOCKED as f64);

/// Gauss–Legendre nodes per unit of `t` for the moments of `e^g` (`g` has degree ≤ n − 1 but
/// is steep for caps near a hemisphere).
const NODES: usize = 160;

/// Table of matched log-ZH coefficients for one order (see the module docs).
pub struct MatchedCaps {
    n: usize,
    /// `(K + 1) × n`: `z_l(u_i)/u_i` at `u_i = i/K` (row `i`, band `l`).
    table: Vec<f64>,
}

/// `P̂_l(t) = √((2l+1)/2)·P_l(t)` for `l < n`.
fn phat(n: usize, t: f64) -> Vec<f64> {
    (0..n).map(|l| ((2 * l + 1) as f64 / 2.0).sqrt() * legendre(l, t)).collect()
}

/// `∫_{−1}^{x} P̂_k(t) dt` for `k < n` (closed form: `(P_{k+1} − P_{k−1})(x)/(2k+1)`, and
/// `x + 1` for `k = 0`).
fn open_moments(n: usize, x: f64) -> Vec<f64> {
    (0..n)
        .map(|k| {
            let i = if k == 0 { x + 1.0 } else { (legendre(k + 1, x) - legendre(k - 1, x)) / (2 * k + 1) as f64 };
            ((2 * k + 1) as f64 / 2.0).sqrt() * i
        })
        .collect()
}

/// Nodes `(t, w, P̂(t))` on `[−1, 1]`, split at `split` (the cap's edge, where `e^g` is
/// steepest).
fn nodes(n: usize, split: f64) -> Vec<(f64, f64, Vec<f64>)> {
    let mut out = Vec::new();
    for (a, b) in [(-1.0, split), (split, 1.0)] {
        if b - a < 1e-12 {
            continue;
        }
        let count = ((NODES as f64 * (b - a) / 2.0).ceil() as usize).max(16);
        let (x, w) = gauss_legendre_on(a, b, count);
        out.extend(x.into_iter().zip(w).map(|(t, w)| (t, w, phat(n, t))));
    }
    out
}

/// `Φ(λ)`, its gradient (moments of `e^g` minus `mu`) and Hessian at `lam`.
fn dual(lam: &[f64], mu: &[f64], pts: &[(f64, f64, Vec<f64>)]) -> (f64, Vec<f64>, Vec<f64>) {
    let n = lam.len();
    let (mut phi, mut grad, mut hess) = (0.0, vec![0.0; n], vec![0.0; n * n]);
    for (_, w, p) in pts {
        let e = w * lam.iter().zip(p).map(|(a, b)| a * b).sum::<f64>().exp();
        phi += e;
        for j in 0..n {
            grad[j] += e * p[j];
            for k in 0..=j {
                hess[j * n + k] += e * p[j] * p[k];
            }
        }
    }
    for j in 0..n {
        for k in 0..j {
            hess[k * n + j] = hess[j * n + k];
        }
    }
    phi -= lam.iter().zip(mu).map(|(a, b)| a * b).sum::<f64>();
    grad.iter_mut().zip(mu).for_each(|(g, m)| *g -= m);
    (phi, grad, hess)
}

/// Solves `H x = b` (H symmetric positive definite, `n × n`) by Cholesky.
fn cholesky_solve(n: usize, h: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for j in 0..n {
        for k in 0..=j {
            let s: f64 = h[j * n + k] - (0..k).map(|i| l[j * n + i] * l[k * n + i]).sum::<f64>();
            if j == k {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                l[j * n + j] = s.sqrt();
            } else {
                l[j * n + k] = s / l[k * n + k];
            }
        }
    }
    let mut y = b.to_vec();
    for j in 0..n {
        y[j] = (y[j] - (0..j).map(|i| l[j * n + i] * y[i]).sum::<f64>()) / l[j * n + j];
    }
    for j in (0..n).rev() {
        y[j] = (y[j] - (j + 1..n).map(|i| l[i * n + j] * y[i]).sum::<f64>()) / l[j * n + j];
    }
    Some(y)
}

/// The `λ` (orthonormal-Legendre coefficients of `g`) of the cap with `cos Θ = x`, by damped
/// Newton from `start`; `None` if it does not converge to moments within 1e-10.
pub fn solve_lambda(n: usize, x: f64, start: &[f64]) -> Option<Vec<f64>> {
    check_order(n);
    let mu = open_moments(n, x);
    let pts = nodes(n, x);
    let mut lam = start.to_vec();
    for _ in 0..200 {
        let (phi, grad, hess) = dual(&lam, &mu, &pts);
        // Φ's gradient is a sum of terms up to e^{max g} ~ 1: rounding leaves ~1e-16 per unit
        // of the largest |λ| (thousands for caps near a hemisphere at order 8).
        let tol = 1e-14 * (1.0 + lam.iter().fold(0f64, |a, b| a.max(b.abs())));
        if grad.iter().all(|g| g.abs() < tol) {
            return Some(lam);
        }
        let step = cholesky_solve(n, &hess, &grad)?;
        let slope: f64 = step.iter().zip(&grad).map(|(a, b)| a * b).sum();
        let mut alpha = 1.0;
        // Near the minimum (Newton decrement below 1e-8) the full step; there Φ's rounding
        // (its terms λ·μ reach thousands) would stall a line search.
        if slope > 1e-8 {
            loop {
                let trial: Vec<f64> = lam.iter().zip(&step).map(|(l, s)| l - alpha * s).collect();
                let (p, _, _) = dual(&trial, &mu, &pts);
                if p <= phi - 1e-4 * alpha * slope || alpha < 1e-10 {
                    break;
                }
                alpha *= 0.5;
            }
        }
        lam.iter_mut().zip(&step).for_each(|(l, s)| *l -= alpha * s);
    }
    let (_, grad, _) = dual(&lam, &mu, &pts);
    grad.iter().all(|g| g.abs() < 1e-10).then_some(lam)
}

impl MatchedCaps {
    /// The table of order `n` (solved once per process and order; see [`MatchedCaps::get`]).
    fn build(n: usize) -> Self {
        check_order(n);
        let k = MATCHED_INTERVALS;
        let mut table = vec![0.0; (k + 1) * n];
        // u = 0: the small-cap limit g ≈ −(cap's projection): λ_l/u → −P̂_l(1).
        for (l, t) in table.iter_mut().take(n).enumerate() {
            *t = -(PI * (2 * l + 1) as f64).sqrt();
        }
        let mut lam = vec![0.0; n]; // u = 0: e^g = 1
        for i in 1..=k {
            let u = i as f64 / k as f64;
            lam = solve_lambda(n, 1.0 - u, &lam)
                .unwrap_or_else(|| panic!("matched log-ZH: no convergence at order {n}, u = {u}"));
            for (t, l) in table[i * n..(i + 1) * n].iter_mut().zip(&lam) {
                *t = (2.0 * PI).sqrt() * l / u;
            }
        }
        Self { n, table }
    }

    /// The table of order `n` (1..=16), built at first use and kept for the process.
    pub fn get(n: usize) -> &'static MatchedCaps {
        static TABLES: [OnceLock<MatchedCaps>; super::MAX_ORDER] = [const { OnceLock::new() }; super::MAX_ORDER];
        check_order(n);
        TABLES[n - 1].get_or_init(|| Self::build(n))
    }

    pub fn order(&self) -> usize {
        self.n
    }

    /// The raw table, `(K + 1) × n` values `z_l(u_i)/u_i`.
    pub fn table(&self) -> &[f64] {
        &self.table
    }

    /// The matched log-ZH `z_l` (ZH coefficients about the cap's axis, `g = Σ z_l y_l^0`) of
    /// the cap with `u = 1 − cos Θ ∈ [0, 1]`: `u` times the Catmull–Rom interpolation of the
    /// table (ends extended linearly). The GPU twin is `matched_zh` in
    /// `glsl/visibility/blockers.comp.glsl`.
    pub fn zh(&self, u: f64) -> Vec<f64> {
        let k = MATCHED_INTERVALS;
        let s = (u.clamp(0.0, 1.0) * k as f64).min(k as f64);
        let i = (s.floor() as usize).min(k - 1);
        let f = s - i as f64;
        let row = |j: isize, l: usize| -> f64 {
            let t = |j: usize| self.table[j * self.n + l];
            match j {
                -1 => 2.0 * t(0) - t(1),
                j if j as usize > k => 2.0 * t(k) - t(k - 1),
                j => t(j as usize),
            }
        };
        (0..self.n)
            .map(|l| {
                let i = i as isize;
                let (p0, p1, p2, p3) = (row(i - 1, l), row(i, l), row(i + 1, l), row(i + 2, l));
                let v = p1
                    + 0.5
                        * f
                        * ((p2 - p0) + f * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + f * (3.0 * (p1 - p2) + p3 - p0)));
                u * v
            })
            .collect()
    }
}

/// The matched log-SH visibility of one sphere (centre `center_rel` relative to the receiver,
/// radius `radius`), order `n`: [`MatchedCaps::zh`] rotated toward the centre; the constant
/// [`MATCHED_INSIDE_LOG`] inside or on the sphere; `None` for a degenerate sphere.
pub fn matched_log_vis(n: usize, center_rel: [f64; 3], radius: f64) -> Option<Vec<f64>> {
    let d = center_rel.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(radius > 0.0 && radius.is_finite() && d.is_finite()) {
        return None;
    }
    if d <= radius {
        let mut v = vec![0.0; n * n];
        v[0] = MATCHED_INSIDE_LOG * (4.0 * PI).sqrt();
        return Some(v);
    }
    let s = radius / d;
    let x = ((d - radius) * (d + radius)).sqrt() / d;
    let u = s * s / (1.0 + x);
    Some(zh::rotate(n, &MatchedCaps::get(n).zh(u), center_rel))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Legendre moments of `e^g` for interpolated (off-node) caps, by an independent
    /// composite Simpson rule, against the closed-form moments of `1 − cap`.
    #[test]
    fn exponential_has_the_caps_moments() {
        for n in [2, 4, 6, 8] {
            let caps = MatchedCaps::get(n);
            let mut worst = 0f64;
            for theta_deg in [0.3, 2.0, 5.7, 14.48, 30.0, 47.3, 70.0, 85.0, 89.5] {
                let x = f64::to_radians(theta_deg).cos();
                let z = caps.zh(1.0 - x);
                let g = |t: f64| -> f64 {
                    (0..n).map(|l| z[l] * ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * legendre(l, t)).sum()
                };
                let m = 20_000;
                for k in 0..n {
                    let h = 2.0 / m as f64;
                    let f = |t: f64| g(t).exp() * legendre(k, t);
                    let mut s = f(-1.0) + f(1.0);
                    for i in 1..m {
                        s += f(-1.0 + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
                    }
                    let got = s * h / 3.0;
                    let want = open_moments(n, x)[k] / ((2 * k + 1) as f64 / 2.0).sqrt();
                    worst = worst.max((got - want).abs());
                }
            }
            eprintln!("order {n}: worst moment error {worst:.2e}");
            assert!(worst < 2e-6, "order {n}: {worst}");
        }
    }
}
