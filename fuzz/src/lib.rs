//! Shared helpers of the fuzz targets (`fuzz_targets/`) and the seed generator
//! (`examples/gen_seeds.rs`): the panic hook, the per-process folder the loaders read their
//! input from, the scene targets' cost filters, and the tiny valid files used as seeds and as
//! the scene targets' fixtures. See docs/robustness.md, "Fuzzing".

use std::collections::HashSet;
use std::fs::File;
use std::io::Cursor;
use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, LayerAttributes, Vec2, WritableImage};
use half::f16;
use image::{ExtendedColorType, ImageEncoder};
use tiff::encoder::{colortype, Compression, DeflateLevel, TiffEncoder};
use tiff::tags::Tag;

/// Largest generated height field side the scene targets run (`heightfield.size`); larger
/// valid sizes (up to 16384) are skipped for their cost, not because they fail.
pub const MAX_SCENE_FIELD: i64 = 256;

/// The largest side the loader targets accept (`LoadOptions::max_dim`), so that a header
/// claiming a huge image is rejected before its pixels are read.
pub const MAX_DIM: u32 = 512;

static DIR: OnceLock<PathBuf> = OnceLock::new();

/// Call once from the target's `init`: names the per-process folder (`/dev/shm` when there is
/// one) and replaces libfuzzer-sys' panic hook.
///
/// libfuzzer-sys' hook aborts on every panic, also on those the library catches on purpose:
/// `hfgi::scene::load::guarded`, `hfgi::io::exr::read_layers` and the albedo-map reader turn a
/// panic inside a third-party decoder into `Error::Format`. That is the behaviour under test,
/// so this hook only prints the first panic at each source location. A panic that escapes the
/// library still reaches libfuzzer-sys' `catch_unwind`, which aborts: libFuzzer reports it as
/// a crash ("deadly signal") and saves the input.
pub fn init(target: &str) {
    let base = if Path::new("/dev/shm").is_dir() { PathBuf::from("/dev/shm") } else { std::env::temp_dir() };
    remove_stale_dirs(&base);
    let dir = base.join(format!("hfgi-fuzz-{target}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create the fuzz target's temp folder");
    let _ = DIR.set(dir);
    let seen: Mutex<HashSet<String>> = Mutex::new(HashSet::new());
    std::panic::set_hook(Box::new(move |info| {
        let at = info.location().map(|l| format!("{}:{}", l.file(), l.line())).unwrap_or_default();
        let first = seen.lock().unwrap_or_else(|e| e.into_inner()).insert(at.clone());
        if first {
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            eprintln!("hfgi-fuzz: panic at {at}: {msg} (first at this location; caught ones are not crashes)");
        }
    }));
}

/// Removes the folders of earlier runs whose process is gone (`hfgi-fuzz-TARGET-PID`).
fn remove_stale_dirs(base: &Path) {
    let Ok(entries) = std::fs::read_dir(base) else { return };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(rest) = name.strip_prefix("hfgi-fuzz-") else { continue };
        let Some(pid) = rest.rsplit('-').next().and_then(|p| p.parse::<u32>().ok()) else { continue };
        if !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// This process's folder (see [`init`]).
pub fn dir() -> &'static Path {
    DIR.get().expect("hfgi_fuzz::init not called")
}

/// Writes `bytes` to `name` in this process's folder and returns the path.
pub fn write_input(name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir().join(name);
    std::fs::write(&path, bytes).expect("write the fuzz input");
    path
}

/// Load options of the height-field targets: defaults, with sides limited to [`MAX_DIM`].
pub fn load_options() -> hfgi::scene::load::LoadOptions {
    hfgi::scene::load::LoadOptions { max_dim: MAX_DIM, ..Default::default() }
}

// ---------------------------------------------------------------------------------------------
// Scene filters

/// Whether the scene targets should parse `text` with `overrides`. Skipped (cost and scope,
/// not correctness):
///
/// - a generated field larger than [`MAX_SCENE_FIELD`] per side: `heightfield.size` in the
///   text, or an override of `heightfield`, `heightfield.size` or `heightfield.size.N` holding
///   an integer above it. Valid, but a 16384² field takes seconds and a gigabyte;
/// - any string value (in the text or an override) that is an absolute path or has a `..`
///   component: `heightfield.file`, `material.albedo_map` and `environment.map` must name
///   files in the target's own folder (the fixtures of [`write_scene_fixtures`]), not files
///   elsewhere on the machine.
///
/// Text that is not TOML is kept (the parser rejects it first); override values are read as
/// the parser reads them (a TOML value, else the text as a string).
pub fn scene_is_cheap(text: &str, overrides: &[String]) -> bool {
    if let Ok(doc) = text.parse::<toml::Table>() {
        if doc.get("heightfield").and_then(|h| h.get("size")).is_some_and(int_above_limit) {
            return false;
        }
        if !paths_stay_inside(&toml::Value::Table(doc)) {
            return false;
        }
    }
    for o in overrides {
        let Some((key, value)) = o.split_once('=') else { continue };
        let key = key.trim();
        let value = override_value(value.trim());
        let sets_size = key == "heightfield" || key == "heightfield.size" || key.starts_with("heightfield.size.");
        if (sets_size && int_above_limit(&value)) || !paths_stay_inside(&value) {
            return false;
        }
    }
    true
}

/// An override's value as `hfgi::scene::file` reads it.
fn override_value(text: &str) -> toml::Value {
    match toml::from_str::<toml::Table>(&format!("v = {text}")) {
        Ok(mut t) if t.len() == 1 => t.remove("v").unwrap_or_else(|| toml::Value::String(text.to_string())),
        _ => toml::Value::String(text.to_string()),
    }
}

/// Whether `v` holds (at any depth) an integer above [`MAX_SCENE_FIELD`].
fn int_above_limit(v: &toml::Value) -> bool {
    match v {
        toml::Value::Integer(i) => *i > MAX_SCENE_FIELD,
        toml::Value::Array(a) => a.iter().any(int_above_limit),
        toml::Value::Table(t) => t.values().any(int_above_limit),
        _ => false,
    }
}

/// Whether every string in `v` is a relative path without `..`.
fn paths_stay_inside(v: &toml::Value) -> bool {
    match v {
        toml::Value::String(s) => {
            let p = Path::new(s);
            !p.is_absolute() && !p.components().any(|c| matches!(c, Component::ParentDir | Component::RootDir))
        }
        toml::Value::Array(a) => a.iter().all(paths_stay_inside),
        toml::Value::Table(t) => t.values().all(paths_stay_inside),
        _ => true,
    }
}

// ---------------------------------------------------------------------------------------------
// Tiny valid files: seeds and the scene targets' fixtures

/// Side of the fixture height fields and albedo map (`h8.png`, ..., `albedo.png`).
pub const FIXTURE_SIDE: usize = 8;

/// A `w × h` ramp with negative and fractional values (exact in f16).
pub fn ramp(w: usize, h: usize) -> Vec<f32> {
    (0..w * h).map(|k| (k % 37) as f32 * 0.75 - 4.0).collect()
}

/// A grey PNG: 8-bit (`sixteen = false`) or 16-bit.
pub fn png_gray(w: u32, h: u32, sixteen: bool) -> Vec<u8> {
    let n = (w * h) as usize;
    let (bytes, color) = if sixteen {
        let v: Vec<u8> = (0..n).flat_map(|k| ((k * 4099) as u16).to_ne_bytes()).collect();
        (v, ExtendedColorType::L16)
    } else {
        ((0..n).map(|k| (k * 37) as u8).collect(), ExtendedColorType::L8)
    };
    png(w, h, &bytes, color)
}

/// A PNG of `bytes` in `color`.
pub fn png(w: u32, h: u32, bytes: &[u8], color: ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(bytes, w, h, color).expect("PNG encoding");
    out
}

/// One EXR sample type.
#[derive(Clone, Copy)]
pub enum ExrSamples {
    F16,
    F32,
    U32,
}

/// A single-part EXR with `channels` (each `w·h` samples of the ramp) of one sample type.
pub fn exr(w: usize, h: usize, channels: &[&str], samples: ExrSamples, encoding: Encoding) -> Vec<u8> {
    let v = ramp(w, h);
    let list = channels
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let shifted: Vec<f32> = v.iter().map(|x| x + c as f32).collect();
            let s = match samples {
                ExrSamples::F16 => FlatSamples::F16(shifted.iter().map(|&x| f16::from_f32(x)).collect()),
                ExrSamples::F32 => FlatSamples::F32(shifted),
                ExrSamples::U32 => FlatSamples::U32(shifted.iter().map(|&x| x.abs() as u32).collect()),
            };
            AnyChannel::new(*name, s)
        })
        .collect();
    let layer = exr::image::Layer::new(Vec2(w, h), LayerAttributes::default(), encoding, AnyChannels::sort(list));
    let mut out = Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut out).expect("EXR encoding");
    out.into_inner()
}

/// Uncompressed, ZIP (one line per block) or RLE EXR encodings by name, for seeds.
pub fn exr_encoding(name: &str) -> Encoding {
    match name {
        "zip" => Encoding::SMALL_LOSSLESS,
        "rle" => Encoding::FAST_LOSSLESS,
        _ => Encoding::UNCOMPRESSED,
    }
}

/// GeoTIFF sample types of the seeds.
#[derive(Clone, Copy)]
pub enum TiffSamples {
    F32,
    I16,
    U16,
}

/// A single-band GeoTIFF of the ramp (times 4 for the integer types) with
/// `ModelPixelScaleTag`, a projected `GeoKeyDirectoryTag` and, if given, `GDAL_NODATA` (which
/// the first sample then holds).
pub fn geotiff(w: u32, h: u32, samples: TiffSamples, compression: Compression, nodata: Option<&str>) -> Vec<u8> {
    let v = ramp(w as usize, h as usize);
    let nd: Option<f64> = nodata.map(|t| t.trim().parse().unwrap_or(f64::NAN));
    let mut out = Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut out).expect("TIFF encoder").with_compression(compression);
    macro_rules! write {
        ($ty:ty, $conv:expr) => {{
            let mut data: Vec<_> = v.iter().map(|&x| $conv(f64::from(x))).collect();
            if let Some(nd) = nd {
                data[0] = nd as _; // the stored value equals the tag's
            }
            let mut img = enc.new_image::<$ty>(w, h).expect("TIFF image");
            let dir = img.encoder();
            dir.write_tag(Tag::ModelPixelScaleTag, &[30.0f64, 30.0, 0.0][..]).expect("tag");
            dir.write_tag(Tag::GeoKeyDirectoryTag, &[1u16, 1, 0, 1, 1024, 0, 1, 1][..]).expect("tag");
            if let Some(text) = nodata {
                dir.write_tag(Tag::GdalNodata, text).expect("tag");
            }
            img.write_data(&data).expect("TIFF data");
        }};
    }
    match samples {
        TiffSamples::F32 => write!(colortype::Gray32Float, |x: f64| x as f32),
        TiffSamples::I16 => write!(colortype::GrayI16, |x: f64| (x * 4.0) as i16),
        TiffSamples::U16 => write!(colortype::Gray16, |x: f64| ((x + 4.0) * 4.0) as u16),
    }
    out.into_inner()
}

/// TIFF compressions of the seeds by name.
pub fn tiff_compression(name: &str) -> Compression {
    match name {
        "lzw" => Compression::Lzw,
        "deflate" => Compression::Deflate(DeflateLevel::Balanced),
        "packbits" => Compression::Packbits,
        _ => Compression::Uncompressed,
    }
}

/// Headerless little-endian f32 samples of the ramp.
pub fn raw_f32(w: usize, h: usize) -> Vec<u8> {
    ramp(w, h).iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The files the scene targets' scenes may name, relative to their folder: height fields
/// `h8.png`, `h16.png`, `h.exr`, `h.tif`, `h.raw` (all [`FIXTURE_SIDE`]², `raw_size = 8`), the
/// albedo map `albedo.png` (8-bit RGB, same size) and the environment map `env.exr`
/// (16×8 RGB). The seeds in `fuzz/seeds/scene_file/` use them.
pub fn fixtures() -> Vec<(&'static str, Vec<u8>)> {
    let s = FIXTURE_SIDE;
    let rgb: Vec<u8> = (0..s * s * 3).map(|k| (k * 11) as u8).collect();
    vec![
        ("h8.png", png_gray(s as u32, s as u32, false)),
        ("h16.png", png_gray(s as u32, s as u32, true)),
        ("h.exr", exr(s, s, &["Y"], ExrSamples::F32, Encoding::UNCOMPRESSED)),
        ("h.tif", geotiff(s as u32, s as u32, TiffSamples::F32, Compression::Uncompressed, Some("-4"))),
        ("h.raw", raw_f32(s, s)),
        ("albedo.png", png(s as u32, s as u32, &rgb, ExtendedColorType::Rgb8)),
        ("env.exr", exr(16, 8, &["B", "G", "R"], ExrSamples::F32, Encoding::UNCOMPRESSED)),
    ]
}

/// Writes [`fixtures`] into this process's folder (scene targets' `init`).
pub fn write_scene_fixtures() {
    for (name, bytes) in fixtures() {
        write_input(name, &bytes);
    }
}

/// Creates `path`'s parent folders and writes `bytes` to it (the seed generator).
pub fn write_file(path: &Path, bytes: &[u8]) {
    if let Some(p) = path.parent() {
        std::fs::create_dir_all(p).expect("create folder");
    }
    let mut f = File::create(path).expect("create file");
    std::io::Write::write_all(&mut f, bytes).expect("write file");
}
