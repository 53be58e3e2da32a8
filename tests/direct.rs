//! Direct illumination: GPU passes against the f64 CPU reference pipeline (same algorithm,
//! docs/direct.md), and the analytic and symmetry properties of the result.
//! Tolerance GPU vs CPU: relative L2 ≤ 1e-3 per layer.

mod common;

use common::scenes::{key_light, rel_l2, scene, sky, uniform};
use common::{gpu, render_layers, rough_field};
use hfgi::frame::Renderer;
use hfgi::reference::direct::render_direct;
use hfgi::scene::model::{Albedo, Interpolation, PyramidMode, Scene};
use hfgi::scene::HeightField;
use hfgi::vk::{Context, Recorder};

fn compare(ctx: &Context, s: &Scene, what: &str) -> f64 {
    let g = render_layers(ctx, s);
    let c = render_direct(s).unwrap();
    let e_direct = rel_l2(&g.direct, &c.direct);
    let e_total = rel_l2(&g.total, &c.total);
    let e_glossy = if s.material.specular.is_some() { rel_l2(&g.glossy, &c.glossy) } else { 0.0 };
    let worst = e_direct.max(e_total).max(e_glossy);
    eprintln!("{what}: rel L2 direct {e_direct:.2e}, glossy {e_glossy:.2e}, total {e_total:.2e}");
    assert!(worst <= 1e-3, "{what}: GPU vs CPU relative L2 {worst:e} > 1e-3");
    worst
}

#[test]
fn gpu_matches_cpu_over_settings() {
    let ctx = gpu();
    let mut base = scene(rough_field(64, 64, 11));
    base.material.specular = Some([0.3, 0.3, 0.3]);
    let mut worst: f64 = 0.0;
    for n in [3, 4, 6] {
        for sub in [1, 2, 4] {
            for interp in [Interpolation::Linear, Interpolation::Bspline] {
                for mode in [PyramidMode::Stack, PyramidMode::Pyramid] {
                    let mut s = base.clone();
                    s.gi.sh_order = n;
                    s.gi.subsample = sub;
                    s.gi.interpolation = interp;
                    s.gi.pyramid = mode;
                    worst = worst.max(compare(&ctx, &s, &format!("n={n} sub={sub} {interp} {mode}")));
                }
            }
        }
    }
    eprintln!("worst relative L2 over 36 configurations: {worst:.2e}");
}

#[test]
fn gpu_matches_cpu_on_other_scenes() {
    let ctx = gpu();
    // Cones with an albedo map and wrap; cliff with a grazing key light; a non-square field.
    let cones = hfgi::scene::generators::Generator::default_for("cones").unwrap().generate(64, 64).unwrap();
    let mut s = scene(cones);
    s.material.albedo =
        Albedo::Map((0..64 * 64).map(|k| [(k % 64) as f32 / 64.0, 0.5, (k / 64) as f32 / 64.0]).collect());
    s.wrap = true;
    compare(&ctx, &s, "cones, albedo map, wrap");

    let cliff = hfgi::scene::generators::Generator::default_for("cliff").unwrap().generate(64, 48).unwrap();
    let mut s = scene(cliff);
    s.key_lights = vec![key_light(12.0, 180.0, 4.0, 6.0), key_light(80.0, 30.0, 20.0, 1.0)];
    s.environment = sky(4);
    s.gi.azimuths = 16;
    compare(&ctx, &s, "cliff 64×48, two key lights (one near the zenith)");

    let mut s = scene(rough_field(61, 37, 5));
    s.gi.level_offset = 0;
    s.gi.level_step = 2;
    s.key_lights.clear();
    compare(&ctx, &s, "61×37, k_v=2, o_v=0, environment only");
}

fn flat(w: usize, h: usize, z: f32) -> HeightField {
    HeightField::new("flat", w, h, vec![z; w * h], 16384).unwrap()
}

#[test]
fn flat_field_visibility_is_the_upper_hemisphere() {
    let ctx = gpu();
    // A periodic flat field is an infinite plane (without wrap, receivers on the border see
    // below the horizon outward, where rays leave the domain and escape).
    for n in [3, 4, 6] {
        let mut s = scene(flat(32, 32, 5.0));
        s.gi.sh_order = n;
        s.wrap = true;
        s.key_lights.clear();
        let mut r = Renderer::new(&ctx, &s).unwrap();
        ctx.submit_and_wait(|cmd| {
            let mut rec = Recorder::new(&ctx, cmd, None);
            r.record(&mut rec);
            Ok(())
        })
        .unwrap();
        let v = r.visibility.read(&ctx, 0).unwrap();
        let hemi = hfgi::math::zh::rotate(n, &hfgi::math::zh::cap(n, std::f64::consts::FRAC_PI_2), [0.0, 0.0, 1.0]);
        let err = v
            .chunks_exact(n * n)
            .flat_map(|c| c.iter().zip(&hemi).map(|(a, b)| (*a as f64 - b).abs()))
            .fold(0.0, f64::max);
        eprintln!("n={n}: max |V − hemisphere| = {err:.2e}");
        assert!(err <= 1e-5, "n={n}: flat-field visibility differs from the hemisphere by {err:e}");
        r.destroy(&ctx);

        // Constant radiance L: diffuse shading = ρ·L.
        let l = 1.7;
        s.environment = uniform(l);
        let g = render_layers(&ctx, &s);
        let rho = [0.7, 0.6, 0.5];
        let err = g
            .direct
            .iter()
            .flat_map(|p| (0..3).map(move |c| (p[c] as f64 - rho[c] * l).abs() / (rho[c] * l)))
            .fold(0.0, f64::max);
        eprintln!("n={n}: max relative |shade − ρL| = {err:.2e}");
        assert!(err <= 1e-4, "n={n}: flat field under constant L: relative error {err:e}");
    }
}

#[test]
fn flat_field_general_environment_documents_the_truncation() {
    // Under a general SH environment a flat field's true shading equals the unshadowed value,
    // but L ⊛ V is truncated to order n, so the pipeline differs by that truncation. The GPU
    // must reproduce exactly the truncation the CPU computes — no more, no less.
    let ctx = gpu();
    let mut s = scene(flat(32, 32, 0.0));
    s.wrap = true;
    s.key_lights.clear();
    s.environment = sky(8);
    let n = s.gi.sh_order;
    let g = render_layers(&ctx, &s);
    let c = render_direct(&s).unwrap();
    let cc = hfgi::math::zh::rotate(n, &hfgi::math::zh::clamped_cosine(n), [0.0, 0.0, 1.0]);
    let rho = [0.7, 0.6, 0.5];
    let unshadowed: Vec<f64> = (0..3)
        .map(|ch| rho[ch] / std::f64::consts::PI * (0..n * n).map(|k| s.environment.sh[k][ch] * cc[k]).sum::<f64>())
        .collect();
    let rel = (0..3).map(|ch| ((c.direct[0][ch] - unshadowed[ch]) / unshadowed[ch]).abs()).fold(0.0, f64::max);
    eprintln!(
        "flat field, sky environment, n={n}: SH truncation of L ⊛ V changes the shading by {:.3}% (relative)",
        rel * 100.0
    );
    assert!(rel > 1e-6, "the truncation should be visible for a general environment");
    let err = rel_l2(&g.direct, &c.direct);
    assert!(err <= 1e-4, "GPU differs from the CPU truncation by {err:e}");
}

fn rotate90(f: &HeightField) -> HeightField {
    // (i, j) → (W−1−j, i): a quarter turn counter-clockwise about the field's centre (square).
    let w = f.width();
    let mut d = vec![0.0; w * w];
    for j in 0..w {
        for i in 0..w {
            d[i * w + (w - 1 - j)] = f.get(i, j);
        }
    }
    HeightField::new("rotated", w, w, d, 16384).unwrap()
}

#[test]
fn rotating_the_field_rotates_the_shading() {
    let ctx = gpu();
    let field = rough_field(48, 48, 21);
    let mut a = scene(field.clone());
    a.gi.azimuths = 32;
    let mut b = a.clone();
    b.field = rotate90(&field);
    let n_env = 8;
    let env: Vec<Vec<f64>> = (0..3).map(|c| a.environment.sh.iter().map(|v| v[c]).collect()).collect();
    let rot: Vec<Vec<f64>> =
        env.iter().map(|c| hfgi::math::sh::rotate_z(n_env, c, std::f64::consts::FRAC_PI_2)).collect();
    b.environment.sh = (0..n_env * n_env).map(|k| [rot[0][k], rot[1][k], rot[2][k]]).collect();
    for l in &mut b.key_lights {
        l.direction = glam::DVec3::new(-l.direction.y, l.direction.x, l.direction.z);
    }
    let ga = render_layers(&ctx, &a);
    let gb = render_layers(&ctx, &b);
    let w = 48;
    let mut worst = 0.0f64;
    let scale = ga.direct.iter().flat_map(|p| p.iter()).fold(0.0f32, |m, v| m.max(v.abs())) as f64;
    for j in 0..w {
        for i in 0..w {
            let pa = ga.direct[j * w + i];
            let pb = gb.direct[i * w + (w - 1 - j)];
            for c in 0..3 {
                worst = worst.max((pa[c] - pb[c]).abs() as f64 / scale);
            }
        }
    }
    eprintln!("90° rotation: max |Δ| / max = {worst:.2e}");
    assert!(worst <= 1e-4, "rotated shading differs by {worst:e} of the maximum");
}

#[test]
fn mirror_symmetric_field_gives_mirror_symmetric_shading() {
    let ctx = gpu();
    let (w, h) = (40, 33);
    let base = rough_field(w, h, 3);
    let d: Vec<f32> = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            base.get(i.min(w - 1 - i), j)
        })
        .collect();
    let mut s = scene(HeightField::new("mirrored", w, h, d, 16384).unwrap());
    // Environment symmetric under x → −x (zonal only) and a key light in the plane x = 0.
    let zonal: Vec<[f64; 3]> = sky(4)
        .sh
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let l = (k as f64).sqrt().floor() as usize;
            if k == l * (l + 1) {
                *v
            } else {
                [0.0; 3]
            }
        })
        .collect();
    s.environment.sh = zonal;
    s.key_lights = vec![key_light(40.0, 90.0, 6.0, 3.0)];
    let g = render_layers(&ctx, &s);
    let scale = g.direct.iter().flat_map(|p| p.iter()).fold(0.0f32, |m, v| m.max(v.abs())) as f64;
    let mut worst = 0.0f64;
    for j in 0..h {
        for i in 0..w {
            let (a, b) = (g.direct[j * w + i], g.direct[j * w + (w - 1 - i)]);
            for c in 0..3 {
                worst = worst.max((a[c] - b[c]).abs() as f64 / scale);
            }
        }
    }
    eprintln!("mirror symmetry: max |Δ| / max = {worst:.2e}");
    assert!(worst <= 1e-4, "mirror symmetry broken by {worst:e}");
}

/// A step: height `h` for `x < x0`, 0 beyond; `w × rows` texels.
fn step(w: usize, rows: usize, x0: usize, h: f32) -> HeightField {
    let d = (0..w * rows).map(|k| if k % w < x0 { h } else { 0.0 }).collect();
    HeightField::new("step", w, rows, d, 16384).unwrap()
}

/// The same light as SH environment coefficients (order `n`): `radiance · cap(α)` rotated to
/// the light's direction (the paper's "fold the key light into the environment").
fn folded(light: &hfgi::scene::model::KeyLight, n: usize) -> hfgi::scene::model::Environment {
    let cap = hfgi::math::zh::rotate(n, &hfgi::math::zh::cap(n, light.angular_radius), light.direction.to_array());
    hfgi::scene::model::Environment {
        sh: cap.iter().map(|c| [c * light.radiance[0], c * light.radiance[1], c * light.radiance[2]]).collect(),
    }
}

/// 10–90% width (texels) of a rising edge in `p`, searched from index `from` onward: the
/// distance between the first crossings of `lo + 0.1Δ` and `lo + 0.9Δ`, with `lo = p[from]` and
/// `hi` = the mean of the last 8 samples; crossings are linearly interpolated.
fn rise_width(p: &[f64], from: usize) -> f64 {
    let lo = p[from];
    let hi = p[p.len() - 8..].iter().sum::<f64>() / 8.0;
    let cross = |level: f64| {
        (from..p.len() - 1)
            .find(|&i| p[i] < level && p[i + 1] >= level)
            .map(|i| i as f64 + (level - p[i]) / (p[i + 1] - p[i]))
            .expect("the profile never crosses the level")
    };
    cross(lo + 0.9 * (hi - lo)) - cross(lo + 0.1 * (hi - lo))
}

#[test]
fn key_light_shadow_is_sharper_than_folded() {
    // A 16-texel step at x = 40 shadows the low side from a light in −x at 30° elevation; the
    // shadow ends near x = 40 + 16/tan 30° ≈ 67.7. Only that light (no other environment).
    let ctx = gpu();
    let (w, rows, x0) = (128, 16, 40);
    let mut s = scene(step(w, rows, x0, 16.0));
    let light = key_light(30.0, 180.0, 3.0, 5.0);
    s.environment = uniform(0.0);
    s.key_lights = vec![light.clone()];
    let profile = |g: &hfgi::frame::ShadingLayers| -> Vec<f64> {
        (0..w).map(|x| g.direct[(rows / 2) * w + x][0] as f64).collect()
    };
    let key = profile(&render_layers(&ctx, &s));
    s.key_lights.clear();
    s.environment = folded(&light, s.gi.sh_order);
    let fold = profile(&render_layers(&ctx, &s));
    let (wk, wf) = (rise_width(&key, x0 + 1), rise_width(&fold, x0 + 1));
    eprintln!("shadow edge 10–90% width along the step: key light {wk:.2} texels, folded into SH (n=4) {wf:.2} texels");
    eprintln!("lit level: key {:.4}, folded {:.4}", key[w - 1], fold[w - 1]);
    assert!(wk > 0.0 && wf > 0.0);
    assert!(wk * 2.0 < wf, "the key light's edge ({wk:.2}) is not clearly sharper than the folded one ({wf:.2})");
}

#[test]
fn level_offset_sharpens_long_shadows() {
    // NS09 §5.2: a larger level offset reads finer levels, so the pyramid blurs the step less
    // and its shadow reaches further, toward the geometric end 40 + 16/tan 30° ≈ 67.7.
    let ctx = gpu();
    let (w, rows, x0) = (128, 16, 40);
    let mut s = scene(step(w, rows, x0, 16.0));
    s.environment = uniform(0.0);
    s.key_lights = vec![key_light(30.0, 180.0, 0.5, 5.0)];
    let expect = x0 as f64 + 16.0 / 30f64.to_radians().tan();
    let mut ends = Vec::new();
    for o in 0..=4 {
        s.gi.level_offset = o;
        let g = render_layers(&ctx, &s);
        let p: Vec<f64> = (0..w).map(|x| g.direct[(rows / 2) * w + x][0] as f64).collect();
        let half = 0.5 * p[w - 1];
        let i = (x0..w - 1).find(|&i| p[i] < half && p[i + 1] >= half).unwrap();
        let end = i as f64 + (half - p[i]) / (p[i + 1] - p[i]);
        eprintln!("level offset {o}: shadow ends at x = {end:.2} (geometry {expect:.2})");
        ends.push(end);
    }
    assert!(ends.windows(2).all(|e| e[1] >= e[0] - 0.25), "shadow length not monotone in o_v: {ends:?}");
    // Still short of the geometry: eq. 17's B-spline approximates (does not interpolate) the
    // sparse ω_i, which lowers the peak at the cliff's edge (docs/direct.md §2).
    assert!(ends[4] - ends[0] > 5.0, "o_v = 4 should lengthen the shadow clearly: {ends:?}");
    assert!(ends.iter().all(|e| *e < expect + 1.0), "a shadow longer than the geometry allows: {ends:?}");
}

#[test]
fn key_light_energy_product_vs_window() {
    // Flat plane, 3° sun at 60°, order 4: true irradiance E = radiance·Ω_cap·sin 60° (to
    // < 0.1% for a 3° cap). docs/direct.md §5 compares the window form (used) with the
    // product of two order-n projections (cap SH ⊛ V_key).
    let mut s = scene(flat(16, 16, 0.0));
    s.wrap = true;
    s.gi.sh_order = 4;
    let light = key_light(60.0, 30.0, 3.0, 10.0);
    s.environment = uniform(0.0);
    s.key_lights = vec![light.clone()];
    let c = render_direct(&s).unwrap();
    let truth = 10.0 * hfgi::frame::shade::cap_solid_angle(light.angular_radius) * 60f64.to_radians().sin();
    let rho = 0.7;
    let window = c.direct[0][0] * std::f64::consts::PI / rho / truth;
    let n = 4;
    let cap = folded(&light, n);
    let l: Vec<f64> = cap.sh.iter().map(|v| v[0]).collect();
    let t = hfgi::math::triple::triple(n);
    let key = c.kinds.iter().position(|k| *k == hfgi::frame::visibility::SetKind::KeyLight(0)).unwrap();
    let prod = hfgi::math::triple::product(t, &l, &c.visibility[key][0]);
    let cc = hfgi::math::zh::rotate(n, &hfgi::math::zh::clamped_cosine(n), [0.0, 0.0, 1.0]);
    let product = prod.iter().zip(&cc).map(|(a, b)| a * b).sum::<f64>() / truth;
    eprintln!(
        "3° sun at 60°, n=4, flat: window form delivers {:.2}% of the true irradiance, cap-SH ⊛ V_key {:.2}%",
        window * 100.0,
        product * 100.0
    );
    assert!((window - 1.0).abs() < 0.05, "window form off by {:.2}%", (window - 1.0) * 100.0);
    assert!(product < 0.2, "the product form kept {:.1}% — docs/direct.md §5 needs updating", product * 100.0);
}

/// Every accuracy fix of docs/accuracy.md §4 alone on the paper's settings, and every preset,
/// GPU against the CPU twin, with the environment and two key lights; `ultra` on a 48² field
/// (m = 128, k = 24, order 8: the longest per-invocation loops on lavapipe).
#[test]
fn gpu_matches_cpu_for_every_fix_and_preset() {
    use hfgi::scene::model::Quality;
    let ctx = gpu();
    let mut base = scene(rough_field(40, 28, 13));
    base.environment = sky(4);
    base.key_lights = vec![key_light(25.0, 200.0, 3.0, 20.0), key_light(60.0, 40.0, 8.0, 2.0)];
    let paper = base.gi.with_quality(Quality::Paper);
    for (name, gi) in common::scenes::single_fixes(&paper, 8) {
        let mut s = base.clone();
        s.gi = gi;
        compare(&ctx, &s, &format!("paper + {name}"));
    }
    for q in [Quality::Draft, Quality::Default, Quality::High] {
        let mut s = base.clone();
        s.gi = base.gi.with_quality(q);
        compare(&ctx, &s, &format!("quality={q}"));
    }
    let mut s = scene(rough_field(48, 48, 17));
    s.environment = sky(4);
    s.gi = s.gi.with_quality(Quality::Ultra);
    compare(&ctx, &s, "quality=ultra, 48²");
}

#[test]
fn gpu_matches_cpu_at_the_highest_sh_order() {
    // sh_order accepts 2..=8; 3/4/6 are covered above, the top of the range here.
    let ctx = gpu();
    let mut s = scene(rough_field(24, 20, 5));
    s.environment = sky(4);
    s.key_lights = vec![key_light(30.0, 120.0, 5.0, 10.0)];
    for q in [hfgi::scene::model::Quality::Paper, hfgi::scene::model::Quality::Ultra] {
        s.gi = s.gi.with_quality(q);
        s.gi.sh_order = 8;
        compare(&ctx, &s, &format!("n=8 quality={q}"));
    }
}

/// The visibility scan's early stop (docs/performance.md §34): with the max pyramid (a scene with
/// indirect light and radial probes, so the renderer makes one) each ray ends where no farther
/// sample can exceed the largest slope so far. Without it (no indirect light, no max pyramid)
/// every ray is scanned to its end. The visibility vectors of every light set must be the same
/// bits: sharp fields — one-texel spikes below zero, a one-texel cliff, steep terraces on a
/// non-square field with a large texel size — and a key light near the horizon.
#[test]
fn visibility_early_stop_keeps_every_horizon() {
    use hfgi::scene::generators::Generator;
    let ctx = gpu();
    let gen = |name: &str, w: usize, h: usize| Generator::default_for(name).unwrap().generate(w, h).unwrap();
    let mut spikes = gen("spikes", 48, 40);
    let below: Vec<f32> = spikes.data().iter().map(|z| z * 40.0 - 25.0).collect();
    spikes = HeightField::new("spikes below zero", 48, 40, below, 4096).unwrap();
    let fields = [
        ("spikes 48×40 below zero", spikes, 1.0),
        ("cliff 64×48", gen("cliff", 64, 48), 1.0),
        ("terraces 56×36, texel 8", gen("terraces", 56, 36), 8.0),
    ];
    for (what, field, texel) in fields {
        let mut s = scene(field);
        s.texel_size = texel;
        s.key_lights = vec![key_light(8.0, 150.0, 3.0, 6.0), key_light(40.0, 300.0, 10.0, 1.0)];
        let read = |s: &Scene| {
            common::render_with(&ctx, s, |ctx, r| {
                let bounded = r.indirect.as_ref().is_some_and(|i| i.max.is_some());
                (bounded, (0..r.visibility.set_count()).map(|i| r.visibility.read(ctx, i).unwrap()).collect::<Vec<_>>())
            })
        };
        s.gi.bounces = 1;
        let (bounded, stopped) = read(&s);
        s.gi.bounces = 0;
        let (unbounded, full) = read(&s);
        assert!(bounded && !unbounded, "{what}: the max pyramid with 1 bounce only ({bounded}, {unbounded})");
        assert_eq!(stopped.len(), 3, "{what}: the environment and two key lights");
        for (k, (a, b)) in stopped.iter().zip(&full).enumerate() {
            let differ = a.iter().zip(b).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
            assert!(a.len() == b.len() && differ == 0, "{what}: set {k}: {differ} of {} values differ", a.len());
        }
    }
}
