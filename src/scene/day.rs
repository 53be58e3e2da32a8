//! `[animation] kind = "day"`: the sun (the scene's first key light) moves along a day arc, the
//! sky follows it, the camera orbits the field (docs/dynamic.md §4). Pure CPU: each frame's
//! lights and camera, which `hfgi animate` hands to the renderer's live inputs
//! (`Renderer::set_key_lights`, `set_environment`, `set_camera`; the heights never change).

use crate::error::{Error, Result};
use crate::scene::model::{Camera, Environment, KeyLight, Scene};

/// Lowest sun elevation of the arc (sunrise and sunset), degrees.
pub const HORIZON_ELEVATION_DEG: f64 = 3.0;
/// Share of the sky's intensity left at sunrise (the rest follows the sun's elevation).
pub const NIGHT_SKY: f64 = 0.3;

/// The day arc's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct DayParams {
    /// Frames from sunrise to sunset, `2..=100000`; frame `f` is at `t = (f mod n)/(n − 1)`.
    pub day_frames: u32,
    /// The sun's elevation at noon, degrees in `[HORIZON_ELEVATION_DEG, 90]`.
    pub max_elevation_deg: f64,
    /// Azimuth the sun sweeps over the day, degrees in `[0, 360]`, centred on the scene's first
    /// key light's azimuth (its azimuth at noon).
    pub sweep_deg: f64,
    /// Turns the camera orbits the field's centre over the day, within ±10.
    pub orbit_turns: f64,
}

impl Default for DayParams {
    fn default() -> Self {
        Self { day_frames: 12, max_elevation_deg: 60.0, sweep_deg: 180.0, orbit_turns: 0.25 }
    }
}

fn check(key: &str, v: impl std::fmt::Display, ok: bool, want: &str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::param(format!("animation.{key}"), v, want))
    }
}

impl DayParams {
    pub fn validate(&self) -> Result<()> {
        check("day_frames", self.day_frames, (2..=100_000).contains(&self.day_frames), "an integer in 2..=100000")?;
        let e = self.max_elevation_deg;
        check(
            "max_elevation_deg",
            e,
            e.is_finite() && (HORIZON_ELEVATION_DEG..=90.0).contains(&e),
            &format!("a number in [{HORIZON_ELEVATION_DEG}, 90] (degrees)"),
        )?;
        let s = self.sweep_deg;
        check("sweep_deg", s, s.is_finite() && (0.0..=360.0).contains(&s), "a number in [0, 360] (degrees)")?;
        let o = self.orbit_turns;
        check("orbit_turns", o, o.is_finite() && o.abs() <= 10.0, "a number in [-10, 10]")
    }
}

/// A scene's day: its noon sun, sky and camera, and the arc.
#[derive(Clone, Debug)]
pub struct DayCycle {
    params: DayParams,
    sun: KeyLight,
    sky: Environment,
    camera: Camera,
    noon_azimuth: f64,
}

/// One frame of the day.
#[derive(Clone, Debug, PartialEq)]
pub struct DayFrame {
    /// The scene's key lights with the first one (the sun) moved.
    pub key_lights: Vec<KeyLight>,
    pub environment: Environment,
    pub camera: Camera,
}

impl DayCycle {
    /// The day of `scene`, whose first key light is the sun; an error without key lights.
    pub fn new(params: DayParams, scene: &Scene) -> Result<Self> {
        params.validate()?;
        let Some(sun) = scene.key_lights.first() else {
            return Err(Error::param(
                "animation.kind",
                "\"day\"",
                "a scene with a [[key_light]] (the first one is the sun that moves)",
            ));
        };
        let d = sun.direction;
        Ok(Self {
            params,
            sun: sun.clone(),
            sky: scene.environment.clone(),
            camera: scene.camera.clone(),
            noon_azimuth: d.y.atan2(d.x),
        })
    }

    /// Time of day of frame `f` in `[0, 1]` (sunrise to sunset; the day repeats).
    pub fn time(&self, f: u64) -> f64 {
        let n = u64::from(self.params.day_frames);
        (f % n) as f64 / (n - 1) as f64
    }

    /// The sun, sky and camera of frame `f`: the sun at elevation `e(t) = e₀ + (e_max − e₀)
    /// sin(πt)` and azimuth `a_noon + sweep·(t − ½)`; the sky rotated about z with the sun's
    /// azimuth and scaled by `NIGHT_SKY + (1 − NIGHT_SKY) sin e(t) / sin e_max`; the camera's
    /// position turned about the vertical through its target by `2π · orbit_turns · t`.
    pub fn frame(&self, f: u64, key_lights: &[KeyLight]) -> DayFrame {
        let t = self.time(f);
        let p = &self.params;
        let e0 = HORIZON_ELEVATION_DEG.to_radians();
        let emax = p.max_elevation_deg.to_radians();
        let elevation = e0 + (emax - e0) * (std::f64::consts::PI * t).sin();
        let turn = p.sweep_deg.to_radians() * (t - 0.5);
        let azimuth = self.noon_azimuth + turn;
        let mut lights = key_lights.to_vec();
        let sun = KeyLight { direction: from_angles(elevation, azimuth), ..self.sun.clone() };
        match lights.first_mut() {
            Some(l) => *l = sun,
            None => lights.push(sun),
        }
        let intensity = NIGHT_SKY + (1.0 - NIGHT_SKY) * elevation.sin() / emax.sin();
        let environment = self.sky.rotated(rot_z(turn)).scaled(intensity);
        let mut camera = self.camera.clone();
        let orbit = rot_z(2.0 * std::f64::consts::PI * p.orbit_turns * t);
        let rel = camera.position - camera.target;
        let r = |i: usize| orbit[i][0] * rel.x + orbit[i][1] * rel.y + orbit[i][2] * rel.z;
        camera.position = camera.target + glam::DVec3::new(r(0), r(1), r(2));
        DayFrame { key_lights: lights, environment, camera }
    }
}

fn from_angles(elevation: f64, azimuth: f64) -> glam::DVec3 {
    glam::DVec3::new(elevation.cos() * azimuth.cos(), elevation.cos() * azimuth.sin(), elevation.sin())
}

/// Rotation by `a` radians about +z (row-major).
pub fn rot_z(a: f64) -> [[f64; 3]; 3] {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_rises_peaks_at_noon_and_sets_and_the_camera_orbits() {
        let mut scene = crate::scene::file::parse_scene("", std::path::Path::new("."), "test", &[]).unwrap();
        scene.key_lights[0].direction = from_angles(0.5, 1.0);
        let day = DayCycle::new(DayParams { day_frames: 5, ..DayParams::default() }, &scene).unwrap();
        let el = |f| day.frame(f, &scene.key_lights).key_lights[0].direction.z.asin().to_degrees();
        assert!((el(0) - HORIZON_ELEVATION_DEG).abs() < 1e-9 && (el(4) - HORIZON_ELEVATION_DEG).abs() < 1e-9);
        assert!((el(2) - 60.0).abs() < 1e-9, "noon {}", el(2));
        let noon = day.frame(2, &scene.key_lights);
        let az = noon.key_lights[0].direction.y.atan2(noon.key_lights[0].direction.x);
        assert!((az - 1.0).abs() < 1e-12, "the noon azimuth is the scene's");
        assert_eq!(day.frame(7, &scene.key_lights), day.frame(2, &scene.key_lights), "the day repeats");
        let (c0, c4) = (day.frame(0, &[]).camera, day.frame(4, &[]).camera);
        let d0 = c0.position - c0.target;
        let d4 = c4.position - c4.target;
        assert!((d0.length() - d4.length()).abs() < 1e-9 && (d0.z - d4.z).abs() < 1e-9);
        let turn = d0.y.atan2(d0.x) - d4.y.atan2(d4.x);
        assert!((turn.rem_euclid(std::f64::consts::TAU) - 1.5 * std::f64::consts::PI).abs() < 1e-9, "{turn}");
        assert!(
            DayCycle::new(DayParams::default(), &crate::scene::model::Scene { key_lights: vec![], ..scene }).is_err()
        );
    }
}
