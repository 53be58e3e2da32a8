//! Image output: OpenEXR layers and 8-bit PNG previews.
pub mod exr;
pub mod png;
