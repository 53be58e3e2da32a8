//! Deterministic procedural height fields.
//!
//! Every generator is a pure function of its parameters and the field size: the same
//! parameters give bit-identical heights on every platform. To guarantee that, the code uses
//! only IEEE-754 `f64` operations that are exactly rounded everywhere (`+ − × ÷`, `sqrt`,
//! `floor`) and its own hash-based noise and sine ([`det_sin`]), never the platform `libm`
//! and never a random-number crate. The result is rounded to `f32` once per sample.
//!
//! Sizes and heights are given *relative to the field width* `w` (in texels), so a generator
//! string gives the same-looking terrain at any resolution: e.g. `fbm` with `amplitude = 0.1`
//! has peaks about `0.1·w` texels high, enough for visible shadows. Heights are in texel units
//! (multiply by the texel size `s` for world units, CONVENTIONS.md).
//!
//! A generator is written `name` or `name:key=value,key=value` (see [`Generator::from_str`]),
//! e.g. `fbm:seed=7,octaves=8` or `city:blocks=12,height=0.2`.

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::scene::heightfield::{HeightField, DEFAULT_MAX_DIM};

pub use noise::det_sin;
use noise::{Octave, Wave};
use shapes::{city, crater, dist, feature_centres, fill, spikes, terraces};

mod noise;
mod shapes;

/// Largest `octaves` accepted by [`Generator::Fbm`].
pub const MAX_OCTAVES: u32 = 16;
/// Largest `count`/`waves`/`blocks` accepted by the generators that place features.
pub const MAX_FEATURES: u32 = 4096;

/// A procedural height field. Construct with [`Generator::default_for`], by parsing a string
/// (`"fbm:seed=3"`) or directly; [`Generator::generate`] validates the parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Generator {
    /// Fractional Brownian motion: a sum of `octaves` octaves of 2-D gradient (Perlin) noise;
    /// octave `k` has frequency `frequency·2^k` and weight `0.5^k`. The sum is normalised by the
    /// total weight, so heights lie roughly within `±amplitude·w`.
    ///
    /// Defaults: `seed = 1`, `octaves = 6`, `frequency = 4` (cycles of the first octave across
    /// the width), `amplitude = 0.1` (fraction of the width).
    Fbm {
        /// Seed of the noise; every seed gives a different field.
        seed: u64,
        /// Number of octaves, `1..=16`.
        octaves: u32,
        /// Cycles of the first octave across the field width, `> 0`.
        frequency: f64,
        /// Peak height as a fraction of the width (finite; may be negative).
        amplitude: f64,
    },
    /// A sum of `waves` plane sine waves with fixed, well-spread directions (golden-angle
    /// steps), increasing frequencies `frequency·(1 + k/2)` and fixed phases, normalised so
    /// heights lie within `±amplitude·w`.
    ///
    /// Defaults: `waves = 3`, `frequency = 3` (cycles across the width of the first wave),
    /// `amplitude = 0.05` (fraction of the width).
    Sines {
        /// Number of waves, `1..=4096`.
        waves: u32,
        /// Cycles across the width of the first wave, `> 0`.
        frequency: f64,
        /// Peak height as a fraction of the width (finite).
        amplitude: f64,
    },
    /// `count` right circular cones on flat ground at 0; the first stands at the field centre
    /// `(w/2, h/2)`, the others at seeded random positions. Each cone has base radius
    /// `r = max(radius·w, 1.5)` texels and height `slope·r`; where cones overlap the higher
    /// surface wins.
    ///
    /// Defaults: `seed = 1`, `count = 5`, `radius = 0.15` (fraction of the width), `slope = 1`
    /// (cones as tall as their radius, 45° flanks).
    Cones {
        /// Seed of the cone positions.
        seed: u64,
        /// Number of cones, `1..=4096`.
        count: u32,
        /// Base radius as a fraction of the width, `> 0`.
        radius: f64,
        /// Height / radius (finite, `> 0`).
        slope: f64,
    },
    /// A vertical step: height 0 for columns `i < round(position·w)` and `height·w` from there
    /// on (x = `w/2` by default). The step is one texel wide in the bilinear surface.
    ///
    /// Defaults: `height = 0.25` (fraction of the width), `position = 0.5`.
    Cliff {
        /// Step height as a fraction of the width (finite; may be negative).
        height: f64,
        /// Column of the step as a fraction of the width, in `(0, 1)`.
        position: f64,
    },
    /// `count` impact craters on flat ground at 0 (the first at the field centre, the others at
    /// seeded random positions and radii within `[0.5, 1]·R`, `R = max(radius·w, 1.5)`). A crater
    /// of radius `r` is a parabolic bowl from `−depth·r` at its centre up to a rim of height
    /// `rim·r` at distance `r`, then a rim wall falling quadratically back to 0 at `1.5·r`.
    /// Overlapping craters add.
    ///
    /// Defaults: `seed = 1`, `count = 6`, `radius = 0.12` (fraction of the width),
    /// `depth = 0.4`, `rim = 0.15` (fractions of the crater radius).
    Craters {
        /// Seed of the crater positions and radii.
        seed: u64,
        /// Number of craters, `1..=4096`.
        count: u32,
        /// Largest crater radius as a fraction of the width, `> 0`.
        radius: f64,
        /// Bowl depth below the ground as a fraction of the crater radius, `≥ 0`.
        depth: f64,
        /// Rim height above the ground as a fraction of the crater radius, `≥ 0`.
        rim: f64,
    },
    /// A city: flat ground at 0 cut by a grid of streets into `blocks` square blocks across the
    /// width (pitch `p = max(w/blocks, 2)` texels); each block is split into 2×2 lots, and each
    /// lot holds, with probability `density`, a rectangular building of seeded height in
    /// `[0.25, 1]·height·w`. Streets occupy the last `street` fraction of each pitch in x and y.
    ///
    /// Defaults: `seed = 1`, `blocks = 8`, `street = 0.25`, `height = 0.12` (fraction of the
    /// width), `density = 0.85`.
    City {
        /// Seed of the building heights.
        seed: u64,
        /// Blocks across the width, `1..=4096`.
        blocks: u32,
        /// Street width as a fraction of the block pitch, in `[0, 1)`.
        street: f64,
        /// Tallest building as a fraction of the width (finite, `> 0`).
        height: f64,
        /// Probability that a lot holds a building, in `[0, 1]`.
        density: f64,
    },
    /// Terraces: the fbm of `seed` (4 octaves, first at 3 cycles across the width, heights within
    /// `±amplitude·w`) rounded to `steps` levels, so that every level change is a one-texel cliff
    /// (the sharpest edge a sampled field has). A hard case for pre-filtering.
    ///
    /// Defaults: `seed = 1`, `steps = 8`, `amplitude = 0.1` (fraction of the width).
    Terraces {
        /// Seed of the underlying fbm.
        seed: u64,
        /// Number of levels across the height range, `1..=4096`.
        steps: u32,
        /// Height range as a fraction of the width (finite).
        amplitude: f64,
    },
    /// Thin spikes: `count` one-texel columns of seeded height in `[0.5, 1]·height·w` at seeded
    /// texels over gentle fbm ground (`±height·w/20`). A hard case for the pyramid's filtering of
    /// thin features.
    ///
    /// Defaults: `seed = 1`, `count = 48`, `height = 0.15` (fraction of the width).
    Spikes {
        /// Seed of the spike positions and heights.
        seed: u64,
        /// Number of spikes, `1..=4096`.
        count: u32,
        /// Tallest spike as a fraction of the width (finite, `> 0`).
        height: f64,
    },
}

/// Names accepted by [`Generator::default_for`] and [`Generator::from_str`].
pub fn names() -> &'static [&'static str] {
    &["fbm", "sines", "cones", "cliff", "craters", "city", "terraces", "spikes"]
}

impl Generator {
    /// The generator called `name` (one of [`names`], case-insensitive) with its default
    /// parameters; an unknown name is [`Error::InvalidParameter`] listing the known ones.
    pub fn default_for(name: &str) -> Result<Self> {
        Ok(match name.trim().to_ascii_lowercase().as_str() {
            "fbm" => Generator::Fbm { seed: 1, octaves: 6, frequency: 4.0, amplitude: 0.1 },
            "sines" => Generator::Sines { waves: 3, frequency: 3.0, amplitude: 0.05 },
            "cones" => Generator::Cones { seed: 1, count: 5, radius: 0.15, slope: 1.0 },
            "cliff" => Generator::Cliff { height: 0.25, position: 0.5 },
            "craters" => Generator::Craters { seed: 1, count: 6, radius: 0.12, depth: 0.4, rim: 0.15 },
            "city" => Generator::City { seed: 1, blocks: 8, street: 0.25, height: 0.12, density: 0.85 },
            "terraces" => Generator::Terraces { seed: 1, steps: 8, amplitude: 0.1 },
            "spikes" => Generator::Spikes { seed: 1, count: 48, height: 0.15 },
            _ => return Err(Error::param("generator", format!("'{name}'"), format!("one of {}", names().join(", ")))),
        })
    }

    /// The generator's name (one of [`names`]).
    pub fn name(&self) -> &'static str {
        match self {
            Generator::Fbm { .. } => "fbm",
            Generator::Sines { .. } => "sines",
            Generator::Cones { .. } => "cones",
            Generator::Cliff { .. } => "cliff",
            Generator::Craters { .. } => "craters",
            Generator::City { .. } => "city",
            Generator::Terraces { .. } => "terraces",
            Generator::Spikes { .. } => "spikes",
        }
    }

    /// Checks every parameter against its documented range ([`Error::InvalidParameter`] naming
    /// `generator.key`, the value and the valid range).
    pub fn validate(&self) -> Result<()> {
        let n = self.name();
        let count =
            |key: &str, v: u32, max: u32| check(n, key, v, (1..=max).contains(&v), &format!("an integer in 1..={max}"));
        let positive = |key: &str, v: f64| check(n, key, v, v.is_finite() && v > 0.0, "a finite number > 0");
        let finite = |key: &str, v: f64| check(n, key, v, v.is_finite(), "a finite number");
        let nonneg = |key: &str, v: f64| check(n, key, v, v.is_finite() && v >= 0.0, "a finite number ≥ 0");
        match *self {
            Generator::Fbm { seed: _, octaves, frequency, amplitude } => {
                count("octaves", octaves, MAX_OCTAVES)?;
                positive("frequency", frequency)?;
                finite("amplitude", amplitude)
            }
            Generator::Sines { waves, frequency, amplitude } => {
                count("waves", waves, MAX_FEATURES)?;
                positive("frequency", frequency)?;
                finite("amplitude", amplitude)
            }
            Generator::Cones { seed: _, count: c, radius, slope } => {
                count("count", c, MAX_FEATURES)?;
                positive("radius", radius)?;
                positive("slope", slope)
            }
            Generator::Cliff { height, position } => {
                finite("height", height)?;
                check(n, "position", position, position > 0.0 && position < 1.0, "a number in (0, 1)")
            }
            Generator::Craters { seed: _, count: c, radius, depth, rim } => {
                count("count", c, MAX_FEATURES)?;
                positive("radius", radius)?;
                nonneg("depth", depth)?;
                nonneg("rim", rim)
            }
            Generator::City { seed: _, blocks, street, height, density } => {
                count("blocks", blocks, MAX_FEATURES)?;
                check(n, "street", street, (0.0..1.0).contains(&street), "a number in [0, 1)")?;
                positive("height", height)?;
                check(n, "density", density, (0.0..=1.0).contains(&density), "a number in [0, 1]")
            }
            Generator::Terraces { seed: _, steps, amplitude } => {
                count("steps", steps, MAX_FEATURES)?;
                finite("amplitude", amplitude)
            }
            Generator::Spikes { seed: _, count: c, height } => {
                count("count", c, MAX_FEATURES)?;
                positive("height", height)
            }
        }
    }

    /// Generates a `width × height` field (heights in texel units), validated by
    /// [`HeightField::new`] with [`DEFAULT_MAX_DIM`]: sides must lie in `2..=16384`.
    pub fn generate(&self, width: usize, height: usize) -> Result<HeightField> {
        self.validate()?;
        let source = format!("generator {self}");
        let max = DEFAULT_MAX_DIM as usize;
        if width < 2 || height < 2 || width > max || height > max {
            return Err(Error::FieldSize { source_name: source, width, height, max: DEFAULT_MAX_DIM });
        }
        let w = width as f64;
        let mut data = Vec::with_capacity(width * height);
        match *self {
            Generator::Fbm { seed, octaves, frequency, amplitude } => {
                let octs: Vec<Octave> = (0..octaves).map(|k| Octave::new(seed, k, frequency)).collect();
                let total: f64 = octs.iter().map(|o| o.weight).sum();
                let scale = amplitude * w / total;
                fill(&mut data, width, height, |x, y| {
                    let sum: f64 = octs.iter().map(|o| o.weight * o.sample(x / w, y / w)).sum();
                    sum * scale
                });
            }
            Generator::Sines { waves, frequency, amplitude } => {
                let ws: Vec<Wave> = (0..waves).map(|k| Wave::new(k, frequency, w)).collect();
                let scale = amplitude * w / f64::from(waves);
                fill(&mut data, width, height, |x, y| ws.iter().map(|v| v.sample(x, y)).sum::<f64>() * scale);
            }
            Generator::Cones { seed, count, radius, slope } => {
                let r = (radius * w).max(1.5);
                let centres = feature_centres(seed, count, width, height);
                fill(&mut data, width, height, |x, y| {
                    centres.iter().map(|&(cx, cy, _)| slope * (r - dist(x, y, cx, cy))).fold(0.0, f64::max)
                });
            }
            Generator::Cliff { height: step, position } => {
                let edge = (position * w).round();
                fill(&mut data, width, height, |x, _| if x >= edge { step * w } else { 0.0 });
            }
            Generator::Craters { seed, count, radius, depth, rim } => {
                let big = (radius * w).max(1.5);
                let craters = feature_centres(seed, count, width, height);
                fill(&mut data, width, height, |x, y| {
                    craters
                        .iter()
                        .map(|&(cx, cy, u)| crater(dist(x, y, cx, cy), big * (0.5 + 0.5 * u), depth, rim))
                        .sum()
                });
            }
            Generator::Terraces { seed, steps, amplitude } => {
                terraces(&mut data, (width, height), seed, steps, amplitude)
            }
            Generator::Spikes { seed, count, height: tall } => spikes(&mut data, (width, height), seed, count, tall),
            Generator::City { seed, blocks, street, height: tall, density } => {
                city(&mut data, (width, height), seed, blocks, street, tall, density)
            }
        }
        HeightField::new(&source, width, height, data, DEFAULT_MAX_DIM)
    }
}

/// Formats as the canonical `name:key=value,...` string, which [`Generator::from_str`] parses
/// back to an equal generator.
impl fmt::Display for Generator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Generator::Fbm { seed, octaves, frequency, amplitude } => {
                write!(f, "fbm:seed={seed},octaves={octaves},frequency={frequency},amplitude={amplitude}")
            }
            Generator::Sines { waves, frequency, amplitude } => {
                write!(f, "sines:waves={waves},frequency={frequency},amplitude={amplitude}")
            }
            Generator::Cones { seed, count, radius, slope } => {
                write!(f, "cones:seed={seed},count={count},radius={radius},slope={slope}")
            }
            Generator::Cliff { height, position } => write!(f, "cliff:height={height},position={position}"),
            Generator::Craters { seed, count, radius, depth, rim } => {
                write!(f, "craters:seed={seed},count={count},radius={radius},depth={depth},rim={rim}")
            }
            Generator::City { seed, blocks, street, height, density } => {
                write!(f, "city:seed={seed},blocks={blocks},street={street},height={height},density={density}")
            }
            Generator::Terraces { seed, steps, amplitude } => {
                write!(f, "terraces:seed={seed},steps={steps},amplitude={amplitude}")
            }
            Generator::Spikes { seed, count, height } => write!(f, "spikes:seed={seed},count={count},height={height}"),
        }
    }
}

/// Parses `name` or `name:key=value,key=value` (names and keys case-insensitive, spaces
/// around items ignored); unspecified keys keep the defaults of [`Generator::default_for`].
/// Errors ([`Error::InvalidParameter`]): unknown name (listing [`names`]), an item without
/// `=`, an unknown key (naming it and the generator's keys), a value that does not parse or is
/// out of range (naming `generator.key` and the valid range).
impl FromStr for Generator {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        let (name, params) = match s.split_once(':') {
            Some((n, p)) => (n, p),
            None => (s, ""),
        };
        let mut g = Generator::default_for(name)?;
        let n = g.name();
        let keys = g.keys();
        for item in params.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let Some((key, value)) = item.split_once('=') else {
                return Err(Error::param(
                    format!("{n} parameter"),
                    format!("'{item}'"),
                    format!("key=value with key one of {}", keys.join(", ")),
                ));
            };
            let key = key.trim().to_ascii_lowercase();
            let value = value.trim();
            if !keys.contains(&key.as_str()) {
                return Err(Error::param(
                    format!("{n} parameter"),
                    format!("'{key}'"),
                    format!("one of {}", keys.join(", ")),
                ));
            }
            g.set(&key, value)?;
        }
        g.validate()?;
        Ok(g)
    }
}

impl Generator {
    /// Parameter keys of this generator, in [`Display`](fmt::Display) order.
    pub fn keys(&self) -> &'static [&'static str] {
        match self {
            Generator::Fbm { .. } => &["seed", "octaves", "frequency", "amplitude"],
            Generator::Sines { .. } => &["waves", "frequency", "amplitude"],
            Generator::Cones { .. } => &["seed", "count", "radius", "slope"],
            Generator::Cliff { .. } => &["height", "position"],
            Generator::Craters { .. } => &["seed", "count", "radius", "depth", "rim"],
            Generator::City { .. } => &["seed", "blocks", "street", "height", "density"],
            Generator::Terraces { .. } => &["seed", "steps", "amplitude"],
            Generator::Spikes { .. } => &["seed", "count", "height"],
        }
    }

    /// Sets one parameter from its text (the key is known to be valid for this generator).
    fn set(&mut self, key: &str, value: &str) -> Result<()> {
        let n = self.name();
        let int = |v: &str| {
            v.parse::<u32>().map_err(|_| Error::param(format!("{n}.{key}"), format!("'{v}'"), "an unsigned integer"))
        };
        let seed = |v: &str| {
            v.parse::<u64>()
                .map_err(|_| Error::param(format!("{n}.{key}"), format!("'{v}'"), "an unsigned 64-bit integer"))
        };
        let real = |v: &str| match v.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(Error::param(format!("{n}.{key}"), format!("'{v}'"), "a finite number")),
        };
        match (self, key) {
            (Generator::Fbm { seed: s, .. }, "seed")
            | (Generator::Cones { seed: s, .. }, "seed")
            | (Generator::Craters { seed: s, .. }, "seed")
            | (Generator::City { seed: s, .. }, "seed")
            | (Generator::Terraces { seed: s, .. }, "seed")
            | (Generator::Spikes { seed: s, .. }, "seed") => *s = seed(value)?,
            (Generator::Fbm { octaves: c, .. }, "octaves")
            | (Generator::Sines { waves: c, .. }, "waves")
            | (Generator::Cones { count: c, .. }, "count")
            | (Generator::Craters { count: c, .. }, "count")
            | (Generator::City { blocks: c, .. }, "blocks")
            | (Generator::Terraces { steps: c, .. }, "steps")
            | (Generator::Spikes { count: c, .. }, "count") => *c = int(value)?,
            (Generator::Fbm { frequency: x, .. }, "frequency")
            | (Generator::Fbm { amplitude: x, .. }, "amplitude")
            | (Generator::Sines { frequency: x, .. }, "frequency")
            | (Generator::Sines { amplitude: x, .. }, "amplitude")
            | (Generator::Cones { radius: x, .. }, "radius")
            | (Generator::Cones { slope: x, .. }, "slope")
            | (Generator::Cliff { height: x, .. }, "height")
            | (Generator::Cliff { position: x, .. }, "position")
            | (Generator::Craters { radius: x, .. }, "radius")
            | (Generator::Craters { depth: x, .. }, "depth")
            | (Generator::Craters { rim: x, .. }, "rim")
            | (Generator::City { street: x, .. }, "street")
            | (Generator::City { height: x, .. }, "height")
            | (Generator::City { density: x, .. }, "density")
            | (Generator::Terraces { amplitude: x, .. }, "amplitude")
            | (Generator::Spikes { height: x, .. }, "height") => *x = real(value)?,
            (g, k) => {
                return Err(Error::param(
                    format!("{n} parameter"),
                    format!("'{k}'"),
                    format!("one of {}", g.keys().join(", ")),
                ))
            }
        }
        Ok(())
    }
}

fn check(generator: &str, key: &str, value: impl fmt::Display, ok: bool, expected: &str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::param(format!("{generator}.{key}"), value, expected))
    }
}
