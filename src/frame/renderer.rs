//! The GI effect assembled from its passes, in the order of NS09 figure 6:
//! heights → pyramid → visibility (environment, key lights) → direct shade.
//!
//! The host owns the command buffer; [`Renderer::record`] records every stage into it.
//! Inputs: the scene (heights, lights, material, settings). Output: the shading buffer of
//! [`ShadePass`] (see its docs for the layout). Intermediates are private.

use super::pyramid::HeightPyramid;
use super::shade::{ShadePass, LAYER_DIRECT, LAYER_GLOSSY, LAYER_INDIRECT, LAYER_TOTAL};
use super::visibility::VisibilityPass;
use crate::error::Result;
use crate::scene::model::Scene;
use crate::vk::{Context, Recorder};

/// The exported layers of the shading texture (CONVENTIONS.md), RGB per texel, row-major.
pub struct ShadingLayers {
    pub width: usize,
    pub height: usize,
    pub total: Vec<[f32; 3]>,
    pub direct: Vec<[f32; 3]>,
    pub indirect: Vec<[f32; 3]>,
    pub glossy: Vec<[f32; 3]>,
}

/// All passes of one scene.
pub struct Renderer {
    pub pyramid: HeightPyramid,
    pub visibility: VisibilityPass,
    pub shade: ShadePass,
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
            Ok(shade) => Ok(Self { pyramid, visibility, shade }),
            Err(e) => {
                visibility.destroy(ctx);
                pyramid.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Records the frame: pyramid, visibility, shading.
    pub fn record(&self, rec: &mut Recorder) {
        self.pyramid.record(rec);
        self.visibility.record(rec);
        self.shade.record(rec);
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
