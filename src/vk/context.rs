//! Device choice, ownership, validation messenger and a submit-and-wait helper.

use std::ffi::CString;
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::Allocator;

use crate::error::{Error, Result, VkCall};

/// How [`Context::headless_with`] creates its instance and device.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable `VK_LAYER_KHRONOS_validation` and collect its warnings and errors.
    /// `None` reads the environment: `HFGI_VALIDATION=1` enables it.
    pub validation: Option<bool>,
    /// Substring (case-insensitive) of the device name to use. `None` reads `HFGI_DEVICE`.
    pub device_filter: Option<String>,
    /// With validation, also enable its synchronization validation (hazards between commands
    /// and submissions: missing barriers). `None` reads `HFGI_SYNC_VALIDATION` (`0` turns it
    /// off; the test suite turns it on).
    pub sync_validation: Option<bool>,
}

/// What a host engine hands to [`Context::from_raw`]. hfgi destroys none of these.
pub struct RawHandles {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    /// A queue that supports compute (and graphics for the view pass). hfgi submits to it only
    /// from [`Context::submit_and_wait`], never from the recording functions.
    pub queue: vk::Queue,
    pub queue_family_index: u32,
    /// The host's allocator; hfgi allocates and frees its own resources through it.
    pub allocator: Arc<Mutex<Allocator>>,
    /// Whether the host enabled `VK_EXT_debug_utils` on the instance (debug labels and names).
    pub debug_utils: bool,
    /// The Vulkan 1.3 features the host enabled on `device` (a device cannot be asked what it was
    /// created with): [`Context::from_raw`] refuses a device without `synchronization2`.
    pub enabled: EnabledFeatures,
    /// The host's pipeline cache, or null: every pipeline hfgi creates is created through it.
    pub pipeline_cache: vk::PipelineCache,
}

/// The device features hfgi needs, as the host enabled them ([`RawHandles::enabled`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EnabledFeatures {
    /// `VkPhysicalDeviceVulkan13Features::synchronization2`: every barrier hfgi records.
    pub synchronization2: bool,
    /// `VkPhysicalDeviceVulkan13Features::dynamicRendering`: the view pass only.
    pub dynamic_rendering: bool,
}

impl EnabledFeatures {
    /// The features of the `VkPhysicalDeviceVulkan13Features` the host chained into its
    /// `VkDeviceCreateInfo`.
    pub fn from_vulkan13(f: &vk::PhysicalDeviceVulkan13Features) -> Self {
        Self { synchronization2: f.synchronization2 == vk::TRUE, dynamic_rendering: f.dynamic_rendering == vk::TRUE }
    }
}

/// Facts about the chosen device, for reports and benchmarks.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub driver: String,
    pub api_version: (u32, u32, u32),
    pub max_image_dimension_2d: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Valid bits of a timestamp on hfgi's queue family (0: no timestamps).
    pub timestamp_valid_bits: u32,
    /// Bytes of the largest `DEVICE_LOCAL` memory heap (what hfgi's buffers live in).
    pub device_local_heap_bytes: u64,
    /// `maxStorageBufferRange`: the largest storage buffer a shader may bind.
    pub max_storage_buffer_range: u32,
    /// `maxMemoryAllocationSize` (Vulkan 1.1): the largest single allocation.
    pub max_memory_allocation_size: u64,
    /// `maxTexelBufferElements`: the most texels a texel view may cover
    /// ([`crate::vk::Buffer::with_texel_view`]).
    pub max_texel_buffer_elements: u32,
    /// `VkPhysicalDeviceSubgroupProperties`: `supportedStages` has `COMPUTE` and
    /// `supportedOperations` has `VOTE` (`subgroupAny`; the indirect scan's walk,
    /// docs/performance.md §18).
    pub subgroup_vote_compute: bool,
}

#[cfg(test)]
impl DeviceInfo {
    /// A device for the checks' unit tests: named `test device`, every limit far above what any
    /// test scene needs, subgroup vote in compute; tests lower the one limit they check.
    pub(crate) fn roomy_test_device() -> Self {
        Self {
            name: "test device".into(),
            kind: vk::PhysicalDeviceType::CPU,
            driver: String::new(),
            api_version: (1, 3, 0),
            max_image_dimension_2d: 16384,
            timestamp_period: 1.0,
            timestamp_valid_bits: 64,
            device_local_heap_bytes: 1 << 40,
            max_storage_buffer_range: u32::MAX,
            max_memory_allocation_size: 1 << 40,
            max_texel_buffer_elements: u32::MAX,
            subgroup_vote_compute: true,
        }
    }
}

struct Messenger {
    loader: ash::ext::debug_utils::Instance,
    raw: vk::DebugUtilsMessengerEXT,
}

/// A Vulkan instance, device, queue and allocator — owned ([`Context::headless`]) or
/// borrowed from a host engine ([`Context::from_raw`]).
pub struct Context {
    entry: ash::Entry,
    instance: ash::Instance,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    queue_family: u32,
    allocator: ManuallyDrop<Arc<Mutex<Allocator>>>,
    owned: bool,
    messenger: Option<Messenger>,
    messages: Arc<Mutex<Vec<String>>>,
    debug_device: Option<ash::ext::debug_utils::Device>,
    info: DeviceInfo,
    submit: Mutex<Option<(vk::CommandPool, vk::Fence)>>,
    pipelines_created: std::sync::atomic::AtomicU64,
    submits: std::sync::atomic::AtomicU64,
    enabled: EnabledFeatures,
    pipeline_cache: vk::PipelineCache,
    /// Transfers deferred by [`Context::batched`] (creation's one submit).
    batch: Mutex<Option<Batch>>,
}

use create::{create_device, create_instance, env_flag, instance_layers};
use host::check_host_device;
pub use host::driver_hint;
use submit::Batch;
pub(crate) use submit::Deferred;

mod create;
mod host;
mod submit;

impl Context {
    /// Creates an instance and device of its own; see [`ContextOptions`] for the environment
    /// variables it reads. Works on lavapipe.
    pub fn headless() -> Result<Self> {
        Self::headless_with(&ContextOptions::default())
    }

    /// Like [`Context::headless`] with explicit options.
    pub fn headless_with(opts: &ContextOptions) -> Result<Self> {
        let validation = opts.validation.unwrap_or_else(|| env_flag("HFGI_VALIDATION"));
        let from_env = opts.device_filter.is_none();
        let filter = opts.device_filter.clone().or_else(|| std::env::var("HFGI_DEVICE").ok()).filter(|s| !s.is_empty());
        // SAFETY: loading the system Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| Error::Loader(e.to_string()))?;
        let (layer_ptrs, ext_ptrs, has_debug_utils) = instance_layers(&entry, validation)?;
        let messages: Arc<Mutex<Vec<String>>> = Arc::new(Mutex::new(Vec::new()));
        let sync = opts.sync_validation.unwrap_or_else(|| env_flag("HFGI_SYNC_VALIDATION"));
        let (instance, messenger) = create_instance(&entry, (&layer_ptrs, &ext_ptrs), validation, sync, &messages)?;

        // From here on, failures must clean up the instance.
        let cleanup = |instance: &ash::Instance, messenger: &Option<Messenger>| unsafe {
            if let Some(m) = messenger {
                m.loader.destroy_debug_utils_messenger(m.raw, None);
            }
            instance.destroy_instance(None);
        };
        let picked = match Self::pick_device(&instance, filter.as_deref(), from_env) {
            Ok(p) => p,
            Err(e) => {
                cleanup(&instance, &messenger);
                return Err(e);
            }
        };
        let (physical, family) = picked;
        let (device, queue, allocator) = match create_device(&instance, physical, family) {
            Ok(d) => d,
            Err(e) => {
                cleanup(&instance, &messenger);
                return Err(e);
            }
        };
        let debug_device = has_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        let info = Self::describe(&instance, physical, family);
        Ok(Self {
            pipelines_created: Default::default(),
            submits: Default::default(),
            enabled: EnabledFeatures { synchronization2: true, dynamic_rendering: true },
            pipeline_cache: vk::PipelineCache::null(),
            batch: Mutex::new(None),
            entry,
            instance,
            physical,
            device,
            queue,
            queue_family: family,
            allocator: ManuallyDrop::new(Arc::new(Mutex::new(allocator))),
            owned: true,
            messenger,
            messages,
            debug_device,
            info,
            submit: Mutex::new(None),
        })
    }

    /// Wraps a host engine's Vulkan objects. The device must have Vulkan 1.3 with
    /// `synchronization2` enabled (and `dynamicRendering` for the view pass,
    /// [`crate::frame::view`]), and the queue family must support compute: otherwise a typed
    /// error names what is missing ([`RawHandles::enabled`] says what the host enabled; the
    /// physical device must support it too). hfgi never destroys the instance, device,
    /// allocator or pipeline cache it was given; it destroys only the objects it created (its
    /// own command pool and fence, the first time [`Context::submit_and_wait`] runs), and
    /// dropping the `Context` never waits on the host's device (`submit_and_wait` has waited
    /// for its own work already). Validation messages are the host's business in this mode
    /// (no messenger is installed).
    pub fn from_raw(raw: RawHandles) -> Result<Self> {
        let props = unsafe { raw.instance.get_physical_device_properties(raw.physical_device) };
        if props.api_version < vk::API_VERSION_1_3 {
            return Err(Error::Unsupported(format!(
                "device API version {}.{} < 1.3",
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version)
            )));
        }
        check_host_device(&raw)?;
        let debug_device = raw.debug_utils.then(|| ash::ext::debug_utils::Device::new(&raw.instance, &raw.device));
        let info = Self::describe(&raw.instance, raw.physical_device, raw.queue_family_index);
        Ok(Self {
            pipelines_created: Default::default(),
            submits: Default::default(),
            enabled: raw.enabled,
            pipeline_cache: raw.pipeline_cache,
            batch: Mutex::new(None),
            entry: raw.entry,
            instance: raw.instance,
            physical: raw.physical_device,
            device: raw.device,
            queue: raw.queue,
            queue_family: raw.queue_family_index,
            allocator: ManuallyDrop::new(raw.allocator),
            owned: false,
            messenger: None,
            messages: Arc::new(Mutex::new(Vec::new())),
            debug_device,
            info,
            submit: Mutex::new(None),
        })
    }

    /// Names of every Vulkan 1.3 capable device (for `hfgi devices`).
    pub fn list_devices() -> Result<Vec<(String, vk::PhysicalDeviceType)>> {
        let entry = unsafe { ash::Entry::load() }.map_err(|e| Error::Loader(e.to_string()))?;
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
        let instance =
            unsafe { entry.create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None) }.map_err(
                |result| Error::NoDevice(format!("vkCreateInstance failed with {result:?}; {}", driver_hint())),
            )?;
        let out = unsafe { instance.enumerate_physical_devices() }.map(|ds| {
            ds.into_iter()
                .map(|pd| {
                    let p = unsafe { instance.get_physical_device_properties(pd) };
                    let n = p.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                    (n, p.device_type)
                })
                .collect()
        });
        unsafe { instance.destroy_instance(None) };
        out.vk("vkEnumeratePhysicalDevices")
    }

    pub fn entry(&self) -> &ash::Entry {
        &self.entry
    }
    pub fn instance(&self) -> &ash::Instance {
        &self.instance
    }
    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.physical
    }
    pub fn device(&self) -> &ash::Device {
        &self.device
    }
    pub fn queue(&self) -> vk::Queue {
        self.queue
    }
    pub fn queue_family(&self) -> u32 {
        self.queue_family
    }
    pub fn allocator(&self) -> &Arc<Mutex<Allocator>> {
        &self.allocator
    }
    /// Queue submissions hfgi has made on this context ([`Context::submit_and_wait`] is its only
    /// `vkQueueSubmit2`): an embedder compares it before and after its frames to check that
    /// hfgi did no queue work of its own (docs/integration.md).
    pub fn submit_count(&self) -> u64 {
        self.submits.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Pipelines (compute and graphics) hfgi has created on this context so far: a per-frame
    /// loop that re-created pipelines would show here.
    pub fn pipelines_created(&self) -> u64 {
        self.pipelines_created.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The pipeline cache every pipeline is created through: the host's
    /// ([`RawHandles::pipeline_cache`]) or null.
    pub fn pipeline_cache(&self) -> vk::PipelineCache {
        self.pipeline_cache
    }

    /// The features hfgi may use on this device (all of them on a headless context).
    pub fn enabled_features(&self) -> EnabledFeatures {
        self.enabled
    }

    pub(crate) fn count_pipeline(&self) {
        self.pipelines_created.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }
    /// The `VK_EXT_debug_utils` device functions, when the extension is enabled.
    pub fn debug_utils(&self) -> Option<&ash::ext::debug_utils::Device> {
        self.debug_device.as_ref()
    }

    /// Whether this context installed a validation messenger.
    pub fn validation_enabled(&self) -> bool {
        self.messenger.is_some()
    }
    /// The shared store of validation messages (also filled during destruction).
    pub fn validation_store(&self) -> Arc<Mutex<Vec<String>>> {
        self.messages.clone()
    }
    /// Validation warnings and errors collected so far (clears the list).
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.messages.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default()
    }
    /// `Err(Error::Validation)` if the validation layer reported anything since the last call.
    pub fn check_validation(&self) -> Result<()> {
        let messages = self.take_validation_messages();
        if messages.is_empty() {
            Ok(())
        } else {
            Err(Error::Validation { messages })
        }
    }

    /// Names a Vulkan object for debuggers and validation messages (no-op without debug utils).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let (Some(d), Ok(c)) = (&self.debug_device, CString::new(name)) {
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&c);
            let _ = unsafe { d.set_debug_utils_object_name(&info) };
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            // A borrowed device is the host's: hfgi's own submits have completed (each waits for
            // its fence), so there is nothing of hfgi's to wait for.
            if self.owned {
                let _ = self.device.device_wait_idle();
            }
            if let Ok(mut g) = self.submit.lock() {
                if let Some((pool, fence)) = g.take() {
                    self.device.destroy_command_pool(pool, None);
                    self.device.destroy_fence(fence, None);
                }
            }
            // Our Arc of the allocator goes first so that an owned allocator frees its memory
            // before the device is destroyed.
            ManuallyDrop::drop(&mut self.allocator);
            if self.owned {
                self.device.destroy_device(None);
                if let Some(m) = self.messenger.take() {
                    m.loader.destroy_debug_utils_messenger(m.raw, None);
                }
                self.instance.destroy_instance(None);
            }
        }
    }
}
