//! Azimuth sample sets and wedges (NS09 §6, eq. 18–21; docs/direct.md §4), shared by the GPU
//! host code (which folds them into per-sample matrices) and the CPU reference (which applies
//! them wedge by wedge).

use std::f64::consts::{FRAC_PI_2, PI};

use super::sh;
use super::wedge::{m_bspl, m_lin, wedge_matrix_legendre, Mat};
use crate::scene::model::{ElevationBasis, Interpolation, KeyLight};

/// One azimuthal wedge: it starts at `start`, spans `width` and reads the NLP vectors of
/// `samples` (2 for linear: j, j+1; 4 for B-spline: j−1 … j+2), already wrapped (complete
/// domain) or clamped (partial domain).
#[derive(Clone, Debug, PartialEq)]
pub struct Wedge {
    pub start: f64,
    pub width: f64,
    pub samples: Vec<usize>,
}

/// The azimuth samples of one light and the wedges between them. Every sample shares the
/// elevation window `[lo, hi]`.
#[derive(Clone, Debug, PartialEq)]
pub struct AzimuthSet {
    pub phi: Vec<f64>,
    pub lo: f64,
    pub hi: f64,
    pub wedges: Vec<Wedge>,
    /// Whether the samples cover the whole circle (m wedges) or a partial range (m − 1).
    pub complete: bool,
}

fn wedge_samples(j: usize, count: usize, complete: bool, interp: Interpolation) -> Vec<usize> {
    let offsets: &[i64] = match interp {
        Interpolation::Linear => &[0, 1],
        Interpolation::Bspline => &[-1, 0, 1, 2],
    };
    offsets
        .iter()
        .map(|o| {
            let k = j as i64 + o;
            if complete {
                k.rem_euclid(count as i64) as usize
            } else {
                k.clamp(0, count as i64 - 1) as usize
            }
        })
        .collect()
}

fn complete_set(phi0: f64, count: usize, lo: f64, hi: f64, interp: Interpolation) -> AzimuthSet {
    let dphi = 2.0 * PI / count as f64;
    let phi: Vec<f64> = (0..count).map(|j| phi0 + j as f64 * dphi).collect();
    let wedges = (0..count)
        .map(|j| Wedge { start: phi[j], width: dphi, samples: wedge_samples(j, count, true, interp) })
        .collect();
    AzimuthSet { phi, lo, hi, wedges, complete: true }
}

/// The environment: `m` samples `φ_j = 2π(j + offset)/m` and `m` wedges over the whole circle,
/// elevation window `[−π/2, π/2]`. `offset` (in wedges, `gi.azimuth_offset`) rotates the set: 0
/// is the paper's `φ_j = 2πj/m`, with rays along the grid's axes and diagonals.
pub fn environment_set(m: usize, offset: f64, interp: Interpolation) -> AzimuthSet {
    complete_set(offset * 2.0 * PI / m as f64, m, -FRAC_PI_2, FRAC_PI_2, interp)
}

/// A key light (§6): `k` samples over the light's azimuthal extent and its elevation window.
/// A cap that contains a pole gets a complete domain of `k` samples around its azimuth.
pub fn key_light_set(light: &KeyLight, k: usize, interp: Interpolation) -> AzimuthSet {
    let d = light.direction.normalize();
    let alpha = light.angular_radius;
    let e = d.z.clamp(-1.0, 1.0).asin();
    let phi_c = d.y.atan2(d.x);
    let (lo, hi) = ((e - alpha).max(-FRAC_PI_2), (e + alpha).min(FRAC_PI_2));
    if e.cos() <= alpha.sin() || k < 2 {
        return complete_set(phi_c, k.max(1), lo, hi, interp);
    }
    let beta = (alpha.sin() / e.cos()).clamp(-1.0, 1.0).asin();
    let dphi = 2.0 * beta / (k - 1) as f64;
    let phi: Vec<f64> = (0..k).map(|j| phi_c - beta + j as f64 * dphi).collect();
    let wedges =
        (0..k - 1).map(|j| Wedge { start: phi[j], width: dphi, samples: wedge_samples(j, k, false, interp) }).collect();
    AzimuthSet { phi, lo, hi, wedges, complete: false }
}

fn matrix(n: usize, width: f64, interp: Interpolation, basis: ElevationBasis) -> Mat {
    match (basis, interp) {
        (ElevationBasis::Nlp, Interpolation::Linear) => m_lin(n, width),
        (ElevationBasis::Nlp, Interpolation::Bspline) => m_bspl(n, width),
        (ElevationBasis::Legendre, i) => wedge_matrix_legendre(n, width, i),
    }
}

/// The wedge matrix (`M_lin` or `M_bspl`, or their `legendre`-basis counterparts) of every wedge
/// of `set`, computed once per width.
pub fn wedge_matrices(n: usize, set: &AzimuthSet, interp: Interpolation, basis: ElevationBasis) -> Vec<Mat> {
    let mut cache: Vec<(f64, Mat)> = Vec::new();
    set.wedges
        .iter()
        .map(|w| match cache.iter().find(|(width, _)| *width == w.width) {
            Some((_, m)) => m.clone(),
            None => {
                let m = matrix(n, w.width, interp, basis);
                cache.push((w.width, m.clone()));
                m
            }
        })
        .collect()
}

/// `Rot_z(M · [v_samples…], start)` of one wedge (eq. 20, then eq. 21's rotation).
pub fn wedge_vector(n: usize, w: &Wedge, m: &Mat, v: &[Vec<f64>]) -> Vec<f64> {
    let stacked: Vec<f64> = w.samples.iter().flat_map(|&s| v[s].iter().copied()).collect();
    sh::rotate_z(n, &m.mul_vec(&stacked), w.start)
}

/// `V = Σ_wedges Rot_z(M · [v…], φ_start)` (eq. 21), wedge by wedge, with the matrices of
/// [`wedge_matrices`].
pub fn accumulate_with(n: usize, set: &AzimuthSet, mats: &[Mat], v: &[Vec<f64>]) -> Vec<f64> {
    let mut out = vec![0.0; n * n];
    for (w, m) in set.wedges.iter().zip(mats) {
        for (o, x) in out.iter_mut().zip(wedge_vector(n, w, m, v)) {
            *o += x;
        }
    }
    out
}

/// [`accumulate_with`] computing the wedge matrices itself.
pub fn accumulate(
    n: usize,
    set: &AzimuthSet,
    interp: Interpolation,
    basis: ElevationBasis,
    v: &[Vec<f64>],
) -> Vec<f64> {
    accumulate_with(n, set, &wedge_matrices(n, set, interp, basis), v)
}

/// The `n² × e` matrix of `Rot_z(·, α)` acting on a vector `x` that is the SH projection of
/// column block `b` (`e` values per sample): returns `R(α) · M[:, b·e .. (b+1)·e]`.
fn rotated_block(n: usize, e: usize, m: &Mat, block: usize, alpha: f64) -> Mat {
    let mut out = Mat::zeros(n * n, e);
    for c in 0..e {
        let col: Vec<f64> = (0..n * n).map(|r| m.get(r, block * e + c)).collect();
        for (r, v) in sh::rotate_z(n, &col, alpha).into_iter().enumerate() {
            out.set(r, c, v);
        }
    }
    out
}

/// Folds the wedges into one `n² × e` matrix per sample, `A_j` (`e` = the basis size,
/// [`crate::math::elevation::size`]), so that `Σ_j A_j v_j == accumulate(n, set, interp, basis, v)`
/// (docs/direct.md §4, "Folding").
pub fn fold(n: usize, set: &AzimuthSet, interp: Interpolation, basis: ElevationBasis) -> Vec<Mat> {
    let e = super::elevation::size(basis, n);
    let mut a: Vec<Mat> = (0..set.phi.len()).map(|_| Mat::zeros(n * n, e)).collect();
    for (w, m) in set.wedges.iter().zip(wedge_matrices(n, set, interp, basis)) {
        for (block, &s) in w.samples.iter().enumerate() {
            let r = rotated_block(n, e, &m, block, w.start);
            for (dst, src) in a[s].data.iter_mut().zip(&r.data) {
                *dst += src;
            }
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn vectors(e: usize, count: usize) -> Vec<Vec<f64>> {
        (0..count).map(|j| (0..e).map(|l| ((j * 7 + l * 3) as f64 * 0.37).sin()).collect()).collect()
    }

    #[test]
    fn fold_equals_wedge_by_wedge() {
        let lights = [
            KeyLight { direction: DVec3::new(0.6, 0.3, 0.5), angular_radius: 0.1, radiance: [1.0; 3] },
            KeyLight { direction: DVec3::new(0.0, 0.1, 1.0), angular_radius: 0.3, radiance: [1.0; 3] },
        ];
        for n in [3, 4, 6] {
            for interp in [Interpolation::Linear, Interpolation::Bspline] {
                let mut sets = vec![environment_set(8, 0.0, interp), environment_set(32, 0.0, interp)];
                sets.extend(lights.iter().map(|l| key_light_set(l, 3, interp)));
                sets.push(key_light_set(&lights[0], 5, interp));
                for (set, basis) in sets.iter().flat_map(|s| [(s, ElevationBasis::Nlp), (s, ElevationBasis::Legendre)])
                {
                    let v = vectors(crate::math::elevation::size(basis, n), set.phi.len());
                    let want = accumulate(n, set, interp, basis, &v);
                    let a = fold(n, set, interp, basis);
                    let mut got = vec![0.0; n * n];
                    for (aj, vj) in a.iter().zip(&v) {
                        for (g, x) in got.iter_mut().zip(aj.mul_vec(vj)) {
                            *g += x;
                        }
                    }
                    let err = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                    assert!(err < 1e-12, "n={n} {interp} complete={}: {err:e}", set.complete);
                }
            }
        }
    }

    /// The `legendre` elevation basis gives the exact SH projection of azimuthally blended
    /// visibility (checked against a brute-force quadrature over the sphere with `sh::eval`);
    /// the NLP basis does not (its floor is printed).
    #[test]
    fn legendre_basis_projects_exactly() {
        use crate::math::quadrature::gauss_legendre_on;
        let n = 4;
        // The paper's set and one rotated by half a wedge (gi.azimuth_offset): the z-rotations
        // follow the samples wherever they are.
        for (interp, offset) in
            [Interpolation::Linear, Interpolation::Bspline].into_iter().flat_map(|i| [(i, 0.0), (i, 0.5)])
        {
            let set = environment_set(8, offset, interp);
            assert!((set.phi[0] - offset * PI / 4.0).abs() < 1e-15 && (set.wedges[0].start - set.phi[0]).abs() < 1e-15);
            let horizon: Vec<f64> = (0..8).map(|j| 0.9 * ((j * 5) as f64 * 0.7).sin() - 0.1).collect();
            let brute = {
                let mut v = vec![0.0; n * n];
                for w in &set.wedges {
                    let (phs, pws) = gauss_legendre_on(0.0, w.width, 24);
                    for (&ph, &pw) in phs.iter().zip(&pws) {
                        let a = ph / w.width;
                        let beta: Vec<f64> = match interp {
                            Interpolation::Linear => vec![1.0 - a, a],
                            Interpolation::Bspline => crate::math::bspline::weights(a).to_vec(),
                        };
                        for (b, &s) in w.samples.iter().enumerate() {
                            let (ws, wws) = gauss_legendre_on(horizon[s], FRAC_PI_2, 24);
                            for (&om, &ow) in ws.iter().zip(&wws) {
                                let phi = w.start + ph;
                                let d = [om.cos() * phi.cos(), om.cos() * phi.sin(), om.sin()];
                                for (o, y) in v.iter_mut().zip(sh::eval(n, d)) {
                                    *o += pw * ow * om.cos() * beta[b] * y;
                                }
                            }
                        }
                    }
                }
                v
            };
            let err = |basis| {
                let v: Vec<Vec<f64>> =
                    horizon.iter().map(|&h| crate::math::elevation::interval(basis, n, h, FRAC_PI_2)).collect();
                let got = accumulate(n, &set, interp, basis, &v);
                got.iter().zip(&brute).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
            };
            let (exact, paper) = (err(ElevationBasis::Legendre), err(ElevationBasis::Nlp));
            eprintln!("{interp}, offset {offset}: max |V − brute force|: legendre {exact:.1e}, nlp {paper:.1e}");
            assert!(exact < 1e-11, "{interp}, offset {offset}: legendre basis off by {exact:e}");
            assert!(paper > 1e-4, "{interp}, offset {offset}: the NLP floor should be visible here ({paper:e})");
        }
    }

    #[test]
    fn key_light_sets_cover_the_cap() {
        let l = KeyLight { direction: DVec3::new(1.0, 0.0, 1.0).normalize(), angular_radius: 0.1, radiance: [1.0; 3] };
        let s = key_light_set(&l, 3, Interpolation::Linear);
        assert!(!s.complete && s.wedges.len() == 2);
        let beta = (0.1f64.sin() / (PI / 4.0).cos()).asin();
        assert!((s.phi[0] + beta).abs() < 1e-12 && (s.phi[2] - beta).abs() < 1e-12);
        assert!((s.lo - (PI / 4.0 - 0.1)).abs() < 1e-12 && (s.hi - (PI / 4.0 + 0.1)).abs() < 1e-12);
        let pole = KeyLight { direction: DVec3::Z, angular_radius: 0.2, radiance: [1.0; 3] };
        let s = key_light_set(&pole, 3, Interpolation::Linear);
        assert!(s.complete && s.wedges.len() == 3 && (s.hi - FRAC_PI_2).abs() < 1e-12);
    }
}
