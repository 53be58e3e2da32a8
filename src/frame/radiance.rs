//! Stages `radiance.gather`, `radiance.decimate`, `radiance.synthesize` (NS09 §5.3;
//! docs/indirect.md §1): the multi-resolution *shade* pyramid of the previous bounce's exit
//! radiance, one scalar pyramid per RGB channel, built exactly like the height pyramid (same
//! filters and storage mode, level step `k_u`).
//!
//! Input: bounce 1's gather reads the direct exit radiance (shading planes `direct` + direct
//! glossy: the paper's scalar approximation for mixtures) into level 0; for bounce `b > 1` the
//! indirect shade of bounce `b − 1` has written that sum into level 0 itself (no gather, no
//! buffer in between). A sub-sampled scalar pyramid's level 0 is the working grid
//! ([`crate::rules::scene::radiance_base`]): the gather averages each cell's field texels, and
//! for `b > 1` it reads the total plane, where the indirect shade of bounce `b − 1` left its
//! exit radiance (the last bounce's shade writes the total there).
//! Output: the levels (and stack) buffers of [`RadiancePyramid::pyramid`], table entries with
//! `source = 1`.
//! Barriers: compute→compute after each stage.

use ash::vk;

use super::pyramid::{levels_with_tail, HeightPyramid, LevelsMemory, PyramidKind, PyramidLayout};
use super::renderer::{needs_indirect, vector_pyramid};
use super::shared::GatherPush;
use crate::constants::{PLANE_DIRECT, PLANE_TOTAL};
use crate::error::Result;
use crate::scene::model::{PyramidMode, Scene, Storage};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, Buffer, ComputePipeline, Context, Recorder};

pub const STAGE_GATHER: &str = super::stages::stage_name("radiance.gather");
pub const STAGE_DECIMATE: &str = super::stages::stage_name("radiance.decimate");
pub const STAGE_SYNTHESIZE: &str = super::stages::stage_name("radiance.synthesize");

/// The radiance pyramid kind: `channels` channels, `source = 1`, its stack in `storage`.
pub fn radiance_kind(channels: u32, storage: Storage) -> PyramidKind {
    PyramidKind {
        stack_storage: storage,
        channels,
        source: 1,
        stage_decimate: STAGE_DECIMATE,
        stage_synthesize: STAGE_SYNTHESIZE,
        label: "radiance",
    }
}

/// Channels and storage mode of a radiance pyramid: 3 channels in the scene's `mode`, or for
/// the glossy vector pyramid (`vector_n2 = Some(n²)`) `3 + 3n²` channels, always a true pyramid.
pub(crate) fn shape(mode: PyramidMode, vector_n2: Option<u32>) -> (u32, PyramidMode) {
    match vector_n2 {
        Some(n2) => (3 + 3 * n2, PyramidMode::Pyramid),
        None => (3, mode),
    }
}

/// The largest height levels buffer that sharing makes: 2^27 bytes, the smallest
/// `maxStorageBufferRange` Vulkan allows. Where the shared buffer would be larger, the two
/// pyramids keep a buffer each, so sharing never makes a buffer too large for a device that
/// took the two (a field above about 1730² at 1×, 3450² at 2×).
pub(crate) const SHARED_LEVELS_MAX: u64 = 1 << 27;

/// Whether a renderer of `scene` keeps the radiance levels in the height levels buffer, after
/// level 0 ([`LevelsMemory`]; docs/pyramid.md, "Shared levels"): both pyramids in stack mode,
/// the scalar radiance pyramid (the vector pyramid's scan reads its levels), indirect light, and
/// a shared buffer of at most [`SHARED_LEVELS_MAX`] bytes.
pub(crate) fn shares_height_levels(scene: &Scene) -> bool {
    height_levels_tail(scene).is_ok_and(|t| t > 0)
}

/// The bytes a renderer's height levels buffer keeps after level 0 for the radiance levels
/// ([`super::pyramid::PyramidBuffers::with_tail`]): three `f32` channels of the radiance
/// pyramid's levels when [`shares_height_levels`], else 0.
pub(crate) fn height_levels_tail(scene: &Scene) -> Result<u64> {
    let gi = &scene.gi;
    if gi.pyramid != PyramidMode::Stack || vector_pyramid(scene) || !needs_indirect(scene) {
        return Ok(0);
    }
    let (w, h) = crate::rules::scene::radiance_base(scene);
    let tail = PyramidLayout::new(w, h, gi.radiance_level_step)?.total * 4 * 3;
    let heights = PyramidLayout::new(scene.field.width(), scene.field.height(), gi.level_step)?;
    let shared = levels_with_tail(heights.total * 4, &heights, tail);
    Ok(if shared <= SHARED_LEVELS_MAX { tail } else { 0 })
}

/// Where the gather reads bounce 1's input (docs/indirect.md §1).
pub struct RadianceInputs<'a> {
    /// The shading planes (direct diffuse and direct glossy).
    pub shade: &'a Buffer,
    /// Incident SH radiance per texel of the direct light (vector pyramid only; any buffer
    /// otherwise).
    pub incident_direct: &'a Buffer,
    /// Whether the shading buffer has the glossy planes (`shade::planes`).
    pub glossy_planes: bool,
    /// The shading planes' texel format.
    pub format: super::shade::ShadingFormat,
    /// The shading planes' size (the field's).
    pub field: (usize, usize),
}

pub struct RadiancePyramid {
    pub pyramid: HeightPyramid,
    gather: ComputePipeline,
    set: vk::DescriptorSet,
    push: GatherPush,
}

impl RadiancePyramid {
    /// A pyramid for a `width × height` radiance image, stack at `work`. `vector_n2`:
    /// `Some(n²)` for the glossy vector pyramid (3 + 3n² channels, always a true pyramid).
    /// `stack`: the finest levels the stack keeps per channel (those the scan reads) and how it
    /// stores them (`gi.storage`). `levels`: where the levels live ([`LevelsMemory`]; a renderer
    /// puts them in its height levels buffer when [`shares_height_levels`]).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Context,
        size: (usize, usize),
        work: (usize, usize),
        k_u: u32,
        mode: PyramidMode,
        wrap: bool,
        vector_n2: Option<u32>,
        stack: (usize, Storage),
        inputs: RadianceInputs,
        levels: LevelsMemory,
    ) -> Result<Self> {
        let (channels, mode) = shape(mode, vector_n2);
        let (stack_levels, storage) = stack;
        let kind = radiance_kind(channels, storage);
        let (w, h, n) = (size.0, size.1, Some(stack_levels));
        let pyramid = HeightPyramid::with_kind(ctx, w, h, work, k_u, mode, wrap, kind, n, levels)?;
        let binds =
            [Bind::Buffer(inputs.shade), Bind::Buffer(pyramid.levels_buffer()), Bind::Buffer(inputs.incident_direct)];
        let push_size = std::mem::size_of::<GatherPush>() as u32;
        let made = ComputePipeline::with_storage_set(ctx, &shaders::RADIANCE_GATHER_COMP, push_size, &binds);
        match made {
            Ok((gather, set)) => {
                let push = GatherPush {
                    width: size.0 as u32,
                    height: size.1 as u32,
                    channel_stride: pyramid.layout().total as u32,
                    vector: vector_n2.is_some() as u32,
                    n2: vector_n2.unwrap_or(0),
                    glossy: inputs.glossy_planes as u32,
                    src_width: inputs.field.0 as u32,
                    src_height: inputs.field.1 as u32,
                    plane: PLANE_DIRECT,
                    packed: inputs.format.packed_flag(),
                    pad: [0; 2],
                };
                Ok(Self { pyramid, gather, set, push })
            }
            Err(e) => {
                pyramid.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Records bounce `bounce`'s pyramid (1-based): the gather ([`Self::gathers`]), then
    /// decimate (+ synthesize).
    pub fn record(&self, rec: &mut Recorder, bounce: u32) {
        if self.gathers(bounce) {
            self.record_gather(rec, bounce);
        }
        self.pyramid.record(rec);
    }

    /// Whether level 0 is the working grid, smaller than the field
    /// ([`crate::rules::scene::radiance_base`]): each of its texels the mean of a cell.
    pub fn on_working_grid(&self) -> bool {
        (self.push.width, self.push.height) != (self.push.src_width, self.push.src_height)
    }

    /// Whether bounce `bounce` (1-based) records `radiance.gather`: bounce 1, and on the working
    /// grid every bounce (a later bounce's from the total plane, where the previous indirect
    /// shade left its exit radiance); at full resolution that shade wrote level 0 itself.
    pub fn gathers(&self, bounce: u32) -> bool {
        bounce == 1 || self.on_working_grid()
    }

    /// Records the gather of bounce `bounce`'s input (stage `radiance.gather`): the direct
    /// planes for bounce 1, the total plane for a later one.
    pub fn record_gather(&self, rec: &mut Recorder, bounce: u32) {
        rec.scope(STAGE_GATHER, |ctx, cmd| {
            let plane = if bounce > 1 { PLANE_TOTAL } else { PLANE_DIRECT };
            let push = GatherPush { plane, ..self.push };
            let g =
                [groups(push.width, crate::constants::WORKGROUP), groups(push.height, crate::constants::WORKGROUP), 1];
            self.gather.dispatch(ctx, cmd, self.set, bytemuck::bytes_of(&push), g);
            barrier::compute_to_compute(ctx, cmd);
        });
    }

    pub fn memory_bytes(&self) -> u64 {
        self.pyramid.memory_bytes()
    }

    /// Channels per level (3, or 3 + 3n² for the vector pyramid).
    pub fn channels(&self) -> u32 {
        3 + 3 * self.push.n2
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.gather.destroy(ctx);
        self.pyramid.destroy(ctx);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::file::parse_scene;

    fn scene(overrides: &[&str]) -> Scene {
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        parse_scene("", std::path::Path::new("."), "test", &o).expect("scene")
    }

    /// Sharing needs the scalar pyramid in stack mode and indirect light, and stops where the
    /// shared buffer would pass 2^27 bytes: a 2048² field at 1× (16 MiB of heights and 164 MiB
    /// of radiance levels) keeps two buffers, the same field at 4× (10 MiB of radiance) shares.
    #[test]
    fn the_levels_are_shared_only_where_the_buffer_stays_within_2_to_the_27_bytes() {
        let base = ["gi.bounces=1", "heightfield.size=64"];
        assert!(shares_height_levels(&scene(&base)));
        assert!(!shares_height_levels(&scene(&["gi.bounces=0", "heightfield.size=64"])));
        assert!(!shares_height_levels(&scene(&[base[0], base[1], "gi.pyramid=\"pyramid\""])));
        let big = ["gi.bounces=1", "heightfield.size=2048"];
        assert!(!shares_height_levels(&scene(&big)));
        assert!(shares_height_levels(&scene(&[big[0], big[1], "gi.subsample=4"])));
        let tail = height_levels_tail(&scene(&[big[0], big[1], "gi.subsample=4"])).unwrap();
        assert!(4 * 2048 * 2048 + tail <= SHARED_LEVELS_MAX, "{tail}");
    }
}
