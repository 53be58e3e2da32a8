//! GeoTIFF digital elevation models (`.tif`, `.tiff`): one band of f32, f64, i8, i16, i32, u8,
//! u16 or u32 samples (f16, i64 and u64 too), stripped or tiled, uncompressed, LZW, Deflate or
//! PackBits, read with the `tiff` crate. Values are taken as they are (metres for a DEM),
//! times [`LoadOptions::height_scale`]; integer samples are not normalised (unlike PNG).
//!
//! GeoTIFF tags read (docs/scene-format.md, `[heightfield]`):
//! - `ModelPixelScaleTag` (33550): the texel size, when the scene does not give one
//!   ([`TiffMeta::pixel_scale`]); a geographic model (`GTModelTypeGeoKey` = 2 in the
//!   `GeoKeyDirectoryTag`, 34735) has its scale in degrees, which the scene must then override.
//! - `GDAL_NODATA` (42113): samples equal to it are missing; [`NoData`] says whether that is an
//!   error naming the first one's position or they are filled.
//!
//! Only the first image (IFD) is read. Sizes are checked before pixel memory is allocated, and a
//! panic inside the decoder is a [`Error::Format`].

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

use crate::error::{Error, Result};
use crate::scene::load::{check_size, finish, guarded, nonempty_len, LoadOptions};

/// What to do with samples equal to the file's NoData value (`heightfield.nodata`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum NoData {
    /// An error naming the first missing sample's position and the count (the default).
    #[default]
    Reject,
    /// Filled with the lowest valid sample of the file.
    Lowest,
    /// Filled with this value, in the file's units (before `height_scale`).
    Value(f32),
}

/// What a GeoTIFF says besides its samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TiffMeta {
    /// `(x, y)` of `ModelPixelScaleTag`: model units per pixel.
    pub pixel_scale: Option<[f64; 2]>,
    /// `GTModelTypeGeoKey` = 2: the model is geographic (the pixel scale is in degrees).
    pub geographic: bool,
    /// The `GDAL_NODATA` value, and how many samples had it.
    pub nodata: Option<(f64, usize)>,
}

/// Loads a single-band GeoTIFF (see the module docs).
pub fn load_tiff(path: &Path, opts: &LoadOptions) -> Result<(crate::scene::heightfield::HeightField, TiffMeta)> {
    nonempty_len(path)?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    guarded(path, "TIFF", || {
        let bad = |what: &str, e: tiff::TiffError| Error::format(path, format!("{what}: {e}"));
        let mut dec = Decoder::new(BufReader::new(file)).map_err(|e| bad("not a valid TIFF", e))?;
        let (w, h) = dec.dimensions().map_err(|e| bad("TIFF without image dimensions", e))?;
        let (w, h) = (w as usize, h as usize);
        check_size(path, w, h, opts.max_dim)?;
        let colour = dec.colortype().map_err(|e| bad("TIFF colour type", e))?;
        let bits = match colour {
            ColorType::Gray(bits) => bits,
            other => {
                return Err(Error::format(
                    path,
                    format!("TIFF of colour type {other:?}; expected one band (a grayscale DEM): select a band first, e.g. `gdal_translate -b 1`"),
                ))
            }
        };
        let bytes = w * h * usize::from(bits).div_ceil(8);
        let limits = {
            let mut l = Limits::default();
            l.decoding_buffer_size = bytes + (1 << 20);
            l
        };
        let mut dec = dec.with_limits(limits);
        let meta = read_meta(&mut dec, path)?;
        let image = dec.read_image().map_err(|e| {
            bad("cannot decode the TIFF's pixels (supported: uncompressed, LZW, Deflate, PackBits; strips or tiles)", e)
        })?;
        let mut data = samples(image);
        if data.len() != w * h {
            return Err(Error::format(path, format!("TIFF holds {} samples, expected {w}×{h}", data.len())));
        }
        let meta = fill_nodata(path, w, &mut data, meta, opts.nodata)?;
        let data = to_f32(path, w, &data)?;
        Ok((finish(path, w, h, data, opts)?, meta))
    })
}

/// The pixel scale, the model type and the NoData value (count filled in later).
fn read_meta<R: std::io::Read + std::io::Seek>(dec: &mut Decoder<R>, path: &Path) -> Result<TiffMeta> {
    let tag_err = |name: &str, e: tiff::TiffError| Error::format(path, format!("GeoTIFF tag {name} unreadable: {e}"));
    let pixel_scale = match dec.find_tag(Tag::ModelPixelScaleTag).map_err(|e| tag_err("ModelPixelScaleTag", e))? {
        None => None,
        Some(v) => {
            let s = v.into_f64_vec().map_err(|e| tag_err("ModelPixelScaleTag", e))?;
            if s.len() < 2 || !s[..2].iter().all(|x| x.is_finite() && *x > 0.0) {
                return Err(Error::format(
                    path,
                    format!("ModelPixelScaleTag {s:?}: expected (x, y[, z]) with x, y finite and > 0"),
                ));
            }
            Some([s[0], s[1]])
        }
    };
    let geographic = match dec.find_tag(Tag::GeoKeyDirectoryTag).map_err(|e| tag_err("GeoKeyDirectoryTag", e))? {
        None => false,
        Some(v) => {
            let keys = v.into_u16_vec().map_err(|e| tag_err("GeoKeyDirectoryTag", e))?;
            // Header (version, revision, minor, count), then (key, location, count, value) per key;
            // GTModelTypeGeoKey = 1024, stored in place (location 0): 1 projected, 2 geographic.
            keys.get(4..).unwrap_or(&[]).chunks_exact(4).any(|k| k[0] == 1024 && k[1] == 0 && k[3] == 2)
        }
    };
    let nodata = match dec.find_tag(Tag::GdalNodata).map_err(|e| tag_err("GDAL_NODATA", e))? {
        None => None,
        Some(v) => {
            let text = v.into_string().map_err(|e| tag_err("GDAL_NODATA", e))?;
            let t = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
            let value = if t.eq_ignore_ascii_case("nan") { Some(f64::NAN) } else { t.parse::<f64>().ok() };
            let Some(value) = value else {
                return Err(Error::format(path, format!("GDAL_NODATA {:?} is not a number", shorten(t))));
            };
            Some((value, 0))
        }
    };
    Ok(TiffMeta { pixel_scale, geographic, nodata })
}

/// Every sample as f64 (exact for every accepted type but 64-bit integers beyond 2^53).
fn samples(image: DecodingResult) -> Vec<f64> {
    match image {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::F16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I64(v) => v.into_iter().map(|x| x as f64).collect(),
    }
}

/// Whether `v` is the NoData value `nd` (NaN matches NaN; an f32 file's value as written).
fn is_nodata(v: f64, nd: f64) -> bool {
    if nd.is_nan() {
        v.is_nan()
    } else {
        v == nd || (v as f32) == (nd as f32) && (nd as f32).is_finite()
    }
}

/// Counts the NoData samples and rejects or fills them ([`NoData`]).
fn fill_nodata(path: &Path, w: usize, data: &mut [f64], mut meta: TiffMeta, mode: NoData) -> Result<TiffMeta> {
    let Some((nd, _)) = meta.nodata else { return Ok(meta) };
    let count = data.iter().filter(|&&v| is_nodata(v, nd)).count();
    meta.nodata = Some((nd, count));
    if count == 0 {
        return Ok(meta);
    }
    let fill = match mode {
        NoData::Reject => {
            let i = data.iter().position(|&v| is_nodata(v, nd)).unwrap_or(0);
            return Err(Error::format(
                path,
                format!(
                    "NoData value {nd} at (x={}, y={}) ({count} of {} samples missing); \
                     set heightfield.nodata = \"lowest\" or a fill value to fill them",
                    i % w,
                    i / w,
                    data.len()
                ),
            ));
        }
        NoData::Value(v) => f64::from(v),
        NoData::Lowest => {
            let lowest = data.iter().copied().filter(|&v| !is_nodata(v, nd) && v.is_finite()).reduce(f64::min);
            lowest.ok_or_else(|| {
                Error::format(path, format!("every sample is NoData ({nd}): nothing to fill them from"))
            })?
        }
    };
    for v in data.iter_mut().filter(|v| is_nodata(**v, nd)) {
        *v = fill;
    }
    Ok(meta)
}

/// The samples as f32; a finite sample beyond f32's range is an error naming its position.
fn to_f32(path: &Path, w: usize, data: &[f64]) -> Result<Vec<f32>> {
    if let Some(i) = data.iter().position(|v| v.is_finite() && !(*v as f32).is_finite()) {
        return Err(Error::format(
            path,
            format!("sample {:e} at (x={}, y={}) is beyond f32's range (±3.4e38)", data[i], i % w, i / w),
        ));
    }
    Ok(data.iter().map(|&v| v as f32).collect())
}

/// At most 40 characters of `t` for a message (a hostile tag may be kilobytes long).
fn shorten(t: &str) -> String {
    if t.chars().count() <= 40 {
        t.to_string()
    } else {
        format!("{}…", t.chars().take(40).collect::<String>())
    }
}
