// Constants shared by the host code and the shaders (module docs: `pub mod constants` in
// src/lib.rs). No `use`, no crate paths and no inner doc comments: `build.rs` `include!`s this
// file on its own.

/// Largest SH order `n` of the shaders' fixed arrays (`hfgi_klm[n²]`, the ZH band factors).
pub const MAX_SH_ORDER: u32 = 8;
/// Side of the 2D compute workgroups (`local_size_x = local_size_y`).
pub const WORKGROUP: u32 = 8;
/// Size of the 1D compute workgroups (the line sweep, the pyramid probe).
pub const WORKGROUP_1D: u32 = 64;

/// Planes of the shading buffer (RGB `f32` triples per texel, each `W × H`): the exported
/// layers (CONVENTIONS.md) total, direct, indirect, glossy, then the glossy light of the direct
/// light and of the bounces (their sum is the glossy layer). A surface without specular has
/// only the first [`PLANES_DIFFUSE`].
pub const PLANE_TOTAL: u32 = 0;
pub const PLANE_DIRECT: u32 = 1;
pub const PLANE_INDIRECT: u32 = 2;
pub const PLANE_GLOSSY: u32 = 3;
pub const PLANE_GLOSSY_DIRECT: u32 = 4;
pub const PLANE_GLOSSY_INDIRECT: u32 = 5;
/// Planes in the shading buffer of a glossy surface (`material.specular` set).
pub const PLANES: u32 = 6;
/// Planes in the shading buffer of a diffuse surface: total, direct, indirect.
pub const PLANES_DIFFUSE: u32 = 3;

/// `ShadePush::next_mode`: where the indirect shade writes its bounce's exit radiance, the next
/// bounce's input (docs/indirect.md §1). Level 0 of the radiance pyramid (full-resolution base).
pub const NEXT_LEVEL0: u32 = 0;
/// The total plane, which `radiance.gather` averages to the working grid (working-grid base; a
/// bounce that is not the last: the last one writes the total there).
pub const NEXT_TOTAL: u32 = 1;
/// Nowhere (working-grid base, the last bounce).
pub const NEXT_NONE: u32 = 2;

/// Entries per order of the optimal-linear SH exponentiation's `a`, `b` tables
/// (`math::shexp::OL_POINTS`, checked equal there).
pub const OL_POINTS: u32 = 49;

/// Gauss–Legendre nodes in elevation for the Phong lobe over a local light's visible window
/// on each azimuth slice (`shade.local_lights`' glossy light).
pub const LOCAL_GLOSSY_NODES: u32 = 6;

/// Intervals of the moment-matched log-ZH table in `u = 1 − cos Θ` (`math::logcap`).
pub const MATCHED_INTERVALS: u32 = 256;
/// With the matched log-ZH a receiver inside a sphere gets the constant log `−MATCHED_BLOCKED`
/// (`e^{−30} ≈ 1e-13`: blocked).
pub const MATCHED_BLOCKED: u32 = 30;

/// `(name, value, unsigned)` of each constant the shaders see, as `#define HFGI_<name>
/// <value>` (with a `u` suffix when `unsigned`: the plane indices multiply `uint`s).
pub const GLSL_DEFINES: &[(&str, u32, bool)] = &[
    ("MAX_SH_ORDER", MAX_SH_ORDER, false),
    ("WORKGROUP", WORKGROUP, false),
    ("WORKGROUP_1D", WORKGROUP_1D, false),
    ("PLANE_TOTAL", PLANE_TOTAL, true),
    ("PLANE_DIRECT", PLANE_DIRECT, true),
    ("PLANE_INDIRECT", PLANE_INDIRECT, true),
    ("PLANE_GLOSSY", PLANE_GLOSSY, true),
    ("PLANE_GLOSSY_DIRECT", PLANE_GLOSSY_DIRECT, true),
    ("PLANE_GLOSSY_INDIRECT", PLANE_GLOSSY_INDIRECT, true),
    ("PLANES", PLANES, true),
    ("PLANES_DIFFUSE", PLANES_DIFFUSE, true),
    ("NEXT_LEVEL0", NEXT_LEVEL0, true),
    ("NEXT_TOTAL", NEXT_TOTAL, true),
    ("NEXT_NONE", NEXT_NONE, true),
    ("OL_POINTS", OL_POINTS, false),
    ("MATCHED_INTERVALS", MATCHED_INTERVALS, false),
    ("LOCAL_GLOSSY_NODES", LOCAL_GLOSSY_NODES, true),
    ("MATCHED_BLOCKED", MATCHED_BLOCKED, false),
];
