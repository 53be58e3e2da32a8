//! Legendre polynomials, the normalised Legendre polynomials (NLP) of §4 (eq. 9, 13) and the
//! associated Legendre functions behind the real SH basis.

/// Legendre polynomial `P_l(x)` (Bonnet recurrence).
pub fn legendre(l: usize, x: f64) -> f64 {
    let mut p0 = 1.0;
    if l == 0 {
        return p0;
    }
    let mut p1 = x;
    for k in 2..=l {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    p1
}

/// Normalised Legendre polynomial `P̂_l(z) = sqrt((2l+1)/2)·P_l(z)` (§4, Rodrigues' formula),
/// orthonormal on `[−1, 1]`; `y_l^0(θ, φ) = P̂_l(cosθ)/sqrt(2π)` (eq. 9).
pub fn nlp(l: usize, z: f64) -> f64 {
    ((2 * l + 1) as f64 / 2.0).sqrt() * legendre(l, z)
}

/// The NLP vector `P̂(z) = [P̂_0(z), …, P̂_{n−1}(z)]` (`n` values, l = 0..n), as used for the
/// reconstruction `v(θ) = v̄ · P̂(cosθ)` of eq. 13.
pub fn nlp_vec(n: usize, z: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(n);
    let (mut p0, mut p1) = (1.0, z);
    for l in 0..n {
        let p = match l {
            0 => 1.0,
            1 => z,
            _ => {
                let lf = l as f64;
                let p2 = ((2.0 * lf - 1.0) * z * p1 - (lf - 1.0) * p0) / lf;
                p0 = p1;
                p1 = p2;
                p2
            }
        };
        out.push(((2 * l + 1) as f64 / 2.0).sqrt() * p);
    }
    out
}

/// Associated Legendre function `P_l^m(x)` for `0 ≤ m`, WITHOUT the Condon–Shortley `(−1)^m`
/// factor: `P_m^m(x) = (2m−1)!!·(1−x²)^{m/2}` (so `P_1^1(x) = +sqrt(1−x²)`). Returns 0 for `m > l`.
pub fn assoc_legendre(l: usize, m: usize, x: f64) -> f64 {
    if m > l {
        return 0.0;
    }
    let s = (1.0 - x * x).max(0.0).sqrt();
    let mut pmm = 1.0;
    for k in 0..m {
        pmm *= (2 * k + 1) as f64 * s;
    }
    assoc_from_pmm(l, m, x, pmm)
}

/// The upward recurrence in `l` from `P_m^m = pmm` (shared with the SH evaluation, which seeds it
/// with `(2m−1)!!` to get the polynomial part `P_l^m / (1−x²)^{m/2}`).
pub(crate) fn assoc_from_pmm(l: usize, m: usize, x: f64, pmm: f64) -> f64 {
    if l == m {
        return pmm;
    }
    let mut p0 = pmm;
    let mut p1 = x * (2 * m + 1) as f64 * pmm;
    for k in (m + 2)..=l {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k + m - 1) as f64 * p0) / (k - m) as f64;
        p0 = p1;
        p1 = p2;
    }
    p1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_orders_closed_form() {
        for i in 0..=20 {
            let x = -1.0 + 0.1 * i as f64;
            let s = (1.0 - x * x).max(0.0).sqrt();
            assert!((legendre(2, x) - 0.5 * (3.0 * x * x - 1.0)).abs() < 1e-15);
            assert!((legendre(3, x) - 0.5 * (5.0 * x * x * x - 3.0 * x)).abs() < 1e-15);
            assert!((assoc_legendre(1, 1, x) - s).abs() < 1e-15);
            assert!((assoc_legendre(2, 1, x) - 3.0 * x * s).abs() < 1e-15);
            assert!((assoc_legendre(2, 2, x) - 3.0 * s * s).abs() < 1e-14);
            assert!((assoc_legendre(3, 2, x) - 15.0 * x * s * s).abs() < 1e-13);
            assert!((assoc_legendre(3, 3, x) - 15.0 * s * s * s).abs() < 1e-13);
            assert_eq!(assoc_legendre(2, 3, x), 0.0);
            for l in 0..10 {
                assert!((assoc_legendre(l, 0, x) - legendre(l, x)).abs() < 1e-14);
                assert!((nlp_vec(10, x)[l] - nlp(l, x)).abs() < 1e-14);
            }
            // The paper's order-4 NLP vector (§4).
            let p = nlp_vec(4, x);
            let r2 = 2f64.sqrt();
            let want = [
                1.0 / r2,
                3f64.sqrt() * x / r2,
                5f64.sqrt() * r2 * (3.0 * x * x - 1.0) / 4.0,
                7f64.sqrt() * r2 * (5.0 * x * x * x - 3.0 * x) / 4.0,
            ];
            for l in 0..4 {
                assert!((p[l] - want[l]).abs() < 1e-14);
            }
        }
    }
}
