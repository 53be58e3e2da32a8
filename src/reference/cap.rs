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
//!
//! Sphere blockers (CONVENTIONS.md "Lighting": opaque, they block every ray that intersects
//! them; they do not reflect) are caps too, formed per receiver ([`SphereCaps`]): on each
//! half-plane a sphere blocks exactly its elevation window, and [`gaps`] enumerates what an
//! elevation interval keeps outside a set of windows.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use crate::math::quadrature::gauss_legendre;
use crate::scene::model::{KeyLight, SphereBlocker};

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

/// One sphere blocker seen from a receiver outside it: `C = c − p`, `l = C/‖C‖`,
/// `sin α = r/‖C‖`, `cos α = √((d − r)(d + r))/d`, `q = d² − r² > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereCap {
    pub rel: DVec3,
    pub l: DVec3,
    pub sin_a: f64,
    pub cos_a: f64,
    pub q: f64,
}

impl SphereCap {
    /// The cap's elevation window on the half-plane of azimuth direction `d` ([`cap_window`]).
    pub fn window(&self, d: [f64; 2]) -> Option<(f64, f64)> {
        cap_window(d, self.l.to_array(), self.sin_a, self.cos_a)
    }

    /// Distance (world units) along unit `u` to where the ray enters the sphere, `∞` if it
    /// misses: the near root of `|τu − C| = r`, `τ = q/(u·C + √((u·C)² − q))` (no
    /// cancellation), for `u·C > 0` and `(u·C)² ≥ q` (exactly the directions of the cap).
    pub fn hit(&self, u: DVec3) -> f64 {
        let b = u.dot(self.rel);
        let disc = b * b - self.q;
        if b <= 0.0 || disc < 0.0 {
            return f64::INFINITY;
        }
        self.q / (b + disc.sqrt())
    }
}

/// The sphere blockers of a scene seen from one receiver `p` (docs/accuracy.md §1). A receiver
/// inside a sphere (`‖c − p‖ ≤ r`) is fully blocked: no direct and no indirect light.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphereCaps {
    pub caps: Vec<SphereCap>,
    pub inside: bool,
}

impl SphereCaps {
    pub fn new(spheres: &[SphereBlocker], p: DVec3) -> Self {
        let mut out = Self::default();
        for s in spheres {
            let rel = s.center - p;
            let (d, r) = (rel.length(), s.radius);
            if d <= r {
                out.inside = true;
                continue;
            }
            let q = (d - r) * (d + r);
            out.caps.push(SphereCap { rel, l: rel / d, sin_a: r / d, cos_a: q.sqrt() / d, q });
        }
        out
    }

    /// Every sphere's elevation window on the half-plane of `d`, in order.
    pub fn windows(&self, d: [f64; 2]) -> Vec<Option<(f64, f64)>> {
        self.caps.iter().map(|c| c.window(d)).collect()
    }

    /// Distance (world units) along unit `u` to the nearest sphere it enters, `∞` if none.
    pub fn hit(&self, u: DVec3) -> f64 {
        self.caps.iter().map(|c| c.hit(u)).fold(f64::INFINITY, f64::min)
    }
}

/// The pieces of `[a, b]` outside every window (`None`: an empty one), in ascending order:
/// `f(x, y)` for each. A cursor sweep, no sorting (the shader's `next_gap` is the same): the
/// cursor jumps over the windows holding it, then the gap runs to the nearest window start
/// beyond it (or `b`). At most `windows.len() + 1` gaps.
pub fn gaps(a: f64, b: f64, windows: &[Option<(f64, f64)>], mut f: impl FnMut(f64, f64)) {
    let mut x = a;
    loop {
        // Each window moves the cursor at most once (x only grows), so this ends.
        loop {
            let mut moved = false;
            for &(w0, w1) in windows.iter().flatten() {
                if w0 <= x && x < w1 {
                    x = w1;
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
        if x >= b {
            return;
        }
        let end = windows.iter().flatten().filter(|w| w.0 > x).fold(b, |e, w| e.min(w.0));
        f(x, end);
        x = end;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn gaps_are_the_complement_of_the_windows() {
        let collect = |a: f64, b: f64, w: &[Option<(f64, f64)>]| {
            let mut v = Vec::new();
            gaps(a, b, w, |x, y| v.push((x, y)));
            v
        };
        assert_eq!(collect(0.0, 1.0, &[]), vec![(0.0, 1.0)]);
        assert_eq!(collect(0.0, 1.0, &[None, Some((2.0, 3.0))]), vec![(0.0, 1.0)]);
        // Overlapping, nested and out-of-order windows, one covering the start.
        let w = [Some((0.6, 0.7)), Some((0.2, 0.4)), Some((-1.0, 0.1)), Some((0.3, 0.5)), Some((0.62, 0.65))];
        assert_eq!(collect(0.0, 1.0, &w), vec![(0.1, 0.2), (0.5, 0.6), (0.7, 1.0)]);
        assert!(collect(0.0, 1.0, &[Some((-0.5, 0.5)), Some((0.4, 1.5))]).is_empty());
    }

    #[test]
    fn sphere_hits_are_its_cap() {
        let s = SphereBlocker { center: DVec3::new(3.0, -1.0, 4.0), radius: 0.8, albedo: [0.5; 3] };
        let caps = SphereCaps::new(std::slice::from_ref(&s), DVec3::ZERO);
        assert!(!caps.inside && caps.caps.len() == 1);
        let cap = caps.caps[0];
        for phi in [-0.5f64, -0.32, -0.3, 0.0] {
            let d = [phi.cos(), phi.sin()];
            let w = cap.window(d);
            for k in 0..200 {
                let om = -1.5 + 3.0 * k as f64 / 199.0;
                let u = DVec3::new(om.cos() * d[0], om.cos() * d[1], om.sin());
                let t = cap.hit(u);
                let in_window = w.is_some_and(|(a, b)| a <= om && om <= b);
                if (u.dot(cap.l) - cap.cos_a).abs() > 1e-9 {
                    assert_eq!(t.is_finite(), in_window, "φ {phi} ω {om}");
                }
                if t.is_finite() {
                    assert!(((u * t - cap.rel).length() - s.radius).abs() < 1e-12);
                }
            }
        }
        assert!(SphereCaps::new(std::slice::from_ref(&s), s.center + DVec3::new(0.0, 0.5, 0.0)).inside);
    }
}
