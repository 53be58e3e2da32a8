//! The shared-exponent RGB word of the shading planes (Ward's RGBE, as in Radiance `.hdr` files,
//! with the exponent rule of the Vulkan specification's shared-exponent conversion and rounding
//! to nearest, ties to even): three 8-bit mantissas `r`, `g`, `b` (bits 0–7, 8–15, 16–23) and
//! one 8-bit exponent `e` (bits 24–31), the value of a channel `m · 2^(e − 127 − 8)`. The
//! shading planes use it with `gi.shading_storage = "rgbe"`, and with the default `"auto"` when GI
//! is sub-sampled (docs/integration.md, "Shading buffer"); `glsl/inc/hfgi_plane.glsl` packs with
//! the same rounding, so that this module reproduces the GPU's words bit for bit.
//!
//! Precision: the largest channel keeps 8 significant bits (a rounding error of at most 2⁻⁹ of
//! its value … 2⁻⁸), a smaller one the same absolute step. Range: the whole of f32's (no
//! pre-exposure: lights scaled by a power of two scale the words' exponents only); negative
//! channels clamp to 0, larger ones than [`MAX`] to it. A non-finite channel (NaN, ±∞) packs to
//! [`NON_FINITE`], which unpacks to NaN in every channel, so that a non-finite result stays
//! visible.

/// Mantissa bits per channel (`N`).
const MANTISSA_BITS: i32 = 8;
/// Exponent bias (`B`): field `e` scales by `2^(e − B − N)`.
const BIAS: i32 = 127;
/// The largest channel value: `(2⁸ − 1) · 2^(255 − 127 − 8)`, just below `f32::MAX`.
pub const MAX: f32 = 3.389_531_4e38; // 255 · 2¹²⁰ (bits 0x7f7f_0000; a test checks it)
/// The word of a texel with a non-finite channel (all bits set; the finite value it would
/// otherwise be, `MAX` in every channel, packs one mantissa step lower in red).
pub const NON_FINITE: u32 = u32::MAX;

/// `2^k` for `k` in −149 … 127, exactly.
fn pow2(k: i32) -> f32 {
    if k >= -126 {
        f32::from_bits(((k + 127) as u32) << 23)
    } else {
        f32::from_bits(1 << (k + 149))
    }
}

/// `v · 2^k` for `k` in −270 … 270, in two exact steps (`2^k` alone may leave f32's range);
/// `hfgi_rgbe_scale` in the shaders.
fn scale(v: f32, k: i32) -> f32 {
    v * pow2(k / 2) * pow2(k - k / 2)
}

/// `⌊log₂ x⌋` of a positive f32, exactly (GLSL: `frexp`).
fn floor_log2(x: f32) -> i32 {
    let bits = x.to_bits();
    let e = ((bits >> 23) & 0xff) as i32;
    if e == 0 {
        // Subnormal: 2⁻¹²⁶ · (mantissa / 2²³).
        -126 - 23 + (31 - (bits & 0x7f_ffff).leading_zeros() as i32)
    } else {
        e - 127
    }
}

/// The mantissa of `v` at exponent field `e`: `v · 2^(B + N − e)` rounded to nearest, ties to
/// even ([`scale`]). Ties are
/// common — a sum of two planes' texels (the total) often falls half-way between two steps —
/// and rounding them up (the Vulkan rule's `⌊x + ½⌋`) biased the total by +2.5e-4…5.3e-4
/// (docs/performance.md §36).
fn mantissa(v: f32, e: i32) -> f32 {
    scale(v, BIAS + MANTISSA_BITS - e).round_ties_even()
}

/// Packs `rgb`: `e = max(−B − 1, ⌊log₂ max⌋) + 1 + B`, plus one where the largest mantissa
/// rounds up to 2⁸; mantissas rounded to nearest, ties to even.
pub fn pack(rgb: [f32; 3]) -> u32 {
    if rgb.iter().any(|c| !c.is_finite()) {
        return NON_FINITE;
    }
    let c = rgb.map(|v| v.clamp(0.0, MAX));
    let m = c[0].max(c[1]).max(c[2]);
    if m == 0.0 {
        return 0;
    }
    let mut e = floor_log2(m).max(-BIAS - 1) + 1 + BIAS;
    if mantissa(m, e) >= 256.0 {
        e += 1;
    }
    let q = c.map(|v| mantissa(v, e) as u32);
    let w = q[0] | (q[1] << 8) | (q[2] << 16) | ((e as u32) << 24);
    if w == NON_FINITE {
        w - 1
    } else {
        w
    }
}

/// Unpacks a word: `m · 2^(e − B − N)` per channel; [`NON_FINITE`] gives NaN.
pub fn unpack(w: u32) -> [f32; 3] {
    if w == NON_FINITE {
        return [f32::NAN; 3];
    }
    let k = (w >> 24) as i32 - BIAS - MANTISSA_BITS;
    [w & 255, (w >> 8) & 255, (w >> 16) & 255].map(|m| scale(m as f32, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: [f32; 3], b: [f32; 3]) -> f32 {
        let m = b[0].max(b[1]).max(b[2]);
        (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max) / m
    }

    #[test]
    fn round_trip_keeps_eight_bits_of_the_largest_channel() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..20000 {
            // The largest channel anywhere in 2⁻¹²⁰ … 2¹²⁰.
            let scale = 2f32.powf(next() * 240.0 - 120.0);
            let mut v = [scale, next() * scale, next() * scale];
            v.rotate_left((next() * 3.0) as usize);
            let u = unpack(pack(v));
            // Round to nearest: half a step, with the largest channel's mantissa ≥ 2⁷.
            assert!(rel(u, v) <= 1.0 / 256.0 + 1e-6, "{v:?} → {u:?}");
        }
    }

    #[test]
    fn representable_values_are_exact_and_words_are_canonical() {
        for w in [0x0000_0001u32, 0x7f00_0000 | 255 | (3 << 8) | (128 << 16), 0xfe00_00ff, 12 << 24 | 200] {
            let v = unpack(w);
            assert_eq!(unpack(pack(v)), v, "{w:#x}");
            assert_eq!(pack(v), w, "{w:#x}");
        }
        assert_eq!(unpack(pack([1.0, 0.5, 0.25])), [1.0, 0.5, 0.25]);
        assert_eq!(pack([0.0; 3]), 0);
        // Ties round to even: 200.5 → 200, 201.5 → 202 (at the exponent of 255 ≤ 2⁸).
        assert_eq!(unpack(pack([255.0, 200.5, 201.5])), [255.0, 200.0, 202.0]);
        // A power-of-two scale moves the exponent only.
        let v = [0.37, 1.9, 0.011];
        assert_eq!(pack(v.map(|c| c * 2f32.powi(20))), pack(v) + (20 << 24));
    }

    #[test]
    fn clamps_negative_and_large_and_marks_non_finite() {
        assert_eq!(unpack(pack([-1.0, 2.0, -0.0])), [0.0, 2.0, 0.0]);
        assert_eq!(unpack(pack([f32::MAX, 0.0, 0.0]))[0], MAX);
        assert_eq!(MAX, 255.0 * 2f32.powi(120));
        assert!(unpack(pack([MAX; 3])).iter().all(|c| c.is_finite()));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(pack([1.0, bad, 1.0]), NON_FINITE);
            assert!(unpack(NON_FINITE).iter().all(|c| c.is_nan()));
        }
    }

    #[test]
    fn exponents_and_powers_of_two_are_exact() {
        assert_eq!(floor_log2(f32::from_bits(1)), -149);
        assert_eq!(floor_log2(0.75), -1);
        assert_eq!(floor_log2(f32::MAX), 127);
        for k in -149..=127 {
            assert_eq!(pow2(k), 2f64.powi(k) as f32, "2^{k}");
        }
    }
}
