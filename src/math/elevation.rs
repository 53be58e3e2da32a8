//! The elevation basis of the per-azimuth visibility and radiance vectors (docs/accuracy.md §4,
//! candidate 5 of the accuracy issue).
//!
//! NS09 §4 keeps each azimuth's elevation function as `n` normalised-Legendre (NLP) coefficients
//! in `z = sin ω` and maps them to SH through the wedge matrices (eq. 20). The SH functions of odd
//! `m` contain `√(1 − z²)`, which no polynomial of degree `< n` represents, so the NLP step loses
//! part of the exact order-`n` projection. The `legendre` basis keeps instead what the SH
//! projection actually needs: for the indicator of an elevation interval `[a, b]`, the integrals
//!
//! `e_lm(a, b) = ∫_a^b P_l^m(sin ω) cos ω dω = ∫_{sin a}^{sin b} P_l^m(z) dz`, `0 ≤ m ≤ l < n`,
//!
//! `n(n+1)/2` numbers (10 at order 4). Since `y_l^{±m} = N_l^m P_l^m(cos θ) trig(mφ)`, the SH
//! projection of a wedge whose elevation functions are such indicators, blended in azimuth, is
//! exactly `N_l^m · F(m, b) · e_lm` (no elevation quadrature at all): the wedge matrices of this
//! basis ([`wedge_matrix`]) have the same φ part as the NLP ones and an identity in elevation.
//!
//! On the GPU `e_lm` comes from a closed form: `g_lm(ω) = cos^{m+1}ω · P_l^{(m)}(sin ω)` equals
//! `P_l^m(sin ω) cos ω` on `[−π/2, π/2]` and is a trigonometric polynomial of degree `≤ l + 1`,
//! `g = c_0 + Σ_k (α_k cos kω + β_k sin kω)`; so
//! `e_lm(a, b) = c_0 Δ + Σ_k (2/k) sin(kΔ/2) (α_k cos kμ + β_k sin kμ)`, `Δ = b − a`, `μ = (a+b)/2`,
//! every term proportional to `sin(kΔ/2)`: a thin interval keeps its relative precision in f32.
//! [`fourier_table`] holds the coefficients (`glsl/inc/hfgi_elevation.glsl` evaluates them).

use std::f64::consts::{FRAC_PI_2, PI, SQRT_2};

use super::quadrature::gauss_legendre_on;
use super::wedge::Mat;
use super::{check_order, legendre, nlp, sh};
use crate::scene::model::ElevationBasis;

/// Number of values per azimuth: `n` (NLP) or `n(n+1)/2` (Legendre).
pub fn size(basis: ElevationBasis, n: usize) -> usize {
    match basis {
        ElevationBasis::Nlp => n,
        ElevationBasis::Legendre => n * (n + 1) / 2,
    }
}

/// Index of `(l, m)`, `0 ≤ m ≤ l`, in a Legendre-basis vector.
pub fn index(l: usize, m: usize) -> usize {
    l * (l + 1) / 2 + m
}

/// The basis vector of the indicator of elevations `[lo, hi]` (clamped to `[−π/2, π/2]`; zero if
/// `hi ≤ lo`): NLP coefficients ([`nlp::interval`]) or the integrals `e_lm(lo, hi)`.
pub fn interval(basis: ElevationBasis, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    match basis {
        ElevationBasis::Nlp => nlp::interval(n, lo, hi),
        ElevationBasis::Legendre => legendre_interval(n, lo, hi),
    }
}

/// `e_lm(lo, hi)` by Gauss–Legendre in `ω` on `[lo, hi]` (the integrand is a trigonometric
/// polynomial of degree ≤ n; `2n + 12` points reach rounding level, checked in the tests).
pub fn legendre_interval(n: usize, lo: f64, hi: f64) -> Vec<f64> {
    check_order(n);
    let (lo, hi) = (lo.clamp(-FRAC_PI_2, FRAC_PI_2), hi.clamp(-FRAC_PI_2, FRAC_PI_2));
    let mut out = vec![0.0; n * (n + 1) / 2];
    if hi <= lo {
        return out;
    }
    let (ws, gw) = gauss_legendre_on(lo, hi, 2 * n + 12);
    for (&w, &g) in ws.iter().zip(&gw) {
        let (z, c) = w.sin_cos();
        for l in 0..n {
            for m in 0..=l {
                out[index(l, m)] += g * c * legendre::assoc_legendre(l, m, z);
            }
        }
    }
    out
}

/// SH normalisation of `y_l^{±m}` without its trig factor: `K_l^0`, or `√2 K_l^m` for `m > 0`.
pub fn sh_norm(l: usize, m: usize) -> f64 {
    if m == 0 {
        sh::k_lm(l, 0)
    } else {
        SQRT_2 * sh::k_lm(l, m)
    }
}

/// Fourier coefficients of `g_lm(ω) = cos^{m+1}ω · P_l^{(m)}(sin ω)` for every `(l, m)` of order
/// `n`: `n(n+1)/2` rows of `2n + 1` values `[c_0, α_1..α_n, β_1..β_n]` (row-major), computed by
/// an exact discrete Fourier transform of the trigonometric polynomial.
pub fn fourier_table(n: usize) -> Vec<f64> {
    check_order(n);
    let samples = 4 * n + 8;
    let row = 2 * n + 1;
    let mut out = vec![0.0; n * (n + 1) / 2 * row];
    for l in 0..n {
        for m in 0..=l {
            let r = &mut out[index(l, m) * row..(index(l, m) + 1) * row];
            for j in 0..samples {
                let w = 2.0 * PI * (j as f64 + 0.3) / samples as f64;
                let (z, c) = w.sin_cos();
                // assoc_legendre is (1−z²)^{m/2} P^{(m)} = |cos ω|^m P^{(m)}; g needs cos^m ω.
                let sign = if c < 0.0 && m % 2 == 1 { -1.0 } else { 1.0 };
                let g = sign * c * legendre::assoc_legendre(l, m, z);
                r[0] += g / samples as f64;
                for k in 1..=n {
                    let (s, ck) = (k as f64 * w).sin_cos();
                    r[k] += 2.0 * g * ck / samples as f64;
                    r[n + k] += 2.0 * g * s / samples as f64;
                }
            }
        }
    }
    out
}

/// The `2n + 1` Fourier moments of the indicator of `[a, b]` (zero if `b ≤ a`):
/// `[Δ, (2/k) sin(kΔ/2) cos kμ (k = 1..n), (2/k) sin(kΔ/2) sin kμ (k = 1..n)]`, `Δ = b − a`,
/// `μ = (a + b)/2`, so that `e_lm(a, b) = Σ_f T[lm][f] · moment_f` with `T` the
/// [`fourier_table`]. The GPU accumulates these per azimuth and meets `T` only once, folded into
/// the wedge matrices ([`fold_to_moments`]).
pub fn fourier_moments(n: usize, a: f64, b: f64) -> Vec<f64> {
    let mut out = vec![0.0; 2 * n + 1];
    if b <= a {
        return out;
    }
    let (d, mu) = (b - a, 0.5 * (a + b));
    out[0] = d;
    for k in 1..=n {
        let kf = k as f64;
        let w = 2.0 / kf * (0.5 * kf * d).sin();
        out[k] = w * (kf * mu).cos();
        out[n + k] = w * (kf * mu).sin();
    }
    out
}

/// `e_lm(a, b)` from [`fourier_table`] and [`fourier_moments`] (for the tests).
pub fn legendre_interval_fourier(n: usize, table: &[f64], a: f64, b: f64) -> Vec<f64> {
    let row = 2 * n + 1;
    let f = fourier_moments(n, a, b);
    (0..n * (n + 1) / 2).map(|e| table[e * row..(e + 1) * row].iter().zip(&f).map(|(t, m)| t * m).sum()).collect()
}

/// The GPU values (indices into the [`fourier_moments`]: `0` the width, `k` the cosine moment of
/// order `k`, `n + k` the sine moment) on which row `(l, m)` of a folded wedge matrix in the
/// legendre basis ([`fold_to_moments`]) is non-zero. The row integrates `g_l|m|(ω) =
/// cos^{|m|+1}ω · P_l^{(|m|)}(sin ω)` ([`fourier_table`]), a trigonometric polynomial of degree
/// `l + 1` with the parity of `l − |m|`: even, it has only the cosines of orders `l + 1, l − 1, …
/// ≥ 0`; odd, only the sines of orders `l + 1, l − 1, … ≥ 1`. Every other entry of the row is zero
/// to rounding (tested): at order 4 a fold reads 34 of the 144 entries of `A_j`, and the 9 rows
/// of a diffuse `U` 16 of 81 (docs/performance.md §22). In decreasing order, as
/// `hfgi_fold_moment` (glsl/inc/hfgi_fold.glsl) reads them.
pub fn fold_support(n: usize, l: usize, m: i64) -> Vec<usize> {
    let even = (l as i64 - m.abs()) % 2 == 0;
    (0..=l + 1).rev().step_by(2).filter(|&k| even || k > 0).map(|k| if even { k } else { n + k }).collect()
}

/// [`fold_support`] of every row of an order-`n` fold, in SH order (row `k = l(l+1) + m`): what
/// `frame::shared::gpu_fold` stores of each row and `fold_texels` counts.
pub fn fold_supports(n: usize) -> Vec<Vec<usize>> {
    (0..n).flat_map(|l| (-(l as i64)..=l as i64).map(move |m| fold_support(n, l, m))).collect()
}

/// Values per azimuth on the GPU: `n` NLP coefficients, or for the `legendre` basis the
/// `2n + 1` [`fourier_moments`] (fewer than the `n(n+1)/2` integrals from order 4 on: 9, 13, 17
/// against 10, 21, 36 at orders 4, 6, 8).
pub fn gpu_size(basis: ElevationBasis, n: usize) -> usize {
    match basis {
        ElevationBasis::Nlp => n,
        ElevationBasis::Legendre => 2 * n + 1,
    }
}

/// A matrix acting on basis vectors (`cols = size(basis, n)`), made to act on the GPU's values
/// ([`gpu_size`]): unchanged for NLP, `A · T` for the legendre basis (`T` the [`fourier_table`]
/// as a `n(n+1)/2 × (2n + 1)` matrix). Exact up to rounding: `e = T · moments`.
pub fn fold_to_moments(basis: ElevationBasis, n: usize, a: Mat) -> Mat {
    if basis == ElevationBasis::Nlp {
        return a;
    }
    let (e, f) = (size(basis, n), 2 * n + 1);
    assert_eq!(a.cols, e, "fold_to_moments: {} columns, expected {e}", a.cols);
    let t = fourier_table(n);
    let mut out = Mat::zeros(a.rows, f);
    for r in 0..a.rows {
        for (i, &v) in a.row(r).iter().enumerate() {
            for c in 0..f {
                out.data[r * f + c] += v * t[i * f + c];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_quadrature_is_converged_and_matches_the_closed_form() {
        for n in [2usize, 4, 6, 8] {
            let t = fourier_table(n);
            for (a, b) in [(-1.5, FRAC_PI_2), (-0.3, 0.2), (0.1, 0.1 + 1e-6), (-FRAC_PI_2, 1.0)] {
                let q = legendre_interval(n, a, b);
                let fine = {
                    // Two halves: an independent, finer rule.
                    let (h1, h2) = (legendre_interval(n, a, 0.5 * (a + b)), legendre_interval(n, 0.5 * (a + b), b));
                    h1.iter().zip(&h2).map(|(x, y)| x + y).collect::<Vec<_>>()
                };
                let f = legendre_interval_fourier(n, &t, a, b);
                let scale = q.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
                for ((x, y), z) in q.iter().zip(&fine).zip(&f) {
                    assert!((x - y).abs() <= 1e-12 * scale, "n={n} [{a},{b}]: {x} vs {y}");
                    assert!((x - z).abs() <= 1e-10 * scale, "n={n} [{a},{b}]: quadrature {x} vs closed form {z}");
                }
            }
        }
    }

    #[test]
    fn m_zero_terms_are_the_nlp_ones() {
        // e_l0 = ∫ P_l dz and the NLP coefficient is ∫ P̂_l dz = √((2l+1)/2) ∫ P_l dz.
        let n = 5;
        let (e, v) = (legendre_interval(n, -0.4, 0.9), nlp::interval(n, -0.4, 0.9));
        for l in 0..n {
            let want = v[l] / ((2 * l + 1) as f64 / 2.0).sqrt();
            assert!((e[index(l, 0)] - want).abs() < 1e-13, "l={l}: {} vs {want}", e[index(l, 0)]);
        }
    }

    #[test]
    fn folded_moments_equal_the_integrals() {
        // A · e(a, b) == fold_to_moments(A) · moments(a, b), for thin and wide intervals.
        for n in [2usize, 4, 6, 8] {
            let e = size(ElevationBasis::Legendre, n);
            let mut a = Mat::zeros(n * n, e);
            for (i, v) in a.data.iter_mut().enumerate() {
                *v = ((i * 7 + 3) as f64 * 0.37).sin();
            }
            let folded = fold_to_moments(ElevationBasis::Legendre, n, a.clone());
            for (lo, hi) in [(-1.5, FRAC_PI_2), (-0.3, 0.2), (0.1, 0.1 + 1e-6)] {
                let want = a.mul_vec(&legendre_interval(n, lo, hi));
                let got = folded.mul_vec(&fourier_moments(n, lo, hi));
                let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (x, y) in want.iter().zip(&got) {
                    assert!((x - y).abs() <= 1e-10 * scale, "n={n} [{lo},{hi}]: {x} vs {y}");
                }
            }
        }
    }

    #[test]
    fn folded_rows_vanish_outside_their_support() {
        // fold_support's parity and degree rule against the folded matrices themselves: every
        // entry it leaves out (the GPU never reads them) is rounding next to the kept ones, for
        // every order, both wedge interpolations, complete sets and a key light's window.
        use crate::math::azimuth;
        use crate::scene::model::{Interpolation, KeyLight};
        let light = KeyLight { direction: glam::DVec3::new(0.3, -0.5, 0.8), angular_radius: 0.1, radiance: [1.0; 3] };
        for n in 1..=8usize {
            for interp in [Interpolation::Linear, Interpolation::Bspline] {
                for set in [
                    azimuth::environment_set(32, 0.0, interp),
                    azimuth::environment_set(7, 0.0, interp),
                    azimuth::key_light_set(&light, 3, interp),
                ] {
                    for a in azimuth::fold(n, &set, interp, ElevationBasis::Legendre) {
                        let a = fold_to_moments(ElevationBasis::Legendre, n, a);
                        let scale = a.data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        assert!(scale > 0.0, "n={n}: an empty fold");
                        let e = 2 * n + 1;
                        let supports = fold_supports(n);
                        assert_eq!(supports.len(), n * n);
                        for (k, (row, support)) in a.data.chunks(e).zip(&supports).enumerate() {
                            for (c, v) in row.iter().enumerate() {
                                if !support.contains(&c) {
                                    assert!(
                                        v.abs() <= 1e-12 * scale,
                                        "n={n} {interp:?} row {k} column {c}: {v:e} of {scale:e}"
                                    );
                                }
                            }
                        }
                        let kept: usize = supports.iter().map(Vec::len).sum();
                        assert!(n < 4 || kept * 4 <= n * n * e, "n={n}: {kept} kept");
                    }
                }
            }
        }
        assert_eq!(
            (fold_support(4, 0, 0), fold_support(4, 1, 0), fold_support(4, 1, 1)),
            (vec![1], vec![6], vec![2, 0])
        );
    }
}
