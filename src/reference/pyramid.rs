//! CPU twin of [`crate::frame::pyramid`] in f64: the same decimation and the same cubic
//! B-spline, written as a direct 4×4 weighted sum (not as bilinear taps), so the GPU's
//! Sigg–Hadwiger form is checked against an independent formulation of the same filter.

use crate::error::Result;
use crate::math::bspline;
use crate::rules::layout::PyramidLayout;
use crate::scene::HeightField;

/// All levels (and optionally the synthesized stack) in f64.
pub struct CpuPyramid {
    pub layout: PyramidLayout,
    pub wrap: bool,
    /// `levels[i]`: level `i`, row-major.
    pub levels: Vec<Vec<f64>>,
    /// `stack[i]`: level `i` B-spline-resampled to its plane, `layout.stack_plane_size(i, work)`
    /// (docs/pyramid.md "Decimated stacks").
    pub stack: Option<Vec<Vec<f64>>>,
    /// Working resolution of the stack.
    pub work: (usize, usize),
}

fn address(p: i64, n: usize, wrap: bool) -> usize {
    let n = n as i64;
    if wrap {
        p.rem_euclid(n) as usize
    } else {
        p.clamp(0, n - 1) as usize
    }
}

fn texel(data: &[f64], w: usize, h: usize, x: i64, y: i64, wrap: bool) -> f64 {
    data[address(y, h, wrap) * w + address(x, w, wrap)]
}

/// Bilinear interpolation at `(x, y)` in texel units (centres at integers), separably and in
/// base-relative form `a + t·(b − a)` like the GPU's `hfgi_bilerp` (docs/hard-cases.md): equal
/// texels give exactly their value, rounding is relative to the local differences.
pub fn bilinear(data: &[f64], w: usize, h: usize, x: f64, y: f64, wrap: bool) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (tx, ty) = (x - fx, y - fy);
    let (ix, iy) = (fx as i64, fy as i64);
    let t = |dx, dy| texel(data, w, h, ix + dx, iy + dy, wrap);
    let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
    let top = lerp(t(0, 0), t(1, 0), tx);
    let bottom = lerp(t(0, 1), t(1, 1), tx);
    lerp(top, bottom, ty)
}

/// Uniform cubic B-spline at `(x, y)`: `Σ_{a,b} β_a(tx) β_b(ty) H[iy−1+b][ix−1+a]`, summed as
/// `H[iy][ix] + Σ β_a β_b (H[…] − H[iy][ix])` (the weights sum to 1), so that a constant
/// neighbourhood is reproduced exactly whatever its magnitude (docs/hard-cases.md).
pub fn bspline(data: &[f64], w: usize, h: usize, x: f64, y: f64, wrap: bool) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (wx, wy) = (bspline::weights(x - fx), bspline::weights(y - fy));
    let (ix, iy) = (fx as i64, fy as i64);
    let base = texel(data, w, h, ix, iy, wrap);
    let mut sum = 0.0;
    for (b, wyb) in wy.iter().enumerate() {
        for (a, wxa) in wx.iter().enumerate() {
            sum += wyb * wxa * (texel(data, w, h, ix - 1 + a as i64, iy - 1 + b as i64, wrap) - base);
        }
    }
    base + sum
}

/// Maps a coordinate on a grid `from` cells wide to a grid `to` cells wide (texel centres,
/// domain edges aligned): `(p + ½)·to/from − ½`.
pub fn rescale(p: f64, from: usize, to: usize) -> f64 {
    (p + 0.5) * to as f64 / from as f64 - 0.5
}

impl CpuPyramid {
    /// Builds every level; with `synthesize`, also the stack at working resolution `work`.
    pub fn build(field: &HeightField, work: (usize, usize), k_v: u32, wrap: bool, synthesize: bool) -> Result<Self> {
        let data: Vec<f64> = field.data().iter().map(|&v| v as f64).collect();
        Self::build_f64(data, (field.width(), field.height()), work, k_v, wrap, synthesize)
    }

    /// [`CpuPyramid::build`] of the heights relative to `origin` (`h − z0` in f64), the twin of a
    /// GPU pyramid with [`crate::frame::pyramid::HeightPyramid::set_origin`]: every level and
    /// lookup is relative to `origin`.
    pub fn build_relative(
        field: &HeightField,
        origin: f32,
        work: (usize, usize),
        k_v: u32,
        wrap: bool,
        synthesize: bool,
    ) -> Result<Self> {
        let data: Vec<f64> = field.data().iter().map(|&v| v as f64 - origin as f64).collect();
        Self::build_f64(data, (field.width(), field.height()), work, k_v, wrap, synthesize)
    }

    /// [`CpuPyramid::build`] from f64 samples (`size.0 × size.1`, row-major), e.g. one channel
    /// of a radiance image.
    pub fn build_f64(
        data: Vec<f64>,
        size: (usize, usize),
        work: (usize, usize),
        k_v: u32,
        wrap: bool,
        synthesize: bool,
    ) -> Result<Self> {
        let layout = PyramidLayout::new(size.0, size.1, k_v)?;
        let mut levels: Vec<Vec<f64>> = vec![data];
        for i in 1..layout.count() {
            let (s, d) = (layout.levels[i - 1], layout.levels[i]);
            let (sw, sh, dw, dh) = (s.width as usize, s.height as usize, d.width as usize, d.height as usize);
            let src = &levels[i - 1];
            let mut out = vec![0.0; dw * dh];
            for y in 0..dh {
                for x in 0..dw {
                    let sx = rescale(x as f64, dw, sw);
                    let sy = rescale(y as f64, dh, sh);
                    out[y * dw + x] = bilinear(src, sw, sh, sx, sy, wrap);
                }
            }
            levels.push(out);
        }
        let mut me = Self { layout, wrap, levels, stack: None, work };
        if synthesize {
            let (w, h) = size;
            let stack = (0..me.layout.count())
                .map(|i| {
                    let (ww, wh) = me.layout.stack_plane_size(i, work);
                    let mut plane = vec![0.0; ww * wh];
                    for y in 0..wh {
                        for x in 0..ww {
                            let (x0, y0) = (rescale(x as f64, ww, w), rescale(y as f64, wh, h));
                            plane[y * ww + x] = me.sample_pyramid(i, x0, y0);
                        }
                    }
                    plane
                })
                .collect();
            me.stack = Some(stack);
        }
        Ok(me)
    }

    /// True-pyramid sampling: B-spline on level `i` at `(x, y)` in level-0 texel units.
    pub fn sample_pyramid(&self, i: usize, x: f64, y: f64) -> f64 {
        let (w, h, lx, ly) = self.level_coords(i, x, y);
        bspline(&self.levels[i], w, h, lx, ly, self.wrap)
    }

    /// Level `i`'s size and the position `(x, y)` (level-0 texel units) in its texels.
    fn level_coords(&self, i: usize, x: f64, y: f64) -> (usize, usize, f64, f64) {
        let l0 = self.layout.levels[0];
        let l = self.layout.levels[i];
        let (w, h) = (l.width as usize, l.height as usize);
        (w, h, rescale(x, l0.width as usize, w), rescale(y, l0.height as usize, h))
    }

    /// Stack sampling: bilinear on stack plane `i` at `(x, y)` in level-0 texel units (mapped
    /// to the plane's grid). `None` if the stack was not built.
    pub fn sample_stack(&self, i: usize, x: f64, y: f64) -> Option<f64> {
        let l0 = self.layout.levels[0];
        let (ww, wh) = self.layout.stack_plane_size(i, self.work);
        let (xw, yw) = (rescale(x, l0.width as usize, ww), rescale(y, l0.height as usize, wh));
        self.stack.as_ref().map(|s| bilinear(&s[i], ww, wh, xw, yw, self.wrap))
    }

    /// Gradient `(∂f/∂x, ∂f/∂y)` (per texel) of the bilinear level-0 surface at `(x, y)` in the
    /// cell whose lower corner is `(cx, cy)` (the twin of `hfgi_scan_limit`).
    pub fn gradient_in_cell(&self, x: f64, y: f64, cx: i64, cy: i64) -> (f64, f64) {
        let l0 = self.layout.levels[0];
        let (w, h) = (l0.width as usize, l0.height as usize);
        let t = |dx: i64, dy: i64| texel(&self.levels[0], w, h, cx + dx, cy + dy, self.wrap);
        let (fx, fy) = (x - cx as f64, y - cy as f64);
        let gx = (t(1, 0) - t(0, 0)) * (1.0 - fy) + (t(1, 1) - t(0, 1)) * fy;
        let gy = (t(0, 1) - t(0, 0)) * (1.0 - fx) + (t(1, 1) - t(1, 0)) * fx;
        (gx, gy)
    }

    /// Level `i` unfiltered: bilinear on its texels at `(x, y)` in level-0 texel units
    /// (`gi.level0 = "bilinear"` reads level 0 this way).
    pub fn sample_raw(&self, i: usize, x: f64, y: f64) -> f64 {
        let (w, h, lx, ly) = self.level_coords(i, x, y);
        bilinear(&self.levels[i], w, h, lx, ly, self.wrap)
    }

    /// Height at level `i`, `(x, y)` in level-0 texel units, as the scanning passes read it:
    /// the stack when it was built, the B-spline on the fly otherwise.
    pub fn height_at(&self, i: usize, x: f64, y: f64) -> f64 {
        self.sample_stack(i, x, y).unwrap_or_else(|| self.sample_pyramid(i, x, y))
    }
}
