//! The brute-force ground truth of CONVENTIONS.md ("Accuracy"), in f64 on the CPU, for small
//! fields (the tests use it to check the GPU version, `src/frame/truth.rs`). docs/accuracy.md
//! §1 is its specification:
//!
//! - per texel, `A ≥ 256` uniformly spaced azimuths; along each, the ray is intersected
//!   exactly with the bilinear patches ([`super::ray`]: a DDA over cells, a quadratic per
//!   cell; rays that leave the domain escape, with `wrap` they stop after `max(W, H)` texels),
//!   or, with [`TruthSettings::march`], marched at `step`-texel samples as before;
//! - visibility: a direction of elevation `ω` is open iff `ω` exceeds the horizon
//!   `ω_hor = atan(sup_t (f(p + t·d) − f(p)) / (t·s))`;
//! - first hits (indirect): the smallest `t` where the surface reaches the node's direction;
//! - elevation integrals by Gauss–Legendre (`nodes`) on the smooth pieces: the open interval
//!   `[max(ω_hor, ω_t), π/2]` and the blocked interval `[ω_t, ω_hor]`, `ω_t` the exact
//!   tangent elevation of the receiver's normal along `φ`;
//! - lighting, exact variant: the order-n SH of the environment as given plus each key light
//!   as its true cap ([`super::cap`]: its own azimuth samples and, on each, its elevation
//!   window intersected with the open interval); SH-visibility variant: environment plus the
//!   caps' SH projections ([`lighting_sh`]);
//! - local lights, both variants: the true sphere ([`super::local_truth`]: a direction sees it
//!   iff its ray reaches the sphere before the height field), `ρ/π · E` added to the direct
//!   exit radiance, which the bounces then take as their source;
//! - sphere blockers (CONVENTIONS.md "Lighting"; [`super::cap::SphereCaps`]): opaque, they
//!   block every ray that meets them and do not reflect. Direct: on each half-plane a sphere
//!   blocks exactly its cap's elevation window; the environment over the open interval of
//!   the uniform azimuths minus, per sphere `k`, its blocked part `(W_k ∩ open) ∖ ∪_{j<k} W_j`
//!   integrated over the sphere's own azimuth samples (like a key light's cap, so that the
//!   chord ends are integrated exactly); a key light's window minus every sphere's window on
//!   its samples ([`super::cap::gaps`]: exact sub-intervals, `nodes` points each); a local
//!   light's node is blocked if its ray enters a sphere before the light. Bounces: a node
//!   whose ray enters a sphere before its first hit carries zero. A receiver inside a
//!   sphere gets nothing (direct and indirect).
//!
//! Two variants: *exact* (`L_o = ρ/π ∫ L_in max(N·ω, 0) dω`) and *SH-visibility* (exact
//! visibility and indirect radiance projected to order n, then shaded as the pipeline does:
//! `L ⊛ V` for the direct light, `U` for the indirect, dotted with the rotated clamped-cosine).
//! Surfaces are treated as diffuse (the glossy layer is zero).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use super::cap::{cap_azimuths, cap_azimuths_toward, cap_window, gaps, SphereCaps};
use super::direct::normals;
use super::local_truth::LocalTruth;
pub use super::ray::bilinear;
use super::ray::{first_hits, horizon_slope, march, pieces, Piece, Surface};
use super::sh_eval::ShBasis;
use crate::error::{Error, Result};
use crate::math::quadrature::gauss_legendre;
use crate::math::{triple, zh};
use crate::scene::model::{Albedo, KeyLight, Scene};

/// Sampling of the ground truth (defaults: CONVENTIONS.md minimums).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSettings {
    /// Uniformly spaced azimuths, `φ_a = 2π(a + ½)/A`.
    pub azimuths: u32,
    /// March step in texels (used only with `march`).
    pub step: f64,
    /// Gauss–Legendre nodes per elevation interval.
    pub nodes: u32,
    /// SH-visibility reference instead of the exact one.
    pub sh_visibility: bool,
    /// March the surface at `step` instead of intersecting the bilinear patches exactly (for
    /// convergence studies; the march's error halves with each halving of the step).
    pub march: bool,
    /// Gauss–Legendre nodes of a key light's azimuth range (exact variant, caps holding no
    /// pole; a cap over a pole uses the `azimuths` uniform ones).
    pub cap_nodes: u32,
}

impl Default for TruthSettings {
    fn default() -> Self {
        Self { azimuths: 256, step: 0.125, nodes: 16, sh_visibility: false, march: false, cap_nodes: 64 }
    }
}

impl TruthSettings {
    pub fn validate(&self) -> Result<()> {
        if !(4..=4096).contains(&self.azimuths) {
            return Err(Error::param("reference azimuths", self.azimuths, "an integer in 4..=4096"));
        }
        if !(self.step.is_finite() && self.step > 0.0 && self.step <= 1.0) {
            return Err(Error::param("reference step", self.step, "a number of texels in (0, 1]"));
        }
        if !(1..=64).contains(&self.nodes) {
            return Err(Error::param("reference nodes", self.nodes, "an integer in 1..=64"));
        }
        if !(1..=1024).contains(&self.cap_nodes) {
            return Err(Error::param("reference cap nodes", self.cap_nodes, "an integer in 1..=1024"));
        }
        Ok(())
    }
}

/// The reference's layers (CONVENTIONS.md exported values), full resolution, row-major.
pub struct TruthOutput {
    pub width: usize,
    pub height: usize,
    pub direct: Vec<[f64; 3]>,
    /// Per bounce `b = 1..=B`.
    pub indirect_bounces: Vec<Vec<[f64; 3]>>,
    pub indirect: Vec<[f64; 3]>,
    pub total: Vec<[f64; 3]>,
}

/// The scene's lighting as order-n SH (RGB): environment + key-light caps (CONVENTIONS.md).
pub fn lighting_sh(scene: &Scene) -> Vec<[f64; 3]> {
    let n = scene.gi.sh_order;
    let mut l: Vec<[f64; 3]> = (0..n * n).map(|k| scene.environment.sh.get(k).copied().unwrap_or([0.0; 3])).collect();
    for key in &scene.key_lights {
        let cap = zh::rotate(n, &zh::cap(n, key.angular_radius), key.direction.normalize().to_array());
        for (o, c) in l.iter_mut().zip(&cap) {
            for (oc, r) in o.iter_mut().zip(&key.radiance) {
                *oc += c * r;
            }
        }
    }
    l
}

/// The environment alone as order-n SH (RGB): the exact reference's SH part; its key lights
/// are caps ([`key_caps`]).
pub fn environment_sh(scene: &Scene) -> Vec<[f64; 3]> {
    let n = scene.gi.sh_order;
    (0..n * n).map(|k| scene.environment.sh.get(k).copied().unwrap_or([0.0; 3])).collect()
}

/// The key lights of the exact reference with their azimuth samples `(φ, weight)`
/// ([`cap_azimuths`]); none for the SH-visibility reference (its lighting holds them as SH).
pub fn key_caps(scene: &Scene, settings: &TruthSettings) -> Vec<(KeyLight, Vec<(f64, f64)>)> {
    if settings.sh_visibility {
        return Vec::new();
    }
    scene.key_lights.iter().map(|k| (k.clone(), cap_azimuths(k, settings.azimuths, settings.cap_nodes))).collect()
}

/// What a receiver sees along one azimuth: the exact ray's pieces, or the march's samples.
pub enum Profile {
    Exact { pieces: Vec<Piece>, origin: [f64; 2], d: [f64; 2] },
    March(Vec<(f64, [f64; 2])>),
}

impl Profile {
    /// The ray from vertex `(i, j)` along azimuth `phi`, as `settings` asks.
    pub fn trace(surf: &Surface, i: usize, j: usize, phi: f64, settings: &TruthSettings) -> Self {
        let d = [phi.cos(), phi.sin()];
        if settings.march {
            Self::March(march(surf, i, j, d, settings.step))
        } else {
            Self::Exact { pieces: pieces(surf, i, j, d), origin: [i as f64, j as f64], d }
        }
    }

    /// The horizon elevation (`−π/2` where the ray leaves the domain at once); `texel_size` `s`.
    pub fn horizon(&self, s: f64) -> f64 {
        let slope = match self {
            Self::Exact { pieces, .. } => horizon_slope(pieces),
            Self::March(m) => m.iter().map(|v| v.0).reduce(f64::max),
        };
        slope.map_or(-FRAC_PI_2, |k| (k / s).atan())
    }

    /// First-hit positions of the ascending elevations `omegas`, in order, ending before the
    /// first one that escapes.
    pub fn hits(&self, omegas: &[f64], s: f64) -> Vec<[f64; 2]> {
        let k: Vec<f64> = omegas.iter().map(|om| om.tan() * s).collect();
        match self {
            Self::Exact { pieces, origin, d } => {
                first_hits(pieces, &k).iter().map(|t| [origin[0] + t * d[0], origin[1] + t * d[1]]).collect()
            }
            Self::March(m) => {
                let (mut next, mut running, mut hit) = (0, f64::NEG_INFINITY, [0.0; 2]);
                let mut out = Vec::with_capacity(k.len());
                for kk in k {
                    while running < kk && next < m.len() {
                        if m[next].0 > running {
                            (running, hit) = (m[next].0, m[next].1);
                        }
                        next += 1;
                    }
                    if running < kk {
                        break;
                    }
                    out.push(hit);
                }
                out
            }
        }
    }
}

/// The exact tangent elevation of normal `n` along azimuth `phi`: `N · dir(ω, φ) = 0`.
pub fn tangent_elevation(n: [f64; 3], phi: f64) -> f64 {
    (-(n[0] * phi.cos() + n[1] * phi.sin())).atan2(n[2])
}

/// What turns the reference's raw per-texel integrals into exit radiance: the lighting, and,
/// built once, the triple-product tensor and the clamped-cosine ZH of order `n`.
pub struct Finisher {
    n: usize,
    sh_visibility: bool,
    light: Vec<[f64; 3]>,
    tri: &'static triple::Triple,
    cc: Vec<f64>,
}

impl Finisher {
    pub fn new(scene: &Scene, sh_visibility: bool) -> Self {
        let n = scene.gi.sh_order;
        Self { n, sh_visibility, light: lighting_sh(scene), tri: triple::triple(n), cc: zh::clamped_cosine(n) }
    }

    /// Exit radiance of one texel from its raw integral (docs/accuracy.md §1): exact mode
    /// `raw[0]` = `E` (rgb) → `ρ/π E`; SH mode, direct: `raw[k][0]` = `V_k` → `ρ/π ⟨L ⊛ V, cc_N⟩`;
    /// SH mode, indirect: `raw[k]` = `U_k` (rgb) → `ρ/π ⟨U, cc_N⟩`.
    pub fn texel(&self, indirect: bool, raw: &[[f64; 3]], nrm: [f64; 3], rho: [f64; 3]) -> [f64; 3] {
        let n = self.n;
        if !self.sh_visibility {
            return [rho[0] / PI * raw[0][0], rho[1] / PI * raw[0][1], rho[2] / PI * raw[0][2]];
        }
        let t: Vec<[f64; 3]> = if indirect {
            raw.to_vec()
        } else {
            let v: Vec<f64> = raw.iter().map(|r| r[0]).collect();
            let per: Vec<Vec<f64>> = (0..3)
                .map(|ch| triple::product(self.tri, &self.light.iter().map(|l| l[ch]).collect::<Vec<_>>(), &v))
                .collect();
            (0..n * n).map(|k| [per[0][k], per[1][k], per[2][k]]).collect()
        };
        let c = zh::rotate(n, &self.cc, nrm);
        let mut e = [0.0; 3];
        for (k, ck) in c.iter().enumerate() {
            for ch in 0..3 {
                e[ch] += t[k][ch] * ck;
            }
        }
        [rho[0] / PI * e[0], rho[1] / PI * e[1], rho[2] / PI * e[2]]
    }
}

/// Per-texel albedo (linear RGB, f64).
pub fn albedo(scene: &Scene) -> Vec<[f64; 3]> {
    let (w, h) = (scene.field.width(), scene.field.height());
    (0..w * h)
        .map(|k| match &scene.material.albedo {
            Albedo::Constant(a) => [a[0] as f64, a[1] as f64, a[2] as f64],
            Albedo::Map(m) => [m[k][0] as f64, m[k][1] as f64, m[k][2] as f64],
        })
        .collect()
}

/// The unit direction of elevation `omega` and azimuth `phi`.
pub(super) fn direction(omega: f64, phi: f64) -> DVec3 {
    DVec3::new(omega.cos() * phi.cos(), omega.cos() * phi.sin(), omega.sin())
}

/// Gauss–Legendre nodes and weights on `[a, b]`.
pub(super) fn nodes_on(gauss: &(Vec<f64>, Vec<f64>), a: f64, b: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
    gauss.0.iter().zip(&gauss.1).map(move |(x, wt)| (0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * wt))
}

/// Everything the per-texel integrals share.
struct Setup<'a> {
    scene: &'a Scene,
    settings: &'a TruthSettings,
    heights: Vec<f64>,
    nrm: Vec<[f64; 3]>,
    /// Environment SH (exact) or environment + key-light SH (SH-visibility).
    light: Vec<[f64; 3]>,
    caps: Vec<(KeyLight, Vec<(f64, f64)>)>,
    gauss: (Vec<f64>, Vec<f64>),
}

impl Setup<'_> {
    fn surface(&self) -> Surface<'_> {
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
    fn direct(&self, i: usize, j: usize) -> Vec<[f64; 3]> {
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
    fn bounce(&self, chans: &[Vec<f64>], i: usize, j: usize) -> Vec<[f64; 3]> {
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

/// The ground truth of `scene` (direct + `scene.gi.bounces` diffuse bounces). `progress` is
/// called with (done, total) work units.
pub fn render_truth(
    scene: &Scene,
    settings: &TruthSettings,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<TruthOutput> {
    settings.validate()?;
    scene.gi.validate()?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let setup = Setup {
        scene,
        settings,
        heights: scene.field.data().iter().map(|&v| v as f64).collect(),
        nrm: normals(scene),
        light: if settings.sh_visibility { lighting_sh(scene) } else { environment_sh(scene) },
        caps: key_caps(scene, settings),
        gauss: gauss_legendre(settings.nodes as usize),
    };
    let finish = Finisher::new(scene, settings.sh_visibility);
    let rho = albedo(scene);
    let total_units = ((scene.gi.bounces as u64 + 1) * (w * h) as u64).max(1);
    let mut done = 0u64;
    let mut pass = |indirect: bool, raw: &dyn Fn(usize, usize) -> Vec<[f64; 3]>| -> Vec<[f64; 3]> {
        let mut out = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let p = j * w + i;
                out.push(finish.texel(indirect, &raw(i, j), setup.nrm[p], rho[p]));
                done += 1;
                progress(done, total_units);
            }
        }
        out
    };
    let mut direct = pass(false, &|i, j| setup.direct(i, j));
    // Local lights (both variants): ρ/π · E added to the direct exit radiance, before the
    // bounces take it as their source.
    if !scene.local_lights.is_empty() {
        let local = LocalTruth {
            lights: &scene.local_lights,
            settings,
            surf: setup.surface(),
            texel_size: scene.texel_size,
            nrm: &setup.nrm,
            gauss: &setup.gauss,
            spheres: &scene.spheres,
        };
        for (p, out) in direct.iter_mut().enumerate() {
            let e = local.irradiance(p % w, p / w);
            for c in 0..3 {
                out[c] += rho[p][c] / PI * e[c];
            }
        }
    }
    // Diffuse bounces: radiance of the previous bounce at the first hit.
    let mut source = direct.clone();
    let mut indirect_bounces = Vec::new();
    for _ in 0..scene.gi.bounces {
        let chans: Vec<Vec<f64>> = (0..3).map(|c| source.iter().map(|v| v[c]).collect()).collect();
        let out = pass(true, &|i, j| setup.bounce(&chans, i, j));
        source = out.clone();
        indirect_bounces.push(out);
    }
    Ok(TruthOutput::assemble(w, h, direct, indirect_bounces))
}

impl TruthOutput {
    /// The exported layers from the direct light and the bounces: `indirect = Σ_b`,
    /// `total = direct + indirect`.
    pub fn assemble(width: usize, height: usize, direct: Vec<[f64; 3]>, indirect_bounces: Vec<Vec<[f64; 3]>>) -> Self {
        let mut indirect = vec![[0.0; 3]; width * height];
        for b in &indirect_bounces {
            for (o, v) in indirect.iter_mut().zip(b) {
                for c in 0..3 {
                    o[c] += v[c];
                }
            }
        }
        let total = direct.iter().zip(&indirect).map(|(d, i)| [d[0] + i[0], d[1] + i[1], d[2] + i[2]]).collect();
        Self { width, height, direct, indirect_bounces, indirect, total }
    }
}
