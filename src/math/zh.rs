//! Zonal harmonics (functions symmetric about +z), stored as one coefficient per band:
//! `f(θ) = Σ_l z_l · y_l^0(θ)`. Used for the BRDF lobes of §7 and for key lights (spherical caps).

use super::legendre::legendre;
use super::quadrature::gauss_legendre_on;
use super::{check_order, sh};
use std::f64::consts::PI;

/// Rotate a ZH vector so that its axis +z maps to the direction `d` (normalised internally):
/// `c_l^m = sqrt(4π/(2l+1)) · z_l · y_l^m(d)` (CONVENTIONS; the "efficient rotation" of §7,
/// \[SLS05\]). Returns `n²` SH coefficients.
///
/// # Panics
/// If `n ∉ 1..=16`, `zh.len() < n`, or `d` is zero / not finite (programmer errors).
pub fn rotate(n: usize, zh: &[f64], d: [f64; 3]) -> Vec<f64> {
    check_order(n);
    assert!(zh.len() >= n, "zh::rotate: need {n} ZH coefficients, got {}", zh.len());
    let mut y = sh::eval(n, d);
    for (l, &zl) in zh.iter().enumerate().take(n) {
        let s = (4.0 * PI / (2 * l + 1) as f64).sqrt() * zl;
        let li = l as i32;
        for m in -li..=li {
            y[sh::index(li, m)] *= s;
        }
    }
    y
}

/// `2π · sqrt((2l+1)/(4π))`: converts `∫ g(t) P_l(t) dt` over `t = cosθ` into the ZH coefficient
/// `∫ g(cosθ) y_l^0 dω` of a function symmetric about +z.
fn zh_scale(l: usize) -> f64 {
    2.0 * PI * ((2 * l + 1) as f64 / (4.0 * PI)).sqrt()
}

/// ZH of the clamped cosine `max(cosθ, 0)` for bands `0..n` (the diffuse lobe of §7):
/// `z_l = 2π·sqrt((2l+1)/(4π)) ∫_0^1 t P_l(t) dt`, by Gauss–Legendre quadrature that is exact for
/// the degree-`l+1` polynomial. Order 4: `{0.886227, 1.023327, 0.495416, 0}`
/// (`√π/2, √(π/3), √(5π)/8, 0`); odd bands `l ≥ 3` are zero.
pub fn clamped_cosine(n: usize) -> Vec<f64> {
    check_order(n);
    let (t, w) = gauss_legendre_on(0.0, 1.0, n / 2 + 2);
    (0..n)
        .map(|l| {
            let i: f64 = t.iter().zip(&w).map(|(&t, &w)| w * t * legendre(l, t)).sum();
            let z = zh_scale(l) * i;
            // Odd bands above 1 vanish exactly; drop the rounding residue.
            if l >= 3 && l % 2 == 1 {
                0.0
            } else {
                z
            }
        })
        .collect()
}

/// ZH of the cosine `cosθ` itself, unclamped, for bands `0..n`: only band 1,
/// `z_1 = 2π·sqrt(3/(4π))·2/3 = 2·sqrt(π/3)`, twice the clamped cosine's. Dotted with incident
/// radiance that is zero below the tangent plane it gives the same irradiance as the whole
/// clamped lobe, with nothing truncated (docs/accuracy.md §6).
pub fn cosine(n: usize) -> Vec<f64> {
    check_order(n);
    (0..n).map(|l| if l == 1 { 2.0 * (PI / 3.0).sqrt() } else { 0.0 }).collect()
}

/// Phong lobe of exponent `s` (§7): the paper's ZH `{1, e^(−1/(2S)), e^(−2/S), e^(−9/(2S))}`,
/// i.e. `z_l = e^(−l²/(2S))` for `l = 0..n`, about the reflection vector.
///
/// These are NOT normalised ZH coefficients: they are the Ramamoorthi–Hanrahan \[RH02\]
/// attenuation factors `A_l / A_0` of a normalised Phong lobe (Gaussian approximation). Use them
/// by scaling the lighting's (or the incident radiance's) own band-`l` coefficients, i.e.
/// glossy radiance `≈ Σ_l z_l Σ_m L_l^m y_l^m(R)` for reflection direction `R`; to dot them with
/// an SH vector as a rotated ZH, multiply each by `sqrt((2l+1)/(4π))` first
/// (`rotate(n, &[z_l·sqrt((2l+1)/(4π))], R)·L = Σ z_l L_l^m y_l^m(R)`).
///
/// # Panics
/// If `n ∉ 1..=16` or `s` is not a positive finite number (programmer errors).
pub fn phong(n: usize, s: f64) -> Vec<f64> {
    check_order(n);
    assert!(s > 0.0 && s.is_finite(), "zh::phong: exponent must be positive and finite, got {s}");
    (0..n).map(|l| (-((l * l) as f64) / (2.0 * s)).exp()).collect()
}

/// ZH of the indicator of the spherical cap `θ ≤ alpha` about +z (key lights, CONVENTIONS
/// "Lighting"): `z_l = 2π·sqrt((2l+1)/(4π)) ∫_{cos α}^1 P_l(t) dt`, in closed form
/// `∫_x^1 P_0 = 1 − x`, `∫_x^1 P_l = (P_{l−1}(x) − P_{l+1}(x))/(2l+1)` for `l ≥ 1`.
/// `alpha` is clamped to `[0, π]`.
pub fn cap(n: usize, alpha: f64) -> Vec<f64> {
    check_order(n);
    let x = alpha.clamp(0.0, PI).cos();
    (0..n)
        .map(|l| {
            let i = if l == 0 { 1.0 - x } else { (legendre(l - 1, x) - legendre(l + 1, x)) / (2 * l + 1) as f64 };
            zh_scale(l) * i
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unclamped cosine's ZH by quadrature over the whole `[−1, 1]`: band 1 only, twice the
    /// clamped cosine's band 1.
    #[test]
    fn cosine_is_band_one_twice_the_clamped_cosines() {
        let (t, w) = gauss_legendre_on(-1.0, 1.0, 8);
        let (cos, cc) = (cosine(6), clamped_cosine(6));
        for (l, z) in cos.iter().enumerate() {
            let want = zh_scale(l) * t.iter().zip(&w).map(|(&t, &w)| w * t * legendre(l, t)).sum::<f64>();
            assert!((z - want).abs() < 1e-12, "band {l}: {z} against {want}");
        }
        assert!((cos[1] - 2.0 * cc[1]).abs() < 1e-12);
    }

    #[test]
    fn cap_matches_thesis_closed_form() {
        // SN08 thesis k0..k3 (see SEED-NOTES 002).
        for a in [0.1, 0.5, 1.0, 2.0] {
            let c: f64 = f64::cos(a);
            let s2 = 1.0 - c * c;
            let want = [
                PI.sqrt() * (1.0 - c),
                0.5 * (3.0 * PI).sqrt() * s2,
                0.5 * (5.0 * PI).sqrt() * c * s2,
                (7.0 * PI).sqrt() / 8.0 * s2 * (5.0 * c * c - 1.0),
            ];
            let z = cap(4, a);
            for l in 0..4 {
                assert!((z[l] - want[l]).abs() < 1e-14, "a={a} l={l} {} {}", z[l], want[l]);
            }
        }
    }
}
