//! Indirect illumination: GPU passes against the f64 CPU reference (docs/indirect.md), and
//! the physical properties of the result. Tolerance GPU vs CPU: relative L2 ≤ 1e-3 per layer.

mod common;

use common::scenes::{rel_l2, scene, sky, uniform};
use common::{debug_buffers, find_buffer, gpu, render_with, rough_field};
use hfgi::frame::{Renderer, ShadingLayers};
use hfgi::reference::indirect::render_gi;
use hfgi::scene::model::{Albedo, GlossyPyramid, Interpolation, PyramidMode, Scene};
use hfgi::scene::HeightField;
use hfgi::vk::{Context, Recorder};

fn render_gpu(ctx: &Context, scene: &Scene) -> (ShadingLayers, Vec<String>) {
    let mut r = Renderer::new(ctx, scene).unwrap();
    let stages = common::record_frame(ctx, &mut r);
    let layers = r.read_layers(ctx).unwrap();
    r.destroy(ctx);
    (layers, stages)
}

fn compare(ctx: &Context, s: &Scene, what: &str) {
    let (g, _) = render_gpu(ctx, s);
    let c = render_gi(s).unwrap();
    let e_ind = rel_l2(&g.indirect, &c.indirect);
    let e_tot = rel_l2(&g.total, &c.total);
    let e_gl = if s.material.specular.is_some() { rel_l2(&g.glossy, &c.glossy) } else { 0.0 };
    let ind_share = {
        let (a, b): (f64, f64) =
            c.indirect.iter().zip(&c.total).fold((0.0, 0.0), |(a, b), (i, t)| (a + i[0], b + t[0]));
        a / b
    };
    eprintln!(
        "{what}: rel L2 indirect {e_ind:.2e}, glossy {e_gl:.2e}, total {e_tot:.2e} (indirect is {:.1}% of the total)",
        ind_share * 100.0
    );
    let worst = e_ind.max(e_tot).max(e_gl);
    assert!(worst <= 1e-3, "{what}: GPU vs CPU relative L2 {worst:e} > 1e-3");
    assert!(ind_share > 0.01, "{what}: the indirect light is too small to test anything");
}

fn bright(field: HeightField) -> Scene {
    let mut s = scene(field);
    s.material.albedo = Albedo::Constant([0.8, 0.7, 0.6]);
    s.gi.azimuths = 16;
    s
}

#[test]
fn gpu_matches_cpu_for_bounces_diffuse_and_glossy() {
    let ctx = gpu();
    for bounces in 1..=3 {
        let mut s = bright(rough_field(28, 28, 7));
        s.gi.bounces = bounces;
        compare(&ctx, &s, &format!("diffuse, {bounces} bounce(s)"));
        s.material.specular = Some([0.3, 0.3, 0.3]);
        s.material.exponent = 8.0;
        compare(&ctx, &s, &format!("glossy, scalar pyramid, {bounces} bounce(s)"));
        if bounces < 3 {
            s.gi.glossy_pyramid = GlossyPyramid::Vector;
            compare(&ctx, &s, &format!("glossy, vector pyramid, {bounces} bounce(s)"));
        }
    }
}

#[test]
fn gpu_matches_cpu_over_settings() {
    let ctx = gpu();
    let base = {
        let mut s = bright(rough_field(26, 20, 3));
        s.gi.bounces = 1;
        s
    };
    for (sub, interp, mode, n) in [
        (2, Interpolation::Bspline, PyramidMode::Pyramid, 3),
        (4, Interpolation::Linear, PyramidMode::Stack, 6),
        (1, Interpolation::Bspline, PyramidMode::Stack, 4),
    ] {
        let mut s = base.clone();
        s.gi.subsample = sub;
        s.gi.interpolation = interp;
        s.gi.pyramid = mode;
        s.gi.sh_order = n;
        compare(&ctx, &s, &format!("sub={sub} {interp} {mode} n={n}"));
    }
    let mut s = base.clone();
    s.wrap = true;
    s.gi.radiance_level_step = 2;
    s.gi.radiance_level_offset = 1;
    compare(&ctx, &s, "wrap, k_u=2, o_u=1");
}

fn max_abs(v: &[[f32; 3]]) -> f32 {
    v.iter().flat_map(|p| p.iter()).fold(0.0f32, |m, x| m.max(x.abs()))
}

#[test]
fn flat_field_and_black_albedo_have_no_indirect_light() {
    let ctx = gpu();
    // Flat: every blocking angle is 0 = ω_min, so the casting set is empty (eq. 6).
    let mut s = bright(HeightField::new("flat", 32, 24, vec![3.0; 32 * 24], 16384).unwrap());
    s.gi.bounces = 2;
    s.material.specular = Some([0.2; 3]);
    let (g, stages) = render_gpu(&ctx, &s);
    assert!(stages.iter().any(|st| st == "indirect.scan"), "{stages:?}");
    // Zero up to f32 rounding of the filtered heights (a constant field's B-spline in f32 may
    // differ from the constant in the last bit, making a sample rise by ~1e-7).
    let (ind, dir) = (max_abs(&g.indirect), max_abs(&g.direct));
    eprintln!("flat field: max indirect {ind:.2e}, max direct {dir:.2e}");
    assert!(dir > 0.0 && ind <= 1e-6 * dir, "flat field: indirect light {ind:e}");
    let cpu = render_gi(&s).unwrap().indirect.iter().flat_map(|p| p.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    eprintln!("flat field, CPU f64: max indirect {cpu:.2e}");
    assert!(cpu <= 1e-12, "CPU: flat field indirect {cpu:e}");
    // Albedo 0 (no specular): nothing leaves the surface, the passes are not even planned.
    let mut s = bright(rough_field(32, 32, 9));
    s.gi.bounces = 2;
    s.material.albedo = Albedo::Constant([0.0; 3]);
    let (g, stages) = render_gpu(&ctx, &s);
    assert!(!stages.iter().any(|st| st.starts_with("indirect") || st.starts_with("radiance")), "{stages:?}");
    assert_eq!(max_abs(&g.indirect), 0.0);
    assert_eq!(max_abs(&g.total), 0.0);
    // The CPU reference agrees: zero.
    let c = render_gi(&s).unwrap();
    assert!(c.indirect.iter().all(|p| p.iter().all(|v| *v == 0.0)));
}

#[test]
fn indirect_light_is_bounded_and_bounces_only_add() {
    // Bound (docs/indirect.md §6): a receiver can gather at most what the brightest surface
    // emits, over the part of its cosine lobe that geometry blocks:
    // indirect_b ≤ ρ · max(L_{b−1}) · (1 − E_vis/π) where E_vis/π = the direct diffuse under a
    // uniform unit environment divided by ρ (the visible, cosine-weighted fraction).
    let ctx = gpu();
    let mut s = bright(rough_field(32, 32, 13));
    s.environment = uniform(1.0);
    s.key_lights.clear();
    s.gi.bounces = 0;
    let (vis, _) = render_gpu(&ctx, &s);
    let rho = [0.8f32, 0.7, 0.6];
    let mut prev_total: Option<Vec<[f32; 3]>> = None;
    let mut prev_bounce_max: Option<f32> = None;
    let mut prev_indirect = vec![[0.0f32; 3]; 32 * 32];
    s.environment = sky(4);
    s.key_lights = vec![common::scenes::key_light(25.0, 120.0, 3.0, 300.0)];
    for b in 0..=3 {
        s.gi.bounces = b;
        let (g, _) = render_gpu(&ctx, &s);
        let bounce: Vec<[f32; 3]> =
            g.indirect.iter().zip(&prev_indirect).map(|(a, p)| [a[0] - p[0], a[1] - p[1], a[2] - p[2]]).collect();
        if let Some(src_max) = prev_bounce_max {
            let mut worst = f32::MIN;
            let mut worst_loose = f32::MIN;
            for (i, p) in bounce.iter().enumerate() {
                for c in 0..3 {
                    let blocked = (1.0 - vis.direct[i][c] / rho[c]).max(0.0);
                    let bound = rho[c] * src_max * blocked;
                    worst = worst.max((p[c] - bound) / (rho[c] * src_max));
                    worst_loose = worst_loose.max((p[c] - rho[c] * src_max) / (rho[c] * src_max));
                }
            }
            eprintln!(
                "bounce {b}: max(indirect − tight bound)/ρ·max = {worst:.3e}, loose {worst_loose:.3e} (≤ 0 required)"
            );
            assert!(worst_loose <= 0.0, "bounce {b} exceeds ρ·max(L_(b−1)) by {worst_loose:e}");
            // Both sides of the tight bound are order-n SH results, so it holds up to the
            // truncation of the cosine lobe (measured ≈ 1% of ρ·max at n = 4).
            assert!(worst <= 0.02, "bounce {b} exceeds the tight bound by {worst:e} of ρ·max");
        }
        if let Some(pt) = &prev_total {
            let (sum_now, sum_prev): (f64, f64) =
                g.total.iter().zip(pt).fold((0.0, 0.0), |(a, b), (x, y)| (a + x[0] as f64, b + y[0] as f64));
            let min_gain =
                g.total.iter().zip(pt).flat_map(|(x, y)| (0..3).map(move |c| x[c] - y[c])).fold(f32::MAX, f32::min);
            eprintln!("bounce {b}: total {sum_prev:.4} → {sum_now:.4}, smallest per-texel change {min_gain:.3e}");
            assert!(min_gain >= -1e-6 * max_abs(&g.total), "adding bounce {b} darkened a texel by {min_gain:e}");
        }
        // The source of the next bounce: this bounce's exit radiance (diffuse; no glossy here).
        let src = if b == 0 { g.direct.clone() } else { bounce };
        prev_bounce_max = Some(max_abs(&src));
        prev_indirect = g.indirect.clone();
        prev_total = Some(g.total.clone());
    }
}

/// Records one frame with a stage timer; returns the timed stage names and the layers.
fn frame(ctx: &Context, r: &mut Renderer, timer: &mut hfgi::vk::StageTimer) -> (Vec<String>, ShadingLayers) {
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, Some(&mut *timer));
        r.record(&mut rec);
        Ok(())
    })
    .unwrap();
    let names: Vec<String> = timer.timings(ctx).unwrap().into_iter().map(|(n, _)| n).collect();
    (names, r.read_layers(ctx).unwrap())
}

#[test]
fn amortised_shading_alternates_direct_and_indirect_after_a_light_change() {
    let ctx = gpu();
    let mut s = bright(rough_field(24, 24, 5));
    s.gi.bounces = 1;
    let shading = |names: &[String]| -> Vec<String> {
        names.iter().filter(|n| n.starts_with("shade.") || n.starts_with("indirect.")).cloned().collect()
    };
    let mut timer = hfgi::vk::StageTimer::new(&ctx, 64).unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (f0, l0) = frame(&ctx, &mut r, &mut timer);
    assert_eq!(shading(&f0), ["shade.direct", "indirect.scan", "indirect.shade"]);
    assert!(f0.contains(&"pyramid.decimate".to_string()) && f0.contains(&"visibility.environment".to_string()));
    // A static frame with nothing changed records nothing and keeps the image.
    let (f1, l1) = frame(&ctx, &mut r, &mut timer);
    assert!(f1.is_empty(), "static frame: {f1:?}");
    assert_eq!(l1.total, l0.total);
    // A light change: even frame 2 the direct light, odd frame 3 the indirect light (NS09 §7),
    // then nothing; the pyramid and the visibility are never re-run.
    r.set_environment(&s.environment.scaled(0.5)).unwrap();
    let (f2, _) = frame(&ctx, &mut r, &mut timer);
    let (f3, l3) = frame(&ctx, &mut r, &mut timer);
    let (f4, l4) = frame(&ctx, &mut r, &mut timer);
    eprintln!("amortised: frame 2 {f2:?}\n  frame 3 {f3:?}\n  frame 4 {f4:?}");
    assert_eq!(shading(&f2), ["shade.direct"], "even frame: direct only");
    assert_eq!(shading(&f3), ["indirect.scan", "indirect.shade"], "odd frame: indirect only");
    assert!(f4.is_empty(), "converged: {f4:?}");
    assert!(!f2.iter().chain(&f3).any(|n| n.starts_with("pyramid.") || n.starts_with("visibility.")));
    assert_eq!(l4.total, l3.total);
    let dimmer = l3.total.iter().zip(&l0.total).all(|(a, b)| (0..3).all(|c| a[c] <= b[c] + 1e-6 * b[c].abs()));
    assert!(dimmer, "a dimmer sky made some texel brighter");
    r.destroy(&ctx);
    // Off: a change re-shades both halves in one frame.
    s.gi.amortize = false;
    let mut r = Renderer::new(&ctx, &s).unwrap();
    frame(&ctx, &mut r, &mut timer);
    r.set_environment(&s.environment.scaled(0.5)).unwrap();
    let (g1, _) = frame(&ctx, &mut r, &mut timer);
    assert_eq!(shading(&g1), ["shade.direct", "indirect.scan", "indirect.shade"]);
    eprintln!("not amortised: frame after the change {g1:?}");
    r.destroy(&ctx);
    timer.destroy(&ctx);
}

#[test]
fn scalar_and_vector_glossy_pyramids_figure_5() {
    // Figure 5: the scalar pyramid evaluates glossy exit radiance toward the camera, the vector
    // pyramid toward each receiver. For a diffuse surface they are the same computation; for a
    // glossy one they differ, and the docs report by how much (the ground truth arbitrates).
    let ctx = gpu();
    let mut s = bright(rough_field(28, 28, 17));
    s.gi.bounces = 1;
    let indirect = |s: &Scene| {
        let (g, _) = render_gpu(&ctx, s);
        g.indirect
            .iter()
            .zip(&g.indirect_glossy)
            .map(|(d, gl)| [d[0] + gl[0], d[1] + gl[1], d[2] + gl[2]])
            .collect::<Vec<_>>()
    };
    let as_f64 = |v: &[[f32; 3]]| v.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect::<Vec<_>>();
    s.gi.glossy_pyramid = GlossyPyramid::Scalar;
    let diffuse_scalar = indirect(&s);
    s.gi.glossy_pyramid = GlossyPyramid::Vector;
    let diffuse_vector = indirect(&s);
    assert_eq!(diffuse_scalar, diffuse_vector, "diffuse surface: the two pyramids must agree exactly");
    s.material.specular = Some([0.3; 3]);
    s.material.exponent = 8.0;
    s.gi.glossy_pyramid = GlossyPyramid::Scalar;
    let scalar = indirect(&s);
    s.gi.glossy_pyramid = GlossyPyramid::Vector;
    let vector = indirect(&s);
    let d = rel_l2(&scalar, &as_f64(&vector));
    eprintln!(
        "glossy (k_s 0.3, S = 8): indirect light of the scalar pyramid differs from the vector one by {:.2}% (rel L2)",
        d * 100.0
    );
    assert!(d > 1e-4 && d.is_finite(), "the two pyramids should differ on a glossy surface: {d:e}");
}

/// Every accuracy fix of docs/accuracy.md §4 alone on the paper's settings, and every preset,
/// GPU against the CPU twin (one bounce; vector glossy pyramid for one of them).
#[test]
fn gpu_matches_cpu_for_every_fix_and_preset() {
    use hfgi::scene::model::Quality;
    let ctx = gpu();
    let mut base = bright(rough_field(24, 18, 9));
    base.gi.bounces = 1;
    let paper = base.gi.with_quality(Quality::Paper);
    for (name, gi) in common::scenes::single_fixes(&paper, 6) {
        let mut s = base.clone();
        s.gi = gi;
        compare(&ctx, &s, &format!("paper + {name}"));
    }
    for q in [Quality::Draft, Quality::Default, Quality::High, Quality::Ultra] {
        let mut s = base.clone();
        s.gi = base.gi.with_quality(q);
        compare(&ctx, &s, &format!("quality={q}"));
    }
    let mut s = base.clone();
    s.gi = base.gi.with_quality(Quality::Default);
    s.material.specular = Some([0.3, 0.3, 0.3]);
    s.material.exponent = 8.0;
    s.gi.glossy_pyramid = GlossyPyramid::Vector;
    s.gi.pyramid = PyramidMode::Pyramid;
    compare(&ctx, &s, "quality=default, vector glossy pyramid, true pyramid");
}

#[test]
fn gpu_matches_cpu_at_the_highest_sh_order() {
    let ctx = gpu();
    let mut s = bright(rough_field(24, 18, 9));
    s.gi.bounces = 1;
    for q in [hfgi::scene::model::Quality::Paper, hfgi::scene::model::Quality::Ultra] {
        s.gi = s.gi.with_quality(q);
        s.gi.sh_order = 8;
        compare(&ctx, &s, &format!("n=8 quality={q}"));
    }
}

/// 30 one-texel spikes (up to 0.15 of the width high) on a 44 × 30 field lowered below zero.
fn spikes_below_zero() -> HeightField {
    use hfgi::scene::generators::Generator;
    let f = Generator::Spikes { seed: 4, count: 30, height: 0.15 }.generate(44, 30).unwrap();
    let data: Vec<f32> = f.data().iter().map(|h| h - 12.0).collect();
    HeightField::new("spikes", 44, 30, data, 4096).unwrap()
}

/// Radial probes (docs/accuracy.md §4) on thin spikes, non-square, heights below zero, 2 bounces
/// with different probe counts: GPU (with the max-pyramid bound, and without it on a periodic
/// field) = twin (which probes every interval), and the probes change the light (so neither
/// side can ignore them unnoticed).
#[test]
fn gpu_matches_cpu_with_radial_probes_on_spikes() {
    let ctx = gpu();
    let mut s = bright(spikes_below_zero());
    s.gi.bounces = 2;
    s.gi.radial_probes = 3;
    s.gi.radial_probes_later = 2;
    for wrap in [false, true] {
        s.wrap = wrap;
        compare(&ctx, &s, &format!("spikes, probes 3 / 2, wrap={wrap}"));
    }
    s.wrap = false;
    let (with, stages) = render_gpu(&ctx, &s);
    assert!(stages.iter().any(|n| n == "pyramid.max"), "{stages:?}");
    s.gi.radial_probes = 0;
    s.gi.radial_probes_later = 0;
    let (without, stages) = render_gpu(&ctx, &s);
    assert!(!stages.iter().any(|n| n == "pyramid.max"), "{stages:?}");
    let change = rel_l2(&with.indirect, &without.indirect.iter().map(|v| v.map(f64::from)).collect::<Vec<_>>());
    eprintln!("probes change the indirect light by {change:.2e} (relative L2)");
    assert!(change > 1e-2, "the probes changed the indirect light by only {change:e}");
}

/// The replay (docs/indirect.md §2, "Replay"): bounce 1's walk records the casting sets of the
/// walk without probes and bounces 2 and 3 cast them without walking (their pipeline has no
/// walk, so the recorded sets are all they can cast). On thin spikes below zero, non-square,
/// with and without probes in bounce 1, sub-sampled and periodic, and with later sets of 16, 8
/// and 4 of the 16 azimuths (every 1st, 2nd, 4th: `rules::scene::replay_stride`): the same
/// light as walking (`gi.replay = false`) within f32 rounding, the twin within its tolerance,
/// and the sets' 8 bytes per receiver and later azimuth allocated only with the replay.
#[test]
fn later_bounces_cast_the_casting_sets_bounce_one_recorded() {
    let ctx = gpu();
    let mut s = bright(spikes_below_zero());
    s.gi.bounces = 3;
    let cases =
        [(2, 1, false, 16), (0, 1, false, 16), (2, 2, false, 16), (2, 1, true, 16), (2, 1, false, 8), (0, 2, true, 4)];
    for (probes, sub, wrap, later) in cases {
        (s.gi.radial_probes, s.gi.subsample, s.wrap, s.gi.azimuths_later) = (probes, sub, wrap, later);
        let what = format!("probes {probes}, subsample {sub}, wrap={wrap}, {later} later azimuths");
        let read = |ctx: &Context, r: &Renderer| (r.read_layers(ctx).unwrap(), r.memory_bytes());
        let (replayed, with) = render_with(&ctx, &s, read);
        s.gi.replay = false;
        let (walked, without) = render_with(&ctx, &s, read);
        s.gi.replay = true;
        let (w, h) = (44usize.div_ceil(sub as usize), 30usize.div_ceil(sub as usize));
        // (Without the replay the pass keeps a 16-byte placeholder, as for every unused buffer.)
        assert_eq!(with - without, (w * h * later as usize * 8 - 16) as u64, "{what}: the recorded sets' bytes");
        for (name, a, b) in
            [("indirect", &replayed.indirect, &walked.indirect), ("total", &replayed.total, &walked.total)]
        {
            let e = rel_l2(a, &b.iter().map(|v| v.map(f64::from)).collect::<Vec<_>>());
            eprintln!("{what}: replayed vs walked {name} {e:.2e}");
            assert!(e <= 1e-6, "{what}: replayed vs walked {name}: relative L2 {e:e}");
        }
        compare(&ctx, &s, &format!("replay, {what}"));
    }
    // Where it does not apply (later probes, a later set that is not a subset of the first's
    // 16 azimuths, one bounce): no sets.
    for (later_probes, later_m, bounces) in [(1, 16, 3), (0, 12, 3), (0, 6, 3), (0, 16, 1)] {
        (s.gi.radial_probes_later, s.gi.azimuths_later, s.gi.bounces) = (later_probes, later_m, bounces);
        let with = render_with(&ctx, &s, |_, r| r.memory_bytes());
        s.gi.replay = false;
        let without = render_with(&ctx, &s, |_, r| r.memory_bytes());
        s.gi.replay = true;
        assert_eq!(with, without, "later probes {later_probes}, later azimuths {later_m}, {bounces} bounce(s)");
    }
}

/// The cast merge (`gi.cast_merge = δ`, docs/indirect.md §2, "Merged casts") in the twin's
/// scan of every receiver of thin spikes below zero (44 × 30, 2 probes, 16 azimuths): with δ
/// the members cast are a subset of those cast without it, in the same order; each rises at
/// least δ above the one cast before it but the ray's last; the last is the same as without
/// (the casting set still reaches its horizon); and fewer members are cast. With δ = 0 every
/// member is cast.
#[test]
fn merged_casts_keep_members_at_least_delta_apart_and_the_horizon() {
    use hfgi::reference::direct::Scan;
    use hfgi::reference::indirect::{receiver_normal, scan_radiance};
    use hfgi::reference::pyramid::CpuPyramid;
    let mut s = bright(spikes_below_zero());
    s.gi.radial_probes = 2;
    let z0 = hfgi::rules::scene::height_origin(&s.field);
    let pyr = CpuPyramid::build_relative(&s.field, z0, (44, 30), s.gi.level_step, false, true).unwrap();
    let delta = 0.03;
    let casts = |merge: f64, p: [f64; 2], phi: f64| {
        let mut scan = Scan::new(&pyr, &s.gi, s.texel_size, false);
        scan.merge = merge;
        let mut cast = Vec::new();
        let mut rad = |i: usize, q: [f64; 2], omega: f64| {
            cast.push((i, q, omega));
            [1.0; 3]
        };
        scan_radiance(&scan, 4, p, phi, receiver_normal(&s, p), true, &mut rad);
        cast.retain(|c| c.0 != usize::MAX); // the near-field limit's cast, not a member's
        cast
    };
    let (mut all, mut merged) = (0, 0);
    for r in 0..44 * 30 {
        let p = [(r % 44) as f64, (r / 44) as f64];
        for j in 0..16 {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / 16.0;
            let every = casts(0.0, p, phi);
            let kept = casts(delta, p, phi);
            assert_eq!(every, casts(f64::MIN_POSITIVE, p, phi), "{p:?} φ {phi}: δ → 0 casts every member");
            let mut rest = every.iter();
            assert!(kept.iter().all(|k| rest.any(|e| e == k)), "{p:?} φ {phi}: not a subset in order");
            assert_eq!(kept.last(), every.last(), "{p:?} φ {phi}: the last member");
            for w in kept.windows(2).take(kept.len().saturating_sub(2)) {
                assert!(w[1].2 - w[0].2 >= delta, "{p:?} φ {phi}: {:?} then {:?}", w[0], w[1]);
            }
            (all, merged) = (all + every.len(), merged + kept.len());
        }
    }
    eprintln!("members cast: {all} without the merge, {merged} with δ = {delta}");
    assert!(merged < all * 9 / 10, "the merge cast {merged} of {all} members");
}

/// The cast merge on the GPU (docs/indirect.md §2, "Merged casts"): thin spikes below zero,
/// non-square, 2 bounces (the first walking with probes, the second replaying), δ = 0.01 and
/// 0.05: GPU = twin; and it changes the light a little (so neither side can ignore it), less
/// than the probes do.
#[test]
fn gpu_matches_cpu_with_merged_casts() {
    let ctx = gpu();
    let mut s = bright(spikes_below_zero());
    (s.gi.bounces, s.gi.radial_probes, s.gi.azimuths_later) = (2, 2, 8);
    s.gi.cast_merge = 0.0;
    let (every, _) = render_gpu(&ctx, &s);
    let every: Vec<[f64; 3]> = every.indirect.iter().map(|v| v.map(f64::from)).collect();
    for delta in [0.01, 0.05] {
        s.gi.cast_merge = delta;
        compare(&ctx, &s, &format!("spikes, cast merge {delta}"));
        let (merged, _) = render_gpu(&ctx, &s);
        let change = rel_l2(&merged.indirect, &every);
        eprintln!("δ = {delta} changes the indirect light by {change:.2e} (relative L2)");
        assert!(change > 1e-5 && change < 1e-2, "δ = {delta}: the merge changed the indirect light by {change:e}");
    }
}

/// Later bounces with their own, smaller azimuth set (`gi.azimuths_later`, docs/performance.md
/// §12), on a non-square field with heights below zero: GPU = twin for 2 and 3 bounces (the
/// later set serves bounces 2 and 3) with 4 of 16 azimuths (every 4th of the first set's, which
/// the later bounces replay) and 6 (its own set, which they walk); and the later set changes
/// the light (the GPU differs from the twin that scans every bounce with the full set), so
/// neither side can ignore it.
#[test]
fn gpu_matches_cpu_with_fewer_azimuths_in_later_bounces() {
    let ctx = gpu();
    let f = rough_field(26, 19, 5);
    let data: Vec<f32> = f.data().iter().map(|h| h - 7.0).collect();
    let mut s = bright(HeightField::new("rough", 26, 19, data, 4096).unwrap());
    for later in [4, 6] {
        s.gi.azimuths_later = later;
        for bounces in [2, 3] {
            s.gi.bounces = bounces;
            compare(&ctx, &s, &format!("16 azimuths, {later} in later bounces, {bounces} bounces"));
        }
    }
    s.gi.azimuths_later = 4;
    s.gi.bounces = 2;
    let (g, _) = render_gpu(&ctx, &s);
    let mut full = s.clone();
    full.gi.azimuths_later = 16;
    let c = render_gi(&full).unwrap();
    let change = rel_l2(&g.indirect, &c.indirect);
    eprintln!("4 instead of 16 azimuths in bounce 2 change the indirect light by {change:.2e} (relative L2)");
    assert!(change > 5e-3, "the later bounce's azimuth set changed the indirect light by only {change:e}");
}

/// The scan's pipelines (docs/performance.md §12, §17, §18, §33): with probes in the first
/// bounce only, the later bounces' scan is a second pipeline with the probes' code compiled out;
/// with probes in every bounce, or one bounce, one pipeline serves. Both stop early against the
/// max pyramid (§18). With the cast merge (first bounce only, a constant of its pipeline) the
/// later bounces have their own; one bounce has one, which also scans a bounce past it (with
/// the merge). (GPU = twin for all: the tests above.)
#[test]
fn later_bounces_without_probes_get_a_scan_pipeline_without_the_probes() {
    let ctx = gpu();
    let pipelines = |bounces: u32, later: u32, merge: f64| {
        let mut s = bright(rough_field(20, 14, 2));
        (s.gi.bounces, s.gi.radial_probes, s.gi.radial_probes_later) = (bounces, 2, later);
        s.gi.cast_merge = merge;
        let before = ctx.pipelines_created();
        let r = Renderer::new(&ctx, &s).unwrap();
        let made = ctx.pipelines_created() - before;
        r.destroy(&ctx);
        made
    };
    let (one, two, two_probed) = (pipelines(1, 0, 0.0), pipelines(2, 0, 0.0), pipelines(2, 1, 0.0));
    eprintln!("pipelines: 1 bounce {one}, 2 bounces {two}, 2 probed bounces {two_probed}");
    assert_eq!(two, one + 1, "an unprobed later bounce has its own scan pipeline");
    assert_eq!(two_probed, one, "probed bounces share the probing pipeline");
    let merged = [pipelines(1, 0, 0.01), pipelines(2, 0, 0.01), pipelines(2, 1, 0.01)];
    eprintln!("with the cast merge: {merged:?}");
    assert_eq!(merged, [one, one + 1, one + 1], "the merging first bounce's pipeline serves no later bounce");
}

/// What the next bounce starts from (docs/indirect.md §1): the indirect shade leaves in level 0
/// of the radiance pyramid, rgb per texel, the bounce's diffuse + glossy exit radiance with the
/// scalar pyramid, and the diffuse part alone with the vector pyramid (which carries the glossy
/// light as T). After one bounce the indirect planes hold exactly that bounce's exit radiance,
/// so they are the expectation. (A shade that wrote the diffuse part alone, or nothing, so that
/// level 0 kept the gathered direct light, fails it.)
#[test]
fn the_indirect_shade_writes_the_next_bounces_level_0() {
    let ctx = gpu();
    let (w, h) = (20, 17);
    let mut s = bright(rough_field(w, h, 3));
    s.gi.bounces = 1;
    s.material.specular = Some([0.3; 3]);
    s.material.exponent = 8.0;
    for vector in [false, true] {
        s.gi.glossy_pyramid = if vector { GlossyPyramid::Vector } else { GlossyPyramid::Scalar };
        let b = debug_buffers(&ctx, &s);
        let get = |name: &str| find_buffer(&b, name);
        let (bounce, diffuse, glossy) = (get("indirect.next"), get("shade.indirect"), get("shade.glossy_indirect"));
        assert_eq!(bounce.len(), 3 * w * h, "rgb per texel");
        let mut max_glossy = 0.0f32;
        for t in 0..w * h {
            for c in 0..3 {
                let want = diffuse[3 * t + c] + if vector { 0.0 } else { glossy[3 * t + c] };
                let got = bounce[3 * t + c];
                assert!(
                    (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                    "vector {vector}, texel {t}: {got} vs {want}"
                );
                max_glossy = max_glossy.max(glossy[3 * t + c]);
            }
        }
        assert!(max_glossy > 1e-3, "the glossy light must be there to tell the two apart: {max_glossy}");
    }
}

/// A diffuse surface's `U` keeps only the bands its clamped-cosine lobe does not zero
/// (`rules::scene::u_bands`; order 4: bands 0–2, order 6: bands 0–4) and shades the same as the
/// full `U`. The full one comes from the same scene with a zero specular colour, which keeps
/// every band (the Phong lobe reads them) but adds no light: every layer agrees within 1e-6
/// (relative L2), and the kept coefficients are the full vector's first ones.
#[test]
fn diffuse_u_keeps_the_bands_the_clamped_cosine_reads() {
    let ctx = gpu();
    // (order, bands kept, storage, lobe): the exact lobe (tests/lobe.rs) reads band 1 only.
    let exact = hfgi::scene::model::DiffuseLobe::Exact;
    let sh = hfgi::scene::model::DiffuseLobe::Sh;
    for (n, kept, storage, lobe) in
        [(4usize, 3usize, "f32", sh), (4, 3, "f16", sh), (6, 5, "f32", sh), (5, 2, "f32", exact)]
    {
        let mut s = scene(rough_field(37, 29, 11));
        s.gi.sh_order = n;
        s.gi.diffuse_lobe = lobe;
        s.gi.azimuths = 8;
        s.gi.bounces = 2;
        s.gi.storage =
            if storage == "f16" { hfgi::scene::model::Storage::F16 } else { hfgi::scene::model::Storage::F32 };
        let mut full = s.clone();
        full.material.specular = Some([0.0; 3]);
        assert_eq!((hfgi::rules::scene::u_bands(&s), hfgi::rules::scene::u_bands(&full)), (kept, n));
        let (a, b) = (debug_buffers(&ctx, &s), debug_buffers(&ctx, &full));
        let (ua, ub) = (find_buffer(&a, "indirect.u"), find_buffer(&b, "indirect.u"));
        let receivers = 37 * 29;
        assert_eq!((ua.len(), ub.len()), (receivers * 3 * kept * kept, receivers * 3 * n * n), "n = {n}");
        for r in 0..receivers {
            let (x, y) = (&ua[r * 3 * kept * kept..][..3 * kept * kept], &ub[r * 3 * n * n..][..3 * kept * kept]);
            assert_eq!(x, y, "n = {n}, {storage}: receiver {r}'s kept coefficients");
        }
        let (la, _) = render_gpu(&ctx, &s);
        let (lb, _) = render_gpu(&ctx, &full);
        for (layer, x, y) in [("indirect", &la.indirect, &lb.indirect), ("total", &la.total, &lb.total)] {
            let y64: Vec<[f64; 3]> = y.iter().map(|p| p.map(f64::from)).collect();
            let e = rel_l2(x, &y64);
            assert!(e <= 1e-6, "n = {n}, {storage}: {layer} {e:e}");
            assert!(x.iter().any(|p| p[0] > 1e-4), "n = {n}: {layer} is empty");
        }
    }
    assert!(common::finish(ctx).is_empty());
}

/// Plane 0 of a renderer's height stack holds level 0 itself, relative to the origin, when the
/// scans read level 0 as the bilinear surface at full resolution (docs/pyramid.md; the scans
/// then read every level through the stack, docs/performance.md §17): bit for bit `h − z0` as
/// `hfgi_fetch` computes it. With `gi.level0 = "bspline"` the plane is the B-spline, which on a
/// rough field differs from the samples; sub-sampled, the plane has the working grid's size.
/// (The scans' use of it is covered by the GPU-vs-twin tests above: the twin reads level 0.)
#[test]
fn height_plane_0_holds_level_0_when_the_scans_read_it_raw() {
    use hfgi::scene::model::Level0;
    let ctx = gpu();
    let (w, h) = (23, 17);
    let mut s = bright(rough_field(w, h, 4));
    s.gi.bounces = 1;
    let origin = render_with(&ctx, &s, |_, r| r.height_origin());
    let b = debug_buffers(&ctx, &s);
    let (level0, plane0) = (find_buffer(&b, "pyramid.level0"), find_buffer(&b, "pyramid.stack0"));
    assert_eq!(plane0.len(), w * h, "plane 0 has level 0's size");
    for (i, (&l, &p)) in level0.iter().zip(plane0).enumerate() {
        assert_eq!(p.to_bits(), (l - origin).to_bits(), "texel {i}: plane 0 {p} vs level 0 − z0 {}", l - origin);
    }
    s.gi.level0 = Level0::Bspline;
    let b = debug_buffers(&ctx, &s);
    let (level0, plane0) = (find_buffer(&b, "pyramid.level0"), find_buffer(&b, "pyramid.stack0"));
    let off = level0.iter().zip(plane0).map(|(l, p)| (l - origin - p).abs()).fold(0.0f32, f32::max);
    assert!(off > 1e-3, "B-spline plane 0 equals the samples ({off:e}): the test field is too smooth");
    s.gi.level0 = Level0::Bilinear;
    s.gi.subsample = 2;
    let b = debug_buffers(&ctx, &s);
    assert_eq!(find_buffer(&b, "pyramid.stack0").len(), w.div_ceil(2) * h.div_ceil(2), "sub-sampled plane 0");
}
