//! SH triple-product tensor `Γ_ijk = ∫ y_i y_j y_k dω`, used for the SH product of lighting and
//! visibility in direct illumination (§7: "the incident radiance is the SH product of …
//! lighting, L, and the visibility, V").

use super::legendre::assoc_legendre;
use super::quadrature::gauss_legendre;
use super::{check_order, sh};
use std::f64::consts::{PI, SQRT_2};

/// Sparse triple-product tensor of order `n`.
///
/// `entries` holds every ORDERED index triple `(i, j, k)` (all permutations, each distinct
/// permutation once) with `|Γ_ijk| > 1e-12`, so that `Σ_{(i,j,k,g)} g·a_i·b_j` accumulated
/// into `c_k` is the full contraction. Sorted by `(k, i, j)`.
#[derive(Clone, Debug)]
pub struct Triple {
    pub n: usize,
    pub entries: Vec<(u16, u16, u16, f64)>,
}

impl Triple {
    /// `Γ_ijk` (0 if not stored).
    pub fn get(&self, i: usize, j: usize, k: usize) -> f64 {
        let key = (k as u16, i as u16, j as u16);
        self.entries.binary_search_by(|e| (e.2, e.0, e.1).cmp(&key)).map(|p| self.entries[p].3).unwrap_or(0.0)
    }
}

/// Compute the tensor by exact quadrature: the integrand factors into
/// `N_i N_j N_k · P_{l_i}^{|m_i|} P_{l_j}^{|m_j|} P_{l_k}^{|m_k|}(z) · trig_i trig_j trig_k(φ)`.
/// The φ factor (a trigonometric polynomial of degree ≤ 3(n−1)) is integrated exactly by
/// `3n + 2` uniform samples; it vanishes unless `|m_k| = |m_i| ± |m_j|`, in which case the z factor
/// is a polynomial of degree ≤ 3(n−1), integrated exactly by `3n/2 + 2` Gauss–Legendre nodes.
/// Computed once per order and process (the shading's product matrices are rebuilt on every
/// lighting update, docs/direct.md §6) and shared by every caller.
///
/// # Panics
/// If `n ∉ 1..=16` (programmer error).
pub fn triple(n: usize) -> &'static Triple {
    check_order(n);
    static TABLES: [std::sync::OnceLock<Triple>; 16] = [const { std::sync::OnceLock::new() }; 16];
    TABLES[n - 1].get_or_init(|| compute(n))
}

fn compute(n: usize) -> Triple {
    let nn = n * n;
    // Per-coefficient (l, m).
    let lm: Vec<(usize, i32)> = (0..n as i32).flat_map(|l| (-l..=l).map(move |m| (l as usize, m))).collect();

    // z tables: pz[node][i] = N_i · P_l^{|m|}(z_node), weights wz.
    let (zs, wz) = gauss_legendre(3 * n / 2 + 2);
    let pz: Vec<Vec<f64>> = zs
        .iter()
        .map(|&z| {
            lm.iter()
                .map(|&(l, m)| {
                    let ma = m.unsigned_abs() as usize;
                    let norm = if m == 0 { sh::k_lm(l, 0) } else { SQRT_2 * sh::k_lm(l, ma) };
                    norm * assoc_legendre(l, ma, z)
                })
                .collect()
        })
        .collect();

    // φ factor for signed m ∈ (−n, n): cos(mφ) for m ≥ 0, sin(|m|φ) for m < 0.
    let nphi = 3 * n + 2;
    let nm = 2 * n - 1;
    let off = n as i32 - 1;
    let dphi = 2.0 * PI / nphi as f64;
    let trig: Vec<Vec<f64>> = (0..nphi)
        .map(|s| {
            let phi = (s as f64 + 0.5) * dphi;
            (0..nm as i32)
                .map(|mm| {
                    let m = mm - off;
                    if m >= 0 {
                        (m as f64 * phi).cos()
                    } else {
                        (-m as f64 * phi).sin()
                    }
                })
                .collect()
        })
        .collect();
    let mut phi_int = vec![0.0; nm * nm * nm];
    for a in 0..nm {
        for b in 0..nm {
            for c in 0..nm {
                phi_int[(a * nm + b) * nm + c] = trig.iter().map(|t| t[a] * t[b] * t[c]).sum::<f64>() * dphi;
            }
        }
    }

    let mut entries = Vec::new();
    for i in 0..nn {
        for j in i..nn {
            for k in j..nn {
                let (mi, mj, mk) = (lm[i].1 + off, lm[j].1 + off, lm[k].1 + off);
                let ph = phi_int[((mi as usize) * nm + mj as usize) * nm + mk as usize];
                if ph.abs() < 1e-12 {
                    continue;
                }
                let zint: f64 = pz.iter().zip(&wz).map(|(p, w)| w * p[i] * p[j] * p[k]).sum();
                let g = zint * ph;
                if g.abs() <= 1e-12 {
                    continue;
                }
                let mut perms = [(i, j, k), (i, k, j), (j, i, k), (j, k, i), (k, i, j), (k, j, i)];
                perms.sort_unstable();
                for (p, q) in perms.iter().enumerate() {
                    if p > 0 && perms[p - 1] == *q {
                        continue;
                    }
                    entries.push((q.0 as u16, q.1 as u16, q.2 as u16, g));
                }
            }
        }
    }
    entries.sort_unstable_by_key(|e| (e.2, e.0, e.1));
    Triple { n, entries }
}

/// SH product (§7, lighting × visibility): the order-`n` projection of the pointwise product of the
/// functions with coefficients `a` and `b`, `c_k = Σ_ij Γ_ijk a_i b_j` (truncated to order `n`).
///
/// # Panics
/// If `a` or `b` has fewer than `n²` entries (programmer error).
pub fn product(t: &Triple, a: &[f64], b: &[f64]) -> Vec<f64> {
    let nn = t.n * t.n;
    assert!(a.len() >= nn && b.len() >= nn, "triple::product: need {nn} coefficients");
    let mut c = vec![0.0; nn];
    for &(i, j, k, g) in &t.entries {
        c[k as usize] += g * a[i as usize] * b[j as usize];
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let t = triple(4);
        let y0 = 1.0 / (4.0 * PI).sqrt();
        // Γ_{0,k,k} = y_0.
        for k in 0..16 {
            assert!((t.get(0, k, k) - y0).abs() < 1e-14);
        }
        // Γ_{00 20 20}-type: ∫ y_1^0 y_1^0 y_2^0 = 2/sqrt(5)·... = 1/sqrt(5π)
        let g = t.get(sh::index(1, 0), sh::index(1, 0), sh::index(2, 0));
        assert!((g - 1.0 / (5.0 * PI).sqrt()).abs() < 1e-14, "{g}");
    }
}
