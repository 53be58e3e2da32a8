//! Recorded transfers (docs/integration.md §3): height uploads and shading read-backs through a
//! host-sized [`StagingRing`], recorded into the caller's command buffer — no submit, no wait.
//! [`Renderer::update_heights`] and [`Renderer::read_layers`] stay as blocking conveniences.

use ash::vk;

use super::renderer::{height_origin, Renderer, ShadingLayers};
use super::shade::{ShadingFormat, LAYER_DIRECT, LAYER_GLOSSY, LAYER_INDIRECT, LAYER_TOTAL, PLANE_GLOSSY_INDIRECT};
use crate::error::Result;
use crate::scene::HeightField;
use crate::vk::{barrier, Recorder, StagingRing};

/// Stage name of [`Renderer::record_heights_upload`].
pub const STAGE_HEIGHTS_UPLOAD: &str = super::stages::stage_name("heights.upload");
/// Stage name of [`Renderer::record_read_layers`].
pub const STAGE_READBACK: &str = super::stages::stage_name("shade.readback");

/// The planes [`Renderer::record_read_layers`] copies, in [`ShadingLayers`] order (those the
/// shading buffer has: a diffuse surface has no glossy planes, whose layers read as zero).
const PLANES: [usize; 5] = [LAYER_TOTAL, LAYER_DIRECT, LAYER_INDIRECT, LAYER_GLOSSY, PLANE_GLOSSY_INDIRECT];

/// Where [`Renderer::record_read_layers`] put the layers in its ring.
#[derive(Clone, Copy, Debug)]
pub struct LayersReadback {
    offset: u64,
    width: usize,
    height: usize,
    /// How many of [`PLANES`] were copied (the rest are zero).
    copied: usize,
    /// The texel format of the copied planes.
    format: ShadingFormat,
}

impl LayersReadback {
    /// The layers, once the host has waited for the command buffer that copied them.
    pub fn layers(&self, ring: &mut StagingRing) -> Result<ShadingLayers> {
        let texels = self.width * self.height;
        let plane = texels as u64 * self.format.texel_bytes();
        let mut out: Vec<Vec<[f32; 3]>> = Vec::with_capacity(PLANES.len());
        for i in 0..PLANES.len() {
            if i >= self.copied {
                out.push(vec![[0.0; 3]; texels]);
                continue;
            }
            out.push(self.format.decode(ring.read(self.offset + i as u64 * plane, plane)?));
        }
        let mut it = out.into_iter();
        let mut next = || it.next().unwrap_or_default();
        Ok(ShadingLayers {
            width: self.width,
            height: self.height,
            total: next(),
            direct: next(),
            indirect: next(),
            glossy: next(),
            indirect_glossy: next(),
        })
    }
}

impl Renderer {
    /// Records new heights from the CPU into the caller's command buffer (stage
    /// `heights.upload`): `field` (the renderer's size, magnitudes within the limits) is copied
    /// into `ring` (an upload ring) now, and the command buffer copies it into the heights
    /// buffer and updates the level table with the new origin, between a barrier after the
    /// previous frames' reads (write-after-read) and one before the compute reads. The next
    /// [`Renderer::record`] rebuilds the pyramid.
    pub fn record_heights_upload(
        &mut self,
        rec: &mut Recorder,
        ring: &mut StagingRing,
        field: &HeightField,
    ) -> Result<()> {
        self.check_new_heights(field)?;
        let offset = ring.push(bytemuck::cast_slice(field.data()))?;
        let table = self.pyramid.origin_table(height_origin(field))?;
        let (src, dst, len) = (ring.buffer().raw, self.pyramid.levels_buffer().raw, (field.data().len() * 4) as u64);
        let table_buffer = self.pyramid.table_buffer().raw;
        rec.scope(STAGE_HEIGHTS_UPLOAD, |ctx, cmd| {
            barrier::compute_to_update(ctx, cmd);
            let region = [vk::BufferCopy::default().src_offset(offset).dst_offset(0).size(len)];
            unsafe {
                ctx.device().cmd_copy_buffer(cmd, src, dst, &region);
                ctx.device().cmd_update_buffer(cmd, table_buffer, 0, &table);
            }
            barrier::update_to_compute(ctx, cmd);
        });
        self.heights_changed = true;
        Ok(())
    }

    /// Bytes one [`Renderer::record_read_layers`] takes from a read-back ring: `W·H` texels of
    /// [`Renderer::shading_format`] per plane it copies (5 for a glossy surface, 3 for a
    /// diffuse one), before the ring's alignment of the start.
    pub fn read_layers_bytes(&self) -> u64 {
        self.plane_bytes() * self.copied_planes() as u64
    }

    /// Bytes of one plane of the shading buffer.
    fn plane_bytes(&self) -> u64 {
        let l = self.pyramid.layout().levels[0];
        l.width as u64 * l.height as u64 * self.shade.format().texel_bytes()
    }

    /// How many of [`PLANES`] the shading buffer has (the glossy ones only for a glossy surface).
    fn copied_planes(&self) -> usize {
        PLANES.iter().take_while(|&&p| p < self.shade.planes()).count()
    }

    /// Records a copy of the exported layers into `ring` (a read-back ring of at least
    /// [`Renderer::read_layers_bytes`] free bytes; stage `shade.readback`): a barrier after the
    /// frame's compute writes, the copies, a barrier to host reads. After the host waited for
    /// the command buffer, [`LayersReadback::layers`] returns what [`Renderer::read_layers`]
    /// would.
    pub fn record_read_layers(&self, rec: &mut Recorder, ring: &mut StagingRing) -> Result<LayersReadback> {
        let l = self.pyramid.layout().levels[0];
        let (width, height) = (l.width as usize, l.height as usize);
        let plane = self.plane_bytes();
        let copied = self.copied_planes();
        let offset = ring.reserve(self.read_layers_bytes())?;
        let (src, dst) = (self.shade.output().raw, ring.buffer().raw);
        rec.scope(STAGE_READBACK, |ctx, cmd| {
            barrier::compute_to_transfer(ctx, cmd);
            let regions: Vec<vk::BufferCopy> = PLANES[..copied]
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    vk::BufferCopy::default()
                        .src_offset(*p as u64 * plane)
                        .dst_offset(offset + i as u64 * plane)
                        .size(plane)
                })
                .collect();
            unsafe { ctx.device().cmd_copy_buffer(cmd, src, dst, &regions) };
            barrier::transfer_to_host(ctx, cmd);
        });
        Ok(LayersReadback { offset, width, height, copied, format: self.shade.format() })
    }
}
