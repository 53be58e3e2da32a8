//! Buffers and images over gpu-allocator, each with a name (used for the allocation, the
//! debug-utils object name and memory reports).

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::Context;
use crate::error::{Error, Result, VkCall};

/// The usage of the passes' storage buffers: written by a shader, read through a texel view
/// ([`Buffer::with_texel_view`]; docs/integration.md, "buffer views"), filled by an upload or
/// cleared (`TRANSFER_DST`), and copied from (`TRANSFER_SRC`: readbacks).
pub const PASS_BUFFER_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_DST.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw(),
);

/// A buffer and its memory. Destroy it with [`Buffer::destroy`]; hfgi never frees it implicitly.
pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    pub name: String,
    /// The buffer's texel view ([`Buffer::with_texel_view`]; null without one).
    pub texel: vk::BufferView,
    alloc: Option<Allocation>,
}

/// A 2D image, its default view and memory. Destroy with [`Image::destroy`].
pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub samples: vk::SampleCountFlags,
    pub name: String,
    alloc: Option<Allocation>,
}

fn alloc_err(name: &str, size: u64, e: impl std::fmt::Display) -> Error {
    Error::Allocation { name: name.to_string(), size, reason: e.to_string() }
}

impl Buffer {
    /// Creates a buffer of `size` bytes. `location` picks GPU-only or host-visible memory.
    pub fn new(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let d = ctx.device();
        let raw = unsafe { d.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let requirements = unsafe { d.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocator().lock().map_err(|e| alloc_err(name, size, e)).and_then(|mut a| {
            a.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| alloc_err(name, size, e))
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { d.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        if let Err(e) = unsafe { d.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            unsafe { d.destroy_buffer(raw, None) };
            if let Ok(mut a) = ctx.allocator().lock() {
                let _ = a.free(allocation);
            }
            return Err(Error::Vulkan { call: "vkBindBufferMemory", result: e });
        }
        ctx.set_name(raw, name);
        Ok(Self { raw, size, name: name.to_string(), texel: vk::BufferView::null(), alloc: Some(allocation) })
    }

    /// A buffer of `size` bytes placed inside `owner`'s memory at byte `offset`, with no
    /// allocation of its own (memory aliasing): the two share those bytes, so a caller may use
    /// them only at times when the other does not (with the barriers between). `offset` must be
    /// a multiple of the new buffer's required alignment (256 always is, on every device hfgi
    /// knows) and `offset + size` within `owner`. Destroying it frees no memory; destroy it before
    /// `owner`. [`Buffer::owned_bytes`] counts it as 0.
    pub fn aliasing(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        owner: &Buffer,
        offset: u64,
    ) -> Result<Self> {
        let size = size.max(4);
        let Some(alloc) = owner.alloc.as_ref() else {
            return Err(Error::Unsupported(format!("buffer '{name}' aliasing '{}', which owns no memory", owner.name)));
        };
        if offset.checked_add(size).map_or(true, |end| end > owner.size) {
            return Err(Error::param(
                format!("aliased buffer {name}"),
                format!("{size} B at offset {offset}"),
                format!("within the {} B of '{}'", owner.size, owner.name),
            ));
        }
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let d = ctx.device();
        let raw = unsafe { d.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let need = unsafe { d.get_buffer_memory_requirements(raw) };
        let have = unsafe { d.get_buffer_memory_requirements(owner.raw) };
        let at = alloc.offset() + offset;
        if at % need.alignment.max(1) != 0 || need.memory_type_bits & have.memory_type_bits != have.memory_type_bits {
            unsafe { d.destroy_buffer(raw, None) };
            return Err(Error::param(
                format!("aliased buffer {name}"),
                format!("offset {at} in memory types {:#x}", have.memory_type_bits),
                format!("a multiple of {} in memory types {:#x}", need.alignment, need.memory_type_bits),
            ));
        }
        if let Err(e) = unsafe { d.bind_buffer_memory(raw, alloc.memory(), at) } {
            unsafe { d.destroy_buffer(raw, None) };
            return Err(Error::Vulkan { call: "vkBindBufferMemory", result: e });
        }
        ctx.set_name(raw, name);
        Ok(Self { raw, size, name: name.to_string(), texel: vk::BufferView::null(), alloc: None })
    }

    /// The bytes this buffer allocated: its size, or 0 for one made by [`Buffer::aliasing`].
    pub fn owned_bytes(&self) -> u64 {
        if self.alloc.is_some() {
            self.size
        } else {
            0
        }
    }

    /// The buffer with a texel view of `format` over all of it, for shaders that read it as a
    /// uniform texel buffer (`samplerBuffer`, `texelFetch`): lavapipe gathers those on its SIMD
    /// lanes, where it reads a storage buffer lane by lane (docs/performance.md §17). The buffer
    /// must have been created with `UNIFORM_TEXEL_BUFFER` usage; the view is destroyed with it.
    /// On failure the buffer is destroyed.
    pub fn with_texel_view(mut self, ctx: &Context, format: vk::Format) -> Result<Self> {
        let texel = match format {
            vk::Format::R32G32B32A32_UINT => 16,
            vk::Format::R32G32_UINT => 8,
            _ => 4, // R32_UINT, and the fewest bytes a texel has: never undercounts
        };
        let max = ctx.info().max_texel_buffer_elements;
        if self.size / texel > u64::from(max) {
            let e = Error::param(
                format!("texel view of GPU buffer {}", self.name),
                format!("{} texels", self.size / texel),
                format!("at most {max} (maxTexelBufferElements of {}); a smaller field", ctx.info().name),
            );
            self.destroy(ctx);
            return Err(e);
        }
        let info = vk::BufferViewCreateInfo::default().buffer(self.raw).format(format).offset(0).range(vk::WHOLE_SIZE);
        match unsafe { ctx.device().create_buffer_view(&info, None) } {
            Ok(v) => {
                ctx.set_name(v, &self.name);
                self.texel = v;
                Ok(self)
            }
            Err(e) => {
                self.destroy(ctx);
                Err(Error::Vulkan { call: "vkCreateBufferView", result: e })
            }
        }
    }

    /// The host-visible bytes of a `CpuToGpu`/`GpuToCpu` buffer.
    pub fn mapped(&mut self) -> Result<&mut [u8]> {
        let name = self.name.clone();
        let size = self.size as usize;
        self.alloc
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
            .ok_or_else(|| Error::Unsupported(format!("buffer '{name}' is not host-visible")))
    }

    /// Frees the buffer and its memory.
    pub fn destroy(mut self, ctx: &Context) {
        if self.texel != vk::BufferView::null() {
            unsafe { ctx.device().destroy_buffer_view(self.texel, None) };
        }
        unsafe { ctx.device().destroy_buffer(self.raw, None) };
        if let (Some(a), Ok(mut al)) = (self.alloc.take(), ctx.allocator().lock()) {
            let _ = al.free(a);
        }
    }

    /// Descriptor info covering the whole buffer.
    pub fn whole(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default().buffer(self.raw).offset(0).range(vk::WHOLE_SIZE)
    }
}

impl Image {
    /// Creates a 2D image (one mip, one layer) in `UNDEFINED` layout with a colour view.
    pub fn new(
        ctx: &Context,
        name: &str,
        extent: vk::Extent2D,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: vk::SampleCountFlags,
    ) -> Result<Self> {
        let d = ctx.device();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { d.create_image(&info, None) }.vk("vkCreateImage")?;
        let requirements = unsafe { d.get_image_memory_requirements(raw) };
        let size = requirements.size;
        let allocation = ctx.allocator().lock().map_err(|e| alloc_err(name, size, e)).and_then(|mut a| {
            a.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| alloc_err(name, size, e))
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { d.destroy_image(raw, None) };
                return Err(e);
            }
        };
        let mut img = Self {
            raw,
            view: vk::ImageView::null(),
            format,
            extent,
            samples,
            name: name.into(),
            alloc: Some(allocation),
        };
        let bound = unsafe {
            d.bind_image_memory(
                raw,
                img.alloc.as_ref().map(|a| a.memory()).unwrap_or_default(),
                img.alloc.as_ref().map(|a| a.offset()).unwrap_or(0),
            )
        };
        if let Err(e) = bound {
            img.destroy(ctx);
            return Err(Error::Vulkan { call: "vkBindImageMemory", result: e });
        }
        let vinfo = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range_of(format));
        match unsafe { d.create_image_view(&vinfo, None) } {
            Ok(v) => img.view = v,
            Err(e) => {
                img.destroy(ctx);
                return Err(Error::Vulkan { call: "vkCreateImageView", result: e });
            }
        }
        ctx.set_name(raw, name);
        Ok(img)
    }

    /// Frees the image, its view and memory.
    pub fn destroy(mut self, ctx: &Context) {
        unsafe {
            if self.view != vk::ImageView::null() {
                ctx.device().destroy_image_view(self.view, None);
            }
            ctx.device().destroy_image(self.raw, None);
        }
        if let (Some(a), Ok(mut al)) = (self.alloc.take(), ctx.allocator().lock()) {
            let _ = al.free(a);
        }
    }

    /// Bytes of device memory bound to the image.
    pub fn size_bytes(&self) -> u64 {
        self.alloc.as_ref().map(|a| a.size()).unwrap_or(0)
    }
}

/// The single colour subresource (mip 0, layer 0).
pub fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1)
}

/// The aspects of `format`: DEPTH and/or STENCIL for depth/stencil formats, COLOR otherwise.
pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 | vk::Format::D32_SFLOAT => vk::ImageAspectFlags::DEPTH,
        vk::Format::S8_UINT => vk::ImageAspectFlags::STENCIL,
        vk::Format::D16_UNORM_S8_UINT | vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// The single subresource (mip 0, layer 0) of an image of `format`, all its aspects.
pub fn range_of(format: vk::Format) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default().aspect_mask(aspect_of(format)).level_count(1).layer_count(1)
}

/// Uploads `data` into `dst` (a device buffer with TRANSFER_DST usage) at byte `offset`,
/// through a staging buffer, and waits. The copy is followed by a barrier making it visible to
/// compute shaders.
pub fn upload(ctx: &Context, dst: &Buffer, offset: u64, data: &[u8]) -> Result<()> {
    let mut staging = Buffer::new(
        ctx,
        "hfgi.staging.upload",
        data.len() as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
    )?;
    if let Err(e) = staging.mapped().map(|m| m[..data.len()].copy_from_slice(data)) {
        staging.destroy(ctx);
        return Err(e);
    }
    let (src, dst_raw, len) = (staging.raw, dst.raw, data.len() as u64);
    let copy: super::context::Deferred = Box::new(move |d: &ash::Device, cmd: vk::CommandBuffer| {
        let region = [vk::BufferCopy::default().src_offset(0).dst_offset(offset).size(len)];
        unsafe { d.cmd_copy_buffer(cmd, src, dst_raw, &region) };
    });
    let Some((copy, staging)) = ctx.defer(copy, Some(staging)) else { return Ok(()) };
    let r = ctx.submit_and_wait(|cmd| {
        copy(ctx.device(), cmd);
        super::barrier::transfer_to_compute(ctx, cmd);
        Ok(())
    });
    staging.into_iter().for_each(|s| s.destroy(ctx));
    r
}

/// Fills `dst` with zeros (`vkCmdFillBuffer`): deferred inside [`Context::batched`], else
/// submitted and waited for.
pub fn zero(ctx: &Context, dst: &Buffer) -> Result<()> {
    let raw = dst.raw;
    let fill: super::context::Deferred = Box::new(move |d: &ash::Device, cmd: vk::CommandBuffer| unsafe {
        d.cmd_fill_buffer(cmd, raw, 0, vk::WHOLE_SIZE, 0)
    });
    let Some((fill, _)) = ctx.defer(fill, None) else { return Ok(()) };
    ctx.submit_and_wait(|cmd| {
        fill(ctx.device(), cmd);
        super::barrier::transfer_to_all(ctx, cmd);
        Ok(())
    })
}

/// Reads `len` bytes from `src` (a buffer with TRANSFER_SRC usage) at byte `offset` and waits.
/// Inserts a barrier that makes prior compute writes visible to the copy.
pub fn download(ctx: &Context, src: &Buffer, offset: u64, len: u64) -> Result<Vec<u8>> {
    let mut staging =
        Buffer::new(ctx, "hfgi.staging.download", len, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
    let r = ctx
        .submit_and_wait(|cmd| {
            super::barrier::compute_to_transfer(ctx, cmd);
            let region = [vk::BufferCopy::default().src_offset(offset).dst_offset(0).size(len)];
            unsafe { ctx.device().cmd_copy_buffer(cmd, src.raw, staging.raw, &region) };
            Ok(())
        })
        .and_then(|_| staging.mapped().map(|m| m[..len as usize].to_vec()));
    staging.destroy(ctx);
    r
}

/// `upload` for f32 slices.
pub fn upload_f32(ctx: &Context, dst: &Buffer, offset_floats: u64, data: &[f32]) -> Result<()> {
    upload(ctx, dst, offset_floats * 4, bytemuck::cast_slice(data))
}

/// `download` for f32 slices.
pub fn download_f32(ctx: &Context, src: &Buffer, offset_floats: u64, count: u64) -> Result<Vec<f32>> {
    let bytes = download(ctx, src, offset_floats * 4, count * 4)?;
    Ok(bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
}

/// Copies mip 0 of a single-sample colour image (in `layout`, which must be TRANSFER_SRC_OPTIMAL
/// or GENERAL, with prior writes made visible to transfer reads) into host memory and waits.
/// Returns the texels tightly packed, row 0 first, `bytes_per_texel` each.
pub fn download_image(ctx: &Context, image: &Image, layout: vk::ImageLayout, bytes_per_texel: u64) -> Result<Vec<u8>> {
    let (w, h) = (u64::from(image.extent.width), u64::from(image.extent.height));
    let len = w * h * bytes_per_texel;
    let mut staging =
        Buffer::new(ctx, "hfgi.staging.image", len, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?;
    let r = ctx
        .submit_and_wait(|cmd| {
            let region = [vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
                )
                .image_extent(vk::Extent3D { width: image.extent.width, height: image.extent.height, depth: 1 })];
            unsafe { ctx.device().cmd_copy_image_to_buffer(cmd, image.raw, layout, staging.raw, &region) };
            Ok(())
        })
        .and_then(|_| staging.mapped().map(|m| m[..len as usize].to_vec()));
    staging.destroy(ctx);
    r
}
