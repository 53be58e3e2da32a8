//! The reference's per-texel integrals: what they share ([`Setup`]) and one texel's accumulators.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use super::{bilinear, direction, nodes_on, tangent_elevation, Profile, TruthSettings};
use crate::reference::cap::{cap_azimuths_toward, cap_window, gaps, SphereCaps};
use crate::reference::ray::Surface;
use crate::reference::sh_eval::ShBasis;
use crate::scene::model::{KeyLight, Scene};

/// Everything the per-texel integrals share.
pub(super) struct Setup<'a> {
    pub(super) scene: &'a Scene,
    pub(super) settings: &'a TruthSettings,
    pub(super) heights: Vec<f64>,
    pub(super) nrm: Vec<[f64; 3]>,
    /// Environment SH (exact) or environment + key-light SH (SH-visibility).
    pub(super) light: Vec<[f64; 3]>,
    pub(super) caps: Vec<(KeyLight, Vec<(f64, f64)>)>,
    pub(super) gauss: (Vec<f64>, Vec<f64>),
}

impl Setup<'_> {
    pub(super) fn surface(&self) -> Surface<'_> {
        let (w, h) = (self.scene.field.width(), self.scene.field.height());
        Surface { heights: &self.heights, width: w, height: h, wrap: self.scene.wrap }
    }

    fn azimuths(&self) -> impl Iterator<Item = f64> {
        let a = self.settings.azimuths;
        (0..a).map(move |k| (k as f64 + 0.5) * 2.0 * PI / a as f64)
    }

    /// The azimuth integral at texel `(i, j)`: `per_azimuth(acc, φ, profile)` for every azimuth of
    /// the reference, then `E` (exact) or the `n²` SH coefficients (SH-visibility) of `acc`.
    fn per_texel(&self, i: usize, j: usize, mut per_azimuth: impl FnMut(&mut Acc, f64, &Profile)) -> Vec<[f64; 3]> {
        let n = self.scene.gi.sh_order;
        let surf = self.surface();
        let p = j * surf.width + i;
        let mut acc = Acc {
            normal: DVec3::from_array(self.nrm[p]),
            dphi: 2.0 * PI / self.settings.azimuths as f64,
            e: [0.0; 3],
            sh: vec![[0.0; 3]; n * n],
            basis: ShBasis::new(n),
        };
        for phi in self.azimuths() {
            per_azimuth(&mut acc, phi, &Profile::trace(&surf, i, j, phi, self.settings));
        }
        if self.settings.sh_visibility {
            acc.sh
        } else {
            vec![acc.e]
        }
    }

    /// The sphere blockers seen from the receiver of texel `(i, j)`.
    fn sphere_caps(&self, i: usize, j: usize) -> SphereCaps {
        let (w, s) = (self.scene.field.width(), self.scene.texel_size);
        SphereCaps::new(&self.scene.spheres, DVec3::new(i as f64 * s, j as f64 * s, self.heights[j * w + i]))
    }

    /// What [`Self::per_texel`] returns for a receiver that sees nothing (inside a sphere).
    fn nothing(&self) -> Vec<[f64; 3]> {
        let n = self.scene.gi.sh_order;
        vec![[0.0; 3]; if self.settings.sh_visibility { n * n } else { 1 }]
    }

    /// Direct light of texel `(i, j)`: `E` (exact) or `V_k` in `.0` (SH-visibility).
    pub(super) fn direct(&self, i: usize, j: usize) -> Vec<[f64; 3]> {
        let s = self.scene.texel_size;
        let spheres = self.sphere_caps(i, j);
        if spheres.inside {
            return self.nothing();
        }
        let mut out = self.per_texel(i, j, |acc, phi, prof| {
            let hor = prof.horizon(s);
            if self.settings.sh_visibility {
                for (om, wt) in nodes_on(&self.gauss, hor, FRAC_PI_2) {
                    let y = acc.basis.eval(direction(om, phi).to_array());
                    for (v, yk) in acc.sh.iter_mut().zip(y) {
                        v[0] += acc.dphi * wt * om.cos() * yk;
                    }
                }
                return;
            }
            let lo = hor.max(tangent_elevation(acc.normal.to_array(), phi));
            for (om, wt) in nodes_on(&self.gauss, lo, FRAC_PI_2) {
                let d = direction(om, phi);
                let y = acc.basis.eval(d.to_array());
                let cosf = acc.normal.dot(d).max(0.0) * om.cos() * wt * acc.dphi;
                for (ch, ec) in acc.e.iter_mut().enumerate() {
                    *ec += cosf * self.light.iter().zip(y).map(|(l, yk)| l[ch] * yk).sum::<f64>();
                }
            }
        });
        if !spheres.caps.is_empty() {
            self.sphere_parts(&spheres, i, j, &mut out);
        }
        if !self.settings.sh_visibility {
            for (key, samples) in &self.caps {
                let c = self.cap(key, samples, i, j, &spheres);
                for (ec, r) in out[0].iter_mut().zip(&key.radiance) {
                    *ec += c * r;
                }
            }
        }
        out
    }

    /// Removes from the direct integral `out` (as [`Self::direct`] forms it) what the spheres
    /// block: per sphere `k`, over its own azimuth samples, the environment (exact: `L·(N·ω)⁺`;
    /// SH-visibility: `y_k`) on `(W_k ∩ open) ∖ ∪_{j<k} W_j`, so that overlaps count once.
    fn sphere_parts(&self, spheres: &SphereCaps, i: usize, j: usize, out: &mut [[f64; 3]]) {
        let (surf, s, sh) = (self.surface(), self.scene.texel_size, self.settings.sh_visibility);
        let p = j * surf.width + i;
        let nv = DVec3::from_array(self.nrm[p]);
        let mut basis = ShBasis::new(self.scene.gi.sh_order);
        for (k, cap) in spheres.caps.iter().enumerate() {
            for (phi, wphi) in cap_azimuths_toward(cap.l, cap.sin_a, self.settings.azimuths, self.settings.cap_nodes) {
                let d = [phi.cos(), phi.sin()];
                let Some((w0, w1)) = cap.window(d) else { continue };
                let hor = Profile::trace(&surf, i, j, phi, self.settings).horizon(s);
                let lo = if sh { hor } else { hor.max(tangent_elevation(self.nrm[p], phi)) };
                let (a, b) = (w0.max(lo), w1.min(FRAC_PI_2));
                if b <= a {
                    continue;
                }
                let earlier: Vec<Option<(f64, f64)>> = spheres.caps[..k].iter().map(|c| c.window(d)).collect();
                gaps(a, b, &earlier, |x, y| {
                    for (om, wt) in nodes_on(&self.gauss, x, y) {
                        let dir = direction(om, phi);
                        let yv = basis.eval(dir.to_array());
                        if sh {
                            for (v, yk) in out.iter_mut().zip(yv) {
                                v[0] -= wphi * wt * om.cos() * yk;
                            }
                        } else {
                            let cosf = nv.dot(dir).max(0.0) * om.cos() * wt * wphi;
                            for (ch, ec) in out[0].iter_mut().enumerate() {
                                *ec -= cosf * self.light.iter().zip(yv).map(|(l, yk)| l[ch] * yk).sum::<f64>();
                            }
                        }
                    }
                });
            }
        }
    }

    /// `∫_cap∩open max(N·ω, 0) dω` at texel `(i, j)` over the cap's azimuth samples, the
    /// spheres' windows taken out of it.
    fn cap(&self, key: &KeyLight, samples: &[(f64, f64)], i: usize, j: usize, spheres: &SphereCaps) -> f64 {
        let (surf, s) = (self.surface(), self.scene.texel_size);
        let p = j * surf.width + i;
        let nv = DVec3::from_array(self.nrm[p]);
        let l = key.direction.normalize().to_array();
        let (sin_a, cos_a) = key.angular_radius.sin_cos();
        let mut sum = 0.0;
        for &(phi, wphi) in samples {
            let Some((w0, w1)) = cap_window([phi.cos(), phi.sin()], l, sin_a, cos_a) else { continue };
            let hor = Profile::trace(&surf, i, j, phi, self.settings).horizon(s);
            let (lo, hi) = (w0.max(hor).max(tangent_elevation(self.nrm[p], phi)), w1.min(FRAC_PI_2));
            if hi > lo {
                gaps(lo, hi, &spheres.windows([phi.cos(), phi.sin()]), |a, b| {
                    for (om, wt) in nodes_on(&self.gauss, a, b) {
                        sum += wphi * wt * om.cos() * nv.dot(direction(om, phi)).max(0.0);
                    }
                });
            }
        }
        sum
    }

    /// One bounce at texel `(i, j)` from the previous bounce's exit radiance `chans` (per
    /// channel): `E` (exact) or `U_k` (SH-visibility). A node whose ray enters a sphere before
    /// its first hit carries nothing (spheres absorb).
    pub(super) fn bounce(&self, chans: &[Vec<f64>], i: usize, j: usize) -> Vec<[f64; 3]> {
        let (surf, s) = (self.surface(), self.scene.texel_size);
        let spheres = self.sphere_caps(i, j);
        if spheres.inside {
            return self.nothing();
        }
        self.per_texel(i, j, |acc, phi, prof| {
            let (hor, lo) = (prof.horizon(s), tangent_elevation(acc.normal.to_array(), phi));
            if hor <= lo {
                return;
            }
            let nodes: Vec<(f64, f64)> = nodes_on(&self.gauss, lo, hor).collect();
            let omegas: Vec<f64> = nodes.iter().map(|v| v.0).collect();
            for ((om, wt), q) in nodes.iter().zip(prof.hits(&omegas, s)) {
                if !spheres.caps.is_empty() {
                    // Planar distances in texels: the sphere entry's, the first hit's.
                    let t_sphere = spheres.hit(direction(*om, phi)) * om.cos() / s;
                    if t_sphere < (q[0] - i as f64).hypot(q[1] - j as f64) {
                        continue;
                    }
                }
                let r: Vec<f64> =
                    chans.iter().map(|c| bilinear(c, surf.width, surf.height, q[0], q[1], surf.wrap)).collect();
                let d = direction(*om, phi);
                if self.settings.sh_visibility {
                    let y = acc.basis.eval(d.to_array());
                    for (uk, yk) in acc.sh.iter_mut().zip(y) {
                        for ch in 0..3 {
                            uk[ch] += acc.dphi * wt * om.cos() * yk * r[ch];
                        }
                    }
                } else {
                    let cosf = acc.normal.dot(d).max(0.0) * om.cos() * wt * acc.dphi;
                    for (ec, rc) in acc.e.iter_mut().zip(&r) {
                        *ec += cosf * rc;
                    }
                }
            }
        })
    }
}

/// One texel's accumulators (`Setup::per_texel`): its normal, the azimuth weight `2π/A`, the
/// exact irradiance `e` and the SH-mode coefficients `sh`, with the SH evaluator.
struct Acc {
    normal: DVec3,
    dphi: f64,
    e: [f64; 3],
    sh: Vec<[f64; 3]>,
    basis: ShBasis,
}
