/// Largest |height| in world units, after `height_scale` and `height_offset` (hard cases
/// use offsets of 10⁷ and amplitudes of 10⁶).
pub const MAX_HEIGHT: f64 = 1e9;
/// `heightfield.texel_size` range, world units.
pub const TEXEL_SIZE: (f64, f64) = (1e-6, 1e6);
/// Largest radiance: each environment SH coefficient (after `intensity`), each key light's
/// radiance component. The sun is about 1.6·10⁹ W m⁻² sr⁻¹.
pub const MAX_RADIANCE: f64 = 1e12;
/// Largest `environment.intensity`.
pub const MAX_INTENSITY: f64 = 1e6;
/// Largest Phong specular colour component `k_s`.
pub const MAX_SPECULAR: f64 = 1e3;
/// Largest Phong exponent `S` (its lobe is a delta far below this at SH order 8).
pub const MAX_EXPONENT: f64 = 1e4;
/// Largest |coordinate| of the camera's position and target, world units.
pub const MAX_COORDINATE: f64 = 1e10;
/// Largest |exposure| in stops (`camera.exposure`, `--exposure`).
pub const MAX_EXPOSURE_STOPS: f64 = 64.0;
/// `material.exponent` range (below it the lobe's normalisation loses every digit in f32).
pub const EXPONENT: (f64, f64) = (1e-3, MAX_EXPONENT);
/// `key_light.N.angular_radius_deg` range, degrees (the sun is 0.27°; a radius that
/// rounds to 0 in f32 would make a zero-width cap).
pub const ANGULAR_RADIUS_DEG: (f64, f64) = (1e-3, 90.0);
/// `camera.fov_deg` range, degrees (the projection's `1/tan(fov/2)` stays in f32).
pub const FOV_DEG: (f64, f64) = (0.01, 179.0);
/// `animation.radius` range (bumps), fraction of the width (a radius that rounds to 0
/// divides by zero in the bump profile).
pub const BUMP_RADIUS: (f64, f64) = (1e-3, 1.0);
/// `local_light.N.radius` range as a multiple of the texel size (a radius that rounds to
/// 0 in f32 would make a zero-size light; one over 10⁶ texels is no longer local).
pub const LOCAL_RADIUS_TEXELS: (f64, f64) = (1e-3, 1e6);
/// Largest |azimuth| in degrees (`key_light.N.azimuth_deg`).
pub const MAX_AZIMUTH_DEG: f64 = 360.0;
/// Largest |world units per simulation unit| of the water (`animation.scale`), and of it
/// times the drop amplitude (`animation.drop_amplitude`): the waves stay far inside
/// [`MAX_HEIGHT`].
pub const MAX_MOTION: f64 = 1e6;
/// Largest |bump amplitude| as a fraction of the width (`animation.amplitude`): at most
/// 1.6·10⁷ world units on a 16384-wide field of unit texels.
pub const MAX_BUMP_AMPLITUDE: f64 = 1e3;

/// Every height of `field` within ±[`MAX_HEIGHT`], else an error naming the first texel
/// past it (heights near f32's limit pass the finiteness check but overflow in the scans).
pub fn check_heights(field: &crate::scene::HeightField) -> crate::Result<()> {
    let Some(k) = field.data().iter().position(|v| f64::from(*v).abs() > MAX_HEIGHT) else { return Ok(()) };
    let (x, y) = (k % field.width(), k / field.width());
    Err(crate::Error::param(
        format!("height at (x={x}, y={y})"),
        field.data()[k],
        format!("within ±{MAX_HEIGHT:e} world units (scale the heights down or use larger units)"),
    ))
}
