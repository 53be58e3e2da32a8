//! Gauss–Legendre quadrature, the workhorse of every reference integral in this crate
//! (NLP projections of eq. 10, the wedge matrices of Appendix A, SH projections).

use std::f64::consts::PI;

/// Gauss–Legendre nodes and weights on `[−1, 1]` for `n` points, nodes in ascending order.
///
/// Nodes are found by Newton iteration on the Legendre polynomial `P_n` (three-term recurrence),
/// starting from Tricomi's asymptotic guess; weights are `2 / ((1 − x²) P_n'(x)²)`. The rule is
/// exact for polynomials of degree `≤ 2n − 1`; nodes and weights are accurate to ~1e-15 for `n`
/// up to 256 (and usable well beyond).
///
/// # Panics
/// If `n == 0` (programmer error).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "gauss_legendre needs at least one point");
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    let nf = n as f64;
    // Roots are symmetric: compute the upper half (descending from ~1) and mirror.
    let half = n.div_ceil(2);
    for i in 0..half {
        // Tricomi initial guess for the i-th largest root.
        let theta = PI * (i as f64 + 0.75) / (nf + 0.5);
        let mut z = (1.0 - (nf - 1.0) / (8.0 * nf * nf * nf)) * theta.cos();
        // Newton to ~1e-15, then one polishing step.
        for _ in 0..100 {
            let (p, d) = legendre_and_derivative(n, z);
            let dz = p / d;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        let (p, d) = legendre_and_derivative(n, z);
        z -= p / d;
        let (_, dp) = legendre_and_derivative(n, z);
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        // Ascending order: the i-th largest root goes to position n−1−i.
        x[n - 1 - i] = z;
        w[n - 1 - i] = wi;
        x[i] = -z;
        w[i] = wi;
    }
    if n % 2 == 1 {
        // The middle root is exactly zero.
        x[n / 2] = 0.0;
    }
    (x, w)
}

/// `P_n(z)` and `P_n'(z)` by the Bonnet recurrence (`|z| < 1`).
fn legendre_and_derivative(n: usize, z: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = z;
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let d = n as f64 * (z * p1 - p0) / (z * z - 1.0);
    (p1, d)
}

/// Nodes and weights of the `n`-point Gauss–Legendre rule mapped to `[a, b]`.
pub fn gauss_legendre_on(a: f64, b: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w) = gauss_legendre(n);
    let h = 0.5 * (b - a);
    let c = 0.5 * (b + a);
    (x.iter().map(|t| c + h * t).collect(), w.iter().map(|wi| h * wi).collect())
}

/// `∫_a^b f(x) dx` by the `n`-point Gauss–Legendre rule (exact for degree `≤ 2n − 1`).
///
/// # Panics
/// If `n == 0` (programmer error).
pub fn integrate(a: f64, b: f64, n: usize, f: impl Fn(f64) -> f64) -> f64 {
    let (x, w) = gauss_legendre_on(a, b, n);
    x.iter().zip(&w).map(|(&xi, &wi)| wi * f(xi)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_two_and_polynomials_exact() {
        for n in [1usize, 2, 3, 5, 8, 17, 64, 128, 256] {
            let (x, w) = gauss_legendre(n);
            let s: f64 = w.iter().sum();
            assert!((s - 2.0).abs() < 1e-13, "n={n} sum={s}");
            assert!(x.windows(2).all(|p| p[0] < p[1]));
            // ∫ x^k over [-1,1] for k ≤ 2n−1, up to degree 40.
            for k in 0..(2 * n).min(40) {
                let q: f64 = x.iter().zip(&w).map(|(xi, wi)| wi * xi.powi(k as i32)).sum();
                let exact = if k % 2 == 1 { 0.0 } else { 2.0 / (k as f64 + 1.0) };
                assert!((q - exact).abs() < 1e-14, "n={n} k={k} q={q} exact={exact}");
            }
        }
    }

    #[test]
    fn nodes_are_roots_to_machine_precision() {
        for n in [16usize, 100, 256] {
            let (x, _) = gauss_legendre(n);
            for &xi in &x {
                let (p, d) = legendre_and_derivative(n, xi);
                assert!((p / d).abs() < 1e-15, "n={n} x={xi} step={}", p / d);
            }
        }
    }

    #[test]
    fn integrate_smooth() {
        let v = integrate(0.0, PI, 32, f64::sin);
        assert!((v - 2.0).abs() < 1e-14);
        let v = integrate(-1.0, 1.0, 256, |x| (50.0 * x).cos());
        assert!((v - 2.0 * 50f64.sin() / 50.0).abs() < 1e-14);
        let v = integrate(-1.0, 2.0, 40, f64::exp);
        assert!((v - (2f64.exp() - (-1f64).exp())).abs() < 1e-13);
    }
}
