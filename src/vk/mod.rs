//! Vulkan plumbing: the only module that touches raw Vulkan. Everything above it (passes, the
//! GI effect, the CLI) goes through these types.

pub mod barrier;
pub mod context;
pub mod graphics;
pub mod memory;
pub mod pipeline;
pub mod recorder;
pub mod staging;
pub mod timer;

pub use ash;
pub use ash::vk as raw;
pub use context::{Context, ContextOptions, DeviceInfo, EnabledFeatures, RawHandles};
pub use graphics::GraphicsPipeline;
pub use memory::{Buffer, Image};
pub use pipeline::{ComputePipeline, DescriptorKind};
pub use recorder::Recorder;
pub use staging::{RingKind, StagingRing};
pub use timer::StageTimer;
