//! A host engine embedding hfgi (docs/integration.md is the contract this follows).
//!
//! The host creates and owns its instance (with `VK_LAYER_KHRONOS_validation` and
//! synchronization validation), device, queue, command pool, fence and gpu-allocator
//! `Allocator`, wraps them with `Context::from_raw`, and for 10 frames records into its own
//! command buffer: its own pass that writes new heights into hfgi's heights buffer, hfgi's frame
//! (after moving the sun with `Renderer::set_key_lights`), and its own pass that copies hfgi's
//! shading out; then it submits itself, with two frames in flight on the queue (it waits for a
//! frame's fence only when it reuses that frame's slot). It checks that
//!
//! - the validation layer (synchronization validation on) reported nothing,
//! - hfgi made no queue submission of its own after creation (`Context::submit_count`, which
//!   counts every `vkQueueSubmit2` hfgi makes),
//! - no pipeline was created in the loop, and
//! - gpu-allocator reports no live allocation once hfgi's objects and the host's are destroyed.
//!
//! Run: `tools/env.sh` pins lavapipe; `cargo run --example embed` (CI runs it from tools/test).
//! Exit status 0 on success, 1 with the reason otherwise.

use std::ffi::c_void;
use std::sync::{Arc, Mutex};

use hfgi::ash::{self, vk};
use hfgi::frame::Renderer;
use hfgi::gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc};
use hfgi::gpu_allocator::MemoryLocation;
use hfgi::scene::model::KeyLight;
use hfgi::scene::HeightField;
use hfgi::vk::{Context, EnabledFeatures, RawHandles, Recorder};

const FRAMES: usize = 10;
const SIZE: usize = 48;

static MESSAGES: Mutex<Vec<String>> = Mutex::new(Vec::new());

unsafe extern "system" fn on_message(
    _severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    let text = unsafe { (*data).message_as_c_str() }.map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
    if let Ok(mut m) = MESSAGES.lock() {
        m.push(text);
    }
    vk::FALSE
}

/// The host's Vulkan objects.
struct Host {
    entry: ash::Entry,
    instance: ash::Instance,
    debug: ash::ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    family: u32,
    queue: vk::Queue,
    allocator: Arc<Mutex<Allocator>>,
}

fn host() -> Result<Host, String> {
    let entry = unsafe { ash::Entry::load() }.map_err(|e| format!("loading Vulkan: {e}"))?;
    let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
    let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let severity = vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR;
    let kinds = vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE;
    let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(severity)
        .message_type(kinds)
        .pfn_user_callback(Some(on_message));
    let app = vk::ApplicationInfo::default().application_name(c"hfgi-embed").api_version(vk::API_VERSION_1_3);
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions)
        .push_next(&mut features)
        .push_next(&mut messenger_info);
    let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| format!("vkCreateInstance: {e}"))?;
    let debug = ash::ext::debug_utils::Instance::new(&entry, &instance);
    let own = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(severity)
        .message_type(kinds)
        .pfn_user_callback(Some(on_message));
    let messenger = unsafe { debug.create_debug_utils_messenger(&own, None) }
        .map_err(|e| format!("vkCreateDebugUtilsMessengerEXT: {e}"))?;
    let physical = unsafe { instance.enumerate_physical_devices() }
        .map_err(|e| format!("vkEnumeratePhysicalDevices: {e}"))?
        .into_iter()
        .next()
        .ok_or("no Vulkan device")?;
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    let want = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
    let family = families.iter().position(|f| f.queue_flags.contains(want)).ok_or("no compute+graphics queue")? as u32;
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default().synchronization2(true).dynamic_rendering(true);
    let dinfo = vk::DeviceCreateInfo::default().queue_create_infos(&queues).push_next(&mut f13);
    let device =
        unsafe { instance.create_device(physical, &dinfo, None) }.map_err(|e| format!("vkCreateDevice: {e}"))?;
    let queue = unsafe { device.get_device_queue(family, 0) };
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: physical,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })
    .map_err(|e| format!("gpu-allocator: {e}"))?;
    let allocator = Arc::new(Mutex::new(allocator));
    Ok(Host { entry, instance, debug, messenger, physical, device, family, queue, allocator })
}

/// A host-visible buffer of the host's own.
struct HostBuffer {
    raw: vk::Buffer,
    alloc: Allocation,
}

fn host_buffer(h: &Host, name: &str, size: u64, usage: vk::BufferUsageFlags, location: MemoryLocation) -> HostBuffer {
    let info = vk::BufferCreateInfo::default().size(size).usage(usage);
    let raw = unsafe { h.device.create_buffer(&info, None) }.expect("vkCreateBuffer");
    let requirements = unsafe { h.device.get_buffer_memory_requirements(raw) };
    let desc = AllocationCreateDesc {
        name,
        requirements,
        location,
        linear: true,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    };
    let alloc = h.allocator.lock().unwrap().allocate(&desc).expect("allocate");
    unsafe { h.device.bind_buffer_memory(raw, alloc.memory(), alloc.offset()) }.expect("bind");
    HostBuffer { raw, alloc }
}

fn barrier(
    h: &Host,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    unsafe { h.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
}

/// Heights of frame `f`: a ridge that slides across the field.
fn heights(f: usize) -> Vec<f32> {
    let x0 = 8.0 + 3.0 * f as f32;
    (0..SIZE * SIZE)
        .map(|i| {
            let (x, y) = ((i % SIZE) as f32, (i / SIZE) as f32);
            6.0 * (-((x - x0).powi(2)) / 40.0).exp() + 0.8 * (0.3 * x + 0.2 * y).sin()
        })
        .collect()
}

fn run() -> Result<(), String> {
    let h = host()?;
    let ctx = Context::from_raw(RawHandles {
        entry: h.entry.clone(),
        instance: h.instance.clone(),
        physical_device: h.physical,
        device: h.device.clone(),
        queue: h.queue,
        queue_family_index: h.family,
        allocator: h.allocator.clone(),
        debug_utils: true,
        enabled: EnabledFeatures { synchronization2: true, dynamic_rendering: true },
        pipeline_cache: vk::PipelineCache::null(),
    })
    .map_err(|e| format!("Context::from_raw: {e}"))?;
    let mut scene = hfgi::scene::file::default_scene().map_err(|e| e.to_string())?;
    scene.field = HeightField::new("embed heights", SIZE, SIZE, heights(0), 16384).map_err(|e| e.to_string())?;
    scene.gi.azimuths = 8;
    scene.gi.bounces = 1;
    let mut renderer = Renderer::new(&ctx, &scene).map_err(|e| format!("Renderer::new: {e}"))?;
    let (submits, pipelines) = (ctx.submit_count(), ctx.pipelines_created());
    eprintln!("created: {submits} submit(s) by hfgi (creation is one), {pipelines} pipelines");
    if submits != 1 {
        return Err(format!("creating the renderer took {submits} submits, not one"));
    }

    let (hfgi_submits, new_pipelines, result) = frames(&h, &ctx, &mut renderer, &scene.key_lights[0])?;
    let _ = (submits, pipelines);
    renderer.destroy(&ctx);
    drop(ctx); // from_raw: destroys hfgi's own pool and fence, never waits on the host's device
    let live = h.allocator.lock().unwrap().generate_report().allocations;
    let messages = std::mem::take(&mut *MESSAGES.lock().unwrap());
    eprintln!("{FRAMES} frames: {hfgi_submits} submits by hfgi after creation, {new_pipelines} pipelines created");
    eprintln!("gpu-allocator: {} live allocations after destroying everything", live.len());
    eprintln!("validation (synchronization validation on): {} messages", messages.len());
    for m in &messages {
        eprintln!("  {m}");
    }
    unsafe { h.device.device_wait_idle() }.map_err(|e| e.to_string())?;
    drop(h.allocator);
    unsafe {
        h.device.destroy_device(None);
        h.debug.destroy_debug_utils_messenger(h.messenger, None);
        h.instance.destroy_instance(None);
    }
    let late = MESSAGES.lock().unwrap().len();
    result?;
    if hfgi_submits != 0 || new_pipelines != 0 {
        return Err(format!("hfgi submitted {hfgi_submits} times and created {new_pipelines} pipelines in the loop"));
    }
    if !live.is_empty() {
        let names: Vec<&str> = live.iter().map(|a| a.name.as_str()).collect();
        return Err(format!("leaked allocations: {names:?}"));
    }
    if !messages.is_empty() || late > 0 {
        return Err(format!("{} validation messages", messages.len() + late));
    }
    eprintln!("embed: ok");
    Ok(())
}

/// One frame slot of the host: its command buffer, fence and staging buffers.
struct Slot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    upload: HostBuffer,
    readback: HostBuffer,
    /// The frame whose commands are in flight in this slot.
    frame: Option<usize>,
}

const IN_FLIGHT: usize = 2;

/// Renders `FRAMES` frames with `IN_FLIGHT` of them in flight on the queue: frame `f + 1` is
/// recorded and submitted before frame `f` finished (one `Renderer`; docs/integration.md §3
/// "Frames in flight"). Returns hfgi's submits and pipelines created in the loop, and whether
/// every frame's shading was finite and differed from the one before.
fn frames(
    h: &Host,
    ctx: &Context,
    renderer: &mut Renderer,
    sun0: &KeyLight,
) -> Result<(u64, u64, Result<(), String>), String> {
    let (submits, pipelines) = (ctx.submit_count(), ctx.pipelines_created());
    let bytes = (SIZE * SIZE * 4) as u64;
    // Plane 0 (the total): one texel per sample in the renderer's format (an RGB f32 triple at
    // full-rate GI, one RGBE word with gi.shading_storage = "rgbe" or sub-sampled GI;
    // ShadingFormat::decode reads both).
    let format = renderer.shading_format();
    let shading = (SIZE * SIZE) as u64 * format.texel_bytes();
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(h.family)
        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
    let pool = unsafe { h.device.create_command_pool(&pool_info, None) }.map_err(|e| e.to_string())?;
    let alloc = vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(IN_FLIGHT as u32);
    let cmds = unsafe { h.device.allocate_command_buffers(&alloc) }.map_err(|e| e.to_string())?;
    let mut slots: Vec<Slot> = cmds
        .into_iter()
        .map(|cmd| Slot {
            cmd,
            fence: unsafe { h.device.create_fence(&vk::FenceCreateInfo::default(), None) }.expect("vkCreateFence"),
            upload: host_buffer(h, "host.heights", bytes, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu),
            readback: host_buffer(
                h,
                "host.readback",
                shading,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            ),
            frame: None,
        })
        .collect();
    let mut outputs: Vec<Vec<f32>> = vec![Vec::new(); FRAMES];
    let finish = |slot: &mut Slot, outputs: &mut Vec<Vec<f32>>| -> Result<(), String> {
        let Some(f) = slot.frame.take() else { return Ok(()) };
        unsafe {
            h.device.wait_for_fences(&[slot.fence], true, u64::MAX).map_err(|e| e.to_string())?;
            h.device.reset_fences(&[slot.fence]).map_err(|e| e.to_string())?;
        }
        let m = slot.readback.alloc.mapped_slice().ok_or("unmapped")?;
        outputs[f] = format.decode(&m[..shading as usize]).into_iter().flatten().collect();
        Ok(())
    };
    for f in 0..FRAMES {
        let slot = &mut slots[f % IN_FLIGHT];
        finish(slot, &mut outputs)?; // the slot's previous frame, IN_FLIGHT frames ago
                                     // The sun moves every frame (a live input, recorded by `record`).
        let direction = hfgi::scene::file::direction_from_angles(20.0 + 5.0 * f as f64, 150.0 + 12.0 * f as f64);
        renderer.set_key_lights(&[KeyLight { direction, ..sun0.clone() }]).map_err(|e| e.to_string())?;
        let z = heights(f + 1);
        slot.upload.alloc.mapped_slice_mut().ok_or("unmapped")?[..bytes as usize]
            .copy_from_slice(bytemuck::cast_slice(&z));
        let cmd = slot.cmd;
        unsafe { h.device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) }
            .map_err(|e| e.to_string())?;
        // Host pass before hfgi: new heights into hfgi's heights buffer. Contract: after hfgi's
        // earlier reads (write-after-read, also of the frame still in flight), then
        // `mark_heights_changed`; hfgi's frame begins with a barrier after every earlier command.
        let (compute, copy) = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::PipelineStageFlags2::COPY);
        barrier(h, cmd, (compute, vk::AccessFlags2::NONE), (copy, vk::AccessFlags2::TRANSFER_WRITE));
        let region = [vk::BufferCopy::default().size(bytes)];
        unsafe { h.device.cmd_copy_buffer(cmd, slot.upload.raw, renderer.heights_buffer().raw, &region) };
        renderer.mark_heights_changed();
        renderer.record(&mut Recorder::new(ctx, cmd, None));
        // Host pass after hfgi: copy the shading out. Contract: compute writes → the reader's
        // stage (here a copy), then copy → host for the CPU read.
        barrier(h, cmd, (compute, vk::AccessFlags2::SHADER_STORAGE_WRITE), (copy, vk::AccessFlags2::TRANSFER_READ));
        let region = [vk::BufferCopy::default().size(shading)];
        unsafe { h.device.cmd_copy_buffer(cmd, renderer.shading_buffer().raw, slot.readback.raw, &region) };
        let host = (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ);
        barrier(h, cmd, (copy, vk::AccessFlags2::TRANSFER_WRITE), host);
        unsafe { h.device.end_command_buffer(cmd) }.map_err(|e| e.to_string())?;
        let cbi = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cbi)];
        unsafe { h.device.queue_submit2(h.queue, &submit, slot.fence) }.map_err(|e| e.to_string())?;
        slot.frame = Some(f);
    }
    for slot in &mut slots {
        finish(slot, &mut outputs)?;
    }
    let (hfgi_submits, new_pipelines) = (ctx.submit_count() - submits, ctx.pipelines_created() - pipelines);
    let mut result = Ok(());
    for (f, total) in outputs.iter().enumerate() {
        if total.iter().any(|v| !v.is_finite()) || total.iter().all(|v| *v == 0.0) {
            result = Err(format!("frame {f}: the shading is not finite or is black"));
        }
        if f > 0 && outputs[f - 1] == *total {
            result = Err(format!("frame {f}: the shading did not change with the heights and the sun"));
        }
    }
    unsafe { h.device.destroy_command_pool(pool, None) };
    let mut a = h.allocator.lock().unwrap();
    for slot in slots {
        unsafe {
            h.device.destroy_fence(slot.fence, None);
            h.device.destroy_buffer(slot.upload.raw, None);
            h.device.destroy_buffer(slot.readback.raw, None);
        }
        a.free(slot.upload.alloc).map_err(|e| e.to_string())?;
        a.free(slot.readback.alloc).map_err(|e| e.to_string())?;
    }
    Ok((hfgi_submits, new_pipelines, result))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("embed: {e}");
        std::process::exit(1);
    }
}
