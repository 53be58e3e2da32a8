//! `product_matrix` (the lighting as a matrix on V) against sphere quadrature.
use super::*;
use crate::math::sh;

/// `T_k = Σ_j V_j M[j][k]` is the order-n projection of the product of the two band-limited
/// functions L(ω)·V(ω), computed here by sphere quadrature (exact for these degrees), not
/// from the triple tensor: orders 1, 2, 4 and 6, one colour channel per random lighting.
#[test]
fn the_product_matrix_applied_to_v_is_the_projection_of_l_times_v() {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for n in [1usize, 2, 4, 6] {
        let n2 = n * n;
        let l: Vec<[f64; 3]> = (0..n2).map(|_| [next(), next(), next()]).collect();
        let v: Vec<f64> = (0..n2).map(|_| next()).collect();
        let m = product_matrix(triple::triple(n), &l);
        for c in 0..3 {
            let lc: Vec<f64> = l.iter().map(|x| x[c]).collect();
            let exact = sh::project(n, |d| sh::reconstruct(n, &lc, d) * sh::reconstruct(n, &v, d), 2 * n + 2);
            for k in 0..n2 {
                let t: f64 = (0..n2).map(|j| v[j] * m[j * n2 + k][c]).sum();
                assert!((t - exact[k]).abs() < 1e-10, "order {n}, channel {c}, k {k}: {t} vs {}", exact[k]);
            }
        }
    }
}
