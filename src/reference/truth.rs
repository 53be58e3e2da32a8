//! The brute-force ground truth of CONVENTIONS.md ("Accuracy"), in f64 on the CPU, for small
//! fields (the tests use it to check the GPU version, `src/frame/truth.rs`). docs/accuracy.md
//! §1 is its specification:
//!
//! - per texel, `A ≥ 256` uniformly spaced azimuths; along each, the bilinear surface is
//!   marched at `1/8`-texel steps (rays that leave the domain escape; with `wrap` the march
//!   stops after `max(W, H)` texels);
//! - visibility: a direction of elevation `ω` is open iff `ω` exceeds the horizon
//!   `ω_hor = max_t atan((f(p + t·d) − f(p)) / t)`;
//! - first hits (indirect): the first march sample whose blocking angle reaches `ω`;
//! - elevation integrals by 16-point Gauss–Legendre on the smooth pieces: the open interval
//!   `[max(ω_hor, ω_t), π/2]` and the blocked interval `[ω_t, ω_hor]`, `ω_t` the exact
//!   tangent elevation of the receiver's normal along `φ`;
//! - lighting: the order-n SH of the environment plus each key light's cap SH, as given.
//!
//! Two variants: *exact* (`L_o = ρ/π ∫ L_in max(N·ω, 0) dω`) and *SH-visibility* (exact
//! visibility and indirect radiance projected to order n, then shaded as the pipeline does:
//! `L ⊛ V` for the direct light, `U` for the indirect, dotted with the rotated clamped-cosine).
//! Surfaces are treated as diffuse (the glossy layer is zero).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use super::direct::normals;
use crate::error::{Error, Result};
use crate::math::quadrature::gauss_legendre;
use crate::math::{sh, triple, zh};
use crate::scene::model::{Albedo, Scene};

/// Sampling of the ground truth (defaults: CONVENTIONS.md minimums).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSettings {
    /// Uniformly spaced azimuths, `φ_a = 2π(a + ½)/A`.
    pub azimuths: u32,
    /// March step in texels.
    pub step: f64,
    /// Gauss–Legendre nodes per elevation interval.
    pub nodes: u32,
    /// SH-visibility reference instead of the exact one.
    pub sh_visibility: bool,
}

impl Default for TruthSettings {
    fn default() -> Self {
        Self { azimuths: 256, step: 0.125, nodes: 16, sh_visibility: false }
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

/// Bilinear surface (CONVENTIONS.md) of `data` (`w × h`) at level-0 position `(x, y)`.
pub fn bilinear(data: &[f64], w: usize, h: usize, x: f64, y: f64, wrap: bool) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (tx, ty) = (x - fx, y - fy);
    let idx = |i: i64, n: usize| if wrap { i.rem_euclid(n as i64) as usize } else { i.clamp(0, n as i64 - 1) as usize };
    let (x0, x1, y0, y1) = (idx(fx as i64, w), idx(fx as i64 + 1, w), idx(fy as i64, h), idx(fy as i64 + 1, h));
    let a = data[y0 * w + x0] * (1.0 - tx) + data[y0 * w + x1] * tx;
    let b = data[y1 * w + x0] * (1.0 - tx) + data[y1 * w + x1] * tx;
    a * (1.0 - ty) + b * ty
}

/// One march along azimuth `phi` from texel `(i, j)`: blocking angle and position of every
/// sample, in order of distance.
pub fn march(scene: &Scene, heights: &[f64], i: usize, j: usize, phi: f64, step: f64) -> Vec<(f64, [f64; 2])> {
    let (w, h) = (scene.field.width(), scene.field.height());
    let (dx, dy) = (phi.cos(), phi.sin());
    let h0 = heights[j * w + i];
    let t_max = w.max(h) as f64;
    let mut out = Vec::new();
    let mut k = 1u32;
    loop {
        let t = k as f64 * step;
        let q = [i as f64 + t * dx, j as f64 + t * dy];
        if scene.wrap {
            if t > t_max {
                break;
            }
        } else if q[0] < 0.0 || q[1] < 0.0 || q[0] > (w - 1) as f64 || q[1] > (h - 1) as f64 {
            break;
        }
        let f = bilinear(heights, w, h, q[0], q[1], scene.wrap);
        out.push((((f - h0) / (t * scene.texel_size)).atan(), q));
        k += 1;
    }
    out
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
    tri: triple::Triple,
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
                .map(|ch| triple::product(&self.tri, &self.light.iter().map(|l| l[ch]).collect::<Vec<_>>(), &v))
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

fn direction(omega: f64, phi: f64) -> DVec3 {
    DVec3::new(omega.cos() * phi.cos(), omega.cos() * phi.sin(), omega.sin())
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
    let n = scene.gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let heights: Vec<f64> = scene.field.data().iter().map(|&v| v as f64).collect();
    let nrm = normals(scene);
    let light = lighting_sh(scene);
    let (gx, gw) = gauss_legendre(settings.nodes as usize);
    let a_count = settings.azimuths as usize;
    let dphi = 2.0 * PI / a_count as f64;
    let finish = Finisher::new(scene, settings.sh_visibility);
    let rho = albedo(scene);
    // GL nodes and weights on [a, b].
    let nodes = |a: f64, b: f64| -> Vec<(f64, f64)> {
        gx.iter().zip(&gw).map(|(x, wt)| (0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * wt)).collect()
    };
    let total_units = ((scene.gi.bounces as u64 + 1) * (w * h) as u64).max(1);
    let mut done = 0u64;

    // Direct light.
    let mut direct = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let p = j * w + i;
            let nv = DVec3::from_array(nrm[p]);
            let mut e = [0.0; 3];
            let mut vis = vec![0.0; n * n];
            for a in 0..a_count {
                let phi = (a as f64 + 0.5) * dphi;
                let hor = march(scene, &heights, i, j, phi, settings.step).iter().fold(-FRAC_PI_2, |m, s| m.max(s.0));
                if settings.sh_visibility {
                    for (om, wt) in nodes(hor, FRAC_PI_2) {
                        let y = sh::eval(n, direction(om, phi).to_array());
                        for (v, yk) in vis.iter_mut().zip(&y) {
                            *v += dphi * wt * om.cos() * yk;
                        }
                    }
                } else {
                    let lo = hor.max(tangent_elevation(nrm[p], phi));
                    for (om, wt) in nodes(lo, FRAC_PI_2) {
                        let d = direction(om, phi);
                        let y = sh::eval(n, d.to_array());
                        let cosf = nv.dot(d).max(0.0) * om.cos() * wt * dphi;
                        for ch in 0..3 {
                            e[ch] += cosf * light.iter().zip(&y).map(|(l, yk)| l[ch] * yk).sum::<f64>();
                        }
                    }
                }
            }
            let raw: Vec<[f64; 3]> =
                if settings.sh_visibility { vis.iter().map(|v| [*v, 0.0, 0.0]).collect() } else { vec![e] };
            direct.push(finish.texel(false, &raw, nrm[p], rho[p]));
            done += 1;
            progress(done, total_units);
        }
    }

    // Diffuse bounces: radiance of the previous bounce at the first hit.
    let mut source = direct.clone();
    let mut indirect_bounces = Vec::new();
    for _ in 0..scene.gi.bounces {
        let chans: Vec<Vec<f64>> = (0..3).map(|c| source.iter().map(|v| v[c]).collect()).collect();
        let mut out = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let p = j * w + i;
                let nv = DVec3::from_array(nrm[p]);
                let mut e = [0.0; 3];
                let mut u = vec![[0.0; 3]; n * n];
                for a in 0..a_count {
                    let phi = (a as f64 + 0.5) * dphi;
                    let samples = march(scene, &heights, i, j, phi, settings.step);
                    let hor = samples.iter().fold(-FRAC_PI_2, |m, s| m.max(s.0));
                    let lo = tangent_elevation(nrm[p], phi);
                    if hor <= lo {
                        continue;
                    }
                    // Nodes ascend; the running maximum of the blocking angle sweeps them.
                    let mut k = 0;
                    let mut running = -FRAC_PI_2;
                    for (om, wt) in nodes(lo, hor) {
                        while running < om && k < samples.len() {
                            running = running.max(samples[k].0);
                            k += 1;
                        }
                        if running < om {
                            break;
                        }
                        let q = samples[k - 1].1;
                        let r: Vec<f64> = chans.iter().map(|c| bilinear(c, w, h, q[0], q[1], scene.wrap)).collect();
                        let d = direction(om, phi);
                        if settings.sh_visibility {
                            let y = sh::eval(n, d.to_array());
                            for (uk, yk) in u.iter_mut().zip(&y) {
                                for ch in 0..3 {
                                    uk[ch] += dphi * wt * om.cos() * yk * r[ch];
                                }
                            }
                        } else {
                            let cosf = nv.dot(d).max(0.0) * om.cos() * wt * dphi;
                            for ch in 0..3 {
                                e[ch] += cosf * r[ch];
                            }
                        }
                    }
                }
                let raw = if settings.sh_visibility { u } else { vec![e] };
                out.push(finish.texel(true, &raw, nrm[p], rho[p]));
                done += 1;
                progress(done, total_units);
            }
        }
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
