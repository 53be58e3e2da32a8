//! The in-memory scene: what a scene file (`docs/scene-format.md`) describes, after validation.
//! Passes and the CPU reference read these types; the TOML layer only fills them.

use crate::error::{Error, Result};
pub use crate::scene::animated::Animation;
use crate::scene::HeightField;

mod content;
mod enums;
mod gi;

pub use content::{Albedo, Camera, Environment, KeyLight, LocalLight, Material, SphereBlocker};
pub use enums::{
    BlockerExp, BlockerKeyLights, BlockerLogCap, BlockerShading, DiffuseLobe, ElevationBasis, GlossyPyramid, Horizon,
    Interpolation, Level0, OmegaMin, PyramidMode, Quality, ScanReach, ShadingFormat, ShadingStorage, Storage,
    VisibilityMethod, LOG_BRDF_EPSILON,
};
pub use gi::GiSettings;

/// `gi.visibility = "sweep"` needs a non-periodic field: the error when `wrap` and `gi` combine
/// them (the scene parser and [`Scene::check_limits`] both ask here).
pub fn check_sweep(wrap: bool, gi: &GiSettings) -> Result<()> {
    if wrap && gi.visibility == VisibilityMethod::Sweep {
        return Err(Error::param(
            "gi.visibility",
            "sweep",
            "\"ladder\" on a periodic field (heightfield.wrap = true): the sweep supports non-periodic fields only",
        ));
    }
    Ok(())
}

/// The exact diffuse lobe needs the incident light zero below the shaded texel's tangent plane,
/// which the casting set is only with the tangent `ω_min` and at full resolution (a sub-sampled
/// receiver has its own normal: measured, `draft`'s indirect light went from 20–54% to 31–90%
/// error), and SH shading throughout, which the sphere blockers' log modes and transfers are not
/// (docs/accuracy.md §6).
pub fn check_lobe(gi: &GiSettings, spheres: usize) -> Result<()> {
    if gi.diffuse_lobe != DiffuseLobe::Exact {
        return Ok(());
    }
    if gi.omega_min != OmegaMin::Tangent {
        return Err(Error::param(
            "gi.diffuse_lobe",
            "exact",
            "\"sh\" with gi.omega_min = \"asin\": the exact lobe needs the tangent ω_min (gi.omega_min = \"tangent\")",
        ));
    }
    if gi.subsample != 1 {
        return Err(Error::param(
            "gi.diffuse_lobe",
            "exact",
            "\"sh\" with gi.subsample > 1: a sub-sampled receiver's tangent plane is not the shaded texel's (gi.subsample = 1)",
        ));
    }
    if spheres > 0 {
        return Err(Error::param("gi.diffuse_lobe", "exact", "\"sh\" in a scene with sphere blockers"));
    }
    Ok(())
}

/// Local lights need a non-periodic field (a periodic one would need every light repeated on
/// the torus; docs/local-lights.md).
pub fn check_local_wrap(wrap: bool, local_lights: usize) -> Result<()> {
    if wrap && local_lights > 0 {
        return Err(Error::param(
            "local_light",
            format!("{local_lights} local light(s) on a periodic field"),
            "a non-periodic field (heightfield.wrap = false): local lights are not repeated across a periodic field",
        ));
    }
    Ok(())
}

/// Magnitude limits of a scene's numbers (docs/robustness.md, "No non-finite output"): within
/// them every stage — pyramids, scans, SH products, Phong lobes, bounces, the view image and
/// the tone map at ±[`MAX_EXPOSURE_STOPS`] — stays inside f32's range, so finite input never
/// gives NaN or infinite output. One table, used by the scene parser's messages.
pub mod limits;

fn within(v: f64, lo: f64, hi: f64) -> bool {
    v.is_finite() && v >= lo && v <= hi
}

/// A complete, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub field: HeightField,
    /// World size of one texel (`s` in CONVENTIONS.md).
    pub texel_size: f64,
    /// Periodic height field.
    pub wrap: bool,
    pub material: Material,
    pub environment: Environment,
    pub key_lights: Vec<KeyLight>,
    /// `[[local_light]]`s (docs/local-lights.md).
    pub local_lights: Vec<LocalLight>,
    /// `[[sphere]]` blockers (docs/blockers.md).
    pub spheres: Vec<SphereBlocker>,
    pub gi: GiSettings,
    pub camera: Camera,
    /// `[animation]`: what moves (`Animation::None` for a static scene).
    pub animation: Animation,
}

impl Scene {
    /// The magnitude limits of [`limits`] on a scene built in code (the scene parser checks
    /// them key by key with the key's name): heights, texel size, radiances, the Phong lobe,
    /// the camera. `Renderer::new` calls it, so an embedder's scene cannot reach NaN through
    /// magnitudes either.
    pub fn check_limits(&self) -> Result<()> {
        limits::check_heights(&self.field)?;
        let (lo, hi) = limits::TEXEL_SIZE;
        if !within(self.texel_size, lo, hi) {
            return Err(Error::param("texel_size", self.texel_size, format!("a number in [{lo:e}, {hi:e}]")));
        }
        self.environment.check()?;
        for (k, l) in self.key_lights.iter().enumerate() {
            l.check(k)?;
        }
        for (k, l) in self.local_lights.iter().enumerate() {
            l.check(k, self.texel_size)?;
        }
        check_local_wrap(self.wrap, self.local_lights.len())?;
        for (k, b) in self.spheres.iter().enumerate() {
            b.check(k, self.texel_size)?;
        }
        self.material.check()?;
        self.camera.check()?;
        check_sweep(self.wrap, &self.gi)?;
        check_lobe(&self.gi, self.spheres.len())
    }
}
