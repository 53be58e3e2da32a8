//! Image output: OpenEXR layers, 8-bit PNG previews and animated GIFs.
pub mod exr;
pub mod gif;
pub mod png;
