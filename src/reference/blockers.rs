//! f64 twin of stage `visibility.blockers` (docs/blockers.md; GPU:
//! `glsl/visibility/blockers.comp.glsl`) and of the shading's product with it.
//!
//! Per receiver of the working grid (level-0 position `q`, world `P = (q·s, f(q))` on the
//! bilinear surface): `f = Σ_spheres log ε · [r/d] · Rot(cap ZH of asin(r/d), (c − P)/d)`
//! ([`sphere_log_vis`]; the constant `log ε` for a receiver inside a sphere; a sphere wholly
//! below the tangent plane of the nearest texel's normal is culled), then `V_s = exp*(f)` by
//! quadrature ([`SphereQuadrature::pipeline`]) or the optimal linear method; in primal mode
//! `V_s = ⊛_i (1 − cap_i)` instead ([`primal`]). In `log_field` mode also
//! `V_env' = exp*(f + log ε·(1 − V_env))`. The shading: `T ← T ⊛ V_s`, in log mode with the
//! environment set's `L ⊛ V_env'` added after the product instead of inside it.

use glam::DVec3;

use super::pyramid::rescale;
use crate::math::shexp::{
    exp_optimal_linear, exp_quadrature, sphere_culled, sphere_log_vis, SphereQuadrature, SQRT_4PI,
};
use crate::math::triple::{self, Triple};
use crate::math::zh;
use crate::scene::model::{BlockerExp, BlockerLogCap, BlockerShading, Scene};

/// The blockers' visibility at every receiver (receiver-grid order): `V_s`, and in log mode
/// the environment's combined vector (`env` = the environment set's `V` per receiver).
pub struct BlockerVisibility {
    pub spheres: Vec<Vec<f64>>,
    pub environment: Option<Vec<Vec<f64>>>,
    /// `log_brdf`: the environment's diffuse transfer `exp*(f_hf + Σ f_i + f_ρ(N))`.
    pub transfer: Option<Vec<Vec<f64>>>,
    /// `log_brdf`: its glossy transfer `exp*(f_hf + Σ f_i + f_φ(R))` (log-SH Phong lobe about
    /// the reflected view vector, eq. 27).
    pub glossy: Option<Vec<Vec<f64>>>,
}

/// A log mode applies (`log_field` or `log_brdf`; it needs the environment set, the first set).
pub fn log_mode(scene: &Scene) -> bool {
    matches!(scene.gi.blocker_shading, BlockerShading::LogField | BlockerShading::LogBrdf)
        && crate::rules::lighting::has_environment(scene)
}

/// `Σ_spheres f_i` (seed 001's `ε` log-ZH or the matched one, `gi.blocker_log_cap`) at the receiver at level-0 position `q` with normal `nrm` (the nearest
/// texel's).
pub fn log_visibility(scene: &Scene, q: [f64; 2], nrm: [f64; 3]) -> Vec<f64> {
    let n = scene.gi.sh_order;
    let s = scene.texel_size;
    let p = DVec3::new(q[0] * s, q[1] * s, scene.field.bilinear(q[0], q[1]));
    let log_eps = scene.gi.blocker_epsilon.ln();
    let mut f = vec![0.0; n * n];
    for b in &scene.spheres {
        let c = (b.center - p).to_array();
        if (b.center - p).length() > b.radius && sphere_culled(nrm, c, b.radius) {
            continue;
        }
        let v = match scene.gi.blocker_log_cap {
            BlockerLogCap::Epsilon => sphere_log_vis(n, c, b.radius, log_eps, scene.gi.blocker_ratio),
            BlockerLogCap::Matched => crate::math::logcap::matched_log_vis(n, c, b.radius),
        };
        if let Some(v) = v {
            f.iter_mut().zip(&v).for_each(|(a, b)| *a += b);
        }
    }
    f
}

/// Primal space: `⊛_i (1 − cap_i)` over the spheres not culled at the receiver at level-0
/// position `q` (normal `nrm`), each product truncated to order n; 0 inside a sphere.
pub fn primal(scene: &Scene, tri: &Triple, q: [f64; 2], nrm: [f64; 3]) -> Vec<f64> {
    let n = scene.gi.sh_order;
    let s = scene.texel_size;
    let p = DVec3::new(q[0] * s, q[1] * s, scene.field.bilinear(q[0], q[1]));
    let mut v = vec![0.0; n * n];
    v[0] = SQRT_4PI;
    for b in &scene.spheres {
        let c = b.center - p;
        let d = c.length();
        if d <= b.radius {
            return vec![0.0; n * n];
        }
        if sphere_culled(nrm, c.to_array(), b.radius) {
            continue;
        }
        let mut open: Vec<f64> = zh::rotate(n, &zh::cap(n, (b.radius / d).asin()), (c / d).to_array());
        open.iter_mut().for_each(|x| *x = -*x);
        open[0] += SQRT_4PI;
        v = triple::product(tri, &v, &open);
    }
    v
}

/// `exp*(f)` by the scene's method.
pub fn exponentiate(scene: &Scene, q: &SphereQuadrature, f: &[f64]) -> Vec<f64> {
    match scene.gi.blocker_exp {
        BlockerExp::Quadrature => exp_quadrature(q, f),
        BlockerExp::Linear => exp_optimal_linear(scene.gi.sh_order, f),
    }
}

/// [`BlockerVisibility`] of every receiver of the `work` grid; `env`: the environment set's
/// visibility per receiver (used in log mode). `normals`: the full-resolution normals.
pub fn blocker_visibility(
    scene: &Scene,
    work: (usize, usize),
    normals: &[[f64; 3]],
    env: Option<&[Vec<f64>]>,
) -> BlockerVisibility {
    let n = scene.gi.sh_order;
    let (w, h) = (scene.field.width(), scene.field.height());
    let quad = SphereQuadrature::pipeline(n);
    let tri = triple::triple(n);
    let log = log_mode(scene);
    let log_eps = scene.gi.blocker_epsilon.ln();
    let mut spheres = Vec::with_capacity(work.0 * work.1);
    let mut environment = log.then(|| Vec::with_capacity(work.0 * work.1));
    let brdf = (log && scene.gi.blocker_shading == BlockerShading::LogBrdf)
        .then(|| crate::math::shexp::log_diffuse_zh(n, crate::scene::model::LOG_BRDF_EPSILON));
    let mut transfer = brdf.as_ref().map(|_| Vec::with_capacity(work.0 * work.1));
    let phong = brdf.as_ref().map(|_| {
        let e = f64::from(scene.material.exponent);
        crate::math::shexp::log_phong_zh(n, e, crate::scene::model::LOG_BRDF_EPSILON)
    });
    let mut glossy = brdf.as_ref().map(|_| Vec::with_capacity(work.0 * work.1));
    for r in 0..work.0 * work.1 {
        let q = [rescale((r % work.0) as f64, work.0, w), rescale((r / work.0) as f64, work.1, h)];
        let (ix, iy) =
            ((q[0] + 0.5).floor().clamp(0.0, (w - 1) as f64), (q[1] + 0.5).floor().clamp(0.0, (h - 1) as f64));
        let nrm = normals[iy as usize * w + ix as usize];
        if scene.gi.blocker_shading == BlockerShading::Primal {
            spheres.push(primal(scene, tri, q, nrm));
            continue;
        }
        let mut f = log_visibility(scene, q, nrm);
        spheres.push(exponentiate(scene, &quad, &f));
        if let (Some(out), Some(env)) = (environment.as_mut(), env) {
            f.iter_mut().zip(&env[r]).for_each(|(a, v)| *a -= log_eps * v);
            f[0] += log_eps * SQRT_4PI;
            out.push(exponentiate(scene, &quad, &f));
            if let (Some(t), Some(z), Some(g), Some(zp)) =
                (transfer.as_mut(), brdf.as_ref(), glossy.as_mut(), phong.as_ref())
            {
                let mut fd = f.clone();
                fd.iter_mut().zip(zh::rotate(n, z, nrm)).for_each(|(a, b)| *a += b);
                t.push(exponentiate(scene, &quad, &fd));
                let r = reflected_view(scene, q, nrm);
                f.iter_mut().zip(zh::rotate(n, zp, r)).for_each(|(a, b)| *a += b);
                g.push(exponentiate(scene, &quad, &f));
            }
        }
    }
    BlockerVisibility { spheres, environment, transfer, glossy }
}

/// The reflected view vector `R = 2(N·ω_o)N − ω_o` at the receiver at level-0 position `q`
/// (on the bilinear surface) with normal `nrm`, `ω_o` toward the scene camera.
fn reflected_view(scene: &Scene, q: [f64; 2], nrm: [f64; 3]) -> [f64; 3] {
    let s = scene.texel_size;
    let p = DVec3::new(q[0] * s, q[1] * s, scene.field.bilinear(q[0], q[1]));
    let wo = (scene.camera.position - p).normalize();
    let nv = DVec3::from_array(nrm).normalize();
    (2.0 * nv.dot(wo) * nv - wo).normalize().to_array()
}

/// `t ⊛ v` per RGB channel (truncated to order n), `t` RGB SH, `v` scalar SH.
pub fn times(tri: &Triple, t: &[[f64; 3]], v: &[f64]) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; t.len()];
    for ch in 0..3 {
        let a: Vec<f64> = t.iter().map(|c| c[ch]).collect();
        for (k, val) in triple::product(tri, &a, v).into_iter().enumerate() {
            out[k][ch] = val;
        }
    }
    out
}
