//! The lighting (`[environment]`, `[[key_light]]`, `[[local_light]]`, `[[sphere]]`), `[gi]` and `[camera]`.

use glam::DVec3;
use toml::Table;

use super::ctx::{fmt_list, Ctx};
use super::raw::{RawCamera, RawEnvironment, RawGi, RawKeyLight, RawLocalLight, RawSphere};
use super::{
    direction_from_angles, DEFAULT_KEY_AZIMUTH_DEG, DEFAULT_KEY_ELEVATION_DEG, DEFAULT_KEY_RADIANCE,
    DEFAULT_KEY_RADIUS_DEG, DEFAULT_LOCAL_RADIANCE, ENVMAP_PROGRESS_PIXELS, MAX_CAMERA_SIDE, MAX_ENV_COEFFS,
};
use crate::error::{Error, Result};
use crate::scene::envmap::{self, Preset};
use crate::scene::model::limits;
use crate::scene::model::{
    Camera, Environment, GiSettings, GlossyPyramid, Interpolation, KeyLight, LocalLight, PyramidMode, Quality,
    SphereBlocker,
};
use crate::scene::HeightField;

impl Ctx<'_> {
    pub(super) fn environment(&self, t: Option<&Table>) -> Result<Environment> {
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

    pub(super) fn key_lights(&self, tables: &[Table]) -> Result<Vec<KeyLight>> {
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
    pub(super) fn local_lights(&self, tables: &[Table], texel_size: f64) -> Result<Vec<LocalLight>> {
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
    pub(super) fn spheres(&self, tables: &[Table], texel_size: f64) -> Result<Vec<SphereBlocker>> {
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

    pub(super) fn gi(&self, t: Option<&Table>) -> Result<GiSettings> {
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
            cast_merge: raw.cast_merge.unwrap_or(d.cast_merge),
            replay: raw.replay.unwrap_or(d.replay),
            azimuths_later: raw.azimuths_later.unwrap_or(d.azimuths_later),
            azimuth_offset: raw.azimuth_offset.unwrap_or(d.azimuth_offset),
            scan_reach: parse_opt(&raw.scan_reach).map_err(param)?.unwrap_or(d.scan_reach),
            omega_min: parse_opt(&raw.omega_min).map_err(param)?.unwrap_or(d.omega_min),
            elevation_basis: parse_opt(&raw.elevation_basis).map_err(param)?.unwrap_or(d.elevation_basis),
            visibility: parse_opt(&raw.visibility).map_err(param)?.unwrap_or(d.visibility),
            diffuse_lobe: parse_opt(&raw.diffuse_lobe).map_err(param)?.unwrap_or(d.diffuse_lobe),
            storage: parse_opt(&raw.storage).map_err(param)?.unwrap_or(d.storage),
            shading_storage: parse_opt(&raw.shading_storage).map_err(param)?.unwrap_or(d.shading_storage),
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

    pub(super) fn camera(&self, t: Option<&Table>, field: &HeightField, texel: f64) -> Result<Camera> {
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
