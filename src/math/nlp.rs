//! 1D elevation functions in the normalised Legendre polynomial (NLP) basis (§4, eqs. 10–13).
//!
//! Elevation `ω` is measured from the horizon up (`[−π/2, π/2]`), `z = cosθ = sin ω`. The
//! binary occlusion function `v̄(ω; σ)` (eq. 3) is 1 for `ω ≤ σ`, i.e. for `z ≤ sin σ`, and 0 above.

use super::check_order;
use super::legendre::nlp_vec;
use super::quadrature::gauss_legendre_on;
use std::f64::consts::{FRAC_PI_2, SQRT_2};

/// NLP coefficients of the occlusion function (eq. 10):
/// `v̄_l(σ) = ∫_{−1}^{sin σ} P̂_l(z) dz`, `l = 0..n`, by Gauss–Legendre quadrature on
/// `[−1, sin σ]` with enough points to be exact for the degree-`(n−1)` polynomials.
/// `sigma` is clamped to `[−π/2, π/2]` (below the nadir everything is visible, above the
/// zenith everything is occluded).
pub fn occlusion(n: usize, sigma: f64) -> Vec<f64> {
    check_order(n);
    let s = sigma.clamp(-FRAC_PI_2, FRAC_PI_2).sin();
    let (zs, ws) = gauss_legendre_on(-1.0, s, n / 2 + 2);
    let mut out = vec![0.0; n];
    for (&z, &w) in zs.iter().zip(&ws) {
        for (o, p) in out.iter_mut().zip(nlp_vec(n, z)) {
            *o += w * p;
        }
    }
    out
}

/// The paper's order-4 closed form of eq. 10 (printed after eq. 13):
/// `[(sinσ+1)/√2, −3cos²σ/(2√6), −5 sinσ cos²σ/(2√10), 7cos²σ(−4+5cos²σ)/(8√14)]`.
/// It agrees with [`occlusion`]`(4, σ)` (checked to 1e-12 in the tests).
pub fn occlusion4_closed(sigma: f64) -> [f64; 4] {
    let (s, c) = sigma.sin_cos();
    let c2 = c * c;
    [
        (s + 1.0) / SQRT_2,
        -3.0 * c2 / (2.0 * 6f64.sqrt()),
        -5.0 * s * c2 / (2.0 * 10f64.sqrt()),
        7.0 * c2 * (-4.0 + 5.0 * c2) / (8.0 * 14f64.sqrt()),
    ]
}

/// NLP coefficients of the visibility function (eqs. 5, 11): visible above the maximum
/// blocking angle `omega_max`, `v = v̄(π/2) − v̄(ω_max)`.
pub fn visibility(n: usize, omega_max: f64) -> Vec<f64> {
    interval(n, omega_max, FRAC_PI_2)
}

/// NLP coefficients of the indicator of elevations in `[lo, hi]`, `v̄(hi) − v̄(lo)`: the key-light
/// visibility of §6 with `[lo, hi] = [ω_max, π/2] ∩ [l_min, l_max]`. An empty interval
/// (`hi ≤ lo`) gives the zero vector.
pub fn interval(n: usize, lo: f64, hi: f64) -> Vec<f64> {
    check_order(n);
    let lo = lo.clamp(-FRAC_PI_2, FRAC_PI_2);
    let hi = hi.clamp(-FRAC_PI_2, FRAC_PI_2);
    if hi <= lo {
        return vec![0.0; n];
    }
    // ∫_{sin lo}^{sin hi} P̂(z) dz directly (one quadrature, no cancellation between two).
    let (zs, ws) = gauss_legendre_on(lo.sin(), hi.sin(), n / 2 + 2);
    let mut out = vec![0.0; n];
    for (&z, &w) in zs.iter().zip(&ws) {
        for (o, p) in out.iter_mut().zip(nlp_vec(n, z)) {
            *o += w * p;
        }
    }
    out
}

/// Reconstruct an elevation function from its NLP coefficients (eq. 13): `Σ_l c_l P̂_l(z)`,
/// `z = cosθ = sin ω`.
pub fn reconstruct(coeffs: &[f64], z: f64) -> f64 {
    nlp_vec(coeffs.len(), z).iter().zip(coeffs).map(|(p, c)| p * c).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visibility_is_difference_of_occlusions() {
        for n in 2..=8 {
            for &w in &[-1.2, -0.3, 0.0, 0.4, 1.1] {
                let v = visibility(n, w);
                let a = occlusion(n, FRAC_PI_2);
                let b = occlusion(n, w);
                for l in 0..n {
                    assert!((v[l] - (a[l] - b[l])).abs() < 1e-14);
                }
            }
            assert!(interval(n, 0.5, 0.2).iter().all(|&x| x == 0.0));
        }
    }
}
