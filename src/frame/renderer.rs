//! The GI effect assembled from its passes, in the order of NS09 figure 6:
//! heights → pyramid → visibility (environment, key lights) → direct shade (+ local lights) → per bounce:
//! radiance pyramid → indirect scan → indirect shade.
//!
//! The host owns the command buffer; [`Renderer::record`] records every stage into it.
//! Inputs: the scene (heights, lights, material, settings). Output: the shading buffer of
//! [`ShadePass`] (see its docs for the layout). Intermediates are private.

use super::blockers::BlockerPass;
use super::indirect::IndirectPass;
use super::live::{self, Live, RendererOptions};
use super::local::LocalLightPass;
use super::plan::{FrameState, Plan, Planner, Stage};
use super::pyramid::{HeightPyramid, LevelsMemory, PyramidKind};
use super::pyramid_max::{uses_max_bound, MaxPyramid};
use super::shade::{ShadePass, ShadingFormat, LAYER_DIRECT, LAYER_GLOSSY, LAYER_INDIRECT, LAYER_TOTAL};
use super::visibility::VisibilityPass;
use crate::error::{Error, Result};
pub use crate::rules::scene::{height_origin, needs_indirect, vector_pyramid};
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
    /// The indirect part of `glossy` (not exported; for comparisons such as figure 5).
    pub indirect_glossy: Vec<[f32; 3]>,
}

/// Stage name of [`Renderer::record_heights_from_image`].
pub const STAGE_HEIGHTS_COPY: &str = super::stages::stage_name("heights.copy");

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
    /// Present when the scene has sphere blockers (docs/blockers.md).
    pub blockers: Option<BlockerPass>,
    pub shade: ShadePass,
    /// Present when the scene has local lights (docs/local-lights.md).
    pub local: Option<LocalLightPass>,
    /// Present when the scene needs indirect light (bounces > 0 and some exit radiance).
    pub indirect: Option<IndirectPass>,
    planner: Planner,
    pub(super) heights_changed: bool,
    stats: RendererStats,
    /// The live inputs (`set_environment`, …; src/frame/live.rs).
    pub(super) live: Live,
}

impl Renderer {
    /// Validates the settings, creates every pass and uploads the heights.
    pub fn new(ctx: &Context, scene: &Scene) -> Result<Self> {
        Self::with_options(ctx, scene, &RendererOptions::default())
    }

    /// [`Renderer::new`] with creation options (e.g. more key-light slots than the scene has,
    /// for [`Renderer::set_key_lights`]).
    /// Creation submits once: every upload is batched ([`Context::batched`]).
    pub fn with_options(ctx: &Context, scene: &Scene, options: &RendererOptions) -> Result<Self> {
        let scene = &live::with_slots(scene, options)?;
        ctx.batched(|| Self::create(ctx, scene))
    }

    fn create(ctx: &Context, scene: &Scene) -> Result<Self> {
        scene.gi.validate()?;
        // Also the exact lobe's restrictions (check_lobe), on the scene with the options' slots.
        scene.check_limits()?;
        let mut pyramid = Self::create_pyramid(ctx, scene)?;
        let planner = Planner::new(scene);
        // The max pyramid (the scans' early stop), before the visibility, which reads it too;
        // the indirect pass owns it.
        let mut max = None;
        let r = pyramid
            .upload(ctx, &scene.field)
            .and_then(|_| pyramid.set_origin(ctx, height_origin(&scene.field)))
            .and_then(|_| {
                if planner.creates_indirect() && uses_max_bound(scene) {
                    max = Some(MaxPyramid::new(ctx, &pyramid)?);
                }
                VisibilityPass::new(ctx, &pyramid, scene, max.as_ref().map(MaxPyramid::buffer))
            });
        let visibility = match r {
            Ok(v) => v,
            Err(e) => {
                max.into_iter().for_each(|m| m.destroy(ctx));
                pyramid.destroy(ctx);
                return Err(e);
            }
        };
        let (blockers, shade) = match Self::create_direct(ctx, scene, &pyramid, &visibility) {
            Ok(d) => d,
            Err(e) => {
                max.into_iter().for_each(|m| m.destroy(ctx));
                visibility.destroy(ctx);
                pyramid.destroy(ctx);
                return Err(e);
            }
        };
        let (local, indirect) =
            match Self::create_local_and_indirect(ctx, scene, &pyramid, &shade, blockers.as_ref(), &planner, max) {
                Ok(l) => l,
                Err(e) => {
                    shade.destroy(ctx);
                    if let Some(b) = blockers {
                        b.destroy(ctx);
                    }
                    visibility.destroy(ctx);
                    pyramid.destroy(ctx);
                    return Err(e);
                }
            };
        Ok(Self {
            pyramid,
            visibility,
            blockers,
            shade,
            local,
            indirect,
            planner,
            heights_changed: true,
            stats: RendererStats::default(),
            live: Live::new(scene.clone()),
        })
    }

    /// The height pyramid of `scene`, its heights not uploaded yet.
    fn create_pyramid(ctx: &Context, scene: &Scene) -> Result<HeightPyramid> {
        let (w, h) = (scene.field.width(), scene.field.height());
        let work = scene.gi.working_size(w, h);
        let gi = &scene.gi;
        let stack = Some(super::pyramid::height_stack_of(gi, w, h)?);
        let kind = PyramidKind::HEIGHTS;
        // Room after level 0 for the radiance levels where they share the buffer (docs/pyramid.md,
        // "Shared levels").
        let levels = LevelsMemory::Own { tail: super::radiance::height_levels_tail(scene)? };
        let (k_v, mode) = (gi.level_step, gi.pyramid);
        let mut pyramid = HeightPyramid::with_kind(ctx, w, h, work, k_v, mode, scene.wrap, kind, stack, levels)?;
        // Level 0 read as the bilinear surface: through the stack, where its size allows.
        pyramid.set_raw_plane0(gi.level0 == crate::scene::model::Level0::Bilinear);
        Ok(pyramid)
    }

    /// The sphere blockers' pass (scenes with spheres) and the direct shade; on failure neither
    /// is left.
    fn create_direct(
        ctx: &Context,
        scene: &Scene,
        pyramid: &HeightPyramid,
        visibility: &VisibilityPass,
    ) -> Result<(Option<BlockerPass>, ShadePass)> {
        let blockers =
            (!scene.spheres.is_empty()).then(|| BlockerPass::new(ctx, pyramid, visibility, scene)).transpose()?;
        let shade = match ShadePass::new(ctx, pyramid, visibility, blockers.as_ref(), scene) {
            Ok(s) => s,
            Err(e) => {
                if let Some(b) = blockers {
                    b.destroy(ctx);
                }
                return Err(e);
            }
        };
        Ok((blockers, shade))
    }

    /// The local lights' pass (scenes with local lights) and the indirect passes (where the
    /// planner creates them; they take `max`); on failure neither is left, nor `max`.
    #[allow(clippy::too_many_arguments)]
    fn create_local_and_indirect(
        ctx: &Context,
        scene: &Scene,
        pyramid: &HeightPyramid,
        shade: &ShadePass,
        blockers: Option<&BlockerPass>,
        planner: &Planner,
        max: Option<MaxPyramid>,
    ) -> Result<(Option<LocalLightPass>, Option<IndirectPass>)> {
        let local =
            match (!scene.local_lights.is_empty()).then(|| LocalLightPass::new(ctx, pyramid, shade, scene)).transpose()
            {
                Ok(l) => l,
                Err(e) => {
                    max.into_iter().for_each(|m| m.destroy(ctx));
                    return Err(e);
                }
            };
        let indirect = if planner.creates_indirect() {
            match IndirectPass::new(ctx, pyramid, shade, blockers.map(|b| b.output()), scene, max) {
                Ok(i) => Some(i),
                Err(e) => {
                    if let Some(l) = local {
                        l.destroy(ctx);
                    }
                    return Err(e);
                }
            }
        } else {
            max.into_iter().for_each(|m| m.destroy(ctx)); // none: made only with the indirect pass
            None
        };
        Ok((local, indirect))
    }

    /// Records the frame: exactly the stages of [`Renderer::plan_next`], in its order
    /// (docs/plan.md): the live inputs' updates, the pyramid and the visibility only when the
    /// heights changed since the last recorded frame (the key lights' when they moved); then
    /// what is out of date of the direct shading and the indirect bounces (amortised with
    /// `gi.amortize`); nothing when nothing changed. A frame that records anything begins with
    /// a barrier after every earlier command (docs/integration.md §3).
    pub fn record(&mut self, rec: &mut Recorder) {
        let plan = self.plan_next();
        let first = rec.stages().len();
        if !plan.stages.is_empty() {
            crate::vk::barrier::before_frame(rec.ctx, rec.cmd);
        }
        for s in &plan.stages {
            self.record_stage(rec, s.stage);
        }
        debug_assert!(
            rec.stages()[first..].iter().map(String::as_str).eq(plan.names()),
            "recorded stages {:?} differ from the plan {:?}",
            &rec.stages()[first..],
            plan.names()
        );
        self.stats.frames += 1;
        self.stats.pyramid_builds += plan.rebuilds_pyramid() as u64;
        self.heights_changed = false;
        self.live.recorded(&plan.stages.iter().map(|s| s.stage).collect::<Vec<_>>());
    }

    /// The plan of the frame the next [`Renderer::record`] records (docs/plan.md).
    pub fn plan_next(&self) -> Plan {
        self.planner.plan(&FrameState {
            heights_changed: self.heights_changed,
            frame_index: self.stats.frames,
            inputs: self.live.pending,
        })
    }

    fn record_stage(&self, rec: &mut Recorder, stage: Stage) {
        let ind = self.indirect.as_ref();
        match stage {
            Stage::InputsUpdate => live::record_updates(&self.live, rec),
            Stage::PyramidDecimate => self.pyramid.record_decimate(rec),
            Stage::PyramidSynthesize => self.pyramid.record_synthesize(rec),
            Stage::PyramidMax => ind.into_iter().for_each(|i| i.record_max(rec)),
            Stage::VisibilityEnvironment => self.visibility.record_sets(rec, true),
            Stage::VisibilityKeyLights => self.visibility.record_sets(rec, false),
            Stage::VisibilityBlockers => self.blockers.iter().for_each(|b| b.record(rec)),
            Stage::ShadeDirect => self.shade.record(rec),
            Stage::ShadeLocalLights => self.local.iter().for_each(|l| l.record(rec)),
            Stage::RadianceGather(b) => ind.into_iter().for_each(|i| i.radiance.record_gather(rec, b)),
            Stage::RadianceDecimate(_) => ind.into_iter().for_each(|i| i.radiance.pyramid.record_decimate(rec)),
            Stage::RadianceSynthesize(_) => ind.into_iter().for_each(|i| i.radiance.pyramid.record_synthesize(rec)),
            Stage::IndirectScan(b) => ind.into_iter().for_each(|i| i.record_scan(rec, b)),
            Stage::IndirectShade(b) => ind.into_iter().for_each(|i| i.record_shade(rec, b)),
        }
    }

    /// Replaces the heights from the CPU (same size as the scene's field; waits for the upload).
    /// The next [`Renderer::record`] rebuilds the pyramid.
    pub fn update_heights(&mut self, ctx: &Context, field: &HeightField) -> Result<()> {
        self.check_new_heights(field)?;
        self.pyramid.upload(ctx, field)?;
        self.pyramid.set_origin(ctx, height_origin(field))?;
        self.heights_changed = true;
        Ok(())
    }

    /// New heights for this renderer: its size, magnitudes within the limits.
    pub(super) fn check_new_heights(&self, field: &HeightField) -> Result<()> {
        crate::scene::model::limits::check_heights(field)?;
        let l = self.pyramid.layout().levels[0];
        if (field.width(), field.height()) != (l.width as usize, l.height as usize) {
            return Err(Error::param(
                "height field size",
                format!("{}×{}", field.width(), field.height()),
                format!("{}×{} (the renderer's size; create a new Renderer to resize)", l.width, l.height),
            ));
        }
        Ok(())
    }

    /// The height origin `z0` the pyramid subtracts from the heights it reads (docs/pyramid.md,
    /// "Origin"): the midrange of the field given to [`Renderer::new`] or the last
    /// [`Renderer::update_heights`]. Heights written on the GPU keep the last one; the heights
    /// buffer always holds absolute heights.
    pub fn height_origin(&self) -> f32 {
        self.pyramid.origin()
    }

    /// The full-resolution heights the frame reads: `f32`, row-major `W × H` from offset 0 of
    /// this buffer (storage + transfer usage). A host or a simulation pass may write them on the
    /// GPU in the same command buffer before [`Renderer::record`] (by a transfer or a compute
    /// shader; `record` begins with the barrier for both) and then calls
    /// [`Renderer::mark_heights_changed`].
    pub fn heights_buffer(&self) -> &Buffer {
        self.pyramid.levels_buffer()
    }

    /// Records a copy of the heights from a host's image (stage `heights.copy`) and marks them
    /// changed. The image must be `R32_SFLOAT`, `W × H` (the renderer's size), created with
    /// `TRANSFER_SRC` usage, and be in `layout` = `TRANSFER_SRC_OPTIMAL` or `GENERAL` with the
    /// host's writes already made visible to the copy stage (the host's own barrier, ending in
    /// `COPY` / `TRANSFER_READ`). The image stays in `layout`; the next [`Renderer::record`]
    /// begins with the transfer→compute barrier for the copied heights.
    pub fn record_heights_from_image(
        &mut self,
        rec: &mut Recorder,
        image: ash::vk::Image,
        format: ash::vk::Format,
        extent: (u32, u32),
        layout: ash::vk::ImageLayout,
    ) -> Result<()> {
        use ash::vk;
        let l = self.pyramid.layout().levels[0];
        if format != vk::Format::R32_SFLOAT {
            return Err(Error::param("height image format", format!("{format:?}"), "R32_SFLOAT"));
        }
        if extent != (l.width, l.height) {
            return Err(Error::param(
                "height image size",
                format!("{}×{}", extent.0, extent.1),
                format!("{}×{} (the renderer's size)", l.width, l.height),
            ));
        }
        if layout != vk::ImageLayout::TRANSFER_SRC_OPTIMAL && layout != vk::ImageLayout::GENERAL {
            return Err(Error::param("height image layout", format!("{layout:?}"), "TRANSFER_SRC_OPTIMAL or GENERAL"));
        }
        let dst = self.pyramid.levels_buffer().raw;
        rec.scope(STAGE_HEIGHTS_COPY, |ctx, cmd| {
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D { width: extent.0, height: extent.1, depth: 1 });
            unsafe { ctx.device().cmd_copy_image_to_buffer(cmd, image, layout, dst, &[region]) };
            crate::vk::barrier::transfer_to_compute(ctx, cmd);
        });
        self.heights_changed = true;
        Ok(())
    }

    /// Tells the renderer that the heights were written on the GPU since the last frame.
    pub fn mark_heights_changed(&mut self) {
        self.heights_changed = true;
    }

    /// The shading texture ([`ShadePass`] output): one RGB texel per field texel in
    /// [`Renderer::shading_format`] (`gi.shading_storage`: an `f32` triple, 12 bytes, tightly
    /// packed, by default; one RGBE word, 4 bytes, with `"rgbe"`), planes `W × H` in the
    /// order total, direct, indirect, then for a glossy surface glossy and two internal ones
    /// ([`Renderer::shading_planes`]: 6, or 3 for a surface created without specular). After
    /// `record`, written by compute; a reader in another stage adds its own barrier (see
    /// `docs/integration.md`).
    pub fn shading_buffer(&self) -> &Buffer {
        self.shade.output()
    }

    /// The texel format of [`Renderer::shading_buffer`] ([`ShadingFormat::decode`] reads it).
    pub fn shading_format(&self) -> ShadingFormat {
        self.shade.format()
    }

    /// Planes in [`Renderer::shading_buffer`]: 6 for a surface created with a specular colour,
    /// 3 (total, direct, indirect) otherwise.
    pub fn shading_planes(&self) -> usize {
        self.shade.planes()
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
            indirect_glossy: self.shade.read_layer(ctx, super::shade::PLANE_GLOSSY_INDIRECT)?,
        })
    }

    /// Diagnostics: every intermediate GPU buffer of the frame, read back as `f32` (waits), in
    /// pipeline order, each with a name:
    ///
    /// - `pyramid.level{i}` (level `i` of the height pyramid, `W_i × H_i`; level 0 alone when
    ///   the radiance levels share the buffer after it, which a frame with indirect light
    ///   overwrites the decimated levels with: docs/pyramid.md, "Shared levels") and, in stack
    ///   mode, `pyramid.stack{i}` (plane `i` at the working resolution, for the levels the stack
    ///   keeps: what the decimated levels were synthesized into);
    /// - `visibility.v.{set}` (`set` = `environment` or `key{k}`): receivers × `n²`;
    /// - `shade.{plane}` for the planes of the shading buffer (`total`, `direct`, `indirect`
    ///   and, for a glossy surface, `glossy`, `glossy_direct`, `glossy_indirect`), rgb per
    ///   texel, and `shade.incident` (`T` per texel) with the glossy vector pyramid;
    /// - with indirect light: `radiance.levels` (every channel; level 0 holds what the last
    ///   bounce's shade left for a next bounce, the coarser levels that bounce's own input),
    ///   `radiance.stack` (stack mode), `indirect.u` (the last bounce's `U`) and `indirect.next`
    ///   (channels 0–2 of level 0 as rgb per texel: the radiance the last bounce leaves for a
    ///   next one). A sub-sampled scalar pyramid's level 0 is the working grid and holds the
    ///   last bounce's input instead: its shades pass the exit radiance on through the total
    ///   plane ([`crate::rules::scene::radiance_base`]).
    ///
    /// Call after a recorded frame has completed (before it, buffers that no frame wrote yet
    /// hold undefined values). For tests and debugging; not part of a frame.
    pub fn debug_buffers(&self, ctx: &Context) -> Result<Vec<(String, Vec<f32>)>> {
        use super::visibility::SetKind;
        let mut out = Vec::new();
        let shared = self.indirect.as_ref().is_some_and(|i| i.radiance.pyramid.levels_aliased());
        let levels = if shared { 1 } else { self.pyramid.layout().count() };
        for i in 0..levels {
            out.push((format!("pyramid.level{i}"), self.pyramid.read_level(ctx, i)?));
        }
        if self.pyramid.stack_buffer().is_some() {
            for i in 0..self.pyramid.stack_levels() {
                out.push((format!("pyramid.stack{i}"), self.pyramid.read_stack(ctx, i)?));
            }
        }
        for (i, kind) in self.visibility.set_kinds().into_iter().enumerate() {
            let name = match kind {
                SetKind::Environment => "visibility.v.environment".to_string(),
                SetKind::KeyLight(k) => format!("visibility.v.key{k}"),
            };
            out.push((name, self.visibility.read(ctx, i)?));
        }
        if let Some(b) = &self.blockers {
            out.push(("visibility.blockers".to_string(), b.read(ctx)?));
        }
        let planes = ["total", "direct", "indirect", "glossy", "glossy_direct", "glossy_indirect"];
        for (p, name) in planes.iter().enumerate().take(self.shade.planes()) {
            out.push((format!("shade.{name}"), self.shade.read_plane(ctx, p)?));
        }
        if let Some(t) = self.shade.read_incident(ctx)? {
            out.push(("shade.incident".to_string(), t));
        }
        if let Some(ind) = &self.indirect {
            out.push(("radiance.levels".to_string(), ind.radiance.pyramid.read_levels_all(ctx)?));
            if let Some(st) = ind.radiance.pyramid.read_stack_all(ctx)? {
                out.push(("radiance.stack".to_string(), st));
            }
            out.push(("indirect.u".to_string(), ind.read_u(ctx)?));
            out.push(("indirect.next".to_string(), ind.read_next(ctx)?));
        }
        Ok(out)
    }

    /// GPU memory held by all passes, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.pyramid.memory_bytes()
            + self.visibility.memory_bytes()
            + self.shade.memory_bytes()
            + self.local.as_ref().map_or(0, |l| l.memory_bytes())
            + self.blockers.as_ref().map_or(0, |b| b.memory_bytes())
            + self.indirect.as_ref().map_or(0, |i| i.memory_bytes())
    }

    pub fn destroy(self, ctx: &Context) {
        if let Some(i) = self.indirect {
            i.destroy(ctx);
        }
        if let Some(l) = self.local {
            l.destroy(ctx);
        }
        self.shade.destroy(ctx);
        if let Some(b) = self.blockers {
            b.destroy(ctx);
        }
        self.visibility.destroy(ctx);
        self.pyramid.destroy(ctx);
    }
}
