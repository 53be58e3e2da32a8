//! Animated GIF output (the `image` crate's `gif` feature): tone-mapped frames, looping forever.

use std::path::Path;

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbaImage};

use crate::error::{Error, Result};
use crate::io::png::{srgb_encode, NAN_COLOUR};

/// Tone-maps linear RGB to 8-bit sRGB RGBA exactly as [`crate::io::png::write_tonemapped`]
/// does (gain `2^exposure`, clamp to [0, 1], sRGB encode, round; NaN pixels magenta), alpha 255.
pub fn tonemap_rgba8(rgb: &[[f32; 3]], exposure: f32) -> Result<Vec<u8>> {
    if !exposure.is_finite() {
        return Err(Error::param("exposure", exposure, "a finite number of stops"));
    }
    let gain = exposure.exp2();
    let mut out = Vec::with_capacity(rgb.len() * 4);
    for px in rgb {
        if px.iter().any(|c| c.is_nan()) {
            out.extend_from_slice(&NAN_COLOUR);
        } else {
            out.extend(
                px.iter().map(|&c| (srgb_encode((c * gain).clamp(0.0, 1.0)).clamp(0.0, 1.0) * 255.0 + 0.5) as u8),
            );
        }
        out.push(255);
    }
    Ok(out)
}

/// Writes `frames` (each RGBA8, `width·height` pixels, e.g. from [`tonemap_rgba8`]) as an
/// animated GIF at `fps` frames per second (`(0, 100]`; GIF delays are whole centiseconds, so
/// the rate is rounded to the nearest such delay), looping forever. Each frame is quantised to
/// its own 256-colour palette.
pub fn write_gif(path: &Path, width: usize, height: usize, frames: &[Vec<u8>], fps: f64) -> Result<()> {
    if !(fps.is_finite() && fps > 0.0 && fps <= 100.0) {
        return Err(Error::param("fps", fps, "a number in (0, 100] (frames per second)"));
    }
    if frames.is_empty() {
        return Err(Error::param("GIF frames", 0, "at least one frame"));
    }
    let (w, h) = crate::scene::load::dims_u32(path, width, height)?;
    let mut bytes = Vec::new();
    let mut enc = GifEncoder::new_with_speed(&mut bytes, 10);
    let fail = |e: image::ImageError| Error::format(path, format!("GIF encoding failed: {e}"));
    enc.set_repeat(Repeat::Infinite).map_err(fail)?;
    let delay = Delay::from_numer_denom_ms((1.0e6 / fps).round() as u32, 1000);
    for (i, f) in frames.iter().enumerate() {
        if f.len() != width * height * 4 {
            return Err(Error::param(
                format!("GIF frame {i} length"),
                f.len(),
                format!("{} bytes (RGBA8, {width}×{height})", width * height * 4),
            ));
        }
        let img = RgbaImage::from_raw(w, h, f.clone())
            .ok_or_else(|| Error::format(path, format!("frame {i}: buffer does not match {width}×{height}")))?;
        enc.encode_frame(Frame::from_parts(img, 0, 0, delay)).map_err(fail)?;
    }
    drop(enc);
    crate::io::atomic::write_bytes(path, &bytes)
}
