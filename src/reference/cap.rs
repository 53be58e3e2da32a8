//! Key lights as true caps in the exact ground truth (CONVENTIONS.md "Accuracy": a direction
//! sees a key light iff it lies in the cap and escapes; docs/accuracy.md §1).
//!
//! A cap of unit direction `l` (elevation `e`, azimuth `φ_c`) and angular radius `α` is
//! integrated azimuth by azimuth. If it holds no pole (`cos e > sin α`) it spans the azimuths
//! `[φ_c − β, φ_c + β]`, `β = asin(sin α / cos e)`; the substitution `φ = φ_c + β·sin u`, `u`
//! Gauss–Legendre on `[−π/2, π/2]`, removes the square-root ends of its chord length. A cap
//! holding a pole is seen on every azimuth: the `A` uniform azimuths of the full circle. On
//! the half-plane of azimuth `φ` (`d = (cos φ, sin φ)`) the cap is the elevation window
//! `|ω − ω_c| ≤ δ`, from `dir(ω)·l = R cos(ω − ω_c)`, `R = √((d·l_xy)² + l_z²)`,
//! `ω_c = atan2(l_z, d·l_xy)`, `cos δ = cos α / R`.

use std::f64::consts::{FRAC_PI_2, PI};

use crate::math::quadrature::gauss_legendre;
use crate::scene::model::KeyLight;

/// The azimuth samples `(φ, weight)` of one key light's cap (the weights sum to the cap's
/// azimuth range). `azimuths`: the uniform count for a cap holding a pole; `nodes`: the
/// Gauss–Legendre nodes of the substitution otherwise.
pub fn cap_azimuths(key: &KeyLight, azimuths: u32, nodes: u32) -> Vec<(f64, f64)> {
    cap_azimuths_toward(key.direction.normalize(), key.angular_radius.sin(), azimuths, nodes)
}

/// [`cap_azimuths`] of the cap toward unit direction `l` with `sin α = sin_a` (a local light
/// seen from one receiver: `l = (c − p)/‖c − p‖`, `sin α = r/‖c − p‖`; docs/local-lights.md).
pub fn cap_azimuths_toward(l: glam::DVec3, sin_a: f64, azimuths: u32, nodes: u32) -> Vec<(f64, f64)> {
    let cos_e = l.x.hypot(l.y);
    if cos_e <= sin_a {
        let dphi = 2.0 * PI / azimuths as f64;
        return (0..azimuths).map(|a| ((a as f64 + 0.5) * dphi, dphi)).collect();
    }
    let phi_c = l.y.atan2(l.x);
    let beta = (sin_a / cos_e).min(1.0).asin();
    let (x, w) = gauss_legendre(nodes as usize);
    x.iter()
        .zip(&w)
        .map(|(x, w)| {
            let u = FRAC_PI_2 * x;
            (phi_c + beta * u.sin(), FRAC_PI_2 * w * beta * u.cos())
        })
        .collect()
}

/// The cap's elevation window `[ω_c − δ, ω_c + δ]` on the half-plane of azimuth direction `d`
/// (`None` where the half-plane misses the cap). `δ` comes from `sin²(δ/2) = (R − cos α)/(2R)`
/// with `R² − cos²α = sin²α − (d × l_xy)²`, which keeps small caps accurate (in f32 too).
pub fn cap_window(d: [f64; 2], l: [f64; 3], sin_a: f64, cos_a: f64) -> Option<(f64, f64)> {
    let dl = d[0] * l[0] + d[1] * l[1];
    let cross = d[0] * l[1] - d[1] * l[0];
    let x = sin_a * sin_a - cross * cross;
    if x < 0.0 {
        return None;
    }
    let r = dl.hypot(l[2]);
    let delta = 2.0 * (x / ((r + cos_a) * 2.0 * r)).sqrt().min(1.0).asin();
    let wc = l[2].atan2(dl);
    Some((wc - delta, wc + delta))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn key(e: f64, az: f64, alpha: f64) -> KeyLight {
        KeyLight {
            direction: DVec3::new(e.cos() * az.cos(), e.cos() * az.sin(), e.sin()),
            angular_radius: alpha,
            radiance: [1.0; 3],
        }
    }

    /// ∫ over the cap of cos ω dω dφ = its solid angle 2π(1 − cos α).
    #[test]
    fn cap_solid_angle() {
        let (x, w) = gauss_legendre(16);
        for (e, az, alpha) in [(0.7, 0.4, 0.1), (0.2, 3.0, 0.6), (1.4, -1.0, 0.3), (-0.3, 2.0, 0.05), (0.1, 1.0, 1.5)] {
            let k = key(e, az, alpha);
            let l = k.direction.to_array();
            let mut omega = 0.0;
            for (phi, wphi) in cap_azimuths(&k, 1024, 64) {
                if let Some((lo, hi)) = cap_window([phi.cos(), phi.sin()], l, alpha.sin(), alpha.cos()) {
                    let (lo, hi) = (lo.max(-FRAC_PI_2), hi.min(FRAC_PI_2));
                    if hi > lo {
                        for (x, wx) in x.iter().zip(&w) {
                            let om = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x;
                            omega += wphi * 0.5 * (hi - lo) * wx * om.cos();
                        }
                    }
                }
            }
            let want = 2.0 * PI * (1.0 - alpha.cos());
            let tol = if e.cos() <= alpha.sin() { 1e-4 } else { 1e-10 };
            assert!(((omega - want) / want).abs() < tol, "e={e} α={alpha}: {omega} vs {want}");
        }
    }
}
