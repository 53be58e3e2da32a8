//! Local lights (spheres) in the ground truth (CONVENTIONS.md "Lighting" and "Accuracy": a
//! direction sees a local light iff its ray reaches the sphere before the height field;
//! docs/accuracy.md §1). f64, CPU; the GPU twin is the `cap = 2` mode of
//! `glsl/reference/truth.comp.glsl`.
//!
//! Per receiver `p = (i·s, j·s, H[j][i])` and light (centre `c`, radius `r`, radiance `L`):
//! `C = c − p`, `d = ‖C‖`, `l = C/d`, `sin α = r/d`, `cos α = √((d − r)(d + r))/d`. The cap is
//! integrated like a key light's ([`super::cap`]): its azimuth samples
//! ([`cap_azimuths_toward`]: Gauss–Legendre in `φ = φ_c + β sin u` over `cap_nodes` points, or
//! the `A` uniform azimuths when the cap holds a pole), on each its elevation window
//! ([`cap_window`]) intersected with `[ω_t, π/2]` (`ω_t` the tangent elevation), and
//! `L·(N·ω)·cos ω` integrated by `nodes`-point Gauss–Legendre. Visibility per direction:
//!
//! - above the horizon `ω_hor` of the azimuth's ray the direction escapes, so it sees the light:
//!   the part of the window above `ω_hor` gets its own Gauss–Legendre nodes, all counted (the
//!   window is split at `ω_hor`, where visibility usually jumps: a light behind a ridge);
//! - below `ω_hor` (the part `[lo, min(hi, ω_hor)]`, its own nodes) a node counts iff the first
//!   hit of its ray with the height field, planar distance `t_hit` texels, lies beyond the
//!   sphere entry, `t_hit > t_s = τ·cos ω / s`, `τ = (d² − r²)/(u·C + √((u·C)² − (d² − r²)))`
//!   (the near root of `|τu − C| = r`, without cancellation; `u` the unit ray), or the ray
//!   escapes. The azimuth's ray is traced once (pieces, or the march's samples with `march`)
//!   for the horizon and the first hits.
//!
//! A receiver inside the sphere (`d ≤ r`) takes the limit at `d = r` (the rule the pipeline
//! uses, `glsl/shade/local.comp.glsl`): `sin α = 1`, `cos α = 0` — the cap is the hemisphere
//! toward `c` (toward +z when `d = 0`) — and the sphere entry distance is 0: no terrain blocks
//! any of its directions. Directions below the receiver's tangent plane never count.
//!
//! Sphere blockers ([`SphereCaps`]; CONVENTIONS.md "Accuracy": a direction sees a local light
//! iff its ray reaches the light sphere before the height field or a blocker): node by node,
//! above the horizon as below it, a node is dropped when its ray enters a blocker before the
//! light, `τ_blocker < τ_light` (3D distances; `τ_light = 0` for a receiver inside the light,
//! which no blocker can then hide). A receiver inside a blocker sees no local light.
//!
//! The result is the irradiance `E = Σ_lights L ∫ visible max(N·ω, 0) dω` (RGB); the reference
//! adds `ρ/π · E` to the direct exit radiance of both variants, before the bounces take it
//! as their source. The SH-visibility variant includes local lights exactly like this: their
//! cap differs per receiver, so they have no fixed SH projection to multiply with `V`.

use std::f64::consts::FRAC_PI_2;

use glam::DVec3;

use super::cap::{cap_azimuths_toward, cap_window, SphereCaps};
use super::ray::{first_hits, Surface};
use super::truth::{direction, nodes_on, tangent_elevation, Profile, TruthSettings};
use crate::scene::model::{LocalLight, SphereBlocker};

/// The cap a local light subtends from one receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalCap {
    /// `C = c − p`, world units.
    pub rel: DVec3,
    /// Unit direction toward the centre (+z when `p` is the centre).
    pub l: DVec3,
    pub sin_a: f64,
    pub cos_a: f64,
    /// `d² − r² = (d − r)(d + r)`, world units² (≤ 0 inside).
    pub q: f64,
    /// The receiver is inside the sphere (`d ≤ r`): the hemisphere toward `c`, unblocked.
    pub inside: bool,
}

impl LocalCap {
    /// The cap of `light` from world point `p`.
    pub fn new(light: &LocalLight, p: DVec3) -> Self {
        let rel = light.position - p;
        let (d, r) = (rel.length(), light.radius);
        let l = if d > 0.0 { rel / d } else { DVec3::Z };
        let q = (d - r) * (d + r);
        if d <= r {
            return Self { rel, l, sin_a: 1.0, cos_a: 0.0, q, inside: true };
        }
        Self { rel, l, sin_a: r / d, cos_a: q.sqrt() / d, q, inside: false }
    }

    /// Planar distance (texels, texel size `s`) from the receiver to where the ray along unit
    /// `u` (elevation cosine `cos_om`) enters the sphere; 0 inside.
    pub fn entry(&self, u: DVec3, cos_om: f64, s: f64) -> f64 {
        self.reach(u) * cos_om / s
    }

    /// Distance (world units) along unit `u` (a direction of the cap) to where the ray enters
    /// the sphere; 0 inside.
    pub fn reach(&self, u: DVec3) -> f64 {
        if self.inside {
            return 0.0;
        }
        let b = u.dot(self.rel);
        let disc = (b * b - self.q).max(0.0);
        self.q / (b + disc.sqrt())
    }
}

/// The local lights of a reference run, with what their integrals share.
pub struct LocalTruth<'a> {
    pub lights: &'a [LocalLight],
    pub settings: &'a TruthSettings,
    pub surf: Surface<'a>,
    pub texel_size: f64,
    /// Per-texel CONVENTIONS.md normals.
    pub nrm: &'a [[f64; 3]],
    /// Gauss–Legendre nodes and weights on `[−1, 1]` (`settings.nodes`).
    pub gauss: &'a (Vec<f64>, Vec<f64>),
    /// The scene's sphere blockers.
    pub spheres: &'a [SphereBlocker],
}

impl LocalTruth<'_> {
    /// `E = Σ_lights L ∫_{visible cap} max(N·ω, 0) dω` (RGB) at texel `(i, j)`.
    pub fn irradiance(&self, i: usize, j: usize) -> [f64; 3] {
        let mut e = [0.0; 3];
        for light in self.lights {
            let g = self.light(light, i, j);
            for (ec, r) in e.iter_mut().zip(&light.radiance) {
                *ec += g * r;
            }
        }
        e
    }

    /// `∫_{visible cap} max(N·ω, 0) dω` of one light at texel `(i, j)`.
    pub fn light(&self, light: &LocalLight, i: usize, j: usize) -> f64 {
        let (surf, s) = (&self.surf, self.texel_size);
        let k = j * surf.width + i;
        let p = DVec3::new(i as f64 * s, j as f64 * s, surf.heights[k]);
        let spheres = SphereCaps::new(self.spheres, p);
        if spheres.inside {
            return 0.0;
        }
        let cap = LocalCap::new(light, p);
        let (nrm, nv) = (self.nrm[k], DVec3::from_array(self.nrm[k]));
        let l = cap.l.to_array();
        // The ray along u enters a blocker before the light.
        let hidden = |u: DVec3| spheres.hit(u) < cap.reach(u);
        // ∫ over [a, b] of (N·ω) cos ω, every node that no blocker hides.
        let open = |phi: f64, a: f64, b: f64| -> f64 {
            nodes_on(self.gauss, a, b)
                .map(|(om, wt)| {
                    let u = direction(om, phi);
                    if hidden(u) {
                        0.0
                    } else {
                        wt * om.cos() * nv.dot(u).max(0.0)
                    }
                })
                .sum()
        };
        let mut sum = 0.0;
        for (phi, wphi) in cap_azimuths_toward(cap.l, cap.sin_a, self.settings.azimuths, self.settings.cap_nodes) {
            let d = [phi.cos(), phi.sin()];
            // Inside, the window is the half-plane's half toward `c`: `|ω − ω_c| ≤ π/2` exactly
            // (cap_window's formula is 0/0 where the half-plane is perpendicular to `l`).
            let window = if cap.inside {
                let wc = l[2].atan2(d[0] * l[0] + d[1] * l[1]);
                Some((wc - FRAC_PI_2, wc + FRAC_PI_2))
            } else {
                cap_window(d, l, cap.sin_a, cap.cos_a)
            };
            let Some((w0, w1)) = window else { continue };
            let (lo, hi) = (w0.max(tangent_elevation(nrm, phi)), w1.min(FRAC_PI_2));
            if hi <= lo {
                continue;
            }
            if cap.inside {
                sum += wphi * open(phi, lo, hi);
                continue;
            }
            let prof = Profile::trace(surf, i, j, phi, self.settings);
            let hor = prof.horizon(s);
            let lo_open = lo.max(hor);
            if hi > lo_open {
                sum += wphi * open(phi, lo_open, hi);
            }
            let hi_below = hi.min(hor);
            if hi_below > lo {
                let nodes: Vec<(f64, f64)> = nodes_on(self.gauss, lo, hi_below).collect();
                let omegas: Vec<f64> = nodes.iter().map(|v| v.0).collect();
                let t_hit = hit_distances(&prof, &omegas, s, i, j);
                for (e, &(om, wt)) in nodes.iter().enumerate() {
                    let u = direction(om, phi);
                    if t_hit.get(e).map_or(true, |&t| t > cap.entry(u, om.cos(), s)) && !hidden(u) {
                        sum += wphi * wt * om.cos() * nv.dot(u).max(0.0);
                    }
                }
            }
        }
        sum
    }
}

/// Planar distances (texels) of the first hits of the ascending elevations `omegas` along
/// `prof` (receiver vertex `(i, j)`, texel size `s`), ending before the first that escapes.
fn hit_distances(prof: &Profile, omegas: &[f64], s: f64, i: usize, j: usize) -> Vec<f64> {
    match prof {
        Profile::Exact { pieces, .. } => {
            let k: Vec<f64> = omegas.iter().map(|om| om.tan() * s).collect();
            first_hits(pieces, &k)
        }
        Profile::March(_) => prof.hits(omegas, s).iter().map(|q| (q[0] - i as f64).hypot(q[1] - j as f64)).collect(),
    }
}

/// A local light's azimuth substitution for the GPU (`φ = φ_c + β·x`, weight `β·w`): per
/// Gauss–Legendre node `u_k` of `[−π/2, π/2]` (`cap_nodes` points), `(sin u_k, π/2·w_k·cos u_k)`
/// — the factors of [`cap_azimuths_toward`] that do not depend on the receiver.
pub fn cap_node_factors(cap_nodes: u32) -> Vec<(f64, f64)> {
    let (x, w) = crate::math::quadrature::gauss_legendre(cap_nodes as usize);
    x.iter()
        .zip(&w)
        .map(|(x, w)| {
            let u = FRAC_PI_2 * x;
            (u.sin(), FRAC_PI_2 * w * u.cos())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_distance_is_the_near_root() {
        let light = LocalLight { position: DVec3::new(3.0, -1.0, 4.0), radius: 0.5, radiance: [1.0; 3] };
        let cap = LocalCap::new(&light, DVec3::ZERO);
        for (om, phi) in [(0.9f64, -0.3f64), (0.95, -0.32), (0.92, -0.28)] {
            let u = direction(om, phi);
            let s = 0.5;
            let t = cap.entry(u, om.cos(), s);
            // The 3D point at planar distance t·s lies on the sphere.
            let tau = t * s / om.cos();
            let dist = (u * tau - cap.rel).length();
            assert!((dist - light.radius).abs() < 1e-12, "{om} {phi}: {dist}");
        }
        let inside = LocalCap::new(&light, light.position + DVec3::new(0.1, 0.0, 0.0));
        assert!(inside.inside && inside.sin_a == 1.0 && inside.entry(DVec3::Z, 0.0, 1.0) == 0.0);
        assert_eq!(LocalCap::new(&light, light.position).l, DVec3::Z);
    }
}
