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
//!   (with the level offset they never read the coarsest ones; [`scan_stack_levels`]).
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

use super::shared::{GpuLevel, PyramidPush};
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

/// What a pyramid holds: its channel count, the `source` id its table entries carry
/// (`hfgi_Level.source`) and its stage names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PyramidKind {
    pub channels: u32,
    pub source: u32,
    pub stage_decimate: &'static str,
    pub stage_synthesize: &'static str,
    pub label: &'static str,
    /// How the stack stores its values (the radiance stack follows `gi.storage`; the height
    /// stack is always f32: heights need more than a half's 11 bits).
    pub stack_storage: Storage,
}

impl PyramidKind {
    /// The height pyramid: one channel, source 0, stages `pyramid.*`.
    pub const HEIGHTS: Self = Self {
        channels: 1,
        source: 0,
        stage_decimate: STAGE_DECIMATE,
        stage_synthesize: STAGE_SYNTHESIZE,
        label: "pyramid",
        stack_storage: Storage::F32,
    };
}

/// The level table of a pyramid: channel `c` of level `i` is entry `c·n_v + i`, level 0 of
/// every channel with `bias = origin`.
fn table_entries(layout: &PyramidLayout, kind: PyramidKind, origin: f32) -> Vec<GpuLevel> {
    (0..kind.channels.max(1) as u64)
        .flat_map(|c| {
            layout.levels.iter().enumerate().map(move |(i, l)| GpuLevel {
                offset: (c * layout.total) as u32 + l.offset,
                source: kind.source,
                bias: if i == 0 { origin } else { 0.0 },
                ..*l
            })
        })
        .collect()
}

/// Stack planes per channel that a scan of `n_v` levels with level bias `bias = k·o` and
/// `far` samples past the ladder reads: sample `i ∈ [−near, n_v + far)` reads level
/// `clamp(i − bias, 0, n_v − 1)` (docs/direct.md §2), so the coarsest level read is
/// `n_v + far − bias − 1`. The scanning shaders size their receiver-base loop by the same
/// formula (`hfgi_scan_levels`, glsl/inc/hfgi_pyramid.glsl).
pub(crate) fn scan_stack_levels(n_v: usize, bias: u32, far: u32) -> usize {
    (n_v as i64 + i64::from(far) - i64::from(bias)).clamp(1, n_v.max(1) as i64) as usize
}

/// The height stack's planes for `scene`'s scans (visibility, key lights and the indirect scan
/// share `k_v`, `o_v` and the far steps): [`scan_stack_levels`] of its `n_v` levels.
pub(crate) fn height_stack_levels(gi: &crate::scene::model::GiSettings, n_v: usize) -> usize {
    scan_stack_levels(n_v, gi.level_step * gi.level_offset, gi.far_steps())
}

/// [`height_stack_levels`] of a `w × h` field's height pyramid (its `n_v` from the layout).
pub(crate) fn height_stack_of(gi: &crate::scene::model::GiSettings, w: usize, h: usize) -> Result<usize> {
    Ok(height_stack_levels(gi, PyramidLayout::new(w, h, gi.level_step)?.count()))
}

/// The name of a pyramid buffer: `hfgi.{label}.{part}` (`part`: `levels`, `table`, `stack`).
pub(crate) fn buffer_name(kind: PyramidKind, part: &str) -> String {
    format!("hfgi.{}.{part}", kind.label)
}

/// The buffers [`HeightPyramid::with_kind`] creates, in bytes as requested, after the same
/// checks (one source for the pass and [`crate::frame::memory`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PyramidBuffers {
    pub layout: PyramidLayout,
    /// `hfgi.{label}.levels`: every channel's levels, `f32`.
    pub levels: u64,
    /// `hfgi.{label}.table`: one [`GpuLevel`] per channel and level.
    pub table: u64,
    /// `hfgi.{label}.stack`: stack mode only, `channels · stack_levels` planes of at most `work`
    /// (`PyramidLayout::stack_plane_size`) in the kind's storage.
    pub stack: Option<u64>,
    /// `hfgi.{label}.planes`: stack mode only, the planes' sizes and offsets
    /// (`PyramidLayout::stack_planes`, `uvec4` each) that the synthesis and the scan read.
    pub planes: Option<Vec<[u32; 4]>>,
    /// Stack planes per channel: the finest levels kept (`1..=n_v`).
    pub stack_levels: usize,
    /// The levels live in another pyramid's buffer ([`LevelsMemory::Alias`]): no allocation of
    /// their own, so [`PyramidBuffers::named`] leaves them out.
    pub levels_aliased: bool,
}

impl PyramidBuffers {
    /// The sizes for [`HeightPyramid::with_kind`]'s arguments, or its error. `max_dimension`:
    /// the device's `maxImageDimension2D` (`None`: not checked, as without a device).
    /// `stack_levels`: the stack's planes per channel (`None`: every level; clamped to `1..=n_v`).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        width: usize,
        height: usize,
        work: (usize, usize),
        k_v: u32,
        mode: PyramidMode,
        kind: PyramidKind,
        stack_levels: Option<usize>,
        max_dimension: Option<usize>,
    ) -> Result<Self> {
        let layout = PyramidLayout::new(width, height, k_v)?;
        let stack_levels = stack_levels.unwrap_or(layout.count()).clamp(1, layout.count());
        let channels = kind.channels.max(1) as u64;
        let table_len = table_entries(&layout, kind, 0.0).len();
        if channels * layout.total > u32::MAX as u64 {
            return Err(Error::param(
                "pyramid size",
                format!("{width}×{height}×{channels}"),
                "fewer than 2^32 samples in all levels",
            ));
        }
        if let Some(max) = max_dimension.filter(|&m| width > m || height > m) {
            return Err(Error::FieldSize { source_name: "pyramid".into(), width, height, max: max as u32 });
        }
        if work.0 < 2 || work.1 < 2 || work.0 > width.max(2) || work.1 > height.max(2) {
            return Err(Error::param(
                "working resolution",
                format!("{}×{}", work.0, work.1),
                format!("2×2 up to {width}×{height}"),
            ));
        }
        let planes = layout.stack_planes(work, stack_levels);
        let stack_floats = layout.stack_values(work, stack_levels) * channels;
        if mode == PyramidMode::Stack && stack_floats > u32::MAX as u64 {
            return Err(Error::param(
                "gi.pyramid",
                "stack",
                format!("`pyramid` for a {width}×{height} field (the stack would hold {stack_floats} floats, more than 2^32)"),
            ));
        }
        Ok(Self {
            levels: layout.total * 4 * channels,
            table: (table_len * std::mem::size_of::<GpuLevel>()) as u64,
            stack: (mode == PyramidMode::Stack).then_some(kind.stack_storage.bytes(stack_floats)),
            planes: (mode == PyramidMode::Stack).then_some(planes),
            stack_levels,
            layout,
            levels_aliased: false,
        })
    }

    /// The sizes with a levels buffer that also has room for `tail` bytes from
    /// [`scratch_offset`] on, where an aliasing pyramid's levels go ([`LevelsMemory::Own`]).
    pub(crate) fn with_tail(mut self, tail: u64) -> Self {
        if tail > 0 {
            self.levels = self.levels.max(scratch_offset(&self.layout) + tail);
        }
        self
    }

    /// The sizes of a pyramid whose levels alias another's ([`LevelsMemory::Alias`]).
    pub(crate) fn aliased(mut self) -> Self {
        self.levels_aliased = true;
        self
    }

    /// `(name, bytes)` of every buffer that allocates memory, in creation order.
    pub(crate) fn named(&self, kind: PyramidKind) -> Vec<(String, u64)> {
        let mut out = Vec::new();
        if !self.levels_aliased {
            out.push((buffer_name(kind, "levels"), self.levels));
        }
        out.push((buffer_name(kind, "table"), self.table));
        out.extend(self.stack.map(|b| (buffer_name(kind, "stack"), b)));
        out.extend(self.planes.as_ref().map(|p| (buffer_name(kind, "planes"), (p.len() * 16) as u64)));
        out
    }
}

/// Alignment of [`scratch_offset`]: a multiple of every device's buffer alignment hfgi knows
/// (`VkMemoryRequirements::alignment` of a storage and texel buffer, at most 256 bytes in
/// practice; [`Buffer::aliasing`] checks it).
pub(crate) const SCRATCH_ALIGN: u64 = 256;

/// Byte offset in a one-channel pyramid's levels buffer after level 0, rounded up to
/// [`SCRATCH_ALIGN`]: where its decimated levels begin, and where an aliasing pyramid's
/// levels may be placed ([`LevelsMemory`]).
pub(crate) fn scratch_offset(layout: &PyramidLayout) -> u64 {
    let l0 = layout.levels[0];
    (u64::from(l0.width) * u64::from(l0.height) * 4).div_ceil(SCRATCH_ALIGN) * SCRATCH_ALIGN
}

/// Where a pyramid's levels live.
///
/// In stack mode the levels after level 0 are only read by the pyramid's own synthesis, right
/// after its decimation: the scans read the stack (and level 0). A renderer therefore lets the
/// scalar radiance pyramid, whose levels are live only from `radiance.gather` to the last
/// `indirect.shade` of a frame, keep them in the height levels buffer after level 0, which is
/// live only from `pyramid.decimate` to `pyramid.synthesize` (docs/pyramid.md, "Shared
/// levels"). The barriers between the stages order the two uses.
#[derive(Clone, Copy)]
pub enum LevelsMemory<'a> {
    /// A buffer of its own, with room for `tail` more bytes from [`scratch_offset`] on (0: none).
    Own { tail: u64 },
    /// Inside `owner` from byte `offset` on, with no memory of its own ([`Buffer::aliasing`]).
    Alias { owner: &'a Buffer, offset: u64 },
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
        Self::with_kind(ctx, width, height, work, k_v, mode, wrap, PyramidKind::HEIGHTS, None)
    }

    /// [`HeightPyramid::new`] for any [`PyramidKind`], with a stack of the finest
    /// `stack_levels` levels per channel (`None`: all; only levels below it may be read from
    /// the stack).
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
    ) -> Result<Self> {
        let own = LevelsMemory::Own { tail: 0 };
        Self::with_levels(ctx, width, height, work, k_v, mode, wrap, kind, stack_levels, own)
    }

    /// [`HeightPyramid::with_kind`] with its levels where `at` says ([`LevelsMemory`]).
    #[allow(clippy::too_many_arguments)]
    pub fn with_levels(
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
        let layout = sizes.layout.clone();
        let table_entries = table_entries(&layout, kind, 0.0);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let (mut levels, mut table, mut stack, mut planes) = (None, None, None, None);
        let (mut decimate, mut synthesize) = (None::<ComputePipeline>, None::<ComputePipeline>);
        let mut sets = (vk::DescriptorSet::null(), vk::DescriptorSet::null());
        let made = (|| -> Result<()> {
            // Texel views: the scans, the shading and the synthesis read the levels through
            // them, the scans the stack and its planes (in pyramid mode, with no stack, the levels
            // and the table in their place).
            let name = buffer_name(kind, "levels");
            let lv = levels.insert(
                match at {
                    LevelsMemory::Own { .. } => {
                        Buffer::new(ctx, &name, sizes.levels, storage, MemoryLocation::GpuOnly)?
                    }
                    LevelsMemory::Alias { owner, offset } => {
                        Buffer::aliasing(ctx, &name, sizes.levels, storage, owner, offset)?
                    }
                }
                .with_texel_view(ctx, vk::Format::R32_UINT)?,
            );
            let tb = table.insert(
                Buffer::new(ctx, &buffer_name(kind, "table"), sizes.table, storage, MemoryLocation::GpuOnly)?
                    .with_texel_view(ctx, vk::Format::R32G32B32A32_UINT)?,
            );
            memory::upload(ctx, tb, 0, bytemuck::cast_slice(&table_entries))?;
            let d = decimate.insert(ComputePipeline::new(
                ctx,
                &shaders::PYRAMID_DECIMATE_COMP,
                &[DescriptorKind::StorageBuffer; 2],
                PUSH_SIZE,
                &[],
                1,
            )?);
            sets.0 = d.allocate_set(ctx, &[Bind::Buffer(lv), Bind::Buffer(tb)])?;
            if let Some(stack_bytes) = sizes.stack {
                let st = stack.insert(
                    Buffer::new(ctx, &buffer_name(kind, "stack"), stack_bytes, storage, MemoryLocation::GpuOnly)?
                        .with_texel_view(ctx, vk::Format::R32_UINT)?,
                );
                let entries = sizes.planes.as_deref().unwrap_or_default();
                let name = buffer_name(kind, "planes");
                let pl = planes.insert(
                    Buffer::new(ctx, &name, (entries.len() * 16) as u64, storage, MemoryLocation::GpuOnly)?
                        .with_texel_view(ctx, vk::Format::R32G32B32A32_UINT)?,
                );
                memory::upload(ctx, pl, 0, bytemuck::cast_slice(entries))?;
                let p = synthesize.insert(ComputePipeline::new(
                    ctx,
                    &shaders::PYRAMID_SYNTHESIZE_COMP,
                    &[
                        DescriptorKind::TexelBuffer,
                        DescriptorKind::StorageBuffer,
                        DescriptorKind::StorageBuffer,
                        DescriptorKind::TexelBuffer,
                    ],
                    PUSH_SIZE,
                    &[(0, kind.stack_storage.spec())],
                    1,
                )?);
                let binds = [Bind::Texel(lv), Bind::Buffer(tb), Bind::Buffer(st), Bind::Texel(pl)];
                sets.1 = p.allocate_set(ctx, &binds)?;
            }
            Ok(())
        })();
        match (made, levels, table, decimate) {
            (Ok(()), Some(levels), Some(table), Some(decimate)) => Ok(Self {
                layout,
                stack_levels: sizes.stack_levels,
                kind,
                origin: 0.0,
                stack_scale: 1.0,
                raw_plane0: false,
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
            (made, levels, table, decimate) => {
                for b in [levels, table, stack, planes].into_iter().flatten() {
                    b.destroy(ctx);
                }
                for mut p in [decimate, synthesize].into_iter().flatten() {
                    p.destroy(ctx);
                }
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

    /// Bytes of GPU memory held by this mode's buffers.
    pub fn memory_bytes(&self) -> u64 {
        self.levels.owned_bytes()
            + self.table.size
            + self.stack.as_ref().map_or(0, |s| s.size)
            + self.planes.as_ref().map_or(0, |s| s.size)
    }

    /// Reads level `i` back (waits). For tests and pictures. Level 0 holds what was written
    /// (absolute heights); levels ≥ 1 hold values relative to [`HeightPyramid::origin`].
    pub fn read_level(&self, ctx: &Context, i: usize) -> Result<Vec<f32>> {
        let l =
            *self.layout.levels.get(i).ok_or_else(|| Error::param("level", i, format!("< {}", self.layout.count())))?;
        memory::download_f32(ctx, &self.levels, l.offset as u64, (l.width * l.height) as u64)
    }

    /// Reads stack plane `i` back (waits; relative to [`HeightPyramid::origin`]). Stack mode only.
    pub fn read_stack(&self, ctx: &Context, i: usize) -> Result<Vec<f32>> {
        let s = self.stack.as_ref().ok_or_else(|| Error::param("read_stack", "pyramid mode", "stack mode"))?;
        if self.kind.stack_storage != Storage::F32 {
            return Err(Error::param("read_stack", "an f16 stack", "an f32 stack (read_stack_all reads any)"));
        }
        if i >= self.stack_levels {
            return Err(Error::param(
                "stack level",
                i,
                format!("< {} (the levels the stack holds)", self.stack_levels),
            ));
        }
        let [w, h, offset, _] = self.plane_table[i];
        memory::download_f32(ctx, s, u64::from(offset), u64::from(w) * u64::from(h))
    }

    /// Diagnostics: the whole levels buffer (every channel, [`PyramidLayout`] order; channel
    /// `c` starts at float `c·total`), read back (waits). Call after a recorded frame completed.
    pub fn read_levels_all(&self, ctx: &Context) -> Result<Vec<f32>> {
        memory::download_f32(ctx, &self.levels, 0, self.layout.total * u64::from(self.kind.channels.max(1)))
    }

    /// Diagnostics: the whole stack buffer (`channels · stack_levels()` planes laid out as
    /// [`HeightPyramid::stack_planes_buffer`] says, padding included), read back (waits); `None`
    /// in pyramid mode. Call after a recorded frame completed.
    pub fn read_stack_all(&self, ctx: &Context) -> Result<Option<Vec<f32>>> {
        let stride = self.plane_table.last().map_or(0, |p| p[2] as usize);
        let values = self.kind.channels.max(1) as usize * stride;
        let storage = self.kind.stack_storage;
        let read = self.stack.as_ref().map(|s| super::storage::download_vectors(ctx, s, storage, 0, 1, values));
        let unexpose = 1.0 / self.stack_scale;
        Ok(read.transpose()?.map(|v| v.into_iter().map(|x| x * unexpose).collect()))
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

    /// Samples the pyramid at `(level, x, y)` queries (x, y in level-0 texel units) on the GPU
    /// exactly as the scanning passes do: bilinear on the stack, or B-spline on the fly. The
    /// values are relative to [`HeightPyramid::origin`] (absolute with the default origin 0).
    /// In stack mode a query's level must be one the stack holds (`< stack_levels()`).
    pub fn probe(&self, ctx: &Context, queries: &[[f32; 3]]) -> Result<Vec<f32>> {
        let top = if self.stack.is_some() { self.stack_levels } else { self.layout.count() };
        if let Some(q) = queries.iter().find(|q| !(q[0] >= 0.0 && (q[0] as usize) < top)) {
            return Err(Error::param("probe level", q[0], format!("0 ≤ level < {top}")));
        }
        let q: Vec<[f32; 4]> = queries.iter().map(|q| [q[0], q[1], q[2], 0.0]).collect();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let qb = Buffer::new(ctx, "hfgi.pyramid.probe.queries", (q.len() * 16) as u64, usage, MemoryLocation::GpuOnly)?;
        let rb =
            match Buffer::new(ctx, "hfgi.pyramid.probe.result", (q.len() * 4) as u64, usage, MemoryLocation::GpuOnly) {
                Ok(b) => b,
                Err(e) => {
                    qb.destroy(ctx);
                    return Err(e);
                }
            };
        let mut pipe: Option<ComputePipeline> = None;
        let r = (|| -> Result<Vec<f32>> {
            memory::upload(ctx, &qb, 0, bytemuck::cast_slice(&q))?;
            let p = pipe.insert(ComputePipeline::new(
                ctx,
                &shaders::PYRAMID_PROBE_COMP,
                &[DescriptorKind::StorageBuffer; 6],
                PUSH_SIZE,
                &[],
                1,
            )?);
            let stack = self.stack.as_ref().unwrap_or(&self.levels);
            let set = p.allocate_set(
                ctx,
                &[
                    Bind::Buffer(&self.levels),
                    Bind::Buffer(&self.table),
                    Bind::Buffer(stack),
                    Bind::Buffer(&qb),
                    Bind::Buffer(&rb),
                    Bind::Buffer(self.height_planes()),
                ],
            )?;
            let push = PyramidPush {
                level: (self.mode == PyramidMode::Pyramid) as u32,
                wrap: self.wrap as u32,
                out_width: self.work.0,
                out_height: self.work.1,
                scale: 1.0,
                flags: 0,
            };
            ctx.submit_and_wait(|cmd| {
                barrier::compute_to_compute(ctx, cmd);
                p.dispatch(
                    ctx,
                    cmd,
                    set,
                    bytemuck::bytes_of(&push),
                    [groups(q.len() as u32, crate::constants::WORKGROUP_1D), 1, 1],
                );
                Ok(())
            })?;
            memory::download_f32(ctx, &rb, 0, q.len() as u64)
        })();
        if let Some(mut p) = pipe {
            p.destroy(ctx);
        }
        qb.destroy(ctx);
        rb.destroy(ctx);
        r
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::direct::scan_level;
    use crate::scene::model::{GiSettings, ScanReach};

    /// The stack a renderer keeps is exactly the set of levels the twin's scan reads: every
    /// level below `height_stack_levels` is read by some sample, none above it is.
    #[test]
    fn the_height_stack_keeps_exactly_the_levels_the_scan_reads() {
        for (size, k_v, o_v, near, reach) in [
            (512, 4, 6, 4, ScanReach::Diagonal),
            (128, 4, 6, 4, ScanReach::Diagonal),
            (97, 3, 2, 0, ScanReach::Side),
            (64, 1, 0, 0, ScanReach::Diagonal),
            (33, 8, 8, 2, ScanReach::Diagonal),
            (2, 4, 6, 4, ScanReach::Side),
        ] {
            let gi = GiSettings {
                level_step: k_v,
                level_offset: o_v,
                near_steps: near,
                scan_reach: reach,
                ..Default::default()
            };
            let n_v = PyramidLayout::new(size, size, k_v).unwrap().count();
            let (lo, hi) = (-(near as i64), n_v as i64 + gi.far_steps() as i64);
            let read: std::collections::BTreeSet<usize> = (lo..hi).map(|i| scan_level(i, k_v, o_v, n_v)).collect();
            let kept = height_stack_levels(&gi, n_v);
            assert_eq!(read, (0..kept).collect(), "{size}², k_v {k_v}, o_v {o_v}, {reach:?}: n_v {n_v}");
        }
    }
}
