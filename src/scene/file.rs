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

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use glam::DVec3;
use toml::{Table, Value};

use crate::error::{Error, Result};
use crate::scene::envmap;
use crate::scene::model::Scene;

mod ctx;
mod field;
mod lighting;
mod overrides;
mod raw;

use ctx::Ctx;
use overrides::set_path;
use raw::RawScene;

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

/// Unit direction at elevation `el` above the horizon and azimuth `az` from +x toward +y
/// (degrees), CONVENTIONS.md "Directions and angles".
pub fn direction_from_angles(el_deg: f64, az_deg: f64) -> DVec3 {
    let (el, az) = (el_deg.to_radians(), az_deg.to_radians());
    DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
}
