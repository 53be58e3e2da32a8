//! `gi.storage = "f16"` (docs/performance.md §9): the visibility vectors `V` and the IR vectors
//! `U` stored as IEEE halves.
//!
//! - The packing: every stored `V` value is the f32 pipeline's value rounded to a half (within
//!   half an ulp, 2⁻¹¹ relative), for even and odd `n²` (the odd one pads each receiver to an
//!   even count), two light sets (the second set's offset) and a sub-sampled receiver grid;
//!   `U` follows the f32 `U` within the rounding of `V` it inherits.
//! - The error it adds, against the exact reference (`render_truth_gpu`), on the hard fields of
//!   `scenes/hard/` at a reduced size (as tests/accuracy.rs): at most 0.05 percentage points in
//!   every layer, and the f16 shading within 1e-3 (relative L2) of the f32 shading.

mod common;

use std::path::Path;

use common::scenes::{key_light, rel_l2, scene};
use common::{gpu, render_layers, render_with, rough_field};
use hfgi::frame::truth::render_truth_gpu;
use hfgi::reference::truth::TruthSettings;
use hfgi::scene::model::{Scene, Storage};

fn with_storage(s: &Scene, storage: Storage) -> Scene {
    let mut s = s.clone();
    s.gi.storage = storage;
    s
}

/// The named debug buffers (`Renderer::debug_buffers`) of one frame.
fn buffers(ctx: &hfgi::vk::Context, s: &Scene) -> Vec<(String, Vec<f32>)> {
    render_with(ctx, s, |ctx, r| r.debug_buffers(ctx).unwrap())
}

fn find<'a>(b: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &b.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no buffer {name}")).1
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
        let a = buffers(&ctx, &with_storage(&s, Storage::F32));
        let b = buffers(&ctx, &with_storage(&s, Storage::F16));
        for name in ["visibility.v.environment", "visibility.v.key0"] {
            let (x, y) = (find(&a, name), find(&b, name));
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
            let (x, y) = (find(&a, name), find(&b, name));
            assert_eq!(x.len(), y.len(), "n = {n}: {name}");
            let e = (x.iter().zip(y).map(|(p, q)| ((p - q) as f64).powi(2)).sum::<f64>()
                / x.iter().map(|p| (*p as f64).powi(2)).sum::<f64>())
            .sqrt();
            assert!(e > 0.0 && e <= 1e-3, "n = {n}: {name} f16 vs f32 relative L2 {e:e}");
            eprintln!("n = {n}, subsample {sub}: {name} f16 vs f32 {e:.2e}");
        }
    }
}

fn load(file: &str, size: &str, extra: &[&str]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hard").join(file);
    let mut o = vec![format!("heightfield.size={size}")];
    o.extend(extra.iter().map(|s| s.to_string()));
    hfgi::scene::file::load_scene(&path, &o).unwrap()
}

/// The f16 pipeline's error against the exact reference is the f32 pipeline's (± 0.05 points per
/// layer) and its shading within 1e-3 of the f32 shading.
fn against_the_reference(file: &str, size: &str, extra: &[&str]) {
    let ctx = gpu();
    let s = load(file, size, extra);
    let exact = render_truth_gpu(&ctx, &s, &TruthSettings::default(), &mut |_, _| {}).unwrap();
    let a = render_layers(&ctx, &with_storage(&s, Storage::F32));
    let b = render_layers(&ctx, &with_storage(&s, Storage::F16));
    for (layer, x, y, r) in [
        ("direct", &a.direct, &b.direct, &exact.direct),
        ("indirect", &a.indirect, &b.indirect, &exact.indirect),
        ("total", &a.total, &b.total, &exact.total),
    ] {
        let (e32, e16) = (rel_l2(x, r), rel_l2(y, r));
        let x64: Vec<[f64; 3]> = x.iter().map(|p| p.map(f64::from)).collect();
        let d = rel_l2(y, &x64);
        eprintln!(
            "{file} {size} {extra:?} {layer}: f32 {:.3}%, f16 {:.3}% (exact); f16 vs f32 {d:.2e}",
            100.0 * e32,
            100.0 * e16
        );
        assert!((e16 - e32).abs() <= 5e-4, "{file} {layer}: f16 {e16:e} vs f32 {e32:e} against the reference");
        assert!(d > 0.0 && d <= 1e-3, "{file} {layer}: f16 vs f32 shading {d:e}");
    }
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
