//! Dynamic height fields (docs/dynamic.md): the GPU water step against its f64 CPU twin,
//! volume conservation, stability, the moving-bumps generator, the `[animation]` scene table, a
//! water animation through the `Renderer`, and `hfgi animate`.
//!
//! Tolerance GPU vs CPU water: max |GPU − CPU| ≤ 1e-4 × amplitude (the initial bump's peak, 1,
//! times `scale`) after 50 steps, on heights and displacements. Conservation: |ΣzΔ| / Σz₀ ≤ 1e-5
//! on the GPU (f32 state, summed in f64) and ≤ 1e-12 on the CPU.

mod common;

use ash::vk as raw;
use common::scenes::scene;
use common::{gpu, max_abs_diff};
use gpu_allocator::MemoryLocation;
use hfgi::error::Error;
use hfgi::frame::pyramid::STAGE_DECIMATE;
use hfgi::frame::water::{WaterSim, STAGE_STEP};
use hfgi::frame::Renderer;
use hfgi::reference::water::{self as cpu_water, WaterCpu};
use hfgi::scene::animated::{
    max_stable_speed, Animation, Boundary, BumpParams, BumpShape, MovingBumps, Rain, WaterParams,
};
use hfgi::scene::file::parse_scene;
use hfgi::scene::HeightField;
use hfgi::vk::{memory, Buffer, Context, Recorder};

/// A Gaussian bump of peak `amp` centred off-centre, on zero.
fn bump(w: usize, h: usize, amp: f32) -> Vec<f32> {
    let (cx, cy, s) = (w as f32 * 0.37, h as f32 * 0.55, 3.0f32);
    (0..w * h)
        .map(|k| {
            let (dx, dy) = ((k % w) as f32 - cx, (k / w) as f32 - cy);
            amp * (-(dx * dx + dy * dy) / (2.0 * s * s)).exp()
        })
        .collect()
}

fn heights_buffer(ctx: &Context, w: usize, h: usize) -> Buffer {
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    Buffer::new(ctx, "test.water.heights", (w * h * 4) as u64, usage, MemoryLocation::GpuOnly).unwrap()
}

/// Runs `steps` GPU steps in one command buffer; returns (heights, displacement).
fn run_gpu(ctx: &Context, sim: &mut WaterSim, out: &Buffer, steps: usize) -> (Vec<f32>, Vec<f32>) {
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, None);
        for _ in 0..steps {
            sim.record_step(&mut rec, out)?;
        }
        Ok(())
    })
    .unwrap();
    let (w, h) = sim.size();
    (memory::download_f32(ctx, out, 0, (w * h) as u64).unwrap(), sim.read_displacement(ctx).unwrap())
}

fn rain(rate: f64) -> Rain {
    Rain { rate, amplitude: 0.5, radius: 4.0, seed: 9 }
}

#[test]
fn water_gpu_matches_cpu_after_50_steps() {
    let ctx = gpu();
    let (w, h) = (64, 48);
    let initial = bump(w, h, 1.0);
    let out = heights_buffer(&ctx, w, h);
    for boundary in [Boundary::Reflective, Boundary::Periodic] {
        let params = WaterParams {
            speed: 0.6,
            damping: 0.02,
            steps_per_frame: 1,
            rest_level: 2.0,
            scale: 0.5,
            boundary,
            rain: rain(2.0),
        };
        let mut sim = WaterSim::new(&ctx, w, h, params.clone(), &initial).unwrap();
        let mut cpu = WaterCpu::new(w, h, params.clone(), &initial).unwrap();
        let drops: usize = (1..=50).map(|s| params.drops_at(s, w, h).len()).sum();
        let (heights, z) = run_gpu(&ctx, &mut sim, &out, 50);
        for _ in 0..50 {
            cpu.step();
        }
        assert_eq!((sim.steps(), cpu.steps()), (50, 50));
        let tol = 1e-4 * params.scale;
        let e_h = max_abs_diff(&heights, &cpu.heights());
        let e_z = max_abs_diff(&z, cpu.displacement());
        let peak = cpu.displacement().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        eprintln!(
            "water {boundary:?} 64×48, 50 steps, {drops} drops: max |GPU − CPU| heights {e_h:.2e}, \
             displacement {e_z:.2e} (tolerance {tol:.1e}); peak |z| {peak:.3}"
        );
        assert!(drops > 20, "the rain schedule should drop something: {drops}");
        assert!(e_h <= tol, "{boundary:?}: heights differ by {e_h:e} > {tol:e}");
        assert!(e_z <= 1e-4, "{boundary:?}: displacements differ by {e_z:e} > 1e-4");
        assert!(peak > 0.05, "the surface should still move: peak {peak}");
        sim.destroy(&ctx);
    }
    out.destroy(&ctx);
}

#[test]
fn water_conserves_volume_without_rain() {
    let ctx = gpu();
    let (w, h) = (64, 48);
    let initial = bump(w, h, 1.0);
    let v0: f64 = initial.iter().map(|&v| f64::from(v)).sum();
    let out = heights_buffer(&ctx, w, h);
    for (boundary, damping) in [(Boundary::Reflective, 0.0), (Boundary::Periodic, 0.0), (Boundary::Reflective, 0.05)] {
        let params = WaterParams {
            speed: 0.65,
            damping,
            steps_per_frame: 1,
            rest_level: 0.0,
            scale: 1.0,
            boundary,
            rain: rain(0.0),
        };
        let mut sim = WaterSim::new(&ctx, w, h, params.clone(), &initial).unwrap();
        let mut cpu = WaterCpu::new(w, h, params, &initial).unwrap();
        let (heights, z) = run_gpu(&ctx, &mut sim, &out, 400);
        for _ in 0..400 {
            cpu.step();
        }
        let vg: f64 = z.iter().map(|&v| f64::from(v)).sum();
        let vh: f64 = heights.iter().map(|&v| f64::from(v)).sum();
        let (rg, rh, rc) = ((vg - v0).abs() / v0, (vh - v0).abs() / v0, (cpu.volume() - v0).abs() / v0);
        eprintln!(
            "volume {boundary:?} damping {damping}, 400 steps: relative drift GPU {rg:.2e} (heights {rh:.2e}), CPU {rc:.2e}"
        );
        assert!(rg <= 1e-5 && rh <= 1e-5, "{boundary:?}: GPU volume drift {rg:e} / {rh:e} > 1e-5");
        assert!(rc <= 1e-12, "{boundary:?}: CPU volume drift {rc:e}");
        sim.destroy(&ctx);
    }
    out.destroy(&ctx);
}

#[test]
fn water_stays_bounded_for_2000_steps_and_the_bound_is_sharp() {
    let ctx = gpu();
    let (w, h) = (64, 48);
    let initial = bump(w, h, 1.0);
    let out = heights_buffer(&ctx, w, h);
    for boundary in [Boundary::Reflective, Boundary::Periodic] {
        let params = WaterParams {
            speed: 0.98 * max_stable_speed(0.005),
            damping: 0.005,
            steps_per_frame: 1,
            rest_level: 0.0,
            scale: 1.0,
            boundary,
            rain: rain(1.0),
        };
        let mut sim = WaterSim::new(&ctx, w, h, params, &initial).unwrap();
        let (_, z) = run_gpu(&ctx, &mut sim, &out, 2000);
        let mean = z.iter().map(|&v| f64::from(v)).sum::<f64>() / z.len() as f64;
        let mean0 = initial.iter().map(|&v| f64::from(v)).sum::<f64>() / z.len() as f64;
        let dev = z.iter().fold(0.0f64, |m, &v| m.max((f64::from(v) - mean).abs()));
        eprintln!(
            "stability {boundary:?}, speed 0.98·max, 2000 steps, {} drops: max |z − mean| {dev:.3}, mean {mean:.4} (initially {mean0:.4})",
            (1..=2000).map(|s| sim.params().drops_at(s, w, h).len()).sum::<usize>()
        );
        assert!(z.iter().all(|v| v.is_finite()) && dev < 10.0, "{boundary:?}: unbounded: max |z − mean| = {dev}");
        // Zero-volume drops: the rain does not drift the mean level (edges clip a few drops).
        assert!((mean - mean0).abs() < 0.1, "{boundary:?}: the mean drifted from {mean0} to {mean}");
        sim.destroy(&ctx);
    }
    out.destroy(&ctx);

    // The CPU scheme just inside and just outside k < (2 − δ)/4 (bypassing validation): noise on
    // a periodic even grid excites the checkerboard mode, which grows only outside the bound.
    let (w, h) = (16, 16);
    let noise: Vec<f64> = (0..w * h).map(|k| ((k * 7919 % 101) as f64 / 101.0) - 0.5).collect();
    let growth = |k: f64, damping: f64| {
        let (mut cur, mut prev) = (noise.clone(), noise.clone());
        for _ in 0..2000 {
            cpu_water::step(w, h, true, k, 1.0 - damping, &mut cur, &mut prev, &[]);
            std::mem::swap(&mut cur, &mut prev);
        }
        cur.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    };
    for damping in [0.0, 0.1] {
        let limit = (2.0 - damping) / 4.0;
        let (inside, outside) = (growth(0.98 * limit, damping), growth(1.02 * limit, damping));
        eprintln!("CPU, damping {damping}: k = 0.98·limit → max |z| {inside:.3}; k = 1.02·limit → {outside:.3e}");
        assert!(inside < 2.0, "damping {damping}: bounded inside the limit, got {inside}");
        assert!(outside > 1e3, "damping {damping}: should blow up outside the limit, got {outside}");
    }
}

#[test]
fn water_parameters_are_validated_with_typed_errors() {
    let ctx = gpu();
    let ok = WaterParams::default();
    let bad = [
        (WaterParams { speed: 0.71, damping: 0.0, ..ok.clone() }, "animation.speed"),
        (WaterParams { speed: 0.70, damping: 0.1, ..ok.clone() }, "animation.speed"),
        (WaterParams { speed: -0.1, ..ok.clone() }, "animation.speed"),
        (WaterParams { damping: 1.5, ..ok.clone() }, "animation.damping"),
        (WaterParams { steps_per_frame: 0, ..ok.clone() }, "animation.steps_per_frame"),
        (WaterParams { scale: 0.0, ..ok.clone() }, "animation.scale"),
        (WaterParams { rain: Rain { rate: 5.0, ..Rain::default() }, ..ok.clone() }, "animation.rain_rate"),
        (WaterParams { rain: Rain { radius: 0.5, ..Rain::default() }, ..ok.clone() }, "animation.drop_radius"),
        (WaterParams { rest_level: f64::NAN, ..ok.clone() }, "animation.rest_level"),
    ];
    for (p, key) in bad {
        match WaterSim::new(&ctx, 8, 8, p, &[0.0; 64]) {
            Err(Error::InvalidParameter { name, value, expected }) => {
                assert_eq!(name, key, "{value}: {expected}");
                if key == "animation.speed" {
                    assert!(expected.contains("stable"), "{expected}");
                }
            }
            Err(e) => panic!("{key}: wrong error {e}"),
            Ok(_) => panic!("{key}: accepted"),
        }
    }
    assert!(matches!(WaterSim::new(&ctx, 8, 8, ok.clone(), &[0.0; 63]), Err(Error::InvalidParameter { .. })));
    let mut nan = vec![0.0; 64];
    nan[9] = f32::NAN;
    assert!(matches!(WaterSim::new(&ctx, 8, 8, ok.clone(), &nan), Err(Error::NonFinite { x: 1, y: 1, .. })));
    assert!(matches!(WaterSim::new(&ctx, 1, 8, ok.clone(), &[0.0; 8]), Err(Error::FieldSize { .. })));
    // A heights buffer that is too small is an error, not a GPU overrun.
    let mut sim = WaterSim::new(&ctx, 8, 8, ok, &[0.0; 64]).unwrap();
    let small = heights_buffer(&ctx, 4, 4);
    let r = ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, None);
        sim.record_step(&mut rec, &small)
    });
    assert!(matches!(r, Err(Error::InvalidParameter { .. })), "{r:?}");
    small.destroy(&ctx);
    sim.destroy(&ctx);
}

#[test]
fn rain_is_deterministic_and_follows_the_rate() {
    let p = WaterParams { rain: Rain { rate: 1.0, amplitude: 2.0, radius: 3.0, seed: 5 }, ..Default::default() };
    let n: usize = (1..=4000).map(|s| p.drops_at(s, 64, 48).len()).sum();
    assert!((3700..=4300).contains(&n), "rate 1 over 4000 steps gave {n} drops");
    assert_eq!(p.drops_at(17, 64, 48), p.drops_at(17, 64, 48));
    for d in (1..200).flat_map(|s| p.drops_at(s, 64, 48)) {
        assert!((0.0..=63.0).contains(&d.x) && (0.0..=47.0).contains(&d.y), "{d:?}");
        assert!((1.0..2.0).contains(&d.amplitude) && d.radius == 3.0, "{d:?}");
    }
    let other = WaterParams { rain: Rain { seed: 6, ..p.rain.clone() }, ..p.clone() };
    assert!((1..50).any(|s| p.drops_at(s, 64, 48) != other.drops_at(s, 64, 48)));
    let dry = WaterParams { rain: Rain { rate: 0.0, ..p.rain.clone() }, ..p };
    assert!((1..1000).all(|s| dry.drops_at(s, 64, 48).is_empty()));
}

fn flat(w: usize, h: usize) -> HeightField {
    HeightField::new("flat", w, h, vec![0.0; w * h], 16384).unwrap()
}

#[test]
fn bumps_are_deterministic_move_and_loop() {
    for shape in [BumpShape::Gaussian, BumpShape::Cosine] {
        for wrap in [false, true] {
            let p = BumpParams { count: 1, shape, period: 40, ..Default::default() };
            let a = MovingBumps::new(p.clone(), flat(48, 40), 0.5, wrap).unwrap();
            let b = MovingBumps::new(p.clone(), flat(48, 40), 0.5, wrap).unwrap();
            let f0 = a.heights_at(0).unwrap();
            assert_eq!(f0, b.heights_at(0).unwrap(), "{shape} wrap={wrap}: not deterministic");
            assert_eq!(a.heights_at(7).unwrap(), a.heights_at(7).unwrap());
            // Peak = amplitude · w · texel size · gain (gain in [0.6, 1]).
            let peak = f0.range().1 as f64;
            let full = p.amplitude * 48.0 * 0.5;
            assert!(peak > 0.5 * full && peak <= full * 1.0001, "{shape}: peak {peak} vs {full}");
            // It moves: the centre follows the path, and the field changes.
            let (c0, c10) = (a.centres_at(0.0)[0], a.centres_at(10.0)[0]);
            let moved = ((c0[0] - c10[0]).powi(2) + (c0[1] - c10[1]).powi(2)).sqrt();
            assert!(moved > 1.0, "{shape} wrap={wrap}: moved only {moved} texels in 10 frames");
            assert_ne!(f0, a.heights_at(10).unwrap());
            // Closed paths: frame `period` is frame 0 again (to rounding of the phase).
            let f40 = a.heights_at(40).unwrap();
            let d = f0.data().iter().zip(f40.data()).fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
            assert!(d < 1e-5, "{shape} wrap={wrap}: frame 40 differs from frame 0 by {d}");
        }
    }
    // The base is kept: bumps add to it.
    let base = HeightField::new("ramp", 32, 32, (0..1024).map(|k| (k % 32) as f32).collect(), 16384).unwrap();
    let p = BumpParams { amplitude: 0.0, ..Default::default() };
    assert_eq!(MovingBumps::new(p, base.clone(), 1.0, false).unwrap().heights_at(3).unwrap(), base);
    // Different seeds, different paths.
    let a = MovingBumps::new(BumpParams { seed: 1, ..Default::default() }, flat(32, 32), 1.0, false).unwrap();
    let b = MovingBumps::new(BumpParams { seed: 2, ..Default::default() }, flat(32, 32), 1.0, false).unwrap();
    assert_ne!(a.heights_at(0).unwrap(), b.heights_at(0).unwrap());
    // Validation names the key.
    for (p, key) in [
        (BumpParams { count: 0, ..Default::default() }, "animation.count"),
        (BumpParams { radius: 0.0, ..Default::default() }, "animation.radius"),
        (BumpParams { period: 1, ..Default::default() }, "animation.period"),
        (BumpParams { travel: 1.5, ..Default::default() }, "animation.travel"),
        (BumpParams { amplitude: f64::INFINITY, ..Default::default() }, "animation.amplitude"),
    ] {
        match MovingBumps::new(p, flat(8, 8), 1.0, false) {
            Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, key),
            other => panic!("{key}: {:?}", other.map(|_| ())),
        }
    }
    let b = MovingBumps::new(BumpParams::default(), flat(8, 8), 1.0, false).unwrap();
    assert!(b.heights_at_time(f64::NAN).is_err());
}

fn parse(text: &str, overrides: &[&str]) -> hfgi::Result<hfgi::scene::model::Scene> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_scene(text, std::path::Path::new("."), "test.toml", &o)
}

fn scene_err(text: &str, overrides: &[&str]) -> (Option<String>, String) {
    match parse(text, overrides) {
        Err(Error::SceneFile { key, message, .. }) => (key, message),
        Err(e) => panic!("wrong error type: {e}"),
        Ok(_) => panic!("accepted: {text} {overrides:?}"),
    }
}

#[test]
fn animation_table_parses_validates_and_overrides() {
    let small = ["heightfield.size=16"];
    assert_eq!(parse("", &small).unwrap().animation, Animation::None);
    let water = hfgi::scene::file::load_scene(std::path::Path::new("scenes/water.toml"), &[]).unwrap();
    match &water.animation {
        Animation::Water(p) => {
            assert!(p.speed < max_stable_speed(p.damping) && p.rain.rate > 0.0);
            assert_eq!(p.boundary, Boundary::Reflective);
        }
        other => panic!("water.toml: {other:?}"),
    }
    assert_eq!(water.field.width(), 128);
    let bumps = hfgi::scene::file::load_scene(std::path::Path::new("scenes/bumps.toml"), &[]).unwrap();
    assert!(matches!(bumps.animation, Animation::Bumps(BumpParams { count: 5, .. })), "{:?}", bumps.animation);

    // --set animation.kind=water on a static scene gives the defaults; wrap picks the boundary.
    let s = parse("", &["heightfield.size=16", "animation.kind=water", "heightfield.wrap=true"]).unwrap();
    assert_eq!(s.animation, Animation::Water(WaterParams { boundary: Boundary::Periodic, ..WaterParams::default() }));
    let s = parse("[animation]\nkind = \"bumps\"\nshape = \"cosine\"\n", &small).unwrap();
    assert!(matches!(s.animation, Animation::Bumps(BumpParams { shape: BumpShape::Cosine, .. })));
    // kind = none ignores the other keys (so an override can switch an animation off).
    let s = parse("[animation]\nkind = \"water\"\nspeed = 0.3\n", &["heightfield.size=16", "animation.kind=none"]);
    assert_eq!(s.unwrap().animation, Animation::None);

    // Errors name the key.
    let (key, msg) = scene_err("[animation]\nkind = \"water\"\nsped = 0.3\n", &small);
    assert_eq!(key.as_deref(), Some("animation.sped"), "{msg}");
    assert!(msg.contains("unknown key") && msg.contains("speed"), "{msg}");
    let (key, msg) = scene_err("[animation]\nkind = \"water\"\nspeed = 0.9\n", &small);
    assert_eq!(key.as_deref(), Some("animation.speed"), "{msg}");
    assert!(msg.contains("0.9") && msg.contains("stable"), "{msg}");
    let (key, msg) = scene_err("[animation]\nkind = \"lava\"\n", &small);
    assert_eq!(key.as_deref(), Some("animation.kind"), "{msg}");
    assert!(msg.contains("lava") && msg.contains("water") && msg.contains("bumps"), "{msg}");
    let (key, msg) = scene_err("[animation]\nkind = \"water\"\ncount = 3\n", &small);
    assert_eq!(key.as_deref(), Some("animation.count"), "{msg}");
    assert!(msg.contains("bumps"), "{msg}");
    let (key, msg) = scene_err("", &["heightfield.size=16", "animation.kind=bumps", "animation.period=1"]);
    assert_eq!(key.as_deref(), Some("animation.period"), "{msg}");
    assert!(msg.contains("--set animation.period=1"), "{msg}");
    let (key, msg) = scene_err("[animation]\nkind = \"bumps\"\nshape = \"square\"\n", &small);
    assert_eq!(key.as_deref(), Some("animation.shape"), "{msg}");
    assert!(msg.contains("square") && msg.contains("gaussian"), "{msg}");
    let (key, msg) = scene_err("[animation]\nkind = \"water\"\nsteps_per_frame = \"two\"\n", &small);
    assert_eq!(key.as_deref(), Some("animation.steps_per_frame"), "{msg}");
    let (key, msg) = scene_err("[animation]\nkind = \"water\"\nrain_rate = 9\n", &small);
    assert_eq!(key.as_deref(), Some("animation.rain_rate"), "{msg}");
}

#[test]
fn sixty_water_frames_through_the_renderer() {
    let ctx = gpu();
    let n = 32;
    let initial = bump(n, n, 1.5);
    let field = HeightField::new("pond", n, n, initial.clone(), 16384).unwrap();
    let mut s = scene(field);
    s.gi.azimuths = 8;
    s.gi.key_light_azimuths = 2;
    s.gi.bounces = 1;
    s.camera.width = 48;
    s.camera.height = 32;
    let params = WaterParams { steps_per_frame: 1, rain: rain(0.5), ..WaterParams::default() };
    let mut renderer = Renderer::new(&ctx, &s).unwrap();
    let view = hfgi::frame::view::ViewPass::for_renderer(&ctx, &s, &renderer, &Default::default()).unwrap();
    let mut sim = WaterSim::new(&ctx, n, n, params.clone(), &initial).unwrap();
    let mut cpu = WaterCpu::new(n, n, params, &initial).unwrap();
    let before = ctx.pipelines_created();
    let mut first = None;
    for f in 0..60 {
        let stages = ctx
            .submit_and_wait(|cmd| {
                let mut rec = Recorder::new(&ctx, cmd, None);
                sim.record_step(&mut rec, renderer.heights_buffer())?;
                renderer.mark_heights_changed();
                renderer.record(&mut rec);
                view.record(&mut rec);
                Ok(rec.stages().to_vec())
            })
            .unwrap();
        cpu.step();
        assert_eq!(&stages[..2], &[STAGE_STEP.to_string(), STAGE_DECIMATE.to_string()], "frame {f}");
        for st in ["shade.direct", "indirect.scan", "view.raster"] {
            assert!(stages.iter().any(|x| x == st), "frame {f}: no {st} in {stages:?}");
        }
        if f == 0 {
            eprintln!("water frame stages: {stages:?}");
        }
        if f == 0 {
            first = Some(renderer.read_layers(&ctx).unwrap().total);
        }
    }
    assert_eq!(ctx.pipelines_created(), before, "pipelines were created inside the frame loop");
    let st = renderer.stats();
    assert_eq!((st.frames, st.pyramid_builds), (60, 60));
    // The renderer's level 0 holds exactly what the simulation wrote (= the CPU twin).
    let level0 = renderer.pyramid.read_level(&ctx, 0).unwrap();
    let err = max_abs_diff(&level0, &cpu.heights());
    eprintln!("renderer level 0 vs CPU water after 60 frames: max error {err:.2e}");
    assert!(err <= 1e-4 * 1.5, "level 0 differs from the CPU twin by {err:e}");
    let last = renderer.read_layers(&ctx).unwrap().total;
    let change = first.unwrap().iter().zip(&last).map(|(a, b)| (a[1] - b[1]).abs()).fold(0.0f32, f32::max);
    assert!(change > 1e-3, "the shading did not change over 60 frames ({change})");

    // A frame without new heights does not rebuild the pyramid.
    let stages = common::record_frame(&ctx, &mut renderer);
    assert!(!stages.iter().any(|s| s == STAGE_DECIMATE), "rebuilt without a change: {stages:?}");
    assert_eq!((renderer.stats().frames, renderer.stats().pyramid_builds), (61, 60));
    assert_eq!(ctx.pipelines_created(), before);
    eprintln!(
        "60 water frames: {} pipelines created before the loop, {} after; {:?}",
        before,
        ctx.pipelines_created(),
        renderer.stats()
    );
    sim.destroy(&ctx);
    view.destroy(&ctx);
    renderer.destroy(&ctx);
}

#[test]
fn cli_animate_day_moves_sun_sky_and_camera_through_live_inputs() {
    // `scenes/day.toml` at 32² (docs/dynamic.md §4): 4 frames from sunrise to sunset.
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(common::hfgi_exe())
        .args(["animate", "scenes/day.toml", "--frames", "4", "--validation"])
        .args(["--set", "heightfield.size=32", "--set", "gi.azimuths=8", "--set", "animation.day_frames=4"])
        .args(["--set", "camera.width=64", "--set", "camera.height=36", "--out", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    let msg = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{msg}");
    eprintln!("{msg}");
    // The heights never change: one pyramid build; the sun's visibility every frame.
    for needle in ["animation day", "pyramid_builds 1", "inputs.update", "visibility.key_lights", "(4 frames)"] {
        assert!(msg.contains(needle), "missing `{needle}` in:\n{msg}");
    }
    let line = msg.lines().find(|l| l.starts_with("pipelines created")).unwrap();
    let nums: Vec<&str> = line.split(|c: char| !c.is_ascii_digit()).filter(|s| !s.is_empty()).collect();
    assert_eq!(nums[0], nums[1], "{line}");
    let frames: Vec<Vec<u8>> = (0..4)
        .map(|f| image::open(dir.path().join(format!("frame_{f:04}.png"))).unwrap().to_rgb8().into_raw())
        .collect();
    for f in 1..4 {
        assert_ne!(frames[f], frames[f - 1], "frame {f} equals frame {}", f - 1);
    }
}

#[test]
fn cli_animate_writes_pngs_and_a_gif() {
    let dir = tempfile::tempdir().unwrap();
    let gif = dir.path().join("anim.gif");
    let out = std::process::Command::new(common::hfgi_exe())
        .args([
            "animate",
            "scenes/water.toml",
            "--frames",
            "3",
            "--set",
            "heightfield.size=32",
            "--set",
            "gi.azimuths=8",
            "--set",
            "animation.rain_rate=2",
            "--set",
            "camera.width=64",
            "--set",
            "camera.height=40",
            "--out",
            dir.path().join("frames").to_str().unwrap(),
            "--gif",
            gif.to_str().unwrap(),
            "--fps",
            "10",
            "--validation",
        ])
        .output()
        .unwrap();
    let msg = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{msg}");
    eprintln!("{msg}");
    for f in 0..3 {
        let img = image::open(dir.path().join(format!("frames/frame_{f:04}.png"))).unwrap();
        assert_eq!((img.width(), img.height()), (64, 40), "frames are the camera's view image");
    }
    assert!(!dir.path().join("frames/frame_0003.png").exists());
    let bytes = std::fs::read(&gif).unwrap();
    assert!(bytes.starts_with(b"GIF89a"), "not a GIF");
    let decoder = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(bytes)).unwrap();
    let frames = image::AnimationDecoder::into_frames(decoder).collect_frames().unwrap();
    assert_eq!(frames.len(), 3);
    for needle in
        ["frames: 3", "pyramid_builds 3", "water.step", "pyramid.decimate", "frame (GI submit, wall)", "median"]
    {
        assert!(msg.contains(needle), "missing `{needle}` in:\n{msg}");
    }
    let line = msg.lines().find(|l| l.starts_with("pipelines created")).unwrap();
    let nums: Vec<&str> = line.split(|c: char| !c.is_ascii_digit()).filter(|s| !s.is_empty()).collect();
    assert_eq!(nums[0], nums[1], "{line}");

    // Bad input is an error with context, not a panic.
    let run = |args: &[&str]| {
        let o = std::process::Command::new(common::hfgi_exe()).args(args).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (ok, msg) = run(&["animate", "scenes/default.toml", "--frames", "2", "--set", "heightfield.size=16"]);
    assert!(!ok && msg.contains("animation") && !msg.contains("panicked"), "{msg}");
    let (ok, msg) = run(&["animate", "scenes/water.toml", "--frames", "2", "--set", "animation.speed=2"]);
    assert!(!ok && msg.contains("animation.speed") && !msg.contains("panicked"), "{msg}");
    let (ok, msg) = run(&["animate", "scenes/water.toml", "--frames", "0"]);
    assert!(!ok && msg.contains("--frames") && !msg.contains("panicked"), "{msg}");
}

#[test]
fn heights_from_a_host_gpu_image() {
    // A host engine keeps its heights in an R32_SFLOAT image: the renderer copies them in the
    // host's command buffer (stage `heights.copy`) and rebuilds the pyramid from them.
    let ctx = gpu();
    let (w, h) = (24usize, 20usize);
    let data: Vec<f32> = (0..w * h).map(|k| ((k % w) as f32 * 0.37).sin() * 3.0 + (k / w) as f32 * 0.1).collect();
    let mut s = scene(HeightField::new("zero", w, h, vec![0.0; w * h], 16384).unwrap());
    s.gi.azimuths = 8;
    let mut renderer = Renderer::new(&ctx, &s).unwrap();
    let usage = raw::ImageUsageFlags::TRANSFER_SRC | raw::ImageUsageFlags::TRANSFER_DST | raw::ImageUsageFlags::STORAGE;
    let extent = raw::Extent2D { width: w as u32, height: h as u32 };
    let image = hfgi::vk::Image::new(
        &ctx,
        "test.host.heights",
        extent,
        raw::Format::R32_SFLOAT,
        usage,
        raw::SampleCountFlags::TYPE_1,
    )
    .unwrap();
    let staging = Buffer::new(
        &ctx,
        "test.staging",
        (w * h * 4) as u64,
        raw::BufferUsageFlags::TRANSFER_SRC | raw::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )
    .unwrap();
    memory::upload_f32(&ctx, &staging, 0, &data).unwrap();
    // Bad inputs are typed errors, not panics.
    let bad = ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, None);
        let e1 = renderer.record_heights_from_image(
            &mut rec,
            image.raw,
            raw::Format::R8_UNORM,
            (w as u32, h as u32),
            raw::ImageLayout::GENERAL,
        );
        let e2 = renderer.record_heights_from_image(
            &mut rec,
            image.raw,
            raw::Format::R32_SFLOAT,
            (3, 3),
            raw::ImageLayout::GENERAL,
        );
        Ok((e1.is_err(), e2.is_err(), rec.stages().to_vec()))
    });
    let (e1, e2, none) = bad.unwrap();
    assert!(e1 && e2 && none.is_empty());
    let stages = ctx
        .submit_and_wait(|cmd| {
            let d = ctx.device();
            let range = hfgi::vk::memory::color_range();
            let to_dst = [raw::ImageMemoryBarrier2::default()
                .dst_stage_mask(raw::PipelineStageFlags2::COPY)
                .dst_access_mask(raw::AccessFlags2::TRANSFER_WRITE)
                .old_layout(raw::ImageLayout::UNDEFINED)
                .new_layout(raw::ImageLayout::TRANSFER_DST_OPTIMAL)
                .image(image.raw)
                .subresource_range(range)];
            unsafe { d.cmd_pipeline_barrier2(cmd, &raw::DependencyInfo::default().image_memory_barriers(&to_dst)) };
            let region = raw::BufferImageCopy::default()
                .image_subresource(raw::ImageSubresourceLayers {
                    aspect_mask: raw::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(raw::Extent3D { width: w as u32, height: h as u32, depth: 1 });
            unsafe {
                d.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    image.raw,
                    raw::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            let to_src = [raw::ImageMemoryBarrier2::default()
                .src_stage_mask(raw::PipelineStageFlags2::COPY)
                .src_access_mask(raw::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(raw::PipelineStageFlags2::COPY)
                .dst_access_mask(raw::AccessFlags2::TRANSFER_READ)
                .old_layout(raw::ImageLayout::TRANSFER_DST_OPTIMAL)
                .new_layout(raw::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .image(image.raw)
                .subresource_range(range)];
            unsafe { d.cmd_pipeline_barrier2(cmd, &raw::DependencyInfo::default().image_memory_barriers(&to_src)) };
            let mut rec = Recorder::new(&ctx, cmd, None);
            renderer.record_heights_from_image(
                &mut rec,
                image.raw,
                raw::Format::R32_SFLOAT,
                (w as u32, h as u32),
                raw::ImageLayout::TRANSFER_SRC_OPTIMAL,
            )?;
            renderer.record(&mut rec);
            Ok(rec.stages().to_vec())
        })
        .unwrap();
    eprintln!("host image frame: {stages:?}");
    assert_eq!(&stages[..2], &["heights.copy".to_string(), STAGE_DECIMATE.to_string()]);
    let level0 = renderer.pyramid.read_level(&ctx, 0).unwrap();
    assert_eq!(level0, data, "level 0 is the host image");
    staging.destroy(&ctx);
    image.destroy(&ctx);
    renderer.destroy(&ctx);
}
