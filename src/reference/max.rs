//! CPU twin and layout of the max reduction of the level-0 heights (stage `pyramid.max`,
//! `glsl/inc/hfgi_max.glsl`, docs/accuracy.md §4): level `L` has `⌈W/8^(L+1)⌉ × ⌈H/8^(L+1)⌉`
//! cells; `m_0[c]` is the largest texel of the 8 × 8 block `c`, `m_L[c]` the largest of the
//! 8 × 8 cells `8c …` of level `L − 1` (indices clamped), until one cell: the field's largest
//! height, which the indirect scan's early stop reads. (Until docs/performance.md §19 it was a
//! max pyramid of 2 × 2 cells with overlapping copies for the scan's per-gap bound, which §18
//! retired; the reduction keeps only what the early stop reads, 1/63 of the field.)

/// Most levels: fields of up to 8⁶ = 262 144 texels per axis (`HFGI_MAX_LEVELS`).
pub const MAX_LEVELS: usize = 6;
/// Cells per axis that one cell of the next level takes the largest of.
pub const BLOCK: usize = 8;

/// Sizes and offsets (floats) of the levels, in one buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaxLayout {
    /// Level 0's size (the height field's).
    pub n0: (usize, usize),
    /// Per level: `(width, height, offset)`.
    pub levels: Vec<(usize, usize, usize)>,
    /// Floats of all levels.
    pub total: usize,
}

impl MaxLayout {
    /// The layout for a `w × h` field (`hfgi_max_count`, `hfgi_max_size`, `hfgi_max_offset`).
    pub fn new(w: usize, h: usize) -> Self {
        let mut levels = Vec::new();
        let (mut sw, mut sh, mut total) = (w, h, 0);
        for _ in 0..MAX_LEVELS {
            (sw, sh) = (sw.div_ceil(BLOCK), sh.div_ceil(BLOCK));
            levels.push((sw, sh, total));
            total += sw * sh;
            if sw <= 1 && sh <= 1 {
                break;
            }
        }
        Self { n0: (w, h), levels, total }
    }

    /// Floats of the whole buffer.
    pub fn floats(&self) -> usize {
        self.total
    }

    /// The top, the field's largest height, in `data` (a buffer of this layout).
    pub fn top(&self, data: &[f32]) -> f32 {
        data[self.levels[self.levels.len() - 1].2]
    }
}

/// The reduction of `heights` (`w × h`, row-major, already relative to the height origin), as
/// `pyramid.max` writes it.
pub fn build(heights: &[f32], w: usize, h: usize) -> (MaxLayout, Vec<f32>) {
    let layout = MaxLayout::new(w, h);
    let mut data = vec![f32::NEG_INFINITY; layout.floats()];
    let (mut src, mut sw, mut sh) = (heights.to_vec(), w, h);
    for &(lw, lh, off) in &layout.levels {
        for y in 0..lh {
            for x in 0..lw {
                let mut m = f32::NEG_INFINITY;
                for j in 0..BLOCK {
                    for i in 0..BLOCK {
                        m = m.max(src[(BLOCK * y + j).min(sh - 1) * sw + (BLOCK * x + i).min(sw - 1)]);
                    }
                }
                data[off + y * lw + x] = m;
            }
        }
        (src, sw, sh) = (data[off..off + lw * lh].to_vec(), lw, lh);
    }
    (layout, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_ends_at_one_cell_and_the_top_is_the_largest_height() {
        let (w, h) = (37, 5);
        let hs: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 101) as f32 - 50.0).collect();
        let (layout, data) = build(&hs, w, h);
        assert_eq!(layout.levels, vec![(5, 1, 0), (1, 1, 5)], "37 × 5 → 5 × 1 → 1 × 1");
        let hmax = hs.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(layout.top(&data), hmax);
    }

    /// On 400 random fields of random sizes from 1 × 1 to 600 × 70 (a seeded generator: the
    /// same cases on every run), with one spike anywhere, below zero or not, the top is the
    /// largest height and every level ends where the next one has one cell.
    #[test]
    fn the_top_is_the_largest_height_of_any_field() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..400 {
            let (w, h) = (1 + (next() * 600.0) as usize, 1 + (next() * 70.0) as usize);
            let mut hs: Vec<f32> = (0..w * h).map(|_| next() as f32 - 2.0).collect();
            let spike = (next() * (w * h) as f64) as usize % (w * h);
            hs[spike] = 40.0 * next() as f32 - 1.0;
            let (layout, data) = build(&hs, w, h);
            let hmax = hs.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            assert_eq!(layout.top(&data), hmax, "{w}×{h}");
            let &(tw, th, _) = layout.levels.last().unwrap();
            assert_eq!((tw, th), (1, 1), "{w}×{h}: {:?}", layout.levels);
            assert_eq!(layout.floats(), data.len());
        }
    }
}
