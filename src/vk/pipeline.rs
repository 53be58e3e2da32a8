//! Compute pipelines from embedded SPIR-V, with one descriptor set layout, a descriptor pool
//! sized for a fixed number of sets, push constants and specialization constants.

use ash::vk;

use super::{Buffer, Context, Image};
use crate::error::{Error, Result, VkCall};
use crate::shaders::Spirv;

/// The kind of each binding of the pipeline's single descriptor set (binding = index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DescriptorKind {
    StorageBuffer,
    StorageImage,
    /// A uniform texel buffer (`samplerBuffer`/`usamplerBuffer`), bound with [`Bind::Texel`].
    TexelBuffer,
}

impl DescriptorKind {
    pub(crate) fn raw(self) -> vk::DescriptorType {
        match self {
            DescriptorKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            DescriptorKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
            DescriptorKind::TexelBuffer => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        }
    }
}

/// A resource bound to one binding.
pub enum Bind<'a> {
    Buffer(&'a Buffer),
    /// A storage image in `GENERAL` layout.
    Image(&'a Image),
    /// A buffer's texel view ([`Buffer::with_texel_view`]).
    Texel(&'a Buffer),
}

/// A compute pipeline and everything it owns.
pub struct ComputePipeline {
    pub name: String,
    pub pipeline: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    kinds: Vec<DescriptorKind>,
    push_size: u32,
}

impl ComputePipeline {
    /// Builds the pipeline. `max_sets` descriptor sets can be allocated from it with
    /// [`ComputePipeline::allocate_set`]. `spec` are `(constant_id, value)` pairs.
    pub fn new(
        ctx: &Context,
        shader: &Spirv,
        kinds: &[DescriptorKind],
        push_size: u32,
        spec: &[(u32, u32)],
        max_sets: u32,
    ) -> Result<Self> {
        let d = ctx.device();
        let mut me = Self {
            name: shader.name.to_string(),
            pipeline: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            kinds: kinds.to_vec(),
            push_size,
        };
        let r = (|| -> Result<()> {
            create_layouts(ctx, kinds, vk::ShaderStageFlags::COMPUTE, push_size, &mut me.set_layout, &mut me.layout)?;
            let module =
                unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(shader.words), None) }
                    .vk("vkCreateShaderModule")?;
            let entries: Vec<_> = spec
                .iter()
                .enumerate()
                .map(|(i, (id, _))| vk::SpecializationMapEntry { constant_id: *id, offset: (i * 4) as u32, size: 4 })
                .collect();
            let data: Vec<u8> = spec.iter().flat_map(|(_, v)| v.to_le_bytes()).collect();
            let si = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
            let mut stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            if !spec.is_empty() {
                stage = stage.specialization_info(&si);
            }
            let ci = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(me.layout)];
            ctx.count_pipeline();
            let made = unsafe { d.create_compute_pipelines(ctx.pipeline_cache(), &ci, None) };
            unsafe { d.destroy_shader_module(module, None) };
            me.pipeline = made.map_err(|(_, e)| Error::Vulkan { call: "vkCreateComputePipelines", result: e })?[0];
            ctx.set_name(me.pipeline, &me.name);
            me.pool = create_pool(ctx, kinds, max_sets)?;
            Ok(())
        })();
        match r {
            Ok(()) => Ok(me),
            Err(e) => {
                me.destroy(ctx);
                Err(e)
            }
        }
    }

    /// A pipeline with one descriptor set holding `binds` (all storage buffers), destroyed
    /// again if the set cannot be made.
    pub fn with_storage_set(
        ctx: &Context,
        shader: &Spirv,
        push_size: u32,
        binds: &[Bind],
    ) -> Result<(Self, vk::DescriptorSet)> {
        Self::with_storage_set_spec(ctx, shader, push_size, &[], binds)
    }

    /// [`Self::with_storage_set`] with specialization constants `spec` (id, value).
    pub fn with_storage_set_spec(
        ctx: &Context,
        shader: &Spirv,
        push_size: u32,
        spec: &[(u32, u32)],
        binds: &[Bind],
    ) -> Result<(Self, vk::DescriptorSet)> {
        let kinds = vec![DescriptorKind::StorageBuffer; binds.len()];
        let mut p = Self::new(ctx, shader, &kinds, push_size, spec, 1)?;
        match p.allocate_set(ctx, binds) {
            Ok(set) => Ok((p, set)),
            Err(e) => {
                p.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Allocates and writes one descriptor set; `binds[i]` goes to binding `i`.
    pub fn allocate_set(&self, ctx: &Context, binds: &[Bind]) -> Result<vk::DescriptorSet> {
        allocate_set(ctx, &self.name, self.pool, self.set_layout, &self.kinds, binds)
    }

    /// Binds the pipeline and `set`, pushes `push` (must be `push_size` bytes) and dispatches
    /// `groups` workgroups.
    pub fn dispatch(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        groups: [u32; 3],
    ) {
        debug_assert_eq!(push.len() as u32, self.push_size, "{}: push-constant size", self.name);
        let d = ctx.device();
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[set], &[]);
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            d.cmd_dispatch(cmd, groups[0].max(1), groups[1].max(1), groups[2].max(1));
        }
    }

    /// Destroys the pipeline, its layouts and its descriptor pool (and so its sets).
    pub fn destroy(&mut self, ctx: &Context) {
        destroy_objects(ctx, &mut self.pool, &mut self.pipeline, &mut self.layout, &mut self.set_layout);
    }
}

/// Creates the descriptor-set layout (binding `i` of type `kinds[i]`, visible to `stages`) and
/// the pipeline layout with a `push_size`-byte push-constant range (shared by compute and
/// graphics pipelines). Handles are written as they are created, so a failure half way leaves
/// them for [`destroy_objects`].
pub(crate) fn create_layouts(
    ctx: &Context,
    kinds: &[DescriptorKind],
    stages: vk::ShaderStageFlags,
    push_size: u32,
    set_layout: &mut vk::DescriptorSetLayout,
    layout: &mut vk::PipelineLayout,
) -> Result<()> {
    let d = ctx.device();
    let bindings: Vec<_> = kinds
        .iter()
        .enumerate()
        .map(|(i, k)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(k.raw())
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    *set_layout = unsafe {
        d.create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings), None)
    }
    .vk("vkCreateDescriptorSetLayout")?;
    let ranges = [vk::PushConstantRange::default().stage_flags(stages).offset(0).size(push_size.max(4))];
    let set_layouts = [*set_layout];
    let mut pli = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    if push_size > 0 {
        pli = pli.push_constant_ranges(&ranges);
    }
    *layout = unsafe { d.create_pipeline_layout(&pli, None) }.vk("vkCreatePipelineLayout")?;
    Ok(())
}

/// A descriptor pool for `max_sets` sets of `kinds` (null when `kinds` is empty).
pub(crate) fn create_pool(ctx: &Context, kinds: &[DescriptorKind], max_sets: u32) -> Result<vk::DescriptorPool> {
    let mut sizes = Vec::new();
    for k in [DescriptorKind::StorageBuffer, DescriptorKind::StorageImage, DescriptorKind::TexelBuffer] {
        let n = kinds.iter().filter(|x| **x == k).count() as u32;
        if n > 0 {
            sizes.push(vk::DescriptorPoolSize { ty: k.raw(), descriptor_count: n * max_sets.max(1) });
        }
    }
    if sizes.is_empty() {
        return Ok(vk::DescriptorPool::null());
    }
    let pi = vk::DescriptorPoolCreateInfo::default().max_sets(max_sets.max(1)).pool_sizes(&sizes);
    unsafe { ctx.device().create_descriptor_pool(&pi, None) }.vk("vkCreateDescriptorPool")
}

/// Destroys a pipeline's descriptor pool (and so its sets), pipeline and layouts, skipping null
/// handles, and nulls them (shared by compute and graphics pipelines).
pub(crate) fn destroy_objects(
    ctx: &Context,
    pool: &mut vk::DescriptorPool,
    pipeline: &mut vk::Pipeline,
    layout: &mut vk::PipelineLayout,
    set_layout: &mut vk::DescriptorSetLayout,
) {
    let d = ctx.device();
    unsafe {
        if *pool != vk::DescriptorPool::null() {
            d.destroy_descriptor_pool(*pool, None);
        }
        if *pipeline != vk::Pipeline::null() {
            d.destroy_pipeline(*pipeline, None);
        }
        if *layout != vk::PipelineLayout::null() {
            d.destroy_pipeline_layout(*layout, None);
        }
        if *set_layout != vk::DescriptorSetLayout::null() {
            d.destroy_descriptor_set_layout(*set_layout, None);
        }
    }
    *pool = vk::DescriptorPool::null();
    *pipeline = vk::Pipeline::null();
    *layout = vk::PipelineLayout::null();
    *set_layout = vk::DescriptorSetLayout::null();
}

/// Workgroup count covering `n` items with groups of `size`.
pub fn groups(n: u32, size: u32) -> u32 {
    n.div_ceil(size)
}

/// Allocates one set of `set_layout` from `pool` and writes `binds[i]` to binding `i`
/// (shared by compute and graphics pipelines).
pub(crate) fn allocate_set(
    ctx: &Context,
    name: &str,
    pool: vk::DescriptorPool,
    set_layout: vk::DescriptorSetLayout,
    kinds: &[DescriptorKind],
    binds: &[Bind],
) -> Result<vk::DescriptorSet> {
    if binds.len() != kinds.len() {
        return Err(Error::param(
            format!("{}: descriptor count", name),
            binds.len(),
            format!("{} bindings", kinds.len()),
        ));
    }
    let d = ctx.device();
    let layouts = [set_layout];
    let ai = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
    let set = unsafe { d.allocate_descriptor_sets(&ai) }.vk("vkAllocateDescriptorSets")?[0];
    let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = binds
        .iter()
        .map(|b| match b {
            Bind::Buffer(buf) => [buf.whole()],
            Bind::Image(_) | Bind::Texel(_) => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = binds
        .iter()
        .map(|b| match b {
            Bind::Image(img) => {
                [vk::DescriptorImageInfo::default().image_view(img.view).image_layout(vk::ImageLayout::GENERAL)]
            }
            Bind::Buffer(_) | Bind::Texel(_) => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let texel_views: Vec<[vk::BufferView; 1]> = binds
        .iter()
        .map(|b| match b {
            Bind::Texel(buf) => {
                debug_assert!(buf.texel != vk::BufferView::null(), "{name}: buffer {} has no texel view", buf.name);
                [buf.texel]
            }
            _ => [vk::BufferView::null()],
        })
        .collect();
    let writes: Vec<_> = binds
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let w =
                vk::WriteDescriptorSet::default().dst_set(set).dst_binding(i as u32).descriptor_type(kinds[i].raw());
            match b {
                Bind::Buffer(_) => w.buffer_info(&buffer_infos[i]),
                Bind::Image(_) => w.image_info(&image_infos[i]),
                Bind::Texel(_) => w.texel_buffer_view(&texel_views[i]),
            }
        })
        .collect();
    unsafe { d.update_descriptor_sets(&writes, &[]) };
    Ok(set)
}
