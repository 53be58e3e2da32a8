//! # hfgi — global illumination on dynamic height fields, Vulkan-native
//!
//! An implementation of Nowrouzezahrai & Snyder, "Fast Global Illumination on Dynamic Height
//! Fields" (EGSR 2009). Layers, each depending only on those above it:
//!
//! - [`vk`]: Vulkan plumbing (context, memory, pipelines, barriers, stage timer).
//! - [`frame`]: the GI effect as named passes that record into a caller's command buffer.
//! - [`rules`]: the pure rules the passes and the twins share (light sets, layouts, scene
//!   implications); [`math`] and [`reference`]: f64 reference math and CPU twins of every GPU
//!   stage, which import `rules`, `math` and `scene`, never `frame`.
//! - [`scene`] and [`io`]: height fields (generators, loaders) and image output.
//!
//! Conventions (coordinates, SH basis, exported values) are in `docs/conventions.md`.

/// Constants shared by the host code and the shaders, from one file (`src/constants.rs`):
/// `build.rs` includes it and defines each of [`constants::GLSL_DEFINES`] as `HFGI_<NAME>` in
/// every shader. Change a value there and both sides change together.
pub mod constants;
pub mod error;
pub mod frame;
pub mod io;
pub mod math;
pub mod progress;
pub mod reference;
pub mod rules;
pub mod scene;
pub mod shaders;
pub mod vk;

pub use error::{Error, Result};

/// The Vulkan bindings and the allocator of hfgi's public API ([`vk::RawHandles`] takes an
/// `ash::Device` and an `Arc<Mutex<gpu_allocator::vulkan::Allocator>>`): a host uses these
/// re-exports to be sure its versions are hfgi's.
pub use ash;
pub use gpu_allocator;
