//! CPU twin of [`crate::frame::water`] in f64: the same scheme, boundary handling and rain
//! schedule (course notes ch. 3 §3.7; `docs/dynamic.md`).
//!
//! The notes model the water surface as a thin elastic membrane whose lattice points store the
//! current and the previous height (fig. 26) and are pulled by their four neighbours (fig. 27):
//! the 2-D wave equation `∂z/∂t = v, ∂v/∂t = c²∇²z`, integrated explicitly. With the two
//! stored time levels the explicit step is
//!
//! ```text
//! z^{n+1} = z^n + (1 − δ)(z^n − z^{n−1}) + k·L(z^n),   k = (c·Δt/Δx)² = speed²,
//! L(z)_ij = z_{i−1,j} + z_{i+1,j} + z_{i,j−1} + z_{i,j+1} − 4 z_ij,
//! ```
//!
//! stable iff `0 < k < (2 − δ)/4` ([`crate::scene::animated::max_stable_speed`]). Drops `D` of
//! step `n+1` ([`WaterParams::drops_at`], profile [`crate::scene::animated::drop_profile`]) are
//! added to both `z^{n+1}` and the stored `z^n`: they displace the surface without giving it a
//! velocity.
//!
//! The GPU carries `(z, v = z^n − z^{n−1})` instead (`v^{n+1} = (1 − δ)v^n + k·L(z^n)`,
//! `z^{n+1} = z^n + v^{n+1} + D`), the same recurrence in exact arithmetic; this twin keeps the
//! notes' two-level form so that the comparison also checks that equivalence.
//!
//! Properties the tests check: with clamp-to-edge (reflective) or periodic neighbours
//! `Σ L(z) = 0`, so `Σz^{n+1} − Σz^n = (1 − δ)(Σz^n − Σz^{n−1})`: a surface that starts at rest
//! keeps its volume exactly (for any damping) until rain falls.

use crate::error::{Error, Result};
use crate::scene::animated::{drop_profile, Boundary, Drop, WaterParams};

/// One step on a `w × h` lattice: reads `cur` (`z^n`) and `prev_next` (`z^{n−1}`), overwrites
/// `prev_next` with `z^{n+1}`, then adds the `drops` to both (`cur` becomes the next step's
/// `z^{n−1}`). No validation: `k` and `retain = 1 − δ` are used as given (so tests can step
/// outside the stable range).
#[allow(clippy::too_many_arguments)]
pub fn step(
    w: usize,
    h: usize,
    periodic: bool,
    k: f64,
    retain: f64,
    cur: &mut [f64],
    prev_next: &mut [f64],
    drops: &[Drop],
) {
    let addr = |p: i64, n: usize| -> usize {
        if periodic {
            p.rem_euclid(n as i64) as usize
        } else {
            p.clamp(0, n as i64 - 1) as usize
        }
    };
    let delta = |d: f64, n: usize| if periodic { d - n as f64 * (d / n as f64 + 0.5).floor() } else { d };
    for j in 0..h {
        for i in 0..w {
            let (x, y) = (i as i64, j as i64);
            let z = cur[j * w + i];
            let lap = cur[j * w + addr(x - 1, w)]
                + cur[j * w + addr(x + 1, w)]
                + cur[addr(y - 1, h) * w + i]
                + cur[addr(y + 1, h) * w + i]
                - 4.0 * z;
            prev_next[j * w + i] = z + retain * (z - prev_next[j * w + i]) + k * lap;
        }
    }
    if drops.is_empty() {
        return;
    }
    for j in 0..h {
        for i in 0..w {
            let mut sum = 0.0;
            for d in drops {
                let dx = delta(i as f64 - f64::from(d.x), w);
                let dy = delta(j as f64 - f64::from(d.y), h);
                sum += f64::from(d.amplitude) * drop_profile((dx * dx + dy * dy).sqrt(), f64::from(d.radius));
            }
            prev_next[j * w + i] += sum;
            cur[j * w + i] += sum;
        }
    }
}

/// The simulation state in f64.
pub struct WaterCpu {
    pub width: usize,
    pub height: usize,
    params: WaterParams,
    /// `z^n`.
    cur: Vec<f64>,
    /// `z^{n−1}`.
    prev: Vec<f64>,
    steps: u64,
}

impl WaterCpu {
    /// Like [`crate::frame::water::WaterSim::new`]: validates `params`, starts at rest with
    /// `z^0 = z^{−1} = initial`.
    pub fn new(width: usize, height: usize, params: WaterParams, initial: &[f32]) -> Result<Self> {
        params.validate()?;
        if width < 2 || height < 2 || initial.len() != width * height {
            return Err(Error::param(
                "water initial state",
                format!("{} values for {width}×{height}", initial.len()),
                "W·H values with W, H ≥ 2",
            ));
        }
        let cur: Vec<f64> = initial.iter().map(|&v| f64::from(v)).collect();
        Ok(Self { width, height, params, prev: cur.clone(), cur, steps: 0 })
    }

    /// Advances one step.
    pub fn step(&mut self) {
        let s = self.steps + 1;
        let drops = self.params.drops_at(s, self.width, self.height);
        step(
            self.width,
            self.height,
            self.params.boundary == Boundary::Periodic,
            self.params.k(),
            1.0 - self.params.damping,
            &mut self.cur,
            &mut self.prev,
            &drops,
        );
        std::mem::swap(&mut self.cur, &mut self.prev);
        self.steps = s;
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The current displacement `z^n`.
    pub fn displacement(&self) -> &[f64] {
        &self.cur
    }

    /// The heights the GPU writes: `rest_level + scale·z^n`.
    pub fn heights(&self) -> Vec<f64> {
        self.cur.iter().map(|z| self.params.rest_level + self.params.scale * z).collect()
    }

    /// `Σ z^n` (the water volume above the rest level, in simulation units × texels²).
    pub fn volume(&self) -> f64 {
        self.cur.iter().sum()
    }
}
