//! Loading (and, for tests and tools, saving) height fields from files.
//!
//! Formats, chosen by the extension (case-insensitive), following CONVENTIONS.md ("Height
//! field"): image row 0 is `j = 0`, and every value is multiplied by
//! [`LoadOptions::height_scale`].
//!
//! - `.png`: 8-bit grayscale (`v / 255`) or 16-bit grayscale (`v / 65535`). Grayscale of 1, 2
//!   or 4 bits is expanded to 8 bits by the decoder (full range kept) and read as 8-bit. Any
//!   other colour type (gray + alpha, RGB, RGBA, palette) is rejected.
//! - `.exr`: the first of the channels `Y`, `R`, `height` (in that order of preference) of the
//!   first layer (part) that has one; samples f16 or f32 (u32 is rejected).
//! - `.tif`, `.tiff`: a single-band GeoTIFF DEM, values as stored (`crate::scene::geotiff`:
//!   sample types, compressions, the pixel-scale and NoData tags).
//! - `.raw`, `.f32`: headerless little-endian f32, row-major; the size comes from
//!   [`LoadOptions::raw_size`] and the file must be exactly `4·w·h` bytes.
//!
//! Every failure is a typed [`Error`] whose message names the file; bad input never panics.
//! Sizes are checked against `[2, max_dim]` before pixel memory is allocated.

use std::fs::File;
use std::io::{BufReader, Cursor};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use image::codecs::png::{PngDecoder, PngEncoder};
use image::{ColorType, ExtendedColorType, ImageDecoder, ImageEncoder};

use crate::error::{Error, Result};
pub use crate::scene::geotiff::{NoData, TiffMeta};
use crate::scene::heightfield::{HeightField, DEFAULT_MAX_DIM};

/// Extensions understood by [`load_heightfield`], for messages.
pub const SUPPORTED_EXTENSIONS: &str = ".png (8- or 16-bit grayscale), .exr (channel Y, R or height; f16 or f32), \
     .tif / .tiff (single-band GeoTIFF DEM), .raw / .f32 (little-endian f32, needs raw_size)";

/// EXR channels tried for the heights, in order of preference.
pub const EXR_HEIGHT_CHANNELS: [&str; 3] = ["Y", "R", "height"];

/// How to interpret a height-field file.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Every value read is multiplied by this (world units per file unit). Default 1; must be
    /// finite.
    pub height_scale: f32,
    /// `(width, height)` of a `.raw` / `.f32` file, which carries no header. Required for those
    /// formats, ignored for the others.
    pub raw_size: Option<(usize, usize)>,
    /// Largest accepted side (the device's `maxImageDimension2D`). Default
    /// [`DEFAULT_MAX_DIM`].
    pub max_dim: u32,
    /// GeoTIFF samples equal to the file's NoData value: an error (the default) or filled.
    pub nodata: NoData,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { height_scale: 1.0, raw_size: None, max_dim: DEFAULT_MAX_DIM, nodata: NoData::Reject }
    }
}

/// Loads the height field at `path`, choosing the format by extension (see the module docs).
///
/// Errors: [`Error::Io`] (cannot open or read), [`Error::Format`] (unknown extension, empty,
/// truncated or corrupt file, wrong colour type or channels, raw file of the wrong length),
/// [`Error::FieldSize`] (a side below 2 or above `max_dim`), [`Error::NonFinite`] (NaN/Inf,
/// naming the position of the first one), [`Error::InvalidParameter`] (non-finite
/// `height_scale`, missing `raw_size`).
pub fn load_heightfield(path: &Path, opts: &LoadOptions) -> Result<HeightField> {
    Ok(load_heightfield_meta(path, opts)?.0)
}

/// [`load_heightfield`], with what a GeoTIFF says besides its samples (the default
/// [`TiffMeta`] for the other formats).
pub fn load_heightfield_meta(path: &Path, opts: &LoadOptions) -> Result<(HeightField, TiffMeta)> {
    if !opts.height_scale.is_finite() {
        return Err(Error::param("height_scale", opts.height_scale, "a finite number"));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let loader: fn(&Path, &LoadOptions) -> Result<HeightField> = match ext.as_deref() {
        Some("png") => load_png,
        Some("exr") => load_exr,
        Some("raw") | Some("f32") => load_raw,
        Some("tif") | Some("tiff") => return crate::scene::geotiff::load_tiff(path, opts),
        Some(other) => {
            return Err(Error::format(
                path,
                format!("unsupported extension '.{other}'; supported: {SUPPORTED_EXTENSIONS}"),
            ))
        }
        None => return Err(Error::format(path, format!("no file extension; supported: {SUPPORTED_EXTENSIONS}"))),
    };
    Ok((loader(path, opts)?, TiffMeta::default()))
}

/// The file's length in bytes; [`Error::Format`] if it is empty or not a regular file.
pub(crate) fn nonempty_len(path: &Path) -> Result<u64> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        let what = if meta.is_dir() { "a directory" } else { "not a regular file (a device, FIFO or socket)" };
        return Err(Error::format(path, format!("is {what}; expected a file to read")));
    }
    if meta.len() == 0 {
        return Err(Error::format(path, "empty file (0 bytes)"));
    }
    Ok(meta.len())
}

pub(crate) fn check_size(path: &Path, width: usize, height: usize, max_dim: u32) -> Result<()> {
    let max = max_dim as usize;
    if width < 2 || height < 2 || width > max || height > max {
        return Err(Error::FieldSize { source_name: path.display().to_string(), width, height, max: max_dim });
    }
    Ok(())
}

/// Largest uncompressed block (tile or group of scan lines) of an EXR file that hfgi reads:
/// 64 MiB, far above real files (a 256×256 tile or 32 lines of 16384 pixels of four f32 channels
/// are 1 and 8 MiB).
pub const MAX_EXR_BLOCK_BYTES: usize = 64 << 20;

/// Rejects an EXR file any of whose parts (`headers`) has blocks of more than
/// [`MAX_EXR_BLOCK_BYTES`]. The `exr` crate allocates and zeroes up to that size for each block
/// before reading it, however few bytes the file holds: a 564-byte file with 83886144×64 tiles
/// took 1.6 GB (found by fuzzing, docs/robustness.md "Fuzzing").
pub(crate) fn check_exr_blocks(path: &Path, headers: &[exr::meta::header::Header]) -> Result<()> {
    for header in headers {
        let (pixels, what) = match header.blocks {
            exr::meta::BlockDescription::Tiles(t) => {
                let (tw, th) = (t.tile_size.width(), t.tile_size.height());
                (tw.saturating_mul(th), format!("tiles of {tw}×{th} pixels"))
            }
            exr::meta::BlockDescription::ScanLines => {
                let lines = header.compression.scan_lines_per_block();
                (lines.saturating_mul(header.layer_size.width()), format!("blocks of {lines} scan line(s)"))
            }
        };
        let bytes = pixels.saturating_mul(header.channels.bytes_per_pixel);
        if bytes > MAX_EXR_BLOCK_BYTES {
            return Err(Error::format(
                path,
                format!(
                    "EXR {what} of {} byte(s) per pixel are {bytes} bytes each; at most {MAX_EXR_BLOCK_BYTES} are read",
                    header.channels.bytes_per_pixel
                ),
            ));
        }
    }
    Ok(())
}

/// Validates the scaled samples into a [`HeightField`] named after `path`.
pub(crate) fn finish(
    path: &Path,
    width: usize,
    height: usize,
    mut data: Vec<f32>,
    opts: &LoadOptions,
) -> Result<HeightField> {
    if opts.height_scale != 1.0 {
        for v in &mut data {
            *v *= opts.height_scale;
        }
    }
    HeightField::new(&path.display().to_string(), width, height, data, opts.max_dim)
}

/// Runs a third-party decoder, turning a panic inside it into [`Error::Format`].
pub(crate) fn guarded<T>(path: &Path, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    catch_unwind(AssertUnwindSafe(f))
        .unwrap_or_else(|_| Err(Error::format(path, format!("{what} decoder failed (corrupt file)"))))
}

fn load_png(path: &Path, opts: &LoadOptions) -> Result<HeightField> {
    nonempty_len(path)?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    guarded(path, "PNG", || {
        let mut limits = image::Limits::default();
        let side = u64::from(opts.max_dim);
        limits.max_alloc = Some((side * side * 2).max(512 << 20) + (64 << 20));
        let decoder = PngDecoder::with_limits(BufReader::new(file), limits)
            .map_err(|e| Error::format(path, format!("not a valid PNG (truncated or corrupt file?): {e}")))?;
        let (w, h) = decoder.dimensions();
        let (w, h) = (w as usize, h as usize);
        check_size(path, w, h, opts.max_dim)?;
        let color = decoder.color_type();
        let sixteen = match color {
            ColorType::L8 => false,
            ColorType::L16 => true,
            other => {
                return Err(Error::format(
                    path,
                    format!(
                        "PNG colour type {other:?} (stored as {:?}) is not accepted; expected 8- or 16-bit grayscale (L8 or L16)",
                        decoder.original_color_type()
                    ),
                ))
            }
        };
        let bytes_per = if sixteen { 2 } else { 1 };
        let mut buf = vec![0u8; w * h * bytes_per];
        if decoder.total_bytes() != buf.len() as u64 {
            return Err(Error::format(
                path,
                format!("PNG decoder reports {} bytes for {w}×{h}", decoder.total_bytes()),
            ));
        }
        decoder
            .read_image(&mut buf)
            .map_err(|e| Error::format(path, format!("truncated or corrupt PNG pixel data: {e}")))?;
        let data: Vec<f32> = if sixteen {
            buf.chunks_exact(2).map(|b| f32::from(u16::from_ne_bytes([b[0], b[1]])) / 65535.0).collect()
        } else {
            buf.iter().map(|&v| f32::from(v) / 255.0).collect()
        };
        finish(path, w, h, data, opts)
    })
}

fn load_exr(path: &Path, opts: &LoadOptions) -> Result<HeightField> {
    use exr::prelude::{read, ReadChannels, ReadLayers, ReadSpecificChannel, SampleType, Vec2};
    nonempty_len(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    guarded(path, "EXR", || {
        let corrupt = |e: exr::error::Error| Error::format(path, format!("truncated or corrupt EXR: {e}"));
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes[..]), false).map_err(corrupt)?;
        // The first layer (part) with one of the height channels, and that channel.
        let found = meta.headers.iter().find_map(|header| {
            EXR_HEIGHT_CHANNELS.iter().find_map(|name| {
                header.channels.list.iter().find(|c| c.name.eq(name)).map(|c| (header, *name, c.clone()))
            })
        });
        let Some((header, name, channel)) = found else {
            let all: Vec<String> =
                meta.headers.iter().flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string())).collect();
            return Err(Error::format(
                path,
                format!(
                    "no height channel: found channels [{}] in {} layer(s); expected one of {} (f16 or f32)",
                    all.join(", "),
                    meta.headers.len(),
                    EXR_HEIGHT_CHANNELS.join(", ")
                ),
            ));
        };
        if header.deep {
            return Err(Error::format(path, "deep EXR data is not supported; expected a flat image"));
        }
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        check_size(path, w, h, opts.max_dim)?;
        check_exr_blocks(path, &meta.headers)?;
        if !matches!(channel.sample_type, SampleType::F16 | SampleType::F32) {
            return Err(Error::format(
                path,
                format!("channel '{name}' holds {:?} samples; expected f16 or f32", channel.sample_type),
            ));
        }
        if channel.sampling != Vec2(1, 1) {
            return Err(Error::format(
                path,
                format!("channel '{name}' is subsampled {:?}; expected one sample per pixel", channel.sampling),
            ));
        }
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .specific_channels()
            .required(name)
            .collect_pixels(
                move |size: Vec2<usize>, _| (size.width(), vec![0.0f32; size.area()]),
                |(width, data): &mut (usize, Vec<f32>), pos: Vec2<usize>, (v,): (f32,)| {
                    if let Some(s) = data.get_mut(pos.y() * *width + pos.x()) {
                        *s = v;
                    }
                },
            )
            .first_valid_layer()
            .all_attributes()
            // On the calling thread: a panic in a decompressor running on exr's rayon pool
            // aborts the process, past `guarded` (found by fuzzing, docs/robustness.md).
            .non_parallel()
            .from_buffered(Cursor::new(&bytes[..]))
            .map_err(corrupt)?;
        let layer = image.layer_data;
        let (rw, rh) = (layer.size.width(), layer.size.height());
        let (width, data) = layer.channel_data.pixels;
        if (rw, rh) != (w, h) || width != w || data.len() != w * h {
            return Err(Error::format(path, format!("EXR layer is {rw}×{rh}, header said {w}×{h}")));
        }
        finish(path, w, h, data, opts)
    })
}

fn load_raw(path: &Path, opts: &LoadOptions) -> Result<HeightField> {
    let Some((w, h)) = opts.raw_size else {
        return Err(Error::param(
            "raw_size",
            "none",
            format!("(width, height) for {}: a .raw/.f32 file (little-endian f32) carries no size", path.display()),
        ));
    };
    check_size(path, w, h, opts.max_dim)?;
    let expected = (w as u64) * (h as u64) * 4;
    let found = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !found.is_file() {
        let what = if found.is_dir() { "a directory" } else { "not a regular file (a device, FIFO or socket)" };
        return Err(Error::format(path, format!("is {what}; expected a file to read")));
    }
    let wrong = |found: u64| {
        let hint = if found == 0 {
            " (empty file)"
        } else if found < expected {
            " (truncated?)"
        } else {
            ""
        };
        Error::format(
            path,
            format!("raw f32 file of {w}×{h}: expected {expected} bytes (4·{w}·{h}, little-endian f32), found {found} bytes{hint}"),
        )
    };
    if found.len() != expected {
        return Err(wrong(found.len()));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 != expected {
        return Err(wrong(bytes.len() as u64));
    }
    let data = bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    finish(path, w, h, data, opts)
}

/// Writes `field` as headerless little-endian f32, row-major (readable with
/// `raw_size = Some((width, height))`).
pub fn save_raw(field: &HeightField, path: &Path) -> Result<()> {
    let bytes: Vec<u8> = field.data().iter().flat_map(|v| v.to_le_bytes()).collect();
    crate::io::atomic::write_bytes(path, &bytes)
}

/// Writes `field` as a 16-bit grayscale PNG, mapping `min..max` linearly to `0..65535`
/// (rounded to nearest), and returns `(min, max)`. A constant field is written as all 0.
/// Loading it back with `height_scale = max − min` and adding `min` recovers the heights to
/// within `(max − min) / 131070`.
pub fn save_png16(field: &HeightField, path: &Path) -> Result<(f32, f32)> {
    let (lo, hi) = field.range();
    let span = f64::from(hi) - f64::from(lo);
    let mut buf = Vec::with_capacity(field.data().len() * 2);
    for &v in field.data() {
        let q = if span > 0.0 {
            ((f64::from(v) - f64::from(lo)) / span * 65535.0).round().clamp(0.0, 65535.0) as u16
        } else {
            0
        };
        buf.extend_from_slice(&q.to_ne_bytes());
    }
    let (w, h) = dims_u32(path, field.width(), field.height())?;
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(&buf, w, h, ExtendedColorType::L16)
        .map_err(|e| Error::format(path, format!("PNG encoding failed: {e}")))?;
    crate::io::atomic::write_bytes(path, &out)?;
    Ok((lo, hi))
}

/// `(width, height)` as `u32` for an image encoder, or [`Error::FieldSize`].
pub(crate) fn dims_u32(path: &Path, width: usize, height: usize) -> Result<(u32, u32)> {
    match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => Err(Error::FieldSize { source_name: path.display().to_string(), width, height, max: u32::MAX }),
    }
}
