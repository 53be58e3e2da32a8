//! `[heightfield]`, `[material]` (with the albedo map image) and `[animation]`.

use std::fs::File;
use std::io::BufReader;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use image::codecs::png::PngDecoder;
use image::{ColorType, ImageDecoder};
use toml::Table;

use super::ctx::{fmt_list, Ctx};
use super::raw::{RawAnimation, RawHeightfield, RawMaterial, SizeSpec, NODATA_TIFF_ONLY};
use super::{DEFAULT_ALBEDO, DEFAULT_EXPONENT, DEFAULT_FIELD_SIZE, DEFAULT_GENERATOR};
use crate::error::{Error, Result};
use crate::scene::animated::{Animation, Boundary, BumpParams, BumpShape, Rain, WaterParams};
use crate::scene::generators::Generator;
use crate::scene::geotiff::{NoData, TiffMeta};
use crate::scene::heightfield::DEFAULT_MAX_DIM;
use crate::scene::load::{load_heightfield_meta, LoadOptions};
use crate::scene::model::limits;
use crate::scene::model::{Albedo, Material};
use crate::scene::HeightField;

impl Ctx<'_> {
    /// `[heightfield]`: the height field (generated or loaded, then offset), the texel size and
    /// whether the field wraps.
    pub(super) fn heightfield(&self, t: Option<&Table>) -> Result<(HeightField, f64, bool)> {
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

    pub(super) fn material(&self, t: Option<&Table>, field: &HeightField) -> Result<Material> {
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
}

impl Ctx<'_> {
    /// `[animation]`: `kind` picks the parameter set; a key of another kind is an error naming
    /// it (with `kind = "none"` the other keys are type-checked and ignored).
    pub(super) fn animation(&self, t: Option<&Table>, wrap: bool) -> Result<Animation> {
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

/// The sRGB electro-optical transfer function (IEC 61966-2-1) of an 8-bit value: `v/255` decoded
/// to linear.
fn srgb_decode(v: u8) -> f32 {
    let x = f64::from(v) / 255.0;
    let y = if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) };
    y as f32
}
