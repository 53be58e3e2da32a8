//! Integration tests of the f64 reference math (`hfgi::math`). Each test states its tolerance.
//! Orders n = 2..=8 wherever the quantity generalises beyond the paper's order 4.

// Index loops over bands read more clearly than iterator chains in these checks.
#![allow(clippy::needless_range_loop)]

use hfgi::math::quadrature::{gauss_legendre, integrate};
use hfgi::math::{legendre, nlp, sh, triple, wedge, zh};
use std::f64::consts::{FRAC_PI_2, PI};

/// Small deterministic PRNG (SplitMix64) for pseudo-random inputs.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [−1, 1).
    fn sym(&mut self) -> f64 {
        2.0 * self.next() - 1.0
    }
    fn vec(&mut self, len: usize) -> Vec<f64> {
        (0..len).map(|_| self.sym()).collect()
    }
    fn dir(&mut self) -> [f64; 3] {
        let z = self.sym();
        let phi = 2.0 * PI * self.next();
        let s = (1.0 - z * z).sqrt();
        [s * phi.cos(), s * phi.sin(), z]
    }
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

fn norm(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

// ---------------------------------------------------------------------------------------------
// 1. Bases
// ---------------------------------------------------------------------------------------------

/// Gram matrix of the SH basis by exact sphere quadrature (GL in z × uniform φ) = I, tol 1e-10
/// (n = 2..=8, 12, 16).
#[test]
fn sh_orthonormal_gram_identity() {
    for n in (2..=8).chain([12, 16]) {
        let nn = n * n;
        let (zs, wz) = gauss_legendre(n + 2);
        let nphi = 2 * n + 4;
        let mut g = vec![0.0; nn * nn];
        for (&z, &w) in zs.iter().zip(&wz) {
            let s = (1.0 - z * z).sqrt();
            for k in 0..nphi {
                let phi = 2.0 * PI * (k as f64 + 0.3) / nphi as f64;
                let y = sh::eval(n, [s * phi.cos(), s * phi.sin(), z]);
                let wt = w * 2.0 * PI / nphi as f64;
                for i in 0..nn {
                    for j in 0..nn {
                        g[i * nn + j] += wt * y[i] * y[j];
                    }
                }
            }
        }
        for i in 0..nn {
            for j in 0..nn {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((g[i * nn + j] - want).abs() < 1e-10, "n={n} G[{i}][{j}]={}", g[i * nn + j]);
            }
        }
    }
}

/// `sh::project` of a basis function returns the unit vector, tol 1e-10.
#[test]
fn sh_project_basis_functions() {
    for n in 2..=8 {
        for i in 0..n * n {
            let c = sh::project(n, |d| sh::eval(n, d)[i], n + 1);
            let mut e = vec![0.0; n * n];
            e[i] = 1.0;
            assert!(max_abs_diff(&c, &e) < 1e-10, "n={n} i={i}");
        }
    }
}

/// NLP orthonormality on [−1, 1] by Gauss–Legendre, tol 1e-10.
#[test]
fn nlp_orthonormal() {
    for n in 2..=8 {
        for i in 0..n {
            for j in 0..n {
                let g = integrate(-1.0, 1.0, n + 1, |z| legendre::nlp(i, z) * legendre::nlp(j, z));
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((g - want).abs() < 1e-10, "n={n} ({i},{j}) {g}");
            }
        }
    }
}

/// Order-4 SH equal the CONVENTIONS Cartesian table (6-digit constants), tol 1e-5, at 50
/// pseudo-random directions; higher orders start with the same values (prefix property).
#[test]
fn sh_eval_matches_conventions_table() {
    let mut rng = Rng(1);
    for _ in 0..50 {
        let [x, y, z] = rng.dir();
        let table = [
            0.282095,
            0.488603 * y,
            0.488603 * z,
            0.488603 * x,
            1.092548 * x * y,
            1.092548 * y * z,
            0.315392 * (3.0 * z * z - 1.0),
            1.092548 * x * z,
            0.546274 * (x * x - y * y),
            0.590044 * y * (3.0 * x * x - y * y),
            2.890611 * x * y * z,
            0.457046 * y * (5.0 * z * z - 1.0),
            0.373176 * z * (5.0 * z * z - 3.0),
            0.457046 * x * (5.0 * z * z - 1.0),
            1.445306 * z * (x * x - y * y),
            0.590044 * x * (x * x - 3.0 * y * y),
        ];
        let e = sh::eval(4, [x, y, z]);
        assert!(max_abs_diff(&e, &table) < 1e-5, "{e:?} vs {table:?}");
        for n in 5..=8 {
            assert!(max_abs_diff(&sh::eval(n, [x, y, z])[..16], &e) < 1e-15);
        }
    }
}

/// The Cartesian evaluation equals the CONVENTIONS angular definition built from
/// `assoc_legendre` and `K_l^m` (n = 8), tol 1e-12.
#[test]
fn sh_eval_matches_angular_definition() {
    let n = 8;
    let mut rng = Rng(2);
    for _ in 0..40 {
        let theta = PI * rng.next();
        let phi = 2.0 * PI * rng.next();
        let e = sh::eval_angles(n, theta, phi);
        for l in 0..n {
            for m in -(l as i32)..=(l as i32) {
                let ma = m.unsigned_abs() as usize;
                let mut ratio = 1.0;
                for k in (l - ma + 1)..=(l + ma) {
                    ratio /= k as f64;
                }
                let k = ((2 * l + 1) as f64 / (4.0 * PI) * ratio).sqrt();
                let p = legendre::assoc_legendre(l, ma, theta.cos());
                let want = match m {
                    0 => k * p,
                    m if m > 0 => 2f64.sqrt() * k * (m as f64 * phi).cos() * p,
                    _ => 2f64.sqrt() * k * (ma as f64 * phi).sin() * p,
                };
                let got = e[sh::index(l as i32, m)];
                assert!((got - want).abs() < 1e-12, "l={l} m={m}: {got} vs {want}");
            }
        }
    }
}

/// No Condon–Shortley phase: y_1^1 = +0.488603 x, y_1^{−1} = +0.488603 y, y_1^0 = +0.488603 z
/// (tol 1e-6), and y_l^0 = P̂_l(cosθ)/sqrt(2π) (tol 1e-14).
#[test]
fn sh_no_condon_shortley_phase() {
    let c = (3.0 / (4.0 * PI)).sqrt();
    assert!((c - 0.488603).abs() < 1e-6);
    let d = [0.6, 0.0, 0.8];
    let e = sh::eval(2, d);
    assert!((e[sh::index(1, 1)] - c * 0.6).abs() < 1e-14 && e[sh::index(1, 1)] > 0.0);
    let e = sh::eval(2, [0.0, 0.6, 0.8]);
    assert!((e[sh::index(1, -1)] - c * 0.6).abs() < 1e-14);
    assert!((e[sh::index(1, 0)] - c * 0.8).abs() < 1e-14);
    assert!(legendre::assoc_legendre(1, 1, 0.0) > 0.0);
    for l in 0..8 {
        let y = sh::eval_angles(8, 0.9, 1.3)[sh::index(l as i32, 0)];
        assert!((y - legendre::nlp(l, 0.9f64.cos()) / (2.0 * PI).sqrt()).abs() < 1e-14);
    }
}

// ---------------------------------------------------------------------------------------------
// 2. NLP occlusion (eqs. 10–13)
// ---------------------------------------------------------------------------------------------

/// The paper's order-4 closed form (after eq. 13) equals the quadrature v̄ for 401 σ in
/// [−π/2, π/2], tol 1e-12.
#[test]
fn occlusion_closed_form_matches_quadrature() {
    for i in 0..=400 {
        let sigma = -FRAC_PI_2 + PI * i as f64 / 400.0;
        let q = nlp::occlusion(4, sigma);
        let c = nlp::occlusion4_closed(sigma);
        assert!(max_abs_diff(&q, &c) < 1e-12, "σ={sigma}: {q:?} vs {c:?}");
    }
}

/// v̄(σ) for n = 2..=8 equals a high-order (64-point) direct integration of eq. 10, visibility
/// (eq. 11) and `interval` equal direct integrals over [sin lo, sin hi], tol 1e-12; `reconstruct`
/// (eq. 13) of the projection of a polynomial of degree < n returns that polynomial, tol 1e-12.
#[test]
fn occlusion_visibility_interval_definitions() {
    for n in 2..=8 {
        for i in 0..=20 {
            let sigma = -FRAC_PI_2 + PI * i as f64 / 20.0;
            let q = nlp::occlusion(n, sigma);
            let want: Vec<f64> = (0..n).map(|l| integrate(-1.0, sigma.sin(), 64, |z| legendre::nlp(l, z))).collect();
            assert!(max_abs_diff(&q, &want) < 1e-12, "n={n} σ={sigma}");
            let v = nlp::visibility(n, sigma);
            let want: Vec<f64> = (0..n).map(|l| integrate(sigma.sin(), 1.0, 64, |z| legendre::nlp(l, z))).collect();
            assert!(max_abs_diff(&v, &want) < 1e-12, "n={n} σ={sigma}");
            let (lo, hi) = (sigma, (sigma + 0.4).min(FRAC_PI_2));
            let iv = nlp::interval(n, lo, hi);
            let want: Vec<f64> = (0..n).map(|l| integrate(lo.sin(), hi.sin(), 64, |z| legendre::nlp(l, z))).collect();
            assert!(max_abs_diff(&iv, &want) < 1e-12, "n={n} [{lo},{hi}]");
        }
        // Reconstruction of a projected polynomial of degree n−1.
        let poly = |z: f64| (0..n).map(|k| (k as f64 + 1.0) * 0.1 * z.powi(k as i32)).sum::<f64>();
        let c: Vec<f64> = (0..n).map(|l| integrate(-1.0, 1.0, n + 1, |z| poly(z) * legendre::nlp(l, z))).collect();
        for i in 0..=10 {
            let z = -1.0 + 0.2 * i as f64;
            assert!((nlp::reconstruct(&c, z) - poly(z)).abs() < 1e-12);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Wedge matrices (eqs. 18–24)
// ---------------------------------------------------------------------------------------------

/// Direct SH projection over the canonical wedge [0, Δφ] of `W(θ, φ) = I(α)·P̂(cosθ)`, by 2D
/// Gauss–Legendre quadrature (θ in [0, π], φ in [0, Δφ]); `blocks[b]` is weighted by `beta(α)[b]`.
fn wedge_direct(n: usize, dphi: f64, blocks: &[Vec<f64>], beta: impl Fn(f64) -> Vec<f64>) -> Vec<f64> {
    let (ths, tws) = hfgi::math::quadrature::gauss_legendre_on(0.0, PI, 96);
    let (phs, pws) = hfgi::math::quadrature::gauss_legendre_on(0.0, dphi, 48);
    let mut out = vec![0.0; n * n];
    for (&th, &tw) in ths.iter().zip(&tws) {
        let p = legendre::nlp_vec(n, th.cos());
        for (&ph, &pw) in phs.iter().zip(&pws) {
            let b = beta(ph / dphi);
            let w: f64 = blocks.iter().zip(&b).map(|(v, bb)| bb * dot(v, &p)).sum();
            let y = sh::eval_angles(n, th, ph);
            for (o, yy) in out.iter_mut().zip(&y) {
                *o += tw * pw * th.sin() * w * yy;
            }
        }
    }
    out
}

/// M_lin·[w_j; w_{j+1}] equals the direct wedge projection, tol 1e-9, n = 2..=8,
/// Δφ ∈ {2π/32, 2π/7, π/2}.
#[test]
fn m_lin_matches_direct_projection() {
    let mut rng = Rng(3);
    for n in 2..=8 {
        for dphi in [2.0 * PI / 32.0, 2.0 * PI / 7.0, FRAC_PI_2] {
            let m = wedge::m_lin(n, dphi);
            assert_eq!((m.rows, m.cols), (n * n, 2 * n));
            let (a, b) = (rng.vec(n), rng.vec(n));
            let got = m.mul_vec(&[a.clone(), b.clone()].concat());
            let want = wedge_direct(n, dphi, &[a, b], |t| vec![1.0 - t, t]);
            let err = max_abs_diff(&got, &want);
            assert!(err < 1e-9, "n={n} Δφ={dphi} err={err}");
        }
    }
}

/// M_bspl·[w_{j−1}; w_j; w_{j+1}; w_{j+2}] equals the direct wedge projection, tol 1e-9.
#[test]
fn m_bspl_matches_direct_projection() {
    let mut rng = Rng(4);
    for n in 2..=8 {
        for dphi in [2.0 * PI / 32.0, 2.0 * PI / 7.0, FRAC_PI_2] {
            let m = wedge::m_bspl(n, dphi);
            assert_eq!((m.rows, m.cols), (n * n, 4 * n));
            let w: Vec<Vec<f64>> = (0..4).map(|_| rng.vec(n)).collect();
            let got = m.mul_vec(&w.concat());
            let want = wedge_direct(n, dphi, &w, |t| hfgi::math::bspline::weights(t).to_vec());
            let err = max_abs_diff(&got, &want);
            assert!(err < 1e-9, "n={n} Δφ={dphi} err={err}");
        }
    }
}

/// Eq. 21 with a constant-in-azimuth NLP vector v: Σ_j Rot_z(M·[v;…;v], jΔφ) over all m
/// wedges is the projection of the azimuthally symmetric v·P̂(cosθ): `√(2π)·v_l` at (l, 0) and
/// 0 elsewhere, tol 1e-9 (linear and B-spline).
#[test]
fn wedges_sum_to_azimuthally_symmetric_function() {
    let mut rng = Rng(5);
    for n in 2..=8 {
        let v = rng.vec(n);
        let mut want = vec![0.0; n * n];
        for l in 0..n {
            want[sh::index(l as i32, 0)] = (2.0 * PI).sqrt() * v[l];
        }
        for m in [32usize, 7, 4, 3] {
            let dphi = 2.0 * PI / m as f64;
            let lin = wedge::m_lin(n, dphi).mul_vec(&[v.clone(), v.clone()].concat());
            let bsp = wedge::m_bspl(n, dphi).mul_vec(&[v.clone(), v.clone(), v.clone(), v.clone()].concat());
            let mut sl = vec![0.0; n * n];
            let mut sb = vec![0.0; n * n];
            for j in 0..m {
                let a = j as f64 * dphi;
                for (s, r) in sl.iter_mut().zip(sh::rotate_z(n, &lin, a)) {
                    *s += r;
                }
                for (s, r) in sb.iter_mut().zip(sh::rotate_z(n, &bsp, a)) {
                    *s += r;
                }
            }
            assert!(max_abs_diff(&sl, &want) < 1e-9, "lin n={n} m={m}");
            assert!(max_abs_diff(&sb, &want) < 1e-9, "bspl n={n} m={m}");
        }
    }
}

/// End-to-end eq. 20–21 on the full circle with azimuth-varying samples w_0..w_{m−1}
/// (periodic): the rotated, summed wedges equal the direct sphere projection of the
/// piecewise-linear / cubic-B-spline interpolated function, wedge j spanning
/// [jΔφ, (j+1)Δφ], tol 1e-9 (checks the rotation direction and the block order).
#[test]
fn wedges_rotated_and_summed_match_full_projection() {
    let mut rng = Rng(6);
    for n in [2usize, 4, 8] {
        let m = 7usize;
        let dphi = 2.0 * PI / m as f64;
        let w: Vec<Vec<f64>> = (0..m).map(|_| rng.vec(n)).collect();
        let at = |j: i64| w[j.rem_euclid(m as i64) as usize].clone();
        let ml = wedge::m_lin(n, dphi);
        let mb = wedge::m_bspl(n, dphi);
        let mut lin = vec![0.0; n * n];
        let mut bsp = vec![0.0; n * n];
        let mut want_lin = vec![0.0; n * n];
        let mut want_bsp = vec![0.0; n * n];
        for j in 0..m as i64 {
            let phi_j = j as f64 * dphi;
            let l = ml.mul_vec(&[at(j), at(j + 1)].concat());
            let b = mb.mul_vec(&[at(j - 1), at(j), at(j + 1), at(j + 2)].concat());
            for (s, r) in lin.iter_mut().zip(sh::rotate_z(n, &l, phi_j)) {
                *s += r;
            }
            for (s, r) in bsp.iter_mut().zip(sh::rotate_z(n, &b, phi_j)) {
                *s += r;
            }
            // Direct projection of wedge j at its true position [φ_j, φ_j + Δφ].
            let (ths, tws) = hfgi::math::quadrature::gauss_legendre_on(0.0, PI, 96);
            let (phs, pws) = hfgi::math::quadrature::gauss_legendre_on(phi_j, phi_j + dphi, 48);
            for (&th, &tw) in ths.iter().zip(&tws) {
                let p = legendre::nlp_vec(n, th.cos());
                for (&ph, &pw) in phs.iter().zip(&pws) {
                    let a = (ph - phi_j) / dphi;
                    let fl = (1.0 - a) * dot(&at(j), &p) + a * dot(&at(j + 1), &p);
                    let beta = hfgi::math::bspline::weights(a);
                    let fb: f64 = (0..4).map(|k| beta[k] * dot(&at(j - 1 + k as i64), &p)).sum();
                    let y = sh::eval_angles(n, th, ph);
                    for i in 0..n * n {
                        want_lin[i] += tw * pw * th.sin() * fl * y[i];
                        want_bsp[i] += tw * pw * th.sin() * fb * y[i];
                    }
                }
            }
        }
        assert!(max_abs_diff(&lin, &want_lin) < 1e-9, "lin n={n}");
        assert!(max_abs_diff(&bsp, &want_bsp) < 1e-9, "bspl n={n}");
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Rotations
// ---------------------------------------------------------------------------------------------

/// rotate_z preserves the norm (1e-12), α then −α is the identity (1e-12), and equals the
/// projection of f(θ, φ − α) by exact quadrature (1e-10).
#[test]
fn rotate_z_properties() {
    let mut rng = Rng(7);
    for n in 2..=8 {
        let c = rng.vec(n * n);
        for alpha in [0.3, -1.7, 2.0 * PI / 7.0, 4.0] {
            let r = sh::rotate_z(n, &c, alpha);
            assert!((norm(&r) - norm(&c)).abs() < 1e-12);
            let back = sh::rotate_z(n, &r, -alpha);
            assert!(max_abs_diff(&back, &c) < 1e-12);
            let (sa, ca) = alpha.sin_cos();
            let proj = sh::project(
                n,
                |d| {
                    // f(θ, φ − α): rotate the direction by −α about z.
                    let q = [ca * d[0] + sa * d[1], -sa * d[0] + ca * d[1], d[2]];
                    sh::reconstruct(n, &c, q)
                },
                n + 1,
            );
            assert!(max_abs_diff(&proj, &r) < 1e-10, "n={n} α={alpha}");
        }
    }
}

/// A function f(d) = g(d·a) symmetric about a: sum over m of a rotated ZH.
fn zh_function(n: usize, z: &[f64], axis: [f64; 3], d: [f64; 3]) -> f64 {
    let t = dot(&axis, &d);
    (0..n).map(|l| z[l] * ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * legendre::legendre(l, t)).sum()
}

/// zh::rotate: per-band norm equals |z_l| (1e-12); equals the exact projection of the
/// smooth axially symmetric function Σ z_l y_l^0(about d) (1e-12); consistent with rotate_z.
#[test]
fn zh_rotate_properties() {
    let mut rng = Rng(8);
    for n in 2..=8 {
        let z = rng.vec(n);
        for _ in 0..5 {
            let d = rng.dir();
            let c = zh::rotate(n, &z, d);
            for l in 0..n {
                let li = l as i32;
                let band: Vec<f64> = (-li..=li).map(|m| c[sh::index(li, m)]).collect();
                assert!((norm(&band) - z[l].abs()).abs() < 1e-12, "n={n} l={l}");
            }
            let proj = sh::project(n, |q| zh_function(n, &z, d, q), n + 1);
            assert!(max_abs_diff(&proj, &c) < 1e-12, "n={n} d={d:?}");
            // The same lobe built at azimuth 0 and rotated about z by d's azimuth.
            let phi = d[1].atan2(d[0]);
            let s = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let c0 = zh::rotate(n, &z, [s, 0.0, d[2]]);
            assert!(max_abs_diff(&sh::rotate_z(n, &c0, phi), &c) < 1e-12);
        }
        // Along +z the rotation is the identity embedding: c_l^0 = z_l.
        let c = zh::rotate(n, &z, [0.0, 0.0, 1.0]);
        for l in 0..n {
            assert!((c[sh::index(l as i32, 0)] - z[l]).abs() < 1e-14);
        }
    }
}

/// zh::rotate(cap(α), d) equals the projection of the cap indicator about d, computed exactly by
/// quadrature in a frame aligned with d (GL in t = d·ω on [cos α, 1] × uniform ψ), tol 1e-12.
#[test]
fn zh_rotate_cap_matches_direct_cap_projection() {
    let mut rng = Rng(9);
    for n in 2..=8 {
        for alpha in [0.05, 0.4, 1.2, 2.5] {
            let d = rng.dir();
            let c = zh::rotate(n, &zh::cap(n, alpha), d);
            // Orthonormal frame (e1, e2, d).
            let h = if d[2].abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
            let e1 = {
                let v = [h[1] * d[2] - h[2] * d[1], h[2] * d[0] - h[0] * d[2], h[0] * d[1] - h[1] * d[0]];
                let l = norm(&v);
                [v[0] / l, v[1] / l, v[2] / l]
            };
            let e2 = [d[1] * e1[2] - d[2] * e1[1], d[2] * e1[0] - d[0] * e1[2], d[0] * e1[1] - d[1] * e1[0]];
            let (ts, wt) = hfgi::math::quadrature::gauss_legendre_on(alpha.cos(), 1.0, n + 2);
            let npsi = 2 * n + 4;
            let mut want = vec![0.0; n * n];
            for (&t, &w) in ts.iter().zip(&wt) {
                let s = (1.0 - t * t).sqrt();
                for k in 0..npsi {
                    let psi = 2.0 * PI * k as f64 / npsi as f64;
                    let (sp, cp) = psi.sin_cos();
                    let q: Vec<f64> = (0..3).map(|i| s * cp * e1[i] + s * sp * e2[i] + t * d[i]).collect();
                    let y = sh::eval(n, [q[0], q[1], q[2]]);
                    for i in 0..n * n {
                        want[i] += w * 2.0 * PI / npsi as f64 * y[i];
                    }
                }
            }
            assert!(max_abs_diff(&c, &want) < 1e-12, "n={n} α={alpha}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 5. ZH lobes
// ---------------------------------------------------------------------------------------------

/// Clamped cosine order 4 = {0.886227, 1.023327, 0.495416, 0} (1e-6) = {√π/2, √(π/3), √(5π)/8, 0}
/// (1e-14); for n = 2..=8 equals a 64-point quadrature of 2π ∫_0^1 t y_l^0 dt (1e-12); Phong
/// values e^(−l²/(2S)) (1e-15).
#[test]
fn clamped_cosine_and_phong() {
    let c = zh::clamped_cosine(4);
    for (a, b) in c.iter().zip([0.886227, 1.023327, 0.495416, 0.0]) {
        assert!((a - b).abs() < 1e-6, "{c:?}");
    }
    for (a, b) in c.iter().zip([PI.sqrt() / 2.0, (PI / 3.0).sqrt(), (5.0 * PI).sqrt() / 8.0, 0.0]) {
        assert!((a - b).abs() < 1e-14);
    }
    for n in 2..=8 {
        let c = zh::clamped_cosine(n);
        assert_eq!(c.len(), n);
        for l in 0..n {
            let want = 2.0 * PI * integrate(0.0, 1.0, 64, |t| t * legendre::nlp(l, t) / (2.0 * PI).sqrt());
            assert!((c[l] - want).abs() < 1e-12, "n={n} l={l}");
        }
        let p = zh::phong(n, 8.0);
        for l in 0..n {
            assert!((p[l] - (-((l * l) as f64) / 16.0).exp()).abs() < 1e-15);
        }
    }
    let p = zh::phong(4, 3.0);
    let want = [1.0, (-1.0 / 6.0f64).exp(), (-2.0 / 3.0f64).exp(), (-9.0 / 6.0f64).exp()];
    assert!(max_abs_diff(&p, &want) < 1e-15);
}

/// The Phong factors are the Ramamoorthi–Hanrahan attenuations A_l/A_0 of the normalised lobe
/// `(S+1)/(2π)·cos^S`: `A_l = (S+1)∫_0^1 t^S P_l(t) dt ≈ e^(−l²/(2S))`, n = 8 (the approximation
/// itself is off by about `l/(2S)`: tol 0.035 at S = 64, 0.007 at S = 512). Used as documented,
/// a constant environment of radiance 1 reflects radiance 1 (tol 1e-14).
#[test]
fn phong_factors_approximate_normalised_lobe() {
    for (s, tol) in [(64.0f64, 0.035), (512.0, 0.007)] {
        let p = zh::phong(8, s);
        for l in 0..8 {
            let a = (s + 1.0) * integrate(0.0, 1.0, 300, |t| t.powf(s) * legendre::legendre(l, t));
            assert!((a - p[l]).abs() < tol, "S={s} l={l}: {a} vs {}", p[l]);
        }
        // Rotated as a ZH after scaling by sqrt((2l+1)/(4π)), dotted with constant lighting 1.
        let z: Vec<f64> = (0..8).map(|l| p[l] * ((2 * l + 1) as f64 / (4.0 * PI)).sqrt()).collect();
        let mut light = vec![0.0; 64];
        light[0] = (4.0 * PI).sqrt();
        let r = dot(&zh::rotate(8, &z, [0.3, -0.5, 0.8]), &light);
        assert!((r - 1.0).abs() < 1e-14);
    }
}

/// Cap ZH closed form vs 64-point quadrature of 2π ∫_{cos α}^1 y_l^0 dt, tol 1e-10; the
/// l = 0 term is the cap's solid angle / sqrt(4π).
#[test]
fn cap_closed_form_matches_quadrature() {
    for n in 2..=8 {
        for alpha in [0.0, 0.01, 0.3, 1.0, FRAC_PI_2, 2.2, PI] {
            let z = zh::cap(n, alpha);
            for l in 0..n {
                let want = 2.0 * PI * integrate(alpha.cos(), 1.0, 64, |t| legendre::nlp(l, t) / (2.0 * PI).sqrt());
                assert!((z[l] - want).abs() < 1e-10, "n={n} α={alpha} l={l}");
            }
            let solid = 2.0 * PI * (1.0 - alpha.cos());
            assert!((z[0] - solid / (4.0 * PI).sqrt()).abs() < 1e-14);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 6. Triple product
// ---------------------------------------------------------------------------------------------

/// Multiplying by the constant function 1 (a = [√(4π), 0, …]) returns b, tol 1e-12.
#[test]
fn triple_product_identity() {
    let mut rng = Rng(10);
    for n in 2..=8 {
        let t = triple::triple(n);
        let mut one = vec![0.0; n * n];
        one[0] = (4.0 * PI).sqrt();
        let b = rng.vec(n * n);
        assert!(max_abs_diff(&triple::product(t, &one, &b), &b) < 1e-12, "n={n}");
        assert!(max_abs_diff(&triple::product(t, &b, &one), &b) < 1e-12, "n={n}");
    }
}

/// Γ is stored with all distinct permutations and is fully symmetric, tol 1e-14; entries are
/// above the 1e-12 threshold and sorted.
#[test]
fn triple_symmetric() {
    for n in 2..=8 {
        let t = triple::triple(n);
        for &(i, j, k, g) in &t.entries {
            assert!(g.abs() > 1e-12);
            let (i, j, k) = (i as usize, j as usize, k as usize);
            for (a, b, c) in [(i, k, j), (j, i, k), (j, k, i), (k, i, j), (k, j, i)] {
                assert!((t.get(a, b, c) - g).abs() < 1e-14, "n={n} ({i},{j},{k})");
            }
        }
        assert!(t.entries.windows(2).all(|w| (w[0].2, w[0].0, w[0].1) < (w[1].2, w[1].0, w[1].1)));
    }
}

/// product(a, b) equals the pointwise product of the two order-n functions projected to order n
/// by exact sphere quadrature, tol 1e-10; and it is commutative (1e-13).
#[test]
fn triple_product_matches_quadrature() {
    let mut rng = Rng(11);
    for n in 2..=8 {
        let t = triple::triple(n);
        let a = rng.vec(n * n);
        let b = rng.vec(n * n);
        let got = triple::product(t, &a, &b);
        let want = sh::project(n, |d| sh::reconstruct(n, &a, d) * sh::reconstruct(n, &b, d), 2 * n);
        assert!(max_abs_diff(&got, &want) < 1e-10, "n={n} err={}", max_abs_diff(&got, &want));
        assert!(max_abs_diff(&got, &triple::product(t, &b, &a)) < 1e-13);
    }
}
