//! Live inputs (docs/integration.md §2, docs/plan.md §1): every kind of light, material and
//! camera change, made on a running renderer between frames, gives the frame a freshly created
//! renderer of the changed scene gives (≤ 1e-6 of the largest value), records exactly the
//! planned stages, and submits nothing and creates no pipeline on its own.

mod common;

use common::scenes::{key_light, scene};
use common::{gpu, record_frame, rough_field};
use glam::DVec3;
use hfgi::frame::{Renderer, RendererOptions, ShadingLayers};
use hfgi::scene::model::{Albedo, Environment, Scene};
use hfgi::vk::Context;

const IU: &str = "inputs.update";
const VK: &str = "visibility.key_lights";
const SD: &str = "shade.direct";
const INDIRECT: [&str; 5] =
    ["radiance.gather", "radiance.decimate", "radiance.synthesize", "indirect.scan", "indirect.shade"];

/// 24² rough field, 8 azimuths, one bounce, a glossy material (so the camera matters).
fn base() -> Scene {
    let mut s = scene(rough_field(24, 24, 5));
    s.gi.azimuths = 8;
    s.gi.bounces = 1;
    s.gi.radial_probes = 0;
    s.gi.amortize = false;
    s.material.specular = Some([0.2, 0.25, 0.3]);
    s.material.exponent = 16.0;
    s
}

fn layers(ctx: &Context, r: &Renderer) -> ShadingLayers {
    r.read_layers(ctx).unwrap()
}

/// The largest difference of any layer, relative to the largest value of `b`'s layers.
fn rel_diff(a: &ShadingLayers, b: &ShadingLayers) -> f64 {
    let pairs = [(&a.total, &b.total), (&a.direct, &b.direct), (&a.indirect, &b.indirect), (&a.glossy, &b.glossy)];
    let (mut d, mut m) = (0f64, 0f64);
    for (x, y) in pairs {
        for (p, q) in x.iter().zip(y.iter()) {
            for c in 0..3 {
                d = d.max(f64::from((p[c] - q[c]).abs()));
                m = m.max(f64::from(q[c].abs()));
            }
        }
    }
    assert!(m > 0.0, "black frame");
    d / m
}

/// A fresh renderer of `scene`, one frame, its layers.
fn fresh(ctx: &Context, scene: &Scene) -> ShadingLayers {
    let mut r = Renderer::new(ctx, scene).unwrap();
    record_frame(ctx, &mut r);
    let out = layers(ctx, &r);
    r.destroy(ctx);
    out
}

fn rot_z(deg: f64) -> [[f64; 3]; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn stages(extra: &[&'static str], indirect: bool) -> Vec<String> {
    let mut v: Vec<&str> = extra.to_vec();
    if indirect {
        v.extend(INDIRECT);
    }
    v.into_iter().map(String::from).collect()
}

type Change = (&'static str, fn(&mut Scene), &'static [&'static str]);

#[test]
fn each_live_change_equals_a_fresh_renderer_and_records_its_stages() {
    let ctx = gpu();
    let mut want = base();
    let opts = RendererOptions { key_lights: Some(2), ..Default::default() };
    let mut live = Renderer::with_options(&ctx, &want, &opts).unwrap();
    record_frame(&ctx, &mut live);
    let changes: [Change; 10] = [
        (
            "environment rotated and dimmed",
            |s| s.environment = s.environment.rotated(rot_z(40.0)).scaled(0.7),
            &[IU, SD],
        ),
        ("key light radiance", |s| s.key_lights[0].radiance = [7.0, 5.0, 3.0], &[IU, SD]),
        ("key light moved", |s| s.key_lights[0] = key_light(55.0, 120.0, 5.0, 6.0), &[IU, VK, SD]),
        ("key light resized", |s| s.key_lights[0].angular_radius = 9f64.to_radians(), &[IU, VK, SD]),
        ("a second key light", |s| s.key_lights.push(key_light(20.0, 300.0, 3.0, 2.0)), &[IU, VK, SD]),
        ("albedo", |s| s.material.albedo = Albedo::Constant([0.3, 0.5, 0.9]), &[SD]),
        ("specular", |s| s.material.specular = Some([0.5, 0.1, 0.05]), &[SD]),
        ("exponent", |s| s.material.exponent = 60.0, &[IU, SD]),
        ("camera", |s| s.camera.position += DVec3::new(30.0, -10.0, 12.0), &[SD]),
        ("back to one key light", |s| s.key_lights.truncate(1), &[IU, VK, SD]),
    ];
    for (what, change, expected) in changes {
        change(&mut want);
        let (submits, pipelines) = (ctx.submit_count(), ctx.pipelines_created());
        match what {
            w if w.starts_with("environment") => live.set_environment(&want.environment),
            w if w.contains("key light") => live.set_key_lights(&want.key_lights),
            "camera" => live.set_camera(&want.camera),
            _ => live.set_material(&want.material),
        }
        .unwrap();
        assert_eq!(ctx.submit_count(), submits, "{what}: a setter submitted work");
        let planned = live.plan_next().names();
        let recorded = record_frame(&ctx, &mut live);
        assert_eq!(ctx.pipelines_created(), pipelines, "{what}: pipelines created by the change");
        assert_eq!(recorded, stages(expected, true), "{what}: recorded stages");
        assert_eq!(planned, recorded, "{what}: plan_next");
        let d = rel_diff(&layers(&ctx, &live), &fresh(&ctx, &want));
        eprintln!("{what}: {recorded:?}, relative difference to a fresh renderer {d:.2e}");
        assert!(d <= 1e-6, "{what}: {d:e} from a freshly created renderer");
    }
    // Nothing changed: nothing recorded, and the shading is the same.
    let before = layers(&ctx, &live);
    assert!(record_frame(&ctx, &mut live).is_empty(), "an unchanged frame recorded stages");
    assert_eq!(rel_diff(&layers(&ctx, &live), &before), 0.0);
    live.destroy(&ctx);
}

#[test]
fn amortised_changes_alternate_then_converge_and_a_diffuse_camera_records_nothing() {
    let ctx = gpu();
    let mut s = base();
    s.gi.amortize = true;
    let mut r = Renderer::new(&ctx, &s).unwrap();
    record_frame(&ctx, &mut r);
    s.environment = s.environment.rotated(rot_z(-70.0));
    r.set_environment(&s.environment).unwrap();
    // Frame 1 (odd): both halves out of date → the indirect light; frame 2 (even): the direct
    // light; frame 3: the indirect light again (it read the old direct light); then nothing.
    let want: [Vec<String>; 4] = [stages(&[IU], true), stages(&[SD], false), stages(&[], true), stages(&[], false)];
    for (f, w) in want.iter().enumerate() {
        let plan = r.plan_next();
        assert_eq!(&record_frame(&ctx, &mut r), w, "frame {}:\n{plan}", f + 1);
    }
    let d = rel_diff(&layers(&ctx, &r), &fresh(&ctx, &s));
    assert!(d <= 1e-6, "amortised: {d:e} from a fresh renderer");
    r.destroy(&ctx);

    let mut diffuse = base();
    diffuse.material.specular = None;
    let mut r = Renderer::new(&ctx, &diffuse).unwrap();
    record_frame(&ctx, &mut r);
    diffuse.camera.position += DVec3::new(-40.0, 5.0, 3.0);
    r.set_camera(&diffuse.camera).unwrap();
    assert!(record_frame(&ctx, &mut r).is_empty(), "diffuse light does not depend on the camera");
    r.destroy(&ctx);
}

#[test]
fn changes_the_renderer_was_not_built_for_are_typed_errors() {
    let ctx = gpu();
    let s = base();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let three = vec![key_light(30.0, 10.0, 3.0, 1.0); 2];
    let e = r.set_key_lights(&three).unwrap_err().to_string();
    assert!(e.contains("at most 1") && e.contains("RendererOptions::key_lights"), "{e}");
    let mut bad = s.key_lights.clone();
    bad[0].radiance[1] = f64::NAN;
    let e = r.set_key_lights(&bad).unwrap_err().to_string();
    assert!(e.contains("key light 0 radiance"), "{e}");
    let mut black = s.material.clone();
    black.albedo = Albedo::Constant([0.0; 3]);
    black.specular = None;
    let e = r.set_material(&black).unwrap_err().to_string();
    assert!(e.contains("reflects light"), "{e}");
    let map = Albedo::Map(vec![[0.5; 3]; 24 * 24]);
    let e = r.set_material(&hfgi::scene::model::Material { albedo: map, ..s.material.clone() }).unwrap_err();
    assert!(e.to_string().contains("albedo"), "{e}");
    let mut matte = s.material.clone();
    matte.specular = None;
    let e = r.set_material(&matte).unwrap_err().to_string();
    assert!(e.contains("no longer has a specular colour") && e.contains("glossy planes"), "{e}");
    // Nothing was applied: the next frame records nothing beyond the first frame.
    assert_eq!(record_frame(&ctx, &mut r).first().map(String::as_str), Some("pyramid.decimate"));
    assert!(record_frame(&ctx, &mut r).is_empty());
    r.destroy(&ctx);

    let mut dark = base();
    dark.environment = Environment { sh: vec![[0.0; 3]; 16] };
    let mut r = Renderer::new(&ctx, &dark).unwrap();
    let e = r.set_environment(&s.environment).unwrap_err().to_string();
    assert!(e.contains("black environment"), "{e}");
    r.set_environment(&dark.environment).unwrap();
    r.destroy(&ctx);
}

/// For a glossy surface (6 shading planes) and a diffuse one (3: its glossy layers read as
/// zero both ways), with f32 planes and with RGBE planes (`gi.shading_storage`: the ring's
/// read-back decodes them as the blocking one does).
#[test]
fn creation_submits_once_and_recorded_transfers_equal_the_blocking_helpers() {
    use hfgi::vk::{Recorder, RingKind, StagingRing};
    let ctx = gpu();
    let mut matte = base();
    matte.material.specular = None;
    let mut packed = base();
    packed.gi.shading_storage = hfgi::scene::model::ShadingStorage::Rgbe;
    for s in [base(), matte, packed] {
        let before = ctx.submit_count();
        let mut blocking = Renderer::new(&ctx, &s).unwrap();
        assert_eq!(ctx.submit_count() - before, 1, "creating a renderer submits once");
        let mut recorded = Renderer::new(&ctx, &s).unwrap();
        record_frame(&ctx, &mut blocking);
        record_frame(&ctx, &mut recorded);
        let next = rough_field(24, 24, 9);
        blocking.update_heights(&ctx, &next).unwrap();
        record_frame(&ctx, &mut blocking);
        let want = layers(&ctx, &blocking);
        let mut up = StagingRing::new(&ctx, "test.upload", 24 * 24 * 4, RingKind::Upload).unwrap();
        // 5 planes for the glossy surface, 3 for the diffuse one; an RGB f32 triple or an RGBE
        // word per texel.
        let planes = if s.material.specular.is_some() { 5 } else { 3 };
        let texel = if s.gi.shading_format() == hfgi::scene::model::ShadingFormat::Rgbe { 4 } else { 12 };
        assert_eq!(recorded.read_layers_bytes(), planes * 24 * 24 * texel);
        let mut down =
            StagingRing::new(&ctx, "test.readback", recorded.read_layers_bytes(), RingKind::Readback).unwrap();
        let submits = ctx.submit_count();
        let (stages, token) = ctx
            .submit_and_wait(|cmd| {
                let mut rec = Recorder::new(&ctx, cmd, None);
                recorded.record_heights_upload(&mut rec, &mut up, &next)?;
                recorded.record(&mut rec);
                let token = recorded.record_read_layers(&mut rec, &mut down)?;
                Ok((rec.stages().to_vec(), token))
            })
            .unwrap();
        assert_eq!(ctx.submit_count() - submits, 1, "only the test's own submit");
        assert_eq!(stages.first().map(String::as_str), Some("heights.upload"));
        assert_eq!(stages.last().map(String::as_str), Some("shade.readback"));
        let got = token.layers(&mut down).unwrap();
        assert_eq!(rel_diff(&got, &want), 0.0, "recorded upload + read-back differ from the blocking helpers");
        let glossy = got.glossy.iter().chain(&got.indirect_glossy).flatten().fold(0f32, |m, v| m.max(v.abs()));
        assert_eq!(glossy == 0.0, s.material.specular.is_none(), "glossy layers: max {glossy}");
        // A full ring is a typed error, not an overwrite.
        let null = hfgi::ash::vk::CommandBuffer::null();
        let e = recorded.record_read_layers(&mut Recorder::new(&ctx, null, None), &mut down);
        assert!(e.unwrap_err().to_string().contains("reset() the ring"));
        up.reset();
        down.reset();
        up.destroy(&ctx);
        down.destroy(&ctx);
        blocking.destroy(&ctx);
        recorded.destroy(&ctx);
    }
}
