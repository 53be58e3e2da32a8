//! The pyramids' sizes and buffer names, without Vulkan: what a pyramid holds
//! ([`PyramidKind`]), the stack planes a scan reads, the buffers [`super::HeightPyramid`]
//! creates ([`PyramidBuffers`], which [`crate::frame::memory`] counts) and where its levels live
//! ([`LevelsMemory`]; docs/pyramid.md, "Shared levels").

use super::{PyramidLayout, STAGE_DECIMATE, STAGE_SYNTHESIZE};
use crate::error::{Error, Result};
use crate::frame::shared::GpuLevel;
use crate::scene::model::{PyramidMode, Storage};
use crate::vk::Buffer;

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
pub(crate) fn table_entries(layout: &PyramidLayout, kind: PyramidKind, origin: f32) -> Vec<GpuLevel> {
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
        self.levels = levels_with_tail(self.levels, &self.layout, tail);
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

/// Bytes of a one-channel levels buffer of `levels` bytes (`layout`'s) that also has room for
/// `tail` bytes from [`scratch_offset`] on (none when `tail` is 0).
pub(crate) fn levels_with_tail(levels: u64, layout: &PyramidLayout, tail: u64) -> u64 {
    if tail > 0 {
        levels.max(scratch_offset(layout) + tail)
    } else {
        levels
    }
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

impl LevelsMemory<'_> {
    /// The bytes this pyramid reserves after level 0 for another's levels (`tail`, or 0).
    pub fn room(&self) -> u64 {
        match self {
            LevelsMemory::Own { tail } => *tail,
            LevelsMemory::Alias { .. } => 0,
        }
    }
}

/// Whether the synthesis computes an f16 stack's words as pairs of B-splines that share their
/// fetches (specialization constant 1 of glsl/pyramid/synthesize.comp.glsl;
/// docs/performance.md §34): every plane of `planes` (`PyramidLayout::stack_planes`, its last
/// entry the channel stride) has an even width, so a word's two values lie on one row, and is
/// no narrower than its level, so their windows start at most one level texel apart. Output
/// identical either way.
pub(crate) fn synthesizes_pairs(kind: PyramidKind, layout: &PyramidLayout, planes: &[[u32; 4]]) -> bool {
    let planes = &planes[..planes.len().saturating_sub(1)];
    kind.stack_storage == Storage::F16
        && planes.iter().zip(&layout.levels).all(|(p, l)| p[0] % 2 == 0 && l.width <= p[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::direct::scan_level;
    use crate::scene::model::{GiSettings, ScanReach};

    /// The stack a renderer keeps is exactly the set of levels the twin's scan reads: every
    /// level below `height_stack_levels` is read by some sample, none above it is.
    /// The paired f16 synthesis applies where every plane's width is even and no plane is
    /// coarser than its level: the radiance stack of a power-of-two field (its 15 finest
    /// levels, as `default` keeps at 128²), not one whose planes halve to odd widths or to a
    /// 1 × 1 plane, not a stack finer than its sub-sampled planes, never f32.
    #[test]
    fn paired_synthesis_needs_even_planes_no_coarser_than_their_levels() {
        let f16 = PyramidKind { stack_storage: Storage::F16, ..PyramidKind::HEIGHTS };
        let pairs = |kind, (w, h): (usize, usize), work: (usize, usize), kept: Option<usize>| {
            let layout = PyramidLayout::new(w, h, 4).unwrap();
            let planes = layout.stack_planes(work, kept.unwrap_or(layout.count()));
            synthesizes_pairs(kind, &layout, &planes)
        };
        assert!(pairs(f16, (128, 128), (128, 128), Some(15)));
        assert!(pairs(f16, (128, 88), (128, 88), Some(15)));
        assert!(pairs(f16, (64, 40), (64, 40), None), "down to its 2 × 1 plane");
        assert!(!pairs(f16, (128, 128), (128, 128), None), "the 1 × 1 plane");
        assert!(!pairs(f16, (100, 100), (100, 100), Some(15)), "planes of 25 texels");
        assert!(!pairs(f16, (128, 128), (64, 64), Some(15)), "level 0 finer than its plane");
        assert!(!pairs(PyramidKind::HEIGHTS, (128, 128), (128, 128), Some(15)), "f32");
    }

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
