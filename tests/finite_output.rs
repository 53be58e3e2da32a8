//! No non-finite output from finite input (docs/robustness.md): every numeric scene key is set
//! to the extremes it accepts, one at a time, on a small scene with a glossy material, a key
//! light and one bounce; the frame (every shading layer and the view image) must be finite.
//! One step past each extreme must be rejected with a message naming the key. A key of
//! docs/scene-format.md that is numeric must appear here (or in `NOT_RENDERED`, with why).

mod common;

use std::path::Path;

use hfgi::frame::view::{ViewOptions, ViewPass};
use hfgi::frame::water::WaterSim;
use hfgi::frame::Renderer;
use hfgi::scene::animated::{Animation, MovingBumps};
use hfgi::scene::file::parse_scene;
use hfgi::scene::model::{limits, Scene};
use hfgi::vk::{Context, Recorder};

/// The small scene every case starts from.
const BASE: [&str; 5] = [
    "heightfield.size=[12,9]",
    "camera.width=16",
    "camera.height=12",
    "gi.bounces=1",
    "material.specular=[0.3,0.3,0.3]",
];

/// Keys whose extremes are rendered with `gi.visibility = "sweep"` too (magnitudes the hull's
/// slopes see, and the sweep's own knob).
const SWEEP_TOO: [&str; 4] =
    ["heightfield.texel_size", "heightfield.height_scale", "heightfield.height_offset", "gi.sweep_near"];

/// Numeric keys not rendered at an extreme, and why (each is still range-checked).
const NOT_RENDERED: [(&str, &str); 5] = [
    ("heightfield.nodata", "GeoTIFF files only: a fill value becomes a height, bounded like every height"),
    (
        "heightfield.size",
        "a cost knob: 16384² is valid and bounded by the memory check, not a magnitude; its minimum 2 is a case",
    ),
    ("heightfield.raw_size", "files only; the same bound as heightfield.size"),
    ("camera.width", "its maximum is a cost knob (8192² pixels); its minimum 1 is a case"),
    ("animation.seed", "an integer seed of a hash, not a magnitude"),
];

/// `(key, accepted extremes, values just beyond them)`; `key` as written in `--set`.
fn cases(scale_max: f64) -> Vec<(&'static str, Vec<String>, Vec<String>)> {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let m = limits::MAX_RADIANCE;
    let h = limits::MAX_HEIGHT * 0.999;
    vec![
        ("heightfield.size", s(&["2"]), s(&["1"])),
        ("heightfield.texel_size", s(&["1e-6", "1e6"]), s(&["9e-7", "1.1e6"])),
        (
            "heightfield.height_scale",
            vec![format!("{scale_max}"), format!("{}", -scale_max)],
            vec![format!("{}", scale_max * 1.01)],
        ),
        ("heightfield.height_offset", vec![format!("{h}"), format!("{}", -h)], s(&["1.01e9", "-1.01e9"])),
        ("material.albedo", s(&["[0,0,0]", "[1,1,1]"]), s(&["[1.01,1,1]", "[-0.01,0,0]"])),
        ("material.specular", s(&["[0,0,0]", "[1e3,1e3,1e3]"]), s(&["[1.1e3,0,0]", "[-1,0,0]"])),
        ("material.exponent", s(&["1e-3", "1e4"]), s(&["9e-4", "1.1e4"])),
        ("environment.intensity", s(&["0", "1e6"]), s(&["-1", "1.1e6"])),
        (
            "environment.sh",
            vec![format!("[[{m},{m},{m}],[-{m},0,{m}],[0,-{m},0],[{m},{m},-{m}]]")],
            vec![format!("[[{},0,0]]", m * 1.1)],
        ),
        ("key_light.0.elevation_deg", s(&["-90", "90"]), s(&["-90.1", "90.1"])),
        ("key_light.0.azimuth_deg", s(&["-360", "360"]), s(&["-361", "361"])),
        ("key_light.0.angular_radius_deg", s(&["1e-3", "90"]), s(&["9e-4", "90.1"])),
        (
            "key_light.0.radiance",
            vec![format!("[{m},{m},{m}]"), s(&["[0,0,0]"])[0].clone()],
            vec![format!("[{},0,0]", m * 1.1)],
        ),
        ("key_light.0.direction", s(&["[1e-300,1e-300,1e-300]", "[1e300,-1e300,1e300]"]), s(&["[0,0,0]"])),
        ("camera.position", s(&["[-1e10,-1e10,1e10]", "[1e10,1e10,-1e10]"]), s(&["[1.1e10,0,0]"])),
        ("camera.target", s(&["[1e10,-1e10,1e10]", "[-1e10,1e10,-1e10]"]), s(&["[0,0,-1.1e10]"])),
        ("camera.fov_deg", s(&["0.01", "179"]), s(&["0.009", "179.1"])),
        ("camera.width", s(&["1"]), s(&["0", "8193"])),
        ("camera.height", s(&["1"]), s(&["0", "8193"])),
        ("camera.exposure", s(&["-64", "64"]), s(&["-64.1", "64.1"])),
        ("gi.sh_order", s(&["2", "8"]), s(&["1", "9"])),
        ("gi.azimuths", s(&["4", "256"]), s(&["3", "257"])),
        ("gi.key_light_azimuths", s(&["2", "64"]), s(&["1", "65"])),
        ("gi.level_step", s(&["1", "32"]), s(&["0", "33"])),
        ("gi.level_offset", s(&["0", "8"]), s(&["9"])),
        ("gi.subsample", s(&["1", "4"]), s(&["3", "8"])),
        ("gi.bounces", s(&["0", "16"]), s(&["17"])),
        ("gi.radiance_level_step", s(&["1", "16"]), s(&["0", "17"])),
        ("gi.radiance_level_offset", s(&["0", "8"]), s(&["9"])),
        ("gi.near_steps", s(&["0", "64"]), s(&["65"])),
        ("gi.radial_probes", s(&["0", "16"]), s(&["17"])),
        ("gi.radial_probes_later", s(&["0", "16"]), s(&["17"])),
        ("gi.azimuths_later", s(&["4", "256"]), s(&["3", "257"])),
        ("gi.azimuth_offset", s(&["0", "0.999"]), s(&["-0.01", "1"])),
        ("gi.cast_merge", s(&["0", "0.2"]), s(&["-0.001", "0.21"])),
        ("gi.sweep_near", s(&["0", "64"]), s(&["65"])),
        ("gi.local_light_azimuths", s(&["2", "64"]), s(&["1", "65"])),
        ("gi.blocker_epsilon", s(&["1e-6", "0.999"]), s(&["9e-7", "1"])),
        (
            "local_light.0.position",
            s(&["[-1e10,-1e10,1e10]", "[1e10,1e10,-1e10]", "[5,4,0.01]", "[5,4,-3]"]),
            s(&["[1.1e10,0,0]"]),
        ),
        ("local_light.0.radius", s(&["1e-3", "1e6"]), s(&["9e-4", "1.1e6"])),
        (
            "local_light.0.radiance",
            vec![format!("[{m},{m},{m}]"), "[0,0,0]".into()],
            vec![format!("[{},0,0]", m * 1.1)],
        ),
        ("sphere.0.center", s(&["[-1e10,-1e10,1e10]", "[1e10,1e10,-1e10]", "[5,4,0]"]), s(&["[1.1e10,0,0]"])),
        ("sphere.0.radius", s(&["1e-3", "1e6"]), s(&["9e-4", "1.1e6"])),
        ("sphere.0.albedo", s(&["[0,0,0]", "[1,1,1]"]), s(&["[1.1,0,0]", "[-0.1,0,0]"])),
    ]
}

/// The keys a case needs besides its own: a local light's position, a sphere's centre and
/// radius (the knobs of both need one).
fn prerequisites(key: &str) -> Vec<String> {
    let mut out = Vec::new();
    if (key.starts_with("local_light.") || key == "gi.local_light_azimuths") && key != "local_light.0.position" {
        out.push("local_light.0.position=[5,4,3]".to_string());
    }
    if key.starts_with("sphere.") || key.starts_with("gi.blocker") {
        if key != "sphere.0.center" {
            out.push("sphere.0.center=[7,3,2]".to_string());
        }
        if key != "sphere.0.radius" {
            out.push("sphere.0.radius=1.5".to_string());
        }
    }
    out
}

/// Animation cases: `(kind, key, accepted extremes, beyond)`.
fn animation_cases() -> Vec<(&'static str, &'static str, Vec<&'static str>, Vec<&'static str>)> {
    vec![
        ("water", "speed", vec!["1e-9", "0.705"], vec!["0", "0.71"]),
        ("water", "damping", vec!["0", "1"], vec!["-0.1", "1.1"]),
        ("water", "steps_per_frame", vec!["1", "64"], vec!["0", "65"]),
        ("water", "rest_level", vec!["-9.9e8", "9.9e8"], vec!["1.1e9"]),
        ("water", "scale", vec!["-1e6", "1e6"], vec!["0", "1.1e6"]),
        ("water", "rain_rate", vec!["0", "4"], vec!["-1", "4.1"]),
        ("water", "drop_amplitude", vec!["-1e6", "1e6"], vec!["1.1e6"]),
        ("water", "drop_radius", vec!["1", "256"], vec!["0.9", "257"]),
        ("bumps", "count", vec!["1", "256"], vec!["0", "257"]),
        ("bumps", "radius", vec!["1e-3", "1"], vec!["9e-4", "1.1"]),
        ("bumps", "amplitude", vec!["-1e3", "1e3"], vec!["1.1e3"]),
        ("bumps", "period", vec!["2", "4294967295"], vec!["1"]),
        ("bumps", "travel", vec!["0", "1"], vec!["-0.1", "1.1"]),
        ("day", "day_frames", vec!["2", "100000"], vec!["1", "100001"]),
        ("day", "max_elevation_deg", vec!["3", "90"], vec!["2.9", "90.1"]),
        ("day", "sweep_deg", vec!["0", "360"], vec!["-1", "361"]),
        ("day", "orbit_turns", vec!["-10", "10"], vec!["-10.1", "10.1"]),
        ("boulders", "lap_frames", vec!["2", "100000"], vec!["1", "100001"]),
    ]
}

fn scene_with(extra: &[String]) -> hfgi::Result<Scene> {
    let mut o: Vec<String> = BASE.iter().map(|s| s.to_string()).collect();
    o.extend_from_slice(extra);
    parse_scene("", Path::new("."), "sweep", &o)
}

/// Asserts every value is finite, naming the case, the layer and the first bad texel.
fn assert_finite(what: &str, layer: &str, v: &[[f32; 3]]) {
    if let Some(k) = v.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        panic!("{what}: {layer} texel {k} is {:?}", v[k]);
    }
}

/// One frame (with `steps` water steps or bumps frame 3 first, for animations), every layer
/// and the view image checked.
fn render_finite(ctx: &Context, scene: &Scene, what: &str) {
    let mut r = Renderer::new(ctx, scene).unwrap_or_else(|e| panic!("{what}: {e}"));
    let view = ViewPass::for_renderer(ctx, scene, &r, &ViewOptions { samples: Some(1) })
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let (w, h) = (scene.field.width(), scene.field.height());
    let mut sim = match &scene.animation {
        Animation::Water(p) => {
            let z: Vec<f32> =
                scene.field.data().iter().map(|&v| ((f64::from(v) - p.rest_level) / p.scale) as f32).collect();
            Some(WaterSim::new(ctx, w, h, p.clone(), &z).unwrap())
        }
        Animation::Bumps(p) => {
            let b = MovingBumps::new(p.clone(), scene.field.clone(), scene.texel_size, scene.wrap).unwrap();
            r.update_heights(ctx, &b.heights_at(3).unwrap_or_else(|e| panic!("{what}: {e}"))).unwrap();
            None
        }
        Animation::Day(p) => {
            let day = hfgi::scene::day::DayCycle::new(p.clone(), scene).unwrap_or_else(|e| panic!("{what}: {e}"));
            let f = day.frame(3, &scene.key_lights);
            r.set_key_lights(&f.key_lights).unwrap_or_else(|e| panic!("{what}: {e}"));
            r.set_environment(&f.environment).unwrap_or_else(|e| panic!("{what}: {e}"));
            r.set_camera(&f.camera).unwrap_or_else(|e| panic!("{what}: {e}"));
            None
        }
        Animation::Boulders(p) => {
            let b = hfgi::scene::boulders::Boulders::new(p.clone(), scene).unwrap_or_else(|e| panic!("{what}: {e}"));
            r.set_spheres(&b.frame(3)).unwrap_or_else(|e| panic!("{what}: {e}"));
            None
        }
        Animation::None => None,
    };
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, None);
        if let Some(s) = sim.as_mut() {
            for _ in 0..3 * s.params().steps_per_frame {
                s.record_step(&mut rec, r.heights_buffer())?;
            }
            r.mark_heights_changed();
        }
        r.record(&mut rec);
        view.record(&mut rec);
        Ok(())
    })
    .unwrap();
    let layers = r.read_layers(ctx).unwrap();
    let hdr = view.read_hdr(ctx).unwrap();
    if let Some(s) = sim {
        s.destroy(ctx);
    }
    view.destroy(ctx);
    r.destroy(ctx);
    for (name, plane) in [
        ("total", &layers.total),
        ("direct", &layers.direct),
        ("indirect", &layers.indirect),
        ("glossy", &layers.glossy),
        ("indirect_glossy", &layers.indirect_glossy),
        ("view", &hdr),
    ] {
        assert_finite(what, name, plane);
    }
}

fn assert_rejected(key: &str, over: &[String]) {
    let e = scene_with(over).err().unwrap_or_else(|| panic!("{over:?} was accepted"));
    let msg = e.to_string();
    let bare = key.rsplit('.').next().unwrap_or(key);
    assert!(msg.contains(bare), "{over:?}: the message does not name {key}: {msg}");
    assert!(msg.len() < 600, "{over:?}: message too long: {msg}");
}

#[test]
fn every_numeric_key_at_its_extremes_gives_finite_output() {
    // The largest accepted height_scale for the base field: its highest |height| at MAX_HEIGHT.
    let base = scene_with(&[]).unwrap();
    let peak = base.field.data().iter().fold(0f64, |a, &v| a.max(f64::from(v).abs()));
    let scale_max = limits::MAX_HEIGHT / peak * 0.999;
    let gpu = common::gpu();
    let mut rendered = 0;
    for (key, values, beyond) in cases(scale_max) {
        for v in &values {
            let set = format!("{key}={v}");
            let mut all = prerequisites(key);
            all.push(set.clone());
            let scene = scene_with(&all).unwrap_or_else(|e| panic!("{set} rejected: {e}"));
            render_finite(&gpu, &scene, &set);
            rendered += 1;
            if SWEEP_TOO.contains(&key) {
                let both = [set.clone(), "gi.visibility=\"sweep\"".to_string()];
                let scene = scene_with(&both).unwrap_or_else(|e| panic!("{both:?} rejected: {e}"));
                render_finite(&gpu, &scene, &both.join(" "));
                rendered += 1;
            }
        }
        for b in &beyond {
            let mut all = prerequisites(key);
            all.push(format!("{key}={b}"));
            assert_rejected(key, &all);
        }
    }
    for (kind, key, values, beyond) in animation_cases() {
        let k = format!("animation.kind=\"{kind}\"");
        for v in values {
            // At damping 1 the default speed 0.5 is past the stability limit √((2 − d)/4).
            let speed = match (kind, key) {
                ("water", "speed") => "animation.damping=0.01",
                ("water", _) => "animation.speed=0.3",
                ("day", _) => "animation.sweep_deg=120",
                ("boulders", _) => "sphere.0={ center = [7, 3, 2], radius = 1.5 }",
                _ => "animation.count=2",
            };
            let set = [k.clone(), speed.to_string(), format!("animation.{key}={v}")];
            let scene = scene_with(&set).unwrap_or_else(|e| panic!("{set:?} rejected: {e}"));
            render_finite(&gpu, &scene, &set.join(" "));
            rendered += 1;
        }
        for b in beyond {
            let sphere = "sphere.0={ center = [7, 3, 2], radius = 1.5 }".to_string();
            assert_rejected(key, &[k.clone(), sphere, format!("animation.{key}={b}")]);
        }
    }
    eprintln!("{rendered} frames at extreme values, all finite");
    assert!(common::finish(gpu).is_empty());
}

/// Every numeric key of docs/scene-format.md is swept above or listed in `NOT_RENDERED`.
#[test]
fn the_sweep_covers_every_numeric_key_of_the_scene_format() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scene-format.md")).unwrap();
    let mut swept: Vec<String> = cases(1.0).iter().map(|(k, _, _)| k.replace(".0.", ".")).collect();
    swept.extend(animation_cases().iter().map(|(_, k, _, _)| format!("animation.{k}")));
    swept.extend(NOT_RENDERED.iter().map(|(k, _)| k.to_string()));
    let mut table = String::new();
    let mut missing = Vec::new();
    for line in doc.lines() {
        if let Some(t) = line.strip_prefix("## `[").map(|t| t.trim_start_matches('[')) {
            table = t.split(']').next().unwrap_or("").to_string();
        } else if line.starts_with("## ") {
            table.clear();
        }
        let cols: Vec<&str> = line.split('|').map(str::trim).collect();
        if table.is_empty() || cols.len() < 4 || !cols[1].starts_with('`') {
            continue;
        }
        let key = cols[1].trim_matches(|c| c == '`' || c == ' ' || c == '†').trim_end_matches("` †").trim_matches('`');
        let ty = cols[2];
        let numeric =
            ["float", "integer", "[r, g, b]", "[x, y, z]", "array of", "[w, h]"].iter().any(|t| ty.contains(t));
        let full = format!("{table}.{key}");
        if numeric && !swept.contains(&full) {
            missing.push(full);
        }
    }
    assert!(missing.is_empty(), "numeric keys of docs/scene-format.md not in the sweep: {missing:?}");
}

/// A scene built in code is held to the same limits: `Renderer::new` and `update_heights`
/// reject magnitudes the parser would reject, with typed errors, before any GPU work.
#[test]
fn a_scene_built_in_code_is_checked_by_the_renderer() {
    let gpu = common::gpu();
    let good = scene_with(&[]).unwrap();
    let mut bright = good.clone();
    bright.key_lights[0].radiance = [1e30, 1.0, 1.0];
    let mut far = good.clone();
    far.camera.position.x = 1e30;
    let mut sharp = good.clone();
    sharp.material.exponent = 1e9;
    for (what, scene) in [("radiance", bright), ("camera", far), ("exponent", sharp)] {
        let e = Renderer::new(&gpu, &scene).err().unwrap_or_else(|| panic!("{what} accepted"));
        assert!(matches!(e, hfgi::Error::InvalidParameter { .. }), "{what}: {e}");
    }
    let mut r = Renderer::new(&gpu, &good).unwrap();
    let (w, h) = (good.field.width(), good.field.height());
    let tall = hfgi::scene::HeightField::new("tall", w, h, vec![1e20; w * h], 16384).unwrap();
    let e = r.update_heights(&gpu, &tall).unwrap_err().to_string();
    assert!(e.contains("1e9") || e.contains("1e+9") || e.contains("±"), "{e}");
    r.destroy(&gpu);
    assert!(common::finish(gpu).is_empty());
}
