//! Stage `view.raster` (docs/view.md): the view image. Rasterises the height-field mesh
//! (CONVENTIONS.md: one vertex per sample at `(i·s, j·s, H[j][i])`, two triangles per quad,
//! split along the `(i, j)–(i+1, j+1)` diagonal) from the scene camera, coloured by the total
//! layer of the shading texture (one colour per vertex, interpolated perspective-correctly), with
//! MSAA resolved into a single-sample HDR image.
//!
//! Inputs are bound when the pass is created (they are stable per [`Renderer`]): the heights
//! buffer (`f32`, row-major `W × H` from offset 0; [`Renderer::heights_buffer`]) and the shading
//! buffer (`vec4` per texel, plane 0 = total; [`Renderer::shading_buffer`]). Vertices are made
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
//!    depth), one indexed instanced draw, and at the end of rendering the MSAA resolve
//!    (`AVERAGE`) into the output image. With one sample the output is rendered directly.
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
use glam::{DMat4, DVec3, DVec4};
use gpu_allocator::MemoryLocation;

use super::shared::ViewPush;
use super::Renderer;
use crate::error::{Error, Result};
use crate::scene::model::{Camera, Scene};
use crate::shaders;
use crate::vk::barrier::{self, Transition};
use crate::vk::graphics::{self, GraphicsDesc, RenderTargets, TargetChoice};
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

/// The camera model of docs/view.md, in f64: an orthonormal basis, a reversed-depth Vulkan
/// perspective and the near/far planes fitted to the field's bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraModel {
    pub eye: DVec3,
    /// Image right, image up and viewing direction, orthonormal: `right = normalize(forward ×
    /// ẑ)` (ŷ instead of ẑ when looking straight up or down), `up = right × forward`.
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
    /// `tan(fov_y / 2)`.
    pub tan_half_fov: f64,
    /// Width / height in pixels.
    pub aspect: f64,
    pub near: f64,
    pub far: f64,
    pub width: u32,
    pub height: u32,
}

impl CameraModel {
    /// Builds the model for a `field_w × field_h` field of texel size `s` whose heights lie in
    /// `lo..=hi`. Errors on a non-finite or degenerate camera.
    pub fn new(camera: &Camera, field_w: usize, field_h: usize, s: f64, lo: f64, hi: f64) -> Result<Self> {
        let finite3 = |v: DVec3| v.is_finite();
        if !finite3(camera.position) || !finite3(camera.target) {
            return Err(Error::param(
                "camera.position/target",
                format!("{:?} / {:?}", camera.position.to_array(), camera.target.to_array()),
                "finite points",
            ));
        }
        let forward = (camera.target - camera.position).try_normalize().ok_or_else(|| {
            Error::param("camera.target", format!("{:?}", camera.target.to_array()), "≠ camera.position")
        })?;
        if !(camera.fov_deg > 0.0 && camera.fov_deg < 180.0) {
            return Err(Error::param("camera.fov_deg", camera.fov_deg, "a number in (0, 180) (degrees)"));
        }
        if camera.width == 0 || camera.height == 0 {
            return Err(Error::param("camera size", format!("{}×{}", camera.width, camera.height), "at least 1×1"));
        }
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::param("texel_size", s, "a finite number > 0"));
        }
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Error::param("height range", format!("{lo}..{hi}"), "finite lo ≤ hi"));
        }
        let mut right = forward.cross(DVec3::Z);
        if right.length() < 1e-9 {
            right = forward.cross(DVec3::Y);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let (x1, y1) = ((field_w.max(1) - 1) as f64 * s, (field_h.max(1) - 1) as f64 * s);
        let mut dmin = f64::INFINITY;
        let mut dmax = f64::NEG_INFINITY;
        for c in 0..8 {
            let p = DVec3::new(
                if c & 1 == 0 { 0.0 } else { x1 },
                if c & 2 == 0 { 0.0 } else { y1 },
                if c & 4 == 0 { lo } else { hi },
            );
            let z = (p - camera.position).dot(forward);
            dmin = dmin.min(z);
            dmax = dmax.max(z);
        }
        let extent = (x1.max(y1) + (hi - lo)).max(s);
        // Margins so that geometry exactly on the box is not clipped by rounding.
        let far = if dmax > 0.0 { dmax * (1.0 + 1e-3) + 1e-6 * extent } else { extent };
        let near = (dmin * (1.0 - 1e-3)).max(far * NEAR_RATIO);
        Ok(Self {
            eye: camera.position,
            right,
            up,
            forward,
            tan_half_fov: (camera.fov_deg.to_radians() * 0.5).tan(),
            aspect: f64::from(camera.width) / f64::from(camera.height),
            near,
            far,
            width: camera.width,
            height: camera.height,
        })
    }

    /// World → view: x right, y up, looking down −z.
    pub fn view(&self) -> DMat4 {
        let (r, u, f) = (self.right, self.up, self.forward);
        DMat4::from_cols(
            DVec4::new(r.x, u.x, -f.x, 0.0),
            DVec4::new(r.y, u.y, -f.y, 0.0),
            DVec4::new(r.z, u.z, -f.z, 0.0),
            DVec4::new(-r.dot(self.eye), -u.dot(self.eye), f.dot(self.eye), 1.0),
        )
    }

    /// View → clip, Vulkan conventions (NDC y down, depth in 0..1) with reversed depth: the
    /// near plane maps to 1, the far plane to 0.
    pub fn projection(&self) -> DMat4 {
        let fy = 1.0 / self.tan_half_fov;
        let (n, f) = (self.near, self.far);
        let a = n / (f - n);
        DMat4::from_cols(
            DVec4::new(fy / self.aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -fy, 0.0, 0.0),
            DVec4::new(0.0, 0.0, a, -1.0),
            DVec4::new(0.0, 0.0, a * f, 0.0),
        )
    }

    /// World → clip.
    pub fn view_projection(&self) -> DMat4 {
        self.projection() * self.view()
    }

    /// Eye-relative world → clip: maps `P − eye` to clip space (`view_projection()` with the eye
    /// at the origin). The GPU uses this form so that its f32 arithmetic never holds absolute
    /// world coordinates times the matrix (docs/view.md).
    pub fn eye_relative_view_projection(&self) -> DMat4 {
        let mut rotation = self.view();
        rotation.w_axis = DVec4::W;
        self.projection() * rotation
    }

    /// The world-space ray through pixel position `(px, py)` (pixel centres at `+0.5`; row 0 is
    /// the top of the image): origin and unit direction.
    pub fn ray(&self, px: f64, py: f64) -> (DVec3, DVec3) {
        let x = (2.0 * px / f64::from(self.width) - 1.0) * self.tan_half_fov * self.aspect;
        let y = (1.0 - 2.0 * py / f64::from(self.height)) * self.tan_half_fov;
        (self.eye, (self.forward + x * self.right + y * self.up).normalize())
    }
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
    camera: Camera,
    height_range: (f32, f32),
    model: CameraModel,
    push: ViewPush,
    recorded: Cell<bool>,
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
        let texels = check_field_size(width, height)?;
        for (name, buf, need) in [("heights", inputs.heights, texels * 4), ("shading", inputs.shading, texels * 16)] {
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
        let (lo, hi) = inputs.height_range;
        let model = CameraModel::new(camera, width, height, texel_size, f64::from(lo), f64::from(hi))?;
        let choice = graphics::choose_targets(ctx, &COLOR_FORMATS, MAX_SAMPLES, opts.samples)?;
        let extent = vk::Extent2D { width: camera.width, height: camera.height };
        let samples = vk::SampleCountFlags::from_raw(choice.samples);

        let mut images: Vec<Image> = Vec::new();
        let mut index = None;
        let mut pipeline = None;
        let made = (|| -> Result<vk::DescriptorSet> {
            for a in attachments(choice.color_format, choice.depth_format, choice.samples) {
                let count = vk::SampleCountFlags::from_raw(a.samples);
                images.push(Image::new(ctx, a.name, extent, a.format, a.usage, count)?);
            }
            // One row of quads between vertex rows 0 and 1 (v = row·W + i); instance j adds j·W
            // in the shader. Diagonal (i, j)–(i+1, j+1).
            let w = width as u32;
            let indices: Vec<u32> = (0..w - 1).flat_map(|i| [i, i + 1, w + i + 1, i, w + i + 1, w + i]).collect();
            debug_assert_eq!((indices.len() * 4) as u64, index_bytes(width));
            let ib = index.insert(Buffer::new(
                ctx,
                INDEX_BUFFER,
                index_bytes(width),
                vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?);
            memory::upload(ctx, ib, 0, bytemuck::cast_slice(&indices))?;
            let p = pipeline.insert(GraphicsPipeline::new(
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
                    samples,
                    topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                    extent,
                    max_sets: 1,
                },
            )?);
            p.allocate_set(ctx, &[Bind::Buffer(inputs.heights), Bind::Buffer(inputs.shading)])
        })();
        let set = match made {
            Ok(s) => s,
            Err(e) => {
                images.into_iter().for_each(|i| i.destroy(ctx));
                if let Some(b) = index {
                    b.destroy(ctx);
                }
                if let Some(mut p) = pipeline {
                    p.destroy(ctx);
                }
                return Err(e);
            }
        };
        let msaa = if choice.samples > 1 { images.pop() } else { None };
        let depth = images.pop().expect("depth image");
        let output = images.pop().expect("output image");
        let mut me = Self {
            pipeline: pipeline.expect("pipeline"),
            set,
            index: index.expect("index buffer"),
            index_count: 6 * (width as u32 - 1),
            instances: height as u32 - 1,
            msaa,
            depth,
            output,
            choice,
            field: (width, height),
            texel_size,
            camera: camera.clone(),
            height_range: inputs.height_range,
            model,
            push: ViewPush::default(),
            recorded: Cell::new(false),
        };
        me.update_push();
        Ok(me)
    }

    /// [`ViewPass::new`] for a renderer's scene: its field size, texel size, camera and height
    /// range, reading [`Renderer::heights_buffer`] and [`Renderer::shading_buffer`].
    pub fn for_renderer(ctx: &Context, scene: &Scene, renderer: &Renderer, opts: &ViewOptions) -> Result<Self> {
        let inputs = ViewInputs {
            heights: renderer.heights_buffer(),
            shading: renderer.shading_buffer(),
            height_range: scene.field.range(),
        };
        Self::new(ctx, scene.field.width(), scene.field.height(), &scene.camera, scene.texel_size, &inputs, opts)
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
        let (lo, hi) = self.height_range;
        self.model =
            CameraModel::new(camera, self.field.0, self.field.1, self.texel_size, f64::from(lo), f64::from(hi))?;
        self.camera = camera.clone();
        self.update_push();
        Ok(())
    }

    /// Sets the height range that bounds the near/far planes (call when animated heights leave
    /// the range given at creation). Takes effect at the next [`ViewPass::record`].
    pub fn set_height_range(&mut self, lo: f32, hi: f32) -> Result<()> {
        self.model =
            CameraModel::new(&self.camera, self.field.0, self.field.1, self.texel_size, f64::from(lo), f64::from(hi))?;
        self.height_range = (lo, hi);
        self.update_push();
        Ok(())
    }

    /// Records the stage `view.raster` (see the module docs for the barriers and layouts).
    pub fn record(&self, rec: &mut Recorder) {
        rec.scope(STAGE_RASTER, |ctx, cmd| {
            barrier::compute_to_graphics(ctx, cmd);
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
                        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
                            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
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
            barrier::image_transitions(ctx, cmd, &list);
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
            graphics::end_rendering(ctx, cmd);
            barrier::image_transitions(
                ctx,
                cmd,
                &[Transition {
                    image: &self.output,
                    old: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    new: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    src: attach,
                    dst: (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
                }],
            );
        });
        self.recorded.set(true);
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

    /// GPU memory held by the pass's images and index buffer, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.output.size_bytes()
            + self.depth.size_bytes()
            + self.msaa.as_ref().map(|m| m.size_bytes()).unwrap_or(0)
            + self.index.size
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.index.destroy(ctx);
        if let Some(m) = self.msaa.take() {
            m.destroy(ctx);
        }
        self.depth.destroy(ctx);
        self.output.destroy(ctx);
    }
}
