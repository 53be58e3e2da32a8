//! Stage `view.raster` (docs/view.md): the view image. Rasterises the height-field mesh
//! (CONVENTIONS.md: one vertex per sample at `(i·s, j·s, H[j][i])`, two triangles per quad,
//! split along the `(i, j)–(i+1, j+1)` diagonal) from the scene camera, coloured by the total
//! layer of the shading texture (one colour per vertex, interpolated perspective-correctly), with
//! MSAA resolved into a single-sample HDR image.
//!
//! Inputs are bound when the pass is created (they are stable per [`Renderer`]): the heights
//! buffer (`f32`, row-major `W × H` from offset 0; [`Renderer::heights_buffer`]) and the shading
//! buffer (RGB `f32` per texel, plane 0 = total; [`Renderer::shading_buffer`]). Vertices are made
//! in the vertex shader from the vertex and instance index (one instance per row of quads, one
//! small index buffer built once), so heights written on the GPU every frame need no upload.
//!
//! # What [`ViewPass::record`] records (all inside the scope `view.raster`)
//!
//! 1. A memory barrier: compute-shader and transfer writes → index reads and vertex/fragment
//!    storage reads (so the heights and the shading texture written earlier in the same
//!    command buffer, or uploaded, are visible). The pass therefore needs no barrier from the
//!    caller after [`Renderer::record`].
//! 2. Layout transitions from UNDEFINED (previous contents discarded): the output image →
//!    COLOR_ATTACHMENT_OPTIMAL, waiting (execution only) for all earlier commands so an earlier
//!    reader of the previous frame's image is safe; the MSAA colour image →
//!    COLOR_ATTACHMENT_OPTIMAL and the depth image → DEPTH_STENCIL_ATTACHMENT_OPTIMAL, each after
//!    the previous frame's attachment writes.
//! 3. Dynamic rendering (`vkCmdBeginRendering`): clear to [`BACKGROUND`] and depth 0 (reversed
//!    depth), one indexed instanced draw, with live sphere blockers ([`ViewPass::set_spheres`])
//!    a second pipeline's instanced draw of one UV sphere per sphere (same depth buffer; it
//!    reads the heights buffer too, for the field's cast shadow on the spheres), and
//!    at the end of rendering the MSAA resolve (`AVERAGE`) into the output image. With one
//!    sample the output is rendered directly.
//! 4. The output image → **TRANSFER_SRC_OPTIMAL**, colour-attachment writes → transfer reads
//!    (`COPY`). That is the layout it is left in; a host that samples it adds its own
//!    transition (TRANSFER_SRC_OPTIMAL → SHADER_READ_ONLY_OPTIMAL).
//!
//! The resolve happens inside the same scope, so there is no separate `view.resolve` stage.
//!
//! [`Renderer`]: super::Renderer
//! [`Renderer::heights_buffer`]: super::Renderer::heights_buffer
//! [`Renderer::shading_buffer`]: super::Renderer::shading_buffer
//! [`Renderer::record`]: super::Renderer::record

use std::cell::Cell;

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

mod camera;
mod spheres;

pub use camera::CameraModel;
pub(crate) use spheres::{sphere_buffer_bytes, sphere_light_bytes, SPHERE_BUFFER, SPHERE_LIGHT_BUFFER};
pub use spheres::{sphere_is_live, SphereLighting, SPHERE_SLICES, SPHERE_STACKS, SPHERE_VERTICES};
use spheres::{GpuSphere, SphereDraw};

use super::shared::ViewPush;
use super::Renderer;
use crate::error::{Error, Result};
use crate::scene::model::{Camera, Environment, KeyLight, Scene, SphereBlocker};
use crate::shaders;
use crate::vk::barrier::{self, Transition};
use crate::vk::graphics::{self, GraphicsDesc, RenderTargets, TargetChoice, GRAPHICS_STAGES};
use crate::vk::pipeline::Bind;
use crate::vk::{memory, Buffer, Context, DescriptorKind, GraphicsPipeline, Image, Recorder};

pub const STAGE_RASTER: &str = super::stages::stage_name("view.raster");

/// Highest MSAA sample count the pass asks for.
pub const MAX_SAMPLES: u32 = 8;

/// The clear colour: linear RGB 0 and alpha 0 where no geometry covers the pixel (covered
/// pixels have alpha 1; MSAA edges have the covered fraction).
pub const BACKGROUND: [f32; 4] = [0.0; 4];

/// HDR colour formats in order of preference (the second only when it multisamples higher).
pub const COLOR_FORMATS: [vk::Format; 2] = [vk::Format::R32G32B32A32_SFLOAT, vk::Format::R16G16B16A16_SFLOAT];

/// Smallest near-plane distance as a fraction of the far-plane distance (when the camera is
/// inside the field's bounding box or the box reaches behind it).
pub const NEAR_RATIO: f64 = 1e-5;

/// Options of the view pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ViewOptions {
    /// Force this MSAA sample count (1, 2, 4, 8, …; must be supported). `None`: the highest
    /// supported count ≤ [`MAX_SAMPLES`].
    pub samples: Option<u32>,
}

/// The GPU inputs of the view pass, bound at creation.
#[derive(Clone, Copy)]
pub struct ViewInputs<'a> {
    /// Heights, `f32`, row-major `W × H` from offset 0 (storage usage).
    pub heights: &'a Buffer,
    /// Shading texture, `vec4` per texel; texels `[0, W·H)` (plane 0) are the colour.
    pub shading: &'a Buffer,
    /// Lowest and highest height: with the field's x/y extent, the bounding box that sets the
    /// near and far planes. Geometry outside it may be clipped; update it with
    /// [`ViewPass::set_height_range`] when the heights change range.
    pub height_range: (f32, f32),
}

/// One image the pass creates (see [`attachments`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Attachment {
    pub name: &'static str,
    pub format: vk::Format,
    pub usage: vk::ImageUsageFlags,
    /// Samples per pixel.
    pub samples: u32,
}

/// The images of the pass in creation order for the chosen formats and sample count: the
/// single-sample output, the depth image and, with `samples > 1`, the MSAA colour image (one
/// source for the pass and [`crate::frame::memory`]).
pub(crate) fn attachments(color: vk::Format, depth: vk::Format, samples: u32) -> Vec<Attachment> {
    let output_usage =
        vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
    let mut out = vec![
        Attachment { name: "hfgi.view.output", format: color, usage: output_usage, samples: 1 },
        Attachment {
            name: "hfgi.view.depth",
            format: depth,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            samples,
        },
    ];
    if samples > 1 {
        out.push(Attachment {
            name: "hfgi.view.msaa",
            format: color,
            usage: vk::ImageUsageFlags::COLOR_ATTACHMENT,
            samples,
        });
    }
    out
}

/// The field sizes the pass draws: at least 2×2 and fewer than 2³² samples; returns the
/// sample count.
pub(crate) fn check_field_size(width: usize, height: usize) -> Result<u64> {
    let texels = width as u64 * height as u64;
    if width < 2 || height < 2 || texels > u64::from(u32::MAX) {
        return Err(Error::param(
            "view: height field size",
            format!("{width}×{height}"),
            "at least 2×2 and fewer than 2³² samples",
        ));
    }
    Ok(texels)
}

/// Name of the index buffer.
pub(crate) const INDEX_BUFFER: &str = "hfgi.view.index";

/// Bytes of [`INDEX_BUFFER`] for a field `width` samples wide: one row of quads, 6 `u32`
/// indices per quad.
pub(crate) fn index_bytes(width: usize) -> u64 {
    6 * (width as u64 - 1) * 4
}

/// The contents of [`INDEX_BUFFER`]: one row of quads between vertex rows 0 and 1
/// (v = row·W + i); instance j adds j·W in the shader. Diagonal (i, j)–(i+1, j+1).
fn row_indices(width: usize) -> Vec<u32> {
    let w = width as u32;
    let indices: Vec<u32> = (0..w - 1).flat_map(|i| [i, i + 1, w + i + 1, i, w + i + 1, w + i]).collect();
    debug_assert_eq!((indices.len() * 4) as u64, index_bytes(width));
    indices
}

/// The inputs [`ViewPass`] binds and the image size it renders: a field of at least 2×2, buffers
/// large enough for it, and a camera image within the device's largest 2D image.
fn check_inputs(ctx: &Context, width: usize, height: usize, camera: &Camera, inputs: &ViewInputs) -> Result<()> {
    let texels = check_field_size(width, height)?;
    for (name, buf, need) in [("heights", inputs.heights, texels * 4), ("shading", inputs.shading, texels * 12)] {
        if buf.size < need {
            return Err(Error::param(
                format!("view: {name} buffer '{}' size", buf.name),
                buf.size,
                format!("at least {need} bytes for a {width}×{height} field"),
            ));
        }
    }
    let max = ctx.info().max_image_dimension_2d;
    if camera.width > max || camera.height > max {
        return Err(Error::param(
            "camera size",
            format!("{}×{}", camera.width, camera.height),
            format!("at most {max}×{max} (the device's maxImageDimension2D)"),
        ));
    }
    Ok(())
}

/// The view-image pass.
pub struct ViewPass {
    pipeline: GraphicsPipeline,
    set: vk::DescriptorSet,
    index: Buffer,
    index_count: u32,
    instances: u32,
    msaa: Option<Image>,
    depth: Image,
    output: Image,
    choice: TargetChoice,
    field: (usize, usize),
    texel_size: f64,
    /// The heights buffer (bound to the sphere pipeline too, for the field's cast shadow).
    heights: vk::DescriptorBufferInfo,
    camera: Camera,
    height_range: (f32, f32),
    model: CameraModel,
    push: ViewPush,
    recorded: Cell<bool>,
    /// Lighting of the spheres ([`ViewPass::set_sphere_lighting`]).
    lighting: SphereLighting,
    /// World box around the live spheres (widens the near/far fit), if any.
    sphere_box: Option<(DVec3, DVec3)>,
    /// The live spheres as drawn (host copy of what the sphere buffer holds).
    sphere_data: Vec<GpuSphere>,
    spheres: Option<SphereDraw>,
}

impl ViewPass {
    /// Creates the pass for a `width × height` field (texel size `texel_size`) seen from
    /// `camera` (its `width × height` is the image size), reading `inputs`. Creates one
    /// graphics pipeline, the attachments and the index buffer (uploaded now: one submit,
    /// waits). Needs `dynamicRendering` (a typed error on a host device without it).
    pub fn new(
        ctx: &Context,
        width: usize,
        height: usize,
        camera: &Camera,
        texel_size: f64,
        inputs: &ViewInputs,
        opts: &ViewOptions,
    ) -> Result<Self> {
        if !ctx.enabled_features().dynamic_rendering {
            return Err(Error::Unsupported(
                "the view pass renders with dynamicRendering (VkPhysicalDeviceVulkan13Features), which the host's \
                 device was created without (RawHandles::enabled)"
                    .into(),
            ));
        }
        ctx.batched(|| Self::build(ctx, width, height, camera, texel_size, inputs, opts))
    }

    fn build(
        ctx: &Context,
        width: usize,
        height: usize,
        camera: &Camera,
        texel_size: f64,
        inputs: &ViewInputs,
        opts: &ViewOptions,
    ) -> Result<Self> {
        check_inputs(ctx, width, height, camera, inputs)?;
        let (lo, hi) = inputs.height_range;
        let model = CameraModel::new(camera, width, height, texel_size, f64::from(lo), f64::from(hi))?;
        let choice = graphics::choose_targets(ctx, &COLOR_FORMATS, MAX_SAMPLES, opts.samples)?;
        let extent = vk::Extent2D { width: camera.width, height: camera.height };
        let (mut images, index, pipeline, set) = Self::create_objects(ctx, width, &choice, extent, inputs)?;
        let msaa = if choice.samples > 1 { images.pop() } else { None };
        let depth = images.pop().expect("depth image");
        let output = images.pop().expect("output image");
        let mut me = Self {
            pipeline,
            set,
            index,
            index_count: 6 * (width as u32 - 1),
            instances: height as u32 - 1,
            msaa,
            depth,
            output,
            choice,
            field: (width, height),
            texel_size,
            heights: inputs.heights.whole(),
            camera: camera.clone(),
            height_range: inputs.height_range,
            model,
            push: ViewPush::default(),
            recorded: Cell::new(false),
            lighting: SphereLighting::default(),
            sphere_box: None,
            sphere_data: Vec::new(),
            spheres: None,
        };
        me.update_push();
        Ok(me)
    }

    /// Creates the attachments ([`attachments`] order), the index buffer (uploaded now) and the
    /// raster pipeline with its descriptor set, in that order. On an error destroys what was
    /// made: the images, then the index buffer, then the pipeline.
    fn create_objects(
        ctx: &Context,
        width: usize,
        choice: &TargetChoice,
        extent: vk::Extent2D,
        inputs: &ViewInputs,
    ) -> Result<(Vec<Image>, Buffer, GraphicsPipeline, vk::DescriptorSet)> {
        let mut images: Vec<Image> = Vec::new();
        let mut index = None;
        let mut pipeline = None;
        let made = (|| -> Result<vk::DescriptorSet> {
            for a in attachments(choice.color_format, choice.depth_format, choice.samples) {
                let count = vk::SampleCountFlags::from_raw(a.samples);
                images.push(Image::new(ctx, a.name, extent, a.format, a.usage, count)?);
            }
            let indices = row_indices(width);
            let ib = index.insert(Buffer::new(
                ctx,
                INDEX_BUFFER,
                index_bytes(width),
                vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?);
            memory::upload(ctx, ib, 0, bytemuck::cast_slice(&indices))?;
            let p = pipeline.insert(Self::create_pipeline(ctx, choice, extent)?);
            p.allocate_set(ctx, &[Bind::Buffer(inputs.heights), Bind::Buffer(inputs.shading)])
        })();
        match made {
            Ok(set) => Ok((images, index.expect("index buffer"), pipeline.expect("pipeline"), set)),
            Err(e) => {
                images.into_iter().for_each(|i| i.destroy(ctx));
                index.into_iter().for_each(|b| b.destroy(ctx));
                pipeline.into_iter().for_each(|mut p| p.destroy(ctx));
                Err(e)
            }
        }
    }

    /// The raster pipeline for the chosen targets and the image size `extent`.
    fn create_pipeline(ctx: &Context, choice: &TargetChoice, extent: vk::Extent2D) -> Result<GraphicsPipeline> {
        GraphicsPipeline::new(
            ctx,
            &GraphicsDesc {
                name: "view/raster",
                vertex: &shaders::VIEW_RASTER_VERT,
                fragment: &shaders::VIEW_RASTER_FRAG,
                kinds: &[DescriptorKind::StorageBuffer; 2],
                push_size: std::mem::size_of::<ViewPush>() as u32,
                color_format: choice.color_format,
                depth_format: Some(choice.depth_format),
                depth_compare: vk::CompareOp::GREATER,
                samples: vk::SampleCountFlags::from_raw(choice.samples),
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                extent,
                max_sets: 1,
            },
        )
    }

    /// [`ViewPass::new`] for a renderer's scene: its field size, texel size, camera and height
    /// range, reading [`Renderer::heights_buffer`] and [`Renderer::shading_buffer`]. With live
    /// spheres in [`Renderer::live_scene`], also the sphere pipeline and buffers, lit by the
    /// live scene's environment and key lights ([`ViewPass::set_sphere_lighting`],
    /// [`ViewPass::set_spheres`]).
    ///
    /// [`Renderer::live_scene`]: super::Renderer::live_scene
    pub fn for_renderer(ctx: &Context, scene: &Scene, renderer: &Renderer, opts: &ViewOptions) -> Result<Self> {
        let inputs = ViewInputs {
            heights: renderer.heights_buffer(),
            shading: renderer.shading_buffer(),
            height_range: scene.field.range(),
        };
        let mut me =
            Self::new(ctx, scene.field.width(), scene.field.height(), &scene.camera, scene.texel_size, &inputs, opts)?;
        let live = renderer.live_scene();
        me.lighting = SphereLighting::new(&live.environment, &live.key_lights);
        if let Err(e) = me.set_spheres(ctx, &live.spheres) {
            me.destroy(ctx);
            return Err(e);
        }
        Ok(me)
    }

    /// The camera model for `camera` and `height_range`, its near/far planes fitted to the
    /// field's box and, with live spheres, their box too.
    fn fit_model(
        &self,
        camera: &Camera,
        height_range: (f32, f32),
        sphere_box: Option<(DVec3, DVec3)>,
    ) -> Result<CameraModel> {
        let (w, h, s) = (self.field.0, self.field.1, self.texel_size);
        let (lo, hi) = (f64::from(height_range.0), f64::from(height_range.1));
        let Some((smin, smax)) = sphere_box else {
            return CameraModel::new(camera, w, h, s, lo, hi);
        };
        let field = CameraModel::new(camera, w, h, s, lo, hi)?;
        let (x1, y1) = ((w.max(1) - 1) as f64 * s, (h.max(1) - 1) as f64 * s);
        let mut model =
            CameraModel::with_box(camera, DVec3::new(0.0, 0.0, lo).min(smin), DVec3::new(x1, y1, hi).max(smax), s)?;
        // A sphere far away pushes the far plane out and, through NEAR_RATIO, the near plane:
        // never past the field's own near plane, so that spheres cannot clip the field.
        model.near = model.near.min(field.near);
        Ok(model)
    }

    /// Sets the spheres drawn with the height field (docs/view.md §6): the live ones
    /// ([`sphere_is_live`]) of `spheres`, e.g. [`Renderer::live_scene`]`.spheres` after
    /// [`Renderer::set_spheres`]. Writes the host-visible sphere buffer now (no submit), so call
    /// it between frames: the GPU must not be executing a recorded frame of this pass (as after
    /// waiting for the frame's fence). The first live spheres create the sphere pipeline and its
    /// buffers, with room for `spheres.len()` spheres; more spheres later wait for the device to
    /// go idle and recreate them. Takes effect at the next [`ViewPass::record`]; the near/far
    /// planes are refitted to include the spheres.
    ///
    /// [`Renderer::live_scene`]: super::Renderer::live_scene
    /// [`Renderer::set_spheres`]: super::Renderer::set_spheres
    pub fn set_spheres(&mut self, ctx: &Context, spheres: &[SphereBlocker]) -> Result<()> {
        let live: Vec<&SphereBlocker> = spheres.iter().filter(|s| sphere_is_live(s)).collect();
        if let Some(k) = live.iter().position(|s| !s.albedo.iter().all(|a| a.is_finite())) {
            return Err(Error::param(format!("sphere {k} albedo"), format!("{:?}", live[k].albedo), "finite"));
        }
        let sphere_box = live.iter().fold(None, |acc: Option<(DVec3, DVec3)>, s| {
            let (a, b) = (s.center - DVec3::splat(s.radius), s.center + DVec3::splat(s.radius));
            Some(acc.map_or((a, b), |(lo, hi)| (lo.min(a), hi.max(b))))
        });
        let model = self.fit_model(&self.camera, self.height_range, sphere_box)?;
        if !live.is_empty() {
            self.ensure_spheres(ctx, spheres.len().max(live.len()), self.lighting.key_lights.len())?;
        }
        self.sphere_data = live.iter().map(|s| GpuSphere::new(s)).collect();
        self.write_buffers()?;
        self.sphere_box = sphere_box;
        self.model = model;
        self.update_push();
        Ok(())
    }

    /// Sets the lighting of the spheres (environment SH and key lights, docs/view.md §6;
    /// [`ViewPass::for_renderer`] takes the renderer's, [`ViewPass::new`] starts with none, i.e.
    /// black spheres). Writes the host-visible lighting buffer now if the sphere objects exist
    /// (the same rule as [`ViewPass::set_spheres`]: between frames).
    pub fn set_sphere_lighting(
        &mut self,
        ctx: &Context,
        environment: &Environment,
        key_lights: &[KeyLight],
    ) -> Result<()> {
        self.lighting = SphereLighting::new(environment, key_lights);
        if let Some(slots) = self.spheres.as_ref().map(|d| d.slots) {
            self.ensure_spheres(ctx, slots, self.lighting.key_lights.len())?;
        }
        self.write_buffers()
    }

    /// The lighting the spheres are drawn with.
    pub fn sphere_lighting(&self) -> &SphereLighting {
        &self.lighting
    }

    /// Live spheres the next frame draws (0 without sphere objects).
    pub fn sphere_count(&self) -> u32 {
        self.spheres.as_ref().map_or(0, |d| d.count)
    }

    /// Writes the host copies of the spheres and the lighting into the sphere objects (if any).
    fn write_buffers(&mut self) -> Result<()> {
        if let Some(d) = self.spheres.as_mut() {
            let bytes = self.lighting.bytes();
            d.light.mapped()?[..bytes.len()].copy_from_slice(&bytes);
            let bytes: &[u8] = bytemuck::cast_slice(&self.sphere_data);
            d.spheres.mapped()?[..bytes.len()].copy_from_slice(bytes);
            d.count = self.sphere_data.len() as u32;
        }
        Ok(())
    }

    /// Makes sure the sphere objects exist with room for `slots` spheres and `keys` key
    /// lights (recreating them after a device wait if they are smaller). New objects are
    /// written from the host copies ([`ViewPass::write_buffers`]).
    fn ensure_spheres(&mut self, ctx: &Context, slots: usize, keys: usize) -> Result<()> {
        if let Some(d) = &self.spheres {
            if d.slots >= slots && d.key_slots >= keys {
                return Ok(());
            }
        }
        let (slots, keys) = match &self.spheres {
            Some(d) => (slots.max(d.slots), keys.max(d.key_slots)),
            None => (slots, keys),
        };
        if let Some(old) = self.spheres.take() {
            // The old objects may still be read by a submitted frame.
            unsafe { ctx.device().device_wait_idle() }
                .map_err(|e| Error::Vulkan { call: "vkDeviceWaitIdle", result: e })?;
            old.destroy(ctx);
        }
        let extent = vk::Extent2D { width: self.camera.width, height: self.camera.height };
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let spheres = Buffer::new(ctx, SPHERE_BUFFER, sphere_buffer_bytes(slots), usage, MemoryLocation::CpuToGpu)?;
        let light =
            match Buffer::new(ctx, SPHERE_LIGHT_BUFFER, sphere_light_bytes(keys), usage, MemoryLocation::CpuToGpu) {
                Ok(b) => b,
                Err(e) => {
                    spheres.destroy(ctx);
                    return Err(e);
                }
            };
        let made = GraphicsPipeline::new(
            ctx,
            &GraphicsDesc {
                name: "view/spheres",
                vertex: &shaders::VIEW_SPHERE_VERT,
                fragment: &shaders::VIEW_SPHERE_FRAG,
                kinds: &[DescriptorKind::StorageBuffer; 3],
                push_size: std::mem::size_of::<ViewPush>() as u32,
                color_format: self.choice.color_format,
                depth_format: Some(self.choice.depth_format),
                depth_compare: vk::CompareOp::GREATER,
                samples: vk::SampleCountFlags::from_raw(self.choice.samples),
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                extent,
                max_sets: 1,
            },
        )
        .and_then(|mut p| {
            // Binding 2 is the heights buffer, which the pass knows by handle only: allocated
            // with a stand-in, then pointed at the heights.
            match p.allocate_set(ctx, &[Bind::Buffer(&spheres), Bind::Buffer(&light), Bind::Buffer(&spheres)]) {
                Ok(set) => {
                    let info = [self.heights];
                    let write = vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(&info);
                    unsafe { ctx.device().update_descriptor_sets(&[write], &[]) };
                    Ok((p, set))
                }
                Err(e) => {
                    p.destroy(ctx);
                    Err(e)
                }
            }
        });
        let (pipeline, set) = match made {
            Ok(v) => v,
            Err(e) => {
                spheres.destroy(ctx);
                light.destroy(ctx);
                return Err(e);
            }
        };
        self.spheres = Some(SphereDraw { pipeline, set, spheres, light, slots, key_slots: keys, count: 0 });
        self.write_buffers()
    }

    fn update_push(&mut self) {
        let vp = self.model.eye_relative_view_projection().as_mat4();
        let eye = self.model.eye.to_array();
        let hi = eye.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (eye[i] - hi[i] as f64) as f32);
        self.push = ViewPush {
            view_proj: vp.to_cols_array_2d(),
            width: self.field.0 as u32,
            height: self.field.1 as u32,
            texel_size: self.texel_size as f32,
            pad: 0,
            eye: [hi[0], hi[1], hi[2], 0.0],
            eye_lo: [lo[0], lo[1], lo[2], 0.0],
        };
    }

    /// Moves the camera (position, target, fov; the image size must stay the same). Takes
    /// effect at the next [`ViewPass::record`].
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        if (camera.width, camera.height) != (self.camera.width, self.camera.height) {
            return Err(Error::param(
                "camera size",
                format!("{}×{}", camera.width, camera.height),
                format!(
                    "{}×{} (the pass's size; create a new ViewPass to resize)",
                    self.camera.width, self.camera.height
                ),
            ));
        }
        self.model = self.fit_model(camera, self.height_range, self.sphere_box)?;
        self.camera = camera.clone();
        self.update_push();
        Ok(())
    }

    /// Sets the height range that bounds the near/far planes (call when animated heights leave
    /// the range given at creation). Takes effect at the next [`ViewPass::record`].
    pub fn set_height_range(&mut self, lo: f32, hi: f32) -> Result<()> {
        self.model = self.fit_model(&self.camera, (lo, hi), self.sphere_box)?;
        self.height_range = (lo, hi);
        self.update_push();
        Ok(())
    }

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

    /// MSAA samples per pixel used.
    pub fn samples(&self) -> u32 {
        self.choice.samples
    }

    /// Every sample count the device supports for the chosen colour + depth formats.
    pub fn supported_samples(&self) -> Vec<u32> {
        graphics::sample_counts(self.choice.supported)
    }

    /// Format of the output (and MSAA) colour image.
    pub fn color_format(&self) -> vk::Format {
        self.choice.color_format
    }

    pub fn depth_format(&self) -> vk::Format {
        self.choice.depth_format
    }

    /// The single-sample output image (TRANSFER_SRC_OPTIMAL after a recorded frame).
    pub fn image(&self) -> &Image {
        &self.output
    }

    /// Image size in pixels (the camera's).
    pub fn size(&self) -> (u32, u32) {
        (self.camera.width, self.camera.height)
    }

    /// The camera model (matrices, near/far) the next frame uses.
    pub fn camera_model(&self) -> &CameraModel {
        &self.model
    }

    /// GPU memory held by the pass's images, index buffer and (with spheres) sphere buffers, in
    /// bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.output.size_bytes()
            + self.depth.size_bytes()
            + self.msaa.as_ref().map(|m| m.size_bytes()).unwrap_or(0)
            + self.index.size
            + self.spheres.as_ref().map_or(0, |d| d.spheres.size + d.light.size)
    }

    pub fn destroy(mut self, ctx: &Context) {
        if let Some(d) = self.spheres.take() {
            d.destroy(ctx);
        }
        self.pipeline.destroy(ctx);
        self.index.destroy(ctx);
        if let Some(m) = self.msaa.take() {
            m.destroy(ctx);
        }
        self.depth.destroy(ctx);
        self.output.destroy(ctx);
    }
}
