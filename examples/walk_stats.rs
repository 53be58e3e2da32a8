//! How long the first bounce's indirect walks are, how much of them a bound on the heights
//! could skip, and how busy the lanes are (docs/performance.md §24). A diagnostic of the f64
//! twin's walk (no GPU; seconds at 128²):
//!
//!     cargo run --release --example walk_stats -- scenes/hard/spikes.toml [--bounds] [KEY=VALUE ...]
//!
//! For every receiver and each of the scene's first-bounce azimuths it walks the ladder with its
//! radial probes as `glsl/indirect/scan.comp.glsl` does (the twin's heights, ω_min and near-field
//! limit; the probed walk and the probe-less walk whose members the replay records) and counts
//! the positions (probes and samples) on the ray, those read before the GPU's early stop — the
//! field's largest height against the probe-less horizon —, before a tighter stop (the largest
//! height of the half-plane ahead of the position), and up to the last member of either walk (an
//! oracle: no conservative stop can end sooner), before the early stop against the probed walk's
//! own horizon, and before an ideal slope-aware stop (one that knows the heights ahead, with the
//! horizon's slope exact or rounded down to 8 tabulated slopes; docs/performance.md §35), and
//! how long the 4 × 2 blocks hold their lanes with the early stop, the oracle and the ideal
//! stops (docs/performance.md §32). With `--bounds` the per-ray figures are taken
//! on every fourth receiver in x and y, with one more stop: the largest height of the cone ahead
//! that holds every texel a later read reaches through the stack's filters (sized for `k = 4`,
//! `o = 6`; no wrap). Then the lane occupancy — the lanes' work over the work of every lane
//! running as long as its group's busiest — of the 4 × 2 blocks of `hfgi_receiver` (lavapipe's
//! SIMD lanes), of four other assignments of rays to lanes, and of lanes on lines of 8
//! receivers: rows, lines along each azimuth, lines across it (docs/performance.md §31).
use std::f64::consts::PI;
use std::io::Write;
use std::path::Path;

use hfgi::reference::direct::{scan_level, Scan};
use hfgi::reference::indirect::{omega_min, probe_steps, receiver_normal};
use hfgi::reference::pyramid::CpuPyramid;
use hfgi::rules::lighting::environment_set;
use hfgi::scene::file::load_scene;
use hfgi::scene::model::{OmegaMin, Scene};

/// One ray: positions on it (to its end), read before the early stop, the half-plane stop and
/// the cone stop, up to its last member; the members of the probed walk.
#[derive(Default, Clone, Copy)]
struct Ray {
    all: u32,
    global: u32,
    half: u32,
    cone: u32,
    oracle: u32,
    members: u32,
    own: u32,
    plain_members: u32,
    slope_aware: u32,
    bucketed: u32,
}

/// The slopes an ideal slope-aware stop is tabulated at (tan of the horizon's elevation).
const SLOPE_BUCKETS: [f64; 8] = [-1.0, -0.5, -0.25, 0.0, 0.125, 0.25, 0.5, 1.0];

/// The largest of `SLOPE_BUCKETS` at or below `s` (−∞ below them all).
fn slope_bucket(s: f64) -> f64 {
    SLOPE_BUCKETS.iter().copied().filter(|b| *b <= s).fold(f64::NEG_INFINITY, f64::max)
}

/// An ideal slope-aware stop (docs/performance.md §35): the first position from which no read of
/// the rest of the ray rises above the probe-less horizon's slope before it, rounded by `round`
/// (a table could only hold a few slopes). Ideal: it knows the heights the walk will read, with
/// no stack filter footprint; `reads` are (t, Δh, that slope) per position.
fn slope_aware_stop(reads: &[(f64, f64, f64)], texel: f64, round: fn(f64) -> f64) -> u32 {
    let below = |k: usize, s: f64| reads[k..].iter().all(|(t, dh, _)| *dh <= s * t * texel);
    (0..reads.len()).find(|&k| below(k, round(reads[k].2))).unwrap_or(reads.len()) as u32
}

/// The largest level-0 height ahead of a position along one azimuth: of the half-plane
/// `s ≥ s₀`, and of the cone from the receiver (`|o| ≤ 0.39 s + 1.5`, `s ≥ 0.77 t − 1`), which
/// holds every texel a read at `t' ≥ t` reaches through the stack's filters (B-spline ±2 texels
/// of level `L` plus the bilinear decimation chain, ≤ 0.23 t' + 1 texels at `k = 4`, `o = 6`).
struct Ahead {
    half: Vec<f64>,
    smin: f64,
    cone: Vec<(f64, f64)>,
}

impl Ahead {
    fn new(l0: &[f64], w: usize, h: usize, d: [f64; 2], p: Option<[f64; 2]>) -> Self {
        let smin = -((w + h) as f64);
        let mut half = vec![f64::MIN; 4 * (w + h) + 4];
        let mut cone = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = l0[y * w + x];
                let b = ((x as f64 * d[0] + y as f64 * d[1] - smin) * 2.0) as usize;
                half[b] = half[b].max(v);
                if let Some(p) = p {
                    let (ex, ey) = (x as f64 - p[0], y as f64 - p[1]);
                    let (s, o) = (ex * d[0] + ey * d[1], (ey * d[0] - ex * d[1]).abs());
                    if s >= -2.0 && o <= 0.39 * s.max(0.0) + 1.5 {
                        cone.push((s, v));
                    }
                }
            }
        }
        for b in (0..half.len() - 1).rev() {
            half[b] = half[b].max(half[b + 1]);
        }
        cone.sort_by(|a, b| a.0.total_cmp(&b.0));
        for k in (0..cone.len().saturating_sub(1)).rev() {
            cone[k].1 = cone[k].1.max(cone[k + 1].1);
        }
        Self { half, smin, cone }
    }

    fn half_from(&self, s: f64) -> f64 {
        let b = ((s - self.smin) * 2.0).floor().max(0.0) as usize;
        self.half.get(b).copied().unwrap_or(f64::MIN)
    }

    fn cone_from(&self, t: f64) -> f64 {
        let k = self.cone.partition_point(|e| e.0 < 0.77 * t - 1.0);
        self.cone.get(k).map_or(f64::MIN, |e| e.1)
    }
}

/// The walk of receiver `p` along azimuth `phi` (see the file's comment).
fn walk(scene: &Scene, scan: &Scan, pyr: &CpuPyramid, p: [f64; 2], phi: f64, gmax: f64, ahead: &Ahead) -> Ray {
    let gi = &scene.gi;
    let texel = scene.texel_size;
    let n_v = pyr.layout.count();
    let d = [phi.cos(), phi.sin()];
    let tangent = gi.omega_min == OmegaMin::Tangent;
    let mut running = omega_min(receiver_normal(scene, p), phi, tangent);
    if let Some(limit) = scan.limit(p, phi).filter(|l| *l > running + 1e-5) {
        running = limit;
    }
    // The receiver's height at each level, which samples of that level are compared with, and
    // the lowest of the levels the ladder reads (hfgi_scan_levels).
    let base: Vec<f64> = (0..n_v).map(|l| pyr.height_at(l, p[0], p[1])).collect();
    let top = scan_level((n_v + gi.far_steps() as usize) as i64 - 1, gi.level_step, gi.level_offset, n_v);
    let bmin = base[..=top].iter().copied().fold(f64::MAX, f64::min);
    let (mut walk, mut plain) = (running.tan(), running.tan());
    let sp = p[0] * d[0] + p[1] * d[1];
    let mut ray = Ray::default();
    let (mut pos, mut stops) = (0u32, [None::<u32>; 4]);
    // Every read: (t, Δh, the probe-less horizon's slope before it).
    let mut reads: Vec<(f64, f64, f64)> = Vec::new();
    let mut visit = |tp: f64, q: [f64; 2], level: usize, probe: bool| {
        // Each stop's bound and the horizon it is held to: the shipped one, the half-plane and
        // the cone against the probe-less horizon, and the shipped one against the probed walk's.
        let half = ahead.half_from(sp + 0.77 * tp - 1.0);
        let checks = [(gmax, plain), (half, plain), (ahead.cone_from(tp), plain), (gmax, walk)];
        for (stop, (bound, slope)) in stops.iter_mut().zip(checks) {
            if stop.is_none() && bound - bmin <= slope * tp * texel {
                *stop = Some(pos);
            }
        }
        let dh = pyr.height_at(level, q[0], q[1]) - base[level];
        reads.push((tp, dh, plain));
        pos += 1;
        if dh > walk * tp * texel {
            walk = dh / (tp * texel);
            ray.oracle = pos;
            ray.members += 1;
        }
        if !probe && dh > plain * tp * texel {
            plain = dh / (tp * texel);
            ray.oracle = pos;
            ray.plain_members += 1;
        }
    };
    let mut t_prev = 0.0;
    for (idx, q, _) in scan.samples(p, phi) {
        let t = scan.step(idx);
        let level = scan_level(idx as i64 - gi.near_steps as i64, gi.level_step, gi.level_offset, n_v);
        for tp in probe_steps(t_prev, t, scan.probes) {
            visit(tp, [p[0] + tp * d[0], p[1] + tp * d[1]], 0, true);
        }
        t_prev = t;
        visit(t, q, level, false);
    }
    ray.all = pos;
    let ends = |round: fn(f64) -> f64| slope_aware_stop(&reads, texel, round);
    let (exact, bucketed) = (ends(|s| s), ends(slope_bucket));
    let [g, hp, c, own] = stops.map(|s| s.unwrap_or(pos));
    (ray.global, ray.half, ray.cone, ray.own) = (g, hp.max(ray.oracle), c.max(ray.oracle), own);
    (ray.slope_aware, ray.bucketed) = (exact.min(ray.global), bucketed.min(ray.global));
    ray
}

/// Rays by azimuth, 4 × 2 block and lane.
type Rays = Vec<Vec<Vec<Ray>>>;

/// Every ray along the azimuths `phis` (the environment's set, which the first bounce scans), as `[azimuth][4 × 2 block][lane]`, and the
/// per-ray means of `Ray`'s counts (with `bounds`, over every fourth receiver in x and y).
fn walk_all(scene: &Scene, phis: &[f64], bounds: bool) -> Result<(Rays, [f64; 10]), Box<dyn std::error::Error>> {
    let gi = &scene.gi;
    let (w, h) = (scene.field.width(), scene.field.height());
    let z0 = hfgi::rules::scene::height_origin(&scene.field);
    let pyr = CpuPyramid::build_relative(&scene.field, z0, (w, h), gi.level_step, scene.wrap, true)?;
    let scan = Scan::new(&pyr, gi, scene.texel_size, scene.wrap);
    let l0 = &pyr.levels[0];
    let gmax = l0.iter().copied().fold(f64::MIN, f64::max);
    let (mut sum, mut rays) = ([0f64; 10], 0f64);
    let mut per = Vec::new();
    for &phi in phis {
        let d = [phi.cos(), phi.sin()];
        let plane = Ahead::new(l0, w, h, d, None);
        let mut blocks = Vec::new();
        for (gx, gy) in (0..h.div_ceil(2)).flat_map(|y| (0..w.div_ceil(4)).map(move |x| (x, y))) {
            let mut block = Vec::new();
            for (x, y) in (0..8).map(|l| (gx * 4 + l % 4, gy * 2 + l / 4)).filter(|&(x, y)| x < w && y < h) {
                let p = [x as f64, y as f64];
                let sub = bounds && x % 4 == 0 && y % 4 == 0;
                let cone = sub.then(|| Ahead::new(l0, w, h, d, Some(p)));
                let ray = walk(scene, &scan, &pyr, p, phi, gmax, cone.as_ref().unwrap_or(&plane));
                block.push(ray);
                if !bounds || sub {
                    let r = [
                        ray.all,
                        ray.global,
                        ray.half,
                        ray.cone,
                        ray.oracle,
                        ray.members,
                        ray.own,
                        ray.plain_members,
                        ray.slope_aware,
                        ray.bucketed,
                    ];
                    sum.iter_mut().zip(r).for_each(|(s, v)| *s += v as f64);
                    rays += 1.0;
                }
            }
            blocks.push(block);
        }
        per.push(blocks);
    }
    Ok((per, sum.map(|s| s / rays)))
}

/// Lane occupancy of SIMD groups (each a list of the lanes' work: positions, members): the
/// work done over the work of every lane running as long as the group's longest.
fn occupancy(groups: impl Iterator<Item = Vec<[u32; 2]>>) -> String {
    let (done, held, _) = lane_sums(groups);
    format!("positions {:.0}%, members {:.0}%", 100.0 * done[0] / held[0], 100.0 * done[1] / held[1])
}

/// Of SIMD groups (each a list of the lanes' two kinds of work): the work done, the work of
/// every lane running as long as its group's longest, and the lanes.
fn lane_sums(groups: impl Iterator<Item = Vec<[u32; 2]>>) -> ([f64; 2], [f64; 2], f64) {
    let (mut done, mut held, mut lanes) = ([0f64; 2], [0f64; 2], 0f64);
    for g in groups {
        for k in 0..2 {
            done[k] += g.iter().map(|w| w[k]).sum::<u32>() as f64;
            held[k] += g.iter().map(|w| w[k]).max().unwrap_or(0) as f64 * g.len() as f64;
        }
        lanes += g.len() as f64;
    }
    (done, held, lanes)
}

/// The lane occupancy of the shipped assignment and of three others (see the file's comment).
fn report_lanes(out: &mut impl Write, per: &[Vec<Vec<Ray>>]) -> std::io::Result<()> {
    let m = per.len();
    let work = |r: &Ray| [r.global, r.members];
    let blocks = per[0].len();
    let lanes = |b: usize| per[0][b].len();
    // Positions per ray that the 4 × 2 blocks' lanes are held for: every lane walks as long as
    // its block's longest ray, ended by the GPU's early stop or, were each ray's end known
    // beforehand, at its last member (the oracle).
    let stops = per.iter().flatten().map(|b| b.iter().map(|r| [r.global, r.oracle]).collect());
    let (_, held, rays) = lane_sums(stops);
    let ideal = per.iter().flatten().map(|b| b.iter().map(|r| [r.slope_aware, r.bucketed]).collect());
    let (_, ideal, _) = lane_sums(ideal);
    let (g, o) = (held[0] / rays, held[1] / rays);
    writeln!(out, "  positions per ray the 4 × 2 blocks hold their lanes for: early stop {g:.1}, oracle {o:.1}")?;
    let (sa, bu) = (ideal[0] / rays, ideal[1] / rays);
    writeln!(out, "    … with the ideal slope-aware stop {sa:.1}, its slope in 8 buckets {bu:.1}")?;
    writeln!(out, "  lane occupancy (work done / work of lanes kept waiting):")?;
    let shipped = per.iter().flat_map(|js| js.iter().map(|b| b.iter().map(work).collect()));
    writeln!(out, "    4 × 2 blocks, one ray each (shipped): {}", occupancy(shipped))?;
    // Each lane runs the rays of φ_j + k·2π/r, k < r, one after the other.
    let back_to_back = |r: usize| {
        (0..m / r).flat_map(move |j| {
            (0..blocks).map(move |b| {
                (0..lanes(b))
                    .map(|l| {
                        (0..r).map(|k| work(&per[j + k * m / r][b][l])).fold([0, 0], |a, w| [a[0] + w[0], a[1] + w[1]])
                    })
                    .collect()
            })
        })
    };
    writeln!(out, "    4 × 2 blocks, the rays of φ and φ + π one after the other: {}", occupancy(back_to_back(2)))?;
    writeln!(out, "    4 × 2 blocks, the rays of φ + kπ/2 one after the other: {}", occupancy(back_to_back(4)))?;
    let octets = (0..blocks).flat_map(|b| {
        (0..lanes(b)).flat_map(move |l| (0..m / 8).map(move |o| (0..8).map(|k| work(&per[8 * o + k][b][l])).collect()))
    });
    writeln!(out, "    one receiver, 8 neighbouring azimuths: {}", occupancy(octets))?;
    let mut keys: Vec<(u32, usize, usize)> = (0..blocks)
        .flat_map(|b| (0..lanes(b)).map(move |l| ((0..m).map(|j| per[j][b][l].members).sum(), b, l)))
        .collect();
    keys.sort_unstable();
    let sorted =
        keys.chunks(8).flat_map(|c| (0..m).map(move |j| c.iter().map(|&(_, b, l)| work(&per[j][b][l])).collect()));
    writeln!(out, "    8 receivers of similar total members (sorted): {}", occupancy(sorted))?;
    Ok(())
}

/// The work of receiver (x, y)'s ray of azimuth j (`per`'s 4 × 2 blocks, full blocks only).
fn at(per: &[Vec<Vec<Ray>>], w: usize, j: usize, x: usize, y: usize) -> [u32; 2] {
    let r = &per[j][(y / 2) * w.div_ceil(4) + x / 4][(x % 4) + 4 * (y % 2)];
    [r.global, r.members]
}

/// Lanes as 8 receivers on a row or a column: of every azimuth a row, or per azimuth the axis
/// nearer its direction (the lanes' rays run along one line), or the axis nearer the
/// perpendicular (their rays run side by side).
fn report_aligned(
    out: &mut impl Write,
    per: &[Vec<Vec<Ray>>],
    w: usize,
    h: usize,
    phis: &[f64],
) -> std::io::Result<()> {
    // The axis nearer the direction φ: rows (1, 0) or columns (0, 1).
    let axis = |phi: f64| if phi.cos().abs() >= phi.sin().abs() { (1, 0) } else { (0, 1) };
    let modes = [("rows of 8 (every azimuth)", 0), ("rows or columns of 8 along the azimuth", 1), ("… across it", 2)];
    for (name, mode) in modes {
        let groups = (0..per.len()).flat_map(|j| {
            let step = match mode {
                0 => (1, 0),
                1 => axis(phis[j]),
                _ => axis(phis[j] + 0.5 * PI),
            };
            let mut gs: Vec<Vec<[u32; 2]>> = Vec::new();
            if step == (0, 1) {
                for x in 0..w {
                    for y0 in (0..h).step_by(8) {
                        gs.push((y0..(y0 + 8).min(h)).map(|y| at(per, w, j, x, y)).collect());
                    }
                }
            } else {
                for y in 0..h {
                    for x0 in (0..w).step_by(8) {
                        gs.push((x0..(x0 + 8).min(w)).map(|x| at(per, w, j, x, y)).collect());
                    }
                }
            }
            gs
        });
        writeln!(out, "    {name}: {}", occupancy(groups))?;
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: walk_stats SCENE [--bounds] [KEY=VALUE ...]")?;
    let bounds = args.iter().any(|a| a == "--bounds");
    let sets: Vec<String> = args[2..].iter().filter(|a| a.contains('=')).cloned().collect();
    let scene = load_scene(Path::new(path), &sets)?;
    let phis = environment_set(&scene.gi, scene.gi.azimuths).phi;
    let (per, [all, g, hp, c, o, mem, own, pm, ex, bk]) = walk_all(&scene, &phis, bounds)?;
    let mut out = std::io::stdout().lock();
    let (w, h) = (scene.field.width(), scene.field.height());
    writeln!(out, "{path} ({w}×{h}, {} azimuths): positions (probes and samples) read per ray:", per.len())?;
    writeln!(out, "  to the ray's end {all:.1}; before the early stop {g:.1}; the half-plane stop {hp:.1}")?;
    if bounds {
        writeln!(out, "  the cone stop {c:.1} (every fourth receiver in x and y)")?;
    }
    writeln!(out, "  up to the last member (oracle) {o:.1}; members of the probed walk per ray {mem:.2}")?;
    writeln!(
        out,
        "  the early stop at the probed walk's own horizon {own:.1}; members of the probe-less walk per ray {pm:.2}"
    )?;
    writeln!(out, "  an ideal slope-aware stop {ex:.1}, its slope in 8 buckets {bk:.1}")?;
    report_lanes(&mut out, &per)?;
    report_aligned(&mut out, &per, w, h, &phis)?;
    Ok(())
}
