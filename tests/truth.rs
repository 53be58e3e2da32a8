//! The brute-force ground truth (docs/accuracy.md §1): analytic checks of the f64 CPU version
//! and the GPU version against it.

mod common;

use common::rough_field;
use common::scenes::{key_light, rel_l2, scene, sky};
use hfgi::reference::truth::{lighting_sh, render_truth, TruthSettings};
use hfgi::scene::HeightField;

fn flat(w: usize, h: usize, z: f32) -> HeightField {
    HeightField::new("flat", w, h, vec![z; w * h], 16384).unwrap()
}

#[test]
fn flat_field_exact_reference_equals_the_analytic_value() {
    // A flat field sees the upper hemisphere: E = Σ_k L_k · (clamped cosine ZH rotated to +z),
    // exact for order-n lighting (only the first n bands of the clamped cosine meet it).
    let mut s = scene(flat(8, 8, 2.0));
    s.wrap = true;
    s.environment = sky(4);
    s.key_lights = vec![key_light(40.0, 30.0, 5.0, 30.0)];
    s.gi.bounces = 1;
    let n = s.gi.sh_order;
    let l = lighting_sh(&s);
    let cc = hfgi::math::zh::rotate(n, &hfgi::math::zh::clamped_cosine(n), [0.0, 0.0, 1.0]);
    let rho = [0.7f32 as f64, 0.6f32 as f64, 0.5f32 as f64]; // the scene's f32 albedo
    let expect: [f64; 3] =
        [0, 1, 2].map(|c| rho[c] / std::f64::consts::PI * l.iter().zip(&cc).map(|(a, b)| a[c] * b).sum::<f64>());
    // The SH-visibility reference shades (L ⊛ V_hemisphere) · cc like the pipeline: the
    // analytic value includes the order-n truncation of the product.
    let hemi = hfgi::math::zh::rotate(n, &hfgi::math::zh::cap(n, std::f64::consts::FRAC_PI_2), [0.0, 0.0, 1.0]);
    let tri = hfgi::math::triple::triple(n);
    let expect_sh: [f64; 3] = [0, 1, 2].map(|c| {
        let lc: Vec<f64> = l.iter().map(|v| v[c]).collect();
        let t = hfgi::math::triple::product(&tri, &lc, &hemi);
        rho[c] / std::f64::consts::PI * t.iter().zip(&cc).map(|(a, b)| a * b).sum::<f64>()
    });
    for sh_visibility in [false, true] {
        let expect = if sh_visibility { expect_sh } else { expect };
        let t = render_truth(&s, &TruthSettings { sh_visibility, ..Default::default() }, &mut |_, _| {}).unwrap();
        let err =
            t.direct.iter().flat_map(|p| (0..3).map(move |c| (p[c] - expect[c]).abs() / expect[c])).fold(0.0, f64::max);
        let ind = t.indirect.iter().flat_map(|p| p.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
        eprintln!("flat field, sh_visibility={sh_visibility}: max relative error {err:.2e}, max indirect {ind:.1e}");
        assert!(err <= 1e-6, "flat field reference off the analytic value by {err:e}");
        assert_eq!(ind, 0.0, "a flat field has no indirect light");
    }
}

#[test]
fn exact_and_sh_visibility_references_differ_by_the_truncation() {
    // On a rough field the two references differ (SH truncation of L ⊛ V and of the cosine
    // lobe): that difference is the floor the pipeline converges to (CONVENTIONS.md).
    let mut s = scene(rough_field(12, 12, 4));
    s.gi.bounces = 1;
    let fast = TruthSettings { azimuths: 64, ..Default::default() };
    let exact = render_truth(&s, &fast, &mut |_, _| {}).unwrap();
    let shv = render_truth(&s, &TruthSettings { sh_visibility: true, ..fast }, &mut |_, _| {}).unwrap();
    let as32 = |v: &[[f64; 3]]| v.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect::<Vec<_>>();
    let d = rel_l2(&as32(&shv.direct), &exact.direct);
    let i = rel_l2(&as32(&shv.indirect), &exact.indirect);
    eprintln!(
        "12² rough field: SH-visibility vs exact reference: direct {:.2}%, indirect {:.2}%",
        d * 100.0,
        i * 100.0
    );
    assert!(d > 1e-4 && d < 0.5, "{d}");
    assert!(exact.indirect.iter().any(|p| p[0] > 0.0));
}

#[test]
fn gpu_reference_matches_the_cpu_reference() {
    let ctx = common::gpu();
    let mut s = scene(rough_field(20, 16, 8));
    s.gi.bounces = 2;
    s.material.albedo = hfgi::scene::model::Albedo::Constant([0.8, 0.7, 0.6]);
    for sh_visibility in [false, true] {
        let settings = TruthSettings { azimuths: 64, sh_visibility, ..Default::default() };
        let cpu = render_truth(&s, &settings, &mut |_, _| {}).unwrap();
        let mut calls = 0;
        let gpu = hfgi::frame::truth::render_truth_gpu(&ctx, &s, &settings, &mut |_, _| calls += 1).unwrap();
        let as32 = |v: &[[f64; 3]]| v.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect::<Vec<_>>();
        let (d, i, t) = (
            rel_l2(&as32(&gpu.direct), &cpu.direct),
            rel_l2(&as32(&gpu.indirect), &cpu.indirect),
            rel_l2(&as32(&gpu.total), &cpu.total),
        );
        eprintln!("sh_visibility={sh_visibility}: GPU vs CPU reference: direct {d:.2e}, indirect {i:.2e}, total {t:.2e} ({calls} progress calls)");
        assert!(d.max(i).max(t) <= 1e-4, "GPU and CPU references differ: {d:e} {i:e} {t:e}");
        assert!(calls >= 3, "progress is reported");
    }
    // The flat field on the GPU (f32): the analytic value to 1e-6.
    let mut f = scene(flat(16, 16, 1.0));
    f.wrap = true;
    f.key_lights.clear();
    f.environment = sky(4);
    let n = f.gi.sh_order;
    let l = lighting_sh(&f);
    let cc = hfgi::math::zh::rotate(n, &hfgi::math::zh::clamped_cosine(n), [0.0, 0.0, 1.0]);
    let rho = [0.7f32 as f64, 0.6f32 as f64, 0.5f32 as f64];
    let expect: [f64; 3] =
        [0, 1, 2].map(|c| rho[c] / std::f64::consts::PI * l.iter().zip(&cc).map(|(a, b)| a[c] * b).sum::<f64>());
    let g = hfgi::frame::truth::render_truth_gpu(&ctx, &f, &TruthSettings::default(), &mut |_, _| {}).unwrap();
    let err =
        g.direct.iter().flat_map(|p| (0..3).map(move |c| (p[c] - expect[c]).abs() / expect[c])).fold(0.0, f64::max);
    eprintln!("flat field on the GPU (f32 integration): max relative error {err:.2e}");
    assert!(err <= 1e-6, "GPU flat-field reference off by {err:e}");
}
