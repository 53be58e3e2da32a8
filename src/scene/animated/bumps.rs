//! Moving bumps (`animation.kind = "bumps"`; [`super`]): Gaussian or raised-cosine bumps on
//! seeded closed paths over the static field, in exactly rounded IEEE operations.

use std::fmt;
use std::str::FromStr;

use super::{check, hash, unit, MAX_BUMPS, SALT_BUMPS};
use crate::error::{Error, Result};
use crate::scene::generators::det_sin;
use crate::scene::heightfield::{HeightField, DEFAULT_MAX_DIM};
use crate::scene::model::limits;

/// Profile of a moving bump (`animation.shape`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BumpShape {
    /// `a·exp(−d²/(2σ²))` with `σ = r/2`, cut off beyond `d = 3r` (where it is below 1.6e-8·a).
    #[default]
    Gaussian,
    /// Raised cosine `a·(1 + cos(π d/r))/2` for `d < r`, 0 outside.
    Cosine,
}

impl FromStr for BumpShape {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "gaussian" => Ok(Self::Gaussian),
            "cosine" => Ok(Self::Cosine),
            _ => Err(Error::param("animation.shape", s, "`gaussian` or `cosine`")),
        }
    }
}

impl fmt::Display for BumpShape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Gaussian => "gaussian",
            Self::Cosine => "cosine",
        })
    }
}

/// Parameters of the moving bumps (`kind = "bumps"`). Sizes are fractions of the field width
/// `w` (like the generators): a bump has radius `radius·w` texels and peak `amplitude·w`
/// texel units (times the texel size for world units).
#[derive(Clone, Debug, PartialEq)]
pub struct BumpParams {
    /// Seed of the paths.
    pub seed: u64,
    /// Number of bumps, `1..=256`.
    pub count: u32,
    /// Bump radius as a fraction of the width, in `(0, 1]`.
    pub radius: f64,
    /// Peak height as a fraction of the width, finite (negative: dents).
    pub amplitude: f64,
    /// Frames per loop, `≥ 2`: every path is closed, so frame `f + period` equals frame `f`.
    pub period: u32,
    /// Half the extent of a path as a fraction of the field size, in `[0, 1]`.
    pub travel: f64,
    pub shape: BumpShape,
}

impl Default for BumpParams {
    fn default() -> Self {
        Self { seed: 1, count: 4, radius: 0.12, amplitude: 0.08, period: 120, travel: 0.3, shape: BumpShape::Gaussian }
    }
}

impl BumpParams {
    /// Checks every range ([`Error::InvalidParameter`] naming `animation.key`).
    pub fn validate(&self) -> Result<()> {
        check("count", self.count, (1..=MAX_BUMPS).contains(&self.count), format!("an integer in 1..={MAX_BUMPS}"))?;
        check(
            "radius",
            self.radius,
            (limits::BUMP_RADIUS.0..=limits::BUMP_RADIUS.1).contains(&self.radius),
            format!("a number in [{}, {}] (fraction of the width)", limits::BUMP_RADIUS.0, limits::BUMP_RADIUS.1),
        )?;
        let m = limits::MAX_BUMP_AMPLITUDE;
        check(
            "amplitude",
            self.amplitude,
            self.amplitude.is_finite() && self.amplitude.abs() <= m,
            format!("a number in [-{m:e}, {m:e}] (fraction of the width)"),
        )?;
        check("period", self.period, self.period >= 2, "an integer ≥ 2 (frames)")?;
        check(
            "travel",
            self.travel,
            self.travel.is_finite() && (0.0..=1.0).contains(&self.travel),
            "a number in [0, 1] (fraction of the field size)",
        )
    }
}

/// One bump's closed Lissajous path: `c(t) = c₀ + a·sin(2π n t/T + φ)` per axis, `n ∈ {1, 2}`.
#[derive(Clone, Debug)]
struct Path {
    centre: [f64; 2],
    reach: [f64; 2],
    cycles: [f64; 2],
    phase: [f64; 2],
    /// Amplitude factor in `[0.6, 1]`.
    gain: f64,
}

/// Bumps moving over a static base field (`Animation::Bumps`).
#[derive(Clone, Debug)]
pub struct MovingBumps {
    params: BumpParams,
    base: HeightField,
    texel_size: f64,
    wrap: bool,
    paths: Vec<Path>,
}

/// `exp(−x)` for `x ≥ 0` with exactly rounded operations only: `e^(−x/256)` by a degree-12
/// Taylor polynomial, squared 8 times (relative error below 1e-13 for `x ≤ 40`; the bumps use
/// `x ≤ 18`).
fn det_exp_neg(x: f64) -> f64 {
    let y = -x / 256.0;
    let mut p = 1.0;
    let mut n = 12.0;
    while n >= 1.0 {
        p = 1.0 + y / n * p;
        n -= 1.0;
    }
    for _ in 0..8 {
        p *= p;
    }
    p
}

impl MovingBumps {
    /// Bumps over `base` (world units; `texel_size` converts the texel-unit bumps to world
    /// units). With `wrap`, paths and distances are periodic.
    pub fn new(params: BumpParams, base: HeightField, texel_size: f64, wrap: bool) -> Result<Self> {
        params.validate()?;
        if !(texel_size.is_finite() && texel_size > 0.0) {
            return Err(Error::param("heightfield.texel_size", texel_size, "a finite number > 0"));
        }
        let (w1, h1) = ((base.width() - 1) as f64, (base.height() - 1) as f64);
        let s = params.seed;
        let paths = (0..u64::from(params.count))
            .map(|i| {
                let u = |k: u64| unit(hash(s, i, k, SALT_BUMPS));
                Path {
                    centre: [w1 * (0.3 + 0.4 * u(0)), h1 * (0.3 + 0.4 * u(1))],
                    reach: [params.travel * w1 * (0.5 + 0.5 * u(2)), params.travel * h1 * (0.5 + 0.5 * u(3))],
                    cycles: [if u(4) < 0.5 { 1.0 } else { 2.0 }, if u(5) < 0.5 { 1.0 } else { 2.0 }],
                    phase: [std::f64::consts::TAU * u(6), std::f64::consts::TAU * u(7)],
                    gain: 0.6 + 0.4 * u(8),
                }
            })
            .collect();
        Ok(Self { params, base, texel_size, wrap, paths })
    }

    pub fn params(&self) -> &BumpParams {
        &self.params
    }

    /// Bump centres (texels) at frame time `t` (fractional frames allowed).
    pub fn centres_at(&self, t: f64) -> Vec<[f64; 2]> {
        let (w, h) = (self.base.width() as f64, self.base.height() as f64);
        let period = f64::from(self.params.period);
        self.paths
            .iter()
            .map(|p| {
                let mut c = [0.0; 2];
                for (a, size) in [(0, w), (1, h)] {
                    let angle = std::f64::consts::TAU * p.cycles[a] * (t / period) + p.phase[a];
                    let v = p.centre[a] + p.reach[a] * det_sin(angle);
                    c[a] = if self.wrap { v - size * (v / size).floor() } else { v };
                }
                c
            })
            .collect()
    }

    /// The field at frame `frame`: the base plus every bump (see [`MovingBumps::heights_at_time`]).
    pub fn heights_at(&self, frame: u64) -> Result<HeightField> {
        self.heights_at_time(frame as f64)
    }

    /// The field at frame time `t`: base + Σ bumps, world units. Errors if `t` is not finite.
    pub fn heights_at_time(&self, t: f64) -> Result<HeightField> {
        if !t.is_finite() {
            return Err(Error::param("animation time", t, "a finite frame time"));
        }
        let (w, h) = (self.base.width(), self.base.height());
        let (wf, hf) = (w as f64, h as f64);
        let r = (self.params.radius * wf).max(1.0);
        let amp = self.params.amplitude * wf * self.texel_size;
        let sigma2 = 0.25 * r * r;
        let cut2 = match self.params.shape {
            BumpShape::Gaussian => 9.0 * r * r,
            BumpShape::Cosine => r * r,
        };
        let centres = self.centres_at(t);
        let mut data: Vec<f64> = self.base.data().iter().map(|&v| f64::from(v)).collect();
        for (c, p) in centres.iter().zip(&self.paths) {
            let a = amp * p.gain;
            for j in 0..h {
                let mut dy = j as f64 - c[1];
                if self.wrap {
                    dy -= hf * (dy / hf + 0.5).floor();
                }
                for i in 0..w {
                    let mut dx = i as f64 - c[0];
                    if self.wrap {
                        dx -= wf * (dx / wf + 0.5).floor();
                    }
                    let d2 = dx * dx + dy * dy;
                    if d2 >= cut2 {
                        continue;
                    }
                    data[j * w + i] += a * match self.params.shape {
                        BumpShape::Gaussian => det_exp_neg(0.5 * d2 / sigma2),
                        BumpShape::Cosine => {
                            0.5 * (1.0 + det_sin(std::f64::consts::PI * d2.sqrt() / r + std::f64::consts::FRAC_PI_2))
                        }
                    };
                }
            }
        }
        HeightField::new("animation (bumps)", w, h, data.into_iter().map(|v| v as f32).collect(), DEFAULT_MAX_DIM)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn det_exp_matches_libm() {
        let mut worst = 0.0f64;
        for k in 0..=4000 {
            let x = k as f64 * 0.01;
            let (a, b) = (det_exp_neg(x), (-x).exp());
            worst = worst.max((a - b).abs() / b);
        }
        assert!(worst <= 1e-13, "relative error {worst:e}");
    }
}
