//! Field shapes of the generators: terraces, spikes, city, craters, the fill and feature placement.

use super::noise::{hash, unit, Octave, SALT_CITY, SALT_FEATURE};

/// The heights of [`Generator::Terraces`](super::Generator::Terraces) into `data`: its fbm rounded to `steps` levels.
pub(super) fn terraces(data: &mut Vec<f32>, (width, height): (usize, usize), seed: u64, steps: u32, amplitude: f64) {
    let w = width as f64;
    let octs: Vec<Octave> = (0..4).map(|k| Octave::new(seed, k, 3.0)).collect();
    let total: f64 = octs.iter().map(|o| o.weight).sum();
    let scale = amplitude * w / total;
    let step = 2.0 * amplitude.abs() * w / f64::from(steps);
    fill(data, width, height, |x, y| {
        let f: f64 = octs.iter().map(|o| o.weight * o.sample(x / w, y / w)).sum::<f64>() * scale;
        if step > 0.0 {
            (f / step + 0.5).floor() * step
        } else {
            f
        }
    });
}

/// The heights of [`Generator::Spikes`](super::Generator::Spikes) (height `tall`) into `data`: fbm ground, then the
/// spikes.
pub(super) fn spikes(data: &mut Vec<f32>, (width, height): (usize, usize), seed: u64, count: u32, tall: f64) {
    let w = width as f64;
    let octs: Vec<Octave> = (0..3).map(|k| Octave::new(seed, k, 2.0)).collect();
    let total: f64 = octs.iter().map(|o| o.weight).sum();
    let scale = 0.05 * tall * w / total;
    fill(data, width, height, |x, y| octs.iter().map(|o| o.weight * o.sample(x / w, y / w)).sum::<f64>() * scale);
    for (cx, cy, u) in feature_centres(seed, count, width, height) {
        let (i, j) = (cx.round() as usize, cy.round() as usize);
        // Spikes on the same texel do not stack: the tallest one stands.
        let v = &mut data[j * width + i];
        *v = v.max(((0.5 + 0.5 * u) * tall * w) as f32);
    }
}

/// The heights of [`Generator::City`](super::Generator::City) (height `tall`) into `data`: streets at 0, buildings on
/// the lots.
pub(super) fn city(
    data: &mut Vec<f32>,
    (width, height): (usize, usize),
    seed: u64,
    blocks: u32,
    street: f64,
    tall: f64,
    density: f64,
) {
    let w = width as f64;
    let pitch = (w / f64::from(blocks)).max(2.0);
    let s = hash(seed, 0, 0, SALT_CITY);
    fill(data, width, height, |x, y| {
        let (bx, u) = split(x / pitch);
        let (by, v) = split(y / pitch);
        let lot = 1.0 - street;
        if u >= lot || v >= lot {
            return 0.0; // street
        }
        let lx = 2 * bx + i64::from(u >= 0.5 * lot);
        let ly = 2 * by + i64::from(v >= 0.5 * lot);
        if unit(hash(s, lx, ly, 1)) < density {
            tall * w * (0.25 + 0.75 * unit(hash(s, lx, ly, 2)))
        } else {
            0.0
        }
    });
}

/// Fills `data` row by row (row `j` = y) with `f(x, y)` at texel `(i, j)`, rounded to f32.
pub(super) fn fill(data: &mut Vec<f32>, width: usize, height: usize, f: impl Fn(f64, f64) -> f64) {
    for j in 0..height {
        for i in 0..width {
            data.push(f(i as f64, j as f64) as f32);
        }
    }
}

pub(super) fn dist(x: f64, y: f64, cx: f64, cy: f64) -> f64 {
    ((x - cx) * (x - cx) + (y - cy) * (y - cy)).sqrt()
}

/// Integer part (floor) and fraction in `[0, 1)` of `t`.
pub(super) fn split(t: f64) -> (i64, f64) {
    let f = t.floor();
    (f as i64, t - f)
}

/// Crater profile at distance `d` from the centre of a crater of radius `r`.
pub(super) fn crater(d: f64, r: f64, depth: f64, rim: f64) -> f64 {
    let t = d / r;
    if t <= 1.0 {
        -depth * r + (depth + rim) * r * t * t
    } else if t < 1.5 {
        let s = (1.5 - t) / 0.5;
        rim * r * s * s
    } else {
        0.0
    }
}

/// `(x, y, u)` of `count` features: the first at `(w/2, h/2)`, the others uniformly placed over
/// `[0, w−1] × [0, h−1]`; `u ∈ [0, 1)` is a per-feature random number (the first gets 1).
pub(super) fn feature_centres(seed: u64, count: u32, width: usize, height: usize) -> Vec<(f64, f64, f64)> {
    let (w1, h1) = ((width - 1) as f64, (height - 1) as f64);
    let mut v = vec![((width / 2) as f64, (height / 2) as f64, 1.0)];
    for k in 1..i64::from(count) {
        v.push((
            w1 * unit(hash(seed, k, 0, SALT_FEATURE)),
            h1 * unit(hash(seed, k, 1, SALT_FEATURE)),
            unit(hash(seed, k, 2, SALT_FEATURE)),
        ));
    }
    v
}
