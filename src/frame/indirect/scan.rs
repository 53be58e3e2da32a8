//! The indirect scan's pipelines (stage `indirect.scan`, glsl/indirect/scan.comp.glsl): their
//! kinds (what each compiles in), specialization constants, bindings, push constants and azimuth
//! chunks. The pass itself is [`super::IndirectPass`].

use ash::vk;

use crate::error::Result;
use crate::frame::radiance::RadiancePyramid;
use crate::frame::renderer::vector_pyramid;
use crate::frame::shared::{azimuth_chunks, IndirectPush, INDIRECT_LOOP_BUDGET};
use crate::math::elevation;
use crate::rules::scene::{replay_stride, u_coefficients};
use crate::scene::model::{PyramidMode, Scene};
use crate::shaders;
use crate::vk::pipeline::Bind;
use crate::vk::{ComputePipeline, Context, DescriptorKind};

/// The scan's push constants at creation (per dispatch, `record_scan` sets the azimuth chunk,
/// the probes and the dynamic flags); their modes are also its specialization constants.
pub(super) fn scan_push(
    scene: &Scene,
    (ww, wh): (u32, u32),
    sample_count: u32,
    rad: &RadiancePyramid,
    raw_planes: u32,
) -> IndirectPush {
    let gi = &scene.gi;
    let k = scene.material.specular.unwrap_or([0.0; 3]);
    IndirectPush {
        work_width: ww,
        work_height: wh,
        wrap: scene.wrap as u32,
        level_step: gi.level_step,
        level_bias: gi.level_step * gi.level_offset,
        texel_size: scene.texel_size as f32,
        stack_mode: (gi.pyramid == PyramidMode::Stack) as u32,
        sample_count,
        radiance_levels: rad.pyramid.layout().count() as u32,
        radiance_stack: (rad.pyramid.mode() == PyramidMode::Stack) as u32,
        flags: crate::frame::shared::scan_flags(gi) | raw_planes,
        scan_extent: crate::frame::shared::scan_extent(gi),
        specular: [k[0], k[1], k[2], 0.0],
        sample_offset: 0,
        probes: gi.probes(1),
        radiance_planes: rad.pyramid.stack_levels() as u32,
        radiance_scale: 1.0, // IndirectPass::set_pre_exposure
    }
}

/// What a scan pipeline compiles in (specialization constants 11 and 12 of
/// `glsl/indirect/scan.comp.glsl`): the radial probes, and its part in the replay of the later
/// bounces' casting sets. lavapipe runs code on every lane whether a uniform flag skips it or not
/// (docs/performance.md §12, §17). The max-pyramid bound is no longer a kind (§18): it is the
/// early stop alone, a comparison per sample, and every bounce of a pass with the max pyramid
/// stops early (`HFGI_FLAG_MAX_BOUND`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct ScanKind {
    pub probes: bool,
    pub replay: Replay,
    /// The cast merge (`GiSettings::merge`; specialization constant 16).
    pub merge: bool,
}

/// A scan's part in the replay (`rules::scene::replays`, docs/indirect.md §2): none (every
/// bounce walks), the first bounce's walk that also records the later bounces' casting sets, or
/// a later bounce that casts them without walking.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Replay {
    Off = 0,
    Record = 1,
    Cast = 2,
}

impl ScanKind {
    /// The kind that scans a bounce with `probes` radial probes and the cast merge or not
    /// exactly and fastest, without the replay.
    pub fn of(probes: u32, merge: bool) -> Self {
        Self { probes: probes > 0, replay: Replay::Off, merge }
    }

    /// Whether a pipeline of this kind scans a bounce of kind `k` exactly: probes are a dynamic
    /// count (probe code with 0 probes scans none); compiled-out code cannot run, and the
    /// merge's angle is a constant of the pipeline.
    pub fn serves(self, k: ScanKind) -> bool {
        (self.probes || !k.probes) && self.replay == k.replay && self.merge == k.merge
    }
}

/// The device capability the scan's walk needs (docs/performance.md §18, docs/integration.md):
/// `subgroupAny` in compute shaders (`VK_SUBGROUP_FEATURE_VOTE_BIT` in `supportedOperations`,
/// `COMPUTE` in `supportedStages`), which every Vulkan 1.3 GPU driver and lavapipe report.
pub(crate) fn check_subgroup_vote(info: &crate::vk::DeviceInfo) -> Result<()> {
    if info.subgroup_vote_compute {
        return Ok(());
    }
    Err(crate::error::Error::Unsupported(format!(
        "{}: the indirect scan needs subgroup vote operations (subgroupAny) in compute shaders \
         (VkPhysicalDeviceSubgroupProperties: VOTE in supportedOperations, COMPUTE in supportedStages); \
         render without indirect light (gi.bounces = 0) on this device",
        info.name
    )))
}

/// The scan pipelines a scene gets: the first bounce's kind and, when later bounces differ,
/// theirs: when the scene has later bounces, or when the first's pipeline could not scan one
/// (a bounce past `gi.bounces` takes the first otherwise, which scans it exactly).
/// With `replay` ([`crate::rules::scene::replays`]) the first bounce's walk records the later
/// bounces' casting sets and they cast them (their pipeline has no walk).
pub(super) fn scan_kinds(scene: &Scene, replay: bool) -> Vec<ScanKind> {
    let gi = &scene.gi;
    let merges = [1, 2].map(|b| gi.merge(b) > 0.0);
    if replay {
        let first = ScanKind { replay: Replay::Record, ..ScanKind::of(gi.probes(1), merges[0]) };
        // The later bounces cast every member (`GiSettings::merge`): the replay has no merge.
        return vec![first, ScanKind { probes: false, replay: Replay::Cast, merge: false }];
    }
    let first = ScanKind::of(gi.probes(1), merges[0]);
    let later = ScanKind::of(gi.probes(2), merges[1]);
    // With one bounce, a bounce past it (recorded by a host) takes the first bounce's pipeline
    // when its code can scan it, with the first bounce's merge: no pipeline only for that.
    let past = ScanKind { merge: first.merge, ..later };
    if later != first && (gi.bounces > 1 || !first.serves(past)) {
        vec![first, later]
    } else {
        vec![first]
    }
}

/// The scan's specialization constants (`glsl/indirect/scan.comp.glsl`) for `n_v` height levels
/// and the creation push `push`: the probes' code compiled in or out by `kind`.
pub(super) fn scan_spec(scene: &Scene, n_v: usize, push: &IndirectPush, kind: ScanKind) -> Vec<(u32, u32)> {
    let gi = &scene.gi;
    let n = gi.sh_order;
    let own = [
        (0, n as u32),
        (1, n_v as u32),
        (2, vector_pyramid(scene) as u32),
        (3, elevation::gpu_size(gi.elevation_basis, n) as u32),
        (7, push.radiance_stack),
        (8, gi.storage.spec()),
        (10, u_coefficients(scene) as u32),
        (11, kind.probes as u32),
        (12, kind.replay as u32),
        (13, crate::frame::shared::fold_texels(n, gi.elevation_basis)),
        // The later set within the first (rules::scene::replay_stride) and its first sample.
        (14, replay_stride(scene).unwrap_or(1)),
        (15, super::setup::later_set_first(gi)),
        // The cast merge δ of the first bounce as tan δ, an f32 constant (0: off, compiled out).
        (16, if kind.merge { (gi.cast_merge.tan() as f32).to_bits() } else { 0 }),
    ];
    [&own[..], &crate::frame::shared::static_modes(4, push.stack_mode, push.wrap, push.flags)].concat()
}

/// Azimuth chunks `(first, count)` of the first bounce's scan and of the later ones' over their
/// sample sets ([`super::ScanData`]'s sets), against lavapipe's loop limit.
pub(super) fn scan_chunks(
    gi: &crate::scene::model::GiSettings,
    ladder: usize,
    sets: [(u32, u32); 2],
) -> [Vec<(u32, u32)>; 2] {
    let (n, e) = (gi.sh_order, elevation::gpu_size(gi.elevation_basis, gi.sh_order));
    [(gi.probes(1), sets[0]), (gi.probes(2), sets[1])].map(|(p, (first, count))| {
        // A member adds an outer iteration of the scan's while-while loop and an e-vector.
        let cost = ladder * (1 + p as usize) * (e + 1) + n * n * e;
        let chunks = azimuth_chunks(count, cost as u32, INDIRECT_LOOP_BUDGET);
        chunks.into_iter().map(|(f, c)| (first + f, c)).collect()
    })
}

/// The scan's pipelines of `kinds` (pushed to `pipes`, which owns them on every exit) and their
/// descriptor sets over `binds`.
pub(super) fn scan_pipelines(
    ctx: &Context,
    scene: &Scene,
    n_v: usize,
    push: &IndirectPush,
    kinds: &[ScanKind],
    binds: &[Bind],
    pipes: &mut Vec<ComputePipeline>,
) -> Result<Vec<vk::DescriptorSet>> {
    let mut sets = Vec::new();
    for &kind in kinds {
        let spec = scan_spec(scene, n_v, push, kind);
        let size = std::mem::size_of::<IndirectPush>() as u32;
        let scan = ComputePipeline::new(ctx, &shaders::INDIRECT_SCAN_COMP, &SCAN_BINDINGS, size, &spec, 1)?;
        sets.push(pipes.push_get(scan).allocate_set(ctx, binds)?);
    }
    Ok(sets)
}

/// The scan's bindings (glsl/indirect/scan.comp.glsl): storage buffers but for the texel
/// buffers it reads per sample (docs/performance.md §17).
pub(super) const SCAN_BINDINGS: [DescriptorKind; 15] = {
    let mut k = [DescriptorKind::TexelBuffer; 15];
    k[1] = DescriptorKind::StorageBuffer; // the level tables and the shading constants: read per receiver
    k[4] = DescriptorKind::StorageBuffer;
    k[9] = DescriptorKind::StorageBuffer; // U: written
    k[10] = DescriptorKind::StorageBuffer;
    k[14] = DescriptorKind::StorageBuffer; // the recorded casting sets: written by bounce 1, read by the later ones
    k
};

pub(super) trait PushGet<T> {
    fn push_get(&mut self, v: T) -> &mut T;
}

impl<T> PushGet<T> for Vec<T> {
    fn push_get(&mut self, v: T) -> &mut T {
        self.push(v);
        self.last_mut().expect("just pushed")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device without subgroup vote in compute is refused by name, before any GPU work
    /// (`render` and `plan` through `memory::check_device`, an embedding through
    /// `IndirectPass::new`); a scene without indirect light does not need it.
    #[test]
    fn a_device_without_subgroup_vote_is_refused_for_indirect_light() {
        let mut scene = crate::scene::file::default_scene().expect("default scene");
        scene.gi.bounces = 1;
        let mut info =
            crate::vk::DeviceInfo { subgroup_vote_compute: false, ..crate::vk::DeviceInfo::roomy_test_device() };
        let err = crate::frame::memory::check_device(&scene, &info).expect_err("no vote").to_string();
        assert!(err.contains("test device") && err.contains("subgroupAny") && err.contains("gi.bounces = 0"), "{err}");
        scene.gi.bounces = 0;
        crate::frame::memory::check_device(&scene, &info).expect("no indirect light, no scan");
        scene.gi.bounces = 1;
        info.subgroup_vote_compute = true;
        crate::frame::memory::check_device(&scene, &info).expect("vote in compute");
    }

    /// The pipelines a scene gets (docs/performance.md §12, §17, §18, §33): `default` without
    /// the cast merge and with 2 bounces a probing first one and a bare second; one bounce,
    /// only the first; probes in the later bounces only, both even with one bounce (a bounce past
    /// `gi.bounces` needs the probes' code, which the first lacks). Every kind serves itself, and
    /// only the probing kind serves the other. The merge (bounce 1 only) is a kind of its own:
    /// a merging first bounce and a bare later one; with one bounce the first alone.
    #[test]
    fn scan_kinds_cover_every_bounce_with_code_it_runs() {
        let mut s = crate::scene::file::default_scene().expect("default scene");
        s.gi.cast_merge = 0.0;
        s.gi.bounces = 2;
        let (probing, bare) = (ScanKind::of(1, false), ScanKind::of(0, false));
        assert_eq!(scan_kinds(&s, false), vec![probing, bare]);
        s.gi.bounces = 1;
        assert_eq!(scan_kinds(&s, false), vec![probing]);
        (s.gi.radial_probes, s.gi.radial_probes_later) = (0, 1);
        assert_eq!(scan_kinds(&s, false), vec![bare, probing]);
        (s.gi.radial_probes, s.gi.radial_probes_later) = (0, 0);
        s.gi.bounces = 3;
        assert_eq!(scan_kinds(&s, false), vec![bare]);
        // The replay: a recording first bounce (with its probes) and a casting later one.
        s.gi.radial_probes = 2;
        let record = ScanKind { probes: true, replay: Replay::Record, merge: false };
        let cast = ScanKind { probes: false, replay: Replay::Cast, merge: false };
        assert_eq!(scan_kinds(&s, true), vec![record, cast]);
        assert!(!record.serves(cast) && !cast.serves(record) && !probing.serves(record));
        for a in [probing, bare] {
            assert!(a.serves(a) && probing.serves(a), "{a:?}");
        }
        assert!(!bare.serves(probing));
        // The cast merge: in the first bounce's kind only.
        s.gi.cast_merge = 0.01;
        let merging = ScanKind::of(1, true);
        assert_eq!(scan_kinds(&s, true), vec![ScanKind { merge: true, ..record }, cast]);
        assert_eq!(scan_kinds(&s, false), vec![merging, bare]);
        s.gi.bounces = 1;
        assert_eq!(scan_kinds(&s, false), vec![merging]);
        assert!(!merging.serves(bare) && !merging.serves(probing) && !probing.serves(merging));
        assert!(!bare.serves(probing));
    }
}
