//! CPU twin and layout of the max pyramid (stage `pyramid.max`, `glsl/inc/hfgi_max.glsl`,
//! docs/accuracy.md §4): per level `L`, `⌈W/2^L⌉ × ⌈H/2^L⌉` cells; `m_L[c]` is the largest
//! level-0 texel whose bilinear cells touch cell `c` (positions `[c·2^L, (c+1)·2^L]` per axis) and
//! `ov_L[c] = max(m_L[c], m_L[c+1])` (clamped) bounds positions `[c·2^L, (c+2)·2^L]`: the
//! bilinear surface over a box of extent `≤ 2^L` whose lower corner lies in cell `c` is `≤ ov_L[c]`.

/// Most levels: fields of up to 65 536 texels per axis (`HFGI_MAX_LEVELS`).
pub const MAX_LEVELS: usize = 17;

/// Sizes and offsets (floats) of the two arrays of levels, `m` then `ov`, in one buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaxLayout {
    /// Level 0's size (the height field's).
    pub n0: (usize, usize),
    /// Per level: `(width, height, offset of m_L)`; `ov_L` is at `offset + m_total`.
    pub levels: Vec<(usize, usize, usize)>,
    /// Floats of all `m` levels (the `ov` levels take as many).
    pub m_total: usize,
}

impl MaxLayout {
    /// The layout for a `w × h` field (`hfgi_max_count`, `hfgi_max_size`, `hfgi_max_offset`).
    pub fn new(w: usize, h: usize) -> Self {
        let size = |l: usize| (w.div_ceil(1 << l), h.div_ceil(1 << l));
        let mut levels = Vec::new();
        let mut total = 0;
        for l in 0..MAX_LEVELS {
            let (sw, sh) = size(l);
            levels.push((sw, sh, total));
            total += sw * sh;
            if sw <= 1 && sh <= 1 {
                break;
            }
        }
        Self { n0: (w, h), levels, m_total: total }
    }

    /// Floats of the whole buffer (`m` and `ov`).
    pub fn floats(&self) -> usize {
        2 * self.m_total
    }

    /// `ov_L` at cell `(x, y)` of `data` (a buffer of this layout).
    pub fn ov(&self, data: &[f32], level: usize, x: usize, y: usize) -> f32 {
        let (w, _, off) = self.levels[level];
        data[self.m_total + off + y * w + x]
    }

    /// The bound of the bilinear level-0 surface over the segment `a`–`b` (level-0 positions),
    /// as the indirect scan read it until docs/performance.md §18 (`max_over` in
    /// `glsl/indirect/scan.comp.glsl`; the scan now reads only the top, the field's largest height).
    pub fn bound(&self, data: &[f32], a: [f64; 2], b: [f64; 2]) -> f32 {
        let lo = [a[0].min(b[0]), a[1].min(b[1])];
        let e = (a[0] - b[0]).abs().max((a[1] - b[1]).abs()).ceil() as usize;
        let level =
            if e <= 1 { 0 } else { (usize::BITS - (e - 1).leading_zeros()) as usize }.min(self.levels.len() - 1);
        let (w, h, _) = self.levels[level];
        let cell = |v: f64, n: usize| ((v / (1u64 << level) as f64).floor().max(0.0) as usize).min(n - 1);
        self.ov(data, level, cell(lo[0], w), cell(lo[1], h))
    }
}

/// The max pyramid of `heights` (`w × h`, row-major, already relative to the height origin), as
/// `pyramid.max` writes it.
pub fn build(heights: &[f32], w: usize, h: usize) -> (MaxLayout, Vec<f32>) {
    let layout = MaxLayout::new(w, h);
    let mut data = vec![f32::NEG_INFINITY; layout.floats()];
    // The largest of n × n values of `src` (size sw × sh) from (x, y), indices clamped.
    let block = |src: &[f32], sw: usize, sh: usize, x: usize, y: usize, n: usize| {
        let mut m = f32::NEG_INFINITY;
        for j in 0..n {
            for i in 0..n {
                m = m.max(src[(y + j).min(sh - 1) * sw + (x + i).min(sw - 1)]);
            }
        }
        m
    };
    for (l, &(lw, lh, off)) in layout.levels.iter().enumerate() {
        let (src, sw, sh, step, n_m, n_ov): (Vec<f32>, _, _, _, _, _) = if l == 0 {
            (heights.to_vec(), w, h, 1, 2, 3)
        } else {
            let (pw, ph, po) = layout.levels[l - 1];
            (data[po..po + pw * ph].to_vec(), pw, ph, 2, 2, 4)
        };
        for y in 0..lh {
            for x in 0..lw {
                data[off + y * lw + x] = block(&src, sw, sh, step * x, step * y, n_m);
                data[layout.m_total + off + y * lw + x] = block(&src, sw, sh, step * x, step * y, n_ov);
            }
        }
    }
    (layout, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bilinear surface at level-0 position (x, y), clamped to the field.
    fn bilinear(hs: &[f32], w: usize, h: usize, x: f64, y: f64) -> f64 {
        let (x, y) = (x.clamp(0.0, (w - 1) as f64), y.clamp(0.0, (h - 1) as f64));
        let (x0, y0) = ((x.floor() as usize).min(w - 1), (y.floor() as usize).min(h - 1));
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let at = |i: usize, j: usize| hs[j * w + i] as f64;
        let a = at(x0, y0) + fx * (at(x1, y0) - at(x0, y0));
        let b = at(x0, y1) + fx * (at(x1, y1) - at(x0, y1));
        a + fy * (b - a)
    }

    #[test]
    fn layout_ends_at_one_cell_and_the_top_is_the_largest_height() {
        let (w, h) = (37, 5);
        let hs: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 101) as f32 - 50.0).collect();
        let (layout, data) = build(&hs, w, h);
        let top = layout.levels.len() - 1;
        assert_eq!(&layout.levels[top].0..=&layout.levels[top].1, &1..=&1);
        assert_eq!(layout.levels.len(), 7, "37 → 19 → 10 → 5 → 3 → 2 → 1");
        let hmax = hs.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(layout.ov(&data, top, 0, 0), hmax);
    }

    /// The bound holds for any segment: brute-force samples of the bilinear surface along it
    /// never exceed it, on 400 random fields with spikes, of random non-square sizes, and random
    /// segments of up to 60 texels (a seeded generator: the cases are the same on every run).
    #[test]
    fn the_bound_is_never_below_the_surface_on_a_segment() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..400 {
            let (w, h) = (2 + (next() * 38.0) as usize, 2 + (next() * 38.0) as usize);
            let hs: Vec<f32> = (0..w * h)
                .map(|_| {
                    let r = next() as f32;
                    if r > 0.97 {
                        40.0 * r
                    } else {
                        r - 0.5
                    }
                })
                .collect();
            let (layout, data) = build(&hs, w, h);
            let a = [next() * (w - 1) as f64, next() * (h - 1) as f64];
            let (len, phi) = (60.0 * next(), std::f64::consts::TAU * next());
            let b = [
                (a[0] + len * phi.cos()).clamp(0.0, (w - 1) as f64),
                (a[1] + len * phi.sin()).clamp(0.0, (h - 1) as f64),
            ];
            let bound = layout.bound(&data, a, b) as f64;
            for k in 0..=400 {
                let f = k as f64 / 400.0;
                let v = bilinear(&hs, w, h, a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
                assert!(v <= bound + 1e-6, "{w}×{h}: surface {v} above the bound {bound} at {f} of {a:?}–{b:?}");
            }
        }
    }
}
