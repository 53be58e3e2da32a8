//! The material, environment, key and local lights, sphere blockers and camera, with their limit checks.

use glam::DVec3;

use super::{limits, within};
use crate::error::{Error, Result};

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

/// `[[local_light]]`: a sphere of uniform radiance at a finite distance (CONVENTIONS.md
/// "Lighting"; docs/local-lights.md). From a point at distance `d > r` from its centre it
/// subtends a cap of half-angle `asin(r/d)`.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalLight {
    /// World position of the centre.
    pub position: DVec3,
    /// Radius in world units (> 0).
    pub radius: f64,
    /// Uniform RGB radiance of its surface.
    pub radiance: [f64; 3],
}

/// `[[sphere]]`: an opaque sphere blocker (CONVENTIONS.md "Lighting"; docs/blockers.md): it
/// blocks every ray that intersects it. Spheres do not reflect light onto the field (their
/// albedo shades them in the view image).
#[derive(Clone, Debug, PartialEq)]
pub struct SphereBlocker {
    /// World position of the centre.
    pub center: DVec3,
    /// Radius in world units (> 0).
    pub radius: f64,
    /// Diffuse albedo (view image).
    pub albedo: [f64; 3],
}

impl SphereBlocker {
    /// Sphere `k` of a scene of texel size `texel_size`: a centre within
    /// ±[`limits::MAX_COORDINATE`], a radius of [`limits::LOCAL_RADIUS_TEXELS`] texels, an
    /// albedo in [0, 1].
    pub fn check(&self, k: usize, texel_size: f64) -> Result<()> {
        let c = limits::MAX_COORDINATE;
        if !self.center.to_array().iter().all(|x| within(*x, -c, c)) {
            return Err(Error::param(
                format!("sphere {k} center"),
                format!("{:?}", self.center),
                format!("each within ±{c:e}"),
            ));
        }
        let (lo, hi) = limits::LOCAL_RADIUS_TEXELS;
        if !within(self.radius, lo * texel_size, hi * texel_size) {
            return Err(Error::param(
                format!("sphere {k} radius"),
                self.radius,
                format!(
                    "a number in [{:e}, {:e}] world units ({lo:e}..{hi:e} texels)",
                    lo * texel_size,
                    hi * texel_size
                ),
            ));
        }
        if !self.albedo.iter().all(|v| within(*v, 0.0, 1.0)) {
            return Err(Error::param(format!("sphere {k} albedo"), format!("{:?}", self.albedo), "each in [0, 1]"));
        }
        Ok(())
    }
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

impl Environment {
    /// The environment rotated by `r` (row-major rotation matrix): the radiance it had in
    /// direction `d` arrives from `R·d` (exact per SH band, [`crate::math::sh::rotate`]);
    /// order `n` = the coefficients given, rounded down to a square.
    pub fn rotated(&self, r: [[f64; 3]; 3]) -> Environment {
        let n = (self.sh.len() as f64).sqrt().floor() as usize;
        if n == 0 {
            return self.clone();
        }
        let per: Vec<Vec<f64>> =
            (0..3).map(|c| crate::math::sh::rotate(n, &self.sh.iter().map(|v| v[c]).collect::<Vec<_>>(), r)).collect();
        Environment { sh: (0..n * n).map(|k| [per[0][k], per[1][k], per[2][k]]).collect() }
    }

    /// The environment times `intensity` (every coefficient).
    pub fn scaled(&self, intensity: f64) -> Environment {
        Environment { sh: self.sh.iter().map(|c| c.map(|v| v * intensity)).collect() }
    }

    /// Every coefficient within ±[`limits::MAX_RADIANCE`] (also for live changes,
    /// `Renderer::set_environment`).
    pub fn check(&self) -> Result<()> {
        let m = limits::MAX_RADIANCE;
        if let Some(k) = self.sh.iter().position(|c| !c.iter().all(|v| within(*v, -m, m))) {
            return Err(Error::param(
                format!("environment SH coefficient {k}"),
                format!("{:?}", self.sh[k]),
                format!("each within ±{m:e}"),
            ));
        }
        Ok(())
    }
}

impl KeyLight {
    /// Key light `k`: radiance in [0, [`limits::MAX_RADIANCE`]], a finite non-zero direction,
    /// an angular radius within [`limits::ANGULAR_RADIUS_DEG`].
    pub fn check(&self, k: usize) -> Result<()> {
        let m = limits::MAX_RADIANCE;
        if !self.radiance.iter().all(|v| within(*v, 0.0, m)) {
            return Err(Error::param(
                format!("key light {k} radiance"),
                format!("{:?}", self.radiance),
                format!("each in [0, {m:e}]"),
            ));
        }
        let d = self.direction;
        if !(d.is_finite() && d.length() > 1e-12) {
            return Err(Error::param(
                format!("key light {k} direction"),
                format!("{d:?}"),
                "a finite, non-zero vector",
            ));
        }
        let (lo, hi) = limits::ANGULAR_RADIUS_DEG;
        if !within(self.angular_radius, lo.to_radians() * (1.0 - 1e-12), hi.to_radians() * (1.0 + 1e-12)) {
            return Err(Error::param(
                format!("key light {k} angular radius"),
                format!("{}°", self.angular_radius.to_degrees()),
                format!("a number in [{lo}, {hi}] degrees"),
            ));
        }
        Ok(())
    }
}

impl LocalLight {
    /// Local light `k` of a scene of texel size `texel_size`: radiance in [0,
    /// [`limits::MAX_RADIANCE`]], a position within ±[`limits::MAX_COORDINATE`], a radius of
    /// [`limits::LOCAL_RADIUS_TEXELS`] texels.
    pub fn check(&self, k: usize, texel_size: f64) -> Result<()> {
        let m = limits::MAX_RADIANCE;
        if !self.radiance.iter().all(|v| within(*v, 0.0, m)) {
            return Err(Error::param(
                format!("local light {k} radiance"),
                format!("{:?}", self.radiance),
                format!("each in [0, {m:e}]"),
            ));
        }
        let c = limits::MAX_COORDINATE;
        if !self.position.to_array().iter().all(|x| within(*x, -c, c)) {
            return Err(Error::param(
                format!("local light {k} position"),
                format!("{:?}", self.position),
                format!("each coordinate within ±{c:e}"),
            ));
        }
        let (lo, hi) = limits::LOCAL_RADIUS_TEXELS;
        if !within(self.radius, lo * texel_size, hi * texel_size) {
            return Err(Error::param(
                format!("local light {k} radius"),
                self.radius,
                format!(
                    "a number in [{:e}, {:e}] world units ({lo:e}..{hi:e} texels)",
                    lo * texel_size,
                    hi * texel_size
                ),
            ));
        }
        Ok(())
    }
}

impl Material {
    /// The Phong exponent within [`limits::EXPONENT`], specular within [0,
    /// [`limits::MAX_SPECULAR`]], a constant albedo finite and ≥ 0.
    pub fn check(&self) -> Result<()> {
        let (elo, ehi) = limits::EXPONENT;
        if !within(f64::from(self.exponent), elo, ehi) {
            return Err(Error::param("material exponent", self.exponent, format!("a number in [{elo}, {ehi}]")));
        }
        if let Some(sp) = self.specular {
            if !sp.iter().all(|v| within(f64::from(*v), 0.0, limits::MAX_SPECULAR)) {
                return Err(Error::param(
                    "material specular",
                    format!("{sp:?}"),
                    format!("each in [0, {:e}]", limits::MAX_SPECULAR),
                ));
            }
        }
        if let Albedo::Constant(a) = self.albedo {
            if !a.iter().all(|v| within(f64::from(*v), 0.0, f64::from(f32::MAX))) {
                return Err(Error::param("material albedo", format!("{a:?}"), "finite, each ≥ 0"));
            }
        }
        Ok(())
    }
}

impl Camera {
    /// Position and target within ±[`limits::MAX_COORDINATE`].
    pub fn check(&self) -> Result<()> {
        let c = limits::MAX_COORDINATE;
        for (name, v) in [("camera position", self.position), ("camera target", self.target)] {
            if !v.to_array().iter().all(|x| within(*x, -c, c)) {
                return Err(Error::param(name, format!("{v:?}"), format!("each coordinate within ±{c:e}")));
            }
        }
        Ok(())
    }
}
