//! Small scenes built in code for the GPU-vs-CPU tests (no scene files involved).
#![allow(dead_code)]

use glam::DVec3;
use hfgi::math::sh;
use hfgi::scene::model::{Albedo, Camera, Environment, GiSettings, KeyLight, Material, Scene};
use hfgi::scene::HeightField;

/// A sky-like order-4 environment: brighter above, a tilt toward +x, some higher bands.
pub fn sky(n: usize) -> Environment {
    let f = |d: [f64; 3]| {
        let up = d[2].max(0.0);
        0.3 + 0.9 * up + 0.4 * (d[0] * 0.6 + d[1] * 0.2).max(0.0) + 0.2 * (3.0 * d[2] * d[2] - 1.0) * d[0]
    };
    let c = sh::project(n, f, 24);
    Environment { sh: c.iter().map(|v| [*v, v * 0.95, v * 1.1]).collect() }
}

/// Constant radiance `l` everywhere.
pub fn uniform(l: f64) -> Environment {
    Environment { sh: vec![[l * (4.0 * std::f64::consts::PI).sqrt(); 3]] }
}

pub fn key_light(elev_deg: f64, azim_deg: f64, radius_deg: f64, radiance: f64) -> KeyLight {
    let (e, a) = (elev_deg.to_radians(), azim_deg.to_radians());
    KeyLight {
        direction: DVec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin()),
        angular_radius: radius_deg.to_radians(),
        radiance: [radiance, radiance * 0.9, radiance * 0.8],
    }
}

/// A scene over `field` with the sky, one key light and default settings but f32 storage.
pub fn scene(field: HeightField) -> Scene {
    let (lo, hi) = field.range();
    let camera = Camera::default_for(field.width(), field.height(), 1.0, lo as f64, hi as f64);
    Scene {
        field,
        texel_size: 1.0,
        wrap: false,
        material: Material { albedo: Albedo::Constant([0.7, 0.6, 0.5]), specular: None, exponent: 32.0 },
        environment: sky(8),
        key_lights: vec![key_light(30.0, 200.0, 5.0, 4.0)],
        local_lights: vec![],
        spheres: vec![],
        // f32 storage and f32 shading planes: the tests that use this scene compare the GPU with
        // the f64 twin or with analytic values at tolerances below a half's rounding (2⁻¹¹); the
        // default f16 storage and the RGBE planes are tested against f32 and the exact reference
        // in tests/storage.rs.
        gi: GiSettings {
            storage: hfgi::scene::model::Storage::F32,
            shading_storage: hfgi::scene::model::ShadingStorage::F32,
            ..GiSettings::default()
        },
        camera,
        animation: Default::default(),
    }
}

/// Relative L2 error ‖x − r‖ / ‖r‖ over all texels and channels, in f64 (CONVENTIONS.md).
pub fn rel_l2(x: &[[f32; 3]], r: &[[f64; 3]]) -> f64 {
    assert_eq!(x.len(), r.len());
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in x.iter().zip(r) {
        for c in 0..3 {
            num += (a[c] as f64 - b[c]).powi(2);
            den += b[c] * b[c];
        }
    }
    if den == 0.0 {
        num.sqrt()
    } else {
        (num / den).sqrt()
    }
}

/// Each accuracy fix of docs/accuracy.md §4 alone on `paper` (the paper's settings), labelled.
pub fn single_fixes(
    paper: &hfgi::scene::model::GiSettings,
    near: u32,
) -> Vec<(String, hfgi::scene::model::GiSettings)> {
    use hfgi::scene::model::{ElevationBasis, Horizon, Level0, OmegaMin, ScanReach};
    let with = |f: &dyn Fn(&mut hfgi::scene::model::GiSettings)| {
        let mut g = paper.clone();
        f(&mut g);
        g
    };
    vec![
        ("level0=bilinear".into(), with(&|g| g.level0 = Level0::Bilinear)),
        ("horizon=samples".into(), with(&|g| g.horizon = Horizon::Samples)),
        (format!("near_steps={near}"), with(&|g| g.near_steps = near)),
        ("scan_reach=diagonal".into(), with(&|g| g.scan_reach = ScanReach::Diagonal)),
        ("omega_min=tangent".into(), with(&|g| g.omega_min = OmegaMin::Tangent)),
        ("elevation_basis=legendre".into(), with(&|g| g.elevation_basis = ElevationBasis::Legendre)),
    ]
}

/// `∫ lobe(ω·R) dω` over the upper hemisphere's directions `ω` for which `keep(ω)` holds, with
/// the normalised Phong lobe `(S+1)/(2π) max(cos, 0)^S` about `refl`: brute force, `nz`
/// Gauss–Legendre nodes in `cos θ` × `nphi` azimuths (independent of the pipeline's SH and
/// slices; the glossy checks of tests/blockers.rs and tests/local_lights.rs).
pub fn lobe_integral(refl: glam::DVec3, s: f64, nz: usize, nphi: usize, keep: impl Fn(glam::DVec3) -> bool) -> f64 {
    let (z, w) = hfgi::math::quadrature::gauss_legendre_on(0.0, 1.0, nz);
    let tau = std::f64::consts::TAU;
    let mut sum = 0.0;
    for (ct, wt) in z.iter().zip(&w) {
        let st = (1.0 - ct * ct).sqrt();
        for k in 0..nphi {
            let phi = (k as f64 + 0.5) * tau / nphi as f64;
            let d = glam::DVec3::new(st * phi.cos(), st * phi.sin(), *ct);
            if keep(d) {
                sum += wt * tau / nphi as f64 * (s + 1.0) / tau * d.dot(refl).max(0.0).powf(s);
            }
        }
    }
    sum
}

/// True when the ray from `p` along unit `d` meets the sphere of centre `c` and radius `r`
/// ahead of `p`.
pub fn hits_sphere(p: glam::DVec3, d: glam::DVec3, c: glam::DVec3, r: f64) -> bool {
    let oc = c - p;
    let along = oc.dot(d);
    along > 0.0 && (oc - along * d).length() < r
}
