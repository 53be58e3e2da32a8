//! Image output: OpenEXR layers, 8-bit PNG previews and animated GIFs, each written atomically
//! ([`atomic`]).
pub mod atomic;
pub mod exr;
pub mod gif;
pub mod png;
