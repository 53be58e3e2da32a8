//! `#[repr(C)]` mirrors of the structs in `glsl/inc/hfgi_shared.glsl`, sizes asserted at
//! compile time. Change both files together.

use bytemuck::{Pod, Zeroable};

/// `hfgi_Level`: one pyramid level inside the levels buffer (offset in floats).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuLevel {
    pub width: u32,
    pub height: u32,
    pub offset: u32,
    pub pad: u32,
}

/// `hfgi_PyramidPush`: push constants of the pyramid passes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PyramidPush {
    pub level: u32,
    pub wrap: u32,
    pub out_width: u32,
    pub out_height: u32,
}

/// `hfgi_VisibilityPush`: push constants of the visibility pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct VisibilityPush {
    pub sample_offset: u32,
    pub sample_count: u32,
    pub out_offset: u32,
    pub wrap: u32,
    pub work_width: u32,
    pub work_height: u32,
    pub level_step: u32,
    pub level_bias: u32,
    pub texel_size: f32,
    pub stack_mode: u32,
    pub pad0: u32,
    pub pad1: u32,
}

/// `hfgi_ShadePush`: push constants of the direct shading pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ShadePush {
    pub width: u32,
    pub height: u32,
    pub work_width: u32,
    pub work_height: u32,
    pub set_count: u32,
    pub wrap: u32,
    pub glossy: u32,
    pub albedo_map: u32,
    pub texel_size: f32,
    pub pad: [f32; 3],
    pub camera: [f32; 4],
    pub specular: [f32; 4],
    pub albedo: [f32; 4],
}

/// `hfgi_WaterPush`: push constants of the water step (`docs/dynamic.md`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct WaterPush {
    pub width: u32,
    pub height: u32,
    pub wrap: u32,
    pub drop_count: u32,
    /// Laplacian weight `k = speed²`.
    pub k: f32,
    /// `1 − damping`.
    pub retain: f32,
    pub rest_level: f32,
    pub scale: f32,
    /// `(x, y, amplitude, radius)` of up to 4 drops (the first `drop_count` are used).
    pub drops: [[f32; 4]; 4],
}

const _: () = assert!(std::mem::size_of::<GpuLevel>() == 16);
const _: () = assert!(std::mem::size_of::<WaterPush>() == 96);
const _: () = assert!(std::mem::size_of::<VisibilityPush>() == 48);
const _: () = assert!(std::mem::size_of::<ShadePush>() == 96);
const _: () = assert!(std::mem::size_of::<PyramidPush>() == 16);
