//! f64 twin of stage `shade.local_lights` (docs/local-lights.md; GPU:
//! `glsl/shade/local.comp.glsl`): the diffuse exit radiance of the local spherical lights at
//! every texel, which the pipeline adds to the direct layer.
//!
//! Per texel `p` (world `P = (x·s, y·s, H)`) and light (centre `c`, radius `r`, radiance `L`):
//! `C = c − P`, `d = ‖C‖`, the cap toward `l = C/d` of `sin α = r/d` (`sin α = 1` inside the
//! sphere: the limit at `d = r`). Its azimuth samples are those of the exact reference's caps
//! ([`cap_azimuths_toward`], `gi.local_light_azimuths` of them); on each, the cap's elevation
//! window ([`cap_window`]) ∩ `[max(ω_hor, ω_t), π/2]`, with `ω_t` the tangent elevation and
//! `ω_hor` the exact horizon of the bilinear surface marched up to the planar distance where
//! the window's central ray enters the sphere (nothing behind that point can hide the light;
//! SN08 eq. 4.24; the horizon may be below zero, eq. 4.23), and `∫ (N·ω) cos ω dω` over it in
//! closed form. `E = Σ_k w_k · slice_k`, exit radiance `ρ/π · L · E`.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use super::cap::{cap_azimuths_toward, cap_window};
use super::sweep::near_slope_on;
use crate::scene::model::{Albedo, LocalLight, Scene};

/// `∫_a^b (N·ω) cos ω dω` on the half-plane of azimuth direction `d`, `h = N·(d, 0)`.
pub fn slice(h: f64, nz: f64, a: f64, b: f64) -> f64 {
    let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
    0.5 * h * ((b - a) + sb * cb - sa * ca) + 0.5 * nz * (sb * sb - sa * sa)
}

/// `∫_a^b lobe(u(ω)·R) cos ω dω` on the half-plane of azimuth direction `d`, the normalised
/// Phong lobe `(S+1)/(2π) max(cos, 0)^S`, by [`crate::constants::LOCAL_GLOSSY_NODES`]
/// Gauss–Legendre nodes (as the shader).
pub fn glossy_slice(d: [f64; 2], refl: DVec3, s: f64, a: f64, b: f64) -> f64 {
    let (x, w) = crate::math::quadrature::gauss_legendre(crate::constants::LOCAL_GLOSSY_NODES as usize);
    let (hw, mid) = (0.5 * (b - a), 0.5 * (a + b));
    let g: f64 = x
        .iter()
        .zip(&w)
        .map(|(x, w)| {
            let om = mid + hw * x;
            let u = DVec3::new(om.cos() * d[0], om.cos() * d[1], om.sin());
            w * u.dot(refl).max(0.0).powf(s) * om.cos()
        })
        .sum();
    hw * g * (s + 1.0) / (2.0 * PI)
}

/// `E / L` of one light at texel `(x, y)` with normal `nrm`: the cosine-weighted solid angle
/// of the part of its cap that the height field leaves open (see the module docs).
pub fn light_irradiance(scene: &Scene, x: usize, y: usize, nrm: [f64; 3], light: &LocalLight) -> f64 {
    light_terms(scene, x, y, nrm, light, None).0
}

/// `(E, G) / L` of one light: [`light_irradiance`] and, with `lobe = (R, S)`, the Phong lobe
/// about `R` integrated over the same visible windows ([`glossy_slice`]).
pub fn light_terms(
    scene: &Scene,
    x: usize,
    y: usize,
    nrm: [f64; 3],
    light: &LocalLight,
    lobe: Option<(DVec3, f64)>,
) -> (f64, f64) {
    let field = &scene.field;
    let s = scene.texel_size;
    let p = DVec3::new(x as f64 * s, y as f64 * s, f64::from(field.get(x, y)));
    let c = light.position - p;
    let (d, r) = (c.length(), light.radius);
    let inside = d <= r;
    let sin_a = if inside { 1.0 } else { r / d };
    let cos_a = if inside { 0.0 } else { ((d - r) * (d + r)).sqrt() / d };
    let l = c / d;
    let n = [field.width() as f64, field.height() as f64];
    let (mut e, mut g) = (0.0, 0.0);
    for (phi, w) in cap_azimuths_toward(l, sin_a, scene.gi.local_light_azimuths, scene.gi.local_light_azimuths) {
        let dir = [phi.cos(), phi.sin()];
        let Some((lo, hi)) = cap_window(dir, l.to_array(), sin_a, cos_a) else { continue };
        let h = nrm[0] * dir[0] + nrm[1] * dir[1];
        let mut a = lo.max((-h).atan2(nrm[2])).max(-FRAC_PI_2);
        let b = hi.min(FRAC_PI_2);
        if b <= a {
            continue;
        }
        // Where the slice's central ray enters the sphere, in planar texels (0 inside it).
        let wc = 0.5 * (lo + b);
        let u = DVec3::new(wc.cos() * dir[0], wc.cos() * dir[1], wc.sin());
        let bc = u.dot(c);
        let t = if inside { 0.0 } else { bc - (bc * bc - (d - r) * (d + r)).max(0.0).sqrt() };
        let reach = t.max(0.0) * wc.cos() / s;
        if reach > 0.0 {
            let height = |qx: f64, qy: f64| field.bilinear(qx, qy);
            if let Some(best) = near_slope_on(n, [x as f64, y as f64], dir, reach, height) {
                a = a.max((best / s).atan());
            }
        }
        if b > a {
            e += w * slice(h, nrm[2], a, b);
            if let Some((r, s)) = lobe {
                g += w * glossy_slice(dir, r, s, a, b);
            }
        }
    }
    (e, g)
}

/// The local lights' glossy exit radiance `k_s ⊙ Σ L·G` per texel (row-major; zero without a
/// Phong lobe), what `shade.local_lights` adds to the glossy layer: the lobe about the
/// reflected view vector (toward the scene camera, as docs/direct.md §6).
pub fn local_glossy(scene: &Scene, normals: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let (w, h) = (scene.field.width(), scene.field.height());
    let mut out = vec![[0.0; 3]; w * h];
    let Some(ks) = scene.material.specular.filter(|_| !scene.local_lights.is_empty()) else { return out };
    let s = f64::from(scene.material.exponent);
    for y in 0..h {
        for x in 0..w {
            let nrm = normals[y * w + x];
            let t = scene.texel_size;
            let p = DVec3::new(x as f64 * t, y as f64 * t, f64::from(scene.field.get(x, y)));
            let wo = (scene.camera.position - p).normalize();
            let nv = DVec3::from_array(nrm);
            let r = (2.0 * nv.dot(wo) * nv - wo).normalize();
            let mut g = [0.0; 3];
            for light in scene.local_lights.iter().filter(|l| l.radiance.iter().any(|v| *v != 0.0)) {
                let k = light_terms(scene, x, y, nrm, light, Some((r, s))).1;
                for (gc, l) in g.iter_mut().zip(&light.radiance) {
                    *gc += l * k;
                }
            }
            out[y * w + x] = [0, 1, 2].map(|ch| f64::from(ks[ch]) * g[ch]);
        }
    }
    out
}

/// The local lights' diffuse exit radiance `ρ/π · Σ L·E` per texel (row-major), what
/// `shade.local_lights` adds to the direct layer; `normals` as [`super::direct::normals`].
pub fn local_exitance(scene: &Scene, normals: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let (w, h) = (scene.field.width(), scene.field.height());
    let mut out = vec![[0.0; 3]; w * h];
    if scene.local_lights.is_empty() {
        return out;
    }
    for y in 0..h {
        for x in 0..w {
            let rho = match &scene.material.albedo {
                Albedo::Constant(a) => a.map(f64::from),
                Albedo::Map(m) => m[y * w + x].map(f64::from),
            };
            let mut e = [0.0; 3];
            for light in scene.local_lights.iter().filter(|l| l.radiance.iter().any(|v| *v != 0.0)) {
                let k = light_irradiance(scene, x, y, normals[y * w + x], light);
                for (ec, l) in e.iter_mut().zip(&light.radiance) {
                    *ec += l * k;
                }
            }
            out[y * w + x] = [0, 1, 2].map(|ch| rho[ch] / PI * e[ch]);
        }
    }
    out
}
