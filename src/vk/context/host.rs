//! [`Context::from_raw`]'s checks of the host's device, and the no-driver hint.

use ash::vk;

use super::{EnabledFeatures, RawHandles};
use crate::error::{Error, Result};

/// [`Context::from_raw`]'s checks: Vulkan 1.3, `synchronization2` enabled and supported,
/// `dynamicRendering` supported where the host says it enabled it, a compute queue family.
pub(super) fn check_host_device(raw: &RawHandles) -> Result<()> {
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
    unsafe { raw.instance.get_physical_device_features2(raw.physical_device, &mut f2) };
    let supported = EnabledFeatures::from_vulkan13(&f13);
    let missing = |what: &str, why: &str| {
        Error::Unsupported(format!(
            "the host's device was created without {what} (VkPhysicalDeviceVulkan13Features), which {why}; \
             enable it in VkDeviceCreateInfo and say so in RawHandles::enabled"
        ))
    };
    if !raw.enabled.synchronization2 {
        return Err(missing("synchronization2", "every barrier hfgi records needs"));
    }
    for (name, enabled, has) in [
        ("synchronization2", raw.enabled.synchronization2, supported.synchronization2),
        ("dynamicRendering", raw.enabled.dynamic_rendering, supported.dynamic_rendering),
    ] {
        if enabled && !has {
            return Err(Error::Unsupported(format!(
                "RawHandles::enabled says {name} is enabled, but the physical device does not support it"
            )));
        }
    }
    let families = unsafe { raw.instance.get_physical_device_queue_family_properties(raw.physical_device) };
    let flags = families.get(raw.queue_family_index as usize).map(|f| f.queue_flags);
    if !flags.is_some_and(|f| f.contains(vk::QueueFlags::COMPUTE)) {
        return Err(Error::Unsupported(format!(
            "queue family {} of the host's device {}: hfgi records compute work and needs a compute queue",
            raw.queue_family_index,
            if flags.is_some() { "has no compute support" } else { "does not exist" }
        )));
    }
    Ok(())
}

/// What to check when the Vulkan loader finds no driver (`ERROR_INCOMPATIBLE_DRIVER`,
/// `ERROR_OUT_OF_HOST_MEMORY` from a broken manifest, or no device): the driver manifest
/// variables and whether the files they name exist.
pub fn driver_hint() -> String {
    let mut parts = Vec::new();
    for var in ["VK_DRIVER_FILES", "VK_ICD_FILENAMES"] {
        if let Ok(v) = std::env::var(var) {
            let files: Vec<String> = std::env::split_paths(&v)
                .map(|p| {
                    let state = if p.is_file() { "exists" } else { "missing" };
                    format!("{} ({state})", p.display())
                })
                .collect();
            parts.push(format!("{var} = {}", files.join(", ")));
        }
    }
    let pinned = if parts.is_empty() {
        "no driver manifest is pinned (VK_DRIVER_FILES unset)".to_string()
    } else {
        format!("the driver manifest is pinned by {}", parts.join("; "))
    };
    format!(
        "{pinned}; check that it names an installed driver's JSON manifest (lavapipe: \
         /usr/share/vulkan/icd.d/lvp_icd.x86_64.json from mesa-vulkan-drivers), or unset it to let the \
         loader search /usr/share/vulkan/icd.d; `hfgi devices` lists what the loader finds"
    )
}
