//! synchronization2 barriers. Nothing else in hfgi writes barriers.

use ash::vk;

use super::Context;

fn memory_barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    let dep = vk::DependencyInfo::default().memory_barriers(&b);
    unsafe { ctx.device().cmd_pipeline_barrier2(cmd, &dep) };
}

/// What a compute shader of hfgi's reads and writes: storage buffers, and the uniform texel
/// buffers the scanning passes read per sample (docs/performance.md §17).
const COMPUTE_ACCESS: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
        | vk::AccessFlags2::SHADER_SAMPLED_READ.as_raw()
        | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
);

/// Compute shader writes → compute shader reads (storage and texel) and writes (between passes
/// or pyramid levels).
pub fn compute_to_compute(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
        (vk::PipelineStageFlags2::COMPUTE_SHADER, COMPUTE_ACCESS),
    );
}

/// Transfer writes (uploads) → compute shader reads (storage and texel) and writes.
pub fn transfer_to_compute(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
        (vk::PipelineStageFlags2::COMPUTE_SHADER, COMPUTE_ACCESS),
    );
}

/// Before transfer writes into buffers that compute shaders read (`vkCmdUpdateBuffer` of the
/// live inputs): earlier compute-shader reads and transfers, in this or an earlier submission
/// to the queue, finish first (write-after-read; write-after-write of an earlier update).
pub fn compute_to_update(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (
            vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::TRANSFER_WRITE,
        ),
        (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
    );
}

/// Transfer writes of any transfer command (copy, fill, update) → compute shader reads
/// (storage and texel).
pub fn update_to_compute(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
        (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_SAMPLED_READ,
        ),
    );
}

/// Transfer writes (creation's batched uploads and fills) → every later command's reads and
/// writes (compute, vertex/index input, fragment, transfer).
pub fn transfer_to_all(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
        (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE),
    );
}

/// Transfer writes → later transfer writes and reads (creation's batched uploads, in order).
pub fn transfer_to_transfer(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
        (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE | vk::AccessFlags2::TRANSFER_READ),
    );
}

/// The start of a `Renderer` frame: every earlier command in submission order (the host's
/// passes, hfgi's previous frame) finishes its reads and makes its writes visible before the
/// frame's compute and transfer work (write-after-read and read-after-write across frames and
/// with the host's own passes).
pub fn before_frame(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
        (
            vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER,
            vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
        ),
    );
}

/// Transfer writes → host reads (a read-back ring, read after the host waited).
pub fn transfer_to_host(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE),
        (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
    );
}

/// Compute shader writes → transfer reads (downloads).
pub fn compute_to_transfer(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
    );
}

/// Full image layout transition of the colour subresource.
#[allow(clippy::too_many_arguments)]
pub fn image_layout(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(super::memory::color_range())];
    let dep = vk::DependencyInfo::default().image_memory_barriers(&b);
    unsafe { ctx.device().cmd_pipeline_barrier2(cmd, &dep) };
}

/// Compute-shader or transfer writes (heights, shading texture, index uploads) → reads by a
/// draw: index fetch and vertex/fragment-shader storage reads.
pub fn compute_to_graphics(ctx: &Context, cmd: vk::CommandBuffer) {
    memory_barrier(
        ctx,
        cmd,
        (
            vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::TRANSFER_WRITE,
        ),
        (
            vk::PipelineStageFlags2::INDEX_INPUT
                | vk::PipelineStageFlags2::VERTEX_SHADER
                | vk::PipelineStageFlags2::FRAGMENT_SHADER,
            vk::AccessFlags2::INDEX_READ | vk::AccessFlags2::SHADER_STORAGE_READ,
        ),
    );
}

/// One layout transition for [`image_transitions`]; the aspect follows the image's format
/// (colour or depth), mip 0 / layer 0.
pub struct Transition<'a> {
    pub image: &'a super::Image,
    pub old: vk::ImageLayout,
    pub new: vk::ImageLayout,
    pub src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    pub dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
}

/// Records several image layout transitions in one `vkCmdPipelineBarrier2`.
pub fn image_transitions(ctx: &Context, cmd: vk::CommandBuffer, list: &[Transition]) {
    let b: Vec<_> = list
        .iter()
        .map(|t| {
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(t.src.0)
                .src_access_mask(t.src.1)
                .dst_stage_mask(t.dst.0)
                .dst_access_mask(t.dst.1)
                .old_layout(t.old)
                .new_layout(t.new)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(t.image.raw)
                .subresource_range(super::memory::range_of(t.image.format))
        })
        .collect();
    let dep = vk::DependencyInfo::default().image_memory_barriers(&b);
    unsafe { ctx.device().cmd_pipeline_barrier2(cmd, &dep) };
}
