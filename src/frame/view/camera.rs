//! The view's camera model (docs/view.md): basis, reversed-depth projection, near/far fit, rays.

use glam::{DMat4, DVec3, DVec4};

use super::NEAR_RATIO;
use crate::error::{Error, Result};
use crate::scene::model::Camera;

/// The camera model of docs/view.md, in f64: an orthonormal basis, a reversed-depth Vulkan
/// perspective and the near/far planes fitted to the field's bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraModel {
    pub eye: DVec3,
    /// Image right, image up and viewing direction, orthonormal: `right = normalize(forward ×
    /// ẑ)` (ŷ instead of ẑ when looking straight up or down), `up = right × forward`.
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
    /// `tan(fov_y / 2)`.
    pub tan_half_fov: f64,
    /// Width / height in pixels.
    pub aspect: f64,
    pub near: f64,
    pub far: f64,
    pub width: u32,
    pub height: u32,
}

impl CameraModel {
    /// Builds the model for a `field_w × field_h` field of texel size `s` whose heights lie in
    /// `lo..=hi`. Errors on a non-finite or degenerate camera.
    pub fn new(camera: &Camera, field_w: usize, field_h: usize, s: f64, lo: f64, hi: f64) -> Result<Self> {
        Self::check(camera, s)?;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Error::param("height range", format!("{lo}..{hi}"), "finite lo ≤ hi"));
        }
        let (x1, y1) = ((field_w.max(1) - 1) as f64 * s, (field_h.max(1) - 1) as f64 * s);
        Ok(Self::fit(camera, DVec3::new(0.0, 0.0, lo), DVec3::new(x1, y1, hi), s))
    }

    /// Builds the model with the near/far planes fitted to the box `min..=max` (world
    /// coordinates) instead of a field's box; `s` (the texel size) is the smallest extent.
    /// [`CameraModel::new`] is this for the box `[0, (W−1)s] × [0, (H−1)s] × [lo, hi]`.
    pub fn with_box(camera: &Camera, min: DVec3, max: DVec3, s: f64) -> Result<Self> {
        Self::check(camera, s)?;
        if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
            return Err(Error::param(
                "view bounding box",
                format!("{:?}..{:?}", min.to_array(), max.to_array()),
                "finite min ≤ max",
            ));
        }
        Ok(Self::fit(camera, min, max, s))
    }

    fn check(camera: &Camera, s: f64) -> Result<()> {
        let finite3 = |v: DVec3| v.is_finite();
        if !finite3(camera.position) || !finite3(camera.target) {
            return Err(Error::param(
                "camera.position/target",
                format!("{:?} / {:?}", camera.position.to_array(), camera.target.to_array()),
                "finite points",
            ));
        }
        if (camera.target - camera.position).try_normalize().is_none() {
            return Err(Error::param("camera.target", format!("{:?}", camera.target.to_array()), "≠ camera.position"));
        }
        if !(camera.fov_deg > 0.0 && camera.fov_deg < 180.0) {
            return Err(Error::param("camera.fov_deg", camera.fov_deg, "a number in (0, 180) (degrees)"));
        }
        if camera.width == 0 || camera.height == 0 {
            return Err(Error::param("camera size", format!("{}×{}", camera.width, camera.height), "at least 1×1"));
        }
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::param("texel_size", s, "a finite number > 0"));
        }
        Ok(())
    }

    /// The model for a checked camera and a finite box.
    fn fit(camera: &Camera, min: DVec3, max: DVec3, s: f64) -> Self {
        let forward = (camera.target - camera.position).normalize();
        let mut right = forward.cross(DVec3::Z);
        if right.length() < 1e-9 {
            right = forward.cross(DVec3::Y);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let mut dmin = f64::INFINITY;
        let mut dmax = f64::NEG_INFINITY;
        for c in 0..8 {
            let p = DVec3::new(
                if c & 1 == 0 { min.x } else { max.x },
                if c & 2 == 0 { min.y } else { max.y },
                if c & 4 == 0 { min.z } else { max.z },
            );
            let z = (p - camera.position).dot(forward);
            dmin = dmin.min(z);
            dmax = dmax.max(z);
        }
        let extent = ((max.x - min.x).max(max.y - min.y) + (max.z - min.z)).max(s);
        // Margins so that geometry exactly on the box is not clipped by rounding.
        let far = if dmax > 0.0 { dmax * (1.0 + 1e-3) + 1e-6 * extent } else { extent };
        let near = (dmin * (1.0 - 1e-3)).max(far * NEAR_RATIO);
        Self {
            eye: camera.position,
            right,
            up,
            forward,
            tan_half_fov: (camera.fov_deg.to_radians() * 0.5).tan(),
            aspect: f64::from(camera.width) / f64::from(camera.height),
            near,
            far,
            width: camera.width,
            height: camera.height,
        }
    }

    /// World → view: x right, y up, looking down −z.
    pub fn view(&self) -> DMat4 {
        let (r, u, f) = (self.right, self.up, self.forward);
        DMat4::from_cols(
            DVec4::new(r.x, u.x, -f.x, 0.0),
            DVec4::new(r.y, u.y, -f.y, 0.0),
            DVec4::new(r.z, u.z, -f.z, 0.0),
            DVec4::new(-r.dot(self.eye), -u.dot(self.eye), f.dot(self.eye), 1.0),
        )
    }

    /// View → clip, Vulkan conventions (NDC y down, depth in 0..1) with reversed depth: the
    /// near plane maps to 1, the far plane to 0.
    pub fn projection(&self) -> DMat4 {
        let fy = 1.0 / self.tan_half_fov;
        let (n, f) = (self.near, self.far);
        let a = n / (f - n);
        DMat4::from_cols(
            DVec4::new(fy / self.aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -fy, 0.0, 0.0),
            DVec4::new(0.0, 0.0, a, -1.0),
            DVec4::new(0.0, 0.0, a * f, 0.0),
        )
    }

    /// World → clip.
    pub fn view_projection(&self) -> DMat4 {
        self.projection() * self.view()
    }

    /// Eye-relative world → clip: maps `P − eye` to clip space (`view_projection()` with the eye
    /// at the origin). The GPU uses this form so that its f32 arithmetic never holds absolute
    /// world coordinates times the matrix (docs/view.md).
    pub fn eye_relative_view_projection(&self) -> DMat4 {
        let mut rotation = self.view();
        rotation.w_axis = DVec4::W;
        self.projection() * rotation
    }

    /// The world-space ray through pixel position `(px, py)` (pixel centres at `+0.5`; row 0 is
    /// the top of the image): origin and unit direction.
    pub fn ray(&self, px: f64, py: f64) -> (DVec3, DVec3) {
        let x = (2.0 * px / f64::from(self.width) - 1.0) * self.tan_half_fov * self.aspect;
        let y = (1.0 - 2.0 * py / f64::from(self.height)) * self.tan_half_fov;
        (self.eye, (self.forward + x * self.right + y * self.up).normalize())
    }
}
