//! Scene files: TOML → validated [`Scene`]. The format is specified in `docs/scene-format.md`.
//!
//! Loading goes in four steps:
//!
//! 1. the text is parsed into a TOML table (syntax errors carry the line and column);
//! 2. if the document has neither an `[environment]` table nor a `key_light` key, the default
//!    lighting is added: `[environment]` with its defaults (`preset = "sky"`) and one
//!    `[[key_light]]` with its defaults (the default sun). So an empty file — or no file —
//!    is the default scene ([`default_scene`]);
//! 3. each `--set key.path=value` override is applied to the table ([`parse_scene`]);
//! 4. every table is deserialized with serde (`deny_unknown_fields`) and every value is checked
//!    against its range; images, height fields and environment maps are loaded, with relative
//!    paths resolved against the scene file's folder.
//!
//! Every failure is an [`Error::SceneFile`] naming the scene file, the key (`gi.azimuths`,
//! `key_light.0.radiance`, ...), the value and what is valid — or, for a key set by an
//! override, also the override. Bad input never panics.

use std::fmt::Display;
use std::fs::File;
use std::io::{BufReader, Read};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use glam::DVec3;
use image::codecs::png::PngDecoder;
use image::{ColorType, ImageDecoder};
use serde::de::{self, DeserializeOwned, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use toml::{Table, Value};

use crate::error::{Error, Result};
use crate::scene::animated::{Animation, Boundary, BumpParams, BumpShape, Rain, WaterParams};
use crate::scene::envmap::{self, Preset};
use crate::scene::generators::Generator;
use crate::scene::geotiff::{NoData, TiffMeta};
use crate::scene::heightfield::DEFAULT_MAX_DIM;
use crate::scene::load::{load_heightfield_meta, LoadOptions};
use crate::scene::model::limits;
use crate::scene::model::{
    Albedo, Camera, Environment, GiSettings, GlossyPyramid, Interpolation, KeyLight, LocalLight, Material, PyramidMode,
    Quality, Scene, SphereBlocker,
};
use crate::scene::HeightField;

/// Generator used when `[heightfield]` names neither `generator` nor `file`.
pub const DEFAULT_GENERATOR: &str = "fbm";
/// Side of a generated field when `heightfield.size` is absent.
pub const DEFAULT_FIELD_SIZE: usize = 256;
/// Default key light elevation (degrees above the horizon).
pub const DEFAULT_KEY_ELEVATION_DEG: f64 = envmap::SKY_SUN_ELEVATION_DEG;
/// Default key light azimuth (degrees from +x toward +y).
pub const DEFAULT_KEY_AZIMUTH_DEG: f64 = envmap::SKY_SUN_AZIMUTH_DEG;
/// Default key light angular radius (degrees).
pub const DEFAULT_KEY_RADIUS_DEG: f64 = 3.0;
/// Default radiance of a `[[local_light]]` (a warm lantern).
pub const DEFAULT_LOCAL_RADIANCE: [f64; 3] = [40.0, 28.0, 12.0];
/// Default key light radiance: a warm white chosen so that, on a horizontal surface, the default
/// key light's irradiance (`L·π·sin²α·sin(elevation)` = 2.31 in luminance) about equals the
/// `sky` preset's (2.29); see `docs/scene-format.md`.
pub const DEFAULT_KEY_RADIANCE: [f64; 3] = [DEFAULT_KEY_RADIANCE_R, DEFAULT_KEY_RADIANCE_G, DEFAULT_KEY_RADIANCE_B];
const DEFAULT_KEY_RADIANCE_R: f64 = 500.0;
const DEFAULT_KEY_RADIANCE_G: f64 = 465.0;
const DEFAULT_KEY_RADIANCE_B: f64 = 400.0;
/// Default diffuse albedo (each channel).
pub const DEFAULT_ALBEDO: f64 = 0.8;
/// Default Phong exponent.
pub const DEFAULT_EXPONENT: f64 = 32.0;
/// Largest camera image side.
pub const MAX_CAMERA_SIDE: u32 = 8192;
/// Largest number of environment SH coefficients (order 8).
pub const MAX_ENV_COEFFS: usize = 64;
/// Environment maps with more pixels than this report their projection's progress
/// ([`crate::progress`]; the CLI draws a bar when stderr is a terminal).
pub const ENVMAP_PROGRESS_PIXELS: usize = 256 * 128;

/// Name used in messages for the scene of [`default_scene`].
const DEFAULT_SCENE_NAME: &str = "<default scene>";

/// The default scene, as `hfgi render` uses it without a scene file: a 256² `fbm` field, the
/// default material (grey 0.8, diffuse), the `sky` preset and one key light at elevation 35°,
/// azimuth 200°, angular radius 3°, radiance [`DEFAULT_KEY_RADIANCE`], default GI settings and
/// camera. The same as parsing an empty scene file (and as `scenes/default.toml`).
pub fn default_scene() -> Result<Scene> {
    parse_scene("", Path::new("."), DEFAULT_SCENE_NAME, &[])
}

/// Reads and parses the scene file at `path` (see [`parse_scene`]); relative paths inside it
/// resolve against the file's folder.
///
/// Errors: [`Error::Io`] if the file cannot be read (or is not UTF-8), else as [`parse_scene`].
pub fn load_scene(path: &Path, overrides: &[String]) -> Result<Scene> {
    let text = read_scene_text(path)?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_scene(&text, &base, &path.display().to_string(), overrides)
}

/// Largest scene file read, in bytes: a scene is a few kilobytes of TOML (an inline
/// environment of order 8 is about 5 KB), so anything larger is not a scene file.
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// The text of the scene file at `path`, after checking that it is a regular file of at most
/// [`MAX_SCENE_BYTES`] — a character device such as `/dev/zero`, a FIFO or a huge file is an
/// error before anything is read (docs/robustness.md, "Bounded inputs and work").
fn read_scene_text(path: &Path) -> Result<String> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::format(path, "is a directory; expected a scene file (TOML)"));
    }
    if !meta.is_file() {
        return Err(Error::format(
            path,
            "is not a regular file (a device, FIFO or socket); expected a scene file (TOML)",
        ));
    }
    if meta.len() > MAX_SCENE_BYTES {
        return Err(Error::format(
            path,
            format!("is {} bytes; a scene file is TOML text of at most {MAX_SCENE_BYTES} bytes", meta.len()),
        ));
    }
    let mut text = String::new();
    // The file may grow after the check: never read more than the limit.
    std::io::Read::take(File::open(path).map_err(|e| Error::io(path, e))?, MAX_SCENE_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(|e| Error::io(path, e))?;
    if text.len() as u64 > MAX_SCENE_BYTES {
        return Err(Error::format(path, format!("grew past {MAX_SCENE_BYTES} bytes while being read")));
    }
    Ok(text)
}

/// The files a scene reads besides itself — `heightfield.file`, `material.albedo_map`,
/// `environment.map`, from the file or from `key=value` overrides — resolved against the scene
/// file's folder, and the scene file itself: the inputs an output must not overwrite
/// ([`crate::io::atomic::check_outputs`]). Text that does not parse yields only what could be
/// read (loading the scene reports the error).
pub fn input_files(path: Option<&Path>, overrides: &[String]) -> Vec<PathBuf> {
    const KEYS: [(&str, &str); 3] = [("heightfield", "file"), ("material", "albedo_map"), ("environment", "map")];
    let base = path.and_then(Path::parent).map(Path::to_path_buf).unwrap_or_default();
    let mut out: Vec<PathBuf> = path.map(Path::to_path_buf).into_iter().collect();
    let doc = path.and_then(|p| read_scene_text(p).ok()).and_then(|t| t.parse::<Table>().ok());
    for (table, key) in KEYS {
        if let Some(v) = doc.as_ref().and_then(|d| d.get(table)?.get(key)?.as_str().map(str::to_string)) {
            out.push(base.join(v));
        }
        for o in overrides {
            if let Some(v) = o.strip_prefix(&format!("{table}.{key}=")) {
                out.push(base.join(v.trim().trim_matches('"')));
            }
        }
    }
    out
}

/// Parses scene-file text into a validated [`Scene`].
///
/// - `base_dir`: folder against which relative `heightfield.file`, `material.albedo_map` and
///   `environment.map` paths resolve (the scene file's folder);
/// - `source_name`: the name used in messages (the scene file's path);
/// - `overrides`: `key.path=value` strings (`hfgi render --set`), applied in order after the
///   default lighting is added and before validation. The value is parsed as a TOML value
///   (`64`, `0.5`, `true`, `[0.5, 0.5, 0.5]`, `"cones"`, `{ azimuths = 64 }`); text that is not
///   a TOML value is taken as a string, so `heightfield.generator=cones:count=3` needs no
///   quotes. Path segments are bare keys; a numeric segment indexes an array
///   (`key_light.0.radiance=[1,1,1]`), and the index one past the end appends a new element
///   (`key_light.1.elevation_deg=10` adds a second key light with default values). Missing
///   tables are created.
///
/// `parse_scene("", ...)` is the default scene ([`default_scene`]).
///
/// Errors: [`Error::SceneFile`] naming `source_name`, the key, the value and the valid range:
/// TOML syntax (with line and column), an unknown key (naming it with its table path and the
/// keys expected there), a value of the wrong type or out of range, conflicting keys, a
/// malformed override, or a referenced file that cannot be loaded (with that file's error).
pub fn parse_scene(text: &str, base_dir: &Path, source_name: &str, overrides: &[String]) -> Result<Scene> {
    let mut ctx = Ctx { file: source_name, base_dir, overrides: Vec::new() };
    let mut doc: Table = toml::from_str(text).map_err(|e| {
        ctx.err(None, crate::error::shorten_lines(e.to_string().trim_end(), crate::error::ECHO_MAX_CHARS))
    })?;
    if !doc.contains_key("environment") && !doc.contains_key("key_light") && !doc.contains_key("local_light") {
        doc.insert("environment".into(), Value::Table(Table::new()));
        doc.insert("key_light".into(), Value::Array(vec![Value::Table(Table::new())]));
    }
    ctx.overrides = overrides.iter().map(|o| ctx.parse_override(o)).collect::<Result<_>>()?;
    let mut root = Value::Table(doc);
    for o in &ctx.overrides {
        set_path(&mut root, &o.segments, o.value.clone()).map_err(|m| ctx.err(Some(&o.key), m))?;
    }
    let doc = match root {
        Value::Table(t) => t,
        _ => Table::new(), // set_path never replaces the root
    };
    let raw: RawScene = ctx.de_table(&doc, "")?;

    let (field, texel_size, wrap) = ctx.heightfield(raw.heightfield.as_ref())?;
    let material = ctx.material(raw.material.as_ref(), &field)?;
    let environment = ctx.environment(raw.environment.as_ref())?;
    let key_lights = ctx.key_lights(raw.key_light.as_deref().unwrap_or(&[]))?;
    let local_lights = ctx.local_lights(raw.local_light.as_deref().unwrap_or(&[]), texel_size)?;
    let spheres = ctx.spheres(raw.sphere.as_deref().unwrap_or(&[]), texel_size)?;
    let gi = ctx.gi(raw.gi.as_ref())?;
    let camera = ctx.camera(raw.camera.as_ref(), &field, texel_size)?;
    let animation = ctx.animation(raw.animation.as_ref(), wrap)?;
    crate::scene::model::check_sweep(wrap, &gi).map_err(|e| ctx.wrap("gi.visibility", e))?;
    crate::scene::model::check_lobe(&gi, spheres.len()).map_err(|e| ctx.wrap("gi.diffuse_lobe", e))?;
    crate::scene::model::check_local_wrap(wrap, local_lights.len()).map_err(|e| ctx.wrap("local_light", e))?;
    Ok(Scene {
        field,
        texel_size,
        wrap,
        material,
        environment,
        key_lights,
        local_lights,
        spheres,
        gi,
        camera,
        animation,
    })
}

// ---------------------------------------------------------------------------------------------
// Raw (serde) schema. Every field is optional so that a one-key table deserializes on its own,
// which is how errors are attributed to a key (see `Ctx::de_table`).

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    heightfield: Option<Table>,
    material: Option<Table>,
    environment: Option<Table>,
    key_light: Option<Vec<Table>>,
    local_light: Option<Vec<Table>>,
    sphere: Option<Vec<Table>>,
    gi: Option<Table>,
    camera: Option<Table>,
    animation: Option<Table>,
}

const NODATA_TIFF_ONLY: &str = "heightfield.nodata applies to GeoTIFF files (.tif/.tiff) only";

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawHeightfield {
    generator: Option<String>,
    size: Option<SizeSpec>,
    file: Option<PathBuf>,
    raw_size: Option<SizeSpec>,
    texel_size: Option<f64>,
    height_scale: Option<f64>,
    height_offset: Option<f64>,
    wrap: Option<bool>,
    nodata: Option<toml::Value>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    albedo: Option<[f64; 3]>,
    albedo_map: Option<PathBuf>,
    specular: Option<[f64; 3]>,
    exponent: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawEnvironment {
    sh: Option<Vec<[f64; 3]>>,
    map: Option<PathBuf>,
    preset: Option<String>,
    intensity: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawKeyLight {
    direction: Option<[f64; 3]>,
    elevation_deg: Option<f64>,
    azimuth_deg: Option<f64>,
    angular_radius_deg: Option<f64>,
    radiance: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawLocalLight {
    position: Option<[f64; 3]>,
    radius: Option<f64>,
    radiance: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawGi {
    sh_order: Option<u32>,
    azimuths: Option<u32>,
    key_light_azimuths: Option<u32>,
    local_light_azimuths: Option<u32>,
    level_step: Option<u32>,
    level_offset: Option<u32>,
    subsample: Option<u32>,
    interpolation: Option<String>,
    pyramid: Option<String>,
    bounces: Option<u32>,
    radiance_level_step: Option<u32>,
    radiance_level_offset: Option<u32>,
    amortize: Option<bool>,
    glossy_pyramid: Option<String>,
    quality: Option<String>,
    level0: Option<String>,
    horizon: Option<String>,
    near_steps: Option<u32>,
    radial_probes: Option<u32>,
    radial_probes_later: Option<u32>,
    replay: Option<bool>,
    azimuths_later: Option<u32>,
    azimuth_offset: Option<f64>,
    scan_reach: Option<String>,
    omega_min: Option<String>,
    elevation_basis: Option<String>,
    visibility: Option<String>,
    diffuse_lobe: Option<String>,
    storage: Option<String>,
    sweep_near: Option<u32>,
    blocker_epsilon: Option<f64>,
    blocker_ratio: Option<bool>,
    blocker_exp: Option<String>,
    blocker_shading: Option<String>,
    blocker_log_cap: Option<String>,
    blocker_key_lights: Option<String>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawSphere {
    center: Option<[f64; 3]>,
    radius: Option<f64>,
    albedo: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    position: Option<[f64; 3]>,
    target: Option<[f64; 3]>,
    fov_deg: Option<f64>,
    width: Option<u32>,
    height: Option<u32>,
    exposure: Option<f64>,
}

/// `[animation]`: the keys of every kind; [`Ctx::animation`] rejects those of another kind.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawAnimation {
    kind: Option<String>,
    seed: Option<u64>,
    // water
    speed: Option<f64>,
    damping: Option<f64>,
    steps_per_frame: Option<u32>,
    rest_level: Option<f64>,
    scale: Option<f64>,
    rain_rate: Option<f64>,
    drop_amplitude: Option<f64>,
    drop_radius: Option<f64>,
    // bumps
    count: Option<u32>,
    radius: Option<f64>,
    amplitude: Option<f64>,
    period: Option<u32>,
    travel: Option<f64>,
    shape: Option<String>,
    // day
    day_frames: Option<u32>,
    max_elevation_deg: Option<f64>,
    sweep_deg: Option<f64>,
    orbit_turns: Option<f64>,
    // boulders
    lap_frames: Option<u32>,
}

/// `n` (square) or `[w, h]`.
#[derive(Clone, Copy, Debug)]
struct SizeSpec(usize, usize);

impl<'de> Deserialize<'de> for SizeSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = SizeSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a size n or [width, height] (non-negative integers)")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<SizeSpec, E> {
                let n = usize::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &self))?;
                Ok(SizeSpec(n, n))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<SizeSpec, E> {
                let n = usize::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Unsigned(v), &self))?;
                Ok(SizeSpec(n, n))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<SizeSpec, A::Error> {
                let w: usize = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let h: usize = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(1, &self))?;
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(3, &self));
                }
                Ok(SizeSpec(w, h))
            }
        }
        d.deserialize_any(V)
    }
}

// ---------------------------------------------------------------------------------------------
// Overrides

/// One parsed `--set key.path=value`.
struct Override {
    /// `key.path` as written (trimmed).
    key: String,
    segments: Vec<String>,
    value: Value,
    /// The whole override as given, for messages.
    text: String,
}

/// Parses an override's value text as a TOML value, else takes it as a string.
fn parse_override_value(text: &str) -> Value {
    match toml::from_str::<Table>(&format!("v = {text}")) {
        Ok(mut t) if t.len() == 1 => t.remove("v").unwrap_or_else(|| Value::String(text.to_string())),
        _ => Value::String(text.to_string()),
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a float",
        Value::Boolean(_) => "a boolean",
        Value::Datetime(_) => "a date-time",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

/// The element `seg` of `cur` (a table key or an array index), created if missing: a table,
/// or an array when `array_next` (the following segment is an index).
fn child_mut<'a>(
    cur: &'a mut Value,
    seg: &str,
    path: &str,
    array_next: bool,
) -> std::result::Result<&'a mut Value, String> {
    let fresh = || if array_next { Value::Array(Vec::new()) } else { Value::Table(Table::new()) };
    match cur {
        Value::Table(t) => Ok(t.entry(seg.to_string()).or_insert_with(fresh)),
        Value::Array(a) => {
            let i = array_index(seg, path, a.len())?;
            if i == a.len() {
                a.push(fresh());
            }
            Ok(&mut a[i])
        }
        other => Err(format!("cannot set below `{path}`: it is {}, not a table or array", type_name(other))),
    }
}

/// Index `seg` into an array of `len` elements at `path`; `len` itself means "append".
fn array_index(seg: &str, path: &str, len: usize) -> std::result::Result<usize, String> {
    let i: usize = seg
        .parse()
        .map_err(|_| format!("`{path}` is an array: expected a numeric index 0..={len} after it, found `{seg}`"))?;
    if i > len {
        return Err(format!(
            "index {i} is past the end of `{path}` ({len} element(s)): use 0..{len} to change one or {len} to append one"
        ));
    }
    Ok(i)
}

/// Sets `root[segments…] = value`, creating missing tables/arrays.
fn set_path(root: &mut Value, segments: &[String], value: Value) -> std::result::Result<(), String> {
    let Some((last, parents)) = segments.split_last() else { return Err("empty key".into()) };
    let mut cur = root;
    for (i, seg) in parents.iter().enumerate() {
        let array_next = segments[i + 1].parse::<usize>().is_ok();
        let path = segments[..i].join(".");
        cur = child_mut(cur, seg, if path.is_empty() { seg } else { &path }, array_next)?;
    }
    let parent = parents.join(".");
    match cur {
        Value::Table(t) => {
            t.insert(last.clone(), value);
            Ok(())
        }
        Value::Array(a) => {
            let i = array_index(last, &parent, a.len())?;
            if i == a.len() {
                a.push(value);
            } else {
                a[i] = value;
            }
            Ok(())
        }
        other => Err(format!("cannot set `{last}` in `{parent}`: it is {}, not a table or array", type_name(other))),
    }
}

// ---------------------------------------------------------------------------------------------
// Building the scene

/// Parsing context: names the file in errors, resolves paths, remembers overrides.
struct Ctx<'a> {
    file: &'a str,
    base_dir: &'a Path,
    overrides: Vec<Override>,
}

/// `a.b` (or `b` when `a` is empty).
fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// `[a, b, c]` with each number in its shortest form.
fn fmt_list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| x.to_string()).collect();
    format!("[{}]", items.join(", "))
}

impl Ctx<'_> {
    /// An [`Error::SceneFile`] for `key` (None: not about one key), noting the override that set
    /// the key, if one did.
    fn err(&self, key: Option<&str>, message: impl Into<String>) -> Error {
        let mut message = message.into();
        if let Some(k) = key {
            let covers = |p: &str| p == k || k.starts_with(&format!("{p}.")) || p.starts_with(&format!("{k}."));
            if let Some(o) = self.overrides.iter().rev().find(|o| covers(&o.key)) {
                message.push_str(&format!(" (set by --set {})", crate::error::shorten(&o.text)));
            }
        }
        Error::SceneFile { file: self.file.to_string(), key: key.map(str::to_string), message }
    }

    /// `invalid key = value: expected …`.
    fn invalid(&self, key: &str, value: impl Display, expected: impl Display) -> Error {
        let value = crate::error::shorten(&value.to_string());
        self.err(Some(key), format!("invalid {key} = {value}: expected {expected}"))
    }

    /// Wraps an error from another module (height-field loader, generator, model validation):
    /// an [`Error::InvalidParameter`] whose name is a scene key keeps it as the key; anything
    /// else is reported under `key`.
    fn wrap(&self, key: &str, e: Error) -> Error {
        match &e {
            Error::InvalidParameter { name, .. } if name == key || name.starts_with(&format!("{key}.")) => {
                self.err(Some(name), e.to_string())
            }
            _ => self.err(Some(key), format!("{key}: {e}")),
        }
    }

    fn resolve(&self, p: &Path) -> PathBuf {
        self.base_dir.join(p)
    }

    fn parse_override(&self, text: &str) -> Result<Override> {
        let bad = |why: &str| {
            self.err(
                None,
                format!("invalid override `--set {text}`: {why}; expected key.path=value, e.g. gi.azimuths=64"),
            )
        };
        let Some((key, value)) = text.split_once('=') else { return Err(bad("no `=`")) };
        let key = key.trim();
        let segments: Vec<String> = key.split('.').map(str::to_string).collect();
        if let Some(s) = segments
            .iter()
            .find(|s| s.is_empty() || !s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'))
        {
            return Err(bad(&format!("`{s}` in `{key}` is not a bare key (letters, digits, _ and -)")));
        }
        Ok(Override {
            key: key.to_string(),
            segments,
            value: parse_override_value(value.trim()),
            text: text.to_string(),
        })
    }

    /// Deserializes `table` (at `path`) into `T`, attributing any error to one key: serde's
    /// unknown-field message names it; otherwise each key is tried on its own (every field of
    /// the raw types is optional) and the first that fails is the culprit.
    fn de_table<T: DeserializeOwned>(&self, table: &Table, path: &str) -> Result<T> {
        let e = match T::deserialize(Value::Table(table.clone())) {
            Ok(t) => return Ok(t),
            Err(e) => e,
        };
        let msg = e.message();
        if let Some((name, tail)) = msg.strip_prefix("unknown field `").and_then(|r| r.split_once('`')) {
            let key = join(path, name);
            let tail = tail.trim_start_matches(',').trim().replace('`', "").replacen(
                "expected one of ",
                "expected one of: ",
                1,
            );
            let where_ = if path.is_empty() { "at the top level".to_string() } else { format!("in [{path}]") };
            let detail = if tail.is_empty() { where_ } else { format!("{where_}; {tail}") };
            return Err(self.err(Some(&key), format!("unknown key `{key}` ({detail})")));
        }
        for (k, v) in table {
            let one: Table = std::iter::once((k.clone(), v.clone())).collect();
            if let Err(e1) = T::deserialize(Value::Table(one)) {
                let key = join(path, k);
                let hint = if key == "key_light" && e1.message().contains("expected a sequence") {
                    " (write each key light as a [[key_light]] table)"
                } else {
                    ""
                };
                return Err(self.err(Some(&key), format!("{key}: {}{hint}", e1.message())));
            }
        }
        let key = (!path.is_empty()).then_some(path);
        Err(self.err(key, if path.is_empty() { msg.to_string() } else { format!("{path}: {msg}") }))
    }

    fn de_opt<T: DeserializeOwned + Default>(&self, table: Option<&Table>, path: &str) -> Result<T> {
        table.map_or_else(|| Ok(T::default()), |t| self.de_table(t, path))
    }

    fn finite_f32(&self, key: &str, v: f64, ok: bool, expected: &str) -> Result<f32> {
        if ok && v.is_finite() && (v as f32).is_finite() {
            Ok(v as f32)
        } else {
            Err(self.invalid(key, v, expected))
        }
    }

    fn rgb(&self, key: &str, v: [f64; 3], lo: f64, hi: f64, expected: &str) -> Result<[f64; 3]> {
        if v.iter().all(|x| x.is_finite() && *x >= lo && *x <= hi && (*x as f32).is_finite()) {
            Ok(v)
        } else {
            Err(self.invalid(key, fmt_list(&v), expected))
        }
    }

    /// `[heightfield]`: the height field (generated or loaded, then offset), the texel size and
    /// whether the field wraps.
    fn heightfield(&self, t: Option<&Table>) -> Result<(HeightField, f64, bool)> {
        let raw: RawHeightfield = self.de_opt(t, "heightfield")?;
        let texel = raw.texel_size.unwrap_or(1.0);
        let (lo, hi) = limits::TEXEL_SIZE;
        if !(texel.is_finite() && (lo..=hi).contains(&texel)) {
            return Err(self.invalid(
                "heightfield.texel_size",
                texel,
                format!("a number in [{lo:e}, {hi:e}] (world units)"),
            ));
        }
        let nodata = self.nodata(raw.nodata.as_ref())?;
        let scale = raw.height_scale.unwrap_or(1.0);
        self.finite_f32("heightfield.height_scale", scale, true, "a finite number")?;
        let (field, texel) = match (&raw.generator, &raw.file) {
            (Some(_), Some(_)) => {
                return Err(
                    self.err(Some("heightfield.file"), "heightfield: give either `generator` or `file`, not both")
                )
            }
            (_, Some(file)) => self.heightfield_file(&raw, file, scale, nodata, texel)?,
            (generator, None) => (self.generated_heightfield(&raw, generator.as_deref(), scale, texel)?, texel),
        };
        let field = self.height_offset(field, raw.height_offset)?;
        self.height_magnitudes(&field)?;
        Ok((field, texel, raw.wrap.unwrap_or(false)))
    }

    /// `heightfield.file`, loaded with `scale` and `nodata`, and the texel size: `texel`, or the
    /// file's pixel scale when `heightfield.texel_size` is absent and the file has one.
    fn heightfield_file(
        &self,
        raw: &RawHeightfield,
        file: &Path,
        scale: f64,
        nodata: NoData,
        texel: f64,
    ) -> Result<(HeightField, f64)> {
        if raw.size.is_some() {
            return Err(self.err(
                Some("heightfield.size"),
                "heightfield.size applies to generators only; a file's size comes from the file \
                 (use heightfield.raw_size for .raw/.f32 files)",
            ));
        }
        let path = self.resolve(file);
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if raw.nodata.is_some() && !matches!(ext.as_deref(), Some("tif") | Some("tiff")) {
            return Err(self.err(Some("heightfield.nodata"), NODATA_TIFF_ONLY));
        }
        let opts = LoadOptions {
            height_scale: scale as f32,
            raw_size: raw.raw_size.map(|s| (s.0, s.1)),
            max_dim: DEFAULT_MAX_DIM,
            nodata,
        };
        let (field, meta) = load_heightfield_meta(&path, &opts).map_err(|e| self.wrap("heightfield.file", e))?;
        if raw.texel_size.is_none() {
            return Ok((field, self.pixel_scale(&meta)?.unwrap_or(texel)));
        }
        Ok((field, texel))
    }

    /// The height field of `generator` (default [`DEFAULT_GENERATOR`]) at `heightfield.size`,
    /// its heights (texel units) scaled to world units by `texel · scale`.
    fn generated_heightfield(
        &self,
        raw: &RawHeightfield,
        generator: Option<&str>,
        scale: f64,
        texel: f64,
    ) -> Result<HeightField> {
        if raw.nodata.is_some() {
            return Err(self.err(Some("heightfield.nodata"), NODATA_TIFF_ONLY));
        }
        if raw.raw_size.is_some() {
            return Err(self.err(
                Some("heightfield.raw_size"),
                "heightfield.raw_size applies to .raw/.f32 files only (use heightfield.size with a generator)",
            ));
        }
        let text = generator.unwrap_or(DEFAULT_GENERATOR);
        let gen: Generator = text.parse().map_err(|e| self.wrap("heightfield.generator", e))?;
        let SizeSpec(w, h) = raw.size.unwrap_or(SizeSpec(DEFAULT_FIELD_SIZE, DEFAULT_FIELD_SIZE));
        let max = DEFAULT_MAX_DIM as usize;
        if !(2..=max).contains(&w) || !(2..=max).contains(&h) {
            return Err(self.invalid(
                "heightfield.size",
                fmt_list(&[w as f64, h as f64]),
                format!("n or [width, height] with each side in 2..={max}"),
            ));
        }
        let field = gen.generate(w, h).map_err(|e| self.wrap("heightfield.generator", e))?;
        // Generated heights are in texel units: world units are × texel size.
        let factor = texel * scale;
        if factor == 1.0 {
            Ok(field)
        } else {
            field
                .scaled(factor as f32, &format!("generator {gen}"))
                .map_err(|e| self.wrap("heightfield.height_scale", e))
        }
    }

    /// `heightfield.height_offset` (world units), when given, added to every height.
    fn height_offset(&self, field: HeightField, offset: Option<f64>) -> Result<HeightField> {
        let Some(z) = offset else { return Ok(field) };
        self.finite_f32("heightfield.height_offset", z, true, "a finite number (world units)")?;
        let data: Vec<f32> = field.data().iter().map(|&v| (v as f64 + z) as f32).collect();
        HeightField::new("height_offset", field.width(), field.height(), data, DEFAULT_MAX_DIM)
            .map_err(|e| self.wrap("heightfield.height_offset", e))
    }

    /// Every height within ±[`limits::MAX_HEIGHT`] (after `height_scale` and `height_offset`).
    fn height_magnitudes(&self, field: &HeightField) -> Result<()> {
        limits::check_heights(field).map_err(|e| self.err(Some("heightfield"), format!("heightfield: {e}")))
    }

    /// `heightfield.nodata`: `"reject"` (default), `"lowest"` or a fill value (file units).
    fn nodata(&self, v: Option<&toml::Value>) -> Result<NoData> {
        const EXPECTED: &str = "\"reject\", \"lowest\" or a fill value (a finite number, in the file's units)";
        match v {
            None => Ok(NoData::Reject),
            Some(toml::Value::String(s)) if s == "reject" => Ok(NoData::Reject),
            Some(toml::Value::String(s)) if s == "lowest" => Ok(NoData::Lowest),
            Some(toml::Value::Integer(i)) => Ok(NoData::Value(*i as f32)),
            Some(toml::Value::Float(x)) => {
                self.finite_f32("heightfield.nodata", *x, true, EXPECTED)?;
                Ok(NoData::Value(*x as f32))
            }
            Some(other) => Err(self.invalid("heightfield.nodata", other, EXPECTED)),
        }
    }

    /// The texel size a GeoTIFF's `ModelPixelScaleTag` gives (`None`: no tag), when the scene
    /// does not set `heightfield.texel_size`: square pixels, in a projected model's units.
    fn pixel_scale(&self, meta: &TiffMeta) -> Result<Option<f64>> {
        let Some([sx, sy]) = meta.pixel_scale else { return Ok(None) };
        let given = "set heightfield.texel_size (world units per texel) to override";
        if meta.geographic {
            return Err(self.err(
                Some("heightfield.texel_size"),
                format!("the GeoTIFF's pixel scale ({sx} × {sy}) is in degrees (a geographic model); {given}"),
            ));
        }
        if (sx - sy).abs() > 1e-6 * sx.max(sy) {
            return Err(self.err(
                Some("heightfield.texel_size"),
                format!("the GeoTIFF's pixels are not square ({sx} × {sy}); hfgi needs square texels; {given}"),
            ));
        }
        Ok(Some(sx))
    }

    fn material(&self, t: Option<&Table>, field: &HeightField) -> Result<Material> {
        let raw: RawMaterial = self.de_opt(t, "material")?;
        let albedo = match (raw.albedo, raw.albedo_map) {
            (Some(_), Some(_)) => {
                return Err(
                    self.err(Some("material.albedo_map"), "material: give either `albedo` or `albedo_map`, not both")
                )
            }
            (_, Some(map)) => Albedo::Map(self.albedo_map(&map, field.width(), field.height())?),
            (albedo, None) => {
                let a = self.rgb(
                    "material.albedo",
                    albedo.unwrap_or([DEFAULT_ALBEDO; 3]),
                    0.0,
                    1.0,
                    "[r, g, b] with each component in [0, 1]",
                )?;
                Albedo::Constant(a.map(|x| x as f32))
            }
        };
        let specular = raw
            .specular
            .map(|s| {
                let m = limits::MAX_SPECULAR;
                self.rgb("material.specular", s, 0.0, m, &format!("[r, g, b] with each component in [0, {m:e}]"))
            })
            .transpose()?
            .map(|s| s.map(|x| x as f32));
        let e = raw.exponent.unwrap_or(DEFAULT_EXPONENT);
        let (lo, hi) = limits::EXPONENT;
        let exponent =
            self.finite_f32("material.exponent", e, (lo..=hi).contains(&e), &format!("a number in [{lo}, {hi}]"))?;
        Ok(Material { albedo, specular, exponent })
    }

    /// An 8-bit PNG (grey, grey+alpha, RGB, RGBA; palette images are expanded to RGB), sRGB
    /// decoded to linear, of the height field's size.
    fn albedo_map(&self, file: &Path, w: usize, h: usize) -> Result<Vec<[f32; 3]>> {
        const KEY: &str = "material.albedo_map";
        let path = self.resolve(file);
        let fail = |what: String| self.err(Some(KEY), format!("{KEY}: {}: {what}", path.display()));
        crate::scene::load::nonempty_len(&path).map_err(|e| self.wrap(KEY, e))?;
        let f = File::open(&path).map_err(|e| fail(e.to_string()))?;
        let decoded = catch_unwind(AssertUnwindSafe(|| -> std::result::Result<Vec<[f32; 3]>, String> {
            let decoder = PngDecoder::new(BufReader::new(f))
                .map_err(|e| format!("not a valid PNG (truncated or corrupt file?): {e}"))?;
            let (pw, ph) = decoder.dimensions();
            if (pw as usize, ph as usize) != (w, h) {
                return Err(format!(
                    "the albedo map is {pw}×{ph} but the height field is {w}×{h}; expected the same size"
                ));
            }
            let channels = match decoder.color_type() {
                ColorType::L8 => 1,
                ColorType::La8 => 2,
                ColorType::Rgb8 => 3,
                ColorType::Rgba8 => 4,
                other => {
                    return Err(format!(
                        "PNG colour type {other:?} is not accepted; expected 8-bit grey, grey+alpha, RGB or RGBA"
                    ))
                }
            };
            let mut buf = vec![0u8; w * h * channels];
            if decoder.total_bytes() != buf.len() as u64 {
                return Err(format!("PNG decoder reports {} bytes for {w}×{h}", decoder.total_bytes()));
            }
            decoder.read_image(&mut buf).map_err(|e| format!("truncated or corrupt PNG pixel data: {e}"))?;
            let lut: Vec<f32> = (0..=255u8).map(srgb_decode).collect();
            Ok(buf
                .chunks_exact(channels)
                .map(|p| {
                    if channels < 3 {
                        [lut[p[0] as usize]; 3]
                    } else {
                        [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]]
                    }
                })
                .collect())
        }))
        .unwrap_or_else(|_| Err("PNG decoder failed (corrupt file)".to_string()));
        decoded.map_err(fail)
    }

    fn environment(&self, t: Option<&Table>) -> Result<Environment> {
        let Some(t) = t else { return Ok(Environment::default()) };
        let raw: RawEnvironment = self.de_table(t, "environment")?;
        let intensity = raw.intensity.unwrap_or(1.0);
        let m = limits::MAX_INTENSITY;
        if !(intensity.is_finite() && (0.0..=m).contains(&intensity)) {
            return Err(self.invalid("environment.intensity", intensity, format!("a number in [0, {m:e}]")));
        }
        let given: Vec<&str> = [("sh", raw.sh.is_some()), ("map", raw.map.is_some()), ("preset", raw.preset.is_some())]
            .into_iter()
            .filter_map(|(k, set)| set.then_some(k))
            .collect();
        if given.len() > 1 {
            return Err(self.err(
                Some(&format!("environment.{}", given[1])),
                format!("environment: give only one of `sh`, `map` and `preset` (found {})", given.join(" and ")),
            ));
        }
        let coeffs = if let Some(sh) = raw.sh {
            let n = sh.len();
            let order = (1..).take_while(|o| o * o <= MAX_ENV_COEFFS).find(|o| o * o == n);
            if order.is_none() {
                return Err(self.invalid(
                    "environment.sh",
                    format!("{n} coefficient(s)"),
                    "a perfect-square count of [r, g, b] triples: 1, 4, 9, 16, 25, 36, 49 or 64 (SH order 1 to 8)",
                ));
            }
            if let Some(k) = sh.iter().position(|c| c.iter().any(|x| !x.is_finite())) {
                return Err(self.invalid(&format!("environment.sh.{k}"), fmt_list(&sh[k]), "finite numbers"));
            }
            sh
        } else if let Some(map) = raw.map {
            let path = self.resolve(&map);
            let (w, h, rgb) = envmap::load_equirect_exr(&path).map_err(|e| self.wrap("environment.map", e))?;
            let progress = w * h > ENVMAP_PROGRESS_PIXELS;
            envmap::project_equirect(w, h, &rgb, envmap::PRESET_ORDER, progress)
        } else {
            let name = raw.preset.as_deref().unwrap_or("sky");
            let preset: Preset = name.parse().map_err(|e| self.wrap("environment.preset", e))?;
            preset.sh()
        };
        let sh: Vec<[f64; 3]> = coeffs.into_iter().map(|c| c.map(|x| x * intensity)).collect();
        let m = limits::MAX_RADIANCE;
        if let Some(k) = sh.iter().position(|c| c.iter().any(|x| x.abs() > m)) {
            let source = ["sh", "map", "preset"].into_iter().find(|k| t.contains_key(*k)).unwrap_or("sh");
            return Err(self.err(
                Some(&format!("environment.{source}")),
                format!(
                    "environment SH coefficient {k} = {} (after intensity {intensity}) is beyond ±{m:e}; \
                     expected radiances within ±{m:e} (scale the environment down)",
                    crate::error::shorten(&fmt_list(&sh[k]))
                ),
            ));
        }
        Ok(Environment { sh })
    }

    fn key_lights(&self, tables: &[Table]) -> Result<Vec<KeyLight>> {
        let mut out = Vec::with_capacity(tables.len());
        for (i, t) in tables.iter().enumerate() {
            let path = format!("key_light.{i}");
            let raw: RawKeyLight = self.de_table(t, &path)?;
            let key = |k: &str| format!("{path}.{k}");
            let direction = match (raw.direction, raw.elevation_deg, raw.azimuth_deg) {
                (Some(_), el, az) if el.is_some() || az.is_some() => {
                    let other = if el.is_some() { "elevation_deg" } else { "azimuth_deg" };
                    return Err(self.err(
                        Some(&key("direction")),
                        format!("{path}: give either `direction` or `elevation_deg` + `azimuth_deg`, not both (found direction and {other})"),
                    ));
                }
                (Some(d), _, _) => {
                    // Scaled by its largest component first, so that neither 1e-300 nor 1e300
                    // components under- or overflow the length.
                    let v = DVec3::from_array(d);
                    let big = v.abs().max_element();
                    if !(v.is_finite() && big > 0.0) {
                        return Err(self.invalid(&key("direction"), fmt_list(&d), "a finite, non-zero [x, y, z]"));
                    }
                    (v / big).normalize()
                }
                (None, el, az) => {
                    let el = el.unwrap_or(DEFAULT_KEY_ELEVATION_DEG);
                    let az = az.unwrap_or(DEFAULT_KEY_AZIMUTH_DEG);
                    if !(el.is_finite() && (-90.0..=90.0).contains(&el)) {
                        return Err(self.invalid(&key("elevation_deg"), el, "a number in [-90, 90] (degrees)"));
                    }
                    let m = limits::MAX_AZIMUTH_DEG;
                    if !(az.is_finite() && az.abs() <= m) {
                        return Err(self.invalid(
                            &key("azimuth_deg"),
                            az,
                            format!("a number in [-{m}, {m}] (degrees)"),
                        ));
                    }
                    direction_from_angles(el, az)
                }
            };
            let r = raw.angular_radius_deg.unwrap_or(DEFAULT_KEY_RADIUS_DEG);
            let (lo, hi) = limits::ANGULAR_RADIUS_DEG;
            if !(lo..=hi).contains(&r) {
                return Err(self.invalid(&key("angular_radius_deg"), r, format!("a number in [{lo}, {hi}] (degrees)")));
            }
            let m = limits::MAX_RADIANCE;
            let radiance = self.rgb(
                &key("radiance"),
                raw.radiance.unwrap_or(DEFAULT_KEY_RADIANCE),
                0.0,
                m,
                &format!("[r, g, b] with each component in [0, {m:e}]"),
            )?;
            out.push(KeyLight { direction, angular_radius: r.to_radians(), radiance });
        }
        Ok(out)
    }

    /// `[[local_light]]` tables: `position` is required; `radius` defaults to one texel,
    /// `radiance` to [`DEFAULT_LOCAL_RADIANCE`].
    fn local_lights(&self, tables: &[Table], texel_size: f64) -> Result<Vec<LocalLight>> {
        let mut out = Vec::with_capacity(tables.len());
        for (i, t) in tables.iter().enumerate() {
            let path = format!("local_light.{i}");
            let raw: RawLocalLight = self.de_table(t, &path)?;
            let key = |k: &str| format!("{path}.{k}");
            let c = limits::MAX_COORDINATE;
            let Some(position) = raw.position else {
                return Err(self
                    .err(Some(&key("position")), format!("{path}: `position = [x, y, z]` (world units) is required")));
            };
            if !position.iter().all(|v| v.is_finite() && v.abs() <= c) {
                return Err(self.invalid(
                    &key("position"),
                    fmt_list(&position),
                    format!("[x, y, z], each within ±{c:e}"),
                ));
            }
            let radius = raw.radius.unwrap_or(texel_size);
            let (lo, hi) = limits::LOCAL_RADIUS_TEXELS;
            let (lo, hi) = (lo * texel_size, hi * texel_size);
            if !(radius.is_finite() && radius >= lo && radius <= hi) {
                return Err(self.invalid(
                    &key("radius"),
                    radius,
                    format!("a number in [{lo:e}, {hi:e}] (world units)"),
                ));
            }
            let m = limits::MAX_RADIANCE;
            let radiance = self.rgb(
                &key("radiance"),
                raw.radiance.unwrap_or(DEFAULT_LOCAL_RADIANCE),
                0.0,
                m,
                &format!("[r, g, b] with each component in [0, {m:e}]"),
            )?;
            out.push(LocalLight { position: DVec3::from_array(position), radius, radiance });
        }
        Ok(out)
    }

    /// `[[sphere]]` tables: `center` and `radius` are required; `albedo` defaults to 0.5 grey.
    fn spheres(&self, tables: &[Table], texel_size: f64) -> Result<Vec<SphereBlocker>> {
        let mut out = Vec::with_capacity(tables.len());
        for (i, t) in tables.iter().enumerate() {
            let path = format!("sphere.{i}");
            let raw: RawSphere = self.de_table(t, &path)?;
            let key = |k: &str| format!("{path}.{k}");
            let c = limits::MAX_COORDINATE;
            let Some(center) = raw.center else {
                return Err(
                    self.err(Some(&key("center")), format!("{path}: `center = [x, y, z]` (world units) is required"))
                );
            };
            if !center.iter().all(|v| v.is_finite() && v.abs() <= c) {
                return Err(self.invalid(&key("center"), fmt_list(&center), format!("[x, y, z], each within ±{c:e}")));
            }
            let (lo, hi) = limits::LOCAL_RADIUS_TEXELS;
            let (lo, hi) = (lo * texel_size, hi * texel_size);
            let Some(radius) = raw.radius else {
                return Err(self.err(Some(&key("radius")), format!("{path}: `radius` (world units) is required")));
            };
            if !(radius.is_finite() && radius >= lo && radius <= hi) {
                return Err(self.invalid(
                    &key("radius"),
                    radius,
                    format!("a number in [{lo:e}, {hi:e}] (world units)"),
                ));
            }
            let albedo =
                self.rgb(&key("albedo"), raw.albedo.unwrap_or([0.5; 3]), 0.0, 1.0, "[r, g, b] with each in [0, 1]")?;
            out.push(SphereBlocker { center: DVec3::from_array(center), radius, albedo });
        }
        Ok(out)
    }

    fn gi(&self, t: Option<&Table>) -> Result<GiSettings> {
        let raw: RawGi = self.de_opt(t, "gi")?;
        let param = |e: Error| self.wrap("gi", e);
        fn parse_opt<T: std::str::FromStr<Err = Error>>(v: &Option<String>) -> Result<Option<T>> {
            v.as_deref().map(str::parse).transpose()
        }
        // The preset first; every explicit knob overrides it.
        let d = GiSettings::preset(parse_opt(&raw.quality).map_err(param)?.unwrap_or(Quality::Default));
        let gi = GiSettings {
            sh_order: raw.sh_order.map_or(d.sh_order, |v| v as usize),
            azimuths: raw.azimuths.unwrap_or(d.azimuths),
            key_light_azimuths: raw.key_light_azimuths.unwrap_or(d.key_light_azimuths),
            local_light_azimuths: raw.local_light_azimuths.unwrap_or(d.local_light_azimuths),
            level_step: raw.level_step.unwrap_or(d.level_step),
            level_offset: raw.level_offset.unwrap_or(d.level_offset),
            subsample: raw.subsample.unwrap_or(d.subsample),
            interpolation: raw
                .interpolation
                .map(|s| s.parse::<Interpolation>())
                .transpose()
                .map_err(param)?
                .unwrap_or(d.interpolation),
            pyramid: raw.pyramid.map(|s| s.parse::<PyramidMode>()).transpose().map_err(param)?.unwrap_or(d.pyramid),
            bounces: raw.bounces.unwrap_or(d.bounces),
            radiance_level_step: raw.radiance_level_step.unwrap_or(d.radiance_level_step),
            radiance_level_offset: raw.radiance_level_offset.unwrap_or(d.radiance_level_offset),
            amortize: raw.amortize.unwrap_or(d.amortize),
            glossy_pyramid: raw
                .glossy_pyramid
                .map(|s| s.parse::<GlossyPyramid>())
                .transpose()
                .map_err(param)?
                .unwrap_or(d.glossy_pyramid),
            quality: d.quality,
            level0: parse_opt(&raw.level0).map_err(param)?.unwrap_or(d.level0),
            horizon: parse_opt(&raw.horizon).map_err(param)?.unwrap_or(d.horizon),
            near_steps: raw.near_steps.unwrap_or(d.near_steps),
            radial_probes: raw.radial_probes.unwrap_or(d.radial_probes),
            radial_probes_later: raw.radial_probes_later.unwrap_or(d.radial_probes_later),
            replay: raw.replay.unwrap_or(d.replay),
            azimuths_later: raw.azimuths_later.unwrap_or(d.azimuths_later),
            azimuth_offset: raw.azimuth_offset.unwrap_or(d.azimuth_offset),
            scan_reach: parse_opt(&raw.scan_reach).map_err(param)?.unwrap_or(d.scan_reach),
            omega_min: parse_opt(&raw.omega_min).map_err(param)?.unwrap_or(d.omega_min),
            elevation_basis: parse_opt(&raw.elevation_basis).map_err(param)?.unwrap_or(d.elevation_basis),
            visibility: parse_opt(&raw.visibility).map_err(param)?.unwrap_or(d.visibility),
            diffuse_lobe: parse_opt(&raw.diffuse_lobe).map_err(param)?.unwrap_or(d.diffuse_lobe),
            storage: parse_opt(&raw.storage).map_err(param)?.unwrap_or(d.storage),
            sweep_near: raw.sweep_near.unwrap_or(d.sweep_near),
            blocker_epsilon: raw.blocker_epsilon.unwrap_or(d.blocker_epsilon),
            blocker_ratio: raw.blocker_ratio.unwrap_or(d.blocker_ratio),
            blocker_exp: parse_opt(&raw.blocker_exp).map_err(param)?.unwrap_or(d.blocker_exp),
            blocker_shading: parse_opt(&raw.blocker_shading).map_err(param)?.unwrap_or(d.blocker_shading),
            blocker_log_cap: parse_opt(&raw.blocker_log_cap).map_err(param)?.unwrap_or(d.blocker_log_cap),
            blocker_key_lights: parse_opt(&raw.blocker_key_lights).map_err(param)?.unwrap_or(d.blocker_key_lights),
        };
        gi.validate().map_err(param)?;
        Ok(gi)
    }

    fn camera(&self, t: Option<&Table>, field: &HeightField, texel: f64) -> Result<Camera> {
        let raw: RawCamera = self.de_opt(t, "camera")?;
        let (lo, hi) = field.range();
        let mut cam = Camera::default_for(field.width(), field.height(), texel, f64::from(lo), f64::from(hi));
        let m = limits::MAX_COORDINATE;
        let vec3 = |k: &str, v: [f64; 3]| {
            if v.iter().all(|x| x.is_finite() && x.abs() <= m) {
                Ok(DVec3::from_array(v))
            } else {
                Err(self.invalid(
                    k,
                    fmt_list(&v),
                    format!("[x, y, z] with each coordinate in [-{m:e}, {m:e}] (world units)"),
                ))
            }
        };
        if let Some(p) = raw.position {
            cam.position = vec3("camera.position", p)?;
        }
        if let Some(p) = raw.target {
            cam.target = vec3("camera.target", p)?;
        }
        if cam.position == cam.target {
            let k = if raw.target.is_some() { "camera.target" } else { "camera.position" };
            return Err(self.err(
                Some(k),
                format!(
                    "camera.position and camera.target are both {}; they must differ",
                    fmt_list(&cam.position.to_array())
                ),
            ));
        }
        if let Some(f) = raw.fov_deg {
            let (lo, hi) = limits::FOV_DEG;
            if !(lo..=hi).contains(&f) {
                return Err(self.invalid("camera.fov_deg", f, format!("a number in [{lo}, {hi}] (degrees)")));
            }
            cam.fov_deg = f;
        }
        for (k, v, slot) in
            [("camera.width", raw.width, &mut cam.width), ("camera.height", raw.height, &mut cam.height)]
        {
            if let Some(v) = v {
                if !(1..=MAX_CAMERA_SIDE).contains(&v) {
                    return Err(self.invalid(k, v, format!("an integer in 1..={MAX_CAMERA_SIDE} (pixels)")));
                }
                *slot = v;
            }
        }
        if let Some(e) = raw.exposure {
            let m = limits::MAX_EXPOSURE_STOPS;
            cam.exposure =
                self.finite_f32("camera.exposure", e, e.abs() <= m, &format!("a number in [-{m}, {m}] (stops)"))?;
        }
        Ok(cam)
    }
}

impl Ctx<'_> {
    /// `[animation]`: `kind` picks the parameter set; a key of another kind is an error naming
    /// it (with `kind = "none"` the other keys are type-checked and ignored).
    fn animation(&self, t: Option<&Table>, wrap: bool) -> Result<Animation> {
        const WATER: &[&str] = &[
            "speed",
            "damping",
            "steps_per_frame",
            "rest_level",
            "scale",
            "rain_rate",
            "drop_amplitude",
            "drop_radius",
        ];
        const BUMPS: &[&str] = &["count", "radius", "amplitude", "period", "travel", "shape"];
        const DAY: &[&str] = &["day_frames", "max_elevation_deg", "sweep_deg", "orbit_turns"];
        const BOULDERS: &[&str] = &["lap_frames"];
        let kinds: [(&str, &[&str]); 4] = [("water", WATER), ("bumps", BUMPS), ("day", DAY), ("boulders", BOULDERS)];
        let Some(t) = t else { return Ok(Animation::None) };
        let raw: RawAnimation = self.de_table(t, "animation")?;
        let kind = raw.kind.as_deref().unwrap_or("none");
        let own = match kinds.iter().find(|(k, _)| *k == kind) {
            _ if kind == "none" => return Ok(Animation::None),
            Some((_, own)) => *own,
            None => {
                let want = "\"none\", \"water\", \"bumps\", \"day\" or \"boulders\"";
                return Err(self.invalid("animation.kind", format!("{kind:?}"), want));
            }
        };
        let other = |k: &str| kinds.iter().find(|(n, keys)| *n != kind && keys.contains(&k)).map(|(n, _)| *n);
        if let Some((k, other_kind)) = t.keys().find_map(|k| other(k).map(|o| (k, o))) {
            let key = format!("animation.{k}");
            return Err(self.err(
                Some(&key),
                format!(
                    "{key} applies to kind = \"{other_kind}\" only; with kind = \"{kind}\" the keys are: kind, seed, {}",
                    own.join(", ")
                ),
            ));
        }
        self.animation_params(&raw, kind, wrap)
    }

    /// The parameters of animation `kind` (not `"none"`) from `raw`, defaults for the keys not
    /// given, validated.
    fn animation_params(&self, raw: &RawAnimation, kind: &str, wrap: bool) -> Result<Animation> {
        let check = |e: Error| self.wrap("animation", e);
        if kind == "water" {
            let d = WaterParams::default();
            let p = WaterParams {
                speed: raw.speed.unwrap_or(d.speed),
                damping: raw.damping.unwrap_or(d.damping),
                steps_per_frame: raw.steps_per_frame.unwrap_or(d.steps_per_frame),
                rest_level: raw.rest_level.unwrap_or(d.rest_level),
                scale: raw.scale.unwrap_or(d.scale),
                boundary: Boundary::from_wrap(wrap),
                rain: Rain {
                    rate: raw.rain_rate.unwrap_or(d.rain.rate),
                    amplitude: raw.drop_amplitude.unwrap_or(d.rain.amplitude),
                    radius: raw.drop_radius.unwrap_or(d.rain.radius),
                    seed: raw.seed.unwrap_or(d.rain.seed),
                },
            };
            p.validate().map_err(check)?;
            Ok(Animation::Water(p))
        } else if kind == "boulders" {
            let d = crate::scene::boulders::BoulderParams::default();
            let p = crate::scene::boulders::BoulderParams { lap_frames: raw.lap_frames.unwrap_or(d.lap_frames) };
            p.validate().map_err(check)?;
            Ok(Animation::Boulders(p))
        } else if kind == "day" {
            let d = crate::scene::day::DayParams::default();
            let p = crate::scene::day::DayParams {
                day_frames: raw.day_frames.unwrap_or(d.day_frames),
                max_elevation_deg: raw.max_elevation_deg.unwrap_or(d.max_elevation_deg),
                sweep_deg: raw.sweep_deg.unwrap_or(d.sweep_deg),
                orbit_turns: raw.orbit_turns.unwrap_or(d.orbit_turns),
            };
            p.validate().map_err(check)?;
            Ok(Animation::Day(p))
        } else {
            let d = BumpParams::default();
            let p = BumpParams {
                seed: raw.seed.unwrap_or(d.seed),
                count: raw.count.unwrap_or(d.count),
                radius: raw.radius.unwrap_or(d.radius),
                amplitude: raw.amplitude.unwrap_or(d.amplitude),
                period: raw.period.unwrap_or(d.period),
                travel: raw.travel.unwrap_or(d.travel),
                shape: raw.shape.as_deref().map(str::parse::<BumpShape>).transpose().map_err(check)?.unwrap_or(d.shape),
            };
            p.validate().map_err(check)?;
            Ok(Animation::Bumps(p))
        }
    }
}

/// Unit direction at elevation `el` above the horizon and azimuth `az` from +x toward +y
/// (degrees), CONVENTIONS.md "Directions and angles".
pub fn direction_from_angles(el_deg: f64, az_deg: f64) -> DVec3 {
    let (el, az) = (el_deg.to_radians(), az_deg.to_radians());
    DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1) of an 8-bit value: `v/255` decoded
/// to linear.
fn srgb_decode(v: u8) -> f32 {
    let x = f64::from(v) / 255.0;
    let y = if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) };
    y as f32
}
