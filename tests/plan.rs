//! The frame plan (docs/plan.md): for each rule, the exact planned stage list, then the frame
//! rendered on the GPU — the recorded stages (`Recorder::stages`) and the timed stages
//! (`StageTimer::timings`) must equal the plan exactly. And `hfgi plan` needs no Vulkan device.

mod common;

use common::scenes::{key_light, scene};
use common::{gpu, rough_field};
use hfgi::frame::plan::{plan, FrameState, Plan};
use hfgi::frame::Renderer;
use hfgi::scene::model::{Albedo, Environment, GlossyPyramid, PyramidMode, Scene};
use hfgi::vk::{Context, Recorder, StageTimer};

const PD: &str = "pyramid.decimate";
const PS: &str = "pyramid.synthesize";
const PM: &str = "pyramid.max";
const VE: &str = "visibility.environment";
const VK: &str = "visibility.key_lights";
const SD: &str = "shade.direct";
const RG: &str = "radiance.gather";
const RD: &str = "radiance.decimate";
const RS: &str = "radiance.synthesize";
const IS: &str = "indirect.scan";
const ISH: &str = "indirect.shade";

/// A small scene (24², 8 azimuths): sky + one key light, albedo 0.7, no bounces, no radial
/// probes (so no `pyramid.max`: `synthesize_stages_only_in_stack_mode` and the `hfgi plan` test
/// cover it, the latter with the `default` preset's probes).
fn base() -> Scene {
    let mut s = scene(rough_field(24, 24, 11));
    s.gi.azimuths = 8;
    s.gi.radial_probes = 0;
    s.gi.radial_probes_later = 0;
    s
}

fn zero_environment() -> Environment {
    Environment { sh: vec![[0.0; 3]; 16] }
}

/// `[heights stages] + [shade.direct] + bounces × [(gather), decimate, (synthesize), scan,
/// shade]`: the gather only for bounce 1 (bounce `b`'s shade writes bounce `b + 1`'s level 0).
fn frame_stages(heights: &[&'static str], direct: bool, bounces: u32, synth: bool) -> Vec<&'static str> {
    let mut v = heights.to_vec();
    if direct {
        v.push(SD);
    }
    for b in 0..bounces {
        if b == 0 {
            v.push(RG);
        }
        v.push(RD);
        if synth {
            v.push(RS);
        }
        v.extend([IS, ISH]);
    }
    v
}

/// Plans and renders `expected.len()` frames of `scene` (static after the first, or with new
/// heights on the frames in `changed`); checks that the pure plan, `Renderer::plan_next`, the
/// recorded stages and the timestamps all equal `expected[f]` exactly. Returns the plans.
fn check_frames(ctx: &Context, what: &str, scene: &Scene, changed: &[u64], expected: &[Vec<&str>]) -> Vec<Plan> {
    let mut r = Renderer::new(ctx, scene).unwrap();
    let mut timer = StageTimer::new(ctx, 96).unwrap();
    let mut plans = Vec::new();
    for (f, want) in expected.iter().enumerate() {
        let f = f as u64;
        let heights_changed = f == 0 || changed.contains(&f);
        if heights_changed && f > 0 {
            r.mark_heights_changed();
        }
        let p = plan(scene, &FrameState { heights_changed, frame_index: f, ..Default::default() });
        eprintln!("{what}, {p}");
        assert_eq!(p.names(), *want, "{what}: planned stages of frame {f}");
        assert_eq!(r.plan_next(), p, "{what}: Renderer::plan_next of frame {f} differs from plan()");
        let recorded = ctx
            .submit_and_wait(|cmd| {
                let mut rec = Recorder::new(ctx, cmd, Some(&mut timer));
                r.record(&mut rec);
                Ok(rec.stages().to_vec())
            })
            .unwrap();
        assert_eq!(recorded, *want, "{what}: recorded stages of frame {f}");
        let timed: Vec<String> = timer.timings(ctx).unwrap().into_iter().map(|(n, _)| n).collect();
        assert_eq!(timed, *want, "{what}: timed stages of frame {f}");
        plans.push(p);
    }
    let builds = expected.iter().filter(|s| s.contains(&PD)).count() as u64;
    assert_eq!(r.stats().frames, expected.len() as u64, "{what}");
    assert_eq!(r.stats().pyramid_builds, builds, "{what}");
    r.destroy(ctx);
    timer.destroy(ctx);
    plans
}

fn reason<'a>(p: &'a Plan, name: &str) -> &'a str {
    &p.stages.iter().find(|s| s.name == name).unwrap_or_else(|| panic!("no stage {name}")).reason
}

fn omitted<'a>(p: &'a Plan, name: &str) -> &'a str {
    &p.omitted.iter().find(|s| s.name == name).unwrap_or_else(|| panic!("{name} not listed as omitted")).reason
}

fn pass_created(p: &Plan, name: &str) -> (bool, String) {
    let pass = p.passes().iter().find(|x| x.name == name).unwrap_or_else(|| panic!("no pass {name}"));
    (pass.created, pass.reason.clone())
}

#[test]
fn environment_only_key_lights_only_and_both() {
    let ctx = gpu();
    let mut env_only = base();
    env_only.key_lights.clear();
    let p = &check_frames(&ctx, "environment only", &env_only, &[], &[vec![PD, PS, VE, SD]])[0];
    assert!(reason(p, VE).contains("environment light is non-zero"), "{p}");
    assert_eq!(omitted(p, VK), "no key lights");

    let mut keys_only = base();
    keys_only.environment = zero_environment();
    keys_only.key_lights.push(key_light(50.0, 30.0, 4.0, 3.0));
    let p = &check_frames(&ctx, "key lights only", &keys_only, &[], &[vec![PD, PS, VK, SD]])[0];
    assert!(reason(p, VK).starts_with("2 key lights"), "{p}");
    assert!(omitted(p, VE).contains("environment light is zero"), "{p}");
    assert!(pass_created(p, "VisibilityPass").1.contains("2 light sets (2 key lights)"), "{p:?}");

    let p = &check_frames(&ctx, "both", &base(), &[], &[vec![PD, PS, VE, VK, SD]])[0];
    assert!(reason(p, PD).contains("first frame"), "{p}");
    assert!(reason(p, PS).contains("stack mode"), "{p}");

    // No light at all: still the pyramid and the (black) direct shading, no visibility stage.
    let mut dark = base();
    dark.environment = Environment::default();
    dark.key_lights.clear();
    check_frames(&ctx, "no lights", &dark, &[], &[vec![PD, PS, SD]]);
}

#[test]
fn bounces_zero_two_and_a_surface_that_reflects_nothing() {
    let ctx = gpu();
    let mut s = base();
    s.gi.bounces = 0;
    let p = &check_frames(&ctx, "bounces 0", &s, &[], &[vec![PD, PS, VE, VK, SD]])[0];
    assert_eq!(pass_created(p, "IndirectPass"), (false, "gi.bounces = 0".into()));
    assert!(omitted(p, IS).contains("gi.bounces = 0"), "{p}");

    s.gi.bounces = 2;
    let want = frame_stages(&[PD, PS, VE, VK], true, 2, true);
    let p = &check_frames(&ctx, "bounces 2", &s, &[], &[want])[0];
    assert!(pass_created(p, "IndirectPass").0 && pass_created(p, "RadiancePyramid").0);
    let gathers: Vec<&str> = p.stages.iter().filter(|x| x.name == RG).map(|x| x.reason.as_str()).collect();
    assert_eq!(gathers.len(), 1, "{gathers:?}");
    assert!(gathers[0].starts_with("gi.bounces = 2, bounce 1 of 2"), "{gathers:?}");
    let decimates: Vec<&str> = p.stages.iter().filter(|x| x.name == RD).map(|x| x.reason.as_str()).collect();
    assert!(
        decimates[1].starts_with("gi.bounces = 2, bounce 2 of 2") && decimates[1].contains("bounce 1's exit radiance"),
        "{decimates:?}"
    );

    // Albedo 0 everywhere (a map) and a zero specular lobe: no indirect pass, no radiance pyramid.
    s.material.albedo = Albedo::Map(vec![[0.0; 3]; 24 * 24]);
    s.material.specular = Some([0.0; 3]);
    let p = &check_frames(&ctx, "albedo 0, bounces 2", &s, &[], &[vec![PD, PS, VE, VK, SD]])[0];
    let (created, why) = pass_created(p, "IndirectPass");
    assert!(!created && why.contains("reflects nothing"), "{why}");
    assert!(!pass_created(p, "RadiancePyramid").0);
    assert!(omitted(p, RG).contains("reflects nothing"), "{p}");

    // Albedo 0 with a non-zero specular lobe still reflects light: the bounces are there.
    s.material.specular = Some([0.3; 3]);
    s.material.exponent = 8.0;
    check_frames(&ctx, "albedo 0, glossy", &s, &[], &[frame_stages(&[PD, PS, VE, VK], true, 2, true)]);
}

#[test]
fn glossy_vector_pyramid_only_with_a_glossy_material() {
    let ctx = gpu();
    let mut s = base();
    s.gi.bounces = 1;
    s.gi.glossy_pyramid = GlossyPyramid::Vector;
    s.material.specular = Some([0.3; 3]);
    s.material.exponent = 8.0;
    // The vector pyramid is always a true pyramid: no radiance.synthesize even in stack mode.
    let want = frame_stages(&[PD, PS, VE, VK], true, 1, false);
    let p = &check_frames(&ctx, "glossy, vector", &s, &[], &[want])[0];
    assert!(reason(p, RD).contains("glossy SH vector pyramid, 51 channels"), "{p}");
    assert!(omitted(p, RS).contains("always a true pyramid"), "{p}");
    assert!(pass_created(p, "RadiancePyramid").1.contains("vector"));

    // Diffuse with the vector pyramid requested: the scalar pyramid, synthesized in stack mode.
    s.material.specular = None;
    let want = frame_stages(&[PD, PS, VE, VK], true, 1, true);
    let p = &check_frames(&ctx, "diffuse, vector requested", &s, &[], &[want])[0];
    assert!(reason(p, RD).contains("scalar RGB pyramid, 3 channels"), "{p}");
    assert!(reason(p, RD).contains("no specular lobe"), "{p}");
}

#[test]
fn synthesize_stages_only_in_stack_mode() {
    let ctx = gpu();
    let mut s = base();
    s.gi.bounces = 1;
    s.gi.pyramid = PyramidMode::Stack;
    check_frames(&ctx, "stack", &s, &[], &[frame_stages(&[PD, PS, VE, VK], true, 1, true)]);
    s.gi.pyramid = PyramidMode::Pyramid;
    let p = &check_frames(&ctx, "pyramid", &s, &[], &[frame_stages(&[PD, VE, VK], true, 1, false)])[0];
    assert!(omitted(p, PS).contains("pyramid mode"), "{p}");
    assert!(omitted(p, RS).contains("pyramid mode"), "{p}");
    // The max pyramid only where the scan uses it: with radial probes (in either bounce
    // setting), a bilinear level 0 and no wrap.
    s.gi.pyramid = PyramidMode::Stack;
    let p = plan(&s, &FrameState::first());
    assert!(omitted(&p, PM).contains("no radial probes"), "{p}");
    s.gi.radial_probes_later = 1;
    let p = &check_frames(&ctx, "probes", &s, &[], &[frame_stages(&[PD, PS, PM, VE, VK], true, 1, true)])[0];
    assert!(reason(p, PM).contains("level-0 maxima"), "{p}");
    assert!(pass_created(p, "MaxPyramid").0);
    s.gi.level0 = hfgi::scene::model::Level0::Bspline;
    let p =
        &check_frames(&ctx, "probes, bspline level 0", &s, &[], &[frame_stages(&[PD, PS, VE, VK], true, 1, true)])[0];
    assert!(omitted(p, PM).contains("bspline"), "{p}");
    assert!(!pass_created(p, "MaxPyramid").0);
    s.gi.level0 = hfgi::scene::model::Level0::Bilinear;
    s.wrap = true;
    let p = &check_frames(&ctx, "probes, wrap", &s, &[], &[frame_stages(&[PD, PS, VE, VK], true, 1, true)])[0];
    assert!(omitted(p, PM).contains("periodic"), "{p}");
}

#[test]
fn static_frames_keep_the_pyramid_and_amortise_the_shading() {
    let ctx = gpu();
    let mut s = base();
    s.gi.bounces = 1;
    let full = frame_stages(&[PD, PS, VE, VK], true, 1, true);
    // Nothing changes after the first frame: static frames record nothing (amortised or not);
    // frame 4 has new heights and records everything again.
    s.gi.amortize = true;
    let plans = check_frames(&ctx, "amortised", &s, &[4], &[full.clone(), vec![], vec![], vec![], full.clone()]);
    assert!(omitted(&plans[1], SD).contains("nothing changed since the last frame"), "{}", plans[1]);
    assert!(omitted(&plans[1], PD).contains("heights unchanged"), "{}", plans[1]);
    assert!(omitted(&plans[2], VE).contains("heights unchanged"), "{}", plans[2]);
    assert!(reason(&plans[4], PD).contains("heights changed since the last frame"), "{}", plans[4]);
    s.gi.amortize = false;
    check_frames(&ctx, "not amortised", &s, &[], &[full, vec![], vec![]]);
    s.gi.bounces = 0;
    check_frames(&ctx, "no bounces", &s, &[], &[vec![PD, PS, VE, VK, SD], vec![], vec![]]);
}

#[test]
fn live_changes_plan_what_they_leave_out_of_date() {
    // Pure: the plan of a frame whose lights changed (tests/live.rs records them on the GPU).
    use hfgi::frame::{Changes, Pending};
    let mut s = base();
    s.gi.bounces = 1;
    let at = |f: u64, inputs: Pending| plan(&s, &FrameState { heights_changed: false, frame_index: f, inputs });
    let both = Pending {
        upload_bytes: 64,
        direct: Changes::ENVIRONMENT,
        indirect: Changes::ENVIRONMENT,
        ..Default::default()
    };
    let indirect = frame_stages(&[], false, 1, true);
    // Amortised: an even frame shades the direct light, an odd one the indirect light.
    let even = at(2, both);
    assert_eq!(even.names(), vec!["inputs.update", SD], "{even}");
    assert!(reason(&even, SD).contains("environment changed; amortised: an even frame"), "{even}");
    assert!(reason(&even, "inputs.update").contains("64 B"), "{even}");
    let odd = at(3, both);
    assert_eq!(odd.names(), [vec!["inputs.update"], indirect.clone()].concat(), "{odd}");
    // One half out of date: that half, whatever the parity.
    let only = Pending { indirect: Changes::DIRECT_LIGHT, ..Default::default() };
    let p = at(2, only);
    assert_eq!(p.names(), indirect, "{p}");
    assert!(reason(&p, RG).contains("the direct light it reads"), "{p}");
    // Moved key lights: their visibility, never the pyramid or the environment's.
    let moved = Pending { key_lights_moved: true, ..both };
    let p = at(2, moved);
    assert_eq!(p.names(), vec!["inputs.update", VK, SD], "{p}");
    assert!(omitted(&p, VE).contains("heights unchanged"), "{p}");
    s.gi.amortize = false;
    let p = plan(&s, &FrameState { heights_changed: false, frame_index: 3, inputs: moved });
    assert_eq!(p.names(), [vec!["inputs.update", VK, SD], indirect].concat(), "{p}");
}

#[test]
fn plan_is_pure_and_lists_every_pass() {
    // No GPU: the plan of a scene is a function of the scene and the frame state.
    let mut s = base();
    s.gi.bounces = 3;
    s.gi.radial_probes = 1;
    let p = plan(&s, &FrameState::first());
    assert_eq!(p.names(), frame_stages(&[PD, PS, PM, VE, VK], true, 3, true));
    assert_eq!(p, plan(&s, &FrameState::static_scene(0)));
    let names: Vec<&str> = p.passes().iter().map(|x| x.name).collect();
    let all = [
        "HeightPyramid",
        "VisibilityPass",
        "ShadePass",
        "BlockerPass",
        "LocalLightPass",
        "IndirectPass",
        "MaxPyramid",
        "RadiancePyramid",
    ];
    assert_eq!(names, all);
    // Every pass but the spheres' and the local lights' (the scene has neither) is created,
    // each with its reason.
    let absent = ["BlockerPass", "LocalLightPass"];
    assert!(p.passes().iter().all(|x| x.created != absent.contains(&x.name) && !x.reason.is_empty()));
    let text = format!("{}{p}", p.passes_text());
    for line in ["pyramid.decimate", "gi.bounces = 3, bounce 3 of 3", "IndirectPass", "created"] {
        assert!(text.contains(line), "{line} missing from\n{text}");
    }
    assert!(p.stages.iter().all(|x| !x.reason.is_empty()));
}

#[test]
fn hfgi_plan_prints_stages_and_reasons_without_a_vulkan_device() {
    let out = std::process::Command::new(common::hfgi_exe())
        .args(["plan", "scenes/default.toml", "--set", "gi.bounces=1", "--frames", "3"])
        // No usable Vulkan driver: creating a context would fail.
        .env("VK_DRIVER_FILES", "/nonexistent/hfgi-no-driver.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/hfgi-no-driver.json")
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run hfgi plan");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    eprintln!("{text}");
    assert!(out.status.success(), "hfgi plan failed:\n{text}");
    for want in [
        "passes (Renderer::new):",
        "IndirectPass     created",
        "frame 0 (heights changed): 11 stages",
        "1. pyramid.decimate         first frame: heights uploaded",
        "2. pyramid.synthesize       stack mode",
        "3. pyramid.max              the visibility and indirect scans stop each ray where nothing farther",
        "4. visibility.environment   environment light is non-zero",
        "5. visibility.key_lights    1 key light",
        "6. shade.direct             heights changed",
        "7. radiance.gather          gi.bounces = 1, bounce 1 of 1",
        "11. indirect.shade",
        "frame 1 (heights unchanged): 0 stages",
        "not recorded: nothing changed since the last frame: the shading is kept",
        "frame 2 (heights unchanged): 0 stages",
        "not recorded: heights unchanged since the last frame",
        "resolved knobs: quality=default sh_order=4 azimuths=32 level_step=4",
        "level0=bilinear horizon=samples",
        "radial_probes=2 radial_probes_later=0 azimuths_later=16",
        "MaxPyramid       created",
        "elevation_basis=legendre",
    ] {
        assert!(text.contains(want), "`hfgi plan` output lacks {want:?}");
    }
    // The CLI's stage list is the library's plan of the same scene.
    let scene =
        hfgi::scene::file::load_scene(std::path::Path::new("scenes/default.toml"), &["gi.bounces=1".into()]).unwrap();
    for f in 0..3 {
        let p = plan(&scene, &FrameState::static_scene(f));
        assert!(text.contains(&p.to_string()), "frame {f} of the plan is not in the output:\n{p}");
    }
    // Bad input is an error, not a panic.
    let out = std::process::Command::new(common::hfgi_exe())
        .args(["plan", "scenes/default.toml", "--frames", "0"])
        .output()
        .expect("run hfgi plan");
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && text.contains("--frames 0") && !text.contains("panicked"), "{text}");
}

#[test]
fn hfgi_plan_buffers_lists_every_buffer_of_the_estimate() {
    // No device: the listing comes from hfgi::frame::memory::renderer, whose total it must sum to.
    let args = ["plan", "--no-device", "--buffers", "--set", "heightfield.size=32", "--set", "gi.bounces=1"];
    let out = std::process::Command::new(common::hfgi_exe()).args(args).output().expect("run hfgi plan");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    let listed: Vec<(&str, f64)> = text
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() == 3 && f[0].starts_with("hfgi.") && f[2] == "MiB").then(|| (f[0], f[1].parse().unwrap()))
        })
        .collect();
    for name in ["hfgi.pyramid.levels", "hfgi.visibility.v", "hfgi.indirect.u", "hfgi.shade.output"] {
        assert!(listed.iter().any(|(n, _)| *n == name), "{name} missing from\n{text}");
    }
    assert!(listed.windows(2).all(|w| w[0].1 >= w[1].1), "not largest first:\n{text}");
    let total_line = text.lines().find(|l| l.starts_with("GPU memory:")).expect("total line");
    let renderer: f64 = total_line.split("renderer ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    let sum: f64 = listed.iter().map(|(_, m)| m).sum();
    assert!((sum - renderer).abs() <= 0.001 * listed.len() as f64 + 0.01, "{sum} vs {renderer}\n{text}");
    assert!(!text.contains("largest buffer"), "{text}");
}

#[test]
fn hfgi_plan_prints_the_stage_table_the_planner_and_recorder_read() {
    let out = std::process::Command::new(common::hfgi_exe())
        .args(["plan", "--stages", "--no-device"])
        .output()
        .expect("run hfgi plan --stages");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    for row in hfgi::frame::STAGES {
        let line =
            text.lines().find(|l| l.trim_start().starts_with(row.name)).unwrap_or_else(|| panic!("{}", row.name));
        assert!(line.contains(row.pass) && line.contains(row.rule), "{line}");
    }
    // The passes' stage constants are the table's names, and the recorder names scopes by them.
    assert_eq!(hfgi::frame::indirect::STAGE_SCAN, hfgi::frame::Stage::IndirectScan(1).name());
    assert_eq!(hfgi::frame::view::STAGE_RASTER, "view.raster");
}
