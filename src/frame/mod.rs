//! The GI effect as passes. Each pass is a file named after its stage, records into a
//! caller's command buffer through [`crate::vk::Recorder`] and has a CPU twin in
//! [`crate::reference`].

pub mod blockers;
pub mod indirect;
pub mod live;
pub mod local;
pub mod memory;
pub mod plan;
pub mod pyramid;
pub mod pyramid_max;
pub mod radiance;
pub mod renderer;
pub mod shade;
pub mod shared;
pub mod stages;
pub mod storage;
pub mod sweep;
pub mod transfer;
pub mod truth;
pub mod view;
pub mod visibility;
pub mod water;

pub use live::RendererOptions;
pub use plan::{Changes, FrameState, Pending, Plan, PlannedPass, PlannedStage, Planner};
pub use renderer::{Renderer, RendererStats, ShadingLayers};
pub use shade::ShadingFormat;
pub use stages::{Stage, StageInfo, STAGES};
