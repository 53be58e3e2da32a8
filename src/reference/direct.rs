//! CPU (f64) twin of the direct-illumination passes, following docs/direct.md literally:
//! horizon scan (eq. 14–17), NLP projection (eq. 10–11), wedges applied one by one with
//! `M_lin`/`M_bspl` and `Rot_z` (eq. 20–21, not the GPU's folded matrices), SH triple product
//! and ZH shading (§7).

use std::f64::consts::FRAC_PI_2;

use glam::DVec3;

use super::pyramid::CpuPyramid;
use super::tangent::tangent_clip;
use crate::math::azimuth::{accumulate_with, AzimuthSet};
use crate::math::elevation;
use crate::math::Mat;
use crate::rules::lighting::SetKind;
use crate::scene::model::{ElevationBasis, GiSettings, Horizon, Level0, Scene};

mod shade;
pub use shade::{render_direct, render_direct_with_horizons, HorizonFn, Lobes};

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
    /// The cast merge `δ` (rad) of the bounce being scanned (`GiSettings::merge`; indirect scans
    /// only, `render_gi` sets it per bounce; docs/indirect.md §2): a casting-set member less
    /// than `δ` above the last member cast is not cast.
    pub merge: f64,
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
            merge: gi.cast_merge,
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
