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

/// `√(4π)`: coefficient 0 of the constant function 1 (`y_0 = 1/√(4π)`).
/// `√(4π)`: the DC coefficient of the constant function 1.
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

/// splitmix64: a tiny deterministic generator for the OL training set and the tests.
struct SplitMix(u64);

impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform on the unit sphere.
    fn dir(&mut self) -> [f64; 3] {
        let z = 2.0 * self.uniform() - 1.0;
        let phi = 2.0 * PI * self.uniform();
        let s = (1.0 - z * z).max(0.0).sqrt();
        [s * phi.cos(), s * phi.sin(), z]
    }
}

/// One blocker of a training configuration: centre relative to the receiver, radius, and
/// whether [`sphere_log_vis`] applies ratio attenuation.
#[derive(Clone, Copy, Debug)]
pub struct TrainingSphere {
    pub center: [f64; 3],
    pub radius: f64,
    pub ratio_attenuation: bool,
}

/// The blocker configurations behind the OL tables (order independent; `count` of them from a
/// fixed splitmix64 seed; the first [`OL_TRAINING`] are the training set, later ones are
/// fresh). Configuration `i`: a receiver normal uniform on the sphere; `k ∈ 1..=6` spheres
/// (uniform) with centres at unit distance, directions uniform in the hemisphere about the
/// normal, radius `r = r/d` uniform in `[0.1, 0.9]`; ratio attenuation on odd `i`.
pub fn ol_training_configs(count: usize) -> Vec<Vec<TrainingSphere>> {
    let mut rng = SplitMix(0x5EED_0E4B_2006);
    (0..count)
        .map(|i| {
            let axis = rng.dir();
            let k = 1 + (rng.next_u64() % 6) as usize;
            (0..k)
                .map(|_| {
                    let mut d = rng.dir();
                    let dot = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
                    if dot < 0.0 {
                        d = [0, 1, 2].map(|j| d[j] - 2.0 * dot * axis[j]);
                    }
                    let radius = 0.1 + 0.8 * rng.uniform();
                    TrainingSphere { center: d, radius, ratio_attenuation: i % 2 == 1 }
                })
                .collect()
        })
        .collect()
}

/// Summed log-SH visibility `Σ_i sphere_log_vis(n, c_i, r_i, log_eps, ratio_i)` of a set of
/// blockers seen from the origin (blockers that give `None` add nothing).
pub fn spheres_log_vis(n: usize, spheres: &[TrainingSphere], log_eps: f64) -> Vec<f64> {
    let mut f = vec![0.0; n * n];
    for s in spheres {
        if let Some(v) = sphere_log_vis(n, s.center, s.radius, log_eps, s.ratio_attenuation) {
            for (a, b) in f.iter_mut().zip(v) {
                *a += b;
            }
        }
    }
    f
}

/// The OL training directions for order `n`: for each of the first [`OL_TRAINING`]
/// configurations of [`ol_training_configs`], the summed log-visibility (any `ln ε < 0`: the
/// direction does not depend on it), DC removed, normalised to `‖u‖ = 1`.
pub fn ol_training_set(n: usize) -> Vec<Vec<f64>> {
    ol_training_configs(OL_TRAINING)
        .iter()
        .map(|cfg| {
            let (_, u) = dc_isolate(n, &spheres_log_vis(n, cfg, -1.0));
            let s = norm(&u);
            u.iter().map(|v| v / s).collect()
        })
        .collect()
}

/// Re-derives the OL tables of order `n` (`2 ≤ n ≤ 16`): `(a(x_i), b(x_i))` at
/// `x_i = i·OL_STEP`, `i < OL_POINTS`.
///
/// For each `x`, `a` and `b` minimise the summed squared error over the training directions
/// `u` of [`ol_training_set`] scaled to `‖f̂‖ = x`:
///
/// `min_{a,b} Σ_u ‖exp*(x u) − a·1 − b·x u‖²`.
///
/// `⟨1, u⟩ = 0`, `‖1‖² = 4π` and `‖x u‖² = x²`, so the normal equations decouple:
///
/// `a(x) = (1/M) Σ_u exp*(x u)_0 / √(4π)`,  `b(x) = (1/(M x)) Σ_u ⟨exp*(x u), u⟩`,  `b(0) = 1`,
///
/// with `M` = [`OL_TRAINING`] and `exp*` by [`exp_quadrature`] with [`SphereQuadrature::new`].
///
/// # Panics
/// If `n ∉ 2..=16` (programmer error).
pub fn ol_fit_table(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 2, "ol_fit_table: order 1 has no f̂");
    let fit = OlFit::new(n);
    (0..OL_POINTS).map(|i| fit.at(i as f64 * OL_STEP)).unzip()
}

/// The least-squares OL fit of [`ol_fit_table`] at any `x` (the training directions evaluated
/// at the quadrature nodes once).
struct OlFit {
    q: SphereQuadrature,
    dirs: Vec<Vec<f64>>,
    at_nodes: Vec<Vec<f64>>,
}

impl OlFit {
    fn new(n: usize) -> Self {
        let q = SphereQuadrature::new(n);
        let dirs = ol_training_set(n);
        let at_nodes = dirs.iter().map(|u| q.eval(u)).collect();
        Self { q, dirs, at_nodes }
    }

    fn at(&self, x: f64) -> (f64, f64) {
        let (mut sa, mut sb) = (0.0, 0.0);
        for (u_nodes, u) in self.at_nodes.iter().zip(&self.dirs) {
            let v: Vec<f64> = u_nodes.iter().map(|u| (x * u).exp()).collect();
            let e = self.q.project(&v);
            sa += e[0] / SQRT_4PI;
            sb += e.iter().zip(u).map(|(e, u)| e * u).sum::<f64>();
        }
        let m = self.dirs.len() as f64;
        (sa / m, if x == 0.0 { 1.0 } else { sb / (m * x) })
    }
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

/// `a(x)` of the OL approximation for orders 2..=8 (`OL_A[n − 2][i] = a(i·OL_STEP)`), as
/// produced by [`ol_fit_table`].
#[rustfmt::skip]
pub const OL_A: [[f64; OL_POINTS]; OL_MAX_ORDER - 1] = [
    // n = 2
    [
        1.0000000000000084, 1.0099769101004077, 1.0402663874181883, 1.0919600356353552,
        1.166929119471657, 1.2679049953761854, 1.3985969284669606, 1.5638528157769285,
        1.7698703676989027, 2.024468703803593, 2.337433215648818, 2.7209500826308712,
        3.1901511747403544, 3.763795457380639, 4.46511970034634, 5.322899624974514,
        6.372773024523789, 7.658889394089886, 9.235966873588843, 11.171857675826434,
        13.550748690072632, 16.477155937010952, 20.080911658419183, 24.523393134641623,
        30.00530545015175, 36.77640966125177, 45.14768729729244, 55.50655705273344,
        68.33591645187109, 84.23797843518423, 103.96412060426753, 128.45227633863215,
        158.87378861847472, 196.6921398803419, 243.73659070923134, 302.29453953122703,
        375.22739617527117, 466.115996476277, 579.4431388656295, 720.8227801868632,
        897.287891502187, 1117.652077482439, 1392.9639716700603, 1737.0783445972024,
        2167.3740675329273, 2705.6568960358745, 3379.294896646655, 4222.646769771638,
        5278.85899464048,
    ],
    // n = 3
    [
        1.0000000000000004, 1.0095983540854203, 1.037322246745801, 1.082212205778419,
        1.144060655146875, 1.2233184287200194, 1.3210463404794246, 1.4389042933718925,
        1.5791736613718328, 1.7448113310127173, 1.9395360994450754, 2.167950306853113,
        2.435701815851559, 2.7496939145226795, 3.1183535954008645, 3.5519721549040413,
        4.063136410387152, 4.667274346950058, 5.383346065880055, 6.2347200030703265,
        7.250286157086623, 8.465873344971167, 9.926057378223945, 11.686472949375606,
        13.81677581596747, 16.40444602834286, 19.559680713783912, 23.421700573470133,
        28.166893399393523, 34.01934799858172, 41.26450271608596, 50.266857206932045,
        61.49299130119887, 75.54152330921448, 93.1821517731457, 115.40659897060861,
        143.4951636688686, 179.10376389737118, 224.3778994851842, 282.1020102153244,
        355.8954096204457, 450.46955009006655, 571.966105150677, 728.4016151211101,
        930.2527313791253, 1191.227074122469, 1529.2792678690907, 1967.9510058845733,
        2538.1395711659566,
    ],
    // n = 4
    [
        1.000000000000014, 1.0093936984539793, 1.0358033699411686, 1.0773960408340286,
        1.1332038959080848, 1.2029168579435245, 1.2867488595624823, 1.3853551370011303,
        1.4997857709918108, 1.631465918540764, 1.782196674732833, 1.954172889386531,
        2.1500159373075873, 2.372820663739814, 2.6262166717704867, 2.9144449038651756,
        3.242451178464438, 3.6159990362990646, 4.041804978883687, 4.527699986262958,
        5.082822123288847, 5.717846125750947, 6.445257146186482, 7.279677387878178,
        8.238256228010645, 9.34113670376996, 10.612014001442613, 12.078804962185803,
        13.77445173892836, 15.737887778906149, 18.015200477776187, 20.66103241592024,
        23.74027236891859, 27.330098682210764, 31.522451609549478, 36.42702844875028,
        42.174916525583754, 48.923005218523144, 56.85935045068473, 66.20970484923487,
        77.24547588536166, 90.29343499395722, 105.74757570840333, 124.08361168537071,
        145.87672043303223, 171.82328093989193, 202.76752988733654, 239.73428000893117,
        283.96911576624007,
    ],
    // n = 5
    [
        0.999999999999993, 1.0093058883847512, 1.0351848267199613, 1.0755243251662934,
        1.1291585767939782, 1.1956001928158912, 1.2748729540311667, 1.3674090503232113,
        1.4739886281908139, 1.5957080743463934, 1.7339687111693807, 1.8904808403808073,
        2.067280145715886, 2.266754826651191, 2.4916827667251384, 2.7452787143024824,
        3.0312519782712566, 3.353875585071802, 3.718068252749943, 4.129490945099114,
        4.594660199484294, 5.121080896731996, 5.717401680082781, 6.393596852347105,
        7.161179307259317, 8.03344990635206, 9.025789723888469, 10.15600278165231,
        11.444718320823897, 12.915863355219216, 14.59721827326066, 16.521070670501455,
        18.724985478876278, 21.252712907655024, 24.15525983828851, 27.49215525841752,
        31.332946245213414, 35.75896811540636, 40.86544089119572, 46.763954480917505,
        53.58541729576661, 61.48355784893033, 70.63908673219643, 81.26464786934027,
        93.6107138721119, 107.9726116044379, 124.69890182455671, 144.2013823981139,
        166.96703972997457,
    ],
    // n = 6
    [
        0.9999999999999999, 1.00925317395061, 1.0348252438995333, 1.0744628254765813,
        1.1269069498809032, 1.1915842960717324, 1.2684217193144038, 1.3577344902418154,
        1.460160247192865, 1.576622506844071, 1.7083142428358695, 1.8566959002387395,
        2.023504518472575, 2.2107720626037928, 2.4208519856245396, 2.656453673163905,
        2.9206848796257034, 3.2171026245375067, 3.5497733258221715, 3.923343232844912,
        4.343120507456345, 4.815170601736547, 5.346426909921403, 5.944819041045656,
        6.6194214799984605, 7.380625890397624, 8.240340876616287, 9.212223679892194,
        10.311949052496882, 11.55752145512971, 12.969637780263811, 14.572109046613548,
        16.392350970835786, 18.461955041741245, 20.817353746668974, 23.500595984902258,
        26.560251515008936, 30.052466599936775, 34.04219692831271, 38.604648512737064,
        43.82696272660287, 49.810188095340514, 56.67158909045727, 64.54735120464046,
        73.59575227436474, 84.00088267326302, 95.97701199441848, 109.7737176126015,
        125.68191159231519,
    ],
    // n = 7
    [
        1.0000000000000298, 1.009217688459594, 1.0345898174008836, 1.0737811294915627,
        1.1254795984671415, 1.189060035732356, 1.264388649556841, 1.351707226911454,
        1.451564641962369, 1.5647780180127413, 1.6924135313510198, 1.8357810332332174,
        1.9964390588192424, 2.1762082233793607, 2.377191905551668, 2.601803713967248,
        2.852801654394716, 3.1333292333137885, 3.4469639950294217, 3.7977742213596217,
        4.190384744592139, 4.630053049518045, 5.122757079628714, 5.675296425152605,
        6.295408865007868, 6.991904569450565, 7.774820654179269, 8.655599219769107,
        9.647292523652647, 10.764799528148833, 12.025138761966714, 13.447763241287836,
        15.054924139965525, 16.8720910000164, 18.92843756095502, 21.257403792016014,
        23.897346473039764, 26.89229273268226, 30.292813369609622, 34.15703561595631,
        38.55181832635844, 43.554116477523614, 49.25256644567061, 55.74932891423417,
        63.16223259638922, 71.62726940724062, 81.30150049169254, 92.36644284651015,
        105.03201845427158,
    ],
    // n = 8
    [
        0.9999999999999575, 1.0091996380226298, 1.0344809630914225, 1.0734907290847386,
        1.1249122219009997, 1.1881131390025845, 1.2629472810071167, 1.3496389311313761,
        1.4487148912749, 1.5609658829913644, 1.687427251500625, 1.8293732115334849,
        1.9883212618846198, 2.166044802055295, 2.364592861832424, 2.5863164351997376,
        2.833901319258583, 3.110407668534887, 3.4193167282379706, 3.7645854340164195,
        4.150709778876975, 4.582798063398821, 5.06665537346442, 5.608880879151753,
        6.216979827221223, 6.899492415739424, 7.6661421011518796, 8.52800630464119,
        9.497712966070788, 10.589666951815344, 11.820310970667133, 13.20842640525274,
        14.775480342995793, 16.54602611162137, 18.548165814063143, 20.814084745133588,
        23.38066919109721, 26.290221002789863, 29.591284539403823, 33.33960415777855,
        37.59923343469938, 42.44382083210685, 47.958100635117, 54.23962281358366,
        61.40076110094445, 69.57104519195987, 78.89987070149381, 89.55964959712486,
        101.74947445148369,
    ],
];

/// `b(x)` of the OL approximation for orders 2..=8 (`OL_B[n − 2][i] = b(i·OL_STEP)`), as
/// produced by [`ol_fit_table`].
#[rustfmt::skip]
pub const OL_B: [[f64; OL_POINTS]; OL_MAX_ORDER - 1] = [
    // n = 2
    [
        1.0, 1.0059810461248353, 1.0240776908056297, 1.0547555630548116,
        1.0988079397857613, 1.1573822789412154, 1.2320187759303687, 1.324702423535992,
        1.4379305819615094, 1.5747986761220951, 1.7391073575579408, 1.9354953292474308,
        2.1696030701630096, 2.448273957611195, 2.7798008241677152, 3.1742278697700623,
        3.6437201612348935, 4.203015793473016, 4.869979285426442, 5.666279095652235,
        6.618217461156204, 7.757747328428624, 9.123719255034048, 10.763411182398334,
        12.734406373286916, 15.106900139013149, 17.966534957175543, 21.41788707715294,
        25.588756816857263, 30.635450824320664, 36.74928929524271, 44.164626596958215,
        53.16874255630049, 64.11404706693385, 77.43314669895506, 93.65745367870304,
        113.44018121410437, 137.58477247611293, 167.08006333848328, 203.14379335480152,
        247.2764705378106, 301.3280821665783, 367.5807496184073, 448.8511794763618,
        548.6177025623424, 671.1778628632533, 821.8439767157955, 1007.1859004929368,
        1235.3325115947634,
    ],
    // n = 3
    [
        1.0, 0.9495209236581116, 0.9148372725866347, 0.8938314370696424,
        0.8850016425739031, 0.8873499127629693, 0.9003031229374568, 0.9236603136652438,
        0.9575615293394042, 1.002475083498324, 1.0592014785912025, 1.1288933362813722,
        1.2130917173310178, 1.3137802062802233, 1.4334591778116874, 1.5752438207742803,
        1.7429908494345487, 1.941460467684198, 2.1765221759374356, 2.455415552185246,
        2.7870803615847586, 3.1825744613158684, 3.65560323664062, 4.2231910751407655,
        4.906534105432555, 5.732084673207043, 6.732932553087105, 7.950566677073317,
        9.43712547139268, 11.25827539013309, 13.496898075366945, 16.25781957541794,
        19.673883889956944, 23.91376258027961, 29.19200855280638, 35.782013585401195,
        44.03272643224565, 54.3902454299596, 67.42573478267764, 83.87155115454733,
        104.66803832561479, 131.02419373560505, 164.49638586070657, 207.0905765275642,
        261.39517062853173, 330.7537995761636, 419.4902048700282, 533.2011354181395,
        679.1380841855251,
    ],
    // n = 4
    [
        1.0, 0.9194983042530964, 0.8601969942523465, 0.8176730454091484,
        0.7887275215484172, 0.7710522126262662, 0.7629963426045191, 0.7634027363888176,
        0.771492639436137, 0.7867849821973468, 0.8090403512045977, 0.8382229783463129,
        0.8744761586535693, 0.9181079666108818, 0.9695851702531141, 1.0295339817187932,
        1.0987468280912343, 1.1781947430387818, 1.2690453139661901, 1.3726864040710702,
        1.490756128317861, 1.6251798159574395, 1.7782149556776674, 1.9525054069779535,
        2.151146486698056, 2.377762917129238, 2.63660206754924, 2.932645452369658,
        3.271742087522624, 3.6607680775082225, 4.107817739165387, 4.622432701755806,
        5.215876801545836, 5.901466268002049, 6.694966745708384, 7.615071194271136,
        8.683975759878372, 9.928074442303584, 11.378797944346617, 13.073627676982941,
        15.057322736836108, 17.383406061322635, 20.115966256396607, 23.331844220660265,
        27.123289198701162, 31.60118795373869, 36.89899417987128, 43.17751409659105,
        50.63073964257188,
    ],
    // n = 5
    [
        1.0, 0.9068602892911614, 0.8387127075178491, 0.7894648127116034,
        0.7548903551555838, 0.7320322232969604, 0.718812641551002, 0.7137755075044726,
        0.7159141506952529, 0.7245551249422983, 0.7392793367162387, 0.7598684815981179,
        0.7862689716106045, 0.8185682284231833, 0.8569799624460505, 0.9018362062056309,
        0.9535846395158704, 1.0127902701349454, 1.0801409033594367, 1.156456103060172,
        1.2426995514616852, 1.3399948798726482, 1.4496451843238662, 1.573156570601274,
        1.7122662014323797, 1.8689754517709496, 2.045588922427989, 2.2447602235184236,
        2.469545623162165, 2.723466869802533, 3.0105847452755614, 3.335585198253204,
        3.703880253052334, 4.121726297836948, 4.5963628417392925, 5.1361754076413195,
        5.7508869145325, 6.451782722356223, 7.251975489316882, 8.166717158282246,
        9.21376678312044, 10.413824573236525, 11.79104453025708, 13.37364044110825,
        15.194602856699948, 17.292548121707863, 19.712724645271177, 22.5082065558809,
        25.741310836935668,
    ],
    // n = 6
    [
        1.0, 0.8993695573041778, 0.8264780162869314, 0.7738499211796303,
        0.7365138533560581, 0.7110996578497164, 0.6952894517534495, 0.6874762403173927,
        0.6865470554454112, 0.6917424899557718, 0.7025642016301374, 0.7187132633535397,
        0.7400488424818353, 0.7665606307089359, 0.7983508409384849, 0.8356230751807767,
        0.878676311605799, 0.9279028721471543, 0.9837896407170982, 1.0469220825456294,
        1.1179908145216015, 1.1978006243786652, 1.287281952277648, 1.3875049444779968,
        1.4996962740628286, 1.625259004311006, 1.765795851002177, 1.9231362844989324,
        2.0993680041809473, 2.29687341980608, 2.5183718897392855, 2.7669685979842638,
        3.046211104145668, 3.360154776853477, 3.7134385263827316, 4.111372491504288,
        4.560039615181648, 5.066413370811362, 5.638494283771894, 6.2854683420732425,
        7.017890916638275, 7.847900430052225, 8.789466738841796, 9.85868004780239,
        11.074087178401106, 12.4570831938247, 14.032367772728643, 15.828477359938843,
        17.87840604996921,
    ],
    // n = 7
    [
        1.0, 0.8943855170661196, 0.8186047953494415, 0.7640025807562535,
        0.7250521504156691, 0.6981133353894043, 0.6807287561072454, 0.6712111342066941,
        0.6683931604388709, 0.6714711935968299, 0.6799049529507464, 0.693351743365302,
        0.7116226768969915, 0.7346533582857262, 0.7624843892230243, 0.7952487614976426,
        0.8331642577334821, 0.8765296381409361, 0.9257238189378418, 0.9812075332773582,
        1.0435271622709785, 1.1133205646512034, 1.1913248391738778, 1.278386037117784,
        1.3754709118800532, 1.4836808546518439, 1.6042682237662578, 1.7386553337758537,
        1.8884564312509642, 2.0555030499520446, 2.241873210518961, 2.4499250112173154,
        2.682335248756337, 2.9421438140976397, 3.232804730132428, 3.5582448390944377,
        3.922931311020009, 4.331949334431724, 4.791091571328341, 5.306961215914568,
        5.887090796632801, 6.540079211404268, 7.275749895297896, 8.105333498424283,
        9.041679011843067, 10.099497935000704, 11.29564684659725, 12.649454641802725,
        14.183101756037855,
    ],
    // n = 8
    [
        1.0, 0.891943025324015, 0.8152069063105419, 0.7601744400465713,
        0.7209475550156333, 0.6937454339718386, 0.6760591972762936, 0.6661835116417515,
        0.6629446419492097, 0.665535721899012, 0.6734132816114483, 0.6862303441328015,
        0.7037922748625726, 0.7260273479579624, 0.7529671903028493, 0.7847341007348646,
        0.8215333377298293, 0.8636491454220598, 0.9114437202482946, 0.9653586063039353,
        1.0259182031640675, 1.0937352091569967, 1.1695179266403188, 1.2540794369010897,
        1.3483487195321657, 1.453383850411554, 1.5703874679091536, 1.7007247517882933,
        1.8459442159381976, 2.0078016766757747, 2.1882878248124555, 2.3896599038611646,
        2.6144780805747785, 2.865647189506099, 3.146464642711165, 3.460675421608969,
        3.812535213235701, 4.20688292098924, 4.649223974258326, 5.145826086483528,
        5.703829372331428, 6.331373037747161, 7.037741208637703, 7.833530872942086,
        8.730845386333401, 9.74351754483172, 10.887366871110478, 12.180496510360136,
        13.643636003902548,
    ],
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative L2 error `‖a − b‖ / ‖b‖` of coefficient vectors.
    fn rel(a: &[f64], b: &[f64]) -> f64 {
        let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
        (d / b.iter().map(|y| y * y).sum::<f64>()).sqrt()
    }

    fn one(n: usize) -> Vec<f64> {
        let mut v = vec![0.0; n * n];
        v[0] = SQRT_4PI;
        v
    }

    fn sphere(center: [f64; 3], radius: f64, ratio_attenuation: bool) -> TrainingSphere {
        TrainingSphere { center, radius, ratio_attenuation }
    }

    #[test]
    fn quadrature_weights_and_round_trip() {
        for n in [1, 4, 8] {
            let q = SphereQuadrature::new(n);
            assert_eq!(q.len(), (6 * n + 16) * (12 * n + 32));
            assert!(!q.is_empty());
            let wsum: f64 = q.weights().iter().sum();
            assert!((wsum - 4.0 * PI).abs() < 1e-12, "{wsum}");
            let d = q.dirs()[q.len() / 3];
            assert!((norm(&d) - 1.0).abs() < 1e-15);
            for (x, y) in q.basis(q.len() / 3).iter().zip(sh::eval(n, d)) {
                assert_eq!(*x, y);
            }
            // Projecting an order-n expansion's node values gives it back.
            let c: Vec<f64> = (0..n * n).map(|k| ((k * 29 % 13) as f64 - 6.0) / 5.0).collect();
            let back = q.project(&q.eval(&c));
            for (x, y) in back.iter().zip(&c) {
                assert!((x - y).abs() < 1e-13, "n={n}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn exp_of_constants() {
        for n in [1, 2, 4, 8] {
            let q = SphereQuadrature::new(n);
            for c in [0.0, 1.3, -2.7, -9.0] {
                let f: Vec<f64> = one(n).iter().map(|v| c * v).collect();
                let want: Vec<f64> = one(n).iter().map(|v| c.exp() * v).collect();
                let got = exp_quadrature(&q, &f);
                assert!(rel(&got, &want) < 1e-12, "n={n} c={c}: {got:?}");
                assert!(rel(&exp_optimal_linear(n, &f), &want) < 1e-13, "OL n={n} c={c}");
                assert!(rel(&exp_taylor(n, &f, 3), &want) < 1e-15, "Taylor n={n} c={c}");
            }
        }
        // f = 0 gives the constant 1 exactly up to rounding.
        let got = exp_quadrature(&SphereQuadrature::new(4), &[0.0; 16]);
        assert!((got[0] - SQRT_4PI).abs() < 1e-13 && got[1..].iter().all(|v| v.abs() < 1e-13), "{got:?}");
    }

    #[test]
    fn exp_quadrature_matches_brute_force_projection() {
        let n = 4;
        let mut rng = SplitMix(7);
        // A random smooth order-4 function, bands damped by 1/(l+1); amplitude ~1.
        let f: Vec<f64> = (0..n * n)
            .map(|k| {
                let l = (k as f64).sqrt().floor();
                (2.0 * rng.uniform() - 1.0) / (l + 1.0)
            })
            .collect();
        let got = exp_quadrature(&SphereQuadrature::new(n), &f);
        let g = |d: [f64; 3]| sh::reconstruct(n, &f, d).exp();
        // 200 Gauss–Legendre nodes × 400 uniform φ (sh::project, evaluated point by point).
        let gl = sh::project(n, g, 200);
        let e_gl = rel(&got, &gl);
        // 200 × 400 midpoint rule in (θ, φ) with the sinθ Jacobian: independent, O(h²).
        let (nt, np) = (200, 400);
        let (dt, dp) = (PI / nt as f64, 2.0 * PI / np as f64);
        let mut mid = vec![0.0; n * n];
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let p = (j as f64 + 0.5) * dp;
                let d = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
                let w = g(d) * t.sin() * dt * dp;
                for (m, y) in mid.iter_mut().zip(sh::eval(n, d)) {
                    *m += w * y;
                }
            }
        }
        let e_mid = rel(&got, &mid);
        eprintln!("exp_quadrature vs 200×400 GL: {e_gl:.2e}; vs 200×400 midpoint: {e_mid:.2e}");
        assert!(e_gl < 1e-9, "{e_gl}");
        assert!(e_mid < 3e-5, "{e_mid}");
    }

    #[test]
    fn ol_order_2_is_exact_and_matches_the_closed_form() {
        // u = √(3/4π)·cosθ (any unit band-1 vector, by symmetry): with κ = x√(3/4π),
        // a = sinhκ/κ, b = 4π√(3/4π)(κ coshκ − sinhκ)/(κ² x).
        let c1 = (3.0 / (4.0 * PI)).sqrt();
        for i in 1..OL_POINTS {
            let x = i as f64 * OL_STEP;
            let k = x * c1;
            let a = k.sinh() / k;
            let b = 4.0 * PI * c1 * (k * k.cosh() - k.sinh()) / (k * k * x);
            assert!((OL_A[0][i] / a - 1.0).abs() < 1e-12, "a({x}) = {} vs {a}", OL_A[0][i]);
            assert!((OL_B[0][i] / b - 1.0).abs() < 1e-12, "b({x}) = {} vs {b}", OL_B[0][i]);
        }
        // Off the grid (interpolated) OL is still exp* to interpolation accuracy.
        let q = SphereQuadrature::new(2);
        let mut worst = 0.0f64;
        for f in [[-2.0, 0.3, -1.1, 0.7], [0.5, 2.1, 1.7, -3.3], [-8.0, 0.01, 0.0, 0.02]] {
            worst = worst.max(rel(&exp_optimal_linear(2, &f), &exp_quadrature(&q, &f)));
        }
        eprintln!("OL at order 2 vs exp_quadrature: {worst:.2e}");
        assert!(worst < 5e-5, "{worst}");
    }

    #[test]
    fn ol_tables_are_the_least_squares_fit() {
        for n in 2..=OL_MAX_ORDER {
            let (a, b) = ol_fit_table(n);
            for i in 0..OL_POINTS {
                assert!((a[i] / OL_A[n - 2][i] - 1.0).abs() < 1e-12, "n={n} i={i}: {} vs {}", a[i], OL_A[n - 2][i]);
                assert!((b[i] / OL_B[n - 2][i] - 1.0).abs() < 1e-12, "n={n} i={i}: {} vs {}", b[i], OL_B[n - 2][i]);
            }
            // Second-order behaviour that holds for any DC-free unit training set:
            // a(x) = 1 + x²/(8π) + O(x³), b(0) = 1.
            let x = OL_STEP;
            assert!((a[1] - 1.0 - x * x / (8.0 * PI)).abs() < 0.1 * x * x / (8.0 * PI), "n={n}: a(½) = {}", a[1]);
            assert_eq!(b[0], 1.0);
        }
    }

    #[test]
    fn ol_interpolation_error_is_small() {
        let mut worst = 0.0f64;
        for n in [3, 4, 8] {
            let fit = OlFit::new(n);
            for x in [0.05, 0.2, 0.4, 0.75, 1.3, 3.25, 5.9, 11.75, 23.6] {
                let (a, b) = fit.at(x);
                let (ai, bi) = ol_coefficients(n, x);
                worst = worst.max((ai / a - 1.0).abs()).max((bi / b - 1.0).abs());
            }
        }
        eprintln!("OL table interpolation: worst relative error of a, b off the grid {worst:.2e}");
        assert!(worst < 2e-4, "{worst}");
        // Past the table: log-linear extrapolation, continuous at the end.
        let (a0, b0) = ol_coefficients(4, 24.0);
        assert!((a0 / OL_A[2][OL_POINTS - 1] - 1.0).abs() < 1e-12 && (b0 / OL_B[2][OL_POINTS - 1] - 1.0).abs() < 1e-12);
        let (a1, b1) = ol_coefficients(4, 25.0);
        assert!(a1 > a0 && b1 > b0);
        assert_eq!(ol_coefficients(1, 3.0), (1.0, 1.0));
    }

    #[test]
    fn sphere_log_vis_is_a_rotated_cap() {
        let (n, le) = (6, (0.2f64).ln());
        // Straight above: only m = 0 coefficients, equal to ln ε · cap ZH.
        let f = sphere_log_vis(n, [0.0, 0.0, 2.0], 1.0, le, false).unwrap();
        let cap = zh::cap(n, (0.5f64).asin());
        for l in 0..n as i32 {
            for m in -l..=l {
                let want = if m == 0 { le * cap[l as usize] } else { 0.0 };
                assert!((f[sh::index(l, m)] - want).abs() < 1e-14, "l={l} m={m}");
            }
        }
        // Oblique: the function about c/d equals the one about +z rotated (values at matching
        // directions), ratio attenuation scales by r/d.
        let c = [1.0, -2.0, 2.0]; // d = 3
        let g = sphere_log_vis(n, c, 1.5, le, false).unwrap();
        let h = sphere_log_vis(n, c, 1.5, le, true).unwrap();
        let up = sphere_log_vis(n, [0.0, 0.0, 3.0], 1.5, le, false).unwrap();
        assert!((sh::reconstruct(n, &g, c) - sh::reconstruct(n, &up, [0.0, 0.0, 1.0])).abs() < 1e-12);
        for (x, y) in h.iter().zip(&g) {
            assert!((x - 0.5 * y).abs() < 1e-14);
        }
        // Inside (or on) the blocker: the constant ln ε; no blocker: None.
        for r in [3.0, 4.0] {
            let v = sphere_log_vis(n, c, r, le, true).unwrap();
            assert!((v[0] - le * SQRT_4PI).abs() < 1e-14 && v[1..].iter().all(|&x| x == 0.0));
        }
        assert!(sphere_log_vis(n, c, 0.0, le, false).is_none());
        assert!(sphere_log_vis(n, c, -1.0, le, false).is_none());
        assert!(sphere_log_vis(n, [f64::NAN, 0.0, 1.0], 0.5, le, false).is_none());
        // Culling: entirely below the tangent plane only.
        assert!(sphere_culled([0.0, 0.0, 2.0], [0.3, 0.1, -1.0], 0.5));
        assert!(!sphere_culled([0.0, 0.0, 2.0], [0.3, 0.1, -1.0], 1.0)); // tangent to the plane: n̂·c = −1 = −r
        assert!(!sphere_culled([0.0, 0.0, 1.0], [0.3, 0.1, -0.4], 0.5)); // straddles the plane
        assert!(!sphere_culled([0.0, 0.0, 1.0], [0.3, 0.1, 2.0], 0.5));
        assert!(!sphere_culled([0.0, 0.0, 0.0], [0.3, 0.1, -9.0], 0.5));
    }

    /// Cosine-weighted visibility `(1/π) ∫ V(ω) max(cos θ, 0) dω` of an order-`n` SH vector `v`
    /// (normal +z).
    fn irradiance(n: usize, v: &[f64]) -> f64 {
        let cc = zh::rotate(n, &zh::clamped_cosine(n), [0.0, 0.0, 1.0]);
        v.iter().zip(&cc).map(|(a, b)| a * b).sum::<f64>() / PI
    }

    /// The closed-form cap check: one sphere centred on the normal hides a cap of half-angle Θ;
    /// the exact cosine-weighted visibility is `1 − sin²Θ` (`1 − (1 − ε) sin²Θ` for the
    /// ε-visibility `ε^cap` that the log function stands for before SH truncation).
    #[test]
    fn cap_occlusion_against_the_closed_form() {
        eprintln!("cosine-weighted visibility of one cap on the normal: E = ⟨V, max(cos,0)⟩/π");
        eprintln!(
            "  n  ε      sinΘ  1−sin²Θ  1−(1−ε)sin²Θ  E[P_n(1−cap)]  E[exp*(f)]  |E−(1−sin²Θ)|  relL2 vs P_n(1−cap)"
        );
        // [order 4, 8][ε = 0.2, 1e-6]: worst |E − (1 − sin²Θ)| and relative L2 vs P_n(1 − cap).
        let mut worst_e = [[0.0f64; 2]; 2];
        let mut worst_l2 = [[0.0f64; 2]; 2];
        for (ni, n) in [4usize, 8].into_iter().enumerate() {
            let q = SphereQuadrature::new(n);
            for (ei, eps) in [0.2f64, 1e-6].into_iter().enumerate() {
                for s in [0.2f64, 0.4, 0.6, 0.8] {
                    let f = sphere_log_vis(n, [0.0, 0.0, 1.0], s, eps.ln(), false).unwrap();
                    let v = exp_quadrature(&q, &f);
                    let e = irradiance(n, &v);
                    let (closed0, closed_eps) = (1.0 - s * s, 1.0 - (1.0 - eps) * s * s);
                    // The SH projection of the true visibility 1 − cap.
                    let cap = zh::rotate(n, &zh::cap(n, s.asin()), [0.0, 0.0, 1.0]);
                    let p0: Vec<f64> = one(n).iter().zip(&cap).map(|(o, c)| o - c).collect();
                    let (de, l2) = ((e - closed0).abs(), rel(&v, &p0));
                    eprintln!(
                        "  {n}  {eps:<6} {s:.1}   {closed0:.4}   {closed_eps:.4}        {:.4}         {e:.4}      {de:.4}         {l2:.4}",
                        irradiance(n, &p0)
                    );
                    worst_e[ni][ei] = worst_e[ni][ei].max(de);
                    worst_l2[ni][ei] = worst_l2[ni][ei].max(l2);
                }
            }
        }
        // Measured maxima over sinΘ ∈ {0.2, 0.4, 0.6, 0.8} (printed above), plus margin:
        // ε = 0.2: |ΔE| 0.083 (n = 4), 0.099 (n = 8); L2 0.098, 0.102.
        // ε = 1e-6: |ΔE| 0.24, 0.20; L2 0.98, 0.59.
        let limit_e = [[0.1, 0.3], [0.12, 0.25]];
        let limit_l2 = [[0.12, 1.2], [0.12, 0.75]];
        for ni in 0..2 {
            for ei in 0..2 {
                assert!(worst_e[ni][ei] < limit_e[ni][ei], "ΔE [{ni}][{ei}]: {}", worst_e[ni][ei]);
                assert!(worst_l2[ni][ei] < limit_l2[ni][ei], "L2 [{ni}][{ei}]: {}", worst_l2[ni][ei]);
            }
        }
        // A small ε is worse, not better: the truncated log function rings, and exp amplifies
        // the ringing (exp(ln ε · ringing) with |ln ε| = 13.8).
        for ni in 0..2 {
            assert!(worst_l2[ni][1] > 3.0 * worst_l2[ni][0] && worst_e[ni][1] > worst_e[ni][0]);
        }
    }

    #[test]
    fn approximations_against_exp_quadrature() {
        let le = (0.2f64).ln();
        let configs: Vec<(&str, Vec<TrainingSphere>)> = vec![
            ("1 sphere above, Θ=30°", vec![sphere([0.0, 0.0, 2.0], 1.0, false)]),
            ("1 small oblique", vec![sphere([1.5, 0.5, 1.0], 0.4, false)]),
            ("1 big near, Θ≈56°", vec![sphere([0.3, -0.2, 1.2], 1.05, false)]),
            ("1 big near, ratio", vec![sphere([0.3, -0.2, 1.2], 1.05, true)]),
            ("2 spheres apart", vec![sphere([1.0, 0.0, 1.0], 0.6, false), sphere([-1.0, 0.2, 0.8], 0.5, false)]),
            ("2 spheres overlapping", vec![sphere([0.2, 0.0, 1.0], 0.6, false), sphere([0.5, 0.3, 1.4], 0.7, false)]),
            (
                "4 spheres, ratio",
                vec![
                    sphere([1.0, 0.0, 0.6], 0.5, true),
                    sphere([0.0, 1.0, 0.6], 0.5, true),
                    sphere([-1.0, 0.0, 0.6], 0.5, true),
                    sphere([0.0, -1.0, 0.6], 0.5, true),
                ],
            ),
            (
                "8 spheres (ring + top)",
                (0..7)
                    .map(|i| {
                        let a = i as f64 * 2.0 * PI / 7.0;
                        sphere([1.5 * a.cos(), 1.5 * a.sin(), 0.9], 0.6, false)
                    })
                    .chain(std::iter::once(sphere([0.0, 0.0, 2.0], 0.9, false)))
                    .collect(),
            ),
        ];
        // Measured relative L2 errors (the printed table), [OL, Taylor 8, Taylor 16, OL + 3
        // squarings]; asserted with margin: error ≤ 1.25·measured + 1e-3.
        let measured: [[[f64; 4]; 8]; 2] = [
            [
                [0.0252, 0.0057, 0.0057, 0.0042],
                [0.0016, 0.0001, 0.0001, 0.0002],
                [0.0806, 0.0082, 0.0082, 0.0060],
                [0.0620, 0.0056, 0.0056, 0.0045],
                [0.0205, 0.0040, 0.0040, 0.0063],
                [0.0796, 0.0314, 0.0313, 0.0265],
                [0.0145, 0.0004, 0.0004, 0.0023],
                [0.0897, 0.0054, 0.0054, 0.0202],
            ],
            [
                [0.0807, 0.0025, 0.0025, 0.0038],
                [0.0169, 0.0013, 0.0013, 0.0010],
                [0.0674, 0.0029, 0.0029, 0.0146],
                [0.0533, 0.0018, 0.0018, 0.0106],
                [0.0634, 0.0088, 0.0088, 0.0049],
                [0.1772, 0.0127, 0.0090, 0.0135],
                [0.0129, 0.0015, 0.0015, 0.0016],
                [0.1008, 0.0101, 0.0100, 0.0252],
            ],
        ];
        for (ni, n) in [4usize, 8].into_iter().enumerate() {
            let q = SphereQuadrature::new(n);
            let t = triple::triple(n);
            let pipe = SphereQuadrature::pipeline(n);
            eprintln!("order {n}, ε = 0.2: relative L2 error vs exp_quadrature (SphereQuadrature::new)");
            eprintln!(
                "  {:<24} ‖f̂‖    OL      OL(best a,b)  Taylor8  Taylor16  OL+3sq  pipeline quad",
                "configuration"
            );
            for (ci, (name, cfg)) in configs.iter().enumerate() {
                let f = spheres_log_vis(n, cfg, le);
                let (e0, fh) = dc_isolate(n, &f);
                let x = norm(&fh);
                let ex = exp_quadrature(&q, &f);
                let errs = [
                    rel(&exp_optimal_linear(n, &f), &ex),
                    rel(&exp_taylor_with(t, &f, 8), &ex),
                    rel(&exp_taylor_with(t, &f, 16), &ex),
                    rel(&exp_ol_squaring(t, &f, 3), &ex),
                ];
                // The best a, b for this very configuration (least squares against ex).
                let best_a = ex[0] / (e0 * SQRT_4PI);
                let best_b = ex.iter().zip(&fh).map(|(e, u)| e * u).sum::<f64>() / (e0 * x * x);
                let best = rel(&ol_apply(e0, &fh, best_a, best_b), &ex);
                let pipe_err = rel(&exp_quadrature(&pipe, &f), &ex);
                eprintln!(
                    "  {name:<24} {x:.3}  {:.4}  {best:.4}        {:.4}   {:.4}    {:.4}  {pipe_err:.1e}",
                    errs[0], errs[1], errs[2], errs[3]
                );
                for (k, e) in errs.iter().enumerate() {
                    let m = measured[ni][ci][k];
                    assert!(*e <= 1.25 * m + 1e-3, "order {n} {name} method {k}: {e} (measured {m})");
                }
                // Reasonable: Taylor and OL with squaring within 5 %; OL within 10 % for one
                // sphere, 25 % always (its intrinsic limit: the best a, b are not much better).
                assert!(errs[1] < 0.05 && errs[2] < 0.05 && errs[3] < 0.05, "{name}: {errs:?}");
                assert!(errs[0] < if cfg.len() == 1 { 0.1 } else { 0.25 }, "{name}: {errs:?}");
                assert!(best <= errs[0] + 1e-12);
                assert!(pipe_err < 1e-6, "{name}: pipeline quadrature {pipe_err}");
            }
        }
    }
}

/// The log-SH diffuse BRDF of seed 001 §5 as an order-`n` ZH about the normal:
/// `g(θ) = ln max(cos θ / π, ε)` projected (`z_l = 2π ∫ g(t)·y_l^0(t) dt`, `t = cos θ`), by
/// Gauss–Legendre on the two smooth pieces `[−1, πε]` (the constant `ln ε`) and `[πε, 1]`
/// (`ln(t/π)`). `exp*(f_vis + rotate(z, N))` is then the transfer vector whose dot with the
/// lighting is the cosine-weighted visible irradiance over π (docs/blockers.md §3).
pub fn log_diffuse_zh(n: usize, eps: f64) -> Vec<f64> {
    check_order(n);
    let knee = (PI * eps).min(1.0);
    zonal_pieces(n, knee, 64, |t| if t <= knee { eps.ln() } else { (t / PI).ln() })
}

/// The order-`n` ZH `z_l = 2π ∫ g(t)·y_l^0(t) dt` of a zonal function smooth on `[−1, knee]` and
/// on `[knee, 1]`, by `nodes` Gauss–Legendre nodes on each piece.
fn zonal_pieces(n: usize, knee: f64, nodes: usize, g: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut z = vec![0.0; n];
    for (a, b) in [(-1.0, knee), (knee, 1.0)] {
        if b <= a {
            continue;
        }
        let (x, w) = crate::math::quadrature::gauss_legendre_on(a, b, nodes);
        for (t, wt) in x.iter().zip(&w) {
            for (l, zl) in z.iter_mut().enumerate() {
                let y = ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * crate::math::legendre::legendre(l, *t);
                *zl += 2.0 * PI * wt * g(*t) * y;
            }
        }
    }
    z
}

/// The log-SH Phong lobe of seed 001 §5 (eq. 27) as an order-`n` ZH about the reflection
/// vector: `g(θ) = ln max((S+1)/(2π)·cos^S θ, ε)` on the upper hemisphere and `ln ε` on the
/// lower (the split the seed asks for, so that even `S` does not reflect below), projected by
/// Gauss–Legendre on its two smooth pieces `[−1, t_k]` (the constant `ln ε`) and `[t_k, 1]`
/// (`ln((S+1)/(2π)) + S ln t`), `t_k = (2πε/(S+1))^{1/S}` where the lobe meets `ε`.
/// `exp*(f_vis + rotate(z, R))` is the glossy transfer whose dot with the lighting is the
/// normalised Phong lobe's visible radiance (docs/blockers.md §3).
///
/// # Panics
/// If `n ∉ 1..=16`, or `s`, `eps` are not positive and finite (programmer errors).
pub fn log_phong_zh(n: usize, s: f64, eps: f64) -> Vec<f64> {
    check_order(n);
    assert!(s > 0.0 && s.is_finite() && eps > 0.0 && eps.is_finite(), "log_phong_zh: S = {s}, ε = {eps}");
    let norm = (s + 1.0) / (2.0 * PI);
    let knee = (eps / norm).powf(1.0 / s).clamp(0.0, 1.0);
    zonal_pieces(n, knee, 96, |t| if t <= knee { eps.ln() } else { norm.ln() + s * t.ln() })
}

#[cfg(test)]
mod log_brdf_tests {
    use super::*;

    /// The seed's own measure (001 §5, fig. 6): the exponentiated log-SH Phong lobe against
    /// the ZH of the lobe it stands for, `max((S+1)/(2π) cos^S θ, ε)` (`ε` below the horizon),
    /// relative L2 over the order-n coefficients — how far a low-order log is from a narrow
    /// lobe. Measured (ε = 0.01; printed): docs/blockers.md §3.
    #[test]
    fn log_phong_lobe_against_its_zh() {
        let eps = 0.01;
        let mut errs = Vec::new();
        for (n, s) in [(4, 4.0), (8, 4.0), (4, 8.0), (8, 8.0), (4, 32.0), (8, 32.0)] {
            let f = crate::math::zh::rotate(n, &log_phong_zh(n, s, eps), [0.0, 0.0, 1.0]);
            let t = exp_quadrature(&SphereQuadrature::new(n), &f);
            let norm = (s + 1.0) / (2.0 * PI);
            let knee = (eps / norm).powf(1.0 / s);
            let lobe = |t: f64| if t <= knee { eps } else { norm * t.powf(s) };
            let (mut num, mut den) = (0.0, 0.0);
            for l in 0..n {
                let mut want = 0.0;
                for (a, b) in [(-1.0, knee), (knee, 1.0)] {
                    let (x, w) = crate::math::quadrature::gauss_legendre_on(a, b, 96);
                    for (u, wt) in x.iter().zip(&w) {
                        let y = ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * crate::math::legendre::legendre(l, *u);
                        want += 2.0 * PI * wt * lobe(*u) * y;
                    }
                }
                let got = t[l * (l + 1)];
                num += (got - want).powi(2);
                den += want * want;
            }
            let err = (num / den).sqrt();
            eprintln!("n={n} S={s} ε={eps}: exp*(log-SH Phong) vs the lobe's ZH: relative L2 {err:.3}");
            errs.push(err);
        }
        // Measured: 0.343 0.037 0.057 0.089 0.824 0.497 (a regression check; the values are the
        // method's, documented, not a target).
        let bound = [0.38, 0.041, 0.063, 0.098, 0.9, 0.55];
        for (e, b) in errs.iter().zip(bound) {
            assert!(*e < b, "{errs:?}");
        }
    }

    /// The transfer of an open sky: `⟨1, exp*(rotate(z, N))⟩` against the exact integral of
    /// `max(cos θ/π, ε)` over the sphere (measured: 6e-4 at n = 4, ε = 0.2; ≤ 9e-4 at n = 8).
    #[test]
    fn log_diffuse_transfer_of_an_open_sky() {
        for (n, eps, tol) in [(4, 0.2, 5e-3), (4, 0.01, 0.5), (8, 0.05, 5e-3), (8, 0.01, 5e-3)] {
            let z = log_diffuse_zh(n, eps);
            let f = crate::math::zh::rotate(n, &z, [0.0, 0.0, 1.0]);
            let q = SphereQuadrature::new(n);
            let t = exp_quadrature(&q, &f);
            // ⟨1, T⟩ = √4π · T_0; ∫ max(cos/π, ε) dω = 2π (ε (1 + πε) + (1 − (πε)²)/(2π)).
            let knee = PI * eps;
            let exact = 2.0 * PI * (eps * (knee + 1.0) + (1.0 - knee * knee) / (2.0 * PI));
            let got = 3.544_907_701_811_032 * t[0];
            eprintln!("n={n} ε={eps}: ⟨1, T⟩ = {got:.4}, exact ∫max(cos/π, ε) = {exact:.4}");
            assert!(((got - exact) / exact).abs() < tol, "{got} vs {exact}");
        }
    }
}
