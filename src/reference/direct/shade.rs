//! The shading half of the CPU twin: the BRDF lobes, the pipeline that renders every texel, its visibility.

use std::f64::consts::PI;

use glam::DVec3;

use super::{interpolate, normals, sweep_visibility, visibility_from, DirectOutput, Scan};
use crate::error::Result;
use crate::math::azimuth::{wedge_matrices, AzimuthSet};
use crate::math::triple::Triple;
use crate::math::{triple, zh};
use crate::reference::blockers::BlockerVisibility;
use crate::reference::pyramid::{rescale, CpuPyramid};
use crate::reference::tangent::{receiver_normal, tangent_clip};
use crate::rules::lighting::{light_sets, set_lighting, SetKind};
use crate::scene::model::{Albedo, DiffuseLobe, PyramidMode, Scene, VisibilityMethod};

/// The BRDF lobes of §7 for one scene: the diffuse lobe of `gi.diffuse_lobe` (the clamped
/// cosine or the cosine, docs/accuracy.md §6) about the normal and the
/// normalised Phong lobe about the reflected view direction, as order-n ZH.
pub struct Lobes {
    n: usize,
    cc: Vec<f64>,
    /// Normalised Phong lobe as ZH, canonical orientation.
    pub phong: Vec<f64>,
}

impl Lobes {
    pub fn new(scene: &Scene) -> Self {
        let n = scene.gi.sh_order;
        let exponent = scene.material.exponent as f64;
        let phong = (0..n)
            .map(|l| ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * (-((l * l) as f64) / (2.0 * exponent)).exp())
            .collect();
        Self { n, cc: crate::rules::scene::diffuse_lobe(n, scene.gi.diffuse_lobe), phong }
    }

    /// The Phong ZH rotated to the reflected view vector at texel `(x, y)` with normal `nrm`.
    pub fn phong_at(&self, scene: &Scene, x: usize, y: usize, nrm: [f64; 3]) -> Vec<f64> {
        let s = scene.texel_size;
        let p = DVec3::new(x as f64 * s, y as f64 * s, scene.field.get(x, y) as f64);
        let wo = (scene.camera.position - p).normalize();
        let nv = DVec3::from_array(nrm);
        let r = 2.0 * nv.dot(wo) * nv - wo;
        zh::rotate(self.n, &self.phong, r.normalize().to_array())
    }

    /// Diffuse `ρ/π · (T · cc_N)` and glossy `k_s · (T · phong_R)` exit radiance at texel
    /// `(x, y)` with normal `nrm`, for incident SH radiance `tr` (`n²` RGB).
    pub fn shade(&self, scene: &Scene, x: usize, y: usize, nrm: [f64; 3], tr: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
        let n = self.n;
        let w = scene.field.width();
        let c = zh::rotate(n, &self.cc, nrm);
        let rho = match &scene.material.albedo {
            Albedo::Constant(a) => [a[0] as f64, a[1] as f64, a[2] as f64],
            Albedo::Map(m) => {
                let a = m[y * w + x];
                [a[0] as f64, a[1] as f64, a[2] as f64]
            }
        };
        let e: Vec<f64> = (0..3).map(|ch| (0..n * n).map(|k| tr[k][ch] * c[k]).sum()).collect();
        let diffuse = [rho[0] / PI * e[0], rho[1] / PI * e[1], rho[2] / PI * e[2]];
        let glossy = match scene.material.specular {
            Some(ks) => {
                let gz = self.phong_at(scene, x, y, nrm);
                let gl: Vec<f64> = (0..3).map(|ch| (0..n * n).map(|k| tr[k][ch] * gz[k]).sum()).collect();
                [ks[0] as f64 * gl[0], ks[1] as f64 * gl[1], ks[2] as f64 * gl[2]]
            }
            None => [0.0; 3],
        };
        (diffuse, glossy)
    }
}

/// The fraction of key light `i`'s cap the spheres leave open at texel `(x, y)`
/// ([`crate::math::overlap::unoccluded_fraction`]; docs/blockers.md §3).
fn key_open(scene: &Scene, x: usize, y: usize, i: usize) -> f64 {
    let s = scene.texel_size;
    let p = DVec3::new(x as f64 * s, y as f64 * s, f64::from(scene.field.get(x, y)));
    let spheres: Vec<([f64; 3], f64)> = scene.spheres.iter().map(|b| ((b.center - p).to_array(), b.radius)).collect();
    let l = &scene.key_lights[i];
    crate::math::overlap::unoccluded_fraction(l.direction.normalize().to_array(), l.angular_radius, &spheres)
}

/// The whole direct pipeline of docs/direct.md on the CPU.
pub fn render_direct(scene: &Scene) -> Result<DirectOutput> {
    render_direct_with(scene, None)
}

/// A horizon oracle: `ω` for light set `set` (index into `light_sets`), azimuth `phi` and the
/// receiver at level-0 position `p`.
pub type HorizonFn<'a> = &'a dyn Fn(usize, f64, [f64; 2]) -> f64;

/// [`render_direct`] with every horizon taken from `horizon` instead of the scan or the sweep
/// (e.g. the exact horizons of [`crate::reference::ray`], to measure what the rest of the pipeline —
/// azimuth sampling, elevation basis, SH products — leaves against the SH-visibility reference).
pub fn render_direct_with_horizons(scene: &Scene, horizon: HorizonFn) -> Result<DirectOutput> {
    render_direct_with(scene, Some(horizon))
}

fn render_direct_with(scene: &Scene, oracle: Option<HorizonFn>) -> Result<DirectOutput> {
    scene.gi.validate()?;
    let gi = &scene.gi;
    let n = gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let work = gi.working_size(w, h);
    // Heights relative to the renderer's origin z0 (docs/pyramid.md, "Origin").
    let z0 = crate::rules::scene::height_origin(&scene.field);
    let stack = gi.pyramid == PyramidMode::Stack;
    let pyr = CpuPyramid::build_relative(&scene.field, z0, work, gi.level_step, scene.wrap, stack)?;
    let scan = Scan::new(&pyr, gi, scene.texel_size, scene.wrap);
    let sets = light_sets(scene);
    let visibility = direct_visibility(scene, &scan, &sets, work, oracle);
    let lighting: Vec<Vec<[f64; 3]>> = sets.iter().map(|(k, set)| set_lighting(scene, *k, set)).collect();

    let t = triple::triple(n);
    let normals = normals(scene);
    let lobes = Lobes::new(scene);
    // Sphere blockers (docs/blockers.md): V_s per receiver, and in log mode the environment's
    // combined visibility, which replaces its V (the environment is set 0).
    let blockers = (!scene.spheres.is_empty()).then(|| {
        let env = (sets.first().map(|s| s.0) == Some(SetKind::Environment)).then(|| visibility[0].as_slice());
        crate::reference::blockers::blocker_visibility(scene, work, &normals, env)
    });
    let albedo = blockers.as_ref().and_then(|b| b.transfer.as_ref()).map(|_| crate::reference::truth::albedo(scene));
    let overlap = scene.gi.blocker_key_lights == crate::scene::model::BlockerKeyLights::Overlap;
    let texels = Texels {
        scene,
        work,
        t,
        sets: &sets,
        visibility: &visibility,
        lighting: &lighting,
        blockers: blockers.as_ref(),
        albedo,
        overlap,
        lobes,
        normals: &normals,
    };
    let (mut direct, mut glossy, incident) = texels.shade();
    // The local lights' diffuse exit radiance (stage shade.local_lights, docs/local-lights.md).
    for (d, l) in direct.iter_mut().zip(crate::reference::local::local_exitance(scene, &normals)) {
        *d = [d[0] + l[0], d[1] + l[1], d[2] + l[2]];
    }
    for (g, l) in glossy.iter_mut().zip(crate::reference::local::local_glossy(scene, &normals)) {
        *g = [g[0] + l[0], g[1] + l[1], g[2] + l[2]];
    }
    let total = direct.iter().zip(&glossy).map(|(d, g)| [d[0] + g[0], d[1] + g[1], d[2] + g[2]]).collect();
    Ok(DirectOutput {
        width: w,
        height: h,
        work,
        direct,
        glossy,
        total,
        visibility,
        kinds: sets.iter().map(|s| s.0).collect(),
        normals,
        incident,
        blockers: blockers.map(|b| b.spheres),
    })
}

/// Visibility at every receiver of the working grid (§1–4), per light set, from the ladder or
/// the sweep, or from `oracle`'s horizons where there is one.
fn direct_visibility(
    scene: &Scene,
    scan: &Scan,
    sets: &[(SetKind, AzimuthSet)],
    work: (usize, usize),
    oracle: Option<HorizonFn>,
) -> Vec<Vec<Vec<f64>>> {
    let gi = &scene.gi;
    let n = gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    // Receiver r's level-0 position, and its normal where the visibility is clipped at the
    // tangent plane (gi.diffuse_lobe = "exact", the GPU's HFGI_FLAG_TANGENT_CLIP): once per
    // receiver, for every light set.
    let receiver = |r: usize| [rescale((r % work.0) as f64, work.0, w), rescale((r / work.0) as f64, work.1, h)];
    let clip = gi.diffuse_lobe == DiffuseLobe::Exact;
    let clip_normals: Vec<Option<[f64; 3]>> =
        (0..work.0 * work.1).map(|r| clip.then(|| receiver_normal(scene, receiver(r)))).collect();

    sets.iter()
        .enumerate()
        .map(|(si, (_, set))| {
            let mats = wedge_matrices(n, set, gi.interpolation, gi.elevation_basis);
            if oracle.is_none() && gi.visibility == VisibilityMethod::Sweep {
                return sweep_visibility(scan, n, set, &mats, work, gi.sweep_near as f64, |r| clip_normals[r]);
            }
            (0..work.0 * work.1)
                .map(|r| {
                    let (p, nrm) = (receiver(r), clip_normals[r]);
                    visibility_from(scan, n, set, &mats, |_, phi| {
                        let omega = match oracle {
                            None => scan.omega_max(p, phi),
                            Some(hz) => hz(si, phi, p),
                        };
                        omega.max(tangent_clip(nrm, phi))
                    })
                })
                .collect()
        })
        .collect()
}

/// Everything the per-texel shading of [`render_direct_with`] shares.
struct Texels<'a> {
    scene: &'a Scene,
    /// Receiver grid.
    work: (usize, usize),
    t: &'a Triple,
    sets: &'a [(SetKind, AzimuthSet)],
    /// Per light set, per receiver, `n²` values.
    visibility: &'a [Vec<Vec<f64>>],
    /// Per light set, `n²` RGB.
    lighting: &'a [Vec<[f64; 3]>],
    blockers: Option<&'a BlockerVisibility>,
    /// The albedo per texel, where the blockers' log mode has a diffuse transfer.
    albedo: Option<Vec<[f64; 3]>>,
    /// `gi.blocker_key_lights = "overlap"`.
    overlap: bool,
    lobes: Lobes,
    normals: &'a [[f64; 3]],
}

impl Texels<'_> {
    /// The diffuse and glossy exit radiance and the incident SH radiance of every texel.
    #[allow(clippy::type_complexity)]
    fn shade(&self) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<Vec<[f64; 3]>>) {
        let (w, h) = (self.scene.field.width(), self.scene.field.height());
        let mut direct = Vec::with_capacity(w * h);
        let mut glossy = Vec::with_capacity(w * h);
        let mut incident = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (d, g, tr) = self.texel(x, y);
                direct.push(d);
                glossy.push(g);
                incident.push(tr);
            }
        }
        (direct, glossy, incident)
    }

    /// Texel `(x, y)`'s diffuse and glossy exit radiance and incident SH radiance.
    fn texel(&self, x: usize, y: usize) -> ([f64; 3], [f64; 3], Vec<[f64; 3]>) {
        let (scene, work) = (self.scene, self.work);
        let (w, h) = (scene.field.width(), scene.field.height());
        let (xw, yw) = (rescale(x as f64, w, work.0), rescale(y as f64, h, work.1));
        let (tr, tr_env) = self.incident(x, y, xw, yw);
        let (mut d, mut g) = self.lobes.shade(scene, x, y, self.normals[y * w + x], &tr);
        if let Some(t3) = self.blockers.and_then(|b| b.transfer.as_ref()) {
            self.log_diffuse(t3, (x, y), (xw, yw), &tr_env, &mut d);
        }
        if let (Some(tg), Some(ks)) = (self.blockers.and_then(|b| b.glossy.as_ref()), scene.material.specular) {
            self.log_glossy((tg, ks), (x, y), (xw, yw), &tr_env, &mut g);
        }
        (d, g, tr)
    }

    /// Incident radiance T = Σ_sets L ⊛ V (§6) at texel `(x, y)` (receiver-grid position
    /// `(xw, yw)`), V interpolated from the receiver grid, times the sphere blockers' V_s where
    /// there are blockers; and the environment's part where its visibility is combined with the
    /// blockers' (log mode).
    fn incident(&self, x: usize, y: usize, xw: f64, yw: f64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let (scene, work, t) = (self.scene, self.work, self.t);
        let n = scene.gi.sh_order;
        let mut tr = vec![[0.0f64; 3]; n * n];
        let mut tr_env = vec![[0.0f64; 3]; n * n];
        let mut tr_key = vec![[0.0f64; 3]; n * n];
        for (si, (vis, light)) in self.visibility.iter().zip(self.lighting).enumerate() {
            let combined = self.blockers.and_then(|b| b.environment.as_ref()).filter(|_| si == 0);
            let v = interpolate(combined.unwrap_or(vis), work, xw, yw, scene.wrap);
            // gi.blocker_key_lights = "overlap": a key light scaled by the fraction of its
            // cap the spheres leave open, outside the product with V_s.
            let open = match self.sets[si].0 {
                SetKind::KeyLight(i) if self.blockers.is_some() && self.overlap => Some(key_open(scene, x, y, i)),
                _ => None,
            };
            let into = if combined.is_some() {
                &mut tr_env
            } else if open.is_some() {
                &mut tr_key
            } else {
                &mut tr
            };
            let scale = open.unwrap_or(1.0);
            for ch in 0..3 {
                let l: Vec<f64> = light.iter().map(|c| c[ch]).collect();
                for (k, val) in triple::product(t, &l, &v).into_iter().enumerate() {
                    into[k][ch] += scale * val;
                }
            }
        }
        if let Some(b) = self.blockers {
            let vs = interpolate(&b.spheres, work, xw, yw, scene.wrap);
            tr = crate::reference::blockers::times(t, &tr, &vs);
            for (a, (e, k)) in tr.iter_mut().zip(tr_env.iter().zip(&tr_key)) {
                *a = [a[0] + e[0] + k[0], a[1] + e[1] + k[1], a[2] + e[2] + k[2]];
            }
        }
        (tr, tr_env)
    }

    /// log_brdf: the environment's diffuse term from its transfer `t3` (seed 001 §5), added to
    /// `d`: ρ/π·(π⟨L_env, T_ρ⟩ − ⟨L_env ⊛ V', cc_N⟩).
    fn log_diffuse(
        &self,
        t3: &[Vec<f64>],
        (x, y): (usize, usize),
        (xw, yw): (f64, f64),
        tr_env: &[[f64; 3]],
        d: &mut [f64; 3],
    ) {
        let scene = self.scene;
        let (n, w) = (scene.gi.sh_order, scene.field.width());
        let t3 = interpolate(t3, self.work, xw, yw, scene.wrap);
        let cc = zh::rotate(n, &zh::clamped_cosine(n), self.normals[y * w + x]);
        let rho = self.albedo.as_ref().map_or([0.0; 3], |a| a[y * w + x]);
        for ch in 0..3 {
            let e: f64 = (0..n * n).map(|k| PI * self.lighting[0][k][ch] * t3[k] - tr_env[k][ch] * cc[k]).sum();
            d[ch] += rho[ch] / PI * e;
        }
    }

    /// log_brdf: the environment's glossy term from its glossy transfer `tg` (eq. 27), added to
    /// `g`: k_s·(⟨L_env, T_φ⟩ − ⟨L_env ⊛ V', phong_R⟩).
    fn log_glossy(
        &self,
        (tg, ks): (&[Vec<f64>], [f32; 3]),
        (x, y): (usize, usize),
        (xw, yw): (f64, f64),
        tr_env: &[[f64; 3]],
        g: &mut [f64; 3],
    ) {
        let scene = self.scene;
        let (n, w) = (scene.gi.sh_order, scene.field.width());
        let tg = interpolate(tg, self.work, xw, yw, scene.wrap);
        let gz = self.lobes.phong_at(scene, x, y, self.normals[y * w + x]);
        for ch in 0..3 {
            let e: f64 = (0..n * n).map(|k| self.lighting[0][k][ch] * tg[k] - tr_env[k][ch] * gz[k]).sum();
            g[ch] += ks[ch] as f64 * e;
        }
    }
}
