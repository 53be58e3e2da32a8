//! Stage `pyramid.max` (docs/accuracy.md §4): the max reduction of the level-0 heights, whose
//! 1 × 1 top (the field's largest height) lets the indirect scan stop each ray where nothing
//! farther can rise above its horizon. Each level takes the largest of 8 × 8 cells of the one
//! before (1/63 of the field in all). (Until docs/performance.md §18 the scan also read a max
//! pyramid's finer levels to skip the probes of gaps that could hold no member; on lavapipe that
//! read cost more than it saved, and since §19 only what the top needs is built.) Layout and CPU
//! twin: [`crate::reference::max`]; shader `glsl/pyramid/max.comp.glsl`.
//!
//! Recorded after `pyramid.decimate` (it reads level 0 of the height pyramid's levels buffer)
//! whenever the heights changed, only for scenes whose indirect scan uses it
//! ([`uses_max_bound`]). One dispatch per level with a compute→compute barrier after each; the
//! pass owns one storage buffer (`hfgi.pyramid.max`, [`MaxLayout::floats`] `f32`), read by
//! `indirect.scan` at binding 11.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::shared::PyramidPush;
use crate::error::Result;
use crate::reference::max::MaxLayout;
use crate::scene::model::{Level0, Scene};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, Recorder};

pub const STAGE_MAX: &str = super::stages::stage_name("pyramid.max");

/// Whether the indirect scan of `scene` reads the max reduction: it has radial probes (the stage
/// was built for the probes' bound, docs/accuracy.md §4; since docs/performance.md §18 it serves
/// the early stop of every bounce of such a scene, which would serve a scene without probes as
/// well: not extended to them yet), level 0 is the bilinear surface (the bound is over it) and
/// the field is not periodic (the layout does not wrap).
pub fn uses_max_bound(scene: &Scene) -> bool {
    why_no_max_bound(scene).is_none()
}

/// Why the indirect scan of `scene` does not read the max reduction, if it does not.
pub fn why_no_max_bound(scene: &Scene) -> Option<&'static str> {
    let gi = &scene.gi;
    if gi.radial_probes == 0 && gi.radial_probes_later == 0 {
        Some("no radial probes (gi.radial_probes and gi.radial_probes_later are 0)")
    } else if gi.level0 != Level0::Bilinear {
        Some("gi.level0 = \"bspline\": the bound holds for the bilinear surface")
    } else if scene.wrap {
        Some("a periodic field: the early stop was built and tested for clamped fields only")
    } else {
        None
    }
}

/// The name of the pass's buffer.
pub(crate) const BUFFER_NAME: &str = "hfgi.pyramid.max";

/// Bytes of the pass's buffer for `layout` ([`MaxLayout::floats`] `f32`).
pub(crate) fn buffer_bytes(layout: &MaxLayout) -> u64 {
    layout.floats() as u64 * 4
}

pub struct MaxPyramid {
    layout: MaxLayout,
    pipeline: ComputePipeline,
    set: vk::DescriptorSet,
    buffer: Buffer,
}

impl MaxPyramid {
    /// The pass for `pyramid`'s level 0.
    pub fn new(ctx: &Context, pyramid: &HeightPyramid) -> Result<Self> {
        let l0 = pyramid.layout().levels[0];
        let layout = MaxLayout::new(l0.width as usize, l0.height as usize);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC;
        // The indirect scan reads it through a texel view (docs/performance.md §17).
        let buffer = Buffer::new(ctx, BUFFER_NAME, buffer_bytes(&layout), usage, MemoryLocation::GpuOnly)?
            .with_texel_view(ctx, vk::Format::R32_UINT)?;
        let binds =
            [Bind::Buffer(pyramid.levels_buffer()), Bind::Buffer(pyramid.table_buffer()), Bind::Buffer(&buffer)];
        let push_size = std::mem::size_of::<PyramidPush>() as u32;
        let made = ComputePipeline::with_storage_set(ctx, &shaders::PYRAMID_MAX_COMP, push_size, &binds);
        match made {
            Ok((pipeline, set)) => Ok(Self { layout, pipeline, set, buffer }),
            Err(e) => {
                buffer.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Records stage `pyramid.max`: every level, finest first.
    pub fn record(&self, rec: &mut Recorder) {
        rec.scope(STAGE_MAX, |ctx, cmd| {
            let (w, h) = self.layout.n0;
            for (level, &(lw, lh, _)) in self.layout.levels.iter().enumerate() {
                let push = PyramidPush {
                    level: level as u32,
                    out_width: w as u32,
                    out_height: h as u32,
                    scale: 1.0,
                    ..Default::default()
                };
                let g =
                    [groups(lw as u32, crate::constants::WORKGROUP), groups(lh as u32, crate::constants::WORKGROUP), 1];
                self.pipeline.dispatch(ctx, cmd, self.set, bytemuck::bytes_of(&push), g);
                barrier::compute_to_compute(ctx, cmd);
            }
        });
    }

    pub fn buffer(&self) -> &Buffer {
        &self.buffer
    }

    pub fn layout(&self) -> &MaxLayout {
        &self.layout
    }

    /// Diagnostics: the whole buffer (layout [`MaxPyramid::layout`]), read back (waits).
    pub fn read(&self, ctx: &Context) -> Result<Vec<f32>> {
        memory::download_f32(ctx, &self.buffer, 0, self.layout.floats() as u64)
    }

    pub fn memory_bytes(&self) -> u64 {
        self.buffer.size
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.buffer.destroy(ctx);
    }
}
