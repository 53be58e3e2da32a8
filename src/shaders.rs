//! Embedded SPIR-V of every shader in `glsl/`, compiled at build time by shaderc.
//!
//! Hosts can build their own pipelines from these words. Names follow the file layout:
//! `glsl/pyramid/decimate.comp.glsl` → [`PYRAMID_DECIMATE_COMP`]. Shared declarations
//! (push-constant structs, B-spline helpers) are in `glsl/inc/` and prefixed `hfgi_`.

/// One embedded SPIR-V module.
#[derive(Clone, Copy, Debug)]
pub struct Spirv {
    /// Path under `glsl/` without the `.glsl` suffix, e.g. `pyramid/decimate.comp`.
    pub name: &'static str,
    /// SPIR-V words (entry point `main`).
    pub words: &'static [u32],
}

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Finds an embedded shader by its name (e.g. `"pyramid/decimate.comp"`).
pub fn by_name(name: &str) -> Option<&'static Spirv> {
    ALL.iter().copied().find(|s| s.name == name)
}
