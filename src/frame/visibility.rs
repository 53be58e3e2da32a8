//! Stages `visibility.environment` and `visibility.key_lights` (NS09 §5.2, §6; docs/direct.md
//! §1–4): the SH visibility vector `V` (n² floats) of each light set at every receiver of the
//! working grid.
//!
//! Output: [`VisibilityPass::buffer`], `f32`, laid out `[set][receiver y][receiver x][k < n²]`.
//! Sets: the environment first (when the scene has one), then each key light in order.
//! After `record`, a compute→compute barrier has been recorded.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::shared::{
    azimuth_chunks, VisibilityPush, FLAG_ACCUMULATE, FLAG_MAX_BOUND, FLAG_SWEEP, VISIBILITY_LOOP_BUDGET,
};
use super::sweep::{SweepPass, SweepPlan};
use crate::error::Result;
use crate::math::azimuth::AzimuthSet;
use crate::math::elevation;
pub use crate::rules::lighting::{has_environment, light_sets, SetKind};
use crate::scene::model::{PyramidMode, Scene, Storage, VisibilityMethod};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

pub const STAGE_ENVIRONMENT: &str = super::stages::stage_name("visibility.environment");
pub const STAGE_KEY_LIGHTS: &str = super::stages::stage_name("visibility.key_lights");

pub(crate) struct SetRange {
    kind: SetKind,
    first: u32,
    count: u32,
}

/// What the pass uploads, computed in f64 from the scene: the azimuth samples
/// (`[cos φ, sin φ, lo, hi]`), the folded wedge matrices `A_j` and each set's sample range.
pub(crate) struct VisibilityData {
    pub samples: Vec<[f32; 4]>,
    pub fold: Vec<f32>,
    pub sets: Vec<SetRange>,
}

impl VisibilityData {
    pub(crate) fn new(scene: &Scene) -> Self {
        Self::for_sets(scene, &light_sets(scene))
    }

    /// The data of `sets` only (in buffer order), e.g. the key lights' sets after they moved.
    pub(crate) fn for_sets(scene: &Scene, sets: &[(SetKind, AzimuthSet)]) -> Self {
        let n = scene.gi.sh_order;
        let mut data = Self { samples: Vec::new(), fold: Vec::new(), sets: Vec::new() };
        for (kind, set) in sets {
            let first = data.samples.len() as u32;
            for &phi in &set.phi {
                data.samples.push([phi.cos() as f32, phi.sin() as f32, set.lo as f32, set.hi as f32]);
            }
            data.fold.extend(super::shared::gpu_fold(n, set, &scene.gi));
            data.sets.push(SetRange { kind: *kind, first, count: set.phi.len() as u32 });
        }
        data
    }
}

/// The line sweep's split for `scene` (`gi.visibility = "sweep"` with some light set), else None.
pub(crate) fn sweep_plan(scene: &Scene) -> Option<SweepPlan> {
    let sets = light_sets(scene);
    let max_set = sets.iter().map(|(_, s)| s.phi.len()).max()?;
    (scene.gi.visibility == VisibilityMethod::Sweep).then(|| {
        let (w, h) = (scene.field.width(), scene.field.height());
        SweepPlan::new((w, h), scene.gi.working_size(w, h), max_set)
    })
}

/// The pass's buffers `(name, bytes)` in creation order, for `samples` azimuth samples, `fold`
/// floats of folded matrices and `sets` light sets on a `work` grid with `n2` coefficients
/// (one source for the pass and [`crate::frame::memory`]); the sweep's follow with
/// `gi.visibility = "sweep"` ([`SweepPlan::buffer_sizes`]).
pub(crate) fn buffer_sizes(
    samples: usize,
    fold: usize,
    sets: usize,
    work: (usize, usize),
    n2: usize,
    storage: Storage,
) -> [(&'static str, u64); 3] {
    let vis_values = (sets.max(1) * work.0 * work.1 * storage.stride(n2)) as u64;
    [
        ("hfgi.visibility.samples", (samples.max(1) * 16) as u64),
        ("hfgi.visibility.fold", (fold.max(1) * 4) as u64),
        ("hfgi.visibility.v", storage.bytes(vis_values)),
    ]
}

/// The visibility pass and its buffers.
pub struct VisibilityPass {
    pipeline: ComputePipeline,
    descriptors: vk::DescriptorSet,
    samples: Buffer,
    fold: Buffer,
    vis: Buffer,
    sets: Vec<SetRange>,
    n: usize,
    /// `gi.storage` of `V`.
    storage: Storage,
    push: VisibilityPush,
    /// Loop iterations per azimuth (ladder + n²·e; n²·e with the sweep), for the azimuth chunks.
    loop_cost: u32,
    /// Where the key lights' sets begin: in the samples (index) and in the fold (floats).
    key_offsets: (u64, u64),
    /// `gi.visibility = "sweep"`: the line sweep feeding the horizons.
    sweep: Option<SweepPass>,
}

/// The visibility shader's bindings (glsl/visibility/visibility.comp.glsl): texel views of what
/// it reads per sample or azimuth (docs/performance.md §17); the level table, read per
/// receiver, and `V`, written, are storage buffers.
const BINDINGS: [DescriptorKind; 9] = {
    let mut k = [DescriptorKind::TexelBuffer; 9];
    k[1] = DescriptorKind::StorageBuffer;
    k[5] = DescriptorKind::StorageBuffer;
    k
};

/// The visibility scan's push constants (`sweeps`: the sweep's horizons serve the far field;
/// `bounded`: the scan reads the max pyramid and stops each ray early, docs/performance.md §34).
fn visibility_push(pyramid: &HeightPyramid, scene: &Scene, sweeps: bool, bounded: bool) -> VisibilityPush {
    let (ww, wh) = pyramid.work();
    VisibilityPush {
        wrap: pyramid.wrap() as u32,
        work_width: ww,
        work_height: wh,
        level_step: scene.gi.level_step,
        level_bias: scene.gi.level_step * scene.gi.level_offset,
        texel_size: scene.texel_size as f32,
        stack_mode: (pyramid.mode() == PyramidMode::Stack) as u32,
        flags: super::shared::scan_flags(&scene.gi)
            | if sweeps { FLAG_SWEEP } else { 0 }
            | if bounded && !sweeps { FLAG_MAX_BOUND } else { 0 }
            | super::shared::raw_plane_flags(pyramid.raw_plane0(), false),
        sweep_near: scene.gi.sweep_near as f32,
        scan_extent: super::shared::scan_extent(&scene.gi),
        ..Default::default()
    }
}

/// The loop iterations of a receiver's ray, per azimuth (the near field's pieces with the sweep,
/// hfgi_near_slope's guard; the ladder's samples without), plus the fold's multiply-adds.
fn loop_cost(scene: &Scene, pyramid: &HeightPyramid, sweep: bool) -> u32 {
    let n = scene.gi.sh_order;
    let walk = if sweep {
        4 * scene.gi.sweep_near as usize + 8
    } else {
        crate::reference::direct::scan_steps(&scene.gi, pyramid.layout().count()).len()
    };
    (walk + n * n * elevation::gpu_size(scene.gi.elevation_basis, n)) as u32
}

impl VisibilityPass {
    /// Builds the pass for `scene` reading `pyramid`. The azimuth samples and the folded wedge
    /// matrices `A_j` are computed here in f64 and uploaded. With `max` (the max pyramid's
    /// buffer, [`super::pyramid_max::MaxPyramid::buffer`], recorded before this pass whenever the
    /// heights change) the scan stops each ray where no farther sample can raise its horizon.
    pub fn new(ctx: &Context, pyramid: &HeightPyramid, scene: &Scene, max: Option<&Buffer>) -> Result<Self> {
        let n = scene.gi.sh_order;
        let n2 = n * n;
        let (ww, wh) = pyramid.work();
        let VisibilityData { samples, fold, sets } = VisibilityData::new(scene);
        let env = sets.iter().filter(|s| s.kind == SetKind::Environment).map(|s| s.count as u64).sum::<u64>();
        let key_offsets = (env, env * (fold.len() as u64) / (samples.len().max(1) as u64));
        let storage = scene.gi.storage;
        let sizes = buffer_sizes(samples.len(), fold.len(), sets.len(), (ww as usize, wh as usize), n2, storage);
        let mut parts: Vec<Buffer> = Vec::new();
        let mut pipeline = None;
        let mut sweep = None;
        let max_set = sets.iter().map(|s| s.count as usize).max().unwrap_or(0);
        let sweeps = scene.gi.visibility == VisibilityMethod::Sweep && max_set > 0;
        let push = visibility_push(pyramid, scene, sweeps, max.is_some());
        let made = (|| -> Result<vk::DescriptorSet> {
            Self::create_buffers(ctx, &mut parts, sizes, &samples, &fold)?;
            if sweeps {
                sweep = Some(SweepPass::new(ctx, pyramid, &parts[0], scene, max_set)?);
            }
            let p = pipeline.insert(Self::create_pipeline(ctx, pyramid, scene, &push)?);
            let stack = pyramid.stack_buffer().unwrap_or(pyramid.levels_buffer());
            p.allocate_set(
                ctx,
                &[
                    Bind::Texel(pyramid.levels_buffer()),
                    Bind::Buffer(pyramid.table_buffer()),
                    Bind::Texel(stack),
                    Bind::Texel(&parts[0]),
                    Bind::Texel(&parts[1]),
                    Bind::Buffer(&parts[2]),
                    // Without the sweep, never read: any view of words.
                    Bind::Texel(sweep.as_ref().map_or(&parts[1], |s: &SweepPass| s.horizons())),
                    Bind::Texel(pyramid.height_planes()),
                    // Without the early stop, never read: any view of words.
                    Bind::Texel(max.unwrap_or(&parts[1])),
                ],
            )
        })();
        let descriptors = match made {
            Ok(d) => d,
            Err(e) => {
                parts.into_iter().for_each(|b| b.destroy(ctx));
                pipeline.into_iter().for_each(|mut p| p.destroy(ctx));
                sweep.into_iter().for_each(|s| s.destroy(ctx));
                return Err(e);
            }
        };
        let vis = parts.pop().expect("v");
        let fold_buf = parts.pop().expect("fold");
        let samples_buf = parts.pop().expect("samples");
        Ok(Self {
            pipeline: pipeline.expect("pipeline"),
            descriptors,
            samples: samples_buf,
            fold: fold_buf,
            vis,
            sets,
            n,
            storage,
            push,
            loop_cost: loop_cost(scene, pyramid, sweep.is_some()),
            sweep,
            key_offsets,
        })
    }

    /// Creates the samples, fold and `V` buffers of `sizes` into `parts` (which the caller
    /// destroys on an error) and uploads `samples` and `fold` (when there are samples).
    fn create_buffers(
        ctx: &Context,
        parts: &mut Vec<Buffer>,
        sizes: [(&'static str, u64); 3],
        samples: &[[f32; 4]],
        fold: &[f32],
    ) -> Result<()> {
        let usage = crate::vk::memory::PASS_BUFFER_USAGE;
        // Texel views (docs/performance.md §17): the samples and the fold's padded rows as
        // uvec4s (§19), V as words (written here as a storage buffer, read by shade.direct through the view).
        let views = [vk::Format::R32G32B32A32_UINT, vk::Format::R32G32B32A32_UINT, vk::Format::R32_UINT];
        for ((name, size), view) in sizes.into_iter().zip(views) {
            parts.push(Buffer::new(ctx, name, size, usage, MemoryLocation::GpuOnly)?.with_texel_view(ctx, view)?);
        }
        if !samples.is_empty() {
            memory::upload(ctx, &parts[0], 0, bytemuck::cast_slice(samples))?;
            memory::upload_f32(ctx, &parts[1], 0, fold)?;
        }
        Ok(())
    }

    /// The visibility pipeline, specialised for `scene`'s order, the pyramid's levels and the
    /// static modes of `push`.
    fn create_pipeline(
        ctx: &Context,
        pyramid: &HeightPyramid,
        scene: &Scene,
        push: &VisibilityPush,
    ) -> Result<ComputePipeline> {
        let n = scene.gi.sh_order;
        ComputePipeline::new(
            ctx,
            &shaders::VISIBILITY_VISIBILITY_COMP,
            &BINDINGS,
            std::mem::size_of::<VisibilityPush>() as u32,
            &[
                &[
                    (0, n as u32),
                    (1, pyramid.layout().count() as u32),
                    (2, elevation::gpu_size(scene.gi.elevation_basis, n) as u32),
                ][..],
                &super::shared::static_modes(3, push.stack_mode, push.wrap, push.flags),
                &[(6, scene.gi.storage.spec()), (7, super::shared::fold_texels(n, scene.gi.elevation_basis))],
            ]
            .concat(),
            1,
        )
    }

    /// The samples and fold of the key lights' sets as `(buffer, byte offset, bytes)` for
    /// `vkCmdUpdateBuffer` (the live inputs, docs/integration.md §2); `data` holds those sets
    /// only ([`VisibilityData::for_sets`]), as many as at creation.
    pub(crate) fn key_light_updates(&self, data: &VisibilityData) -> [(vk::Buffer, u64, Vec<u8>); 2] {
        let keys = self.sets.iter().filter(|s| s.kind != SetKind::Environment).map(|s| s.count as usize).sum::<usize>();
        debug_assert_eq!(data.samples.len(), keys, "key-light samples");
        [
            (self.samples.raw, self.key_offsets.0 * 16, bytemuck::cast_slice(&data.samples).to_vec()),
            (self.fold.raw, self.key_offsets.1 * 4, bytemuck::cast_slice(&data.fold).to_vec()),
        ]
    }

    /// Records one dispatch per light set, inside the stage scopes.
    pub fn record(&self, rec: &mut Recorder) {
        self.record_sets(rec, true);
        self.record_sets(rec, false);
    }

    /// Records the environment set (stage `visibility.environment`) or the key-light sets
    /// (stage `visibility.key_lights`); nothing when there are no such sets.
    pub fn record_sets(&self, rec: &mut Recorder, environment: bool) {
        let receivers = self.push.work_width * self.push.work_height;
        let stride = self.storage.stride(self.n * self.n) as u32;
        let groups = [
            groups(self.push.work_width, crate::constants::WORKGROUP),
            groups(self.push.work_height, crate::constants::WORKGROUP),
            1,
        ];
        let stage = if environment { STAGE_ENVIRONMENT } else { STAGE_KEY_LIGHTS };
        let chosen: Vec<(usize, &SetRange)> =
            self.sets.iter().enumerate().filter(|(_, s)| (s.kind == SetKind::Environment) == environment).collect();
        if chosen.is_empty() {
            return;
        }
        rec.scope(stage, |ctx, cmd| {
            let mut swept = false;
            for (i, s) in &chosen {
                // With the sweep, chunks of azimuths whose horizons fit its buffer; else one.
                let sweep_chunk = self.sweep.as_ref().map_or(s.count, |w| w.plan().chunk);
                for (hfirst, hcount) in azimuth_chunks(s.count, 1, sweep_chunk) {
                    if let Some(w) = &self.sweep {
                        if swept {
                            // The previous chunk's or set's projection read the horizons
                            // (write-after-read, found by synchronization validation).
                            barrier::compute_to_compute(ctx, cmd);
                        }
                        w.record(ctx, cmd, s.first + hfirst, hcount);
                        swept = true;
                    }
                    // Azimuth chunks against lavapipe's loop limit; later ones accumulate into V.
                    for (c, (first, count)) in
                        azimuth_chunks(hcount, self.loop_cost, VISIBILITY_LOOP_BUDGET).iter().enumerate()
                    {
                        let later = hfirst + first > 0;
                        if c > 0 {
                            barrier::compute_to_compute(ctx, cmd);
                        }
                        let push = VisibilityPush {
                            sample_offset: s.first + hfirst + first,
                            sample_count: *count,
                            out_offset: *i as u32 * receivers * stride,
                            flags: self.push.flags | if later { FLAG_ACCUMULATE } else { 0 },
                            horizon_first: s.first + hfirst,
                            ..self.push
                        };
                        self.pipeline.dispatch(ctx, cmd, self.descriptors, bytemuck::bytes_of(&push), groups);
                    }
                }
            }
            barrier::compute_to_compute(ctx, cmd);
        });
    }

    /// Number of light sets (the first dimension of [`VisibilityPass::buffer`]).
    pub fn set_count(&self) -> usize {
        self.sets.len()
    }
    /// What each set is, in buffer order.
    pub fn set_kinds(&self) -> Vec<SetKind> {
        self.sets.iter().map(|s| s.kind).collect()
    }
    /// The V vectors of all sets: sets × receivers × `n²` values in `gi.storage` (f32 words, or
    /// halves two to a word with each receiver padded to an even count; glsl/inc/hfgi_store.glsl).
    pub fn buffer(&self) -> &Buffer {
        &self.vis
    }
    /// Reads the V vectors of set `i` back (`receivers × n²` floats whatever `gi.storage`; waits).
    pub fn read(&self, ctx: &Context, i: usize) -> Result<Vec<f32>> {
        let receivers = (self.push.work_width * self.push.work_height) as usize;
        super::storage::download_vectors(ctx, &self.vis, self.storage, i * receivers, receivers, self.n * self.n)
    }
    /// Bytes of GPU memory held.
    pub fn memory_bytes(&self) -> u64 {
        self.samples.size + self.fold.size + self.vis.size + self.sweep.as_ref().map_or(0, SweepPass::memory_bytes)
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.samples.destroy(ctx);
        self.fold.destroy(ctx);
        self.vis.destroy(ctx);
        if let Some(s) = self.sweep {
            s.destroy(ctx);
        }
    }
}
