//! 8-bit PNG previews: tonemapped linear RGB and normalised grayscale.
//!
//! Image row 0 is data row `j = 0` (the top of the image is the first row).

use std::path::Path;

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

use crate::error::{Error, Result};
use crate::scene::load::dims_u32;

/// The colour written for a pixel with a NaN in any channel (magenta, so it stands out).
pub const NAN_COLOUR: [u8; 3] = [255, 0, 255];

/// The sRGB opto-electronic transfer function (IEC 61966-2-1), exact piecewise form:
/// `12.92·x` for `x ≤ 0.0031308`, else `1.055·x^(1/2.4) − 0.055`. Meant for `x ∈ [0, 1]`
/// (the result is then in `[0, 1]`); other inputs are not clamped, NaN gives NaN.
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Quantises `v ∈ [0, 1]` to 8 bits, rounding to nearest.
fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Writes linear RGB as an 8-bit sRGB PNG: each channel is multiplied by `2^exposure`,
/// clamped to `[0, 1]` (so +Inf → 1, −Inf → 0), encoded with [`srgb_encode`] and rounded to
/// 8 bits. A pixel with a NaN in any channel is written as [`NAN_COLOUR`] (magenta); a
/// non-finite `exposure` is [`Error::InvalidParameter`]. `rgb` is row-major,
/// `width·height` pixels.
pub fn write_tonemapped(path: &Path, width: usize, height: usize, rgb: &[[f32; 3]], exposure: f32) -> Result<()> {
    if !exposure.is_finite() {
        return Err(Error::param("exposure", exposure, "a finite number of stops"));
    }
    check_len(path, width, height, rgb.len())?;
    let gain = exposure.exp2();
    let mut buf = Vec::with_capacity(rgb.len() * 3);
    for px in rgb {
        if px.iter().any(|c| c.is_nan()) {
            buf.extend_from_slice(&NAN_COLOUR);
        } else {
            buf.extend(px.iter().map(|&c| to_u8(srgb_encode((c * gain).clamp(0.0, 1.0)))));
        }
    }
    write_png(path, width, height, &buf, ExtendedColorType::Rgb8)
}

/// Writes `data` (row-major, `width·height`) as an 8-bit grayscale PNG mapping its finite
/// `min..max` linearly to `0..255` (rounded), and returns `(min, max)`. A constant field is
/// written as mid grey (128). Non-finite samples are ignored for the range and written as
/// 255 (+Inf) or 0 (NaN, −Inf); with no finite sample at all the range is `(0, 0)`.
pub fn write_gray_normalized(path: &Path, width: usize, height: usize, data: &[f32]) -> Result<(f32, f32)> {
    check_len(path, width, height, data.len())?;
    let (lo, hi) = data
        .iter()
        .filter(|v| v.is_finite())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 0.0) };
    let span = f64::from(hi) - f64::from(lo);
    let buf: Vec<u8> = data
        .iter()
        .map(|&v| {
            if v.is_nan() || v == f32::NEG_INFINITY {
                0
            } else if v == f32::INFINITY {
                255
            } else if span > 0.0 {
                ((f64::from(v) - f64::from(lo)) / span * 255.0).round().clamp(0.0, 255.0) as u8
            } else {
                128
            }
        })
        .collect();
    write_png(path, width, height, &buf, ExtendedColorType::L8)?;
    Ok((lo, hi))
}

fn check_len(path: &Path, width: usize, height: usize, len: usize) -> Result<()> {
    if width == 0 || height == 0 || width.checked_mul(height) != Some(len) {
        return Err(Error::param(
            format!("{}: pixel count", path.display()),
            len,
            format!("width·height = {width}×{height} pixels (both ≥ 1)"),
        ));
    }
    Ok(())
}

fn write_png(path: &Path, width: usize, height: usize, buf: &[u8], color: ExtendedColorType) -> Result<()> {
    let (w, h) = dims_u32(path, width, height)?;
    let mut out = Vec::new();
    PngEncoder::new(&mut out).write_image(buf, w, h, color).map_err(|e| match e {
        image::ImageError::IoError(io) => Error::io(path, io),
        other => Error::format(path, format!("PNG encoding failed: {other}")),
    })?;
    super::atomic::write_bytes(path, &out)
}
