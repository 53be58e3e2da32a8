//! The line sweep of `gi.visibility = "sweep"` (docs/direct.md §7; Timonen & Westerholm 2010):
//! the horizon angle of every receiver along each azimuth sample, from the level-0 surface, for
//! the visibility pass to project instead of scanning. Recorded inside the visibility stages
//! (`visibility.environment`, `visibility.key_lights`), chunk by chunk of azimuths.
//!
//! Buffers: `hfgi.visibility.horizons` (f32, `[azimuth of the chunk][receiver][2]`: the
//! weighted horizons of the line below and the line above) and `hfgi.visibility.hull` (the
//! lines' convex-hull stacks, `(u, h)` f32 pairs, scratch). Each dispatch is followed by a
//! compute→compute barrier (the next dispatch reuses the hull stacks; the projection reads the
//! horizons). The CPU twin is [`crate::reference::sweep`].

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::shared::{SweepPush, FLAG_RAW_LEVEL0};
use crate::error::Result;
use crate::scene::model::{PyramidMode, Scene};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, Buffer, ComputePipeline, Context};

/// Bytes each of the sweep's two buffers may take: the azimuths per chunk and the lines per
/// dispatch are chosen to stay within it.
pub const SWEEP_BUDGET: u64 = 4 << 20;

/// How the sweep of a `n0` field with a `work` receiver grid is split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SweepPlan {
    /// Azimuths per chunk (the horizons buffer holds one chunk).
    pub chunk: u32,
    /// Lines per azimuth (an upper bound over all azimuths: `W + H + 4`).
    pub lines: u32,
    /// Lines per azimuth in one dispatch.
    pub line_batch: u32,
    /// Hull entries per line: every point a line pushes (`2·max(W, H) + 4`).
    pub hull_capacity: u32,
    pub receivers: u32,
}

impl SweepPlan {
    /// The split for a set of at most `max_set` azimuths.
    pub fn new(n0: (usize, usize), work: (usize, usize), max_set: usize) -> Self {
        let lines = (n0.0 + n0.1 + 4) as u64;
        let hull_capacity = 2 * n0.0.max(n0.1) as u64 + 4;
        let receivers = (work.0 * work.1) as u64;
        let per_line = hull_capacity * 8;
        let threads = (SWEEP_BUDGET / per_line).max(1);
        let chunk = (SWEEP_BUDGET / (receivers * 8)).min(threads / lines).clamp(1, max_set.max(1) as u64);
        let line_batch = (threads / chunk).clamp(1, lines);
        Self {
            chunk: chunk as u32,
            lines: lines as u32,
            line_batch: line_batch as u32,
            hull_capacity: hull_capacity as u32,
            receivers: receivers as u32,
        }
    }

    /// The pass's buffers `(name, bytes)` in creation order (one source for the pass and
    /// [`crate::frame::memory`]).
    pub fn buffer_sizes(&self) -> [(&'static str, u64); 2] {
        [
            ("hfgi.visibility.horizons", self.chunk as u64 * self.receivers as u64 * 8),
            ("hfgi.visibility.hull", self.chunk as u64 * self.line_batch as u64 * self.hull_capacity as u64 * 8),
        ]
    }
}

/// The sweep pipeline and its buffers.
pub struct SweepPass {
    pipeline: ComputePipeline,
    descriptors: vk::DescriptorSet,
    horizons: Buffer,
    hull: Buffer,
    plan: SweepPlan,
    push: SweepPush,
}

impl SweepPass {
    /// Builds the sweep over `pyramid`'s level 0 for the azimuth samples in `samples` (the
    /// visibility pass's buffer, `[cos φ, sin φ, lo, hi]`), sets of at most `max_set` azimuths.
    pub fn new(
        ctx: &Context,
        pyramid: &HeightPyramid,
        samples: &Buffer,
        scene: &Scene,
        max_set: usize,
    ) -> Result<Self> {
        let (ww, wh) = pyramid.work();
        let l0 = pyramid.layout().levels[0];
        let plan = SweepPlan::new((l0.width as usize, l0.height as usize), (ww as usize, wh as usize), max_set);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let [(hn, hs), (un, us)] = plan.buffer_sizes();
        // The visibility shader reads the horizons through a texel view (docs/performance.md §17).
        let horizons =
            Buffer::new(ctx, hn, hs, usage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER, MemoryLocation::GpuOnly)?
                .with_texel_view(ctx, vk::Format::R32_UINT)?;
        let hull = match Buffer::new(ctx, un, us, usage, MemoryLocation::GpuOnly) {
            Ok(b) => b,
            Err(e) => {
                horizons.destroy(ctx);
                return Err(e);
            }
        };
        let stack = pyramid.stack_buffer().unwrap_or(pyramid.levels_buffer());
        let stack_mode = (pyramid.mode() == PyramidMode::Stack) as u32;
        let raw0 = super::shared::scan_flags(&scene.gi) & FLAG_RAW_LEVEL0;
        let made = ComputePipeline::with_storage_set_spec(
            ctx,
            &shaders::VISIBILITY_SWEEP_COMP,
            std::mem::size_of::<SweepPush>() as u32,
            &super::shared::static_modes(0, stack_mode, 0, raw0),
            &[
                Bind::Buffer(pyramid.levels_buffer()),
                Bind::Buffer(pyramid.table_buffer()),
                Bind::Buffer(stack),
                Bind::Buffer(samples),
                Bind::Buffer(&horizons),
                Bind::Buffer(&hull),
                Bind::Buffer(pyramid.height_planes()),
            ],
        );
        let (pipeline, descriptors) = match made {
            Ok(p) => p,
            Err(e) => {
                horizons.destroy(ctx);
                hull.destroy(ctx);
                return Err(e);
            }
        };
        let push = SweepPush {
            work_width: ww,
            work_height: wh,
            stack_mode,
            flags: raw0,
            texel_size: scene.texel_size as f32,
            hull_capacity: plan.hull_capacity,
            line_count: plan.line_batch,
            reach: scene.gi.sweep_near as f32,
            ..Default::default()
        };
        Ok(Self { pipeline, descriptors, horizons, hull, plan, push })
    }

    /// The split of the sweep.
    pub fn plan(&self) -> SweepPlan {
        self.plan
    }

    /// Records the sweep of azimuth samples `[first, first + count)` (`count ≤ plan().chunk`):
    /// one dispatch per batch of lines, each followed by a compute→compute barrier.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, first: u32, count: u32) {
        debug_assert!(count <= self.plan.chunk);
        let mut line = 0;
        while line < self.plan.lines {
            let push = SweepPush { sample_offset: first, sample_count: count, line_first: line, ..self.push };
            let g = [groups(self.plan.line_batch, crate::constants::WORKGROUP_1D), count, 1];
            self.pipeline.dispatch(ctx, cmd, self.descriptors, bytemuck::bytes_of(&push), g);
            barrier::compute_to_compute(ctx, cmd);
            line += self.plan.line_batch;
        }
    }

    /// The horizons of the last recorded chunk.
    pub fn horizons(&self) -> &Buffer {
        &self.horizons
    }

    /// Bytes of GPU memory held.
    pub fn memory_bytes(&self) -> u64 {
        self.horizons.size + self.hull.size
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.horizons.destroy(ctx);
        self.hull.destroy(ctx);
    }
}
