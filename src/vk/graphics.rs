//! Graphics pipelines for dynamic rendering (Vulkan 1.3 `vkCmdBeginRendering`), in the style of
//! [`super::ComputePipeline`]: one descriptor set layout from a list of kinds, push constants
//! visible to the vertex and fragment stages, a descriptor pool for a fixed number of sets. Also
//! the render-target helpers the view pass needs: choosing the MSAA count and formats, and
//! beginning/ending a dynamic rendering scope.

use ash::vk;

use super::pipeline::{allocate_set, create_layouts, create_pool, destroy_objects, Bind, DescriptorKind};
use super::{Buffer, Context, Image};
use crate::error::{Error, Result, VkCall};
use crate::shaders::Spirv;

/// Stages that see the descriptor set and the push constants of a [`GraphicsPipeline`].
pub const GRAPHICS_STAGES: vk::ShaderStageFlags =
    vk::ShaderStageFlags::from_raw(vk::ShaderStageFlags::VERTEX.as_raw() | vk::ShaderStageFlags::FRAGMENT.as_raw());

/// What a [`GraphicsPipeline`] draws into and how.
#[derive(Clone, Copy, Debug)]
pub struct GraphicsDesc<'a> {
    /// Debug name of the pipeline (also used in error messages).
    pub name: &'a str,
    pub vertex: &'a Spirv,
    pub fragment: &'a Spirv,
    /// Bindings of the single descriptor set (binding = index), visible to both stages.
    pub kinds: &'a [DescriptorKind],
    /// Push-constant bytes (vertex + fragment), 0 for none.
    pub push_size: u32,
    /// The single colour attachment's format.
    pub color_format: vk::Format,
    /// Depth attachment format (`None`: no depth test).
    pub depth_format: Option<vk::Format>,
    /// Depth comparison (with a depth format); depth writes are on.
    pub depth_compare: vk::CompareOp,
    pub samples: vk::SampleCountFlags,
    pub topology: vk::PrimitiveTopology,
    /// Viewport and scissor size (static state).
    pub extent: vk::Extent2D,
    /// Descriptor sets that can be allocated with [`GraphicsPipeline::allocate_set`].
    pub max_sets: u32,
}

/// A graphics pipeline (no vertex input: vertices come from `gl_VertexIndex` and storage
/// buffers), no culling, no blending, static viewport, and everything it owns.
pub struct GraphicsPipeline {
    pub name: String,
    pub pipeline: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    kinds: Vec<DescriptorKind>,
    push_size: u32,
}

/// The `vkCreateGraphicsPipelines` call of [`GraphicsPipeline::new`]: `desc`'s fixed-function
/// state (no vertex input, no culling, no blending, static viewport) with the `(vertex,
/// fragment)` shader modules and `layout`, for dynamic rendering with `desc`'s formats.
fn create_pipeline(
    ctx: &Context,
    desc: &GraphicsDesc,
    layout: vk::PipelineLayout,
    (vertex, fragment): (vk::ShaderModule, vk::ShaderModule),
) -> Result<vk::Pipeline> {
    let stages = [
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vertex).name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(fragment)
            .name(c"main"),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
    let viewports = [vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: desc.extent.width as f32,
        height: desc.extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    }];
    let scissors = [vk::Rect2D { offset: vk::Offset2D::default(), extent: desc.extent }];
    let viewport = vk::PipelineViewportStateCreateInfo::default().viewports(&viewports).scissors(&scissors);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(desc.samples);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(desc.depth_format.is_some())
        .depth_write_enable(desc.depth_format.is_some())
        .depth_compare_op(desc.depth_compare)
        .max_depth_bounds(1.0);
    let attachments = [vk::PipelineColorBlendAttachmentState::default().color_write_mask(
        vk::ColorComponentFlags::R
            | vk::ColorComponentFlags::G
            | vk::ColorComponentFlags::B
            | vk::ColorComponentFlags::A,
    )];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
    let color_formats = [desc.color_format];
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(&color_formats)
        .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
    let ci = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .layout(layout)
        .push_next(&mut rendering)];
    ctx.count_pipeline();
    let made = unsafe { ctx.device().create_graphics_pipelines(ctx.pipeline_cache(), &ci, None) };
    Ok(made.map_err(|(_, e)| Error::Vulkan { call: "vkCreateGraphicsPipelines", result: e })?[0])
}

impl GraphicsPipeline {
    /// Builds the pipeline for dynamic rendering with the formats of `desc`.
    pub fn new(ctx: &Context, desc: &GraphicsDesc) -> Result<Self> {
        let d = ctx.device();
        let mut me = Self {
            name: desc.name.to_string(),
            pipeline: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            kinds: desc.kinds.to_vec(),
            push_size: desc.push_size,
        };
        let mut modules = Vec::new();
        let r = (|| -> Result<()> {
            create_layouts(ctx, desc.kinds, GRAPHICS_STAGES, desc.push_size, &mut me.set_layout, &mut me.layout)?;
            for s in [desc.vertex, desc.fragment] {
                let m = unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(s.words), None) }
                    .vk("vkCreateShaderModule")?;
                modules.push(m);
            }
            me.pipeline = create_pipeline(ctx, desc, me.layout, (modules[0], modules[1]))?;
            ctx.set_name(me.pipeline, &me.name);
            me.pool = create_pool(ctx, desc.kinds, desc.max_sets)?;
            Ok(())
        })();
        for m in modules {
            unsafe { d.destroy_shader_module(m, None) };
        }
        match r {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Allocates and writes one descriptor set; `binds[i]` goes to binding `i`.
    pub fn allocate_set(&self, ctx: &Context, binds: &[Bind]) -> Result<vk::DescriptorSet> {
        allocate_set(ctx, &self.name, self.pool, self.set_layout, &self.kinds, binds)
    }

    /// Inside a rendering scope: binds the pipeline, `set` and `index` (u32 indices), pushes
    /// `push` (must be `push_size` bytes) and draws `index_count` indices `instance_count` times.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_indexed(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        index: &Buffer,
        index_count: u32,
        instance_count: u32,
    ) {
        debug_assert_eq!(push.len() as u32, self.push_size, "{}: push-constant size", self.name);
        let d = ctx.device();
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[set], &[]);
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, GRAPHICS_STAGES, 0, push);
            }
            d.cmd_bind_index_buffer(cmd, index.raw, 0, vk::IndexType::UINT32);
            d.cmd_draw_indexed(cmd, index_count, instance_count, 0, 0, 0);
        }
    }

    /// Destroys the pipeline, its layouts and its descriptor pool (and so its sets).
    pub fn destroy(&mut self, ctx: &Context) {
        destroy_objects(ctx, &mut self.pool, &mut self.pipeline, &mut self.layout, &mut self.set_layout);
    }
}

/// Attachments of one dynamic rendering scope.
pub struct RenderTargets<'a> {
    /// Colour attachment, cleared to `clear_color`, in COLOR_ATTACHMENT_OPTIMAL.
    pub color: &'a Image,
    /// Single-sample image that `color` (multisampled) is averaged into at the end of the
    /// scope, in COLOR_ATTACHMENT_OPTIMAL. `None`: `color` is stored instead.
    pub resolve: Option<&'a Image>,
    /// Depth attachment, cleared to `clear_depth`, in DEPTH_STENCIL_ATTACHMENT_OPTIMAL; not
    /// stored.
    pub depth: Option<&'a Image>,
    pub clear_color: [f32; 4],
    pub clear_depth: f32,
}

/// Begins a dynamic rendering scope over the whole of `t.color`.
pub fn begin_rendering(ctx: &Context, cmd: vk::CommandBuffer, t: &RenderTargets) {
    let mut color = vk::RenderingAttachmentInfo::default()
        .image_view(t.color.view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: t.clear_color } });
    if let Some(r) = t.resolve {
        color = color
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .resolve_mode(vk::ResolveModeFlags::AVERAGE)
            .resolve_image_view(r.view)
            .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
    }
    let colors = [color];
    let depth = t.depth.map(|img| {
        vk::RenderingAttachmentInfo::default()
            .image_view(img.view)
            .image_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: t.clear_depth, stencil: 0 },
            })
    });
    let mut info = vk::RenderingInfo::default()
        .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: t.color.extent })
        .layer_count(1)
        .color_attachments(&colors);
    if let Some(d) = depth.as_ref() {
        info = info.depth_attachment(d);
    }
    unsafe { ctx.device().cmd_begin_rendering(cmd, &info) };
}

/// Ends the scope begun by [`begin_rendering`] (this is where an MSAA resolve happens).
pub fn end_rendering(ctx: &Context, cmd: vk::CommandBuffer) {
    unsafe { ctx.device().cmd_end_rendering(cmd) };
}

/// Formats and sample count chosen by [`choose_targets`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetChoice {
    pub color_format: vk::Format,
    pub depth_format: vk::Format,
    /// Samples per pixel (1, 2, 4, 8, …).
    pub samples: u32,
    /// Every count the device supports for this colour + depth pair (bit mask).
    pub supported: vk::SampleCountFlags,
}

/// Depth formats tried in order (pure depth, no stencil: D16_UNORM and one of the other two are
/// mandatory for depth attachments).
pub const DEPTH_FORMATS: [vk::Format; 3] =
    [vk::Format::D32_SFLOAT, vk::Format::X8_D24_UNORM_PACK32, vk::Format::D16_UNORM];

/// Sample counts an optimal-tiling 2D image of `format` with `usage` supports, or empty if the
/// format lacks `feature`.
fn format_counts(
    ctx: &Context,
    format: vk::Format,
    feature: vk::FormatFeatureFlags,
    usage: vk::ImageUsageFlags,
) -> vk::SampleCountFlags {
    let inst = ctx.instance();
    let pd = ctx.physical_device();
    let props = unsafe { inst.get_physical_device_format_properties(pd, format) };
    if !props.optimal_tiling_features.contains(feature) {
        return vk::SampleCountFlags::empty();
    }
    match unsafe {
        inst.get_physical_device_image_format_properties(
            pd,
            format,
            vk::ImageType::TYPE_2D,
            vk::ImageTiling::OPTIMAL,
            usage,
            vk::ImageCreateFlags::empty(),
        )
    } {
        Ok(p) => p.sample_counts,
        Err(_) => vk::SampleCountFlags::empty(),
    }
}

/// The sample counts in `flags`, ascending.
pub fn sample_counts(flags: vk::SampleCountFlags) -> Vec<u32> {
    (0..7).map(|b| 1u32 << b).filter(|c| flags.as_raw() & c != 0).collect()
}

/// Chooses an HDR colour format (the first of `colors` that reaches the highest count, so
/// R32G32B32A32_SFLOAT is kept unless a fallback multisamples higher), a depth format from
/// [`DEPTH_FORMATS`] and the sample count: the highest count ≤ `cap` in
/// `framebufferColorSampleCounts & framebufferDepthSampleCounts` and the formats' own
/// `sampleCounts`, or exactly `forced` (an error if unsupported). The colour formats must also
/// support being a transfer source (for read-back) and a single-sample resolve target.
pub fn choose_targets(ctx: &Context, colors: &[vk::Format], cap: u32, forced: Option<u32>) -> Result<TargetChoice> {
    let limits = unsafe { ctx.instance().get_physical_device_properties(ctx.physical_device()) }.limits;
    let framebuffer = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
    let depth = DEPTH_FORMATS
        .iter()
        .map(|&f| {
            (
                f,
                format_counts(
                    ctx,
                    f,
                    vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT,
                    vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                ),
            )
        })
        .find(|(_, c)| !c.is_empty())
        .ok_or_else(|| Error::Unsupported("no depth attachment format (D32_SFLOAT, X8_D24, D16_UNORM)".into()))?;
    let mut best: Option<TargetChoice> = None;
    for &cf in colors {
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let feature = vk::FormatFeatureFlags::COLOR_ATTACHMENT | vk::FormatFeatureFlags::TRANSFER_SRC;
        let counts = format_counts(ctx, cf, feature, usage) & depth.1 & framebuffer;
        if !counts.contains(vk::SampleCountFlags::TYPE_1) {
            continue;
        }
        let pick = match forced {
            Some(n) if n.is_power_of_two() && counts.as_raw() & n != 0 => Some(n),
            Some(_) => None,
            None => sample_counts(counts).into_iter().filter(|&c| c <= cap.max(1)).max(),
        };
        if let Some(samples) = pick {
            let c = TargetChoice { color_format: cf, depth_format: depth.0, samples, supported: counts };
            if best.map_or(true, |b| samples > b.samples) {
                best = Some(c);
            }
        }
    }
    best.ok_or_else(|| match forced {
        Some(n) => Error::param(
            "view sample count",
            n,
            format!(
                "a count this device supports for {colors:?} + {:?}: {:?} (framebuffer limits {:?})",
                depth.0,
                sample_counts(framebuffer),
                framebuffer
            ),
        ),
        None => Error::Unsupported(format!("none of the colour formats {colors:?} is renderable and copyable")),
    })
}
