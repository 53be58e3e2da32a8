//! Stage `pyramid`: the multi-resolution height pyramid (NS09 §5.2 and §9; SN08).
//!
//! Level 0 is the input field. Level `i` has `round(N · 2^(−i/k_v))` samples per axis and is
//! level `i−1` bilinearly decimated (texel-centre aligned). Levels: `n_v = ⌊k_v·log2(max(Nx,Ny))⌋ + 1`,
//! so the coarsest level has one or two samples. Two storage modes:
//!
//! - [`PyramidMode::Stack`] (the paper's): every level is resampled back to the working
//!   resolution with a cubic B-spline (Sigg & Hadwiger's bilinear-tap form) into a stack of
//!   full-resolution planes; later passes sample it bilinearly. The stack holds the finest
//!   `stack_levels ≤ n_v` levels of each channel: a renderer keeps only those its scans read
//!   (with the level offset they never read the coarsest ones; `sizes::scan_stack_levels`).
//! - [`PyramidMode::Pyramid`] (the paper's future work, §10): only the decimated levels are
//!   kept, and later passes evaluate the cubic B-spline on the fly.
//!
//! Buffers, not images: levels are packed in one storage buffer (`f32`, row-major, offsets in
//! [`PyramidLayout`]); the stack is a second buffer of up to `n_v` planes per channel. After
//! [`HeightPyramid::record`] a compute→compute barrier has been recorded, so later compute
//! passes may read both; for transfer reads add [`crate::vk::barrier::compute_to_transfer`].
//! Before it, the caller's writes to level 0 (by transfer or compute) are made visible by a
//! barrier the pass records itself.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::shared::PyramidPush;
use crate::error::{Error, Result};
pub use crate::rules::layout::PyramidLayout;
use crate::scene::model::Storage;
use crate::scene::HeightField;
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

/// The pyramid passes' push-constant bytes (`hfgi_PyramidPush`).
const PUSH_SIZE: u32 = std::mem::size_of::<PyramidPush>() as u32;

/// Stage names (timestamp scopes and debug labels).
pub const STAGE_DECIMATE: &str = super::stages::stage_name("pyramid.decimate");
pub const STAGE_SYNTHESIZE: &str = super::stages::stage_name("pyramid.synthesize");

pub use crate::scene::model::PyramidMode;

mod readback;
mod sizes;

pub(crate) use sizes::{buffer_name, height_stack_levels, height_stack_of, table_entries, PyramidBuffers};
pub(crate) use sizes::{levels_with_tail, scratch_offset, synthesizes_pairs};
pub use sizes::{LevelsMemory, PyramidKind};

/// The levels buffer where `at` says ([`LevelsMemory`]), with its texel view (`R32_UINT`).
fn create_levels(
    ctx: &Context,
    name: &str,
    bytes: u64,
    usage: vk::BufferUsageFlags,
    at: LevelsMemory,
) -> Result<Buffer> {
    let buffer = match at {
        LevelsMemory::Own { .. } => Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly)?,
        LevelsMemory::Alias { owner, offset } => Buffer::aliasing(ctx, name, bytes, usage, owner, offset)?,
    };
    buffer.with_texel_view(ctx, vk::Format::R32_UINT)
}

/// The height pyramid pass and its buffers. The same pass builds the RGB radiance pyramid
/// ([`PyramidKind`] with 3 channels): channel `c` of level `i` is table entry `c·n_v + i`, at
/// float offset `c·total + offset_i`, and (for `i < stack_levels`) stack plane
/// `c·stack_levels + i`.
pub struct HeightPyramid {
    layout: PyramidLayout,
    stack_levels: usize,
    kind: PyramidKind,
    origin: f32,
    /// The pre-exposure of an f16 stack (its synthesis stores values times it; 1 with f32).
    stack_scale: f32,
    /// Plane 0 of the stack holds level 0's own values ([`HeightPyramid::set_raw_plane0`]).
    raw_plane0: bool,
    /// Bytes reserved after level 0 for another pyramid's levels ([`LevelsMemory::Own`]).
    room: u64,
    mode: PyramidMode,
    wrap: bool,
    work: (u32, u32),
    levels: Buffer,
    table: Buffer,
    stack: Option<Buffer>,
    /// The stack planes' table (`PyramidBuffers::planes`), with the stack.
    planes: Option<Buffer>,
    /// Its entries: `[width, height, offset, 0]` per plane, then the channel stride.
    plane_table: Vec<[u32; 4]>,
    decimate: ComputePipeline,
    synthesize: Option<ComputePipeline>,
    decimate_set: vk::DescriptorSet,
    synthesize_set: vk::DescriptorSet,
}

impl HeightPyramid {
    /// Allocates the buffers and pipelines for a `width × height` field whose stack (stack mode)
    /// is synthesized at the working resolution `work` (the visibility grid; `(width, height)`
    /// without sub-sampling), every level of it.
    pub fn new(
        ctx: &Context,
        width: usize,
        height: usize,
        work: (usize, usize),
        k_v: u32,
        mode: PyramidMode,
        wrap: bool,
    ) -> Result<Self> {
        let (kind, own) = (PyramidKind::HEIGHTS, LevelsMemory::Own { tail: 0 });
        Self::with_kind(ctx, width, height, work, k_v, mode, wrap, kind, None, own)
    }

    /// [`HeightPyramid::new`] for any [`PyramidKind`], with a stack of the finest
    /// `stack_levels` levels per channel (`None`: all; only levels below it may be read from
    /// the stack), its levels where `at` says ([`LevelsMemory`]: a buffer of its own, possibly
    /// with room for another pyramid's levels after level 0, or inside another's buffer).
    #[allow(clippy::too_many_arguments)]
    pub fn with_kind(
        ctx: &Context,
        width: usize,
        height: usize,
        work: (usize, usize),
        k_v: u32,
        mode: PyramidMode,
        wrap: bool,
        kind: PyramidKind,
        stack_levels: Option<usize>,
        at: LevelsMemory,
    ) -> Result<Self> {
        let max = ctx.info().max_image_dimension_2d as usize;
        let sizes = PyramidBuffers::new(width, height, work, k_v, mode, kind, stack_levels, Some(max))?;
        let sizes = match at {
            LevelsMemory::Own { tail } => sizes.with_tail(tail),
            LevelsMemory::Alias { .. } => sizes.aliased(),
        };
        let mut parts = Parts::default();
        let made = parts.make(ctx, kind, &sizes, at);
        match (made, parts) {
            (
                Ok(()),
                Parts {
                    levels: Some(levels),
                    table: Some(table),
                    decimate: Some(decimate),
                    stack,
                    planes,
                    synthesize,
                    sets,
                },
            ) => Ok(Self {
                layout: sizes.layout,
                stack_levels: sizes.stack_levels,
                kind,
                origin: 0.0,
                stack_scale: 1.0,
                raw_plane0: false,
                room: at.room(),
                mode,
                wrap,
                work: (work.0 as u32, work.1 as u32),
                levels,
                table,
                stack,
                planes,
                plane_table: sizes.planes.unwrap_or_default(),
                decimate,
                synthesize,
                decimate_set: sets.0,
                synthesize_set: sets.1,
            }),
            (made, parts) => {
                parts.destroy(ctx);
                Err(made.err().unwrap_or_else(|| Error::Unsupported("pyramid construction".into())))
            }
        }
    }

    /// Copies `field` into level 0 (through a staging buffer; waits). Engines that produce
    /// heights on the GPU instead write `f32`s to [`HeightPyramid::levels_buffer`] at offset 0.
    pub fn upload(&self, ctx: &Context, field: &HeightField) -> Result<()> {
        let l0 = self.layout.levels[0];
        if field.width() != l0.width as usize || field.height() != l0.height as usize {
            return Err(Error::param(
                "height field size",
                format!("{}×{}", field.width(), field.height()),
                format!("{}×{} (the size this pyramid was created for)", l0.width, l0.height),
            ));
        }
        memory::upload_f32(ctx, &self.levels, 0, field.data())
    }

    /// Sets the origin `z0`: level 0 (every channel) is read as `value − z0`, so every other
    /// level, the stack and every lookup hold values relative to `z0` while level 0 keeps what
    /// the caller wrote (docs/pyramid.md, "Origin"). Uploads the level table (waits); takes
    /// effect at the next [`HeightPyramid::record`]. A renderer sets the midrange of its heights
    /// ([`crate::frame::renderer::height_origin`]); the default is 0.
    pub fn set_origin(&mut self, ctx: &Context, origin: f32) -> Result<()> {
        memory::upload(ctx, &self.table, 0, &self.table_for(origin)?)?;
        self.origin = origin;
        Ok(())
    }

    /// The level table's bytes with origin `origin` (finite).
    fn table_for(&self, origin: f32) -> Result<Vec<u8>> {
        if !origin.is_finite() {
            return Err(Error::param("pyramid origin", origin, "a finite height"));
        }
        Ok(bytemuck::cast_slice(&table_entries(&self.layout, self.kind, origin)).to_vec())
    }

    /// [`HeightPyramid::set_origin`] without the upload: sets the origin and returns the level
    /// table's new bytes for the caller to record (`vkCmdUpdateBuffer` into
    /// [`HeightPyramid::table_buffer`] at offset 0).
    pub(crate) fn origin_table(&mut self, origin: f32) -> Result<Vec<u8>> {
        let bytes = self.table_for(origin)?;
        self.origin = origin;
        Ok(bytes)
    }

    /// The origin `z0` subtracted from level 0 on every read ([`HeightPyramid::set_origin`]).
    pub fn origin(&self) -> f32 {
        self.origin
    }

    /// Records the decimation (and, in stack mode, the synthesis) into `rec`'s command buffer.
    pub fn record(&self, rec: &mut Recorder) {
        self.record_decimate(rec);
        self.record_synthesize(rec);
    }

    /// Records the decimation alone (stage `*.decimate`).
    pub fn record_decimate(&self, rec: &mut Recorder) {
        let wrap = self.wrap as u32;
        let layout = &self.layout;
        let (n, channels) = (layout.count() as u32, self.kind.channels.max(1));
        rec.scope(self.kind.stage_decimate, |ctx, cmd| {
            // Level 0 may have been written by a copy or by a host compute pass.
            barrier::transfer_to_compute(ctx, cmd);
            barrier::compute_to_compute(ctx, cmd);
            for i in 1..n {
                let l = layout.levels[i as usize];
                let push = PyramidPush { level: i, wrap, out_width: n, out_height: 0, scale: 1.0, flags: 0 };
                self.decimate.dispatch(
                    ctx,
                    cmd,
                    self.decimate_set,
                    bytemuck::bytes_of(&push),
                    [
                        groups(l.width, crate::constants::WORKGROUP),
                        groups(l.height, crate::constants::WORKGROUP),
                        channels,
                    ],
                );
                barrier::compute_to_compute(ctx, cmd);
            }
        });
    }

    /// Records the synthesis of the stack (stage `*.synthesize`); nothing in pyramid mode.
    /// Dispatch z = stack plane `c·stack_levels + i`; `level` carries `stack_levels | n_v << 16`
    /// (glsl/pyramid/synthesize.comp.glsl).
    pub fn record_synthesize(&self, rec: &mut Recorder) {
        let wrap = self.wrap as u32;
        let n = self.stack_levels as u32;
        let channels = self.kind.channels.max(1);
        if let Some(p) = &self.synthesize {
            rec.scope(self.kind.stage_synthesize, |ctx, cmd| {
                let (ww, wh) = self.work;
                let level = n | (self.layout.count() as u32) << 16;
                let (scale, flags) = (self.stack_scale, self.raw_plane0 as u32);
                let push = PyramidPush { level, wrap, out_width: ww, out_height: wh, scale, flags };
                // An f16 stack: one invocation per word of two values, over half the rows.
                let rows = if self.kind.stack_storage == Storage::F16 { wh.div_ceil(2) } else { wh };
                p.dispatch(
                    ctx,
                    cmd,
                    self.synthesize_set,
                    bytemuck::bytes_of(&push),
                    [groups(ww, crate::constants::WORKGROUP), groups(rows, crate::constants::WORKGROUP), n * channels],
                );
                barrier::compute_to_compute(ctx, cmd);
            });
        }
    }

    pub fn layout(&self) -> &PyramidLayout {
        &self.layout
    }
    pub fn mode(&self) -> PyramidMode {
        self.mode
    }
    pub fn wrap(&self) -> bool {
        self.wrap
    }
    /// Working resolution of the stack (and of the visibility grid).
    pub fn work(&self) -> (u32, u32) {
        self.work
    }
    /// All decimated levels, packed (see [`PyramidLayout`]). Level 0 is the input. A renderer's
    /// height levels buffer may be larger: it also holds the radiance levels after level 0
    /// ([`LevelsMemory`]).
    pub fn levels_buffer(&self) -> &Buffer {
        &self.levels
    }

    /// Bytes of [`HeightPyramid::levels_buffer`] reserved from [`scratch_offset`] on for another
    /// pyramid's levels (the `tail` of [`LevelsMemory::Own`]; 0 for [`HeightPyramid::new`]). An
    /// `IndirectPass` puts its radiance levels there only when they fit in it.
    pub fn levels_room(&self) -> u64 {
        self.room
    }

    /// Whether the levels live in another pyramid's buffer ([`LevelsMemory::Alias`]).
    pub fn levels_aliased(&self) -> bool {
        self.levels.owned_bytes() == 0
    }
    /// The level table (`hfgi_Level[n_v]`), for passes that sample the pyramid.
    pub fn table_buffer(&self) -> &Buffer {
        &self.table
    }
    /// The synthesized stack (`channels · stack_levels()` planes of `work()` size, row-major),
    /// in stack mode: f32, or with [`PyramidKind::stack_storage`] f16 halves two to a word
    /// (glsl/inc/hfgi_store.glsl).
    pub fn stack_buffer(&self) -> Option<&Buffer> {
        self.stack.as_ref()
    }

    /// The stack planes' table (`[width, height, offset, 0]` per plane of channel 0, offsets in
    /// values, then `[0, 0, channel stride, 0]`; `PyramidLayout::stack_planes`); stack mode only.
    pub fn stack_planes_buffer(&self) -> Option<&Buffer> {
        self.planes.as_ref()
    }

    /// What the scanning shaders bind as the height stack's planes (`hfgi_hplanes`,
    /// glsl/inc/hfgi_pyramid.glsl): [`HeightPyramid::stack_planes_buffer`], or in pyramid mode,
    /// which never reads it, the level table.
    pub fn height_planes(&self) -> &Buffer {
        self.planes.as_ref().unwrap_or(&self.table)
    }

    /// Stack planes per channel: the finest levels the stack holds (`n_v` unless created with
    /// fewer; [`HeightPyramid::with_kind`]).
    pub fn stack_levels(&self) -> usize {
        self.stack_levels
    }

    /// Whether the synthesis computes each word of an f16 stack as two B-splines sharing their
    /// fetches (`synthesizes_pairs`: even plane widths, no plane coarser than its level;
    /// docs/pyramid.md). Diagnostics: the output is the same either way.
    pub fn synthesizes_pairs(&self) -> bool {
        self.synthesize.is_some() && synthesizes_pairs(self.kind, &self.layout, &self.plane_table)
    }

    /// Bytes of GPU memory held by this mode's buffers.
    pub fn memory_bytes(&self) -> u64 {
        self.levels.owned_bytes()
            + self.table.size
            + self.stack.as_ref().map_or(0, |s| s.size)
            + self.planes.as_ref().map_or(0, |s| s.size)
    }

    /// With `on` (a renderer whose scans read level 0 as the bilinear surface, gi.level0 =
    /// "bilinear"), the synthesis writes level 0's own values (relative to its bias, as
    /// `hfgi_fetch` reads them) to plane 0 instead of their B-spline, which such scans never
    /// read, provided plane 0 has level 0's size (no sub-sampling): the bilinear read of plane 0
    /// is then bit for bit the raw read of level 0, and the scans read every level through the
    /// stack, one read path per sample instead of both on every lane (`HFGI_FLAG_RAW_PLANE0`,
    /// docs/performance.md §17). Returns whether plane 0 now holds them. Before the first
    /// synthesis.
    pub(crate) fn set_raw_plane0(&mut self, on: bool) -> bool {
        let l0 = self.layout.levels[0];
        let plane0 = self.plane_table.first().map(|p| (p[0], p[1]));
        self.raw_plane0 = on && self.stack.is_some() && plane0 == Some((l0.width, l0.height));
        self.raw_plane0
    }

    /// Whether plane 0 of the stack holds level 0's own values ([`HeightPyramid::set_raw_plane0`]).
    pub fn raw_plane0(&self) -> bool {
        self.raw_plane0
    }

    /// Sets the pre-exposure of an f16 stack ([`super::storage::pre_exposure`]): the next
    /// synthesis stores its values times `scale`, and [`HeightPyramid::read_stack_all`] divides
    /// by it.
    pub(crate) fn set_stack_scale(&mut self, scale: f32) {
        self.stack_scale = scale;
    }

    /// Frees every buffer and pipeline.
    pub fn destroy(mut self, ctx: &Context) {
        self.decimate.destroy(ctx);
        if let Some(p) = self.synthesize.as_mut() {
            p.destroy(ctx);
        }
        self.levels.destroy(ctx);
        self.table.destroy(ctx);
        for b in [self.stack, self.planes].into_iter().flatten() {
            b.destroy(ctx);
        }
    }
}

/// What [`HeightPyramid::with_kind`] creates, collected as it goes so that a failure destroys
/// what exists.
#[derive(Default)]
struct Parts {
    levels: Option<Buffer>,
    table: Option<Buffer>,
    stack: Option<Buffer>,
    planes: Option<Buffer>,
    decimate: Option<ComputePipeline>,
    synthesize: Option<ComputePipeline>,
    /// The decimation's and the synthesis' descriptor sets.
    sets: (vk::DescriptorSet, vk::DescriptorSet),
}

impl Parts {
    /// The levels, the table and the decimation; in stack mode the stack, its planes and the
    /// synthesis. Texel views: the scans, the shading and the synthesis read the levels through
    /// them, the scans the stack and its planes (in pyramid mode, with no stack, the levels and
    /// the table in their place).
    fn make(&mut self, ctx: &Context, kind: PyramidKind, sizes: &PyramidBuffers, at: LevelsMemory) -> Result<()> {
        let storage = crate::vk::memory::PASS_BUFFER_USAGE;
        let table_entries = table_entries(&sizes.layout, kind, 0.0);
        let lv = self.levels.insert(create_levels(ctx, &buffer_name(kind, "levels"), sizes.levels, storage, at)?);
        let tb = self.table.insert(
            Buffer::new(ctx, &buffer_name(kind, "table"), sizes.table, storage, MemoryLocation::GpuOnly)?
                .with_texel_view(ctx, vk::Format::R32G32B32A32_UINT)?,
        );
        memory::upload(ctx, tb, 0, bytemuck::cast_slice(&table_entries))?;
        let d = self.decimate.insert(ComputePipeline::new(
            ctx,
            &shaders::PYRAMID_DECIMATE_COMP,
            &[DescriptorKind::StorageBuffer; 2],
            PUSH_SIZE,
            &[],
            1,
        )?);
        self.sets.0 = d.allocate_set(ctx, &[Bind::Buffer(lv), Bind::Buffer(tb)])?;
        let Some(stack_bytes) = sizes.stack else { return Ok(()) };
        let st = self.stack.insert(
            Buffer::new(ctx, &buffer_name(kind, "stack"), stack_bytes, storage, MemoryLocation::GpuOnly)?
                .with_texel_view(ctx, vk::Format::R32_UINT)?,
        );
        let entries = sizes.planes.as_deref().unwrap_or_default();
        let name = buffer_name(kind, "planes");
        let pl = self.planes.insert(
            Buffer::new(ctx, &name, (entries.len() * 16) as u64, storage, MemoryLocation::GpuOnly)?
                .with_texel_view(ctx, vk::Format::R32G32B32A32_UINT)?,
        );
        memory::upload(ctx, pl, 0, bytemuck::cast_slice(entries))?;
        let p = self.synthesize.insert(ComputePipeline::new(
            ctx,
            &shaders::PYRAMID_SYNTHESIZE_COMP,
            &[
                DescriptorKind::TexelBuffer,
                DescriptorKind::StorageBuffer,
                DescriptorKind::StorageBuffer,
                DescriptorKind::TexelBuffer,
            ],
            PUSH_SIZE,
            &[(0, kind.stack_storage.spec()), (1, synthesizes_pairs(kind, &sizes.layout, entries) as u32)],
            1,
        )?);
        let binds = [Bind::Texel(lv), Bind::Buffer(tb), Bind::Buffer(st), Bind::Texel(pl)];
        self.sets.1 = p.allocate_set(ctx, &binds)?;
        Ok(())
    }

    fn destroy(self, ctx: &Context) {
        for b in [self.levels, self.table, self.stack, self.planes].into_iter().flatten() {
            b.destroy(ctx);
        }
        for mut p in [self.decimate, self.synthesize].into_iter().flatten() {
            p.destroy(ctx);
        }
    }
}
