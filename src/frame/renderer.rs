//! The GI effect assembled from its passes, in the order of NS09 figure 6:
//! heights → pyramid → visibility (environment, key lights) → direct shade.
//!
//! The host owns the command buffer; [`Renderer::record`] records every stage into it.
//! Inputs: the scene (heights, lights, material, settings). Output: the shading buffer of
//! [`ShadePass`] (see its docs for the layout). Intermediates are private.

use super::pyramid::HeightPyramid;
use super::shade::{ShadePass, LAYER_DIRECT, LAYER_GLOSSY, LAYER_INDIRECT, LAYER_TOTAL};
use super::visibility::VisibilityPass;
use crate::error::{Error, Result};
use crate::scene::model::Scene;
use crate::scene::HeightField;
use crate::vk::{Buffer, Context, Recorder};

/// The exported layers of the shading texture (CONVENTIONS.md), RGB per texel, row-major.
pub struct ShadingLayers {
    pub width: usize,
    pub height: usize,
    pub total: Vec<[f32; 3]>,
    pub direct: Vec<[f32; 3]>,
    pub indirect: Vec<[f32; 3]>,
    pub glossy: Vec<[f32; 3]>,
}

/// Counters that show what a frame did (for tests and the `animate` report).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RendererStats {
    /// Frames recorded.
    pub frames: u64,
    /// Frames that rebuilt the height pyramid (heights changed since the previous frame).
    pub pyramid_builds: u64,
}

/// All passes of one scene.
pub struct Renderer {
    pub pyramid: HeightPyramid,
    pub visibility: VisibilityPass,
    pub shade: ShadePass,
    heights_changed: bool,
    stats: RendererStats,
}

impl Renderer {
    /// Validates the settings, creates every pass and uploads the heights.
    pub fn new(ctx: &Context, scene: &Scene) -> Result<Self> {
        scene.gi.validate()?;
        let (w, h) = (scene.field.width(), scene.field.height());
        let work = scene.gi.working_size(w, h);
        let pyramid = HeightPyramid::new(ctx, w, h, work, scene.gi.level_step, scene.gi.pyramid, scene.wrap)?;
        let r = pyramid.upload(ctx, &scene.field).and_then(|_| VisibilityPass::new(ctx, &pyramid, scene));
        let visibility = match r {
            Ok(v) => v,
            Err(e) => {
                pyramid.destroy(ctx);
                return Err(e);
            }
        };
        match ShadePass::new(ctx, &pyramid, &visibility, scene) {
            Ok(shade) => {
                Ok(Self { pyramid, visibility, shade, heights_changed: true, stats: RendererStats::default() })
            }
            Err(e) => {
                visibility.destroy(ctx);
                pyramid.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Records the frame: pyramid (only when the heights changed since the last recorded
    /// frame), visibility, shading.
    pub fn record(&mut self, rec: &mut Recorder) {
        self.stats.frames += 1;
        if self.heights_changed {
            self.pyramid.record(rec);
            self.stats.pyramid_builds += 1;
            self.heights_changed = false;
        }
        self.visibility.record(rec);
        self.shade.record(rec);
    }

    /// Replaces the heights from the CPU (same size as the scene's field; waits for the upload).
    /// The next [`Renderer::record`] rebuilds the pyramid.
    pub fn update_heights(&mut self, ctx: &Context, field: &HeightField) -> Result<()> {
        let l = self.pyramid.layout().levels[0];
        if (field.width(), field.height()) != (l.width as usize, l.height as usize) {
            return Err(Error::param(
                "height field size",
                format!("{}×{}", field.width(), field.height()),
                format!("{}×{} (the renderer's size; create a new Renderer to resize)", l.width, l.height),
            ));
        }
        self.pyramid.upload(ctx, field)?;
        self.heights_changed = true;
        Ok(())
    }

    /// The full-resolution heights the frame reads: `f32`, row-major `W × H` from offset 0 of
    /// this buffer (storage + transfer usage). A host or a simulation pass may write them on the
    /// GPU in the same command buffer before [`Renderer::record`] (by a transfer or a compute
    /// shader; `record` begins with the barrier for both) and then calls
    /// [`Renderer::mark_heights_changed`].
    pub fn heights_buffer(&self) -> &Buffer {
        self.pyramid.levels_buffer()
    }

    /// Tells the renderer that the heights were written on the GPU since the last frame.
    pub fn mark_heights_changed(&mut self) {
        self.heights_changed = true;
    }

    /// The shading texture ([`ShadePass`] output): `vec4` per texel, planes `W × H` in the order
    /// total, direct, indirect, glossy. After `record`, written by compute; a reader in another
    /// stage adds its own barrier (see `docs/integration.md`).
    pub fn shading_buffer(&self) -> &Buffer {
        self.shade.output()
    }

    pub fn stats(&self) -> RendererStats {
        self.stats
    }

    /// Reads every exported layer back (waits).
    pub fn read_layers(&self, ctx: &Context) -> Result<ShadingLayers> {
        let l = self.pyramid.layout().levels[0];
        Ok(ShadingLayers {
            width: l.width as usize,
            height: l.height as usize,
            total: self.shade.read_layer(ctx, LAYER_TOTAL)?,
            direct: self.shade.read_layer(ctx, LAYER_DIRECT)?,
            indirect: self.shade.read_layer(ctx, LAYER_INDIRECT)?,
            glossy: self.shade.read_layer(ctx, LAYER_GLOSSY)?,
        })
    }

    /// GPU memory held by all passes, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.pyramid.memory_bytes() + self.visibility.memory_bytes() + self.shade.memory_bytes()
    }

    pub fn destroy(self, ctx: &Context) {
        self.shade.destroy(ctx);
        self.visibility.destroy(ctx);
        self.pyramid.destroy(ctx);
    }
}
