//! The pyramid layout (docs/pyramid.md): level sizes and offsets for a field and a level step,
//! shared by the GPU pyramids and their CPU twin (`reference::pyramid`). [`GpuLevel`] is the
//! `hfgi_Level` struct of `glsl/inc/hfgi_shared.glsl` (`frame::shared` re-exports it with the
//! other GPU structs; its size is asserted there).

use bytemuck::{Pod, Zeroable};

use crate::error::{Error, Result};

/// `hfgi_Level`: one pyramid level inside the levels buffer (offset in floats).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLevel {
    pub width: u32,
    pub height: u32,
    pub offset: u32,
    /// Buffer the level lives in: 0 heights, 1 radiance (`hfgi_Level.source`).
    pub source: u32,
    /// Subtracted from every sample read from this level (`hfgi_fetch`): the height origin
    /// `z0` on level 0 of a renderer's height pyramid ([`crate::frame::pyramid::HeightPyramid::set_origin`],
    /// docs/pyramid.md), 0 everywhere else.
    pub bias: f32,
}

/// Sizes and buffer offsets of every level.
#[derive(Clone, Debug, PartialEq)]
pub struct PyramidLayout {
    /// Level step `k_v`: levels per halving of the resolution.
    pub k_v: u32,
    /// Level `i`: width, height and offset (in floats) in the levels buffer.
    pub levels: Vec<GpuLevel>,
    /// Total floats of all levels.
    pub total: u64,
}

impl PyramidLayout {
    /// The layout for an `width × height` field with level step `k_v ≥ 1`.
    pub fn new(width: usize, height: usize, k_v: u32) -> Result<Self> {
        if k_v == 0 || k_v > 64 {
            return Err(Error::param("level step k_v", k_v, "an integer in 1..=64"));
        }
        if width < 2 || height < 2 {
            return Err(Error::param("pyramid size", format!("{width}×{height}"), "at least 2×2"));
        }
        let n = width.max(height) as f64;
        let n_v = (k_v as f64 * n.log2() + 1e-9).floor() as usize + 1;
        let mut levels = Vec::with_capacity(n_v);
        let mut offset = 0u64;
        for i in 0..n_v {
            let f = 2f64.powf(-(i as f64) / k_v as f64);
            let (w, h) = if i == 0 {
                (width, height)
            } else {
                (((width as f64 * f).round() as usize).max(1), ((height as f64 * f).round() as usize).max(1))
            };
            if offset > u32::MAX as u64 {
                return Err(Error::param(
                    "pyramid size",
                    format!("{width}×{height}"),
                    "fewer than 2^32 samples in all levels",
                ));
            }
            levels.push(GpuLevel { width: w as u32, height: h as u32, offset: offset as u32, source: 0, bias: 0.0 });
            offset += (w * h) as u64;
        }
        Ok(Self { k_v, levels, total: offset })
    }

    /// Number of levels `n_v`.
    pub fn count(&self) -> usize {
        self.levels.len()
    }

    /// Step `τ_i = 2^(−(n_v−1−i)/k_v)` of eq. 14, in units of the domain.
    pub fn tau(&self, i: usize) -> f64 {
        2f64.powf(-((self.count() - 1 - i) as f64) / self.k_v as f64)
    }

    /// The size of stack plane `i` (level `i` resampled for the scans, docs/pyramid.md
    /// "Decimated stacks"): the working resolution `work` halved `j` times, the largest `j` that
    /// keeps at least level `i`'s texels along both axes (a coarse level's cubic B-spline is
    /// smoother than its texels: a bilinear read of it at that density moves the errors against
    /// the exact reference by ≤ 0.006 percentage points, docs/performance.md §16).
    pub fn stack_plane_size(&self, i: usize, work: (usize, usize)) -> (usize, usize) {
        let l = self.levels[i];
        let fits = |j: u32| (work.0 >> j) >= l.width as usize && (work.1 >> j) >= l.height as usize;
        let j = (1..31).take_while(|&j| fits(j)).last().unwrap_or(0);
        (work.0 >> j, work.1 >> j)
    }

    /// The stack's first `planes` planes per channel: `[width, height, offset, 0]` each, offsets
    /// in values from the channel's start, then `[0, 0, stride, 0]` with the channel stride.
    /// Every plane is padded to an even count (two f16 values per 32-bit word never straddle
    /// planes).
    pub fn stack_planes(&self, work: (usize, usize), planes: usize) -> Vec<[u32; 4]> {
        let mut out = Vec::with_capacity(planes + 1);
        let mut offset = 0u64;
        for i in 0..planes {
            let (w, h) = self.stack_plane_size(i, work);
            out.push([w as u32, h as u32, offset as u32, 0]);
            offset += self.stack_plane_values(i, work);
        }
        out.push([0, 0, offset as u32, 0]);
        out
    }

    /// The values stack plane `i` occupies: its texels, padded to an even count.
    fn stack_plane_values(&self, i: usize, work: (usize, usize)) -> u64 {
        let (w, h) = self.stack_plane_size(i, work);
        ((w * h) as u64).div_ceil(2) * 2
    }

    /// The channel stride of [`PyramidLayout::stack_planes`] in u64 (its `u32` offsets are exact
    /// while the whole stack holds fewer than 2³² values).
    pub fn stack_values(&self, work: (usize, usize), planes: usize) -> u64 {
        (0..planes).map(|i| self.stack_plane_values(i, work)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Planes: the working grid halved while both axes keep ≥ the level's texels, not once
    /// more; the table's offsets are the padded sums.
    #[test]
    fn stack_planes_keep_their_levels_resolution() {
        for (w, h, work, k) in
            [(512, 512, (512, 512), 4), (128, 88, (128, 88), 4), (128, 88, (64, 44), 4), (37, 29, (37, 29), 8)]
        {
            let layout = PyramidLayout::new(w, h, k).unwrap();
            for i in 0..layout.count() {
                let l = layout.levels[i];
                let (pw, ph) = layout.stack_plane_size(i, work);
                let j = (0..31).find(|&j| (work.0 >> j, work.1 >> j) == (pw, ph));
                let j = j.unwrap_or_else(|| panic!("{w}×{h} level {i}: {pw}×{ph} is no power-of-two reduction"));
                let keeps = |a: usize, b: usize| a >= l.width as usize && b >= l.height as usize;
                assert!(j == 0 || keeps(pw, ph), "{w}×{h} level {i}: {pw}×{ph} below {}×{}", l.width, l.height);
                assert!(!keeps(work.0 >> (j + 1), work.1 >> (j + 1)), "{w}×{h} level {i}: {pw}×{ph} could be halved");
            }
            let planes = layout.stack_planes(work, layout.count());
            let mut offset = 0;
            for (i, p) in planes[..layout.count()].iter().enumerate() {
                let (pw, ph) = layout.stack_plane_size(i, work);
                assert_eq!(*p, [pw as u32, ph as u32, offset, 0]);
                offset += ((pw * ph) as u32).div_ceil(2) * 2;
            }
            assert_eq!(planes[layout.count()], [0, 0, offset, 0]);
            assert_eq!(planes[0][..2], [work.0 as u32, work.1 as u32], "level 0 keeps the working grid");
        }
        // 512², k = 4: levels 512, 431, 362, 304 keep 512² planes, 256 … 152 get 256², 128 … 76
        // get 128², 64 get 64².
        let layout = PyramidLayout::new(512, 512, 4).unwrap();
        let sizes: Vec<usize> = (0..13).map(|i| layout.stack_plane_size(i, (512, 512)).0).collect();
        assert_eq!(sizes, [512, 512, 512, 512, 256, 256, 256, 256, 128, 128, 128, 128, 64]);
    }
}
