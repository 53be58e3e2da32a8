//! Instance and device creation for [`Context::headless_with`], and the device choice.

use std::ffi::{c_char, c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::host::driver_hint;
use super::{Context, DeviceInfo, Messenger};
use crate::error::{Error, Result, VkCall};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if user.is_null() || data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: `user` is the `Mutex<Vec<String>>` owned by the Context's Arc, which outlives the
    // messenger; `data` is valid for the duration of the callback.
    let (store, data) = unsafe { (&*(user as *const Mutex<Vec<String>>), &*data) };
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let msg = format!("[{severity:?} {types:?}] {}: {}", text(data.p_message_id_name), text(data.p_message));
    if let Ok(mut v) = store.lock() {
        v.push(msg);
    }
    vk::FALSE
}

pub(super) fn env_flag(name: &str) -> bool {
    std::env::var(name).map(|v| !v.is_empty() && v != "0").unwrap_or(false)
}

fn rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// The instance layers (validation, where `validation` asks for it and it is installed) and
/// extensions (`VK_EXT_debug_utils` where available) [`Context::headless_with`] enables, and
/// whether `VK_EXT_debug_utils` is available.
pub(super) fn instance_layers(
    entry: &ash::Entry,
    validation: bool,
) -> Result<(Vec<*const c_char>, Vec<*const c_char>, bool)> {
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
    let exts =
        unsafe { entry.enumerate_instance_extension_properties(None) }.vk("vkEnumerateInstanceExtensionProperties")?;
    let has_debug_utils =
        exts.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::debug_utils::NAME));
    let mut layer_ptrs = Vec::new();
    if validation {
        if !layers.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER)) {
            return Err(Error::Unsupported(
                "validation requested (HFGI_VALIDATION=1) but VK_LAYER_KHRONOS_validation is not installed \
                 (Debian: apt-get install vulkan-validationlayers)"
                    .into(),
            ));
        }
        if !has_debug_utils {
            return Err(Error::Unsupported("validation requested but VK_EXT_debug_utils is unavailable".into()));
        }
        layer_ptrs.push(VALIDATION_LAYER.as_ptr());
    }
    let mut ext_ptrs = Vec::new();
    if has_debug_utils {
        ext_ptrs.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    Ok((layer_ptrs, ext_ptrs, has_debug_utils))
}

/// The instance with layers `layer_ptrs` and extensions `ext_ptrs`, and with `validation` the
/// messenger that collects its warnings and errors into `messages` (with `sync`,
/// synchronization validation too).
pub(super) fn create_instance(
    entry: &ash::Entry,
    (layer_ptrs, ext_ptrs): (&[*const c_char], &[*const c_char]),
    validation: bool,
    sync: bool,
    messages: &Arc<Mutex<Vec<String>>>,
) -> Result<(ash::Instance, Option<Messenger>)> {
    let mut dbg_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
                | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
        )
        .pfn_user_callback(Some(on_message))
        .user_data(Arc::as_ptr(messages) as *mut c_void);

    let app =
        vk::ApplicationInfo::default().application_name(c"hfgi").engine_name(c"hfgi").api_version(vk::API_VERSION_1_3);
    let mut ici = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(layer_ptrs)
        .enabled_extension_names(ext_ptrs);
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    if validation {
        // Chained so that instance creation/destruction messages are caught too.
        ici = ici.push_next(&mut dbg_info);
        if sync {
            ici = ici.push_next(&mut features);
        }
    }
    let instance = unsafe { entry.create_instance(&ici, None) }
        .map_err(|result| Error::NoDevice(format!("vkCreateInstance failed with {result:?}; {}", driver_hint())))?;
    let messenger = if validation {
        let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
        match unsafe { loader.create_debug_utils_messenger(&dbg_info, None) } {
            Ok(raw) => Some(Messenger { loader, raw }),
            Err(e) => {
                unsafe { instance.destroy_instance(None) };
                return Err(Error::Vulkan { call: "vkCreateDebugUtilsMessengerEXT", result: e });
            }
        }
    } else {
        None
    };
    Ok((instance, messenger))
}

/// The device (one queue of `family`, `synchronization2` and `dynamicRendering` enabled), its
/// queue and an allocator on it; on failure nothing of it is left (the instance is the
/// caller's to clean up).
pub(super) fn create_device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    family: u32,
) -> Result<(ash::Device, vk::Queue, Allocator)> {
    let priorities = [1.0f32];
    let qci = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default().synchronization2(true).dynamic_rendering(true);
    let dci = vk::DeviceCreateInfo::default().queue_create_infos(&qci).push_next(&mut f13);
    let device = unsafe { instance.create_device(physical, &dci, None) }
        .map_err(|e| Error::Vulkan { call: "vkCreateDevice", result: e })?;
    let queue = unsafe { device.get_device_queue(family, 0) };
    let allocator = match Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: physical,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    }) {
        Ok(a) => a,
        Err(e) => {
            unsafe { device.destroy_device(None) };
            return Err(Error::Allocation { name: "allocator".into(), size: 0, reason: e.to_string() });
        }
    };
    Ok((device, queue, allocator))
}

impl Context {
    /// The best device, or the first whose name contains `filter` (from `HFGI_DEVICE` when
    /// `from_env`, else from [`ContextOptions::device_filter`]; messages name the source).
    pub(super) fn pick_device(
        instance: &ash::Instance,
        filter: Option<&str>,
        from_env: bool,
    ) -> Result<(vk::PhysicalDevice, u32)> {
        let devices = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
        let mut candidates = Vec::new();
        let mut seen = Vec::new();
        for pd in devices {
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let name = props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            seen.push(name.clone());
            if props.api_version < vk::API_VERSION_1_3 {
                continue;
            }
            if let Some(f) = filter {
                if !name.to_lowercase().contains(&f.to_lowercase()) {
                    continue;
                }
            }
            let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            let want = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
            if let Some(fam) = families.iter().position(|f| f.queue_flags.contains(want)) {
                candidates.push((rank(props.device_type), pd, fam as u32));
            }
        }
        candidates.sort_by_key(|c| c.0);
        candidates.first().map(|c| (c.1, c.2)).ok_or_else(|| {
            Error::NoDevice(format!(
                "{}; devices present: [{}] (need Vulkan 1.3 and a graphics+compute queue)",
                match (filter, from_env) {
                    (Some(f), true) => format!("no device name contains {f:?} (HFGI_DEVICE)"),
                    (Some(f), false) => format!("no device name contains {f:?} (the requested device)"),
                    (None, _) if seen.is_empty() => format!("the Vulkan loader found no device; {}", driver_hint()),
                    (None, _) => "none usable".into(),
                },
                seen.join(", ")
            ))
        })
    }

    pub(super) fn describe(instance: &ash::Instance, pd: vk::PhysicalDevice, family: u32) -> DeviceInfo {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut m3 = vk::PhysicalDeviceMaintenance3Properties::default();
        let mut sub = vk::PhysicalDeviceSubgroupProperties::default();
        let mut p2 =
            vk::PhysicalDeviceProperties2::default().push_next(&mut driver).push_next(&mut m3).push_next(&mut sub);
        unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
        let props = p2.properties;
        let mem = unsafe { instance.get_physical_device_memory_properties(pd) };
        let device_local_heap_bytes = mem.memory_heaps[..mem.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .max()
            .unwrap_or(0);
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let name = props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let dname = driver.driver_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let dinfo = driver.driver_info_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let valid_bits =
            if props.limits.timestamp_compute_and_graphics == vk::TRUE || props.limits.timestamp_period > 0.0 {
                families.get(family as usize).map(|f| f.timestamp_valid_bits).unwrap_or(0)
            } else {
                0
            };
        DeviceInfo {
            name,
            kind: props.device_type,
            driver: format!("{dname} {dinfo}").trim().to_string(),
            api_version: (
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version),
                vk::api_version_patch(props.api_version),
            ),
            max_image_dimension_2d: props.limits.max_image_dimension2_d,
            timestamp_period: props.limits.timestamp_period,
            timestamp_valid_bits: valid_bits,
            device_local_heap_bytes,
            max_storage_buffer_range: props.limits.max_storage_buffer_range,
            max_memory_allocation_size: m3.max_memory_allocation_size,
            max_texel_buffer_elements: props.limits.max_texel_buffer_elements,
            subgroup_vote_compute: sub.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
                && sub.supported_operations.contains(vk::SubgroupFeatureFlags::VOTE),
        }
    }
}
