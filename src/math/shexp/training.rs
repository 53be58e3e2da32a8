//! The OL tables' training set and least-squares fit (Ren et al. 2006 §4; [`super`]).

use super::{dc_isolate, norm, sphere_log_vis, SphereQuadrature, OL_POINTS, OL_STEP, OL_TRAINING, SQRT_4PI};
use std::f64::consts::PI;

/// splitmix64: a tiny deterministic generator for the OL training set and the tests.
pub(super) struct SplitMix(pub(super) u64);

impl SplitMix {
    pub(super) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub(super) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform on the unit sphere.
    pub(super) fn dir(&mut self) -> [f64; 3] {
        let z = 2.0 * self.uniform() - 1.0;
        let phi = 2.0 * PI * self.uniform();
        let s = (1.0 - z * z).max(0.0).sqrt();
        [s * phi.cos(), s * phi.sin(), z]
    }
}

/// One blocker of a training configuration: centre relative to the receiver, radius, and
/// whether [`sphere_log_vis`] applies ratio attenuation.
#[derive(Clone, Copy, Debug)]
pub struct TrainingSphere {
    pub center: [f64; 3],
    pub radius: f64,
    pub ratio_attenuation: bool,
}

/// The blocker configurations behind the OL tables (order independent; `count` of them from a
/// fixed splitmix64 seed; the first [`OL_TRAINING`] are the training set, later ones are
/// fresh). Configuration `i`: a receiver normal uniform on the sphere; `k ∈ 1..=6` spheres
/// (uniform) with centres at unit distance, directions uniform in the hemisphere about the
/// normal, radius `r = r/d` uniform in `[0.1, 0.9]`; ratio attenuation on odd `i`.
pub fn ol_training_configs(count: usize) -> Vec<Vec<TrainingSphere>> {
    let mut rng = SplitMix(0x5EED_0E4B_2006);
    (0..count)
        .map(|i| {
            let axis = rng.dir();
            let k = 1 + (rng.next_u64() % 6) as usize;
            (0..k)
                .map(|_| {
                    let mut d = rng.dir();
                    let dot = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
                    if dot < 0.0 {
                        d = [0, 1, 2].map(|j| d[j] - 2.0 * dot * axis[j]);
                    }
                    let radius = 0.1 + 0.8 * rng.uniform();
                    TrainingSphere { center: d, radius, ratio_attenuation: i % 2 == 1 }
                })
                .collect()
        })
        .collect()
}

/// Summed log-SH visibility `Σ_i sphere_log_vis(n, c_i, r_i, log_eps, ratio_i)` of a set of
/// blockers seen from the origin (blockers that give `None` add nothing).
pub fn spheres_log_vis(n: usize, spheres: &[TrainingSphere], log_eps: f64) -> Vec<f64> {
    let mut f = vec![0.0; n * n];
    for s in spheres {
        if let Some(v) = sphere_log_vis(n, s.center, s.radius, log_eps, s.ratio_attenuation) {
            for (a, b) in f.iter_mut().zip(v) {
                *a += b;
            }
        }
    }
    f
}

/// The OL training directions for order `n`: for each of the first [`OL_TRAINING`]
/// configurations of [`ol_training_configs`], the summed log-visibility (any `ln ε < 0`: the
/// direction does not depend on it), DC removed, normalised to `‖u‖ = 1`.
pub fn ol_training_set(n: usize) -> Vec<Vec<f64>> {
    ol_training_configs(OL_TRAINING)
        .iter()
        .map(|cfg| {
            let (_, u) = dc_isolate(n, &spheres_log_vis(n, cfg, -1.0));
            let s = norm(&u);
            u.iter().map(|v| v / s).collect()
        })
        .collect()
}

/// Re-derives the OL tables of order `n` (`2 ≤ n ≤ 16`): `(a(x_i), b(x_i))` at
/// `x_i = i·OL_STEP`, `i < OL_POINTS`.
///
/// For each `x`, `a` and `b` minimise the summed squared error over the training directions
/// `u` of [`ol_training_set`] scaled to `‖f̂‖ = x`:
///
/// `min_{a,b} Σ_u ‖exp*(x u) − a·1 − b·x u‖²`.
///
/// `⟨1, u⟩ = 0`, `‖1‖² = 4π` and `‖x u‖² = x²`, so the normal equations decouple:
///
/// `a(x) = (1/M) Σ_u exp*(x u)_0 / √(4π)`,  `b(x) = (1/(M x)) Σ_u ⟨exp*(x u), u⟩`,  `b(0) = 1`,
///
/// with `M` = [`OL_TRAINING`] and `exp*` by [`exp_quadrature`](super::exp_quadrature) with [`SphereQuadrature::new`].
///
/// # Panics
/// If `n ∉ 2..=16` (programmer error).
pub fn ol_fit_table(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 2, "ol_fit_table: order 1 has no f̂");
    let fit = OlFit::new(n);
    (0..OL_POINTS).map(|i| fit.at(i as f64 * OL_STEP)).unzip()
}

/// The least-squares OL fit of [`ol_fit_table`] at any `x` (the training directions evaluated
/// at the quadrature nodes once).
pub(super) struct OlFit {
    q: SphereQuadrature,
    dirs: Vec<Vec<f64>>,
    at_nodes: Vec<Vec<f64>>,
}

impl OlFit {
    pub(super) fn new(n: usize) -> Self {
        let q = SphereQuadrature::new(n);
        let dirs = ol_training_set(n);
        let at_nodes = dirs.iter().map(|u| q.eval(u)).collect();
        Self { q, dirs, at_nodes }
    }

    pub(super) fn at(&self, x: f64) -> (f64, f64) {
        let (mut sa, mut sb) = (0.0, 0.0);
        for (u_nodes, u) in self.at_nodes.iter().zip(&self.dirs) {
            let v: Vec<f64> = u_nodes.iter().map(|u| (x * u).exp()).collect();
            let e = self.q.project(&v);
            sa += e[0] / SQRT_4PI;
            sb += e.iter().zip(u).map(|(e, u)| e * u).sum::<f64>();
        }
        let m = self.dirs.len() as f64;
        (sa / m, if x == 0.0 { 1.0 } else { sb / (m * x) })
    }
}
