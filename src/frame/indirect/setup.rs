//! The indirect pass's setup: scan data and buffer sizes, the shade, the radiance pyramid, bindings.

use ash::vk;

use super::scan::PushGet;
use crate::error::Result;
use crate::frame::pyramid::{scratch_offset, HeightPyramid, LevelsMemory, PyramidLayout};
use crate::frame::pyramid_max::MaxPyramid;
use crate::frame::radiance::{RadianceInputs, RadiancePyramid};
use crate::frame::renderer::vector_pyramid;
use crate::frame::shade::ShadePass;
use crate::frame::shared::ShadePush;
use crate::reference::direct::scan_steps;
use crate::reference::indirect::radiance_level;
use crate::rules::scene::{radiance_base, replay_bytes, replays, u_coefficients};
use crate::scene::model::{PyramidMode, Scene};
use crate::shaders;
use crate::vk::pipeline::Bind;
use crate::vk::{Buffer, ComputePipeline, Context};

/// What the scan uploads, from the scene: the azimuth samples (`[cos φ, sin φ, 0, 0]`) and
/// folded wedge matrices of the first bounce's set (`gi.azimuths`) and, when later bounces use
/// fewer (`gi.azimuths_later`), of theirs after it; and the scan's step ladder for `n_v` height
/// levels (one source for the pass and [`crate::frame::memory`]).
pub(crate) struct ScanData {
    pub samples: Vec<[f32; 4]>,
    pub fold: Vec<f32>,
    pub ladder: Vec<f64>,
    /// The samples `(first, count)` of the first bounce's scan and of the later ones'.
    pub sets: [(u32, u32); 2],
}

impl ScanData {
    pub(crate) fn new(scene: &Scene, n_v: usize) -> Self {
        let gi = &scene.gi;
        let (first, later) = (gi.azimuths, gi.scan_azimuths(2));
        let later_first = later_set_first(gi);
        let (mut samples, mut fold) = (Vec::new(), Vec::new());
        for m in if later_first > 0 { vec![first, later] } else { vec![first] } {
            let set = crate::rules::lighting::environment_set(gi, m);
            samples.extend(set.phi.iter().map(|p| [p.cos() as f32, p.sin() as f32, 0.0, 0.0]));
            fold.extend(crate::frame::shared::gpu_fold(gi.sh_order, &set, gi)); // n² padded rows per sample
        }
        let sets = [(0, first), (later_first, later)];
        Self { samples, fold, ladder: scan_steps(gi, n_v), sets }
    }

    /// The radiance level of every scan sample: [`radiance_levels`] of this ladder.
    pub(crate) fn radiance_levels(&self, scene: &Scene) -> Result<Vec<u32>> {
        radiance_levels(scene, &self.ladder)
    }
}

/// The first sample of the later bounces' set among the uploaded samples ([`ScanData`]): after
/// the first bounce's `gi.azimuths` when they scan fewer (`gi.azimuths_later`; whatever
/// `gi.bounces`: a host may record more bounces), else 0 (they share the first set).
pub(crate) fn later_set_first(gi: &crate::scene::model::GiSettings) -> u32 {
    if gi.scan_azimuths(2) != gi.azimuths {
        gi.azimuths
    } else {
        0
    }
}

/// The radiance level of every step of `ladder` (docs/indirect.md §2, computed in f64): what
/// the scan uploads as `hfgi.indirect.radiance_level`.
pub(crate) fn radiance_levels(scene: &Scene, ladder: &[f64]) -> Result<Vec<u32>> {
    let gi = &scene.gi;
    // The pyramid's own level-0 grid: the ladder's steps in its texels.
    let (w, h) = radiance_base(scene);
    let n_u = PyramidLayout::new(w, h, gi.radiance_level_step)?.count();
    let n0 = w.max(h) as f64;
    let level = |tau: f64| radiance_level(n0 * tau, gi.radiance_level_step, gi.radiance_level_offset, n_u) as u32;
    Ok(ladder.iter().map(|&tau| level(tau)).collect())
}

/// The radiance stack's planes per channel: the levels the scan reads, 0 up to the coarsest in
/// `levels` ([`radiance_levels`]; the near-field limit reads level 0).
pub(crate) fn radiance_stack_levels(levels: &[u32]) -> usize {
    levels.iter().max().map_or(1, |&l| l as usize + 1)
}

/// The pass's own buffers `(name, bytes)` in creation order (each at least 16 bytes), for a
/// `work` grid and [`ScanData`] of `samples` samples, `fold` floats and `ladder` steps; the
/// recorded casting sets only with the replay ([`replays`]; else 16 bytes nothing reads).
pub(crate) fn buffer_sizes(
    scene: &Scene,
    work: (u32, u32),
    samples: usize,
    fold: usize,
    ladder: usize,
) -> [(&'static str, u64); 5] {
    // U: receivers × u_coefficients × rgb in gi.storage (glsl/inc/hfgi_store.glsl).
    let u = 3 * u_coefficients(scene);
    let u_bytes = scene.gi.storage.bytes((work.0 as u64 * work.1 as u64) * scene.gi.storage.stride(u) as u64);
    let grid = (work.0 as usize, work.1 as usize);
    let members = if replays(scene, grid, ladder) { replay_bytes(scene, grid) } else { 0 };
    [
        ("hfgi.indirect.samples", samples as u64 * 16),
        ("hfgi.indirect.fold", fold as u64 * 4),
        ("hfgi.indirect.radiance_level", ladder as u64 * 4),
        ("hfgi.indirect.u", u_bytes),
        ("hfgi.indirect.members", members),
    ]
    .map(|(name, size)| (name, size.max(16)))
}

/// The shading shader in indirect mode (`indirect.shade`).
fn shade_pipeline(ctx: &Context, scene: &Scene, next_stride: u32) -> Result<ComputePipeline> {
    let spec = crate::frame::shade::spec(scene, Some(next_stride));
    let size = std::mem::size_of::<ShadePush>() as u32;
    ComputePipeline::new(ctx, &shaders::SHADE_DIRECT_COMP, &crate::frame::shade::BINDINGS, size, &spec, 1)
}

/// The indirect shade's pipeline (pushed last to `pipes`) and its descriptor set: `U` in, the
/// shading planes and the next bounce's radiance level 0 out.
#[allow(clippy::too_many_arguments)]
pub(super) fn shade_set(
    ctx: &Context,
    scene: &Scene,
    pyramid: &HeightPyramid,
    shade: &ShadePass,
    u: &Buffer,
    rad: &RadiancePyramid,
    blockers: Option<&Buffer>,
    pipes: &mut Vec<ComputePipeline>,
) -> Result<vk::DescriptorSet> {
    let [light, triple, albedo, consts, output] = shade.bindings();
    let sh = pipes.push_get(shade_pipeline(ctx, scene, rad.pyramid.layout().total as u32)?);
    sh.allocate_set(
        ctx,
        &[
            Bind::Texel(pyramid.levels_buffer()),
            Bind::Texel(u),
            Bind::Texel(light),
            Bind::Texel(triple),
            Bind::Buffer(albedo),
            Bind::Buffer(consts),
            Bind::Buffer(output),
            Bind::Buffer(rad.pyramid.levels_buffer()), // the next bounce's level 0
            Bind::Buffer(output),                      // T of the direct mode: unused here
            Bind::Buffer(blockers.unwrap_or(output)),  // unread without spheres
            Bind::Buffer(output),                      // the spheres: unread by the bounces
        ],
    )
}

/// Bounce `b`'s radiance pyramid over the field, its stack at the working resolution `work`
/// holding the radiance levels the scan reads. Its levels go into `heights`' levels buffer after
/// level 0 where the scene allows it ([`crate::frame::radiance::shares_height_levels`]) and that
/// pyramid was created with the room for them ([`HeightPyramid::levels_room`] at least
/// [`crate::frame::radiance::height_levels_tail`]; a `Renderer` makes it so, `HeightPyramid::new` does
/// not), else into a buffer of their own.
pub(super) fn radiance_pyramid(
    ctx: &Context,
    scene: &Scene,
    heights: &HeightPyramid,
    levels: &[u32],
    shade: &ShadePass,
) -> Result<RadiancePyramid> {
    let gi = &scene.gi;
    let n = gi.sh_order;
    let (ww, wh) = heights.work();
    let work = (ww as usize, wh as usize);
    let (owner, offset) = (heights.levels_buffer(), scratch_offset(heights.layout()));
    let tail = crate::frame::radiance::height_levels_tail(scene)?;
    let room = heights.levels_room();
    let at = if tail > 0 && tail <= room && offset + tail <= owner.size && heights.mode() == PyramidMode::Stack {
        LevelsMemory::Alias { owner, offset }
    } else {
        LevelsMemory::Own { tail: 0 }
    };
    RadiancePyramid::new(
        ctx,
        radiance_base(scene),
        work,
        gi.radiance_level_step,
        gi.pyramid,
        scene.wrap,
        vector_pyramid(scene).then_some((n * n) as u32),
        (radiance_stack_levels(levels), gi.storage),
        RadianceInputs {
            shade: shade.output(),
            incident_direct: shade.incident(),
            glossy_planes: crate::frame::shade::glossy_planes(scene),
            format: shade.format(),
            field: (scene.field.width(), scene.field.height()),
        },
        at,
    )
}

pub(super) const U: usize = 3;
pub(super) const MEMBERS: usize = 4;

/// The texel views of the scan's own buffers ([`buffer_sizes`]' order): the samples and the fold
/// matrices' padded rows are `uvec4`s, the radiance levels and `U` (which the scan writes as a
/// storage buffer and the indirect shade reads through the view) 32-bit words; the recorded
/// casting sets are a storage buffer only (their view, of words, is unused).
pub(super) const BUFFER_VIEWS: [vk::Format; 5] = [
    vk::Format::R32G32B32A32_UINT,
    vk::Format::R32G32B32A32_UINT,
    vk::Format::R32_UINT,
    vk::Format::R32_UINT,
    vk::Format::R32_UINT,
];

/// The indirect scan's bindings 0–14 (glsl/indirect/scan.comp.glsl): the height levels, table
/// and stack, the radiance levels, table and stack, the buffers of [`BUFFER_VIEWS`], the
/// shading constants, the max pyramid, the radiance stack's and the height stack's planes, the
/// recorded casting sets.
pub(super) fn scan_binds<'a>(
    pyramid: &'a HeightPyramid,
    rad: &'a RadiancePyramid,
    bufs: &'a [Buffer],
    consts: &'a Buffer,
    max: Option<&'a MaxPyramid>,
) -> [Bind<'a>; 15] {
    let hstack = pyramid.stack_buffer().unwrap_or(pyramid.levels_buffer());
    let rstack = rad.pyramid.stack_buffer().unwrap_or(rad.pyramid.levels_buffer());
    [
        Bind::Texel(pyramid.levels_buffer()),
        Bind::Buffer(pyramid.table_buffer()),
        Bind::Texel(hstack),
        Bind::Texel(rad.pyramid.levels_buffer()),
        Bind::Buffer(rad.pyramid.table_buffer()),
        Bind::Texel(rstack),
        Bind::Texel(&bufs[0]),
        Bind::Texel(&bufs[1]),
        Bind::Texel(&bufs[2]),
        Bind::Buffer(&bufs[U]),
        Bind::Buffer(consts),
        // Without the bound the scan never reads binding 11: any view of 32-bit words.
        Bind::Texel(max.map_or(&bufs[1], |m| m.buffer())),
        // Pyramid mode has no stack and no planes: any view of uvec4s.
        Bind::Texel(rad.pyramid.stack_planes_buffer().unwrap_or(&bufs[0])),
        Bind::Texel(pyramid.height_planes()),
        Bind::Buffer(&bufs[MEMBERS]),
    ]
}
