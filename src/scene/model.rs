//! The in-memory scene: what a scene file (`docs/scene-format.md`) describes, after validation.
//! Passes and the CPU reference read these types; the TOML layer only fills them.

use std::str::FromStr;

use glam::DVec3;

use crate::error::{Error, Result};
pub use crate::scene::animated::Animation;
use crate::scene::HeightField;

/// How the height pyramid is stored and sampled (`gi.pyramid`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PyramidMode {
    /// Every level B-spline-synthesized to the working resolution (NS09 §9).
    #[default]
    Stack,
    /// Decimated levels only, B-spline filtered on the fly (NS09 §10).
    Pyramid,
}

impl FromStr for PyramidMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "stack" => Ok(Self::Stack),
            "pyramid" => Ok(Self::Pyramid),
            _ => Err(Error::param("gi.pyramid", s, "`stack` or `pyramid`")),
        }
    }
}

impl std::fmt::Display for PyramidMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Stack => "stack",
            Self::Pyramid => "pyramid",
        })
    }
}

/// Azimuthal interpolation of the per-direction NLP vectors inside a wedge (`gi.interpolation`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interpolation {
    /// `M_lin` (eq. 20).
    #[default]
    Linear,
    /// `M_bspl` (Appendix A).
    Bspline,
}

impl FromStr for Interpolation {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "linear" => Ok(Self::Linear),
            "bspline" => Ok(Self::Bspline),
            _ => Err(Error::param("gi.interpolation", s, "`linear` or `bspline`")),
        }
    }
}

impl std::fmt::Display for Interpolation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Linear => "linear",
            Self::Bspline => "bspline",
        })
    }
}

/// How glossy exit radiance enters the radiance pyramid (`gi.glossy_pyramid`, §5.3, fig. 5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GlossyPyramid {
    /// One RGB pyramid of diffuse + glossy-toward-the-camera exit radiance (the paper's
    /// cheaper approximation for mixtures).
    #[default]
    Scalar,
    /// The diffuse RGB pyramid plus a pyramid of the incident SH radiance; the glossy lobe is
    /// evaluated toward each receiver (converges to the ground truth).
    Vector,
}

impl FromStr for GlossyPyramid {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "scalar" => Ok(Self::Scalar),
            "vector" => Ok(Self::Vector),
            _ => Err(Error::param("gi.glossy_pyramid", s, "`scalar` or `vector`")),
        }
    }
}

impl std::fmt::Display for GlossyPyramid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Scalar => "scalar",
            Self::Vector => "vector",
        })
    }
}

/// Algorithm settings (`[gi]`). Defaults are the paper's (§9).
#[derive(Clone, Debug, PartialEq)]
pub struct GiSettings {
    /// SH order n (bands 0..n−1, n² coefficients), 2..=8.
    pub sh_order: usize,
    /// Azimuthal samples m for environment visibility (and indirect), 4..=256.
    pub azimuths: u32,
    /// Azimuthal samples per key light, 2..=64.
    pub key_light_azimuths: u32,
    /// Pyramid level step k_v, 1..=16.
    pub level_step: u32,
    /// Level offset o_v, 0..=8.
    pub level_offset: u32,
    /// Visibility sub-sampling: 1, 2 or 4.
    pub subsample: u32,
    pub interpolation: Interpolation,
    pub pyramid: PyramidMode,
    /// Indirect bounces, 0..=16 (0: direct light only).
    pub bounces: u32,
    /// Radiance-pyramid level step k_u, 1..=16 (§5.3).
    pub radiance_level_step: u32,
    /// Radiance-pyramid level offset o_u, 0..=8 (§5.3).
    pub radiance_level_offset: u32,
    /// Amortised shading (§7): with static heights, even frames update the direct shading
    /// and odd frames the indirect; when heights change, both.
    pub amortize: bool,
    /// Glossy radiance pyramid (§5.3): scalar approximation or SH vector pyramid.
    pub glossy_pyramid: GlossyPyramid,
}

impl Default for GiSettings {
    fn default() -> Self {
        Self {
            sh_order: 4,
            azimuths: 32,
            key_light_azimuths: 3,
            level_step: 4,
            level_offset: 2,
            subsample: 1,
            interpolation: Interpolation::Linear,
            pyramid: PyramidMode::Stack,
            bounces: 0,
            radiance_level_step: 4,
            radiance_level_offset: 2,
            amortize: true,
            glossy_pyramid: GlossyPyramid::Scalar,
        }
    }
}

/// Surface albedo: one RGB value or one per texel (linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    Constant([f32; 3]),
    /// Row-major, one RGB per height-field texel.
    Map(Vec<[f32; 3]>),
}

/// `[material]`: diffuse albedo plus an optional normalised Phong lobe.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub albedo: Albedo,
    /// Phong specular colour k_s (None: diffuse only).
    pub specular: Option<[f32; 3]>,
    /// Phong exponent S (> 0).
    pub exponent: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self { albedo: Albedo::Constant([0.8; 3]), specular: None, exponent: 32.0 }
    }
}

/// `[environment]`: SH radiance, `n²` RGB coefficients already multiplied by `intensity`
/// (index `k = l(l+1)+m`, CONVENTIONS.md). May hold more or fewer coefficients than the
/// rendering order: extra bands are ignored, missing ones are zero.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Environment {
    pub sh: Vec<[f64; 3]>,
}

/// `[[key_light]]`: a spherical cap light.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyLight {
    /// Unit direction from the surface toward the light centre.
    pub direction: DVec3,
    /// Angular radius α in radians, in (0, π/2].
    pub angular_radius: f64,
    /// Uniform RGB radiance inside the cap.
    pub radiance: [f64; 3],
}

/// `[camera]`: a pinhole camera for the view image and for view-dependent (glossy) shading.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// World position.
    pub position: DVec3,
    /// World point looked at.
    pub target: DVec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f64,
    /// View image size in pixels.
    pub width: u32,
    pub height: u32,
    /// Tone-mapping exposure (stops) of the PNG.
    pub exposure: f32,
}

impl Camera {
    /// A camera looking at the middle of a `w × h` field (texel size `s`, height range
    /// `lo..hi`) from the south-west and above.
    pub fn default_for(w: usize, h: usize, s: f64, lo: f64, hi: f64) -> Self {
        let (cx, cy) = ((w as f64 - 1.0) * s * 0.5, (h as f64 - 1.0) * s * 0.5);
        let extent = (w.max(h) as f64) * s;
        let mid = 0.5 * (lo + hi);
        Self {
            position: DVec3::new(cx - 0.9 * extent, cy - 0.9 * extent, hi + 0.8 * extent),
            target: DVec3::new(cx, cy, mid),
            fov_deg: 40.0,
            width: 960,
            height: 540,
            exposure: -1.5,
        }
    }
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
    pub gi: GiSettings,
    pub camera: Camera,
    /// `[animation]`: what moves (`Animation::None` for a static scene).
    pub animation: Animation,
}

impl GiSettings {
    /// Checks every range; errors name the key (`gi.azimuths` ...).
    pub fn validate(&self) -> Result<()> {
        let check = |key: &str, v: u32, lo: u32, hi: u32| {
            if v < lo || v > hi {
                Err(Error::param(key, v, format!("an integer in {lo}..={hi}")))
            } else {
                Ok(())
            }
        };
        check("gi.sh_order", u32::try_from(self.sh_order).unwrap_or(u32::MAX), 2, 8)?;
        check("gi.azimuths", self.azimuths, 4, 256)?;
        check("gi.key_light_azimuths", self.key_light_azimuths, 2, 64)?;
        check("gi.level_step", self.level_step, 1, 16)?;
        check("gi.level_offset", self.level_offset, 0, 8)?;
        if ![1, 2, 4].contains(&self.subsample) {
            return Err(Error::param("gi.subsample", self.subsample, "1, 2 or 4"));
        }
        check("gi.bounces", self.bounces, 0, 16)?;
        check("gi.radiance_level_step", self.radiance_level_step, 1, 16)?;
        check("gi.radiance_level_offset", self.radiance_level_offset, 0, 8)?;
        Ok(())
    }

    /// Working (visibility) grid for a `w × h` field: `ceil(w/s) × ceil(h/s)`, at least 2×2.
    pub fn working_size(&self, w: usize, h: usize) -> (usize, usize) {
        let s = self.subsample.max(1) as usize;
        (w.div_ceil(s).max(2), h.div_ceil(s).max(2))
    }
}
