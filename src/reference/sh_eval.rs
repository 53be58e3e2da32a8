//! Allocation-free real SH evaluation for the ground truth's inner loops (the same recurrence
//! as `glsl/inc/hfgi_sh.glsl`, f64, with the `K_l^m` table built once); equals
//! [`crate::math::sh::eval`] to rounding.

use crate::math::sh;

/// `y_k(d)` for `k < n²` into a reused buffer.
pub struct ShBasis {
    n: usize,
    /// `K_l^|m|` (times √2 for `m ≠ 0`) at index `l(l+1) + m`, `m ≥ 0`.
    klm: Vec<f64>,
    pub y: Vec<f64>,
}

impl ShBasis {
    pub fn new(n: usize) -> Self {
        let mut klm = vec![0.0; n * n];
        for l in 0..n {
            for m in 0..=l {
                let f = if m == 0 { 1.0 } else { std::f64::consts::SQRT_2 };
                klm[l * (l + 1) + m] = f * sh::k_lm(l, m);
            }
        }
        Self { n, klm, y: vec![0.0; n * n] }
    }

    /// Fills `self.y` with `y_k(d)`, `d` a unit vector.
    pub fn eval(&mut self, d: [f64; 3]) -> &[f64] {
        let (mut cm, mut sm, mut qmm) = (1.0, 0.0, 1.0);
        for m in 0..self.n {
            let (mut qa, mut qb) = (qmm, 0.0);
            for l in m..self.n {
                let mut q = qmm;
                if l > m {
                    q = ((2 * l - 1) as f64 * d[2] * qa - (l + m - 1) as f64 * qb) / (l - m) as f64;
                    qb = qa;
                    qa = q;
                }
                let c = l * (l + 1);
                if m == 0 {
                    self.y[c] = self.klm[c] * q;
                } else {
                    self.y[c + m] = self.klm[c + m] * q * cm;
                    self.y[c - m] = self.klm[c + m] * q * sm;
                }
            }
            let cn = cm * d[0] - sm * d[1];
            sm = cm * d[1] + sm * d[0];
            cm = cn;
            qmm *= (2 * m + 1) as f64;
        }
        &self.y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equals_sh_eval() {
        for n in [1, 2, 4, 6] {
            let mut b = ShBasis::new(n);
            for d in [[0.0, 0.0, 1.0], [0.6, -0.48, 0.64], [-0.36, 0.48, -0.8], [1.0, 0.0, 0.0]] {
                let want = sh::eval(n, d);
                for (a, w) in b.eval(d).iter().zip(&want) {
                    assert!((a - w).abs() < 1e-13, "n={n} {d:?}: {a} vs {w}");
                }
            }
        }
    }
}
