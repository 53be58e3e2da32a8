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
}
