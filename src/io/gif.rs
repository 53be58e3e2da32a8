//! Animated GIF output: tone-mapped frames, looping forever — whole ([`write_gif`], through the
//! `image` crate) or streamed frame by frame to disk ([`GifStream`], through the `gif` crate),
//! so that a long animation never holds its frames in memory.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbaImage};

use crate::error::{Error, Result};
use crate::io::atomic::TempFile;
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

/// An animated GIF written frame by frame (docs/robustness.md, "Bounded inputs and work"): each
/// [`GifStream::push`] quantises one frame and appends it to a temporary file next to the
/// target, so memory holds one frame whatever the frame count; [`GifStream::finish`] writes
/// the trailer and commits the file atomically ([`TempFile`]). Dropped unfinished, nothing is
/// left and the target is unchanged. Frames as in [`write_gif`].
pub struct GifStream {
    encoder: Option<gif::Encoder<BufWriter<File>>>,
    file: TempFile,
    width: usize,
    height: usize,
    delay_cs: u16,
    frames: usize,
}

impl GifStream {
    /// Starts a GIF of `width × height` at `fps` frames per second (`(0, 100]`) at `path`.
    pub fn create(path: &Path, width: usize, height: usize, fps: f64) -> Result<Self> {
        if !(fps.is_finite() && fps > 0.0 && fps <= 100.0) {
            return Err(Error::param("fps", fps, "a number in (0, 100] (frames per second)"));
        }
        let (w, h) = crate::scene::load::dims_u32(path, width, height)?;
        let (w, h) = match (u16::try_from(w), u16::try_from(h)) {
            (Ok(w), Ok(h)) => (w, h),
            _ => return Err(Error::format(path, format!("GIF frames are at most 65535×65535; got {width}×{height}"))),
        };
        let file = TempFile::create(path)?;
        let fail = |e: gif::EncodingError| Error::format(path, format!("GIF encoding failed: {e}"));
        let mut encoder = gif::Encoder::new(BufWriter::new(file.writer()?), w, h, &[]).map_err(fail)?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(fail)?;
        let delay_cs = (100.0 / fps).round().clamp(1.0, f64::from(u16::MAX)) as u16;
        Ok(Self { encoder: Some(encoder), file, width, height, delay_cs, frames: 0 })
    }

    /// Appends one RGBA8 frame of the stream's size (e.g. from [`tonemap_rgba8`]).
    pub fn push(&mut self, rgba: &[u8]) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if rgba.len() != w * h * 4 {
            return Err(Error::param(
                format!("GIF frame {} length", self.frames),
                rgba.len(),
                format!("{} bytes (RGBA8, {w}×{h})", w * h * 4),
            ));
        }
        let path = self.file.path().to_path_buf();
        let encoder = self.encoder.as_mut().ok_or_else(|| Error::format(&path, "GIF already finished"))?;
        let mut pixels = rgba.to_vec();
        let mut frame = gif::Frame::from_rgba_speed(w as u16, h as u16, &mut pixels, 10);
        frame.delay = self.delay_cs;
        encoder.write_frame(&frame).map_err(|e| Error::format(&path, format!("GIF encoding failed: {e}")))?;
        self.frames += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Writes the trailer, flushes, syncs and commits the file (staged inside
    /// [`crate::io::atomic::all_or_nothing`]). At least one frame is needed.
    pub fn finish(mut self) -> Result<()> {
        let path = self.file.path().to_path_buf();
        if self.frames == 0 {
            return Err(Error::param("GIF frames", 0, "at least one frame"));
        }
        let encoder = self.encoder.take().ok_or_else(|| Error::format(&path, "GIF already finished"))?;
        let mut writer = encoder.into_inner().map_err(|e| Error::format(&path, format!("GIF encoding failed: {e}")))?;
        writer.flush().map_err(|e| Error::io(&path, e))?;
        drop(writer);
        let Self { file, .. } = self;
        file.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn a_streamed_gif_appears_only_when_finished() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.gif");
        std::fs::write(&path, b"previous").unwrap();
        let frame = |v: u8| vec![v; 5 * 3 * 4];
        // Dropped unfinished (an error mid-animation): the previous file stays, nothing is left.
        let mut s = GifStream::create(&path, 5, 3, 25.0).unwrap();
        s.push(&frame(10)).unwrap();
        assert!(s.push(&[0u8; 7]).is_err());
        drop(s);
        assert_eq!(std::fs::read(&path).unwrap(), b"previous");
        assert_eq!(entries(dir.path()), ["a.gif"]);
        // Finished: replaced whole, with every frame.
        let mut s = GifStream::create(&path, 5, 3, 25.0).unwrap();
        for v in [0, 100, 200] {
            s.push(&frame(v)).unwrap();
        }
        assert_eq!(s.frames(), 3);
        s.finish().unwrap();
        let mut d = gif::DecodeOptions::new().read_info(std::fs::File::open(&path).unwrap()).unwrap();
        let mut n = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            assert_eq!((f.width, f.height, f.delay), (5, 3, 4));
            n += 1;
        }
        assert_eq!(n, 3);
        assert_eq!(entries(dir.path()), ["a.gif"]);
        // No frame: an error, nothing written.
        let empty = GifStream::create(&dir.path().join("b.gif"), 5, 3, 25.0).unwrap();
        assert!(empty.finish().is_err());
        assert_eq!(entries(dir.path()), ["a.gif"]);
    }
}
