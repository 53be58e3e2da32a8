//! SH exponentiation (Ren et al. 2006, "Real-time soft shadows in dynamic scenes using
//! spherical harmonic exponentiation", SIGGRAPH 2006) in f64, and the log-SH visibility of a
//! sphere blocker.
//!
//! Visibility from a receiver is the product of the visibilities `g_i` of its blockers; in log
//! space the product becomes a sum, `g = Π g_i = exp(Σ f_i)` with `f_i = ln g_i`. A blocker
//! sphere hides a cap; its visibility `1 − cap` has no logarithm where it is 0, so it is
//! replaced by `ε` there: `g_i = ε^{cap_i}`, `f_i = ln ε · cap_i` ([`sphere_log_vis`]). The SH
//! vectors `f_i` are summed and the sum `f` is exponentiated in SH: `exp*(f)`, the order-`n`
//! projection of `exp(f(ω))` where `f(ω) = Σ_k f_k y_k(ω)` is the (truncated) expansion.
//!
//! Three ways to compute `exp*(f)`:
//! - [`exp_quadrature`]: the reference. Evaluate `f` at the nodes of a [`SphereQuadrature`],
//!   exponentiate, project back.
//! - [`exp_optimal_linear`]: the paper's optimal linear (OL) approximation with DC isolation,
//!   `exp*(f) ≈ e^{f_0/√(4π)} (a(‖f̂‖)·1 + b(‖f̂‖)·f̂)`, `a`, `b` from the tables
//!   [`OL_A`], [`OL_B`] (least-squares fits, re-derived by [`ol_fit_table`]; printed as source
//!   by `cargo run --example ol_tables`).
//! - [`exp_taylor`]: DC isolation + truncated Taylor series with SH (triple) products,
//!   `exp*(f) ≈ e^{f_0/√(4π)} Σ_{k=0..K} f̂^{*k}/k!`; and [`exp_ol_squaring`], OL on
//!   `f̂/2^s` followed by `s` SH squarings.
//!
//! The OL tables: the paper obtains `a(x)`, `b(x)` by a least-squares fit and tabulates them
//! over `x = ‖f̂‖`. Its exact training set could not be consulted when this was written, so the
//! set is ours and explicit: unit, DC-free log-visibility directions of 64 seeded random
//! configurations of 1–6 sphere blockers ([`ol_training_configs`], [`ol_training_set`]), each
//! scaled to `‖f̂‖ = x`; [`ol_fit_table`] gives the closed-form least-squares solution and the
//! test `ol_tables_are_the_least_squares_fit` re-derives [`OL_A`], [`OL_B`] from it (to 1e-12).
//! Independent of the training set: at order 2 the fit is exact (checked against the closed
//! form `a = sinh κ/κ`, `κ = x·√(3/(4π))`), and `a = 1 + x²/(8π) + O(x³)` at every order.
//!
//! Notation: `f_0` is coefficient 0 (the DC term; the mean of `f` over the sphere is
//! `f_0/√(4π)`), `f̂` is `f` with `f_0` set to 0, `1 = (√(4π), 0, …)` is the SH vector of the
//! constant function 1, `‖·‖` is the Euclidean norm of the coefficient vector (= the L2 norm of
//! the function on the sphere), `*` the order-`n` SH product ([`super::triple::product`]).
//! Orders follow `CONVENTIONS.md` ("Spherical harmonics"): `n` bands, `n²` coefficients.

use super::quadrature::gauss_legendre;
use super::triple::{self, Triple};
use super::{check_order, sh, zh};
use std::f64::consts::PI;

mod log_brdf;
mod tables;
#[cfg(test)]
mod tests;
mod training;

pub use log_brdf::{log_diffuse_zh, log_phong_zh};
pub use tables::{OL_A, OL_B};
pub use training::{ol_fit_table, ol_training_configs, ol_training_set, spheres_log_vis, TrainingSphere};
#[cfg(test)]
use training::{OlFit, SplitMix};

/// `√(4π)`: coefficient 0 of the constant function 1 (`y_0 = 1/√(4π)`).
pub const SQRT_4PI: f64 = 3.544_907_701_811_032;

/// A product quadrature over the sphere for SH exponentiation: `nz` Gauss–Legendre nodes in
/// `z = cosθ` times `nphi` uniform samples `φ_j = (j + ½)·2π/nphi`, weight `w_i·2π/nphi`. The SH
/// basis values at every node are stored, so evaluating an expansion at all nodes
/// ([`eval`](Self::eval)) and projecting node values back ([`project`](Self::project):
/// `c_k = Σ_nodes w·v·y_k`) are dot products.
///
/// The rule is exact for every polynomial of degree `≤ 2·nz − 1` in `z` times a trigonometric
/// polynomial of degree `< nphi` in `φ`. [`new`](Self::new) takes `nz = 6n + 16`,
/// `nphi = 2·nz`: exact for `f̂^k·y_j` (degree `(k+1)(n−1)`) up to `k ≈ 12n/(n−1)`
/// Taylor terms of `exp(f̂)` (`k = 13` at `n = 8`, `k = 20` at `n = 4`). `exp(f)` is not a
/// polynomial, so the projection is not exact, but it converges spectrally; measured against a
/// 160 × 320 rule, the relative L2 error of [`exp_quadrature`] for unit log-visibility
/// directions `u` scaled to `‖f̂‖ = x` (the worst of 40, [`ol_training_set`]) is:
///
/// | n | nz × nphi | x = 4   | x = 8   | x = 12  | x = 16  | x = 24  |
/// |---|-----------|---------|---------|---------|---------|---------|
/// | 4 | 40 × 80   | 2e-14   | 2e-14   | 2e-14   | 2e-14   | 7e-14   |
/// | 6 | 52 × 104  | 1e-14   | 1e-14   | 4e-14   | 3e-12   | 1e-9    |
/// | 8 | 64 × 128  | 2e-14   | 1e-13   | 5e-11   | 2e-9    | 3e-7    |
///
/// Sums of sphere caps at `ε = 0.2` stay below `‖f̂‖ ≈ 6` in all our tests (1e-14); `ε = 1e-6`
/// gives `‖f̂‖ ≈ 24–29` (≤ 1e-9). With `nz = 2n + 8` (the smallest rule one might pick) the
/// `n = 8`, `x = 4` error is 7e-5: exponentiation needs far more nodes than the product of two
/// order-`n` expansions.
#[derive(Clone, Debug)]
pub struct SphereQuadrature {
    n: usize,
    dirs: Vec<[f64; 3]>,
    weights: Vec<f64>,
    /// `basis[i·n² + k] = y_k(dirs[i])`.
    basis: Vec<f64>,
}

impl SphereQuadrature {
    /// The rule for order `n` used by [`exp_quadrature`]: `nz = 6n + 16`, `nphi = 12n + 32`
    /// (see the type's documentation for the measured accuracy).
    ///
    /// # Panics
    /// If `n ∉ 1..=16` (programmer error).
    pub fn new(n: usize) -> Self {
        Self::with_size(n, 6 * n + 16, 12 * n + 32)
    }

    /// The smaller rule of the GPU pass (`visibility.blockers`) and its f64 twin:
    /// `nz = 3n + 8`, `nphi = 2·nz` (800 nodes at `n = 4`, 2048 at `n = 8`). Measured relative
    /// L2 error of [`exp_quadrature`] with it, for unit log-visibility directions scaled to
    /// `‖f̂‖ = x` (worst of 40): `n = 4`: 1e-12 at `x = 4`, 1e-9 at `x = 8`; `n = 8`: 3e-7 at
    /// `x = 4`, 4e-5 at `x = 8` — below f32 rounding for sphere sets at `ε = 0.2`
    /// (`‖f̂‖ ≲ 3`), not for `ε → 0`.
    ///
    /// # Panics
    /// If `n ∉ 1..=16` (programmer error).
    pub fn pipeline(n: usize) -> Self {
        let nz = Self::pipeline_nz(n);
        Self::with_size(n, nz, 2 * nz)
    }

    /// Number of nodes of [`pipeline`](Self::pipeline)`(n)` without building it.
    pub fn pipeline_len(n: usize) -> usize {
        let nz = Self::pipeline_nz(n);
        nz * 2 * nz
    }

    fn pipeline_nz(n: usize) -> usize {
        3 * n + 8
    }

    /// A rule with `nz` Gauss–Legendre nodes in `z` and `nphi` uniform samples in `φ`.
    ///
    /// # Panics
    /// If `n ∉ 1..=16`, `nz == 0` or `nphi == 0` (programmer errors).
    pub fn with_size(n: usize, nz: usize, nphi: usize) -> Self {
        check_order(n);
        assert!(nz >= 1 && nphi >= 1, "SphereQuadrature: need nz, nphi ≥ 1 (got {nz}, {nphi})");
        let (zs, wz) = gauss_legendre(nz);
        let dphi = 2.0 * PI / nphi as f64;
        let mut dirs = Vec::with_capacity(nz * nphi);
        let mut weights = Vec::with_capacity(nz * nphi);
        let mut basis = Vec::with_capacity(nz * nphi * n * n);
        for (&z, &w) in zs.iter().zip(&wz) {
            let st = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) * dphi;
                let d = [st * phi.cos(), st * phi.sin(), z];
                dirs.push(d);
                weights.push(w * dphi);
                basis.extend(sh::eval(n, d));
            }
        }
        Self { n, dirs, weights, basis }
    }

    /// The SH order `n`.
    pub fn order(&self) -> usize {
        self.n
    }

    /// Number of nodes (`nz·nphi`).
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Always false (a rule has at least one node); here for `len`'s sake.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// The unit directions of the nodes.
    pub fn dirs(&self) -> &[[f64; 3]] {
        &self.dirs
    }

    /// The weights (they sum to `4π`).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The `n²` SH basis values `y_k` at node `i`.
    pub fn basis(&self, i: usize) -> &[f64] {
        let nn = self.n * self.n;
        &self.basis[i * nn..(i + 1) * nn]
    }

    /// `f(ω_i) = Σ_k c_k y_k(ω_i)` at every node.
    ///
    /// # Panics
    /// If `c.len() < n²` (programmer error).
    pub fn eval(&self, c: &[f64]) -> Vec<f64> {
        let nn = self.n * self.n;
        assert!(c.len() >= nn, "SphereQuadrature::eval: need {nn} coefficients, got {}", c.len());
        self.basis.chunks_exact(nn).map(|y| y.iter().zip(c).map(|(y, c)| y * c).sum()).collect()
    }

    /// The order-`n` projection `c_k = Σ_i w_i v_i y_k(ω_i)` of the node values `v`.
    ///
    /// # Panics
    /// If `values.len() != self.len()` (programmer error).
    pub fn project(&self, values: &[f64]) -> Vec<f64> {
        let nn = self.n * self.n;
        assert_eq!(values.len(), self.len(), "SphereQuadrature::project: one value per node");
        let mut out = vec![0.0; nn];
        for ((y, &v), &w) in self.basis.chunks_exact(nn).zip(values).zip(&self.weights) {
            let wv = w * v;
            for (o, y) in out.iter_mut().zip(y) {
                *o += wv * y;
            }
        }
        out
    }
}

/// The reference SH exponentiation: `exp*(f)_k = ∫ exp(f(ω)) y_k(ω) dω` with
/// `f(ω) = Σ_j f_j y_j(ω)`, by the quadrature `q` (order `q.order()`; `f` has `n²` coefficients,
/// extra ones are ignored). Accuracy: see [`SphereQuadrature`].
///
/// # Panics
/// If `f.len() < n²` (programmer error).
pub fn exp_quadrature(q: &SphereQuadrature, f: &[f64]) -> Vec<f64> {
    let v: Vec<f64> = q.eval(f).into_iter().map(f64::exp).collect();
    q.project(&v)
}

/// Splits `f` (first `n²` coefficients) into the DC factor `e^{f_0/√(4π)}` and `f̂`.
fn dc_isolate(n: usize, f: &[f64]) -> (f64, Vec<f64>) {
    let nn = n * n;
    assert!(f.len() >= nn, "SH exponentiation: need {nn} coefficients, got {}", f.len());
    let mut fh = f[..nn].to_vec();
    fh[0] = 0.0;
    ((f[0] / SQRT_4PI).exp(), fh)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Largest order with an OL table.
pub const OL_MAX_ORDER: usize = 8;
/// Spacing of the OL tables in `x = ‖f̂‖`.
pub const OL_STEP: f64 = 0.5;
/// Entries per order in the OL tables: `x = 0, 0.5, …, 24`.
pub const OL_POINTS: usize = 49;
const _: () = assert!(OL_POINTS == crate::constants::OL_POINTS as usize);
/// Number of training configurations behind the OL tables ([`ol_training_configs`]).
pub const OL_TRAINING: usize = 64;

/// Ren et al.'s optimal linear (OL) SH exponentiation with DC isolation:
///
/// `exp*(f) ≈ e^{f_0/√(4π)} · (a(‖f̂‖)·1 + b(‖f̂‖)·f̂)`.
///
/// DC isolation is exact (`exp(f) = e^{f_0/√(4π)}·exp(f̂)`: the DC term is a constant
/// function); only `exp*(f̂)` is approximated, by the best combination of `1` and `f̂` in the
/// least-squares sense, with `a(x)`, `b(x)` read from [`OL_A`], [`OL_B`] by [`ol_coefficients`].
/// The approximation is exact for `n ≤ 2` (`exp*` of a band-1 function lies in
/// `span{1, f̂}` by symmetry; up to the table interpolation, 2e-5) and to first order in `f̂` (`a = 1 + x²/(8π) + O(x³)`,
/// `b → 1`). Its error grows with `‖f̂‖`. Relative L2 errors against [`exp_quadrature`] at
/// `ε = 0.2` (test `approximations_against_exp_quadrature`): 0.2–8 % for one sphere, 1–18 %
/// for 2–8 spheres (`‖f̂‖` up to 2.6; order 8 is worse than order 4); on fresh random
/// configurations of 1–6 spheres the mean is 8–9 % and the worst 30–35 % at `‖f̂‖ ≈ 6`. Part
/// of it is intrinsic (`exp*(f̂)` has components outside `span{1, f̂}`): the best `a, b` for
/// each configuration reach 10–100 % of the tabulated ones' error. [`exp_taylor`] (≤ 3 %) and
/// [`exp_ol_squaring`] (≤ 3 %) are more accurate at the price of SH products.
///
/// # Panics
/// If `n ∉ 1..=OL_MAX_ORDER` or `f.len() < n²` (programmer errors).
pub fn exp_optimal_linear(n: usize, f: &[f64]) -> Vec<f64> {
    assert!((1..=OL_MAX_ORDER).contains(&n), "exp_optimal_linear: order {n} outside 1..={OL_MAX_ORDER}");
    let (e0, fh) = dc_isolate(n, f);
    let (a, b) = ol_coefficients(n, norm(&fh));
    ol_apply(e0, &fh, a, b)
}

/// `e0·(a·1 + b·f̂)`.
fn ol_apply(e0: f64, fh: &[f64], a: f64, b: f64) -> Vec<f64> {
    let mut out: Vec<f64> = fh.iter().map(|x| e0 * b * x).collect();
    out[0] = e0 * a * SQRT_4PI;
    out
}

/// `(a(x), b(x))` of the OL approximation for order `n` at `x = ‖f̂‖ ≥ 0`, from [`OL_A`] and
/// [`OL_B`]: Catmull–Rom cubic interpolation of `ln a` and `ln b` (both are positive: `a ≥ 1`
/// by Jensen, `b > 0` because `d/dx ∫exp(x u) = ⟨exp(x u), u⟩` grows from 0 at `x = 0`) on
/// the grid `x = i·OL_STEP` (the first interval by the Lagrange cubic through entries 0..=3;
/// measured relative error against the fit itself ≤ 7e-5); beyond the last entry (`x > 24`)
/// `ln a`, `ln b` are extrapolated linearly from the last two entries. Order 1 has no `f̂`: `(1, 1)`.
///
/// # Panics
/// If `n ∉ 1..=OL_MAX_ORDER` (programmer error).
pub fn ol_coefficients(n: usize, x: f64) -> (f64, f64) {
    assert!((1..=OL_MAX_ORDER).contains(&n), "ol_coefficients: order {n} outside 1..={OL_MAX_ORDER}");
    if n == 1 {
        return (1.0, 1.0);
    }
    let (ta, tb) = (&OL_A[n - 2], &OL_B[n - 2]);
    (interp_log(ta, x), interp_log(tb, x))
}

/// Interpolation of `ln t` at `s = x/OL_STEP`: Catmull–Rom, except the Lagrange cubic through
/// entries 0..=3 on the first interval and, on the last, the point past the end extrapolated
/// quadratically (`p_N = 3p_{N−1} − 3p_{N−2} + p_{N−3}`); linear extrapolation of `ln t` past
/// the end.
fn interp_log(t: &[f64; OL_POINTS], x: f64) -> f64 {
    let s = x.max(0.0) / OL_STEP;
    let last = OL_POINTS - 1;
    let l = |i: usize| t[i].ln();
    if s >= last as f64 {
        let slope = l(last) - l(last - 1);
        return (l(last) + slope * (s - last as f64)).exp();
    }
    let i = s.floor() as usize;
    let u = s - i as f64;
    if i == 0 {
        // Lagrange cubic through grid points 0..=3.
        let (p0, p1, p2, p3) = (l(0), l(1), l(2), l(3));
        let v = -p0 * (u - 1.0) * (u - 2.0) * (u - 3.0) / 6.0 + p1 * u * (u - 2.0) * (u - 3.0) / 2.0
            - p2 * u * (u - 1.0) * (u - 3.0) / 2.0
            + p3 * u * (u - 1.0) * (u - 2.0) / 6.0;
        return v.exp();
    }
    let (p0, p1, p2) = (l(i - 1), l(i), l(i + 1));
    let p3 = if i + 2 > last { 3.0 * l(last) - 3.0 * l(last - 1) + l(last - 2) } else { l(i + 2) };
    let v = p1 + 0.5 * u * ((p2 - p0) + u * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + u * (3.0 * (p1 - p2) + p3 - p0)));
    v.exp()
}

/// DC isolation + truncated Taylor series with SH products (product projection):
///
/// `exp*(f) ≈ e^{f_0/√(4π)} · Σ_{k=0..degree} f̂^{*k}/k!`,  `f̂^{*0} = 1`, `f̂^{*k} = f̂^{*(k−1)} * f̂`,
///
/// every product projected back to order `n` (so even `degree → ∞` is not `exp*(f)`: the
/// truncation after each product leaves 0.01–3 % relative L2 error at `ε = 0.2`; see the tests).
/// With the order-n triple-product tensor `triple::triple(n)`; [`exp_taylor_with`] takes any one.
///
/// # Panics
/// If `n ∉ 1..=16` or `f.len() < n²` (programmer errors).
pub fn exp_taylor(n: usize, f: &[f64], degree: usize) -> Vec<f64> {
    exp_taylor_with(triple::triple(n), f, degree)
}

/// [`exp_taylor`] with a prebuilt tensor `t` (order `t.n`).
///
/// # Panics
/// If `f.len() < n²` (programmer error).
pub fn exp_taylor_with(t: &Triple, f: &[f64], degree: usize) -> Vec<f64> {
    let (e0, fh) = dc_isolate(t.n, f);
    let mut term = vec![0.0; t.n * t.n];
    term[0] = SQRT_4PI;
    let mut sum = term.clone();
    for k in 1..=degree {
        term = triple::product(t, &term, &fh);
        let inv = 1.0 / k as f64;
        for (s, x) in sum.iter_mut().zip(term.iter_mut()) {
            *x *= inv;
            *s += *x;
        }
    }
    sum.iter().map(|s| s * e0).collect()
}

/// OL with scaling and squaring (our variant, not one of the paper's named methods):
/// `exp*(f) ≈ e^{f_0/√(4π)} · (OL(f̂/2^s))^{*2^s}`, i.e. [`exp_optimal_linear`] on `f̂/2^s`
/// (where OL is accurate: small norm) followed by `s` SH self-products. Each squaring adds a
/// projection error, so `s ≈ 3–4` is best. With `s = 3`: 0.02–2.7 % at `ε = 0.2` in the tests
/// (OL: 0.2–18 %, [`exp_taylor`] of degree 8: 0.01–3 %) for 3 SH products instead of 8.
///
/// # Panics
/// If `t.n ∉ 1..=OL_MAX_ORDER` or `f.len() < n²` (programmer errors).
pub fn exp_ol_squaring(t: &Triple, f: &[f64], squarings: u32) -> Vec<f64> {
    let n = t.n;
    assert!((1..=OL_MAX_ORDER).contains(&n), "exp_ol_squaring: order {n} outside 1..={OL_MAX_ORDER}");
    let (e0, fh) = dc_isolate(n, f);
    let scale = 0.5f64.powi(squarings as i32);
    let fs: Vec<f64> = fh.iter().map(|v| v * scale).collect();
    let (a, b) = ol_coefficients(n, norm(&fs));
    let mut g = ol_apply(1.0, &fs, a, b);
    for _ in 0..squarings {
        g = triple::product(t, &g, &g);
    }
    g.iter().map(|v| v * e0).collect()
}

/// Log-SH visibility of one sphere blocker (centre `center_rel` relative to the receiver at
/// the origin, radius `radius`): `ln ε` times the indicator of the cap it hides, the cap of
/// half-angle `α = asin(r/d)` about `c/d` (`d = ‖c‖`):
///
/// `f = s · ln ε · rotate(cap_ZH(α), c/d)`,  `s = r/d` with `ratio_attenuation`, else 1,
///
/// by [`zh::cap`] and [`zh::rotate`]. `exp(f)` is then `ε^s` inside the cap and 1 outside
/// (up to SH truncation): the blocker lets a fraction `ε^s` through; ratio attenuation makes
/// small / distant blockers (small `r/d`) more transparent. `log_eps = ln ε` should be `< 0`.
///
/// A receiver inside or on the blocker (`d ≤ r`) is fully blocked: the result is the constant
/// function `ln ε` (coefficient 0 `= ln ε·√(4π)`, no ratio attenuation). `None` when there is
/// no blocker to speak of: `radius ≤ 0`, or a non-finite input. Culling blockers behind the
/// receiver's tangent plane is the caller's business ([`sphere_culled`]).
///
/// # Panics
/// If `n ∉ 1..=16` (programmer error).
pub fn sphere_log_vis(
    n: usize,
    center_rel: [f64; 3],
    radius: f64,
    log_eps: f64,
    ratio_attenuation: bool,
) -> Option<Vec<f64>> {
    check_order(n);
    let d = norm(&center_rel);
    if !(radius > 0.0 && radius.is_finite() && d.is_finite() && log_eps.is_finite()) {
        return None;
    }
    if d <= radius {
        let mut v = vec![0.0; n * n];
        v[0] = log_eps * SQRT_4PI;
        return Some(v);
    }
    let s = radius / d;
    let scale = if ratio_attenuation { log_eps * s } else { log_eps };
    let cap: Vec<f64> = zh::cap(n, s.asin()).into_iter().map(|z| z * scale).collect();
    Some(zh::rotate(n, &cap, center_rel))
}

/// True when the whole sphere (centre `center_rel` relative to the receiver, radius `radius`)
/// lies strictly below the tangent plane through the receiver with normal `normal` (normalised
/// internally): `n̂·c < −r`. Such a blocker hides nothing of the upper hemisphere. A zero or
/// non-finite normal culls nothing.
pub fn sphere_culled(normal: [f64; 3], center_rel: [f64; 3], radius: f64) -> bool {
    let len = norm(&normal);
    if !(len > 0.0 && len.is_finite()) {
        return false;
    }
    let dot = (normal[0] * center_rel[0] + normal[1] * center_rel[1] + normal[2] * center_rel[2]) / len;
    dot < -radius
}
