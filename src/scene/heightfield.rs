//! The height-field type: an `Nx × Ny` row-major array of finite f32 heights (CONVENTIONS.md).

use crate::error::{Error, Result};

/// Largest side accepted when no device limit is known (lavapipe's `maxImageDimension2D`).
pub const DEFAULT_MAX_DIM: u32 = 16384;

/// A validated height field. Sample `(i, j)` (column `i` = x, row `j` = y) is at
/// world position `(i·s, j·s, h)`; `data[j * width + i]`. Heights are in world units.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    width: usize,
    height: usize,
    data: Vec<f32>,
}

impl HeightField {
    /// Validates and wraps `data` (row-major, `width * height` values).
    ///
    /// `source_name` (a file path or generator name) is used in error messages. Errors when a
    /// side is below 2 or above `max_dim`, when `data.len()` does not match, or when any value
    /// is NaN/Inf (naming the first bad position).
    pub fn new(source_name: &str, width: usize, height: usize, data: Vec<f32>, max_dim: u32) -> Result<Self> {
        if width < 2 || height < 2 || width > max_dim as usize || height > max_dim as usize {
            return Err(Error::FieldSize { source_name: source_name.to_string(), width, height, max: max_dim });
        }
        if data.len() != width * height {
            return Err(Error::param(
                format!("{source_name}: sample count"),
                data.len(),
                format!("{} values for a {width}×{height} field", width * height),
            ));
        }
        if let Some(k) = data.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                source_name: source_name.to_string(),
                x: k % width,
                y: k / width,
                value: data[k],
            });
        }
        Ok(Self { width, height, data })
    }

    /// Number of columns (x).
    pub fn width(&self) -> usize {
        self.width
    }
    /// Number of rows (y).
    pub fn height(&self) -> usize {
        self.height
    }
    /// Row-major samples.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
    /// Height at column `i`, row `j`.
    pub fn get(&self, i: usize, j: usize) -> f32 {
        self.data[j * self.width + i]
    }
    /// The bilinear surface (CONVENTIONS.md) at level-0 position `(x, y)` in texels, clamped
    /// to the field, in f64 (the local lights' and sphere blockers' twins, the boulders'
    /// resting height; the shaders read it the same way).
    pub fn bilinear(&self, x: f64, y: f64) -> f64 {
        let (w, h) = (self.width, self.height);
        let cx = x.clamp(0.0, (w - 1) as f64);
        let cy = y.clamp(0.0, (h - 1) as f64);
        let i = (cx.floor() as usize).min(w.saturating_sub(2));
        let j = (cy.floor() as usize).min(h.saturating_sub(2));
        let (fx, fy) = (cx - i as f64, cy - j as f64);
        let g = |a: usize, b: usize| f64::from(self.get(a.min(w - 1), b.min(h - 1)));
        let a = g(i, j) + (g(i + 1, j) - g(i, j)) * fx;
        let b = g(i, j + 1) + (g(i + 1, j + 1) - g(i, j + 1)) * fx;
        a + (b - a) * fy
    }
    /// `(min, max)` of the heights.
    pub fn range(&self) -> (f32, f32) {
        self.data.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
    }
    /// Multiplies every height by `s` (a scene's `height_scale`). Errors if the result is not finite.
    pub fn scaled(mut self, s: f32, source_name: &str) -> Result<Self> {
        for v in &mut self.data {
            *v *= s;
        }
        Self::new(source_name, self.width, self.height, self.data, u32::MAX)
    }
}
