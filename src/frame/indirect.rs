//! Stages `indirect.scan` and `indirect.shade` (NS09 §3, §5.2–5.3, §6–7; docs/indirect.md),
//! recorded once per bounce after the radiance pyramid of the previous bounce:
//!
//! - `indirect.scan`: per receiver of the working grid, the IR vector `U` (eq. 12, 19–21),
//!   RGB coefficients of its first [`u_bands`](crate::rules::scene::u_bands) bands in [`IndirectPass::u_buffer`].
//! - `indirect.shade`: the shading shader in indirect mode (`glsl/shade/direct.comp.glsl`,
//!   `HFGI_INDIRECT = 1`) shades `U` with the diffuse and Phong lobes at full resolution, adds
//!   the bounce to the shading planes `indirect` and indirect glossy, recomposes `total` and
//!   `glossy`, and writes the bounce's exit radiance (the next bounce's input) straight into
//!   level 0 of the radiance pyramid (after this bounce's scan has read the pyramid).
//!
//! With [`uses_max_bound`](super::pyramid_max::uses_max_bound) the pass also owns the max
//! pyramid (stage `pyramid.max`, [`MaxPyramid`]; the renderer creates it before the visibility
//! pass, which reads it too, and records it when the heights change), and every bounce's scan
//! stops each ray where nothing farther can rise above its horizon (docs/accuracy.md §4,
//! docs/performance.md §18, §34). Barriers: compute→compute after each stage.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::pyramid_max::MaxPyramid;
use super::radiance::RadiancePyramid;
use super::shade::ShadePass;
use super::shared::{IndirectPush, ShadePush, FLAG_ACCUMULATE, FLAG_MAX_BOUND};
use crate::constants::{NEXT_LEVEL0, NEXT_NONE, NEXT_TOTAL};
use crate::error::Result;
use crate::rules::scene::u_coefficients;
use crate::scene::model::{Scene, Storage};
use crate::vk::pipeline::groups;
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, Recorder};

mod scan;
mod setup;
use crate::rules::scene::replays;
pub(crate) use scan::check_subgroup_vote;
use scan::{scan_chunks, scan_kinds, scan_pipelines, scan_push, ScanKind};
pub(crate) use setup::{buffer_sizes, radiance_levels, radiance_stack_levels, ScanData};
use setup::{radiance_pyramid, scan_binds, shade_set, BUFFER_VIEWS, MEMBERS, U};

pub const STAGE_SCAN: &str = super::stages::stage_name("indirect.scan");
pub const STAGE_SHADE: &str = super::stages::stage_name("indirect.shade");

pub struct IndirectPass {
    pub radiance: RadiancePyramid,
    /// The max pyramid whose top the scans' early stop reads
    /// ([`uses_max_bound`](super::pyramid_max::uses_max_bound)).
    pub max: Option<MaxPyramid>,
    /// The scan's pipelines with their sets, by what each compiles in ([`ScanKind`]: the radial
    /// probes): one per kind the scene's bounces need.
    scans: Vec<(ScanKind, ComputePipeline, vk::DescriptorSet)>,
    shade: ComputePipeline,
    shade_set: vk::DescriptorSet,
    buffers: Vec<Buffer>, // samples, fold, radiance levels, U, recorded casting sets
    push: IndirectPush,
    /// Radial probes of bounce 1 and of the later bounces (`GiSettings::probes`).
    probes: [u32; 2],
    /// Whether bounce 1 and the later bounces merge casts (`GiSettings::merge`).
    merges: [bool; 2],
    /// Whether the later bounces cast the casting sets the first bounce's walk recorded
    /// ([`replays`]): then the pass has two pipelines, the first bounce's (walking and
    /// recording) and the later ones' (casting without a walk).
    replay: bool,
    /// Azimuth chunks `(first, count)`, one dispatch each: of the first bounce's scan and of
    /// the later ones' (their probes and azimuth sets may differ, and a probe is a loop
    /// iteration like a sample).
    chunks: [Vec<(u32, u32)>; 2],
    shade_push: ShadePush,
    /// Coefficients per channel ([`u_coefficients`]) and `gi.storage` of `U` (for
    /// [`IndirectPass::read_u`]).
    u_coefficients: usize,
    storage: Storage,
    /// `gi.bounces`: [`IndirectPass::record_shade`]'s last bounce.
    bounces: u32,
}

impl IndirectPass {
    /// `blockers`: the sphere blockers' visibility buffer, when the scene has spheres (each
    /// bounce's incident radiance is multiplied by it, docs/blockers.md §4). `max`: the max
    /// pyramid where [`super::pyramid_max::uses_max_bound`] (the renderer creates it before the
    /// visibility pass, which reads it too); the pass owns it and records it (`pyramid.max`),
    /// and destroys it on failure.
    pub fn new(
        ctx: &Context,
        pyramid: &HeightPyramid,
        shade: &ShadePass,
        blockers: Option<&Buffer>,
        scene: &Scene,
        max: Option<MaxPyramid>,
    ) -> Result<Self> {
        check_subgroup_vote(ctx.info())?;
        let gi = &scene.gi;
        let (ww, wh) = pyramid.work();
        let data = ScanData::new(scene, pyramid.layout().count());
        let levels = data.radiance_levels(scene)?;
        let ScanData { samples, fold, ladder, sets } = data;
        let mut bufs: Vec<Buffer> = Vec::new();
        let mut pipes: Vec<ComputePipeline> = Vec::new();
        let mut radiance = None;
        let replay = replays(scene, (ww as usize, wh as usize), ladder.len());
        let kinds = scan_kinds(scene, replay);
        let made = (|| -> Result<(Vec<vk::DescriptorSet>, vk::DescriptorSet, IndirectPush)> {
            let sizes = buffer_sizes(scene, (ww, wh), samples.len(), fold.len(), ladder.len());
            Self::create_buffers(ctx, &mut bufs, sizes)?;
            let rad = radiance.insert(radiance_pyramid(ctx, scene, pyramid, &levels, shade)?);
            let push = Self::first_push(scene, pyramid, rad, sets[0].1);
            Self::upload(ctx, &bufs, (&samples, &fold, &levels), replay)?;
            let binds = scan_binds(pyramid, rad, &bufs, shade.bindings()[3], max.as_ref());
            let scan_sets = scan_pipelines(ctx, scene, pyramid.layout().count(), &push, &kinds, &binds, &mut pipes)?;
            let shade_set = shade_set(ctx, scene, pyramid, shade, &bufs[U], rad, blockers, &mut pipes)?;
            Ok((scan_sets, shade_set, push))
        })();
        let (scan_sets, shade_set, push) = match made {
            Ok(s) => s,
            Err(e) => {
                bufs.into_iter().for_each(|b| b.destroy(ctx));
                pipes.into_iter().for_each(|mut p| p.destroy(ctx));
                radiance.into_iter().for_each(|r| r.destroy(ctx));
                max.into_iter().for_each(|m| m.destroy(ctx));
                return Err(e);
            }
        };
        let shade_pipe = pipes.pop().expect("shade");
        let scans = kinds.into_iter().zip(pipes).zip(scan_sets).map(|((b, p), set)| (b, p, set)).collect();
        let mut pass = Self {
            radiance: radiance.expect("radiance"),
            max,
            scans,
            shade: shade_pipe,
            shade_set,
            buffers: bufs,
            chunks: scan_chunks(gi, ladder.len(), sets),
            push,
            probes: [gi.probes(1), gi.probes(2)],
            merges: [gi.merge(1) > 0.0, gi.merge(2) > 0.0],
            replay,
            shade_push: shade.push(),
            u_coefficients: u_coefficients(scene),
            storage: gi.storage,
            bounces: gi.bounces,
        };
        pass.set_pre_exposure(super::storage::pre_exposure(scene));
        Ok(pass)
    }

    /// Creates the scan's own buffers of `sizes` ([`buffer_sizes`]' order) with their texel
    /// views ([`BUFFER_VIEWS`]) into `bufs`, which the caller destroys on an error.
    fn create_buffers(ctx: &Context, bufs: &mut Vec<Buffer>, sizes: [(&'static str, u64); 5]) -> Result<()> {
        let usage = crate::vk::memory::PASS_BUFFER_USAGE;
        for ((name, size), view) in sizes.into_iter().zip(BUFFER_VIEWS) {
            bufs.push(Buffer::new(ctx, name, size, usage, MemoryLocation::GpuOnly)?.with_texel_view(ctx, view)?);
        }
        Ok(())
    }

    /// The scan's push constants for the first bounce's `sample_count` samples, with the raw
    /// level-0 planes of the height stack and of `rad`'s stack (which this sets).
    fn first_push(
        scene: &Scene,
        pyramid: &HeightPyramid,
        rad: &mut RadiancePyramid,
        sample_count: u32,
    ) -> IndirectPush {
        // Radiance level 0 read as the bilinear image through the stack too (with f16 storage
        // rounded to halves like every other plane of the stack; docs/performance.md §17).
        let raw0 = scene.gi.level0 == crate::scene::model::Level0::Bilinear;
        let rplane = rad.pyramid.set_raw_plane0(raw0);
        let raw_planes = super::shared::raw_plane_flags(pyramid.raw_plane0(), rplane);
        scan_push(scene, pyramid.work(), sample_count, rad, raw_planes)
    }

    /// Uploads the samples, the fold and the radiance levels' table into `bufs` 0–2 and, with
    /// the `replay`, clears the recorded casting sets.
    fn upload(
        ctx: &Context,
        bufs: &[Buffer],
        (samples, fold, levels): (&[[f32; 4]], &[f32], &[u32]),
        replay: bool,
    ) -> Result<()> {
        memory::upload(ctx, &bufs[0], 0, bytemuck::cast_slice(samples))?;
        memory::upload_f32(ctx, &bufs[1], 0, fold)?;
        memory::upload(ctx, &bufs[2], 0, bytemuck::cast_slice(levels))?;
        // Defined sets before the first bounce records any (a later bounce recorded alone
        // casts no member rather than reading garbage); without the replay nothing reads them.
        if replay {
            memory::zero(ctx, &bufs[MEMBERS])?;
        }
        Ok(())
    }

    /// Sets the pre-exposure of f16 storage ([`super::storage::pre_exposure`] of the live
    /// scene): what the radiance stack's synthesis and the scan store is multiplied by it, what
    /// the scan and the shade read is divided by it. The renderer calls it whenever the lights
    /// or the material change.
    pub(crate) fn set_pre_exposure(&mut self, scale: f32) {
        self.push.radiance_scale = scale;
        self.shade_push.u_scale = scale;
        self.radiance.pyramid.set_stack_scale(scale);
    }

    /// Records bounces `1..=bounces`: radiance pyramid, scan, shade for each. After new
    /// heights, [`IndirectPass::record_max`] comes first, before the visibility (which reads the
    /// max pyramid too; `Renderer::record` records both in that order).
    pub fn record(&self, rec: &mut Recorder, bounces: u32) {
        for b in 1..=bounces {
            self.radiance.record(rec, b);
            self.record_scan(rec, b);
            self.record_shade_of(rec, b, b == bounces);
        }
    }

    /// The live inputs' push fields (docs/integration.md §2): `f` edits the indirect shading's
    /// push constants (camera, material) as the direct pass's; `specular` is the scan's
    /// (the vector pyramid's glossy exit radiance).
    pub(crate) fn update_pushes(&mut self, f: impl Fn(&mut ShadePush), specular: [f32; 3]) {
        f(&mut self.shade_push);
        self.push.specular = [specular[0], specular[1], specular[2], 0.0];
    }

    /// Records stage `pyramid.max` if the scans use the bound (nothing otherwise); after the
    /// heights' level 0 is written and before `visibility.*` and `indirect.scan`, which read it.
    pub fn record_max(&self, rec: &mut Recorder) {
        if let Some(m) = &self.max {
            m.record(rec);
        }
    }

    /// Records the scan of bounce `bounce` (1-based) of the radiance pyramid (stage
    /// `indirect.scan`).
    /// With the replay a later bounce casts the casting sets that the last recorded scan of
    /// bounce 1 stored (docs/indirect.md §2): record bounce 1 first whenever the heights change
    /// ([`IndirectPass::record`] does).
    pub fn record_scan(&self, rec: &mut Recorder, bounce: u32) {
        let later = bounce > 1;
        let probes = self.probes[later as usize];
        // The pipeline of this kind, else one that serves it exactly (scan_kinds creates one);
        // with the replay the first (walking and recording) or the second (casting).
        let (_, scan, set) = if self.replay {
            &self.scans[later as usize]
        } else {
            let kind = ScanKind::of(probes, self.merges[later as usize]);
            self.scans
                .iter()
                .find(|s| s.0 == kind)
                .or_else(|| self.scans.iter().find(|s| s.0.serves(kind)))
                .unwrap_or(&self.scans[0])
        };
        rec.scope(STAGE_SCAN, |ctx, cmd| {
            let g = [
                groups(self.push.work_width, crate::constants::WORKGROUP),
                groups(self.push.work_height, crate::constants::WORKGROUP),
                1,
            ];
            // Every bounce stops early when the pass has the max pyramid (docs/performance.md §18).
            let bound = if self.max.is_some() { FLAG_MAX_BOUND } else { 0 };
            // Azimuth chunks against lavapipe's loop limit; the later ones accumulate into U.
            for (i, (first, count)) in self.chunks[later as usize].iter().enumerate() {
                let flags = self.push.flags | bound | if i > 0 { FLAG_ACCUMULATE } else { 0 };
                let push = IndirectPush { sample_offset: *first, sample_count: *count, flags, probes, ..self.push };
                scan.dispatch(ctx, cmd, *set, bytemuck::bytes_of(&push), g);
                barrier::compute_to_compute(ctx, cmd);
            }
        });
    }

    /// Records the shading of bounce `bounce` (1-based; stage `indirect.shade`): bounce 1
    /// writes the indirect planes, later bounces add to them. On a working-grid radiance
    /// pyramid a bounce before the scene's last (`gi.bounces`) leaves its exit radiance in the
    /// total plane for the next bounce's gather, and the last one writes the total.
    pub fn record_shade(&self, rec: &mut Recorder, bounce: u32) {
        self.record_shade_of(rec, bounce, bounce >= self.bounces);
    }

    fn record_shade_of(&self, rec: &mut Recorder, bounce: u32, last: bool) {
        let next_mode = match (self.radiance.on_working_grid(), last) {
            (false, _) => NEXT_LEVEL0,
            (true, false) => NEXT_TOTAL,
            (true, true) => NEXT_NONE,
        };
        rec.scope(STAGE_SHADE, |ctx, cmd| {
            let push = ShadePush { accumulate: (bounce > 1) as u32, next_mode, ..self.shade_push };
            let g =
                [groups(push.width, crate::constants::WORKGROUP), groups(push.height, crate::constants::WORKGROUP), 1];
            self.shade.dispatch(ctx, cmd, self.shade_set, bytemuck::bytes_of(&push), g);
            barrier::compute_to_compute(ctx, cmd);
        });
    }

    /// The IR vectors of the last bounce: receivers × `b²` × rgb in `gi.storage`
    /// (glsl/inc/hfgi_store.glsl), with `b` = [`u_bands`](crate::rules::scene::u_bands) (bands 0 … b − 1).
    pub fn u_buffer(&self) -> &Buffer {
        &self.buffers[U]
    }

    /// Diagnostics: the IR vectors of the last bounce (receivers × `b²` × rgb with
    /// `b` = [`u_bands`](crate::rules::scene::u_bands), as f32 whatever `gi.storage`), read back (waits). Call after a
    /// recorded frame completed.
    pub fn read_u(&self, ctx: &Context) -> Result<Vec<f32>> {
        let values = 3 * self.u_coefficients;
        let receivers = (self.push.work_width * self.push.work_height) as usize;
        let u = super::storage::download_vectors(ctx, &self.buffers[U], self.storage, 0, receivers, values)?;
        let unexpose = 1.0 / self.push.radiance_scale;
        Ok(u.into_iter().map(|x| x * unexpose).collect())
    }

    /// Diagnostics: the radiance the last bounce leaves for the next one in level 0 of the
    /// radiance pyramid, as rgb per texel (`W × H`: its diffuse + glossy exit radiance, or the
    /// diffuse part alone with the glossy vector pyramid), read back (waits). On a working-grid
    /// pyramid ([`RadiancePyramid::on_working_grid`]) level 0 is that grid and holds the last
    /// bounce's own input (the shades pass their exit radiance on through the total plane).
    pub fn read_next(&self, ctx: &Context) -> Result<Vec<f32>> {
        let p = &self.radiance.pyramid;
        let (l0, stride) = (p.layout().levels[0], p.layout().total);
        let texels = l0.width as u64 * l0.height as u64;
        let ch = (0..3u64)
            .map(|c| memory::download_f32(ctx, p.levels_buffer(), c * stride, texels))
            .collect::<Result<Vec<_>>>()?;
        Ok((0..texels as usize).flat_map(|t| [ch[0][t], ch[1][t], ch[2][t]]).collect())
    }

    pub fn memory_bytes(&self) -> u64 {
        self.buffers.iter().map(|b| b.size).sum::<u64>()
            + self.radiance.memory_bytes()
            + self.max.as_ref().map_or(0, |m| m.memory_bytes())
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.scans.drain(..).for_each(|(_, mut p, _)| p.destroy(ctx));
        self.shade.destroy(ctx);
        self.buffers.drain(..).for_each(|b| b.destroy(ctx));
        self.radiance.destroy(ctx);
        if let Some(m) = self.max.take() {
            m.destroy(ctx);
        }
    }
}
