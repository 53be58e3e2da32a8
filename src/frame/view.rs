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
mod record;
mod spheres;
mod update;

pub use camera::CameraModel;
pub(crate) use spheres::{sphere_buffer_bytes, sphere_light_bytes, SPHERE_BUFFER, SPHERE_LIGHT_BUFFER};
pub use spheres::{sphere_is_live, SphereLighting, SPHERE_SLICES, SPHERE_STACKS, SPHERE_VERTICES};
use spheres::{GpuSphere, SphereDraw};

use super::shade::ShadingFormat;
use super::shared::ViewPush;
use super::Renderer;
use crate::error::{Error, Result};
use crate::scene::model::{Camera, Scene};
use crate::shaders;
use crate::vk::graphics::{self, GraphicsDesc, TargetChoice};
use crate::vk::pipeline::Bind;
use crate::vk::{memory, Buffer, Context, DescriptorKind, GraphicsPipeline, Image};

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
    /// Shading texture: texels `[0, W·H)` (plane 0, the total) in `shading_format` are the
    /// colour (`Renderer::shading_buffer`'s layout).
    pub shading: &'a Buffer,
    /// The texel format of `shading` (`Renderer::shading_format`).
    pub shading_format: ShadingFormat,
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
    for (name, buf, need) in [
        ("heights", inputs.heights, texels * 4),
        ("shading", inputs.shading, texels * inputs.shading_format.texel_bytes()),
    ] {
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
    /// The texel format of the shading buffer read.
    shading_format: ShadingFormat,
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
            shading_format: inputs.shading_format,
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
            shading_format: renderer.shading_format(),
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
