//! Height-field generators, loaders and image writers: round trips and rejections.

use std::path::{Path, PathBuf};

use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, LayerAttributes, Vec2, WritableImage};
use half::f16;
use hfgi::io::exr::{read_layers, write_layers, write_rgb_layers, write_scalar, Layer};
use hfgi::io::png::{srgb_encode, write_gray_normalized, write_tonemapped, NAN_COLOUR};
use hfgi::scene::generators::{det_sin, names, Generator};
use hfgi::scene::load::{load_heightfield, save_png16, save_raw, LoadOptions};
use hfgi::scene::HeightField;
use hfgi::Error;
use image::{ExtendedColorType, ImageEncoder};

// ---------------------------------------------------------------------------------------------
// Helpers

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}

fn opts() -> LoadOptions {
    LoadOptions::default()
}

fn raw_opts(w: usize, h: usize) -> LoadOptions {
    LoadOptions { raw_size: Some((w, h)), ..LoadOptions::default() }
}

/// Loads, expecting an error; returns it with its message.
fn load_err(path: &Path, o: &LoadOptions) -> (Error, String) {
    match load_heightfield(path, o) {
        Ok(f) => panic!("{} loaded as a {}×{} field; expected an error", path.display(), f.width(), f.height()),
        Err(e) => {
            let msg = e.to_string();
            (e, msg)
        }
    }
}

/// Asserts that `msg` names the file and contains every one of `facts`.
fn assert_msg(msg: &str, path: &Path, facts: &[&str]) {
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(msg.contains(name), "message does not name the file {name}: {msg}");
    for f in facts {
        assert!(msg.contains(f), "message lacks '{f}': {msg}");
    }
}

/// Cuts the file at `path` to half its length.
fn truncate_half(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    std::fs::write(path, &bytes[..bytes.len() / 2]).unwrap();
}

fn write_png(path: &Path, w: u32, h: u32, bytes: &[u8], color: ExtendedColorType) {
    let file = std::fs::File::create(path).unwrap();
    image::codecs::png::PngEncoder::new(file).write_image(bytes, w, h, color).unwrap();
}

fn write_png16(path: &Path, w: u32, h: u32, values: &[u16]) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
    write_png(path, w, h, &bytes, ExtendedColorType::L16);
}

/// Writes an uncompressed single-part EXR with the given channels.
fn write_exr(path: &Path, w: usize, h: usize, channels: Vec<(&str, FlatSamples)>) {
    let list = channels.into_iter().map(|(name, s)| AnyChannel::new(name, s)).collect();
    let layer =
        exr::image::Layer::new(Vec2(w, h), LayerAttributes::default(), Encoding::UNCOMPRESSED, AnyChannels::sort(list));
    Image::from_layer(layer).write().to_file(path).unwrap();
}

fn f32s(v: &[f32]) -> FlatSamples {
    FlatSamples::F32(v.to_vec())
}

fn f16s(v: &[f32]) -> FlatSamples {
    FlatSamples::F16(v.iter().map(|&x| f16::from_f32(x)).collect())
}

/// A 5×3 ramp of heights, with negative and fractional values (exact in f16).
fn ramp() -> Vec<f32> {
    (0..15).map(|k| k as f32 * 0.75 - 4.0).collect()
}

fn bits(f: &HeightField) -> Vec<u32> {
    f.data().iter().map(|v| v.to_bits()).collect()
}

// ---------------------------------------------------------------------------------------------
// Generators

#[test]
fn generator_names_defaults_and_display_round_trip() {
    assert_eq!(names(), &["fbm", "sines", "cones", "cliff", "craters", "city", "terraces", "spikes"]);
    for name in names() {
        let g: Generator = name.parse().unwrap();
        assert_eq!(g, Generator::default_for(name).unwrap());
        assert_eq!(g.name(), *name);
        let again: Generator = g.to_string().parse().unwrap();
        assert_eq!(again, g, "{g}");
    }
    assert_eq!("FBM".parse::<Generator>().unwrap(), Generator::default_for("fbm").unwrap());
}

#[test]
fn generator_parameters_parse() {
    let g: Generator = "fbm:seed=7, octaves=8,frequency=2.5,amplitude=0.2".parse().unwrap();
    assert_eq!(g, Generator::Fbm { seed: 7, octaves: 8, frequency: 2.5, amplitude: 0.2 });
    let g: Generator = "city:blocks=12,height=0.2".parse().unwrap();
    assert!(matches!(g, Generator::City { seed: 1, blocks: 12, height, .. } if height == 0.2));
    let g: Generator = "cliff:".parse().unwrap();
    assert_eq!(g, Generator::default_for("cliff").unwrap());
}

#[test]
fn generator_parameter_errors() {
    let e = "fbm:colour=3".parse::<Generator>().unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
    assert!(msg.contains("colour") && msg.contains("seed, octaves, frequency, amplitude"), "{msg}");

    let e = "fbm:octaves=many".parse::<Generator>().unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
    assert!(msg.contains("fbm.octaves") && msg.contains("many") && msg.contains("integer"), "{msg}");

    let e = "fbm:octaves=0".parse::<Generator>().unwrap_err();
    assert!(e.to_string().contains("1..=16"), "{e}");

    let e = "sines:frequency=-1".parse::<Generator>().unwrap_err();
    assert!(e.to_string().contains("sines.frequency") && e.to_string().contains("> 0"), "{e}");

    let e = "cliff:position=1.5".parse::<Generator>().unwrap_err();
    assert!(e.to_string().contains("cliff.position"), "{e}");

    let e = "city:density=nan".parse::<Generator>().unwrap_err();
    assert!(e.to_string().contains("city.density"), "{e}");

    let e = "craters:seed".parse::<Generator>().unwrap_err();
    assert!(e.to_string().contains("key=value"), "{e}");

    let e = "mountains".parse::<Generator>().unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
    assert!(msg.contains("mountains") && msg.contains("fbm, sines, cones, cliff, craters, city"), "{msg}");

    let bad = Generator::Fbm { seed: 1, octaves: 40, frequency: 1.0, amplitude: 1.0 };
    assert!(matches!(bad.generate(8, 8), Err(Error::InvalidParameter { .. })));
}

#[test]
fn generators_are_deterministic() {
    for name in names() {
        let g = Generator::default_for(name).unwrap();
        let a = g.generate(37, 23).unwrap();
        let b = g.clone().generate(37, 23).unwrap();
        assert_eq!(bits(&a), bits(&b), "{name}");
    }
}

/// Pins the exact output (FNV-1a of the f32 bits) so a platform or refactoring that changes a
/// single bit is caught.
#[test]
fn generators_match_golden_checksums() {
    fn fnv(f: &HeightField) -> u64 {
        f.data()
            .iter()
            .flat_map(|v| v.to_bits().to_le_bytes())
            .fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
    }
    let got: Vec<(&str, u64)> =
        names().iter().map(|n| (*n, fnv(&Generator::default_for(n).unwrap().generate(33, 17).unwrap()))).collect();
    let want: Vec<(&str, u64)> = GOLDEN.to_vec();
    assert_eq!(got, want);
}

const GOLDEN: [(&str, u64); 8] = [
    ("fbm", 15006484521439985629),
    ("sines", 6532275230212800631),
    ("cones", 6142997224739252925),
    ("cliff", 1960994348892847669),
    ("craters", 125357845671508425),
    ("city", 14778149378463391892),
    ("terraces", 8295839374892931381),
    ("spikes", 4242860902646804452),
];

#[test]
fn seed_changes_the_field() {
    for (a, b) in [
        ("fbm:seed=1", "fbm:seed=2"),
        ("cones:seed=1", "cones:seed=2"),
        ("craters:seed=1", "craters:seed=2"),
        ("city:seed=1", "city:seed=2"),
    ] {
        let fa = a.parse::<Generator>().unwrap().generate(64, 48).unwrap();
        let fb = b.parse::<Generator>().unwrap().generate(64, 48).unwrap();
        assert_ne!(bits(&fa), bits(&fb), "{a} vs {b}");
    }
}

#[test]
fn generators_give_finite_fields_with_relief() {
    for name in names() {
        let g = Generator::default_for(name).unwrap();
        for (w, h) in [(97, 61), (2, 2), (128, 128)] {
            let f = g.generate(w, h).unwrap();
            assert_eq!((f.width(), f.height(), f.data().len()), (w, h, w * h));
            assert!(f.data().iter().all(|v| v.is_finite()), "{name} {w}×{h}");
            let (lo, hi) = f.range();
            assert!(hi > lo, "{name} {w}×{h} is flat ({lo}..{hi})");
            assert!(hi - lo <= w as f32, "{name} {w}×{h}: relief {} is implausibly large", hi - lo);
        }
    }
    // fbm relief is of the order of 0.1·width (visible shadows).
    let f = Generator::default_for("fbm").unwrap().generate(128, 128).unwrap();
    let (lo, hi) = f.range();
    assert!(hi - lo > 0.05 * 128.0 && hi - lo < 0.4 * 128.0, "fbm relief {}", hi - lo);
}

#[test]
fn generators_reject_bad_sizes() {
    let g = Generator::default_for("sines").unwrap();
    assert!(matches!(g.generate(1, 5), Err(Error::FieldSize { width: 1, height: 5, .. })));
    assert!(matches!(g.generate(5, 0), Err(Error::FieldSize { .. })));
    assert!(matches!(g.generate(20000, 2), Err(Error::FieldSize { .. })));
}

#[test]
fn cliff_is_a_vertical_step_at_half_width() {
    let (w, h) = (97, 61);
    let f = Generator::default_for("cliff").unwrap().generate(w, h).unwrap();
    let edge = (0.5 * w as f64).round() as usize;
    let step = 0.25 * w as f32;
    for j in 0..h {
        for i in 0..w {
            let want = if i >= edge { step } else { 0.0 };
            assert_eq!(f.get(i, j), want, "({i}, {j})");
        }
        assert_eq!(f.get(edge, j) - f.get(edge - 1, j), step);
    }
    let f = Generator::default_for("cliff").unwrap().generate(2, 2).unwrap();
    assert_eq!(f.data(), &[0.0, 0.5, 0.0, 0.5]);
}

#[test]
fn cones_and_craters_have_the_documented_shape() {
    // The first cone stands at (w/2, h/2) with height slope·radius·w.
    let f = "cones:count=1,radius=0.25,slope=2".parse::<Generator>().unwrap().generate(64, 64).unwrap();
    assert_eq!(f.get(32, 32), 2.0 * 16.0);
    assert_eq!(f.get(32 + 8, 32), 2.0 * 8.0);
    assert_eq!(f.get(0, 0), 0.0);
    // One crater: bowl floor −depth·r at the centre, rim +rim·r at distance r, flat far away.
    let f = "craters:count=1,radius=0.25,depth=0.5,rim=0.25".parse::<Generator>().unwrap().generate(64, 64).unwrap();
    assert_eq!(f.get(32, 32), -8.0);
    assert_eq!(f.get(32 + 16, 32), 4.0);
    assert_eq!(f.get(0, 0), 0.0);
}

#[test]
fn city_has_flat_streets_and_blocks() {
    let f = "city:blocks=4,street=0.25,density=1".parse::<Generator>().unwrap().generate(64, 64).unwrap();
    // Pitch 16: columns 12..16 of each pitch are street, at ground level.
    for j in 0..64 {
        for k in 0..4 {
            assert_eq!(f.get(16 * k + 13, j), 0.0);
        }
    }
    // With density 1 every lot is built: heights in [0.25, 1]·0.12·64.
    let v = f.get(3, 3);
    assert!((0.25 * 0.12 * 64.0..=0.12 * 64.0).contains(&v), "{v}");
    // Lots are flat-topped rectangles: a 6×6 lot has one height.
    assert!((0..6).all(|j| (0..6).all(|i| f.get(i, j) == v)));
}

#[test]
fn deterministic_sine_is_accurate() {
    for k in -2000..2000 {
        let x = k as f64 * 0.37;
        assert!((det_sin(x) - x.sin()).abs() < 1e-12, "{x}");
    }
    assert_eq!(det_sin(0.0), 0.0);
}

// ---------------------------------------------------------------------------------------------
// PNG loader

#[test]
fn png16_round_trip_is_exact() {
    let dir = tmp();
    let path = dir.path().join("h16.png");
    let values: Vec<u16> = vec![0, 1, 2, 1000, 32767, 32768, 65534, 65535, 12345, 54321, 7, 60000];
    write_png16(&path, 4, 3, &values);
    let scale = 2.5f32;
    let f = load_heightfield(&path, &LoadOptions { height_scale: scale, ..opts() }).unwrap();
    assert_eq!((f.width(), f.height()), (4, 3));
    let want: Vec<f32> = values.iter().map(|&v| v as f32 / 65535.0 * scale).collect();
    assert_eq!(f.data(), want.as_slice());
    // Row 0 of the image is j = 0.
    assert_eq!(f.get(3, 0), 1000.0 / 65535.0 * scale);
    assert_eq!(f.get(1, 2), 54321.0 / 65535.0 * scale);
}

#[test]
fn png8_round_trip_is_exact() {
    let dir = tmp();
    let path = dir.path().join("h8.PNG");
    let values: Vec<u8> = vec![0, 1, 127, 128, 254, 255];
    write_png(&path, 3, 2, &values, ExtendedColorType::L8);
    let f = load_heightfield(&path, &opts()).unwrap();
    let want: Vec<f32> = values.iter().map(|&v| v as f32 / 255.0).collect();
    assert_eq!(f.data(), want.as_slice());
    let f = load_heightfield(&path, &LoadOptions { height_scale: -3.0, ..opts() }).unwrap();
    assert_eq!(f.get(1, 0), 1.0 / 255.0 * -3.0);
}

#[test]
fn save_png16_round_trips_a_generated_field() {
    let dir = tmp();
    let path = dir.path().join("fbm.png");
    let field = Generator::default_for("fbm").unwrap().generate(97, 61).unwrap();
    let (lo, hi) = save_png16(&field, &path).unwrap();
    assert_eq!((lo, hi), field.range());
    let back = load_heightfield(&path, &LoadOptions { height_scale: hi - lo, ..opts() }).unwrap();
    let tol = (hi - lo) / 65535.0;
    for (a, b) in field.data().iter().zip(back.data()) {
        assert!((a - (b + lo)).abs() <= tol, "{a} vs {}", b + lo);
    }
}

#[test]
fn png_rejects_colour_images() {
    let dir = tmp();
    let path = dir.path().join("colour.png");
    write_png(&path, 2, 2, &[0u8; 12], ExtendedColorType::Rgb8);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["Rgb8", "grayscale"]);

    let path = dir.path().join("gray_alpha.png");
    write_png(&path, 2, 2, &[0u8; 8], ExtendedColorType::La8);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["La8", "L8 or L16"]);
}

#[test]
fn png_rejects_truncated_file() {
    let dir = tmp();
    let path = dir.path().join("cut.png");
    let values: Vec<u16> = (0..64 * 64).map(|k| (k * 7919 % 65536) as u16).collect();
    write_png16(&path, 64, 64, &values);
    truncate_half(&path);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["truncated"]);
}

#[test]
fn png_rejects_empty_file() {
    let dir = tmp();
    let path = dir.path().join("empty.png");
    std::fs::write(&path, b"").unwrap();
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["empty file"]);
}

#[test]
fn png_rejects_garbage() {
    let dir = tmp();
    let path = dir.path().join("garbage.png");
    std::fs::write(&path, b"this is not a png file at all").unwrap();
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["not a valid PNG"]);
}

#[test]
fn png_rejects_1x1() {
    let dir = tmp();
    let path = dir.path().join("one.png");
    write_png16(&path, 1, 1, &[5]);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::FieldSize { width: 1, height: 1, .. }), "{e:?}");
    assert_msg(&msg, &path, &["1×1", "at least 2×2"]);
}

#[test]
fn png_rejects_oversized_before_decoding() {
    let dir = tmp();
    let path = dir.path().join("big.png");
    write_png(&path, 40, 2, &[0u8; 80], ExtendedColorType::L8);
    let (e, msg) = load_err(&path, &LoadOptions { max_dim: 32, ..opts() });
    assert!(matches!(e, Error::FieldSize { width: 40, height: 2, max: 32, .. }), "{e:?}");
    assert_msg(&msg, &path, &["40×2"]);
}

// ---------------------------------------------------------------------------------------------
// EXR loader

#[test]
fn exr_round_trips_f32_and_f16_in_each_height_channel() {
    let dir = tmp();
    let v = ramp();
    for channel in ["Y", "R", "height"] {
        for half in [false, true] {
            let path = dir.path().join(format!("h_{channel}_{}.exr", if half { "f16" } else { "f32" }));
            let samples = if half { f16s(&v) } else { f32s(&v) };
            // A decoy channel that is not a height channel.
            write_exr(&path, 5, 3, vec![(channel, samples), ("Z", f32s(&[9.0; 15]))]);
            let f = load_heightfield(&path, &LoadOptions { height_scale: 2.0, ..opts() }).unwrap();
            assert_eq!((f.width(), f.height()), (5, 3), "{path:?}");
            let want: Vec<f32> = v.iter().map(|x| x * 2.0).collect();
            assert_eq!(f.data(), want.as_slice(), "{path:?}");
        }
    }
}

#[test]
fn exr_prefers_y_then_r_then_height() {
    let dir = tmp();
    let (a, b, c) = (vec![1.0f32; 6], vec![2.0f32; 6], vec![3.0f32; 6]);
    let path = dir.path().join("yrh.exr");
    write_exr(&path, 3, 2, vec![("height", f32s(&c)), ("R", f32s(&b)), ("Y", f32s(&a)), ("G", f32s(&c))]);
    assert_eq!(load_heightfield(&path, &opts()).unwrap().data(), a.as_slice());
    let path = dir.path().join("rh.exr");
    write_exr(&path, 3, 2, vec![("height", f32s(&c)), ("R", f32s(&b)), ("G", f32s(&c))]);
    assert_eq!(load_heightfield(&path, &opts()).unwrap().data(), b.as_slice());
}

#[test]
fn exr_written_by_write_scalar_loads() {
    let dir = tmp();
    let path = dir.path().join("scalar.exr");
    let field = Generator::default_for("craters").unwrap().generate(40, 30).unwrap();
    write_scalar(&path, 40, 30, "height", field.data()).unwrap();
    assert_eq!(load_heightfield(&path, &opts()).unwrap(), field);
}

#[test]
fn exr_without_height_channel_names_the_channels_found() {
    let dir = tmp();
    let path = dir.path().join("nochan.exr");
    write_exr(&path, 2, 2, vec![("G", f32s(&[0.0; 4])), ("depth.Z", f32s(&[0.0; 4]))]);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["G, depth.Z", "Y, R, height"]);
}

#[test]
fn exr_rejects_u32_samples() {
    let dir = tmp();
    let path = dir.path().join("u32.exr");
    write_exr(&path, 2, 2, vec![("Y", FlatSamples::U32(vec![1; 4]))]);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["U32", "f16 or f32"]);
}

#[test]
fn exr_rejects_truncated_file() {
    let dir = tmp();
    let path = dir.path().join("cut.exr");
    let v: Vec<f32> = (0..64 * 64).map(|k| k as f32).collect();
    write_exr(&path, 64, 64, vec![("Y", f32s(&v))]);
    truncate_half(&path);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["truncated or corrupt EXR"]);
}

#[test]
fn exr_rejects_header_only_fragment() {
    let dir = tmp();
    let path = dir.path().join("head.exr");
    write_exr(&path, 8, 8, vec![("Y", f32s(&[0.0; 64]))]);
    let bytes = std::fs::read(&path).unwrap();
    for cut in [4, 20, 100] {
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let (e, msg) = load_err(&path, &opts());
        assert!(matches!(e, Error::Format { .. }), "{cut}: {e:?}");
        assert_msg(&msg, &path, &["EXR"]);
    }
}

#[test]
fn exr_rejects_empty_file() {
    let dir = tmp();
    let path = dir.path().join("empty.exr");
    std::fs::write(&path, b"").unwrap();
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["empty file"]);
}

#[test]
fn exr_rejects_1x1() {
    let dir = tmp();
    let path = dir.path().join("one.exr");
    write_exr(&path, 1, 1, vec![("Y", f32s(&[1.0]))]);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::FieldSize { width: 1, height: 1, .. }), "{e:?}");
    assert_msg(&msg, &path, &["1×1", "at least 2×2"]);
}

#[test]
fn exr_rejects_nan_and_inf_with_position() {
    let dir = tmp();
    for (label, bad) in [("nan", f32::NAN), ("inf", f32::INFINITY), ("neginf", f32::NEG_INFINITY)] {
        let path = dir.path().join(format!("{label}.exr"));
        let mut v = ramp();
        v[5 + 3] = bad; // x = 3, y = 1 of a 5×3 field
        write_exr(&path, 5, 3, vec![("Y", f32s(&v))]);
        let (e, msg) = load_err(&path, &opts());
        assert!(matches!(e, Error::NonFinite { x: 3, y: 1, .. }), "{e:?}");
        assert_msg(&msg, &path, &["x=3, y=1", "not finite"]);
    }
    // f16 NaN too.
    let path = dir.path().join("nan16.exr");
    let mut v = ramp();
    v[14] = f32::NAN;
    write_exr(&path, 5, 3, vec![("R", f16s(&v))]);
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::NonFinite { x: 4, y: 2, .. }), "{e:?}");
    assert_msg(&msg, &path, &["x=4, y=2"]);
}

// ---------------------------------------------------------------------------------------------
// Raw loader

#[test]
fn raw_round_trip() {
    let dir = tmp();
    let field = Generator::default_for("city").unwrap().generate(33, 17).unwrap();
    for name in ["h.raw", "h.f32", "h.RAW"] {
        let path = dir.path().join(name);
        save_raw(&field, &path).unwrap();
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 4 * 33 * 17);
        assert_eq!(load_heightfield(&path, &raw_opts(33, 17)).unwrap(), field);
    }
    let path = dir.path().join("h.raw");
    let f = load_heightfield(&path, &LoadOptions { height_scale: 0.5, ..raw_opts(33, 17) }).unwrap();
    assert_eq!(f.get(7, 9), field.get(7, 9) * 0.5);
    // Little-endian, row-major: the first 4 bytes are sample (0, 0).
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(f32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]), field.get(1, 0));
}

#[test]
fn raw_requires_raw_size() {
    let dir = tmp();
    let path = dir.path().join("nosize.raw");
    std::fs::write(&path, [0u8; 16]).unwrap();
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
    assert_msg(&msg, &path, &["raw_size"]);
}

#[test]
fn raw_rejects_wrong_size() {
    let dir = tmp();
    let path = dir.path().join("wrong.raw");
    std::fs::write(&path, vec![0u8; 4 * 10 * 10]).unwrap();
    let (e, msg) = load_err(&path, &raw_opts(12, 10));
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["expected 480 bytes", "found 400 bytes"]);
    let (_, msg) = load_err(&path, &raw_opts(5, 10));
    assert_msg(&msg, &path, &["expected 200 bytes", "found 400 bytes"]);
}

#[test]
fn raw_rejects_truncated_file() {
    let dir = tmp();
    let path = dir.path().join("cut.f32");
    let field = Generator::default_for("sines").unwrap().generate(16, 16).unwrap();
    save_raw(&field, &path).unwrap();
    truncate_half(&path);
    let (e, msg) = load_err(&path, &raw_opts(16, 16));
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["expected 1024 bytes", "found 512 bytes", "truncated"]);
}

#[test]
fn raw_rejects_empty_file() {
    let dir = tmp();
    let path = dir.path().join("empty.raw");
    std::fs::write(&path, b"").unwrap();
    let (e, msg) = load_err(&path, &raw_opts(4, 4));
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["expected 64 bytes", "found 0 bytes", "empty file"]);
}

#[test]
fn raw_rejects_1x1_and_absurd_sizes() {
    let dir = tmp();
    let path = dir.path().join("one.raw");
    std::fs::write(&path, 1.0f32.to_le_bytes()).unwrap();
    let (e, msg) = load_err(&path, &raw_opts(1, 1));
    assert!(matches!(e, Error::FieldSize { width: 1, height: 1, .. }), "{e:?}");
    assert_msg(&msg, &path, &["1×1", "at least 2×2"]);
    // A size that would overflow or exhaust memory is refused before reading.
    let (e, _) = load_err(&path, &raw_opts(usize::MAX, usize::MAX));
    assert!(matches!(e, Error::FieldSize { .. }), "{e:?}");
}

#[test]
fn raw_rejects_nan_and_inf_with_position() {
    let dir = tmp();
    for (label, bad) in [("nan", f32::NAN), ("inf", f32::INFINITY)] {
        let path = dir.path().join(format!("{label}.raw"));
        let mut v = ramp();
        v[5 + 3] = bad;
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(&path, bytes).unwrap();
        let (e, msg) = load_err(&path, &raw_opts(5, 3));
        assert!(matches!(e, Error::NonFinite { x: 3, y: 1, .. }), "{e:?}");
        assert_msg(&msg, &path, &["x=3, y=1", "not finite"]);
    }
}

// ---------------------------------------------------------------------------------------------
// Dispatch

#[test]
fn unknown_extension_lists_supported_ones() {
    let dir = tmp();
    for name in ["h.bmp", "noext"] {
        let path = dir.path().join(name);
        std::fs::write(&path, b"xx").unwrap();
        let (e, msg) = load_err(&path, &opts());
        assert!(matches!(e, Error::Format { .. }), "{e:?}");
        assert_msg(&msg, &path, &[".png", ".exr", ".tif", ".raw", ".f32"]);
    }
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let dir = tmp();
    for name in ["missing.png", "missing.exr", "missing.raw"] {
        let path: PathBuf = dir.path().join(name);
        let (e, msg) = load_err(&path, &raw_opts(4, 4));
        assert!(matches!(e, Error::Io { .. }), "{e:?}");
        assert_msg(&msg, &path, &[]);
    }
}

#[test]
fn non_finite_height_scale_is_rejected() {
    let dir = tmp();
    let path = dir.path().join("h.raw");
    std::fs::write(&path, [0u8; 16]).unwrap();
    let (e, msg) = load_err(&path, &LoadOptions { height_scale: f32::NAN, ..raw_opts(2, 2) });
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
    assert!(msg.contains("height_scale"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// EXR writer

#[test]
fn exr_layers_round_trip() {
    let dir = tmp();
    let path = dir.path().join("shading.exr");
    let (w, h) = (7, 5);
    let n = w * h;
    let px = |o: f32| -> Vec<[f32; 3]> {
        (0..n).map(|k| [k as f32 + o, -(k as f32) * 0.5 + o, 1e-3 * k as f32 + o]).collect()
    };
    let (total, direct, indirect) = (px(100.0), px(10.0), px(1.0));
    write_rgb_layers(&path, w, h, &[("", &total), ("direct", &direct), ("indirect", &indirect)]).unwrap();
    let (rw, rh, chans) = read_layers(&path).unwrap();
    assert_eq!((rw, rh), (w, h));
    let mut names: Vec<(String, String)> = chans.iter().map(|(l, c, _)| (l.clone(), c.clone())).collect();
    names.sort();
    let mut want: Vec<(String, String)> = ["", "direct", "indirect"]
        .iter()
        .flat_map(|l| ["R", "G", "B"].map(|c| (l.to_string(), c.to_string())))
        .collect();
    want.sort();
    assert_eq!(names, want);
    for (layer, channel, data) in &chans {
        let src = match layer.as_str() {
            "" => &total,
            "direct" => &direct,
            "indirect" => &indirect,
            other => panic!("unexpected layer {other}"),
        };
        let c = ["R", "G", "B"].iter().position(|x| x == channel).unwrap();
        let expect: Vec<f32> = src.iter().map(|p| p[c]).collect();
        assert_eq!(data, &expect, "{layer}.{channel}");
    }
    // The stored channel names follow the OpenEXR layer convention.
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    assert_eq!(meta.headers.len(), 1);
    let stored: Vec<String> = meta.headers[0].channels.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(stored, ["B", "G", "R", "direct.B", "direct.G", "direct.R", "indirect.B", "indirect.G", "indirect.R"]);
    assert!(meta.headers[0].channels.list.iter().all(|c| c.sample_type == exr::meta::attribute::SampleType::F32));
}

#[test]
fn exr_generic_layers_and_validation() {
    let dir = tmp();
    let path = dir.path().join("generic.exr");
    let a = [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0];
    let b = [-1.0f32; 6];
    write_layers(
        &path,
        3,
        2,
        &[Layer { name: "glossy", channels: vec![("R", &a)] }, Layer { name: "", channels: vec![("A", &b)] }],
    )
    .unwrap();
    let (w, h, chans) = read_layers(&path).unwrap();
    assert_eq!((w, h), (3, 2));
    assert_eq!(
        chans,
        vec![("".to_string(), "A".to_string(), b.to_vec()), ("glossy".to_string(), "R".to_string(), a.to_vec())]
    );

    let short = [0.0f32; 5];
    let e = write_layers(&path, 3, 2, &[Layer { name: "", channels: vec![("R", &short)] }]).unwrap_err();
    assert!(matches!(e, Error::InvalidParameter { .. }) && e.to_string().contains("6 samples"), "{e}");
    let e = write_layers(&path, 3, 2, &[Layer { name: "x", channels: vec![("R", &a), ("R", &a)] }]).unwrap_err();
    assert!(e.to_string().contains("x.R"), "{e}");
    let e = write_layers(&path, 3, 2, &[]).unwrap_err();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e}");
    let e = write_layers(&path, 0, 2, &[Layer { name: "", channels: vec![] }]).unwrap_err();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e}");
}

#[test]
fn read_layers_rejects_bad_files() {
    let dir = tmp();
    let path = dir.path().join("bad.exr");
    std::fs::write(&path, b"").unwrap();
    let e = read_layers(&path).unwrap_err();
    assert!(matches!(e, Error::Format { .. }) && e.to_string().contains("bad.exr"), "{e:?}");
    let e = read_layers(&dir.path().join("absent.exr")).unwrap_err();
    assert!(matches!(e, Error::Io { .. }) && e.to_string().contains("absent.exr"), "{e:?}");
}

// ---------------------------------------------------------------------------------------------
// PNG writer

#[test]
fn srgb_encode_values() {
    assert_eq!(srgb_encode(0.0), 0.0);
    assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
    assert!((srgb_encode(0.5) - 0.735_356_9).abs() < 1e-6, "{}", srgb_encode(0.5));
    // Linear segment up to and including the threshold, power segment above, continuous.
    let t = 0.003_130_8f32;
    assert_eq!(srgb_encode(t), 12.92 * t);
    let above = f32::from_bits(t.to_bits() + 1);
    assert!((srgb_encode(above) - 12.92 * t).abs() < 1e-6);
    assert!((srgb_encode(0.001) - 0.01292).abs() < 1e-7);
    assert!(srgb_encode(f32::NAN).is_nan());
}

fn read_png_rgb(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::ImageReader::open(path).unwrap().decode().unwrap();
    let rgb = img.to_rgb8();
    (rgb.width(), rgb.height(), rgb.into_raw())
}

#[test]
fn tonemapped_png_pixels() {
    let dir = tmp();
    let path = dir.path().join("tone.png");
    let rgb = [
        [0.0, 0.5, 1.0],
        [0.25, 4.0, -1.0],
        [f32::NAN, 0.0, 0.0],
        [f32::INFINITY, f32::NEG_INFINITY, 0.125],
        [0.0; 3],
        [1.0; 3],
    ];
    write_tonemapped(&path, 3, 2, &rgb, 1.0).unwrap();
    let (w, h, px) = read_png_rgb(&path);
    assert_eq!((w, h), (3, 2));
    let q = |x: f32| (srgb_encode(x) * 255.0 + 0.5) as u8;
    assert_eq!(&px[0..3], &[0, 255, 255]); // ×2: 0, 1, 2→1
    assert_eq!(&px[3..6], &[q(0.5), 255, 0]);
    assert_eq!(&px[6..9], &NAN_COLOUR);
    assert_eq!(&px[9..12], &[255, 0, q(0.25)]);
    assert_eq!(&px[12..15], &[0, 0, 0]);
    assert_eq!(&px[15..18], &[255, 255, 255]);
    assert_eq!(q(0.5), 188);

    let e = write_tonemapped(&path, 4, 2, &rgb, 0.0).unwrap_err();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e}");
    let e = write_tonemapped(&path, 3, 2, &rgb, f32::NAN).unwrap_err();
    assert!(matches!(e, Error::InvalidParameter { .. }), "{e}");
}

#[test]
fn all_nan_image_does_not_panic() {
    let dir = tmp();
    let path = dir.path().join("nan.png");
    write_tonemapped(&path, 2, 2, &[[f32::NAN; 3]; 4], 0.0).unwrap();
    let (_, _, px) = read_png_rgb(&path);
    assert!(px.chunks(3).all(|p| p == NAN_COLOUR));
}

#[test]
fn gray_normalized_png() {
    let dir = tmp();
    let path = dir.path().join("gray.png");
    let data = [-2.0, 0.0, 2.0, f32::NAN, 1.0, f32::INFINITY];
    let range = write_gray_normalized(&path, 3, 2, &data).unwrap();
    assert_eq!(range, (-2.0, 2.0));
    let img = image::ImageReader::open(&path).unwrap().decode().unwrap();
    assert_eq!(img.color(), image::ColorType::L8);
    assert_eq!(img.to_luma8().into_raw(), vec![0, 128, 255, 0, 191, 255]);

    let range = write_gray_normalized(&path, 2, 2, &[3.5; 4]).unwrap();
    assert_eq!(range, (3.5, 3.5));
    let img = image::ImageReader::open(&path).unwrap().decode().unwrap();
    assert_eq!(img.to_luma8().into_raw(), vec![128; 4]);
}

// ---------------------------------------------------------------------------------------------
// Inputs found by fuzzing (docs/robustness.md, "Fuzzing"; the files are also fuzz seeds)

/// A 613-byte B44-compressed tiled EXR (channels Y, Z; 8×8) whose block makes exr's B44 decoder
/// subtract with overflow: a panic where overflow checks are on (tests, debug builds). exr ran
/// its decompressors on its rayon pool, where a panic aborts the whole process past the loaders'
/// `catch_unwind`; both EXR readers now decompress on the calling thread, so the panic is a
/// corrupt-file error (and without overflow checks the decoder wraps, as OpenEXR's does).
#[test]
fn fuzz_exr_decoder_panic_is_an_error_not_an_abort() {
    let dir = tmp();
    let path = dir.path().join("b44.exr");
    std::fs::write(&path, include_bytes!("../fuzz/seeds/heights_exr/crash-b44-overflow.exr")).unwrap();
    match load_heightfield(&path, &opts()) {
        Ok(f) => assert_eq!((f.width(), f.height()), (8, 8)),
        Err(e) => assert_msg(&e.to_string(), &path, &[]),
    }
    if let Err(e) = read_layers(&path) {
        assert_msg(&e.to_string(), &path, &[]);
    }
    // No R, G, B: an error either way, but not an abort.
    let e = hfgi::scene::envmap::load_equirect_exr(&path).unwrap_err();
    assert_msg(&e.to_string(), &path, &[]);
}

/// A 487-byte EXR whose data window is 1073741815×4 pixels (3 f16 channels): exr allocates every
/// channel at the claimed size before decoding, and the environment-map loader took more than
/// 8 GB. The header is now checked against `MAX_ENV_SAMPLES` first.
#[test]
fn fuzz_envmap_claiming_a_huge_size_is_rejected_before_allocating() {
    let dir = tmp();
    let path = dir.path().join("huge.exr");
    std::fs::write(&path, include_bytes!("../fuzz/seeds/envmap_exr/oom-huge-data-window.exr")).unwrap();
    let e = hfgi::scene::envmap::load_equirect_exr(&path).unwrap_err();
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&e.to_string(), &path, &["1073741815×4", "3 channel(s)", "samples"]);
}

/// A 564-byte tiled EXR of 8×8 pixels whose tiles are 83886144×64: exr allocates and zeroes a
/// buffer of up to one tile (here the 1.6 GB a chunk claimed) before reading a block, so the
/// loaders took 1.6 GB before failing at the end of the file. Blocks are now checked against
/// `MAX_EXR_BLOCK_BYTES` from the header, by both EXR loaders.
#[test]
fn fuzz_exr_with_huge_tiles_is_rejected_from_its_header() {
    let dir = tmp();
    let path = dir.path().join("tiles.exr");
    std::fs::write(&path, include_bytes!("../fuzz/seeds/heights_exr/oom-huge-tile.exr")).unwrap();
    let (e, msg) = load_err(&path, &opts());
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert_msg(&msg, &path, &["tiles of 83886144×64 pixels", "at most 67108864"]);
    let msg = hfgi::scene::envmap::load_equirect_exr(&path).unwrap_err().to_string();
    assert_msg(&msg, &path, &["tiles of 83886144×64 pixels"]);
}
