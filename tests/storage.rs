//! `gi.storage = "f16"` (docs/performance.md §9): the visibility vectors `V`, the IR vectors `U`
//! and the radiance stack stored as IEEE halves.
//!
//! - The packing: every stored `V` value is the f32 pipeline's value rounded to a half (within
//!   half an ulp, 2⁻¹¹ relative), for even and odd `n²` (the odd one pads each receiver to an
//!   even count), two light sets (the second set's offset) and a sub-sampled receiver grid; the
//!   radiance stack (planes of odd size) and `U` follow the f32 pipeline's within the rounding
//!   of `V` they inherit.
//! - The error it adds, against the exact reference (`render_truth_gpu`), on the hard fields of
//!   `scenes/hard/` at a reduced size (as tests/accuracy.rs): at most 0.05 percentage points in
//!   every layer, and the f16 shading within 1e-3 (relative L2) of the f32 shading.
//! - The range: `U` and the radiance stack are pre-exposed (`frame::storage::pre_exposure`), so
//!   lights in physical units keep the half's precision, and the pre-exposure follows the live
//!   lights.

mod common;

use std::path::Path;

use common::scenes::{key_light, rel_l2, scene};
use common::{debug_buffers, find_buffer, gpu, render_layers, rough_field};
use hfgi::frame::truth::render_truth_gpu;
use hfgi::frame::ShadingFormat;
use hfgi::math::rgbe;
use hfgi::reference::truth::TruthSettings;
use hfgi::scene::model::{Scene, ShadingStorage, Storage};

/// `s` with `storage` and f32 shading planes (RGBE planes are compared with f32 planes on their
/// own, below).
fn with_storage(s: &Scene, storage: Storage) -> Scene {
    let mut s = s.clone();
    s.gi.storage = storage;
    s.gi.shading_storage = ShadingStorage::F32;
    s
}

/// One layer of two renders: its name, the first's, the second's.
type LayerPair<'a> = (&'static str, &'a Vec<[f32; 3]>, &'a Vec<[f32; 3]>);

/// The direct, indirect and total layers of two renders, by name.
fn layer_pairs<'a>(a: &'a hfgi::frame::ShadingLayers, b: &'a hfgi::frame::ShadingLayers) -> [LayerPair<'a>; 3] {
    [("direct", &a.direct, &b.direct), ("indirect", &a.indirect, &b.indirect), ("total", &a.total, &b.total)]
}

/// A layer in f64, as `rel_l2` takes its reference.
fn to64(v: &[[f32; 3]]) -> Vec<[f64; 3]> {
    v.iter().map(|p| p.map(f64::from)).collect()
}

#[test]
fn f16_vectors_are_the_f32_vectors_rounded() {
    let ctx = gpu();
    for (n, sub) in [(4usize, 1u32), (3, 2), (5, 1)] {
        let mut s = scene(rough_field(37, 29, 5));
        s.gi.sh_order = n;
        s.gi.subsample = sub;
        s.gi.azimuths = 16;
        s.gi.bounces = 1;
        s.key_lights = vec![key_light(35.0, 60.0, 4.0, 3.0)];
        let a = debug_buffers(&ctx, &with_storage(&s, Storage::F32));
        let b = debug_buffers(&ctx, &with_storage(&s, Storage::F16));
        for name in ["visibility.v.environment", "visibility.v.key0"] {
            let (x, y) = (find_buffer(&a, name), find_buffer(&b, name));
            assert_eq!(x.len(), y.len(), "n = {n}: {name}");
            assert!(x.iter().any(|v| v.abs() > 1e-3), "n = {n}: {name} is empty");
            for (i, (v32, v16)) in x.iter().zip(y).enumerate() {
                // Round to nearest: within half an ulp of the half, 2^-11 relative (2^-25 below
                // the normal range).
                let tol = (v32.abs() * 2f32.powi(-11)).max(2f32.powi(-25));
                assert!((v32 - v16).abs() <= tol, "n = {n}, {name}[{i}]: f32 {v32} vs f16 {v16}");
            }
        }
        // The radiance stack (planes of odd size: a word may hold two planes' values) and U
        // come from the shading of f16 V: within 1e-3 (relative L2) of the f32 pipeline's.
        for name in ["radiance.stack", "indirect.u"] {
            let (x, y) = (find_buffer(&a, name), find_buffer(&b, name));
            assert_eq!(x.len(), y.len(), "n = {n}: {name}");
            let e = (x.iter().zip(y).map(|(p, q)| ((p - q) as f64).powi(2)).sum::<f64>()
                / x.iter().map(|p| (*p as f64).powi(2)).sum::<f64>())
            .sqrt();
            assert!(e > 0.0 && e <= 1e-3, "n = {n}: {name} f16 vs f32 relative L2 {e:e}");
            eprintln!("n = {n}, subsample {sub}: {name} f16 vs f32 {e:.2e}");
        }
    }
}

/// Every mode that reads or writes the f16 buffers renders with f16 within 1e-3 (relative L2,
/// every layer) of the same scene with f32: the true pyramid with the glossy vector pyramid
/// (no radiance stack; U from the vector pyramid), swept horizons, sphere blockers in log
/// space (which read `V`), a periodic field, three bounces with sub-sampling 4.
#[test]
fn f16_renders_every_mode_like_f32() {
    let ctx = gpu();
    let sphere = "[[sphere]]\ncenter = [12.0, 10.0, 6.0]\nradius = 3.0\n";
    let cases: [(&str, &str, &[&str]); 5] = [
        (
            "pyramid, glossy vector",
            "",
            &["gi.pyramid=\"pyramid\"", "gi.glossy_pyramid=\"vector\"", "material.specular=[0.2,0.2,0.2]"],
        ),
        ("sweep", "", &["gi.visibility=\"sweep\""]),
        ("spheres, log_field", sphere, &["gi.blocker_shading=\"log_field\"", "environment.preset=\"sky\""]),
        ("wrap", "", &["heightfield.wrap=true"]),
        ("subsample 4, 3 bounces", "", &["gi.subsample=4", "gi.bounces=3", "heightfield.size=[64,41]"]),
    ];
    for (label, text, extra) in cases {
        let mut o: Vec<String> =
            ["heightfield.size=[37,29]", "gi.azimuths=8", "gi.bounces=1"].map(String::from).to_vec();
        o.extend(extra.iter().map(|s| s.to_string()));
        let s =
            hfgi::scene::file::parse_scene(text, Path::new("."), "test", &o).unwrap_or_else(|e| panic!("{label}: {e}"));
        let a = render_layers(&ctx, &with_storage(&s, Storage::F32));
        let b = render_layers(&ctx, &with_storage(&s, Storage::F16));
        for (layer, x, y) in
            [("direct", &a.direct, &b.direct), ("indirect", &a.indirect, &b.indirect), ("total", &a.total, &b.total)]
        {
            let d = rel_l2(y, &to64(x));
            assert!(y.iter().flatten().all(|v| v.is_finite()), "{label}: f16 {layer} not finite");
            assert!(d <= 1e-3, "{label}: {layer} f16 vs f32 {d:e}");
            eprintln!("{label}: {layer} f16 vs f32 {d:.2e}");
        }
    }
}

/// RGBE shading planes (`gi.shading_storage = "rgbe"`) are words as the host packs them
/// (`math::rgbe::pack`: the Vulkan rule's exponent, ties to even): every word is the packing of
/// its own value (shared exponent from the largest channel, that channel's mantissa normalised
/// to 128…255), on a glossy surface with several bounces and a local light, sub-sampled and not
/// (the indirect shade's, the local lights' and the total's read-modify-writes), and every value
/// is finite.
#[test]
fn rgbe_shading_planes_are_the_hosts_words() {
    let ctx = gpu();
    for (sub, glossy) in [(1u32, false), (2, true)] {
        let mut s = scene(rough_field(37, 29, 5));
        s.gi.subsample = sub;
        s.gi.azimuths = 8;
        s.gi.bounces = 2;
        s.key_lights = vec![key_light(35.0, 60.0, 4.0, 3.0)];
        if glossy {
            // With a local light too: shade.local_lights adds to the packed planes.
            s.material.specular = Some([0.2, 0.25, 0.3]);
            s.local_lights = vec![hfgi::scene::model::LocalLight {
                position: glam::DVec3::new(18.0, 14.0, 9.0),
                radius: 1.5,
                radiance: [40.0, 30.0, 20.0],
            }];
        }
        let mut s = with_storage(&s, Storage::F16);
        s.gi.shading_storage = ShadingStorage::Rgbe;
        let words = common::render_with(&ctx, &s, |ctx, r| {
            assert_eq!(r.shading_format(), ShadingFormat::Rgbe);
            let b = r.shading_buffer();
            hfgi::vk::memory::download(ctx, b, 0, b.size).unwrap()
        });
        let words: Vec<u32> = words.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        assert_eq!(words.len(), 37 * 29 * if glossy { 6 } else { 3 });
        assert!(words.iter().filter(|w| **w != 0).count() > words.len() / 3, "sub {sub}: planes mostly empty");
        for (i, &w) in words.iter().enumerate() {
            let v = rgbe::unpack(w);
            assert!(v.iter().all(|c| c.is_finite()), "sub {sub}: word {i} ({w:#x}) not finite");
            assert_eq!(rgbe::pack(v), w, "sub {sub}: word {i} ({w:#x} = {v:?}) is not the host's packing");
        }
    }
}

/// Per layer (direct, indirect, total): the errors of `a` and `b` (two settings of `s`) against
/// `s`'s exact reference and `b` against `a` (relative L2), printed with `what`.
fn errors_against_the_reference(what: &str, s: &Scene, a: &Scene, b: &Scene) -> [(&'static str, f64, f64, f64); 3] {
    let ctx = gpu();
    let exact = render_truth_gpu(&ctx, s, &TruthSettings::default(), &mut |_, _| {}).unwrap();
    let (a, b) = (render_layers(&ctx, a), render_layers(&ctx, b));
    let refs = [&exact.direct, &exact.indirect, &exact.total];
    let mut out = [("", 0.0, 0.0, 0.0); 3];
    for (k, ((layer, x, y), r)) in layer_pairs(&a, &b).into_iter().zip(refs).enumerate() {
        let (ea, eb, d) = (rel_l2(x, r), rel_l2(y, r), rel_l2(y, &to64(x)));
        eprintln!("{what} {layer}: {:.3}% → {:.3}% (exact); against each other {d:.2e}", 100.0 * ea, 100.0 * eb);
        out[k] = (layer, ea, eb, d);
    }
    out
}

/// RGBE shading planes against f32 planes (both with f16 storage) and the exact reference: the
/// error of no layer grows by more than 0.02 percentage points, and the shading stays within
/// 5e-3 (relative L2) of the f32 planes' — the 8-bit mantissa's rounding (at most 2⁻⁹ of a
/// texel's largest channel, so more relative to a smaller channel: 1.7e-3 to 4.1e-3 measured),
/// repeated where a plane is read, summed and written again (the indirect bounces, the total).
/// docs/performance.md §36.
fn rgbe_against_the_reference(file: &str, size: &str, extra: &[&str]) {
    let s = load(file, size, extra);
    let f32_planes = with_storage(&s, Storage::F16);
    let mut rgbe = f32_planes.clone();
    rgbe.gi.shading_storage = ShadingStorage::Rgbe;
    let what = format!("{file} {size} {extra:?}, f32 → RGBE planes");
    for (layer, e32, ergbe, d) in errors_against_the_reference(&what, &s, &f32_planes, &rgbe) {
        // Lower is allowed: the rounding moves the error either way, by up to the rounding's
        // own size (steep's sub-sampled total: 9.303% → 9.282%).
        assert!(ergbe - e32 <= 2e-4, "{file} {layer}: RGBE {ergbe:e} vs f32 {e32:e} against the reference");
        assert!(d > 0.0 && d <= 5e-3, "{file} {layer}: RGBE vs f32 planes {d:e}");
    }
}

/// The f16 pipeline's error against the exact reference is the f32 pipeline's (± 0.05 points per
/// layer) and its shading within 1e-3 of the f32 shading.
fn against_the_reference(file: &str, size: &str, extra: &[&str]) {
    let s = load(file, size, extra);
    let (f32_, f16) = (with_storage(&s, Storage::F32), with_storage(&s, Storage::F16));
    let what = format!("{file} {size} {extra:?}, f32 → f16");
    for (layer, e32, e16, d) in errors_against_the_reference(&what, &s, &f32_, &f16) {
        assert!((e16 - e32).abs() <= 5e-4, "{file} {layer}: f16 {e16:e} vs f32 {e32:e} against the reference");
        assert!(d > 0.0 && d <= 1e-3, "{file} {layer}: f16 vs f32 shading {d:e}");
    }
}

#[test]
fn rgbe_planes_add_little_error_on_terraces_and_steep_sub_sampled() {
    rgbe_against_the_reference("terraces.toml", "48", &["gi.bounces=2"]);
    rgbe_against_the_reference("steep.toml", "[48, 34]", &["gi.subsample=2", "gi.bounces=2"]);
}

/// RGBE planes keep f32's range: a key light of radiance 10¹¹ renders within 5e-3 of f32 planes
/// in every layer, finite (a 5-bit exponent, as `E5B9G9R9`, would clamp at 65408: tried, the
/// direct layer was 94% off).
#[test]
fn rgbe_planes_keep_physical_units() {
    let ctx = gpu();
    let mut s = physical_units_scene();
    let a = render_layers(&ctx, &s);
    s.gi.shading_storage = ShadingStorage::Rgbe;
    let b = render_layers(&ctx, &s);
    for (layer, x, y) in layer_pairs(&a, &b) {
        assert!(y.iter().flatten().all(|v| v.is_finite()), "RGBE {layer} is not finite");
        let e = rel_l2(y, &to64(x));
        assert!(e > 0.0 && e <= 5e-3, "{layer}: RGBE vs f32 planes {e:e}");
        eprintln!("key light 1e11: {layer} RGBE vs f32 planes {e:.2e}");
    }
}

/// A key light of radiance 10¹¹ (within `limits::MAX_RADIANCE`) on a 32×24 rough field, one
/// bounce: the f16 pre-exposure's and the RGBE planes' range test.
fn physical_units_scene() -> Scene {
    let mut s = scene(rough_field(32, 24, 9));
    s.gi.azimuths = 8;
    s.gi.bounces = 1;
    s.key_lights = vec![key_light(40.0, 30.0, 0.27, 1e11)];
    s
}

fn load(file: &str, size: &str, extra: &[&str]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hard").join(file);
    let mut o = vec![format!("heightfield.size={size}")];
    o.extend(extra.iter().map(|s| s.to_string()));
    hfgi::scene::file::load_scene(&path, &o).unwrap()
}

#[test]
fn f16_adds_no_error_on_terraces() {
    against_the_reference("terraces.toml", "48", &[]);
}

#[test]
fn f16_adds_no_error_on_spikes_sub_sampled() {
    against_the_reference("spikes.toml", "48", &["gi.subsample=2"]);
}

#[test]
fn f16_adds_no_error_on_a_steep_non_square_field_below_zero() {
    against_the_reference("steep.toml", "[48, 34]", &[]);
}

/// Pre-exposure (`frame::storage::pre_exposure`, docs/performance.md §14): `U` and the radiance
/// stack are stored times a power of two that follows the lights, so a key light of radiance
/// 10¹¹ (within `limits::MAX_RADIANCE`, 10⁶ times the half's range) renders with f16 within
/// 1e-3 (relative L2) of f32 in every layer, and finite. Without it (scale 1: tried) `U` and the
/// stack were clamped at 65504 and the indirect light lost more than half of its sum.
#[test]
fn f16_is_pre_exposed_so_physical_units_keep_their_precision() {
    let ctx = gpu();
    let s = physical_units_scene();
    let a = render_layers(&ctx, &with_storage(&s, Storage::F32));
    let b = render_layers(&ctx, &with_storage(&s, Storage::F16));
    for (layer, x, y) in layer_pairs(&a, &b) {
        assert!(y.iter().flatten().all(|v| v.is_finite()), "f16 {layer} is not finite");
        let e = rel_l2(y, &to64(x));
        assert!(e <= 1e-3, "{layer}: f16 vs f32 {e:e}");
        eprintln!("key light 1e11: {layer} f16 vs f32 {e:.2e}");
    }
}

/// Lights scaled by 2²⁰ after creation (`Renderer::set_environment`, `set_key_lights`) give, with
/// f16, exactly 2²⁰ times the shading: the pre-exposure follows the live lights by the same power
/// of two, so the same halves are stored. Without the renderer updating it, the scaled stack and
/// `U` would pass the half's range (2¹⁰ · 2²⁰) and be clamped.
/// RGBE planes give the same exactness: the scale moves their exponents only.
#[test]
fn f16_pre_exposure_follows_the_live_lights_exactly() {
    follows_the_live_lights_exactly(ShadingStorage::F32);
    follows_the_live_lights_exactly(ShadingStorage::Rgbe);
}

fn follows_the_live_lights_exactly(planes: ShadingStorage) {
    let ctx = gpu();
    let mut s = scene(rough_field(32, 24, 4));
    s.gi.azimuths = 8;
    s.gi.bounces = 2;
    s.gi.amortize = false;
    s = with_storage(&s, Storage::F16);
    s.gi.shading_storage = planes;
    let mut r = hfgi::frame::Renderer::new(&ctx, &s).unwrap();
    common::record_frame(&ctx, &mut r);
    let a = r.read_layers(&ctx).unwrap();
    let k = 2f64.powi(20);
    let env = hfgi::scene::model::Environment { sh: s.environment.sh.iter().map(|c| c.map(|v| v * k)).collect() };
    let keys: Vec<_> = s
        .key_lights
        .iter()
        .map(|l| hfgi::scene::model::KeyLight { radiance: l.radiance.map(|v| v * k), ..l.clone() })
        .collect();
    r.set_environment(&env).unwrap();
    r.set_key_lights(&keys).unwrap();
    common::record_frame(&ctx, &mut r);
    let b = r.read_layers(&ctx).unwrap();
    r.destroy(&ctx);
    for (layer, x, y) in layer_pairs(&a, &b) {
        assert!(x.iter().flatten().any(|v| *v > 0.0), "{planes:?} planes: {layer} is dark");
        for (i, (p, q)) in x.iter().flatten().zip(y.iter().flatten()).enumerate() {
            assert_eq!(p * k as f32, *q, "{planes:?} planes, {layer}[{i}]: {p} × 2^20 ≠ {q}");
        }
    }
}
