//! GPU height pyramid against its f64 CPU twin, both storage modes.
//! Tolerance: max |GPU − CPU| ≤ 1e-4 × height range, on levels, stack planes and probes.

mod common;

use common::{gpu, max_abs_diff, rough_field};
use hfgi::frame::pyramid::{HeightPyramid, PyramidLayout, PyramidMode};
use hfgi::reference::pyramid::CpuPyramid;
use hfgi::vk::{Recorder, StageTimer};

/// Uploads `field` into `pyr` and records its decimation and synthesis (one submit, waited).
fn build(ctx: &hfgi::vk::Context, pyr: &HeightPyramid, field: &hfgi::scene::HeightField) {
    pyr.upload(ctx, field).unwrap();
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, None);
        pyr.record(&mut rec);
        Ok(())
    })
    .unwrap();
}

fn check(ctx: &hfgi::vk::Context, w: usize, h: usize, k_v: u32, mode: PyramidMode, wrap: bool, sub: usize) {
    let work = (w.div_ceil(sub).max(2), h.div_ceil(sub).max(2));
    let field = rough_field(w, h, (w * 31 + h + k_v as usize) as u32);
    let (lo, hi) = field.range();
    let tol = 1e-4 * (hi - lo) as f64;
    let pyr = HeightPyramid::new(ctx, w, h, work, k_v, mode, wrap).unwrap();
    build(ctx, &pyr, &field);
    let cpu = CpuPyramid::build(&field, work, k_v, wrap, mode == PyramidMode::Stack).unwrap();
    let what = format!("{w}×{h} k_v={k_v} {mode} wrap={wrap} work={work:?}");
    assert_eq!(pyr.layout(), &cpu.layout, "{what}: layouts differ");
    let mut worst = 0.0f64;
    for i in 0..cpu.layout.count() {
        let err = max_abs_diff(&pyr.read_level(ctx, i).unwrap(), &cpu.levels[i]);
        assert!(err <= tol, "{what}: level {i} max error {err:e} > {tol:e}");
        worst = worst.max(err);
        if let Some(stack) = &cpu.stack {
            let err = max_abs_diff(&pyr.read_stack(ctx, i).unwrap(), &stack[i]);
            assert!(err <= tol, "{what}: stack plane {i} max error {err:e} > {tol:e}");
            worst = worst.max(err);
        }
    }
    // Probes at off-grid positions, including outside the domain (clamp / wrap addressing).
    let mut queries = Vec::new();
    let mut s = 12345u32;
    let mut rnd = || {
        s = s.wrapping_mul(1664525).wrapping_add(1013904223);
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    for i in 0..cpu.layout.count() {
        for _ in 0..40 {
            queries.push([i as f32, rnd() * (w as f32 + 4.0) - 2.0, rnd() * (h as f32 + 4.0) - 2.0]);
        }
    }
    let got = pyr.probe(ctx, &queries).unwrap();
    let want: Vec<f64> = queries
        .iter()
        .map(|q| match mode {
            PyramidMode::Stack => cpu.sample_stack(q[0] as usize, q[1] as f64, q[2] as f64).unwrap(),
            PyramidMode::Pyramid => cpu.sample_pyramid(q[0] as usize, q[1] as f64, q[2] as f64),
        })
        .collect();
    let err = max_abs_diff(&got, &want);
    assert!(err <= tol, "{what}: probe max error {err:e} > {tol:e}");
    worst = worst.max(err);
    eprintln!("{what}: {} levels, max |GPU − CPU| = {worst:.2e} (tolerance {tol:.2e})", cpu.layout.count());
    pyr.destroy(ctx);
}

#[test]
fn gpu_matches_cpu_stack_and_pyramid_modes() {
    let ctx = gpu();
    for mode in [PyramidMode::Stack, PyramidMode::Pyramid] {
        for (w, h, k) in
            [(64, 64, 4), (97, 61, 4), (61, 97, 3), (97, 61, 1), (50, 33, 2), (128, 128, 4), (2, 2, 4), (3, 7, 5)]
        {
            check(&ctx, w, h, k, mode, false, 1);
        }
        check(&ctx, 64, 48, 4, mode, true, 1);
        check(&ctx, 97, 61, 4, mode, false, 2);
        check(&ctx, 64, 64, 3, mode, true, 4);
    }
}

#[test]
fn layout_follows_the_paper() {
    // 256², k_v = 4: 33 levels (thesis eq. 4.4, n = ls·log2(size) + 1); τ_{n_v−1} = 1 (eq. 14).
    let l = PyramidLayout::new(256, 256, 4).unwrap();
    assert_eq!(l.count(), 33);
    assert_eq!((l.levels[4].width, l.levels[8].width, l.levels[32].width), (128, 64, 1));
    assert!((l.tau(32) - 1.0).abs() < 1e-15 && (l.tau(0) - 1.0 / 256.0).abs() < 1e-15);
    assert_eq!(PyramidLayout::new(97, 61, 1).unwrap().count(), 7);
    assert!(PyramidLayout::new(97, 61, 0).is_err());
    assert!(PyramidLayout::new(1, 61, 4).is_err());
}

#[test]
fn memory_of_each_mode_at_512() {
    let ctx = gpu();
    let mut bytes = Vec::new();
    for mode in [PyramidMode::Stack, PyramidMode::Pyramid] {
        let p = HeightPyramid::new(&ctx, 512, 512, (512, 512), 4, mode, false).unwrap();
        bytes.push(p.memory_bytes());
        eprintln!(
            "pyramid memory 512² k_v=4 ({} levels), {mode}: {} bytes ({:.2} MiB)",
            p.layout().count(),
            p.memory_bytes(),
            p.memory_bytes() as f64 / (1 << 20) as f64
        );
        p.destroy(&ctx);
    }
    let ratio = bytes[0] as f64 / bytes[1] as f64;
    eprintln!("pyramid memory 512²: stack / pyramid = {ratio:.1}×");
    // The stack adds one f32 plane per level, each the working grid (512) halved while the
    // half still holds the level's round(512·2^(−i/4)) texels: 512 for levels 0-3, 256 for 4-7,
    // 128 for 8-11, … (docs/pyramid.md "Storage modes"; the paper's full-size planes would be
    // 37 × 512², > 10× the pyramid).
    let layout = PyramidLayout::new(512, 512, 4).unwrap();
    let planes: u64 = (0..layout.count() as i32)
        .map(|i| {
            let size = (512.0 * 2f64.powf(-i as f64 / 4.0)).round().max(1.0) as u64;
            let mut side = 512u64;
            while side / 2 >= size && side > 1 {
                side /= 2;
            }
            (side * side).div_ceil(2) * 2 * 4 // padded to an even count (the 1×1 planes)
        })
        .sum();
    assert_eq!(bytes[0] - bytes[1], planes + 16 * (layout.count() as u64 + 1), "stack planes and their table");
}

#[test]
fn stage_timer_names_the_pyramid_stages() {
    let ctx = gpu();
    let field = rough_field(64, 64, 7);
    let pyr = HeightPyramid::new(&ctx, 64, 64, (64, 64), 4, PyramidMode::Stack, false).unwrap();
    pyr.upload(&ctx, &field).unwrap();
    let mut timer = StageTimer::new(&ctx, 16).unwrap();
    let stages = ctx
        .submit_and_wait(|cmd| {
            let mut rec = Recorder::new(&ctx, cmd, Some(&mut timer));
            pyr.record(&mut rec);
            Ok(rec.stages().to_vec())
        })
        .unwrap();
    assert_eq!(stages, ["pyramid.decimate", "pyramid.synthesize"]);
    assert!(timer.supported(), "lavapipe supports timestamps");
    let t = timer.timings(&ctx).unwrap();
    let names: Vec<_> = t.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["pyramid.decimate", "pyramid.synthesize"]);
    assert!(t.iter().all(|(_, ms)| ms.is_finite() && *ms >= 0.0), "{t:?}");
    eprintln!("timings ({}): {t:?}", ctx.info().name);
    timer.destroy(&ctx);
    pyr.destroy(&ctx);
}

/// Stage `pyramid.max` against its CPU twin (`reference::max::build`), exactly (maxima of the
/// same f32 values): a non-square field of thin spikes on ground below zero, recorded by the
/// renderer of a scene with indirect light; and the renderer leaves the stage (and the pass)
/// out on a periodic field.
#[test]
fn max_pyramid_equals_its_twin_exactly() {
    use hfgi::scene::generators::Generator;
    let ctx = gpu();
    let mut field = Generator::Spikes { seed: 3, count: 40, height: 0.2 }.generate(77, 50).unwrap();
    let data: Vec<f32> = field.data().iter().map(|h| h - 30.0).collect();
    field = hfgi::scene::HeightField::new("spikes below zero", 77, 50, data, 4096).unwrap();
    let mut scene = common::scenes::scene(field.clone());
    scene.gi.azimuths = 8;
    scene.gi.bounces = 1;
    scene.gi.radial_probes = 2;
    let mut r = hfgi::frame::Renderer::new(&ctx, &scene).unwrap();
    let stages = common::record_frame(&ctx, &mut r);
    assert!(stages.iter().any(|s| s == "pyramid.max"), "{stages:?}");
    let max = r.indirect.as_ref().and_then(|i| i.max.as_ref()).expect("the scene uses the bound");
    let gpu_data = max.read(&ctx).unwrap();
    let z0 = r.height_origin();
    let rel: Vec<f32> = field.data().iter().map(|h| h - z0).collect();
    let (layout, cpu) = hfgi::reference::max::build(&rel, 77, 50);
    assert_eq!(max.layout(), &layout);
    assert_eq!(gpu_data.len(), cpu.len());
    let differ = gpu_data.iter().zip(&cpu).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} of {} values differ", cpu.len());
    r.destroy(&ctx);

    scene.wrap = true;
    let r = hfgi::frame::Renderer::new(&ctx, &scene).unwrap();
    assert!(r.indirect.as_ref().is_some_and(|i| i.max.is_none()), "no max pyramid with wrap");
    assert!(!r.plan_next().names().contains(&"pyramid.max"));
    r.destroy(&ctx);
}

/// An f16 stack (the radiance stack's storage, one channel of heights here) against the f64
/// twin's planes, within a half's rounding. With even plane widths every word's two B-splines
/// share their fetches (glsl/pyramid/synthesize.comp.glsl, HFGI_PAIRS; docs/performance.md §34;
/// the levels between two plane sizes put the second window one level texel further on some
/// words and not on others); with odd widths, or planes coarser than their levels (sub-sampled),
/// each value is computed alone. Every plane is checked, padding excluded.
#[test]
fn f16_stack_matches_cpu_paired_and_alone() {
    use hfgi::frame::pyramid::{LevelsMemory, PyramidKind};
    use hfgi::scene::model::Storage;
    let gpu = gpu();
    let ctx: &hfgi::vk::Context = &gpu;
    let kind = PyramidKind { stack_storage: Storage::F16, ..PyramidKind::HEIGHTS };
    for (w, h, sub, what) in
        [(64usize, 40usize, 1usize, "paired"), (50, 36, 1, "planes of 25: alone"), (64, 40, 2, "sub-sampled: alone")]
    {
        let work = (w.div_ceil(sub), h.div_ceil(sub));
        let field = rough_field(w, h, (w * 7 + h) as u32);
        let (lo, hi) = field.range();
        let own = LevelsMemory::Own { tail: 0 };
        let pyr = HeightPyramid::with_kind(ctx, w, h, work, 4, PyramidMode::Stack, false, kind, None, own).unwrap();
        assert_eq!(pyr.synthesizes_pairs(), what == "paired", "{w}×{h} work {work:?} ({what})");
        build(ctx, &pyr, &field);
        let cpu = CpuPyramid::build(&field, work, 4, false, true).unwrap();
        let stack = cpu.stack.as_ref().unwrap();
        let got = pyr.read_stack_all(ctx).unwrap().unwrap();
        let planes = pyr.layout().stack_planes(work, pyr.stack_levels());
        let mut worst = 0.0f64;
        for (i, p) in planes[..pyr.stack_levels()].iter().enumerate() {
            let (offset, count) = (p[2] as usize, (p[0] * p[1]) as usize);
            for (k, (g, c)) in got[offset..offset + count].iter().zip(&stack[i]).enumerate() {
                // A half's rounding (2⁻¹¹ relative) plus the f32 pipeline's 1e-4 of the range.
                let (err, tol) = ((*g as f64 - c).abs(), c.abs() * 2f64.powi(-11) + 1e-4 * (hi - lo) as f64);
                assert!(err <= tol, "{w}×{h} work {work:?} ({what}): plane {i} value {k}: {g} vs {c}");
                worst = worst.max(err / tol);
            }
        }
        eprintln!("{w}×{h} work {work:?} ({what}): worst error / tolerance {worst:.3}");
        pyr.destroy(ctx);
    }
}
