//! Animated height fields: the `[animation]` table of a scene (`docs/scene-format.md`) and the
//! CPU side of both animation kinds (`docs/dynamic.md`).
//!
//! - [`Animation::Water`]: a water surface simulated on the GPU by
//!   [`crate::frame::water::WaterSim`] (CPU twin [`crate::reference::water`]). This module holds
//!   its parameters, their stability check and the deterministic rain schedule
//!   ([`WaterParams::drops_at`]), which the GPU pass and its twin share.
//! - [`Animation::Bumps`]: Gaussian or raised-cosine bumps moving along seeded closed paths over
//!   the scene's static field, evaluated on the CPU by [`MovingBumps::heights_at`] and uploaded
//!   with [`crate::frame::Renderer::update_heights`].
//!
//! Everything is a pure function of the parameters and the step/frame number: the same
//! parameters give the same heights on every run. The bump field uses only exactly rounded
//! IEEE operations (and [`det_sin`](crate::scene::generators::det_sin)), like [`crate::scene::generators`], so it is also identical
//! across platforms.

use std::fmt;

use crate::error::{Error, Result};
use crate::scene::model::limits;

mod bumps;

pub use bumps::{BumpParams, BumpShape, MovingBumps};

/// Most rain drops that can fall in one simulation step (they travel in push constants).
pub const MAX_DROPS_PER_STEP: usize = 4;
/// Largest `animation.steps_per_frame`.
pub const MAX_STEPS_PER_FRAME: u32 = 64;
/// Largest `animation.count` of moving bumps.
pub const MAX_BUMPS: u32 = 256;
/// Range of `animation.drop_radius` (texels).
pub const DROP_RADIUS_RANGE: (f64, f64) = (1.0, 256.0);

/// What moves in a scene (`animation.kind`).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Animation {
    /// A static scene (the default).
    #[default]
    None,
    /// The scene's height field is the initial water surface, simulated on the GPU.
    Water(WaterParams),
    /// Bumps moving over the scene's height field, evaluated on the CPU each frame.
    Bumps(BumpParams),
    /// A day: the sun moves, the sky follows, the camera orbits; the heights stay
    /// (`crate::scene::day`).
    Day(crate::scene::day::DayParams),
    /// The scene's spheres roll over the terrain (`crate::scene::boulders`); the heights stay.
    Boulders(crate::scene::boulders::BoulderParams),
}

impl Animation {
    /// `none`, `water`, `bumps`, `day` or `boulders` (the `animation.kind` value).
    pub fn kind(&self) -> &'static str {
        match self {
            Animation::None => "none",
            Animation::Water(_) => "water",
            Animation::Bumps(_) => "bumps",
            Animation::Day(_) => "day",
            Animation::Boulders(_) => "boulders",
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Water

/// What happens at the edge of the simulated grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Boundary {
    /// Clamp-to-edge neighbours (a zero-flux, Neumann wall): waves reflect, volume is conserved.
    #[default]
    Reflective,
    /// Periodic (wrap-around) neighbours, as with the scene's `heightfield.wrap = true`.
    Periodic,
}

impl Boundary {
    /// `Periodic` when the height field wraps, else `Reflective`.
    pub fn from_wrap(wrap: bool) -> Self {
        if wrap {
            Boundary::Periodic
        } else {
            Boundary::Reflective
        }
    }
}

/// Rain: drops that fall at seeded positions and steps ([`WaterParams::drops_at`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Rain {
    /// Expected drops per simulation step, `0..=4` (each of the [`MAX_DROPS_PER_STEP`] slots of
    /// a step holds a drop with probability `rate / 4`). 0: no rain.
    pub rate: f64,
    /// Peak displacement of a drop (simulation units), finite. Each drop's amplitude is this
    /// times a seeded factor in `[0.5, 1)`.
    pub amplitude: f64,
    /// Drop radius in texels, `1..=256`.
    pub radius: f64,
    /// Seed of the drop positions, amplitudes and steps.
    pub seed: u64,
}

impl Default for Rain {
    fn default() -> Self {
        Self { rate: 0.25, amplitude: 0.5, radius: 3.0, seed: 1 }
    }
}

/// Parameters of the water simulation (`kind = "water"`; `docs/dynamic.md`).
///
/// The state is a displacement `z` per texel; the heights handed to the renderer are
/// `rest_level + scale · z`. One step is the explicit scheme of the course notes' membrane
/// model (ch. 3 §3.7): `z⁺ = z + (1 − δ)(z − z⁻) + k·∇²z`, with `k = speed²` and `δ = damping`;
/// drops displace the surface at rest (they change `z` and `z⁻` alike).
#[derive(Clone, Debug, PartialEq)]
pub struct WaterParams {
    /// Courant number `c·Δt/Δx`: wave speed in texels per step, `> 0` and below
    /// [`max_stable_speed`]`(damping)`.
    pub speed: f64,
    /// Damping `δ ∈ [0, 1]`: the fraction of the velocity lost per step.
    pub damping: f64,
    /// Simulation steps per animation frame, `1..=64`.
    pub steps_per_frame: u32,
    /// World height of the undisturbed surface, finite.
    pub rest_level: f64,
    /// World units per simulation unit, finite and ≠ 0.
    pub scale: f64,
    /// Edge handling.
    pub boundary: Boundary,
    pub rain: Rain,
}

impl Default for WaterParams {
    fn default() -> Self {
        Self {
            speed: 0.5,
            damping: 0.01,
            steps_per_frame: 2,
            rest_level: 0.0,
            scale: 1.0,
            boundary: Boundary::Reflective,
            rain: Rain::default(),
        }
    }
}

/// One rain drop of a step: centre in texels, peak displacement and radius (all `f32`, as the
/// GPU receives them; the CPU twin uses the same rounded values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drop {
    pub x: f32,
    pub y: f32,
    pub amplitude: f32,
    pub radius: f32,
}

/// Largest stable Courant number for damping `δ`: `√((2 − δ)/4)` (1/√2 without damping).
///
/// Von Neumann analysis of `z⁺ = (2 − δ + kλ) z − (1 − δ) z⁻` for an eigenvalue `λ ∈ [−8, 0]`
/// of the 5-point Laplacian: the roots of `r² − (2 − δ + kλ) r + (1 − δ) = 0` lie in the unit
/// disc iff `0 ≤ δ ≤ 2` and `4 − 2δ + kλ ≥ 0`; the worst mode (the checkerboard, `λ = −8`)
/// gives `k ≤ (2 − δ)/4`. At equality it neither grows nor decays (and grows linearly for
/// `δ = 0`, a double root at −1), so the speed must stay strictly below the bound.
pub fn max_stable_speed(damping: f64) -> f64 {
    0.5 * (2.0 - damping).sqrt()
}

/// The profile of a drop at distance `r` (texels) from its centre, `t = r/R`:
/// `(1 − t²)²·(1 − 4t²)` for `t < 1`, 0 outside. The course notes seed each ripple with "a
/// dampened sine wave as the function for raindrop mass" (ch. 3 §3.7); this polynomial is one
/// damped wave — a crest of height 1 at the centre, a node at `t = ½`, a trough ring — chosen
/// with zero volume (`∫₀¹ (1 − s)²(1 − 4s) ds = 0`, `s = t²`) so that rain does not raise or
/// lower the mean level. Smooth (C¹) at `t = 1`.
pub fn drop_profile(r: f64, radius: f64) -> f64 {
    let t2 = (r / radius) * (r / radius);
    if t2 < 1.0 {
        let e = 1.0 - t2;
        e * e * (1.0 - 4.0 * t2)
    } else {
        0.0
    }
}

const SALT_RAIN: u64 = 0x7261_696e;
const SALT_BUMPS: u64 = 0x6275_6d70;

/// SplitMix64 finaliser.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Hash of a seed, two integers and a salt.
fn hash(seed: u64, a: u64, b: u64, salt: u64) -> u64 {
    mix(mix(mix(seed ^ salt) ^ a) ^ b.rotate_left(32))
}

/// Uniform in `[0, 1)` from the top 53 bits of `h`.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

fn check(key: &str, value: impl fmt::Display, ok: bool, expected: impl Into<String>) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::param(format!("animation.{key}"), value, expected))
    }
}

impl WaterParams {
    /// `k = speed²`, the Laplacian weight of the scheme.
    pub fn k(&self) -> f64 {
        self.speed * self.speed
    }

    /// Checks every range, including the stability condition `speed < √((2 − damping)/4)`.
    /// Errors ([`Error::InvalidParameter`]) name the scene key (`animation.speed`, ...).
    pub fn validate(&self) -> Result<()> {
        let d = self.damping;
        check("damping", d, d.is_finite() && (0.0..=1.0).contains(&d), "a number in [0, 1]")?;
        let max = max_stable_speed(d);
        check(
            "speed",
            self.speed,
            self.speed.is_finite() && self.speed > 0.0 && self.speed < max,
            format!(
                "a number in (0, {max:.6}): the scheme is stable only for speed < √((2 − damping)/4) \
                 (damping = {d}; docs/dynamic.md)"
            ),
        )?;
        let spf = self.steps_per_frame;
        check(
            "steps_per_frame",
            spf,
            (1..=MAX_STEPS_PER_FRAME).contains(&spf),
            format!("an integer in 1..={MAX_STEPS_PER_FRAME}"),
        )?;
        let h = limits::MAX_HEIGHT;
        check(
            "rest_level",
            self.rest_level,
            self.rest_level.is_finite() && self.rest_level.abs() <= h,
            format!("a number in [-{h:e}, {h:e}] (world units)"),
        )?;
        let m = limits::MAX_MOTION;
        check(
            "scale",
            self.scale,
            self.scale.is_finite() && self.scale != 0.0 && self.scale.abs() <= m,
            format!("a number ≠ 0 in [-{m:e}, {m:e}] (world units per simulation unit)"),
        )?;
        let r = &self.rain;
        check(
            "rain_rate",
            r.rate,
            r.rate.is_finite() && (0.0..=MAX_DROPS_PER_STEP as f64).contains(&r.rate),
            format!("a number in [0, {MAX_DROPS_PER_STEP}] (expected drops per step)"),
        )?;
        check(
            "drop_amplitude",
            r.amplitude,
            r.amplitude.is_finite() && (r.amplitude * self.scale).abs() <= m,
            format!("a number with |drop_amplitude × scale| ≤ {m:e} (world units)"),
        )?;
        let (lo, hi) = DROP_RADIUS_RANGE;
        check(
            "drop_radius",
            r.radius,
            r.radius.is_finite() && (lo..=hi).contains(&r.radius),
            format!("a number in [{lo}, {hi}] (texels)"),
        )
    }

    /// The drops that fall in step `step` (steps count from 1) on a `width × height` grid:
    /// slot `s` of the step holds a drop when `hash(seed, step, s) < rate/4`, centred uniformly
    /// in `[0, w−1] × [0, h−1]` with amplitude `amplitude · [0.5, 1)` and radius `radius`.
    pub fn drops_at(&self, step: u64, width: usize, height: usize) -> Vec<Drop> {
        let r = &self.rain;
        let p = r.rate / MAX_DROPS_PER_STEP as f64;
        let (w1, h1) = (width.saturating_sub(1) as f64, height.saturating_sub(1) as f64);
        (0..MAX_DROPS_PER_STEP as u64)
            .filter_map(|s| {
                let h = |i: u64| unit(hash(r.seed, step, 8 * s + i, SALT_RAIN));
                (h(0) < p).then(|| Drop {
                    x: (w1 * h(1)) as f32,
                    y: (h1 * h(2)) as f32,
                    amplitude: (r.amplitude * (0.5 + 0.5 * h(3))) as f32,
                    radius: r.radius as f32,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stability_bound() {
        assert!((max_stable_speed(0.0) - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
        let mut p = WaterParams { speed: 0.70, damping: 0.0, ..Default::default() };
        assert!(p.validate().is_ok());
        p.speed = 0.7072;
        assert!(p.validate().is_err());
    }
}
