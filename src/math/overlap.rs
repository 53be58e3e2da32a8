//! Solid angle of the intersection of two spherical caps (a key light and a sphere blocker's
//! shadow cap; `gi.blocker_key_lights = "overlap"`, docs/blockers.md §3).
//!
//! Caps of angular radii `a`, `b` whose centres are `γ` apart overlap in a lens bounded by two
//! circle arcs that meet at `X` and `X'`. Its area is the two circular sectors minus the kite
//! `A X B X'` (the spherical analogue of the planar lens formula `r₁²φ₁ + r₂²φ₂ − d r₁ sin φ₁`):
//!
//! `Ω = 2φ_a (1 − cos a) + 2φ_b (1 − cos b) − 2 E(A X B)`,
//!
//! `φ_a` the angle at `A` between `AB` and `AX` (spherical law of cosines in haversine form,
//! `hav φ_a = (hav b − hav(a − γ)) / (sin a sin γ)`, stable for small angles), `E` the spherical
//! excess of the triangle with sides `a`, `b`, `γ` (L'Huilier's formula, stable for small
//! triangles). `1 − cos x = 2 sin²(x/2)` throughout, so a 0.5° sun keeps its digits in f32 too
//! (the GPU twin is `hfgi_cap_overlap` in `glsl/shade/direct.comp.glsl`).

use std::f64::consts::PI;

fn hav(x: f64) -> f64 {
    let s = (0.5 * x).sin();
    s * s
}

/// Solid angle of the intersection of the caps of angular radii `a`, `b` (in `[0, π]`) whose
/// centres are `gamma` apart (in `[0, π]`).
pub fn cap_overlap(a: f64, b: f64, gamma: f64) -> f64 {
    let cap = |x: f64| 4.0 * PI * hav(x);
    if gamma >= a + b {
        return 0.0;
    }
    if gamma <= (a - b).abs() {
        return cap(a.min(b));
    }
    if a + b + gamma >= 2.0 * PI {
        // Both caps cover everything but the parts outside the other: Ω = Ω_a + Ω_b − 4π.
        return cap(a) + cap(b) - 4.0 * PI;
    }
    let angle = |r: f64, o: f64| -> f64 {
        // The angle at the centre of the cap of radius r toward X, opposite side o.
        let h = ((hav(o) - hav(r - gamma)) / (r.sin() * gamma.sin())).clamp(0.0, 1.0);
        2.0 * h.sqrt().asin()
    };
    let (pa, pb) = (angle(a, b), angle(b, a));
    let s = 0.5 * (a + b + gamma);
    let t = |x: f64| (0.5 * x).tan().max(0.0);
    let excess = 4.0 * (t(s) * t(s - a) * t(s - b) * t(s - gamma)).sqrt().atan();
    (4.0 * pa * hav(a) + 4.0 * pb * hav(b) - 2.0 * excess).max(0.0)
}

/// The fraction of a key light's cap (unit direction `dir`, angular radius `alpha`) that the
/// spheres `(centre relative to the receiver, radius)` leave open, seen from the receiver:
/// `Π_i (1 − Ω(light ∩ sphere_i)/Ω_light)` (exact for one sphere; for several it treats their
/// shadows as independent), 0 inside a sphere.
pub fn unoccluded_fraction(dir: [f64; 3], alpha: f64, spheres: &[([f64; 3], f64)]) -> f64 {
    let light = 4.0 * PI * hav(alpha);
    let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let l = len(dir);
    let mut t = 1.0;
    for &(c, r) in spheres {
        let d = len(c);
        if d <= r {
            return 0.0;
        }
        let cosg = ((c[0] * dir[0] + c[1] * dir[1] + c[2] * dir[2]) / (d * l)).clamp(-1.0, 1.0);
        // γ by atan2 of |c × dir| and c·dir (accurate for small angles, unlike acos).
        let cr = [c[1] * dir[2] - c[2] * dir[1], c[2] * dir[0] - c[0] * dir[2], c[0] * dir[1] - c[1] * dir[0]];
        let gamma = (len(cr) / (d * l)).atan2(cosg);
        t *= 1.0 - (cap_overlap(alpha, (r / d).asin(), gamma) / light).min(1.0);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against Monte Carlo-free brute force: the fraction of a fine Fibonacci lattice of
    /// directions inside both caps (4·10⁶ points; independent of the formula).
    #[test]
    fn overlap_against_a_direction_lattice() {
        let count = 4_000_000usize;
        let golden = PI * (3.0 - 5f64.sqrt());
        let dirs: Vec<[f64; 3]> = (0..count)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
                let r = (1.0 - z * z).sqrt();
                let p = golden * i as f64;
                [r * p.cos(), r * p.sin(), z]
            })
            .collect();
        let mut worst = 0f64;
        for (a, b, g) in [
            (0.3f64, 0.5f64, 0.6f64),
            (0.5, 0.3, 0.6),
            (0.2, 0.2, 0.1),
            (1.0, 0.4, 1.2),
            (1.4, 1.3, 2.0),
            (0.3, 1.2, 1.4),
            (0.05, 0.4, 0.42),
            (1.5, 1.5, 0.5),
            (2.0, 1.5, 2.5),
        ] {
            let (ca, cb) = ([0.0, 0.0, 1.0], [g.sin(), 0.0, g.cos()]);
            let dot = |u: &[f64; 3], v: &[f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
            let inside = dirs.iter().filter(|d| dot(d, &ca) >= a.cos() && dot(d, &cb) >= b.cos()).count();
            let want = 4.0 * PI * inside as f64 / count as f64;
            let got = cap_overlap(a, b, g);
            let err = (got - want).abs() / (4.0 * PI * hav(a.min(b)));
            eprintln!("a={a} b={b} γ={g}: {got:.6} vs lattice {want:.6} (error {err:.1e} of the smaller cap)");
            worst = worst.max(err);
        }
        assert!(worst < 2e-3, "{worst}");
    }

    /// Small caps (a 0.5° sun behind a 2° limb): the formula against the planar lens area,
    /// which it must approach as the caps shrink (relative difference O(angle²)).
    #[test]
    fn small_caps_approach_the_planar_lens() {
        let (a, b) = (0.5f64.to_radians(), 2f64.to_radians());
        for g in [1.6, 2.0, 2.3, 2.45] {
            let g = f64::to_radians(g);
            let pa = ((a * a + g * g - b * b) / (2.0 * a * g)).acos();
            let pb = ((b * b + g * g - a * a) / (2.0 * b * g)).acos();
            let planar = a * a * pa + b * b * pb - g * a * pa.sin();
            let got = cap_overlap(a, b, g);
            assert!(((got - planar) / planar).abs() < 1e-3, "γ={g}: {got} vs {planar}");
        }
        assert_eq!(cap_overlap(a, b, 3f64.to_radians()), 0.0);
        assert!((cap_overlap(a, b, 1f64.to_radians()) - 4.0 * PI * hav(a)).abs() < 1e-15);
    }
}
