//! `#[repr(C)]` mirrors of the structs in `glsl/inc/hfgi_shared.glsl`, sizes asserted at
//! compile time and every field's offset checked against the header's std430 layout by the
//! test at the end of this file (it parses the header). Change both files together.

use bytemuck::{Pod, Zeroable};

pub use crate::rules::layout::GpuLevel;

/// `hfgi_PyramidPush`: push constants of the pyramid passes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PyramidPush {
    /// Decimate: the level written; synthesize: `stack_levels | n_v << 16`; probe: the mode.
    pub level: u32,
    pub wrap: u32,
    pub out_width: u32,
    pub out_height: u32,
    /// Synthesize into an f16 stack: the pre-exposure its values are stored at
    /// ([`crate::frame::storage::pre_exposure`]); 1 otherwise.
    pub scale: f32,
    /// Synthesize: 1 when plane 0 holds level 0's own values (`HeightPyramid::set_raw_plane0`).
    pub flags: u32,
}

/// `HFGI_FLAG_RAW_LEVEL0` (glsl/inc/hfgi_pyramid.glsl): level 0 read as the bilinear surface.
pub const FLAG_RAW_LEVEL0: u32 = 1;
/// `HFGI_FLAG_HORIZON_SAMPLES`: `ω_max` is the largest blocking angle.
pub const FLAG_HORIZON_SAMPLES: u32 = 2;
/// `HFGI_FLAG_TANGENT`: `ω_min` is the exact tangent elevation.
pub const FLAG_TANGENT: u32 = 4;

/// `HFGI_FLAG_ACCUMULATE`: add to the output instead of overwriting it (azimuth chunks).
pub const FLAG_ACCUMULATE: u32 = 8;
/// `HFGI_FLAG_MAX_BOUND`: the indirect and visibility scans stop each ray where nothing farther
/// can rise above its horizon, by the max pyramid's top (stage `pyramid.max`;
/// docs/performance.md §18, §34).
pub const FLAG_MAX_BOUND: u32 = 16;
/// `HFGI_FLAG_SWEEP`: the visibility pass reads `ω_max` from the line sweep's horizons.
pub const FLAG_SWEEP: u32 = 32;
/// `HFGI_FLAG_RAW_PLANE0`: the height stack's plane 0 holds level 0's own values
/// ([`crate::frame::pyramid::HeightPyramid::set_raw_plane0`]), so a scan reads level 0 through
/// the stack like every other level: one read path per sample (docs/performance.md §17).
pub const FLAG_RAW_PLANE0: u32 = 64;
/// `HFGI_FLAG_RAW_RPLANE0`: the same of the radiance stack (the indirect scan).
pub const FLAG_RAW_RPLANE0: u32 = 128;

/// `HFGI_FLAG_TANGENT_CLIP`: the visibility window starts no lower than the receiver's tangent
/// elevation (`gi.diffuse_lobe = "exact"`: `V` zero below the tangent plane; docs/accuracy.md §6).
pub const FLAG_TANGENT_CLIP: u32 = 256;

/// The static flags of scans reading `heights` (and `radiance`) whose stacks' plane 0 holds
/// level 0's own values.
pub fn raw_plane_flags(heights: bool, radiance: bool) -> u32 {
    (if heights { FLAG_RAW_PLANE0 } else { 0 }) | if radiance { FLAG_RAW_RPLANE0 } else { 0 }
}

/// The flags that change between the dispatches of one pipeline (`HFGI_DYNAMIC_FLAGS`); every
/// other bit is fixed when the pipeline is created and reaches the shader as a specialization
/// constant too ([`static_modes`]).
pub const DYNAMIC_FLAGS: u32 = FLAG_ACCUMULATE | FLAG_MAX_BOUND;

/// Specialization constants `first_id`, `first_id + 1`, `first_id + 2` of a scanning shader: the
/// storage mode (1: stack), periodic addressing and the static flags — the same values as the
/// push constants' `stack_mode`, `wrap` and `flags` (minus [`DYNAMIC_FLAGS`]). lavapipe executes
/// both sides of a branch even on a uniform value, so a path that the pipeline never takes (the
/// true pyramid's B-spline reads in stack mode, periodic addressing, the other ω_min) cost as
/// much as the one it takes; as constants, the compiler removes them (docs/performance.md §5).
pub fn static_modes(first_id: u32, stack_mode: u32, wrap: u32, flags: u32) -> [(u32, u32); 3] {
    [(first_id, stack_mode), (first_id + 1, wrap), (first_id + 2, flags & !DYNAMIC_FLAGS)]
}

/// Loop iterations one invocation of the visibility pass may run per dispatch, counted as
/// `ladder + n²·e` per azimuth (the scan, then the fold `A_j v_j`; `e` values per azimuth,
/// `math::elevation::gpu_size`). Loops the compiler unrolls (constant trip counts) do not count;
/// the budget leaves room for those it does not.
/// lavapipe silently ends an invocation's loops after 65535 iterations in total
/// (docs/accuracy.md §1).
pub const VISIBILITY_LOOP_BUDGET: u32 = 40_000;
/// The same for the indirect scan, counted as `ladder · (e + 1) + n² · e` per azimuth (every
/// casting-set member adds an iteration of the outer loop and an `e`-vector, then the fold; the
/// ladder counts each radial probe): 16 azimuths × 130 samples × 21 (44k)
/// was measured intact, 128 × 130 × 21 lost most of the indirect light, and so did order 8 when
/// each member still evaluated the 36 legendre integrals (8 × 36 loop iterations a member).
pub const INDIRECT_LOOP_BUDGET: u32 = 40_000;

/// The folded wedge matrices `A_j` of `set` as the scan shaders read them, f32, one block per
/// azimuth, each block zero-padded to whole `vec4`s (the shaders read them through an
/// `R32G32B32A32` view, docs/performance.md §19). NLP basis: the `n²` rows of `e` values,
/// each padded to whole `vec4`s. Legendre basis: only the entries that can be non-zero, row by
/// row, those of [`math::elevation::fold_support`](crate::math::elevation::fold_support) in its
/// order (`glsl/inc/hfgi_fold.glsl`; the others are zero to rounding: a fifth of the reads and
/// multiply-adds, docs/performance.md §22).
pub fn gpu_fold(n: usize, set: &crate::math::azimuth::AzimuthSet, gi: &crate::scene::model::GiSettings) -> Vec<f32> {
    use crate::math::{azimuth, elevation};
    use crate::scene::model::ElevationBasis;
    let basis = gi.elevation_basis;
    let e = elevation::gpu_size(basis, n);
    let supports = elevation::fold_supports(n); // the same rows at every azimuth
    azimuth::fold(n, set, gi.interpolation, basis)
        .into_iter()
        .flat_map(|a| {
            let a = elevation::fold_to_moments(basis, n, a);
            debug_assert_eq!(a.data.len(), n * n * e);
            let mut block: Vec<f32> = if basis == ElevationBasis::Legendre {
                a.data
                    .chunks(e)
                    .zip(&supports)
                    .flat_map(|(row, support)| support.iter().map(|&c| row[c] as f32))
                    .collect()
            } else {
                let e4 = e.div_ceil(4) * 4;
                a.data
                    .chunks(e)
                    .flat_map(|row| row.iter().map(|&v| v as f32).chain(std::iter::repeat(0.0)).take(e4))
                    .collect()
            };
            block.resize(block.len().div_ceil(4) * 4, 0.0);
            debug_assert_eq!(block.len(), 4 * fold_texels(n, basis) as usize);
            block
        })
        .collect()
}

/// The `vec4` texels of one azimuth's block of [`gpu_fold`] (the shaders' `HFGI_FOLD_SIZE`).
pub fn fold_texels(n: usize, basis: crate::scene::model::ElevationBasis) -> u32 {
    use crate::math::elevation;
    let entries = if basis == crate::scene::model::ElevationBasis::Legendre {
        elevation::fold_supports(n).iter().map(Vec::len).sum()
    } else {
        n * n * elevation::gpu_size(basis, n).div_ceil(4) * 4
    };
    entries.div_ceil(4) as u32
}

/// Splits `count` azimuth samples into chunks `(first, count)` of at most `budget / cost`
/// samples each (at least one; `cost` loop iterations per azimuth), one dispatch each, the later
/// ones accumulating.
pub fn azimuth_chunks(count: u32, cost: u32, budget: u32) -> Vec<(u32, u32)> {
    let per = (budget / cost.max(1)).max(1);
    (0..count.div_ceil(per)).map(|c| (c * per, per.min(count - c * per))).collect()
}

/// The `FLAG_*` bits of a scene's accuracy settings (docs/accuracy.md §4).
pub fn scan_flags(gi: &crate::scene::model::GiSettings) -> u32 {
    use crate::scene::model::{DiffuseLobe, Horizon, Level0, OmegaMin};
    let mut f = 0;
    if gi.level0 == Level0::Bilinear {
        f |= FLAG_RAW_LEVEL0;
    }
    if gi.horizon == Horizon::Samples {
        f |= FLAG_HORIZON_SAMPLES;
    }
    if gi.omega_min == OmegaMin::Tangent {
        f |= FLAG_TANGENT;
    }
    if gi.diffuse_lobe == DiffuseLobe::Exact {
        f |= FLAG_TANGENT_CLIP;
    }
    f
}

/// `near_steps | far_steps << 16`: the scan samples before the ladder's first and past its last.
pub fn scan_extent(gi: &crate::scene::model::GiSettings) -> u32 {
    gi.near_steps | (gi.far_steps() << 16)
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
    /// `FLAG_*` bits (docs/accuracy.md §4).
    pub flags: u32,
    /// `near_steps | far_steps << 16` ([`scan_extent`]).
    pub scan_extent: u32,
    /// With [`FLAG_SWEEP`]: the sample whose horizons start the horizons buffer.
    pub horizon_first: u32,
    /// With [`FLAG_SWEEP`]: `gi.sweep_near`, the texels marched along each receiver's own ray.
    pub sweep_near: f32,
    pub pad1: u32,
    pub pad2: u32,
}

/// `hfgi_SweepPush`: push constants of the line sweep (`glsl/visibility/sweep.comp.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SweepPush {
    pub sample_offset: u32,
    pub sample_count: u32,
    pub line_first: u32,
    pub line_count: u32,
    pub work_width: u32,
    pub work_height: u32,
    pub stack_mode: u32,
    pub flags: u32,
    pub texel_size: f32,
    pub hull_capacity: u32,
    /// `gi.sweep_near`: the far field starts this many texels ahead.
    pub reach: f32,
    pub pad1: u32,
}

/// `hfgi_LocalPush`: push constants of the local lights' shading (`shade.local_lights`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LocalPush {
    pub width: u32,
    pub height: u32,
    /// Local-light slots.
    pub light_count: u32,
    /// `gi.local_light_azimuths`.
    pub azimuths: u32,
    pub texel_size: f32,
    pub albedo_map: u32,
    /// 1: the material has a Phong lobe (glossy light of the local lights).
    pub glossy: u32,
    /// Phong exponent S.
    pub exponent: f32,
    pub albedo: [f32; 4],
    /// Phong `k_s` (rgb).
    pub specular: [f32; 4],
    /// The camera (the glossy view vector), high f32 part …
    pub camera: [f32; 4],
    /// … and the low part (`camera + camera_lo` = the f64 position).
    pub camera_lo: [f32; 4],
}

/// `hfgi_BlockerPush`: push constants of the sphere blockers' visibility (`visibility.blockers`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct BlockerPush {
    pub width: u32,
    pub height: u32,
    pub work_width: u32,
    pub work_height: u32,
    /// Sphere slots.
    pub sphere_count: u32,
    /// Nodes of the exponentiation's quadrature.
    pub quad_count: u32,
    pub texel_size: f32,
    /// `ln ε`.
    pub log_eps: f32,
    /// 1: ratio attenuation.
    pub ratio: u32,
    /// Log mode: first float of the environment set's `V` in the visibility buffer.
    pub env_offset: u32,
    /// Spacing of the OL tables.
    pub ol_step: f32,
    /// Primal mode: entries of the SH triple-product table.
    pub triple_count: u32,
    /// `log_brdf`: the camera (the Phong lobe's view vector) as a high f32 part …
    pub camera: [f32; 4],
    /// … and the low part (`camera + camera_lo` = the f64 position).
    pub camera_lo: [f32; 4],
    /// `log_brdf`: `√(4π/(2l+1))` times the log-SH Phong lobe's ZH (`shexp::log_phong_zh`),
    /// bands `0..MAX_SH_ORDER`.
    pub log_phong: [f32; 8],
}

const _: () = assert!(crate::constants::MAX_SH_ORDER == 8, "BlockerPush::log_phong holds MAX_SH_ORDER bands");

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
    /// Indirect mode: 1 adds the bounce to the indirect planes, 0 overwrites them.
    pub accumulate: u32,
    /// Sphere slots (binding 10), for the key lights' shadows.
    pub sphere_count: u32,
    /// 1: key lights are shadowed by the exact cap overlap with the spheres (`gi.blocker_key_lights`).
    pub key_overlap: u32,
    /// Indirect mode: the pre-exposure `U` is stored at ([`crate::frame::storage::pre_exposure`]);
    /// the shade reads `U / u_scale`. 1 in direct mode.
    pub u_scale: f32,
    /// Indirect mode: where the exit radiance goes ([`crate::constants::NEXT_LEVEL0`], `NEXT_TOTAL`,
    /// `NEXT_NONE`).
    pub next_mode: u32,
    pub pad: [u32; 2],
    /// Camera position, split as `camera + camera_lo` (two f32 per coordinate, the f64
    /// position to ~48 bits) so that the view vector `(camera − P) + camera_lo` keeps its
    /// precision when the heights are far from 0 (docs/hard-cases.md).
    pub camera: [f32; 4],
    pub specular: [f32; 4],
    pub albedo: [f32; 4],
    /// The low part of the camera position (see `camera`).
    pub camera_lo: [f32; 4],
}

/// `hfgi_IndirectPush`: push constants of the indirect scan (`indirect.scan`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct IndirectPush {
    pub work_width: u32,
    pub work_height: u32,
    pub wrap: u32,
    pub level_step: u32,
    pub level_bias: u32,
    pub texel_size: f32,
    pub stack_mode: u32,
    pub sample_count: u32,
    /// Radiance-pyramid levels per channel `n_u`.
    pub radiance_levels: u32,
    /// 1: the radiance pyramid is a stack (scalar mode with `gi.pyramid = stack`).
    pub radiance_stack: u32,
    /// `FLAG_*` bits (docs/accuracy.md §4).
    pub flags: u32,
    /// `near_steps | far_steps << 16` ([`scan_extent`]).
    pub scan_extent: u32,
    /// Phong `k_s` (rgb, 0): the vector pyramid's glossy lobe.
    pub specular: [f32; 4],
    /// First azimuth sample of this dispatch ([`azimuth_chunks`]).
    pub sample_offset: u32,
    /// `gi.radial_probes`: level-0 probes between two ladder samples.
    pub probes: u32,
    /// Radiance stack planes per channel ([`crate::frame::pyramid::HeightPyramid::stack_levels`]):
    /// channel `c` of radiance level `l` is stack plane `c·radiance_planes + l`.
    pub radiance_planes: u32,
    /// The pre-exposure of the f16 radiance stack and `U` ([`crate::frame::storage::pre_exposure`]):
    /// the scan divides what it reads from the stack by it and multiplies `U` by it when it stores.
    pub radiance_scale: f32,
}

/// `hfgi_GatherPush`: push constants of `radiance.gather`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GatherPush {
    pub width: u32,
    pub height: u32,
    /// Floats per channel in the radiance levels buffer (`PyramidLayout::total`).
    pub channel_stride: u32,
    /// 1: vector pyramid (diffuse only in channels 0–2, incident SH in channels 3…).
    pub vector: u32,
    /// `n²` SH coefficients per texel of the incident buffers.
    pub n2: u32,
    /// 1: the shading buffer has the glossy planes (`shade::planes`), and bounce 1 adds the
    /// direct glossy plane (scalar pyramid).
    pub glossy: u32,
    /// The shading planes' size (the field's); `width × height` is level 0's, the working grid
    /// when it is smaller ([`crate::rules::scene::radiance_base`]): each level-0 texel is then
    /// the mean of the field texels in its cell.
    pub src_width: u32,
    pub src_height: u32,
    /// The shading plane read (`PLANE_DIRECT` for bounce 1; `PLANE_TOTAL` for a later bounce of
    /// a working-grid pyramid, where the previous indirect shade left its exit radiance).
    pub plane: u32,
    /// 1: RGBE shading planes (`shade::ShadingFormat::Rgbe`; `hfgi_plane.glsl`).
    pub packed: u32,
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<IndirectPush>() == 80);
const _: () = assert!(std::mem::offset_of!(IndirectPush, specular) == 48);
const _: () = assert!(std::mem::offset_of!(IndirectPush, sample_offset) == 64);
const _: () = assert!(std::mem::offset_of!(IndirectPush, probes) == 68);
const _: () = assert!(std::mem::offset_of!(VisibilityPush, flags) == 40);
const _: () = assert!(std::mem::offset_of!(VisibilityPush, horizon_first) == 48);
const _: () = assert!(std::mem::size_of::<VisibilityPush>() == 64);
const _: () = assert!(std::mem::size_of::<SweepPush>() == 48);
const _: () = assert!(std::mem::offset_of!(SweepPush, texel_size) == 32);
const _: () = assert!(std::mem::offset_of!(SweepPush, hull_capacity) == 36);
const _: () = assert!(std::mem::offset_of!(SweepPush, reach) == 40);
const _: () = assert!(std::mem::offset_of!(VisibilityPush, sweep_near) == 52);
const _: () = assert!(std::mem::size_of::<GatherPush>() == 48);

/// `hfgi_ViewPush`: push constants of the view raster pass (vertex stage).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ViewPush {
    /// Eye-relative world → clip, column-major (`mat4`): the view-projection with the eye at the
    /// origin. The vertex shader applies it to `(P − eye) − eye_lo` (docs/view.md).
    pub view_proj: [[f32; 4]; 4],
    pub width: u32,
    pub height: u32,
    pub texel_size: f32,
    /// 1: RGBE shading planes (`shade::ShadingFormat::Rgbe`; `hfgi_plane.glsl`).
    pub packed: u32,
    /// The eye position as a high and a low f32 (`eye + eye_lo` = the f64 position), so that
    /// vertices far from 0 (heights near 1e7) keep their precision relative to the eye.
    pub eye: [f32; 4],
    pub eye_lo: [f32; 4],
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

/// `hfgi_TruthPush`: push constants of the ground-truth reference (`src/frame/truth.rs`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TruthPush {
    pub width: u32,
    pub height: u32,
    pub wrap: u32,
    pub azimuths: u32,
    pub step: f32,
    pub texel_size: f32,
    pub sh_visibility: u32,
    pub indirect: u32,
    pub row_offset: u32,
    pub rows: u32,
    /// This dispatch integrates azimuths `[azimuth_first, azimuth_first + azimuth_count)`.
    pub azimuth_first: u32,
    pub azimuth_count: u32,
    /// 1: march at `step`; 0: exact intersection with the bilinear patches.
    pub march: u32,
    /// 1: the dispatch integrates the key light `cap_*` over the cap-sample buffer's entries
    /// `[azimuth_first, azimuth_first + azimuth_count)` (exact reference, direct light);
    /// 2: the local light `local_*` over its per-receiver samples `[azimuth_first,
    /// azimuth_first + azimuth_count)` (both variants, direct light); 3: the sphere blockers'
    /// blocked parts over their flattened per-receiver samples `[azimuth_first,
    /// azimuth_first + azimuth_count)` of `[0, S·max(azimuths, local_nodes))` (both variants,
    /// direct light; spheres in binding 7).
    pub cap: u32,
    /// 1: add to the output buffer; 0: overwrite it (the first dispatch of a pass).
    pub accumulate: u32,
    /// Local light or sphere blocker: azimuth samples of a cap holding no pole (the cap
    /// buffer's first `local_nodes` entries, `(sin u, π/2·w·cos u)`).
    pub local_nodes: u32,
    /// Key light: unit direction, `cos α` in `w`.
    pub cap_dir: [f32; 4],
    /// Key light: RGB radiance, `sin α` in `w`; local light: RGB radiance.
    pub cap_radiance: [f32; 4],
    /// Local light: centre, high f32 part (`xyz`); radius (`w`).
    pub local_centre: [f32; 4],
    /// Local light: centre minus the high part (`xyz`): the f64 centre split in two f32.
    pub local_lo: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<TruthPush>() == 128);
const _: () = assert!(std::mem::size_of::<GpuLevel>() == 20);
const _: () = assert!(std::mem::size_of::<WaterPush>() == 96);
const _: () = assert!(std::mem::size_of::<ShadePush>() == 128);
const _: () = assert!(std::mem::size_of::<LocalPush>() == 96);
const _: () = assert!(std::mem::size_of::<BlockerPush>() == 112);
const _: () = assert!(std::mem::size_of::<PyramidPush>() == 24);
const _: () = assert!(std::mem::size_of::<ViewPush>() == 112);

#[cfg(test)]
mod layout_against_glsl;
