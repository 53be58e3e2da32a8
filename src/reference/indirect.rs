//! CPU (f64) twin of the indirect-illumination passes, following docs/indirect.md literally:
//! radiance pyramid of the previous bounce (§5.3), casting-set scan with eq. 6 and eq. 12,
//! wedges with `M_lin`/`M_bspl` and `Rot_z` (eq. 19–21), shading with the BRDF lobes (§7).

use super::direct::{interpolate, normals, render_direct, scan_steps, DirectOutput, Lobes, Scan};
use super::pyramid::{rescale, CpuPyramid};
pub use super::tangent::{omega_min, receiver_normal};
use crate::error::Result;
use crate::math::azimuth::{accumulate_with, wedge_matrices, AzimuthSet};
use crate::math::triple::Triple;
use crate::math::wedge::Mat;
use crate::math::{elevation, zh};
use crate::rules::scene::{radiance_base, radiance_cell};
use crate::scene::model::{Level0, OmegaMin, PyramidMode, Scene};
use glam::DVec3;

/// Direct and indirect results of the whole pipeline.
pub struct GiOutput {
    pub direct: DirectOutput,
    /// Per bounce `b = 1..=B`: diffuse indirect exit radiance (full resolution).
    pub indirect_bounces: Vec<Vec<[f64; 3]>>,
    /// Per bounce: glossy indirect exit radiance toward the camera.
    pub glossy_bounces: Vec<Vec<[f64; 3]>>,
    /// Exported layers (CONVENTIONS.md): `indirect` = Σ_b diffuse, `glossy` = direct + Σ_b
    /// glossy, `total` = direct + indirect + glossy.
    pub indirect: Vec<[f64; 3]>,
    pub glossy: Vec<[f64; 3]>,
    pub total: Vec<[f64; 3]>,
}

/// Radiance-pyramid level read by scan sample `i` at step `t` texels (docs/indirect.md §2):
/// the level whose texel matches `t`, `k_u·o_u` levels finer, clamped to `[0, n_u − 1]`.
pub fn radiance_level(t: f64, k_u: u32, o_u: u32, n_u: usize) -> usize {
    let l = (k_u as f64 * t.log2() + 1e-6).floor() as i64 - (k_u * o_u) as i64;
    l.clamp(0, n_u as i64 - 1) as usize
}

/// NLP vectors `u` (per RGB channel, `n` values each) of one receiver along azimuth `phi`
/// (eq. 6, 8, 12): the casting set above `ω_min`; `radiance(i, q, ω_i)` is the exit radiance
/// of casting-set member `i` at level-0 position `q` toward the receiver.
pub fn scan_radiance(
    scan: &Scan,
    n: usize,
    p: [f64; 2],
    phi: f64,
    normal: [f64; 3],
    tangent: bool,
    radiance: &mut dyn FnMut(usize, [f64; 2], f64) -> [f64; 3],
) -> [Vec<f64>; 3] {
    let (dx, dy) = (phi.cos(), phi.sin());
    let omega_min = omega_min(normal, phi, tangent);
    let e = elevation::size(scan.basis, n);
    let mut u = [vec![0.0; e], vec![0.0; e], vec![0.0; e]];
    let mut running = omega_min;
    // The near-field limit t → 0: the receiver's own surface with its own radiance (level 0).
    // Skipped when narrower than 1e-5 rad (as on the GPU): at the tangent plane its cosine-weighted
    // share is O(width²), and on a plane the two angles differ only by rounding.
    if let Some(limit) = scan.limit(p, phi).filter(|l| *l > running + 1e-5) {
        let seg = elevation::interval(scan.basis, n, running, limit);
        let rad = radiance(usize::MAX, p, limit);
        for (c, uc) in u.iter_mut().enumerate() {
            for (a, b) in uc.iter_mut().zip(&seg) {
                *a += rad[c] * b;
            }
        }
        running = limit;
    }
    // A casting-set member (eq. 6) of ladder position i, seen over [running, ω); eq. 12
    // telescoped.
    let mut cast = |(i, q, omega): Member, running: &mut f64| {
        let seg = elevation::interval(scan.basis, n, *running, omega);
        let rad = radiance(i, q, omega);
        for (c, uc) in u.iter_mut().enumerate() {
            for (a, b) in uc.iter_mut().zip(&seg) {
                *a += rad[c] * b;
            }
        }
        *running = omega;
    };
    // The members: every position above the horizon so far (the last member's ω). With the
    // cast merge (docs/indirect.md §2, "Merged casts") a member less than δ above the last one
    // cast is held instead, and the next one cast covers its interval; the ray's last member
    // held is cast at its end.
    let mut held: Option<Member> = None;
    let mut found = |m: Member, running: &mut f64| {
        if m.2 > held.map_or(*running, |h| h.2) {
            if m.2 - *running >= scan.merge {
                held = None;
                cast(m, running);
            } else {
                held = Some(m);
            }
        }
    };
    let mut t_prev = 0.0;
    for (i, q, omega) in scan.samples(p, phi) {
        // Radial probes, read with this sample's radiance level. (The GPU skips those its
        // max-pyramid bound rules out: the same members.)
        let t = scan.step(i);
        for tp in probe_steps(t_prev, t, scan.probes) {
            let qp = [p[0] + tp * dx, p[1] + tp * dy];
            found((i, qp, scan.probe(p, qp, tp)), &mut running);
        }
        t_prev = t;
        found((i, q, omega), &mut running);
    }
    if let Some(m) = held {
        cast(m, &mut running);
    }
    u
}

/// A casting-set member: its ladder position, its level-0 position and its elevation `ω`.
type Member = (usize, [f64; 2], f64);

/// The radial probes between ladder steps `t_prev` and `t` (texels; docs/accuracy.md §4): when
/// they are more than a texel apart, `n_p = clamp(⌈t − t_prev⌉ − 1, 0, probes)` level-0 samples
/// evenly between them, in order.
pub fn probe_steps(t_prev: f64, t: f64, probes: usize) -> impl Iterator<Item = f64> {
    let np = ((t - t_prev).ceil() as i64 - 1).clamp(0, probes as i64);
    (1..=np).map(move |s| t_prev + (t - t_prev) * s as f64 / (np + 1) as f64)
}

/// The radiance pyramids of one bounce (docs/indirect.md §1): `channels[0..3]` the RGB exit
/// radiance (scalar mode: diffuse + glossy toward the camera; vector mode: diffuse), and in
/// vector mode `channels[3 + 3k + c]` the incident SH coefficient `T_k` of channel `c`.
struct RadianceSource {
    channels: Vec<CpuPyramid>,
    levels: Vec<usize>,
    /// `gi.level0 = "bilinear"`: level 0 is the unfiltered image.
    raw0: bool,
    /// The field's size and the pyramid's level-0 grid ([`radiance_base`]), when they differ:
    /// positions are mapped from the one to the other.
    to_base: Option<((usize, usize), (usize, usize))>,
}

impl RadianceSource {
    fn at(&self, channel: usize, level: usize, q: [f64; 2]) -> f64 {
        let c = &self.channels[channel];
        let q = match self.to_base {
            Some(((w, h), (bw, bh))) => [rescale(q[0], w, bw), rescale(q[1], h, bh)],
            None => q,
        };
        if self.raw0 && level == 0 {
            c.sample_raw(0, q[0], q[1])
        } else {
            c.height_at(level, q[0], q[1])
        }
    }
}

/// Exit radiance of the casting point `q` toward the receiver (direction of elevation `ω`
/// along `φ`, seen from the receiver), docs/indirect.md §2.
fn member_radiance(
    scene: &Scene,
    src: &RadianceSource,
    phong: &[f64],
    i: usize,
    q: [f64; 2],
    omega: f64,
    phi: f64,
) -> [f64; 3] {
    let level = src.levels.get(i).copied().unwrap_or(0); // usize::MAX: the t → 0 limit, level 0
    let mut rad = [0, 1, 2].map(|c| src.at(c, level, q));
    if src.channels.len() > 3 {
        let n = scene.gi.sh_order;
        let ks = scene.material.specular.unwrap_or([0.0; 3]);
        // Outgoing direction s from q toward the receiver, reflected about q's normal.
        let nc = DVec3::from_array(receiver_normal(scene, q));
        let s = -DVec3::new(omega.cos() * phi.cos(), omega.cos() * phi.sin(), omega.sin());
        let r = (2.0 * nc.dot(s) * nc - s).normalize();
        let lobe = zh::rotate(n, phong, r.to_array());
        for (k, l) in lobe.iter().enumerate() {
            for (c, v) in rad.iter_mut().enumerate() {
                *v += ks[c] as f64 * l * src.at(3 + 3 * k + c, level, q);
            }
        }
    }
    rad
}

/// The mean of the `size` texels in each cell of a `base` grid ([`radiance_cell`]): level 0 of
/// a sub-sampled scene's radiance pyramid (docs/indirect.md §1).
fn average_to(data: &[f64], size: (usize, usize), base: (usize, usize)) -> Vec<f64> {
    let mut sum = vec![0.0; base.0 * base.1];
    let mut count = vec![0u32; base.0 * base.1];
    for y in 0..size.1 {
        let row = radiance_cell(y, size.1, base.1) * base.0;
        for x in 0..size.0 {
            let cell = row + radiance_cell(x, size.0, base.0);
            sum[cell] += data[y * size.0 + x];
            count[cell] += 1;
        }
    }
    sum.iter().zip(&count).map(|(s, &n)| if n == 0 { 0.0 } else { s / n as f64 }).collect()
}

/// Direct light plus `scene.gi.bounces` indirect bounces on the CPU.
pub fn render_gi(scene: &Scene) -> Result<GiOutput> {
    let direct = render_direct(scene)?;
    let gi = &scene.gi;
    let n = gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let work = direct.work;
    let stack = gi.pyramid == PyramidMode::Stack;
    let z0 = crate::rules::scene::height_origin(&scene.field);
    let pyr = CpuPyramid::build_relative(&scene.field, z0, work, gi.level_step, scene.wrap, stack)?;
    let mut scan = Scan::new(&pyr, gi, scene.texel_size, scene.wrap);
    let tangent = gi.omega_min == OmegaMin::Tangent;
    // The first bounce's azimuth set and the later bounces' (`gi.azimuths_later`).
    let sets = [1, 2].map(|b| {
        let set = crate::rules::lighting::environment_set(gi, gi.scan_azimuths(b));
        let mats = wedge_matrices(n, &set, gi.interpolation, gi.elevation_basis);
        (set, mats)
    });
    let lobes = Lobes::new(scene);
    let nrm = normals(scene);
    let tri = crate::math::triple::triple(n);
    let n_v = pyr.layout.count();

    // Bounce 0: the direct light. Scalar pyramid: diffuse + glossy toward the camera; vector
    // pyramid: diffuse + the incident SH radiance T (true pyramid always).
    let vector = crate::rules::scene::vector_pyramid(scene);
    let add = |d: &[[f64; 3]], g: &[[f64; 3]]| -> Vec<[f64; 3]> {
        d.iter().zip(g).map(|(d, g)| [d[0] + g[0], d[1] + g[1], d[2] + g[2]]).collect()
    };
    let (mut diffuse_src, mut glossy_src, mut incident) =
        (direct.direct.clone(), direct.glossy.clone(), direct.incident.clone());
    let mut indirect_bounces = Vec::new();
    let mut glossy_bounces = Vec::new();
    for bounce in 1..=gi.bounces {
        scan.probes = gi.probes(bounce) as usize;
        scan.merge = gi.merge(bounce);
        let mut images: Vec<Vec<f64>> = if vector {
            (0..3).map(|c| diffuse_src.iter().map(|v| v[c]).collect()).collect()
        } else {
            let s = add(&diffuse_src, &glossy_src);
            (0..3).map(|c| s.iter().map(|v| v[c]).collect()).collect()
        };
        if vector {
            for k in 0..n * n {
                for c in 0..3 {
                    images.push(incident.iter().map(|t| t[k][c]).collect());
                }
            }
        }
        let src = radiance_source(scene, images, work, n_v, stack && !vector)?;
        let channels = u_grid(scene, &scan, &src, &sets[(bounce > 1) as usize], &lobes, work, tangent);
        drop(src);
        let (diffuse, glossy, next_incident) = shade_bounce(scene, &direct, &lobes, &nrm, tri, &channels, work);
        diffuse_src = diffuse.clone();
        glossy_src = glossy.clone();
        incident = next_incident;
        indirect_bounces.push(diffuse);
        glossy_bounces.push(glossy);
    }
    let sum = |base: Vec<[f64; 3]>, parts: &[Vec<[f64; 3]>]| {
        let mut out = base;
        for p in parts {
            for (o, v) in out.iter_mut().zip(p) {
                for c in 0..3 {
                    o[c] += v[c];
                }
            }
        }
        out
    };
    let indirect = sum(vec![[0.0; 3]; w * h], &indirect_bounces);
    let glossy = sum(direct.glossy.clone(), &glossy_bounces);
    let total = sum(direct.direct.clone(), &[indirect.clone(), glossy.clone()]);
    Ok(GiOutput { direct, indirect_bounces, glossy_bounces, indirect, glossy, total })
}

/// The radiance pyramid a bounce reads (docs/indirect.md §1–2): the exit-radiance `images` (RGB,
/// then in vector mode the incident SH coefficients), averaged to the radiance base grid where it
/// is the working grid, decimated, with the ladder's radiance level per scan sample.
fn radiance_source(
    scene: &Scene,
    images: Vec<Vec<f64>>,
    work: (usize, usize),
    n_v: usize,
    mode_stack: bool,
) -> Result<RadianceSource> {
    let gi = &scene.gi;
    let (w, h) = (scene.field.width(), scene.field.height());
    let base = radiance_base(scene);
    let channels: Vec<CpuPyramid> = images
        .into_iter()
        .map(|data| {
            let data = if base == (w, h) { data } else { average_to(&data, (w, h), base) };
            CpuPyramid::build_f64(data, base, work, gi.radiance_level_step, scene.wrap, mode_stack)
        })
        .collect::<Result<_>>()?;
    let n_u = channels[0].layout.count();
    // The ladder's steps in the base grid's texels (docs/indirect.md §2).
    let n_base = base.0.max(base.1) as f64;
    let levels: Vec<usize> = scan_steps(gi, n_v)
        .into_iter()
        .map(|tau| radiance_level(n_base * tau, gi.radiance_level_step, gi.radiance_level_offset, n_u))
        .collect();
    let to_base = (base != (w, h)).then_some(((w, h), base));
    Ok(RadianceSource { channels, levels, raw0: gi.level0 == Level0::Bilinear, to_base })
}

/// U at every receiver of the working grid, per channel (eq. 19–21), over the azimuth set `set`
/// with its wedge matrices.
fn u_grid(
    scene: &Scene,
    scan: &Scan,
    src: &RadianceSource,
    (set, mats): &(AzimuthSet, Vec<Mat>),
    lobes: &Lobes,
    work: (usize, usize),
    tangent: bool,
) -> [Vec<Vec<f64>>; 3] {
    let n = scene.gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let u_grid: Vec<[Vec<f64>; 3]> = (0..work.0 * work.1)
        .map(|r| {
            let p = [rescale((r % work.0) as f64, work.0, w), rescale((r / work.0) as f64, work.1, h)];
            let normal = receiver_normal(scene, p);
            let per_phi: Vec<[Vec<f64>; 3]> = set
                .phi
                .iter()
                .map(|&phi| {
                    let mut rad = |i, q, omega| member_radiance(scene, src, &lobes.phong, i, q, omega, phi);
                    scan_radiance(scan, n, p, phi, normal, tangent, &mut rad)
                })
                .collect();
            [0, 1, 2].map(|c| {
                let v: Vec<Vec<f64>> = per_phi.iter().map(|u| u[c].clone()).collect();
                accumulate_with(n, set, mats, &v)
            })
        })
        .collect();
    [0, 1, 2].map(|c| u_grid.iter().map(|u| u[c].clone()).collect())
}

/// A bounce's shading at every texel from U (`channels`, interpolated from the working grid),
/// times the sphere blockers' visibility where there are blockers: the diffuse and glossy exit
/// radiance and the incident SH radiance.
#[allow(clippy::type_complexity)]
fn shade_bounce(
    scene: &Scene,
    direct: &DirectOutput,
    lobes: &Lobes,
    nrm: &[[f64; 3]],
    tri: &Triple,
    channels: &[Vec<Vec<f64>>; 3],
    work: (usize, usize),
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<Vec<[f64; 3]>>) {
    let n = scene.gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let mut diffuse = Vec::with_capacity(w * h);
    let mut glossy = Vec::with_capacity(w * h);
    let mut incident = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (xw, yw) = (rescale(x as f64, w, work.0), rescale(y as f64, h, work.1));
            let uc: Vec<Vec<f64>> = channels.iter().map(|c| interpolate(c, work, xw, yw, scene.wrap)).collect();
            let mut tr: Vec<[f64; 3]> = (0..n * n).map(|k| [uc[0][k], uc[1][k], uc[2][k]]).collect();
            if let Some(b) = &direct.blockers {
                // The sphere blockers shade the bounce light too (docs/blockers.md §4).
                tr = super::blockers::times(tri, &tr, &interpolate(b, work, xw, yw, scene.wrap));
            }
            let (d, g) = lobes.shade(scene, x, y, nrm[y * w + x], &tr);
            diffuse.push(d);
            glossy.push(g);
            incident.push(tr);
        }
    }
    (diffuse, glossy, incident)
}
