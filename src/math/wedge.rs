//! SH projection of an azimuthal wedge (§6 eqs. 18–21, Appendix A eqs. 22–24).
//!
//! Within a wedge of angular extent `Δφ`, canonically starting at `φ = 0`, the spherical function
//! is an azimuthal blend of per-direction NLP elevation functions (eq. 23):
//! `W(θ, φ) = I(α; w…) · P̂(cosθ)`, `α = φ/Δφ`. Its SH projection is linear in the stacked NLP
//! vectors (eq. 20): `W = M · [w_j; w_{j+1}]` (linear) or `M · [w_{j−1}; w_j; w_{j+1}; w_{j+2}]`
//! (cubic B-spline), with
//! `M[r][c] = ∫_0^{Δφ} ∫_0^π [I]_c · P̂_{c mod n}(cosθ) · Y_r(θ, φ) · sinθ dθ dφ`.
//! The paper computed these in Maple; here they are computed by Gauss–Legendre quadrature,
//! exploiting separability: `Y_r = N_l^m P_l^{|m|}(cosθ)·trig(mφ)`, so
//! `M[(l,m)][(b,k)] = T(l,|m|,k) · F(m,b)` with `T = ∫_0^π P̂_k(cosθ) N_l^m P_l^{|m|}(cosθ) sinθ dθ`
//! (integrated in θ, since odd `m` carries `sinθ` factors that are not polynomial in `z`) and
//! `F = ∫_0^{Δφ} β_b(φ/Δφ) trig(mφ) dφ`. Both integrands are entire (trigonometric polynomials
//! times polynomials), so the rules used converge to ~1e-15.
//! Each wedge's vector is then rotated to its start azimuth `φ_j` with [`super::sh::rotate_z`]
//! and summed (eq. 21).

use super::quadrature::gauss_legendre_on;
use super::{bspline, check_order, legendre, sh};
use std::f64::consts::{PI, SQRT_2};

/// Small dense row-major matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Mat {
    pub rows: usize,
    pub cols: usize,
    /// Row-major: element `(r, c)` at `r * cols + c`.
    pub data: Vec<f64>,
}

impl Mat {
    /// The `rows × cols` zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Mat {
        Mat { rows, cols, data: vec![0.0; rows * cols] }
    }

    /// Element `(r, c)`.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        assert!(r < self.rows && c < self.cols, "Mat::get({r}, {c}) out of {}×{}", self.rows, self.cols);
        self.data[r * self.cols + c]
    }

    /// Set element `(r, c)`.
    pub fn set(&mut self, r: usize, c: usize, v: f64) {
        assert!(r < self.rows && c < self.cols, "Mat::set({r}, {c}) out of {}×{}", self.rows, self.cols);
        self.data[r * self.cols + c] = v;
    }

    /// Row `r` as a slice.
    pub fn row(&self, r: usize) -> &[f64] {
        &self.data[r * self.cols..(r + 1) * self.cols]
    }

    /// `self · x`.
    ///
    /// # Panics
    /// If `x.len() != self.cols` (programmer error).
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(x.len(), self.cols, "Mat::mul_vec: length mismatch");
        (0..self.rows).map(|r| self.row(r).iter().zip(x).map(|(a, b)| a * b).sum()).collect()
    }
}

/// `M_lin(Δφ)` (eq. 20, Appendix A eq. 24): `n² × 2n`. Columns `0..n` multiply `w_j` (weight
/// `1 − α`), columns `n..2n` multiply `w_{j+1}` (weight `α`), `α = φ/Δφ`.
///
/// # Panics
/// If `n ∉ 1..=16` or `dphi` is not finite (programmer errors).
pub fn m_lin(n: usize, dphi: f64) -> Mat {
    wedge_matrix(n, dphi, |a| [1.0 - a, a])
}

/// `M_bspl(Δφ)` (Appendix A): `n² × 4n`. Column blocks `b = 0..4` multiply the NLP vectors of
/// samples `j−1, j, j+1, j+2` with the uniform cubic B-spline weights
/// [`bspline::weights`]`(α)[b]`. At order 4 this is 16×16 (the paper's "16×32" does not match its
/// own definition: four NLP vectors of four coefficients each).
///
/// # Panics
/// If `n ∉ 1..=16` or `dphi` is not finite (programmer errors).
pub fn m_bspl(n: usize, dphi: f64) -> Mat {
    wedge_matrix(n, dphi, bspline::weights)
}

/// Number of Gauss–Legendre points in θ ∈ [0, π] for order `n`: the integrand is a
/// trigonometric polynomial of degree ≤ 2n − 1; 32 + 4n points reach rounding level
/// (checked by doubling in the tests).
pub(crate) fn theta_points(n: usize) -> usize {
    32 + 4 * n
}

/// Number of Gauss–Legendre points in φ ∈ [0, Δφ]: the integrand is a cubic times
/// `cos/sin(mφ)` with `m < n`.
pub(crate) fn phi_points(n: usize, dphi: f64) -> usize {
    32 + (n as f64 * dphi.abs()).ceil() as usize
}

/// φ part of a wedge matrix: `f[(m + n − 1)·B + b] = ∫_0^{Δφ} β_b(φ/Δφ) trig(mφ) dφ`, trig = cos
/// for `m ≥ 0`, `sin(|m|φ)` for `m < 0`.
fn phi_part<const B: usize>(n: usize, dphi: f64, weights: &impl Fn(f64) -> [f64; B]) -> Vec<f64> {
    let mut f = vec![0.0; (2 * n - 1) * B];
    let (phs, pws) = gauss_legendre_on(0.0, dphi, phi_points(n, dphi));
    for (&ph, &pw) in phs.iter().zip(&pws) {
        let beta = weights(ph / dphi);
        for m in 0..n {
            let (s, c) = (m as f64 * ph).sin_cos();
            for b in 0..B {
                f[(m + n - 1) * B + b] += pw * beta[b] * c;
                if m > 0 {
                    f[(n - 1 - m) * B + b] += pw * beta[b] * s;
                }
            }
        }
    }
    f
}

/// The wedge matrix of the `legendre` elevation basis ([`super::elevation`]): `n² × B·n(n+1)/2`,
/// column block `b` multiplies the `e_lm` vector of sample `b` (linear: `j, j+1`; B-spline:
/// `j−1 … j+2`); `M[(l,m)][(b, (l,|m|))] = N_l^{|m|} · F(m, b)` and zero elsewhere — the exact SH
/// projection of the azimuthally blended indicators.
pub fn wedge_matrix_legendre(n: usize, dphi: f64, interp: crate::scene::model::Interpolation) -> Mat {
    match interp {
        crate::scene::model::Interpolation::Linear => legendre_matrix(n, dphi, |a| [1.0 - a, a]),
        crate::scene::model::Interpolation::Bspline => legendre_matrix(n, dphi, bspline::weights),
    }
}

fn legendre_matrix<const B: usize>(n: usize, dphi: f64, weights: impl Fn(f64) -> [f64; B]) -> Mat {
    check_order(n);
    assert!(dphi.is_finite(), "wedge matrix: Δφ must be finite, got {dphi}");
    let e = n * (n + 1) / 2;
    let mut out = Mat::zeros(n * n, B * e);
    if dphi == 0.0 {
        return out;
    }
    let f = phi_part(n, dphi, &weights);
    for l in 0..n {
        let li = l as i32;
        for mi in -li..=li {
            let ma = mi.unsigned_abs() as usize;
            let norm = super::elevation::sh_norm(l, ma);
            let fm = &f[(mi + n as i32 - 1) as usize * B..(mi + n as i32) as usize * B];
            for (b, &fb) in fm.iter().enumerate() {
                out.set(sh::index(li, mi), b * e + super::elevation::index(l, ma), norm * fb);
            }
        }
    }
    out
}

fn wedge_matrix<const B: usize>(n: usize, dphi: f64, weights: impl Fn(f64) -> [f64; B]) -> Mat {
    check_order(n);
    assert!(dphi.is_finite(), "wedge matrix: Δφ must be finite, got {dphi}");
    let mut out = Mat::zeros(n * n, B * n);
    if dphi == 0.0 {
        return out;
    }

    // θ part: t[(l*n + m)*n + k] = ∫_0^π P̂_k(cosθ) · N_l^m P_l^m(cosθ) · sinθ dθ, m ≥ 0.
    let mut t = vec![0.0; n * n * n];
    let (ths, tws) = gauss_legendre_on(0.0, PI, theta_points(n));
    let norms: Vec<f64> = (0..n * n)
        .map(|i| {
            let (l, m) = (i / n, i % n);
            if m > l {
                0.0
            } else if m == 0 {
                sh::k_lm(l, 0)
            } else {
                SQRT_2 * sh::k_lm(l, m)
            }
        })
        .collect();
    for (&th, &tw) in ths.iter().zip(&tws) {
        let (st, z) = th.sin_cos();
        let p = legendre::nlp_vec(n, z);
        for l in 0..n {
            for m in 0..=l {
                let y = tw * st * norms[l * n + m] * legendre::assoc_legendre(l, m, z);
                let row = &mut t[(l * n + m) * n..(l * n + m + 1) * n];
                for (tk, pk) in row.iter_mut().zip(&p) {
                    *tk += y * pk;
                }
            }
        }
    }

    let f = phi_part(n, dphi, &weights);

    for l in 0..n {
        let li = l as i32;
        for mi in -li..=li {
            let r = sh::index(li, mi);
            let ma = mi.unsigned_abs() as usize;
            let trow = &t[(l * n + ma) * n..(l * n + ma + 1) * n];
            let fm = &f[(mi + n as i32 - 1) as usize * B..(mi + n as i32) as usize * B];
            let orow = &mut out.data[r * B * n..(r + 1) * B * n];
            for (oblock, &fb) in orow.chunks_exact_mut(n).zip(fm) {
                for (o, &tk) in oblock.iter_mut().zip(trow) {
                    *o = tk * fb;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The θ rule is converged: doubling the points changes nothing above 1e-14.
    #[test]
    fn theta_quadrature_converged() {
        for n in [2usize, 4, 8, 16] {
            let coarse = theta_table(n, theta_points(n));
            let fine = theta_table(n, 2 * theta_points(n));
            for (a, b) in coarse.iter().zip(&fine) {
                assert!((a - b).abs() < 1e-14, "n={n}: {a} vs {b}");
            }
        }
    }

    /// The φ rule is converged for wedges up to the full circle.
    #[test]
    fn phi_quadrature_converged() {
        for n in [2usize, 4, 8, 16] {
            for dphi in [2.0 * PI / 32.0, PI / 2.0, 2.0 * PI] {
                let a = phi_table(n, dphi, phi_points(n, dphi));
                let b = phi_table(n, dphi, 2 * phi_points(n, dphi));
                for (x, y) in a.iter().zip(&b) {
                    assert!((x - y).abs() < 1e-14, "n={n} dphi={dphi}: {x} vs {y}");
                }
            }
        }
    }

    fn theta_table(n: usize, pts: usize) -> Vec<f64> {
        let (ths, tws) = gauss_legendre_on(0.0, PI, pts);
        let mut t = vec![0.0; n * n * n];
        for (&th, &tw) in ths.iter().zip(&tws) {
            let (st, z) = th.sin_cos();
            let p = legendre::nlp_vec(n, z);
            for l in 0..n {
                for m in 0..=l {
                    for k in 0..n {
                        t[(l * n + m) * n + k] += tw * st * sh::k_lm(l, m) * legendre::assoc_legendre(l, m, z) * p[k];
                    }
                }
            }
        }
        t
    }

    fn phi_table(n: usize, dphi: f64, pts: usize) -> Vec<f64> {
        let (phs, pws) = gauss_legendre_on(0.0, dphi, pts);
        let mut f = vec![0.0; 2 * n * 4];
        for (&ph, &pw) in phs.iter().zip(&pws) {
            let beta = bspline::weights(ph / dphi);
            for m in 0..n {
                for b in 0..4 {
                    f[(2 * m) * 4 + b] += pw * beta[b] * (m as f64 * ph).cos();
                    f[(2 * m + 1) * 4 + b] += pw * beta[b] * (m as f64 * ph).sin();
                }
            }
        }
        f
    }

    #[test]
    fn shapes() {
        assert_eq!((m_lin(4, 0.3).rows, m_lin(4, 0.3).cols), (16, 8));
        // n² × 4n: 16×16 at order 4.
        assert_eq!((m_bspl(4, 0.3).rows, m_bspl(4, 0.3).cols), (16, 16));
        assert_eq!((m_bspl(8, 0.3).rows, m_bspl(8, 0.3).cols), (64, 32));
    }
}
