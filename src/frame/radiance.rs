//! Stages `radiance.gather`, `radiance.decimate`, `radiance.synthesize` (NS09 §5.3;
//! docs/indirect.md §1): the multi-resolution *shade* pyramid of the previous bounce's exit
//! radiance, one scalar pyramid per RGB channel, built exactly like the height pyramid (same
//! filters and storage mode, level step `k_u`).
//!
//! Input: bounce 1 reads the direct exit radiance (shading planes `direct` + direct glossy:
//! the paper's scalar approximation for mixtures); bounce `b > 1` reads the bounce buffer the
//! previous indirect shade wrote. Output: the levels (and stack) buffers of
//! [`RadiancePyramid::pyramid`], table entries with `source = 1`. Barriers: compute→compute
//! after each stage.

use ash::vk;

use super::pyramid::{HeightPyramid, PyramidKind};
use super::shared::GatherPush;
use crate::error::Result;
use crate::scene::model::PyramidMode;
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

pub const STAGE_GATHER: &str = "radiance.gather";
pub const STAGE_DECIMATE: &str = "radiance.decimate";
pub const STAGE_SYNTHESIZE: &str = "radiance.synthesize";

/// The radiance pyramid kind: 3 channels, `source = 1`.
pub const RADIANCE: PyramidKind = PyramidKind {
    channels: 3,
    source: 1,
    stage_decimate: STAGE_DECIMATE,
    stage_synthesize: STAGE_SYNTHESIZE,
    label: "radiance",
};

pub struct RadiancePyramid {
    pub pyramid: HeightPyramid,
    gather: ComputePipeline,
    set: vk::DescriptorSet,
    push: GatherPush,
}

impl RadiancePyramid {
    /// A pyramid for a `width × height` radiance image, stack at `work`, fed from `shade`
    /// (the shading planes) or `bounce` (the last bounce's exit radiance, `vec4` per texel).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Context,
        size: (usize, usize),
        work: (usize, usize),
        k_u: u32,
        mode: PyramidMode,
        wrap: bool,
        shade: &Buffer,
        bounce: &Buffer,
    ) -> Result<Self> {
        let pyramid = HeightPyramid::with_kind(ctx, size.0, size.1, work, k_u, mode, wrap, RADIANCE)?;
        let made = (|| {
            let mut p = ComputePipeline::new(
                ctx,
                &shaders::RADIANCE_GATHER_COMP,
                &[DescriptorKind::StorageBuffer; 3],
                std::mem::size_of::<GatherPush>() as u32,
                &[],
                1,
            )?;
            match p
                .allocate_set(ctx, &[Bind::Buffer(shade), Bind::Buffer(bounce), Bind::Buffer(pyramid.levels_buffer())])
            {
                Ok(set) => Ok((p, set)),
                Err(e) => {
                    p.destroy(ctx);
                    Err(e)
                }
            }
        })();
        match made {
            Ok((gather, set)) => {
                let push = GatherPush {
                    width: size.0 as u32,
                    height: size.1 as u32,
                    from_bounce: 0,
                    channel_stride: pyramid.layout().total as u32,
                };
                Ok(Self { pyramid, gather, set, push })
            }
            Err(e) => {
                pyramid.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Records gather + decimate (+ synthesize) for bounce `bounce` (1-based).
    pub fn record(&self, rec: &mut Recorder, bounce: u32) {
        rec.scope(STAGE_GATHER, |ctx, cmd| {
            let push = GatherPush { from_bounce: (bounce > 1) as u32, ..self.push };
            let g = [groups(push.width, 8), groups(push.height, 8), 1];
            self.gather.dispatch(ctx, cmd, self.set, bytemuck::bytes_of(&push), g);
            barrier::compute_to_compute(ctx, cmd);
        });
        self.pyramid.record(rec);
    }

    pub fn memory_bytes(&self) -> u64 {
        self.pyramid.memory_bytes()
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.gather.destroy(ctx);
        self.pyramid.destroy(ctx);
    }
}
