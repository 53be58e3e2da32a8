//! Local spherical lights (docs/local-lights.md; stage `shade.local_lights`): the closed-form
//! cap irradiance on a flat field, shadowing by a ridge, GPU = f64 twin, the stage lists, the
//! live setter, and the typed errors.

mod common;

use common::scenes::{rel_l2, scene};
use common::{gpu, record_frame, render_layers, rough_field};
use glam::DVec3;
use hfgi::frame::plan::plan;
use hfgi::frame::{FrameState, Renderer, RendererOptions};
use hfgi::reference::direct::normals;
use hfgi::reference::local::local_exitance;
use hfgi::scene::model::{Albedo, Environment, LocalLight, Scene};
use hfgi::scene::HeightField;

const SD: &str = "shade.direct";
const SL: &str = "shade.local_lights";

fn lamp(x: f64, y: f64, z: f64, r: f64, l: [f64; 3]) -> LocalLight {
    LocalLight { position: DVec3::new(x, y, z), radius: r, radiance: l }
}

/// `field` lit by `lights` only (black environment, no key light), diffuse albedo 0.5.
fn lit_only_by(field: HeightField, lights: Vec<LocalLight>) -> Scene {
    let mut s = scene(field);
    s.environment = Environment { sh: vec![] };
    s.key_lights.clear();
    s.local_lights = lights;
    s.material.albedo = Albedo::Constant([0.5, 0.5, 0.5]);
    s
}

fn field(name: &str, w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> HeightField {
    HeightField::new(name, w, h, (0..w * h).map(|k| f(k % w, k / w)).collect(), 16384).unwrap()
}

/// Closed form (Funk–Hecke of a uniform cap fully above the horizon): exit radiance
/// `ρ/π · π L sin²Θ cos θ_c`, `sin Θ = r/d`, `θ_c` the angle between +z and the centre.
/// `None` where the cap reaches below the horizon.
fn flat_cap_exitance(p: DVec3, light: &LocalLight, rho: f64) -> Option<[f64; 3]> {
    let c = light.position - p;
    let d = c.length();
    let (sin_t, theta_c) = (light.radius / d, (c.z / d).acos());
    (theta_c + sin_t.asin() <= std::f64::consts::FRAC_PI_2 - 1e-3)
        .then(|| light.radiance.map(|l| rho * l * sin_t * sin_t * theta_c.cos()))
}

#[test]
fn flat_field_equals_the_closed_form_cap_irradiance() {
    let ctx = gpu();
    let (w, h) = (33, 25);
    let light = lamp(14.3, 11.6, 6.0, 1.5, [2.0, 3.0, 4.0]);
    let s = lit_only_by(field("flat", w, h, |_, _| -3.0), vec![light.clone()]);
    let out = render_layers(&ctx, &s);
    let twin = local_exitance(&s, &normals(&s));
    let (mut worst_gpu, mut worst_twin, mut n) = (0f64, 0f64, 0);
    for y in 0..h {
        for x in 0..w {
            let p = DVec3::new(x as f64, y as f64, -3.0);
            let Some(want) = flat_cap_exitance(p, &light, 0.5) else { continue };
            let k = y * w + x;
            for c in 0..3 {
                worst_gpu = worst_gpu.max((f64::from(out.direct[k][c]) - want[c]).abs() / want[c]);
                worst_twin = worst_twin.max((twin[k][c] - want[c]).abs() / want[c]);
            }
            n += 1;
        }
    }
    eprintln!(
        "{n} texels with the cap above the horizon: worst relative error GPU {worst_gpu:.2e}, twin {worst_twin:.2e}"
    );
    assert!(n > 200, "{n} texels tested");
    assert!(worst_twin <= 1e-4, "twin: {worst_twin:e}");
    assert!(worst_gpu <= 1e-4, "GPU: {worst_gpu:e}");
    // The total carries it too (nothing else lights this scene).
    assert_eq!(out.total, out.direct);
}

#[test]
fn a_light_below_a_ridge_is_shadowed_one_above_it_is_not() {
    let ctx = gpu();
    // A one-texel wall of height 10 at x = 20; the receiver at x = 10, lights at x = 30.
    let wall = || field("wall", 48, 24, |x, _| if x == 20 { 10.0 } else { 0.0 });
    let receiver = 12 * 48 + 10;
    let flat_lamp = || lamp(30.0, 12.0, 3.0, 1.0, [5.0; 3]);
    let low = flat_lamp();
    let high = lamp(30.0, 12.0, 40.0, 1.0, [5.0; 3]);
    let below = render_layers(&ctx, &lit_only_by(wall(), vec![low.clone()]));
    let above = render_layers(&ctx, &lit_only_by(wall(), vec![high.clone()]));
    let flat_low = render_layers(&ctx, &lit_only_by(field("flat", 48, 24, |_, _| 0.0), vec![low]));
    let want = flat_cap_exitance(DVec3::new(10.0, 12.0, 0.0), &high, 0.5).unwrap();
    eprintln!(
        "receiver: low light {:?} (flat field {:?}), high light {:?} (closed form {want:?})",
        below.direct[receiver], flat_low.direct[receiver], above.direct[receiver]
    );
    let open = flat_cap_exitance(DVec3::new(10.0, 12.0, 0.0), &flat_lamp(), 0.5).unwrap()[0];
    let e = (f64::from(flat_low.direct[receiver][0]) - open).abs() / open;
    assert!(e <= 1e-4, "the low light lights the flat field as the closed form says: {e:e}");
    assert_eq!(below.direct[receiver], [0.0; 3], "the wall hides the low light");
    let e = (f64::from(above.direct[receiver][0]) - want[0]).abs() / want[0];
    assert!(e <= 1e-4, "the high light is unshadowed: {e:e} from the closed form");
    // Behind the wall, on the light's side, the low light shines again.
    assert!(below.direct[12 * 48 + 25][0] > 1e-3, "{:?}", below.direct[12 * 48 + 25]);
}

/// A rough field with two lights (one near the surface, one that a receiver is inside of),
/// heights far below zero, texel size 2, non-square: the GPU's direct layer equals the f64
/// twin's, environment and key light included.
#[test]
fn gpu_equals_the_twin() {
    let ctx = gpu();
    let r = rough_field(40, 28, 9);
    let f = HeightField::new("low rough", 40, 28, r.data().iter().map(|v| v * 2.0 - 500.0).collect(), 16384).unwrap();
    let mut s = scene(f);
    s.texel_size = 2.0;
    s.gi.azimuths = 8;
    let z = |x: usize, y: usize| f64::from(s.field.get(x, y));
    s.local_lights = vec![
        lamp(20.0, 30.0, z(10, 15) + 3.0, 1.5, [30.0, 20.0, 10.0]),
        lamp(60.0, 10.0, z(30, 5) + 0.5, 2.5, [5.0, 8.0, 12.0]),
    ];
    let out = render_layers(&ctx, &s);
    let twin = hfgi::reference::direct::render_direct(&s).unwrap();
    let local = local_exitance(&s, &normals(&s));
    let norm = |v: &[[f64; 3]]| v.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
    let share = norm(&local) / norm(&twin.direct);
    let e = rel_l2(&out.direct, &twin.direct);
    eprintln!("GPU vs twin, direct layer: {e:.2e} (the local lights are {:.0}% of it)", 100.0 * share);
    assert!(share > 0.2, "the local lights matter in this scene");
    assert!(e <= 1e-4, "{e:e}");
    // A glossy surface: the lights' Phong highlights join the glossy layer.
    s.material.specular = Some([0.4, 0.3, 0.2]);
    s.material.exponent = 12.0;
    let out = render_layers(&ctx, &s);
    let twin = hfgi::reference::direct::render_direct(&s).unwrap();
    let local = hfgi::reference::local::local_glossy(&s, &normals(&s));
    let share = norm(&local) / norm(&twin.glossy);
    let e = rel_l2(&out.glossy, &twin.glossy);
    let t = rel_l2(&out.total, &twin.total);
    eprintln!("GPU vs twin, glossy layer: {e:.2e}, total {t:.2e} (the local lights are {:.0}% of it)", 100.0 * share);
    assert!(share > 0.2, "the local lights' highlights matter in this scene");
    assert!(e <= 1e-4 && t <= 1e-4, "glossy {e:e}, total {t:e}");
}

/// The local lights' glossy light on a flat field against a brute-force integral of the
/// normalised Phong lobe over the directions that hit the light's sphere (Gauss–Legendre in
/// cos θ × uniform azimuths with a ray–sphere test; independent of the slices), for receivers
/// whose reflected view vector passes near the light.
#[test]
fn glossy_on_a_flat_field_against_the_exact_integral() {
    let light = lamp(16.0, 16.0, 4.0, 1.5, [10.0, 10.0, 10.0]);
    let mut s = lit_only_by(field("flat", 33, 33, |_, _| 0.0), vec![light.clone()]);
    s.material.specular = Some([1.0; 3]);
    s.camera.position = DVec3::new(40.0, 16.0, 10.0);
    let exact = |p: DVec3, refl: DVec3, sexp: f64| -> f64 {
        let hit = |d: DVec3| common::scenes::hits_sphere(p, d, light.position, light.radius);
        10.0 * common::scenes::lobe_integral(refl, sexp, 400, 1600, hit)
    };
    for (sexp, az) in [(8.0, 8), (8.0, 16), (32.0, 16)] {
        s.material.exponent = sexp as f32;
        s.gi.local_light_azimuths = az;
        let g = hfgi::reference::local::local_glossy(&s, &normals(&s));
        let (mut num, mut den) = (0.0, 0.0);
        for x in 18..30 {
            let p = DVec3::new(x as f64, 16.0, 0.0);
            let wo = (s.camera.position - p).normalize();
            let want = exact(p, DVec3::new(-wo.x, -wo.y, wo.z), sexp);
            num += (g[16 * 33 + x][0] - want).powi(2);
            den += want * want;
        }
        let err = (num / den).sqrt();
        eprintln!("S = {sexp}, {az} azimuths: local-light glossy vs the exact integral {err:.2e}");
        assert!(err < 1e-2, "S = {sexp}, {az} azimuths: {err:e}");
    }
}

#[test]
fn stages_are_planned_only_with_local_lights() {
    let mut s = lit_only_by(rough_field(16, 16, 1), vec![lamp(8.0, 8.0, 20.0, 1.0, [1.0; 3])]);
    let names = |s: &Scene| plan(s, &FrameState::first()).names();
    assert_eq!(names(&s), ["pyramid.decimate", "pyramid.synthesize", SD, SL]);
    let p = plan(&s, &FrameState::first());
    assert!(p.passes().iter().any(|q| q.name == "LocalLightPass" && q.created));
    s.local_lights.clear();
    s.key_lights = scene(rough_field(16, 16, 1)).key_lights;
    assert!(!names(&s).contains(&SL));
    let p = plan(&s, &FrameState::first());
    let why = p.omitted.iter().find(|o| o.name == SL).map(|o| o.reason.clone());
    assert_eq!(why.as_deref(), Some("no local lights"));
    assert!(p.passes().iter().any(|q| q.name == "LocalLightPass" && !q.created));
}

/// Moving, recolouring, adding and removing local lights on a live renderer equals a fresh
/// renderer of the changed scene, re-shades without any visibility stage, and submits nothing.
#[test]
fn set_local_lights_equals_a_fresh_renderer() {
    let ctx = gpu();
    let mut want = scene(rough_field(24, 20, 3));
    want.gi.azimuths = 8;
    want.gi.bounces = 1;
    want.gi.amortize = false;
    want.local_lights = vec![lamp(10.0, 8.0, 14.0, 1.0, [20.0, 10.0, 5.0])];
    let opts = RendererOptions { local_lights: Some(2), ..Default::default() };
    let mut live = Renderer::with_options(&ctx, &want, &opts).unwrap();
    record_frame(&ctx, &mut live);
    let indirect = ["radiance.gather", "radiance.decimate", "radiance.synthesize", "indirect.scan", "indirect.shade"];
    let steps: [fn(&mut Scene); 4] = [
        |s| s.local_lights[0].position = DVec3::new(15.0, 12.0, 11.0),
        |s| s.local_lights[0].radiance = [1.0, 30.0, 2.0],
        |s| s.local_lights.push(lamp(3.0, 17.0, 9.0, 2.0, [8.0; 3])),
        |s| s.local_lights.truncate(1),
    ];
    for (i, step) in steps.into_iter().enumerate() {
        step(&mut want);
        let (submits, pipelines) = (ctx.submit_count(), ctx.pipelines_created());
        live.set_local_lights(&want.local_lights).unwrap();
        assert_eq!(ctx.submit_count(), submits);
        let recorded = record_frame(&ctx, &mut live);
        assert_eq!(ctx.pipelines_created(), pipelines);
        let mut expect = vec!["inputs.update", SD, SL];
        expect.extend(indirect);
        assert_eq!(recorded, expect, "change {i}");
        let a = live.read_layers(&ctx).unwrap();
        let mut fresh_scene = want.clone();
        fresh_scene.local_lights = want.local_lights.clone();
        let b = render_layers(&ctx, &fresh_scene);
        let e = rel_l2(&a.total, &b.total.iter().map(|v| v.map(f64::from)).collect::<Vec<_>>());
        eprintln!("change {i}: relative L2 to a fresh renderer {e:.1e}");
        assert!(e <= 1e-6, "change {i}: {e:e}");
    }
    let too_many = vec![lamp(1.0, 1.0, 5.0, 1.0, [1.0; 3]); 3];
    let err = live.set_local_lights(&too_many).unwrap_err().to_string();
    assert!(err.contains("at most 2"), "{err}");
    let bad = vec![lamp(1.0, 1.0, 5.0, -1.0, [1.0; 3])];
    let err = live.set_local_lights(&bad).unwrap_err().to_string();
    assert!(err.contains("local light 0 radius"), "{err}");
    live.destroy(&ctx);
}

/// A glossy surface under local lights: moving the camera re-shades (the highlights follow the
/// view) and equals a fresh renderer.
#[test]
fn glossy_highlights_follow_the_camera() {
    let ctx = gpu();
    let mut want = lit_only_by(rough_field(24, 20, 3), vec![lamp(10.0, 8.0, 6.0, 1.5, [20.0, 10.0, 5.0])]);
    want.material.specular = Some([0.5; 3]);
    want.material.exponent = 10.0;
    want.gi.amortize = false;
    let mut live = Renderer::new(&ctx, &want).unwrap();
    record_frame(&ctx, &mut live);
    let before = live.read_layers(&ctx).unwrap();
    want.camera.position += DVec3::new(-25.0, 10.0, 4.0);
    live.set_camera(&want.camera).unwrap();
    assert_eq!(record_frame(&ctx, &mut live), [SD, SL]);
    let a = live.read_layers(&ctx).unwrap();
    let b = render_layers(&ctx, &want);
    let e = rel_l2(&a.total, &b.total.iter().map(|v| v.map(f64::from)).collect::<Vec<_>>());
    let moved = rel_l2(&before.glossy, &a.glossy.iter().map(|v| v.map(f64::from)).collect::<Vec<_>>());
    eprintln!("camera moved: glossy changed by {moved:.2e}; relative L2 to a fresh renderer {e:.1e}");
    assert!(moved > 1e-2, "{moved:e}");
    assert!(e <= 1e-6, "{e:e}");
    live.destroy(&ctx);
}

#[test]
fn periodic_fields_and_bad_lights_are_typed_errors() {
    let ctx = gpu();
    let mut s = lit_only_by(rough_field(16, 16, 1), vec![lamp(8.0, 8.0, 20.0, 1.0, [1.0; 3])]);
    s.wrap = true;
    let err = Renderer::new(&ctx, &s).err().expect("wrap rejected").to_string();
    assert!(err.contains("local_light") && err.contains("periodic"), "{err}");
    s.wrap = false;
    s.local_lights[0].radiance = [f64::NAN, 0.0, 0.0];
    let err = Renderer::new(&ctx, &s).err().expect("NaN rejected").to_string();
    assert!(err.contains("local light 0 radiance"), "{err}");
    let mut s2 = scene(rough_field(16, 16, 1));
    s2.local_lights.clear();
    let mut r = Renderer::new(&ctx, &s2).unwrap();
    let err = r.set_local_lights(&[lamp(8.0, 8.0, 20.0, 1.0, [1.0; 3])]).unwrap_err().to_string();
    assert!(err.contains("at most 0"), "{err}");
    r.destroy(&ctx);
}
