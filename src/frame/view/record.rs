//! Recording the stage `view.raster` ([`ViewPass::record`]; barriers and layouts: the [`super`]
//! module docs) and reading the view image back.

use ash::vk;

use super::{ViewPass, BACKGROUND, SPHERE_VERTICES, STAGE_RASTER};
use crate::error::{Error, Result};
use crate::vk::barrier::{self, Transition};
use crate::vk::graphics::{self, RenderTargets, GRAPHICS_STAGES};
use crate::vk::{memory, Context, Recorder};

impl ViewPass {
    /// Records the stage `view.raster` (see the module docs for the barriers and layouts).
    pub fn record(&self, rec: &mut Recorder) {
        rec.scope(STAGE_RASTER, |ctx, cmd| {
            barrier::compute_to_graphics(ctx, cmd);
            barrier::image_transitions(ctx, cmd, &self.attachment_transitions());
            let targets = RenderTargets {
                color: self.msaa.as_ref().unwrap_or(&self.output),
                resolve: self.msaa.as_ref().map(|_| &self.output),
                depth: Some(&self.depth),
                clear_color: BACKGROUND,
                clear_depth: 0.0,
            };
            graphics::begin_rendering(ctx, cmd, &targets);
            self.pipeline.draw_indexed(
                ctx,
                cmd,
                self.set,
                bytemuck::bytes_of(&self.push),
                &self.index,
                self.index_count,
                self.instances,
            );
            self.draw_spheres(ctx, cmd);
            graphics::end_rendering(ctx, cmd);
            barrier::image_transitions(
                ctx,
                cmd,
                &[Transition {
                    image: &self.output,
                    old: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    new: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    src: (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE),
                    dst: (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
                }],
            );
        });
        self.recorded.set(true);
    }

    /// The transitions before rendering (module docs, step 2): the output image, the depth
    /// image and, with MSAA, the MSAA colour image, each from UNDEFINED to its attachment layout.
    fn attachment_transitions(&self) -> Vec<Transition<'_>> {
        let attach = (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
        let attach_rw = (
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_READ | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        );
        let tests = vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
        let mut list = vec![
            Transition {
                image: &self.output,
                old: vk::ImageLayout::UNDEFINED,
                new: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                src: (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::NONE),
                dst: attach_rw,
            },
            Transition {
                image: &self.depth,
                old: vk::ImageLayout::UNDEFINED,
                new: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                src: (tests, vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE),
                dst: (
                    tests,
                    vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
                ),
            },
        ];
        if let Some(m) = &self.msaa {
            list.push(Transition {
                image: m,
                old: vk::ImageLayout::UNDEFINED,
                new: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                src: attach,
                dst: attach_rw,
            });
        }
        list
    }

    /// The live spheres' instanced draw (inside the rendering; nothing without spheres).
    fn draw_spheres(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        if let Some(d) = self.spheres.as_ref().filter(|d| d.count > 0) {
            let dev = ctx.device();
            unsafe {
                dev.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, d.pipeline.pipeline);
                dev.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, d.pipeline.layout, 0, &[d.set], &[]);
                dev.cmd_push_constants(cmd, d.pipeline.layout, GRAPHICS_STAGES, 0, bytemuck::bytes_of(&self.push));
                dev.cmd_draw(cmd, SPHERE_VERTICES, d.count, 0, 0);
            }
        }
    }

    /// Reads the view image back (waits) as RGBA, row 0 = top of the image; alpha is the
    /// covered fraction of the pixel. Call after a recorded frame has completed.
    pub fn read_rgba(&self, ctx: &Context) -> Result<Vec<[f32; 4]>> {
        if !self.recorded.get() {
            return Err(Error::Unsupported("view image read before any frame was recorded".into()));
        }
        let layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        Ok(match self.choice.color_format {
            vk::Format::R32G32B32A32_SFLOAT => {
                let bytes = memory::download_image(ctx, &self.output, layout, 16)?;
                bytes
                    .chunks_exact(16)
                    .map(|c| {
                        std::array::from_fn(|k| {
                            f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]])
                        })
                    })
                    .collect()
            }
            _ => {
                let bytes = memory::download_image(ctx, &self.output, layout, 8)?;
                bytes
                    .chunks_exact(8)
                    .map(|c| std::array::from_fn(|k| half::f16::from_le_bytes([c[2 * k], c[2 * k + 1]]).to_f32()))
                    .collect()
            }
        })
    }

    /// Reads the linear HDR view image back (waits) as RGB, row-major, row 0 = top.
    pub fn read_hdr(&self, ctx: &Context) -> Result<Vec<[f32; 3]>> {
        Ok(self.read_rgba(ctx)?.into_iter().map(|p| [p[0], p[1], p[2]]).collect())
    }
}
