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

use super::cap::cap_azimuths;
use super::direct::normals;
use super::local_truth::LocalTruth;
pub use super::ray::bilinear;
use super::ray::{first_hits, horizon_slope, march, pieces, Piece, Surface};
use crate::error::{Error, Result};
use crate::math::quadrature::gauss_legendre;
use crate::math::{triple, zh};
use crate::scene::model::{Albedo, KeyLight, Scene};

mod setup;
use setup::Setup;

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
