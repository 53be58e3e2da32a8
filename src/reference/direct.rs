//! CPU (f64) twin of the direct-illumination passes, following docs/direct.md literally:
//! horizon scan (eq. 14–17), NLP projection (eq. 10–11), wedges applied one by one with
//! `M_lin`/`M_bspl` and `Rot_z` (eq. 20–21, not the GPU's folded matrices), SH triple product
//! and ZH shading (§7).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use super::blockers::BlockerVisibility;
use super::pyramid::{rescale, CpuPyramid};
use super::tangent::{receiver_normal, tangent_clip};
use crate::error::Result;
use crate::math::azimuth::{accumulate_with, wedge_matrices, AzimuthSet};
use crate::math::triple::Triple;
use crate::math::Mat;
use crate::math::{elevation, triple, zh};
use crate::rules::lighting::{light_sets, set_lighting, SetKind};
use crate::scene::model::{
    Albedo, DiffuseLobe, ElevationBasis, GiSettings, Horizon, Level0, PyramidMode, Scene, VisibilityMethod,
};

/// Tolerance (texels) of the domain test of docs/direct.md §2.
pub const EDGE_TOL: f64 = 1e-3;

/// Everything the CPU pipeline computes.
pub struct DirectOutput {
    pub width: usize,
    pub height: usize,
    /// Receiver grid.
    pub work: (usize, usize),
    pub direct: Vec<[f64; 3]>,
    pub glossy: Vec<[f64; 3]>,
    pub total: Vec<[f64; 3]>,
    /// Per light set (environment first, then key lights), per receiver, `n²` values.
    pub visibility: Vec<Vec<Vec<f64>>>,
    pub kinds: Vec<SetKind>,
    /// Full-resolution normals.
    pub normals: Vec<[f64; 3]>,
    /// Incident SH radiance `T = Σ L ⊛ V` at every texel (`n²` RGB), the glossy vector
    /// pyramid's input (docs/indirect.md §1).
    pub incident: Vec<Vec<[f64; 3]>>,
    /// The sphere blockers' visibility `V_s` per receiver (scenes with spheres;
    /// [`super::blockers`]): each bounce's incident radiance is multiplied by it too.
    pub blockers: Option<Vec<Vec<f64>>>,
}

/// Scan parameters shared by every receiver (docs/direct.md §2, docs/accuracy.md §4).
pub struct Scan<'a> {
    pub pyr: &'a CpuPyramid,
    pub k_v: u32,
    pub o_v: u32,
    pub texel_size: f64,
    pub wrap: bool,
    /// `gi.level0 = "bilinear"`: level 0 read as the bilinear surface of the samples.
    pub raw0: bool,
    /// `gi.horizon = "samples"`: `ω_max` is the largest blocking angle.
    pub horizon_samples: bool,
    /// Samples before the ladder's first (`gi.near_steps`) and past its last.
    pub near: usize,
    pub far: usize,
    /// Elevation basis of the per-azimuth vectors (`gi.elevation_basis`).
    pub basis: ElevationBasis,
    /// Level-0 probes between two ladder samples, of the bounce being scanned
    /// (`GiSettings::probes`; indirect scans only, `render_gi` sets it per bounce).
    pub probes: usize,
}

impl<'a> Scan<'a> {
    /// The scan of `gi` over `pyr`.
    pub fn new(pyr: &'a CpuPyramid, gi: &GiSettings, texel_size: f64, wrap: bool) -> Self {
        Self {
            pyr,
            k_v: gi.level_step,
            o_v: gi.level_offset,
            texel_size,
            wrap,
            raw0: gi.level0 == Level0::Bilinear,
            horizon_samples: gi.horizon == Horizon::Samples,
            near: gi.near_steps as usize,
            far: gi.far_steps() as usize,
            basis: gi.elevation_basis,
            probes: gi.radial_probes as usize,
        }
    }

    /// Step `t` (texels) of ladder position `idx` (sample `i = idx − near`, eq. 14).
    pub fn step(&self, idx: usize) -> f64 {
        let n_v = self.pyr.layout.count() as i64;
        let l0 = self.pyr.layout.levels[0];
        let i = idx as i64 - self.near as i64;
        (l0.width.max(l0.height) as f64) * 2f64.powf(-((n_v - 1 - i) as f64) / self.k_v as f64)
    }

    /// Blocking angle at level-0 position `q` against the receiver `p`, both on level 0, at
    /// distance `t` texels (a radial probe).
    pub fn probe(&self, p: [f64; 2], q: [f64; 2], t: f64) -> f64 {
        ((self.height(0, q[0], q[1]) - self.height(0, p[0], p[1])) / (t * self.texel_size)).atan()
    }

    /// Level-0 height at `(x, y)` as the scan reads it (the sweep's profile, [`super::sweep`]).
    pub fn height0(&self, x: f64, y: f64) -> f64 {
        self.height(0, x, y)
    }

    /// Height at pyramid level `level`, level-0 position `(x, y)`, as the scan reads it.
    fn height(&self, level: usize, x: f64, y: f64) -> f64 {
        if self.raw0 && level == 0 {
            self.pyr.sample_raw(0, x, y)
        } else {
            self.pyr.height_at(level, x, y)
        }
    }

    /// The near-field limit `t → 0` of the blocking angle (only with near steps; `None` where the
    /// ray leaves the domain at once): the slope of the bilinear level-0 surface at `p` along
    /// `phi` in the cell the ray enters, as the reference's first piece starts.
    pub fn limit(&self, p: [f64; 2], phi: f64) -> Option<f64> {
        if self.near == 0 {
            return None;
        }
        let l0 = self.pyr.layout.levels[0];
        let (dx, dy) = (phi.cos(), phi.sin());
        let e = [p[0] + 1e-3 * dx, p[1] + 1e-3 * dy];
        let (w, h) = (l0.width as f64, l0.height as f64);
        if !self.wrap && (e[0] < 0.0 || e[1] < 0.0 || e[0] > w - 1.0 || e[1] > h - 1.0) {
            return None;
        }
        let (gx, gy) = self.pyr.gradient_in_cell(p[0], p[1], e[0].floor() as i64, e[1].floor() as i64);
        Some(((gx * dx + gy * dy) / self.texel_size).atan())
    }

    /// `ω_max` at level-0 position `p` along azimuth `phi`: the largest blocking angle, or
    /// eq. 17's spline maximum through the ladder's `n_v` samples (and the largest extra one).
    pub fn omega_max(&self, p: [f64; 2], phi: f64) -> f64 {
        let n_v = self.pyr.layout.count();
        let mut ladder = Vec::new();
        let mut extra = self.limit(p, phi).unwrap_or(-FRAC_PI_2);
        for (idx, _, omega) in self.samples(p, phi) {
            let i = idx as i64 - self.near as i64;
            if self.horizon_samples || i < 0 || i >= n_v as i64 {
                extra = extra.max(omega);
            } else {
                ladder.push(omega);
            }
        }
        extra.max(bspline_max(&ladder))
    }

    /// The valid samples of the scan from level-0 position `p` along azimuth `phi`, in order:
    /// `(idx, q, ω)`, `idx` the position in the ladder (sample `i = idx − near`), `t_i` of eq. 14
    /// in texels (`i < 0` inside the first texel, `i ≥ n_v` past `max(W, H)`), the level offset
    /// of §5.2 and `ω_i` of eq. 15; the scan ends at the first sample outside the domain (no
    /// wrap, docs/direct.md §2).
    pub fn samples(&self, p: [f64; 2], phi: f64) -> impl Iterator<Item = (usize, [f64; 2], f64)> + '_ {
        let layout = &self.pyr.layout;
        let n_v = layout.count();
        let l0 = layout.levels[0];
        let (w, h) = (l0.width as f64, l0.height as f64);
        let (dx, dy) = (phi.cos(), phi.sin());
        let near = self.near as i64;
        (0..self.near + n_v + self.far)
            .map(move |idx| {
                let i = idx as i64 - near;
                let t = self.step(idx);
                (idx, i, t, [p[0] + t * dx, p[1] + t * dy])
            })
            .take_while(move |(_, _, _, q)| {
                self.wrap
                    || !(q[0] < -EDGE_TOL || q[1] < -EDGE_TOL || q[0] > w - 1.0 + EDGE_TOL || q[1] > h - 1.0 + EDGE_TOL)
            })
            .map(move |(idx, i, t, q)| {
                let level = scan_level(i, self.k_v, self.o_v, n_v);
                let dh = self.height(level, q[0], q[1]) - self.height(level, p[0], p[1]);
                (idx, q, (dh / (t * self.texel_size)).atan())
            })
    }
}

/// Pyramid level read by scan sample `i` (§5.2 level offset, docs/direct.md §2): the level
/// whose texel matches the step, `k·o` levels finer, `clamp(i − k·o, 0, n_v − 1)`.
pub fn scan_level(i: i64, k_v: u32, o_v: u32, n_v: usize) -> usize {
    (i - (k_v * o_v) as i64).clamp(0, n_v as i64 - 1) as usize
}

/// The steps `τ_i = 2^(−(n_v−1−i)/k)` (units of `max(W, H)`) of every scan sample of `gi` over a
/// pyramid of `n_v` levels, in ladder order from `i = −near_steps`.
pub fn scan_steps(gi: &GiSettings, n_v: usize) -> Vec<f64> {
    let (near, far) = (gi.near_steps as i64, gi.far_steps() as i64);
    (-near..n_v as i64 + far).map(|i| 2f64.powf(-((n_v as i64 - 1 - i) as f64) / gi.level_step as f64)).collect()
}

/// Maximum of the uniform cubic B-spline through `omega` at knots and mid-points, ends
/// extended by repetition (eq. 17); `−π/2` for an empty sequence.
pub fn bspline_max(omega: &[f64]) -> f64 {
    let c = omega.len();
    let at = |i: i64| omega[i.clamp(0, c as i64 - 1) as usize];
    let mut best = -FRAC_PI_2;
    for i in 0..c as i64 {
        best = best.max((at(i - 1) + 4.0 * at(i) + at(i + 1)) / 6.0);
        if (i as usize) + 1 < c {
            best = best.max((at(i - 1) + 23.0 * at(i) + 23.0 * at(i + 1) + at(i + 2)) / 48.0);
        }
    }
    best
}

/// `V` of one light set from the horizon `omega(k, φ_k)` of each of its azimuths: the visible
/// window `[max(ω, lo), hi]` in the elevation basis (§3), accumulated over the wedges (§4).
fn visibility_from(
    scan: &Scan,
    n: usize,
    set: &AzimuthSet,
    mats: &[Mat],
    omega: impl Fn(usize, f64) -> f64,
) -> Vec<f64> {
    let v: Vec<Vec<f64>> = set
        .phi
        .iter()
        .enumerate()
        .map(|(k, &phi)| elevation::interval(scan.basis, n, omega(k, phi).max(set.lo), set.hi))
        .collect();
    accumulate_with(n, set, mats, &v)
}

/// `V` of one light set at every receiver of the `work` grid with the swept horizons
/// ([`super::sweep`], `gi.visibility = "sweep"`, near reach `reach` texels; `normal(r)` the
/// receiver's normal for the tangent clip, [`tangent_clip`]). The azimuth
/// directions are taken in f32, as the GPU reads them, so that both choose the same major axis
/// at 45°.
pub fn sweep_visibility(
    scan: &Scan,
    n: usize,
    set: &AzimuthSet,
    mats: &[Mat],
    work: (usize, usize),
    reach: f64,
    normal: impl Fn(usize) -> Option<[f64; 3]>,
) -> Vec<Vec<f64>> {
    let horizons: Vec<Vec<f64>> = set
        .phi
        .iter()
        .map(|&phi| super::sweep::horizons(scan, work, phi.cos() as f32 as f64, phi.sin() as f32 as f64, reach))
        .collect();
    (0..work.0 * work.1)
        .map(|r| {
            let nrm = normal(r);
            visibility_from(scan, n, set, mats, |k, phi| horizons[k][r].max(tangent_clip(nrm, phi)))
        })
        .collect()
}

/// Bilinear interpolation of per-receiver vectors at `(x, y)` in receiver-grid units (§6).
pub fn interpolate(vis: &[Vec<f64>], work: (usize, usize), x: f64, y: f64, wrap: bool) -> Vec<f64> {
    let (fx, fy) = (x.floor(), y.floor());
    let (tx, ty) = (x - fx, y - fy);
    let idx = |i: i64, n: usize| if wrap { i.rem_euclid(n as i64) as usize } else { i.clamp(0, n as i64 - 1) as usize };
    let (x0, x1, y0, y1) =
        (idx(fx as i64, work.0), idx(fx as i64 + 1, work.0), idx(fy as i64, work.1), idx(fy as i64 + 1, work.1));
    let corners =
        [(x0, y0, (1.0 - tx) * (1.0 - ty)), (x1, y0, tx * (1.0 - ty)), (x0, y1, (1.0 - tx) * ty), (x1, y1, tx * ty)];
    let mut out = vec![0.0; vis[0].len()];
    for (cx, cy, wgt) in corners {
        for (o, v) in out.iter_mut().zip(&vis[cy * work.0 + cx]) {
            *o += wgt * v;
        }
    }
    out
}

/// CONVENTIONS.md normals (periodic central differences with `wrap`).
pub fn normals(scene: &Scene) -> Vec<[f64; 3]> {
    let f = &scene.field;
    let (w, h, s) = (f.width() as i64, f.height() as i64, scene.texel_size);
    let at = |i: i64, j: i64| f.get(i.rem_euclid(w) as usize, j.rem_euclid(h) as usize) as f64;
    let mut out = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let (i0, i1, j0, j1) = if scene.wrap {
                (i - 1, i + 1, j - 1, j + 1)
            } else {
                ((i - 1).max(0), (i + 1).min(w - 1), (j - 1).max(0), (j + 1).min(h - 1))
            };
            let hx = (at(i1, j) - at(i0, j)) / ((i1 - i0) as f64 * s);
            let hy = (at(i, j1) - at(i, j0)) / ((j1 - j0) as f64 * s);
            let n = DVec3::new(-hx, -hy, 1.0).normalize();
            out.push(n.to_array());
        }
    }
    out
}

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
/// (e.g. the exact horizons of [`super::ray`], to measure what the rest of the pipeline —
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
        super::blockers::blocker_visibility(scene, work, &normals, env)
    });
    let albedo = blockers.as_ref().and_then(|b| b.transfer.as_ref()).map(|_| super::truth::albedo(scene));
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
    for (d, l) in direct.iter_mut().zip(super::local::local_exitance(scene, &normals)) {
        *d = [d[0] + l[0], d[1] + l[1], d[2] + l[2]];
    }
    for (g, l) in glossy.iter_mut().zip(super::local::local_glossy(scene, &normals)) {
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
            tr = super::blockers::times(t, &tr, &vs);
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
