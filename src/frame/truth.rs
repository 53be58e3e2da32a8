//! Stage `reference.truth`: the brute-force ground truth of CONVENTIONS.md on the GPU
//! (`glsl/reference/truth.comp.glsl`; docs/accuracy.md §1). The shader integrates per texel
//! (irradiance, or the SH projections `V`/`U`); the host finishes each texel in f64 with
//! [`crate::reference::truth::Finisher`], exactly as the CPU version
//! ([`crate::reference::truth::render_truth`]) does, and feeds each bounce's exit radiance to
//! the next. Work is split into bands of rows, one submission each, so that a long reference
//! reports progress and never holds the queue for long.
//!
//! Key lights of the exact reference are true caps: the host computes each cap's azimuth
//! samples `(φ, weight)` ([`crate::reference::cap::cap_azimuths`]) into one buffer (binding 6),
//! and a direct pass is the environment's dispatches over the uniform azimuths followed, per key
//! light, by dispatches over that light's samples with its direction, `cos α`, `sin α` and
//! radiance in the push constants (`cap = 1`), all accumulating into the output buffer.
//!
//! Local lights (both variants; [`crate::reference::local_truth`] is the f64 twin): their cap
//! differs per receiver, so the shader forms it per texel (`cap = 2`, one light per dispatch:
//! its centre as a high and a low f32, `(c_hi − P) + c_lo`, its radius and radiance in the push
//! constants) and takes its azimuth samples from the first `cap_nodes` entries of the cap
//! buffer (`(sin u, π/2·w·cos u)`, [`crate::reference::local_truth::cap_node_factors`]) or, for
//! a cap holding a pole, the `A` uniform azimuths; the dispatches run over
//! `max(A, cap_nodes)` samples, each texel skipping those beyond its own count. They accumulate
//! `E = Σ L ∫ max(N·ω, 0) dω` into a region of the output buffer after the `W·H·n²` texels',
//! which the host adds as `ρ/π · E` to the finished direct exit radiance, as the CPU does.
//!
//! Sphere blockers (both variants; [`crate::reference::cap::SphereCaps`] and `gaps` are the
//! f64 twins): the spheres go to binding 7 (per sphere its centre as a high and a low f32 and
//! its radius), their count is specialization constant 5. A receiver inside one gets nothing.
//! The direct pass adds, after the key lights, the sphere dispatches (`cap = 3`): over the
//! flattened samples `[0, S·max(A, cap_nodes))` (sphere `a / M`, its per-receiver sample
//! `a % M`, chosen like a local light's), each takes out the environment on its window within
//! the open interval, less the windows of the spheres before it. The key-light dispatches
//! integrate their window minus every sphere's window, the local lights' and the bounces'
//! nodes drop what a sphere hides (docs/accuracy.md §1).
//!
//! This is a measuring tool, not a frame pass: it owns its buffers and submits on its own
//! (`Context::submit_and_wait`).

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::shared::TruthPush;
use crate::error::Result;
use crate::math::quadrature::gauss_legendre;
use crate::reference::direct::normals;
use crate::reference::local_truth::cap_node_factors;
use crate::reference::truth::{albedo, environment_sh, key_caps, lighting_sh, Finisher, TruthOutput, TruthSettings};
use crate::scene::model::Scene;
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder, StageTimer};

pub const STAGE_TRUTH: &str = super::stages::stage_name("reference.truth");

/// Loop iterations one invocation may run per dispatch. lavapipe silently ends an invocation's
/// loops after 65535 iterations in total (measured: a 16² flat field lost 45% of its light at
/// 256 azimuths in one dispatch; a 512-texel periodic march lost 2 of 16 azimuths), so the
/// azimuth integral is accumulated over dispatches that stay well below that.
pub const LOOP_BUDGET: u64 = 40_000;

/// Loop iterations of one ray: pieces of the exact intersection (one per crossing of an integer
/// line: at most `W + H` inside the domain, `√2·max(W, H)` over a periodic one) or march steps.
pub fn ray_iterations(w: usize, h: usize, wrap: bool, settings: &TruthSettings) -> u64 {
    let side = w.max(h) as f64;
    if settings.march {
        let reach = side * if wrap { 1.0 } else { std::f64::consts::SQRT_2 };
        (reach / settings.step).ceil() as u64 + 2
    } else if wrap {
        (side * std::f64::consts::SQRT_2).ceil() as u64 + 3
    } else {
        (w + h) as u64 + 3
    }
}

/// Azimuths per dispatch for a `w × h` field with `spheres` sphere blockers: the ray (twice for
/// a bounce: horizon, then the sweep of the blocked nodes) plus the Gauss–Legendre nodes with
/// their SH loops must fit [`LOOP_BUDGET`]. Cap and sphere samples (one ray and the nodes)
/// use the same chunk. With spheres an interval splits into up to `S + 1` gaps (each its
/// nodes; a bounce node tests the `S` spheres), found by a cursor sweep of up to
/// `(S + 1)²·S` steps.
pub fn azimuth_chunk(w: usize, h: usize, wrap: bool, settings: &TruthSettings, n: usize, spheres: usize) -> u32 {
    // Per node 12·n² + 16: at order 6 the bounce pass in SH mode overran with 3·n² + 16 (the
    // SH evaluation and the RGB accumulation are loops the compiler keeps at that order; the
    // GPU-vs-CPU test at orders 6 and 8 in tests/truth.rs found it: 138% off).
    let s = spheres as u64;
    let per_azimuth = 2 * ray_iterations(w, h, wrap, settings)
        + (s + 1) * settings.nodes as u64 * (12 * (n * n) as u64 + 16)
        + s * (s + 1) * (s + 2)
        + 4;
    (LOOP_BUDGET / per_azimuth).clamp(1, 64) as u32
}

/// Renders the ground truth of `scene` on the GPU. `progress(done, total)` counts texel rows
/// over all bounces.
pub fn render_truth_gpu(
    ctx: &Context,
    scene: &Scene,
    settings: &TruthSettings,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<TruthOutput> {
    render_truth_gpu_timed(ctx, scene, settings, progress).map(|(o, _)| o)
}

/// The cap buffer (binding 6): the local lights' and spheres' azimuth factors
/// ([`cap_node_factors`], `cap_nodes` entries, only when the scene has local lights or
/// spheres), then every key light's samples `(φ, weight)`; and the index of the first
/// key-light sample.
fn cap_buffer(scene: &Scene, settings: &TruthSettings) -> (Vec<[f32; 2]>, u32) {
    let mut out: Vec<[f32; 2]> = if scene.local_lights.is_empty() && scene.spheres.is_empty() {
        Vec::new()
    } else {
        cap_node_factors(settings.cap_nodes).iter().map(|(x, w)| [*x as f32, *w as f32]).collect()
    };
    let first_key = out.len() as u32;
    out.extend(key_caps(scene, settings).iter().flat_map(|(_, s)| s.iter().map(|(p, wt)| [*p as f32, *wt as f32])));
    if out.is_empty() {
        out.push([0.0; 2]);
    }
    (out, first_key)
}

/// `v` as a high f32 and the f32 of what it leaves (`v ≈ hi + lo` to ~f64 precision).
fn split(v: glam::DVec3) -> ([f32; 3], [f32; 3]) {
    let hi = v.to_array().map(|x| x as f32);
    let lo = [0, 1, 2].map(|k| (v[k] - hi[k] as f64) as f32);
    (hi, lo)
}

/// The sphere buffer (binding 7): per sphere `(c_hi, r)` and `(c_lo, 0)` (one empty sphere's
/// worth when there are none: a buffer cannot be empty).
fn sphere_buffer(scene: &Scene) -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity(2 * scene.spheres.len().max(1));
    for b in &scene.spheres {
        let (hi, lo) = split(b.center);
        out.push([hi[0], hi[1], hi[2], b.radius as f32]);
        out.push([lo[0], lo[1], lo[2], 0.0]);
    }
    if out.is_empty() {
        out.resize(2, [0.0; 4]);
    }
    out
}

/// The push constants of every dispatch of one pass over rows `[row, row + rows)` (texel-wide
/// fields set, `indirect`/rows left to the caller): the environment's (or the bounce's)
/// uniform azimuths in chunks, then, for the exact direct light, each key light's samples,
/// then, for the direct light of both variants, the spheres' samples (`cap = 3`, all spheres
/// flattened, `max(A, cap_nodes)` per sphere), then each local light's (the first of those
/// with `accumulate = 0`: they have their own output region).
fn pass_pushes(scene: &Scene, settings: &TruthSettings, indirect: bool, chunk: u32) -> Vec<TruthPush> {
    let (w, h) = (scene.field.width(), scene.field.height());
    let base = TruthPush {
        width: w as u32,
        height: h as u32,
        wrap: scene.wrap as u32,
        azimuths: settings.azimuths,
        step: settings.step as f32,
        texel_size: scene.texel_size as f32,
        sh_visibility: settings.sh_visibility as u32,
        indirect: indirect as u32,
        march: settings.march as u32,
        accumulate: 1,
        ..Default::default()
    };
    let mut out = Vec::new();
    let mut add = |push: TruthPush, first: u32, count: u32| {
        let mut f = first;
        while f < first + count {
            let c = chunk.min(first + count - f);
            out.push(TruthPush { azimuth_first: f, azimuth_count: c, ..push });
            f += c;
        }
    };
    add(base, 0, settings.azimuths);
    if !indirect {
        let mut offset = cap_buffer(scene, settings).1;
        for (key, samples) in key_caps(scene, settings) {
            let l = key.direction.normalize();
            let (sin_a, cos_a) = key.angular_radius.sin_cos();
            let r = key.radiance;
            let push = TruthPush {
                cap: 1,
                cap_dir: [l.x as f32, l.y as f32, l.z as f32, cos_a as f32],
                cap_radiance: [r[0] as f32, r[1] as f32, r[2] as f32, sin_a as f32],
                ..base
            };
            add(push, offset, samples.len() as u32);
            offset += samples.len() as u32;
        }
    }
    if !indirect && !scene.spheres.is_empty() {
        let per = settings.azimuths.max(settings.cap_nodes);
        add(TruthPush { cap: 3, local_nodes: settings.cap_nodes, ..base }, 0, per * scene.spheres.len() as u32);
    }
    if !indirect {
        for light in &scene.local_lights {
            let (hi, lo) = split(light.position);
            let r = light.radiance;
            let push = TruthPush {
                cap: 2,
                local_nodes: settings.cap_nodes,
                cap_radiance: [r[0] as f32, r[1] as f32, r[2] as f32, 0.0],
                local_centre: [hi[0], hi[1], hi[2], light.radius as f32],
                local_lo: [lo[0], lo[1], lo[2], 0.0],
                ..base
            };
            add(push, 0, settings.azimuths.max(settings.cap_nodes));
        }
    }
    out[0].accumulate = 0;
    if let Some(first) = out.iter_mut().find(|p| p.cap == 2) {
        first.accumulate = 0;
    }
    out
}

/// [`render_truth_gpu`] plus the GPU time of all its dispatches in milliseconds (the sum of
/// the `reference.truth` timestamp scopes; `None` where the queue has no timestamps).
pub fn render_truth_gpu_timed(
    ctx: &Context,
    scene: &Scene,
    settings: &TruthSettings,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(TruthOutput, Option<f64>)> {
    settings.validate()?;
    scene.gi.validate()?;
    let n = scene.gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let light = if settings.sh_visibility { lighting_sh(scene) } else { environment_sh(scene) };
    let (gx, gw) = gauss_legendre(settings.nodes as usize);
    let gauss: Vec<[f32; 2]> = gx.iter().zip(&gw).map(|(x, wt)| [*x as f32, *wt as f32]).collect();
    let light32: Vec<[f32; 4]> = light.iter().map(|l| [l[0] as f32, l[1] as f32, l[2] as f32, 0.0]).collect();
    let caps = cap_buffer(scene, settings).0;
    let spheres = sphere_buffer(scene);
    let consts = super::shade::constants(n, crate::scene::model::DiffuseLobe::Sh, 1.0, 0);
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
    let mut bufs: Vec<Buffer> = Vec::new();
    let mut pipe: Option<ComputePipeline> = None;
    let mut timer = StageTimer::new(ctx, 1)?;
    let result = (|| -> Result<(TruthOutput, Option<f64>)> {
        for (name, bytes) in [
            ("hfgi.truth.heights", (w * h * 4) as u64),
            ("hfgi.truth.light", (n * n * 16) as u64),
            ("hfgi.truth.source", (w * h * 16) as u64),
            ("hfgi.truth.gauss", (gauss.len() * 8) as u64),
            ("hfgi.truth.consts", (consts.len() * 4) as u64),
            // Per texel n² vec4, then the local lights' E (one vec4 per texel).
            ("hfgi.truth.out", (w * h * (n * n + 1) * 16) as u64),
            ("hfgi.truth.caps", (caps.len() * 8) as u64),
            ("hfgi.truth.spheres", (spheres.len() * 16) as u64),
        ] {
            bufs.push(Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly)?);
        }
        memory::upload_f32(ctx, &bufs[0], 0, scene.field.data())?;
        memory::upload(ctx, &bufs[1], 0, bytemuck::cast_slice(&light32))?;
        memory::upload(ctx, &bufs[3], 0, bytemuck::cast_slice(&gauss))?;
        memory::upload(ctx, &bufs[4], 0, bytemuck::cast_slice(&consts))?;
        memory::upload(ctx, &bufs[6], 0, bytemuck::cast_slice(&caps))?;
        memory::upload(ctx, &bufs[7], 0, bytemuck::cast_slice(&spheres))?;
        let p = pipe.insert(ComputePipeline::new(
            ctx,
            &shaders::REFERENCE_TRUTH_COMP,
            &[DescriptorKind::StorageBuffer; 8],
            std::mem::size_of::<TruthPush>() as u32,
            &[
                (0, n as u32),
                (1, settings.nodes),
                (2, scene.wrap as u32),
                (3, settings.march as u32),
                (4, settings.sh_visibility as u32),
                (5, scene.spheres.len() as u32),
            ],
            1,
        )?);
        let binds: Vec<Bind> = bufs.iter().map(Bind::Buffer).collect();
        let set = p.allocate_set(ctx, &binds)?;
        let mut run = Passes { ctx, scene, settings, pipe: p, set, bufs: &bufs, timer: &mut timer, gpu_ms: Some(0.0) };
        let out = run.all(progress)?;
        Ok((out, run.gpu_ms))
    })();
    if let Some(mut p) = pipe {
        p.destroy(ctx);
    }
    timer.destroy(ctx);
    bufs.into_iter().for_each(|b| b.destroy(ctx));
    result
}

/// The passes of one reference (direct, then each bounce) on prepared buffers.
struct Passes<'a> {
    ctx: &'a Context,
    scene: &'a Scene,
    settings: &'a TruthSettings,
    pipe: &'a ComputePipeline,
    set: vk::DescriptorSet,
    bufs: &'a [Buffer],
    timer: &'a mut StageTimer,
    gpu_ms: Option<f64>,
}

impl Passes<'_> {
    fn all(&mut self, progress: &mut dyn FnMut(u64, u64)) -> Result<TruthOutput> {
        let (w, h) = (self.scene.field.width(), self.scene.field.height());
        let total = (self.scene.gi.bounces as u64 + 1) * h as u64;
        let mut done = 0u64;
        let direct = self.pass(false, &mut done, total, progress)?;
        let mut source = direct.clone();
        let mut indirect_bounces = Vec::new();
        for _ in 0..self.scene.gi.bounces {
            let src: Vec<[f32; 4]> = source.iter().map(|v| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0]).collect();
            memory::upload(self.ctx, &self.bufs[2], 0, bytemuck::cast_slice(&src))?;
            let b = self.pass(true, &mut done, total, progress)?;
            source = b.clone();
            indirect_bounces.push(b);
        }
        Ok(TruthOutput::assemble(w, h, direct, indirect_bounces))
    }

    /// One pass (direct or a bounce) over all rows, in bands; returns the finished exit radiance.
    fn pass(
        &mut self,
        indirect: bool,
        done: &mut u64,
        total: u64,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Vec<[f64; 3]>> {
        let (ctx, scene, settings) = (self.ctx, self.scene, self.settings);
        let (w, h) = (scene.field.width(), scene.field.height());
        let n2 = scene.gi.sh_order * scene.gi.sh_order;
        let rows_per_band = (16384 / w.max(1)).clamp(1, h) as u32;
        let chunk = azimuth_chunk(w, h, scene.wrap, settings, scene.gi.sh_order, scene.spheres.len());
        let pushes = pass_pushes(scene, settings, indirect, chunk);
        let (pipe, set) = (self.pipe, self.set);
        let mut row = 0u32;
        while row < h as u32 {
            let rows = rows_per_band.min(h as u32 - row);
            ctx.submit_and_wait(|cmd| {
                let mut rec = Recorder::new(ctx, cmd, Some(&mut *self.timer));
                rec.scope(STAGE_TRUTH, |ctx, cmd| {
                    barrier::transfer_to_compute(ctx, cmd);
                    for push in &pushes {
                        let push = TruthPush { row_offset: row, rows, ..*push };
                        let g = [
                            groups(w as u32, crate::constants::WORKGROUP),
                            groups(rows, crate::constants::WORKGROUP),
                            1,
                        ];
                        pipe.dispatch(ctx, cmd, set, bytemuck::bytes_of(&push), g);
                        barrier::compute_to_compute(ctx, cmd);
                    }
                });
                Ok(())
            })?;
            self.gpu_ms = match (self.gpu_ms, self.timer.timings(ctx)) {
                (Some(acc), Ok(t)) => Some(acc + t.iter().map(|(_, ms)| ms).sum::<f64>()),
                _ => None,
            };
            row += rows;
            *done += rows as u64;
            progress(*done, total);
        }
        let locals = !indirect && !scene.local_lights.is_empty();
        let raw = memory::download_f32(ctx, &self.bufs[5], 0, (w * h * (n2 + locals as usize) * 4) as u64)?;
        let (nrm, rho) = (normals(scene), albedo(scene));
        let finish = Finisher::new(scene, settings.sh_visibility);
        Ok((0..w * h)
            .map(|t| {
                let texel: Vec<[f64; 3]> = (0..n2)
                    .map(|k| {
                        let o = (t * n2 + k) * 4;
                        [raw[o] as f64, raw[o + 1] as f64, raw[o + 2] as f64]
                    })
                    .collect();
                let mut out = finish.texel(indirect, &texel, nrm[t], rho[t]);
                if locals {
                    // The local lights' E: ρ/π · E onto the direct exit radiance.
                    let o = (w * h * n2 + t) * 4;
                    for c in 0..3 {
                        out[c] += rho[t][c] / std::f64::consts::PI * raw[o + c] as f64;
                    }
                }
                out
            })
            .collect())
    }
}
