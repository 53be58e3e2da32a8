//! Real orthonormal spherical harmonics exactly as in `CONVENTIONS.md`: no Condon–Shortley
//! phase, `y_l^0 = K_l^0 P_l^0(cosθ)`, `y_l^m = √2 K_l^m cos(mφ) P_l^m(cosθ)` and
//! `y_l^{−m} = √2 K_l^m sin(mφ) P_l^m(cosθ)` for `m > 0`, with
//! `K_l^m = sqrt((2l+1)/(4π)·(l−m)!/(l+m)!)`; index `k = l(l+1) + m`.
//!
//! `Y(θ, φ)` in eqs. 18–22 is the vector returned by [`eval`]; `Rot_z` of eq. 21 is
//! [`rotate_z`].

use super::check_order;
use super::legendre::assoc_from_pmm;
use super::quadrature::gauss_legendre;
use std::f64::consts::PI;

/// Flat coefficient index of `(l, m)`: `l(l+1) + m` (`|m| ≤ l`).
pub fn index(l: i32, m: i32) -> usize {
    debug_assert!(l >= 0 && m.abs() <= l, "invalid SH index (l={l}, m={m})");
    (l * (l + 1) + m) as usize
}

/// `K_l^m = sqrt((2l+1)/(4π) · (l−m)!/(l+m)!)` for `0 ≤ m ≤ l`.
pub fn k_lm(l: usize, m: usize) -> f64 {
    let mut ratio = 1.0;
    for k in (l - m + 1)..=(l + m) {
        ratio /= k as f64;
    }
    ((2 * l + 1) as f64 / (4.0 * PI) * ratio).sqrt()
}

/// All `n²` real SH basis functions at direction `d` (normalised internally; need not be unit).
///
/// Evaluated in Cartesian form — `sin^mθ·cos(mφ) = Re((x+iy)^m)`, `sin^mθ·sin(mφ) = Im((x+iy)^m)`
/// times the polynomial part of `P_l^m` — so it is exact and smooth at the poles.
///
/// # Panics
/// If `n ∉ 1..=16`, or `d` is zero or not finite (programmer errors).
pub fn eval(n: usize, d: [f64; 3]) -> Vec<f64> {
    check_order(n);
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    assert!(len > 0.0 && len.is_finite(), "sh::eval: direction must be non-zero and finite, got {d:?}");
    let (x, y, z) = (d[0] / len, d[1] / len, d[2] / len);
    let mut out = vec![0.0; n * n];
    // (x + iy)^m, built up as m increases.
    let (mut cm, mut sm) = (1.0, 0.0);
    // (2m−1)!!
    let mut dfact = 1.0;
    for m in 0..n {
        if m > 0 {
            let c = x * cm - y * sm;
            let s = x * sm + y * cm;
            cm = c;
            sm = s;
            dfact *= (2 * m - 1) as f64;
        }
        for l in m..n {
            // Polynomial part Q_l^m(z) = P_l^m(z) / (1 − z²)^{m/2}.
            let q = assoc_from_pmm(l, m, z, dfact);
            let k = k_lm(l, m);
            let (li, mi) = (l as i32, m as i32);
            if m == 0 {
                out[index(li, 0)] = k * q;
            } else {
                let f = std::f64::consts::SQRT_2 * k * q;
                out[index(li, mi)] = f * cm;
                out[index(li, -mi)] = f * sm;
            }
        }
    }
    out
}

/// [`eval`] at the direction `(sinθ cosφ, sinθ sinφ, cosθ)`.
pub fn eval_angles(n: usize, theta: f64, phi: f64) -> Vec<f64> {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    eval(n, [st * cp, st * sp, ct])
}

/// Rotation about +z by `alpha` (eq. 21's `Rot_z`): returns the SH vector of
/// `g(θ, φ) = f(θ, φ − alpha)` where `c` is the SH vector of `f` (first `n²` entries used). A
/// wedge canonically starting at `φ = 0` ends up starting at `φ = alpha`.
///
/// Per band `l` and `m > 0`, with `a = c[l,m]` (cos part) and `b = c[l,−m]` (sin part):
/// `a' = a cos(mα) − b sin(mα)`, `b' = a sin(mα) + b cos(mα)`; `m = 0` is unchanged.
///
/// # Panics
/// If `n ∉ 1..=16` or `c.len() < n²` (programmer errors).
pub fn rotate_z(n: usize, c: &[f64], alpha: f64) -> Vec<f64> {
    check_order(n);
    assert!(c.len() >= n * n, "rotate_z: need {} coefficients, got {}", n * n, c.len());
    let mut out = c[..n * n].to_vec();
    for m in 1..n {
        let (s, co) = (m as f64 * alpha).sin_cos();
        let mi = m as i32;
        for l in m..n {
            let li = l as i32;
            let (ia, ib) = (index(li, mi), index(li, -mi));
            let (a, b) = (c[ia], c[ib]);
            out[ia] = a * co - b * s;
            out[ib] = a * s + b * co;
        }
    }
    out
}

/// SH projection `c_k = ∫ f(ω) y_k(ω) dω` of `f` to order `n` by sphere quadrature: `quad`
/// Gauss–Legendre nodes in `z = cosθ` times `2·quad` uniform samples in `φ`.
///
/// Exact (to rounding) when `f` is itself an SH expansion of order `n_f` with
/// `quad ≥ (n + n_f)/2`; for other functions it is an ordinary (spectrally convergent for
/// smooth `f`) quadrature.
///
/// # Panics
/// If `n ∉ 1..=16` or `quad == 0` (programmer errors).
pub fn project(n: usize, f: impl Fn([f64; 3]) -> f64, quad: usize) -> Vec<f64> {
    check_order(n);
    assert!(quad >= 1, "project: quad must be positive");
    let (zs, ws) = gauss_legendre(quad);
    let nphi = 2 * quad;
    let dphi = 2.0 * PI / nphi as f64;
    let mut out = vec![0.0; n * n];
    for (&z, &wz) in zs.iter().zip(&ws) {
        let st = (1.0 - z * z).max(0.0).sqrt();
        for k in 0..nphi {
            let phi = (k as f64 + 0.5) * dphi;
            let d = [st * phi.cos(), st * phi.sin(), z];
            let w = wz * dphi * f(d);
            if w == 0.0 {
                continue;
            }
            for (o, y) in out.iter_mut().zip(eval(n, d)) {
                *o += w * y;
            }
        }
    }
    out
}

/// Evaluate an SH expansion `Σ_k c_k y_k(d)` of order `n` at direction `d`.
pub fn reconstruct(n: usize, c: &[f64], d: [f64; 3]) -> f64 {
    eval(n, d).iter().zip(c).map(|(y, c)| y * c).sum()
}

/// The coefficients of `f(R⁻¹ω)` for `f = Σ c_k y_k` of order `n`: the expansion rotated by
/// the rotation matrix `r` (row-major, orthonormal), so that what `f` had in direction `d` the
/// result has in direction `R·d`. A rotation keeps each band, so projecting the rotated
/// expansion with [`project`] at `n` Gauss–Legendre nodes (exact for the product of two
/// order-`n` expansions) is exact to rounding. `Environment::rotated` uses it for a rotating
/// sky (an environment map rotates the same way: its SH projection commutes with rotation).
///
/// # Panics
/// If `n ∉ 1..=16` or `c.len() < n²` (programmer errors).
pub fn rotate(n: usize, c: &[f64], r: [[f64; 3]; 3]) -> Vec<f64> {
    check_order(n);
    assert!(c.len() >= n * n, "rotate: need {} coefficients, got {}", n * n, c.len());
    // R⁻¹ = Rᵀ for a rotation: (Rᵀd)_i = Σ_j r[j][i] d_j.
    let inv = |d: [f64; 3]| [0, 1, 2].map(|i| r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2]);
    project(n, |d| reconstruct(n, c, inv(d)), n.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_layout() {
        assert_eq!(index(0, 0), 0);
        assert_eq!(index(1, -1), 1);
        assert_eq!(index(1, 1), 3);
        assert_eq!(index(3, 3), 15);
        assert_eq!(index(7, 7), 63);
    }

    #[test]
    fn eval_angles_matches_eval() {
        let (t, p) = (0.7, 2.1);
        let a = eval_angles(6, t, p);
        let b = eval(6, [3.0 * t.sin() * p.cos(), 3.0 * t.sin() * p.sin(), 3.0 * t.cos()]);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-14);
        }
    }

    #[test]
    fn rotate_matches_rotate_z_and_moves_values_with_the_directions() {
        let n = 5;
        let c: Vec<f64> = (0..n * n).map(|k| ((k * 37 % 11) as f64 - 5.0) / 7.0).collect();
        let a = 0.83f64;
        let rz = [[a.cos(), -a.sin(), 0.0], [a.sin(), a.cos(), 0.0], [0.0, 0.0, 1.0]];
        for (x, y) in rotate(n, &c, rz).iter().zip(rotate_z(n, &c, a)) {
            assert!((x - y).abs() < 1e-12, "{x} vs {y}");
        }
        // A rotation about an oblique axis (Rodrigues): f'(R·d) = f(d).
        let (u, t) = ([0.36f64, -0.48, 0.8], 1.9f64);
        let (s, co) = t.sin_cos();
        let k = [[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]];
        let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let kk: f64 = (0..3).map(|m| k[i][m] * k[m][j]).sum();
                f64::from(u8::from(i == j)) + s * k[i][j] + (1.0 - co) * kk
            })
        });
        let rot = rotate(n, &c, r);
        for d in [[0.3, 0.2, 0.9], [-0.7, 0.1, -0.2], [0.0, -1.0, 0.05]] {
            let rd = [0, 1, 2].map(|i| r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2]);
            let (x, y) = (reconstruct(n, &rot, rd), reconstruct(n, &c, d));
            assert!((x - y).abs() < 1e-12, "{x} vs {y}");
        }
    }
}
