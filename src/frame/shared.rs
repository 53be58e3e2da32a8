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

const _: () = assert!(std::mem::size_of::<GpuLevel>() == 16);
const _: () = assert!(std::mem::size_of::<PyramidPush>() == 16);
