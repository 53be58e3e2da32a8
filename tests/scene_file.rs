//! Scene files (`docs/scene-format.md`): the example scenes, defaults, overrides, error
//! messages, and the environment-map projection.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use hfgi::io::exr::write_rgb_layers;
use hfgi::math::{sh, zh};
use hfgi::scene::envmap::{load_equirect_exr, project_equirect, Preset, PRESET_ORDER};
use hfgi::scene::file::{default_scene, load_scene, parse_scene, DEFAULT_KEY_RADIANCE};
use hfgi::scene::generators::Generator;
use hfgi::scene::load::save_png16;
use hfgi::scene::model::{Albedo, Camera, GiSettings, Interpolation, Material, PyramidMode, Scene};
use hfgi::Error;
use image::{ExtendedColorType, ImageEncoder};

// ---------------------------------------------------------------------------------------------
// Helpers

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn parse(text: &str) -> hfgi::Result<Scene> {
    parse_scene(text, Path::new("."), "test.toml", &[])
}

fn parse_with(text: &str, overrides: &[&str]) -> hfgi::Result<Scene> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_scene(text, Path::new("."), "test.toml", &o)
}

/// Parses, expecting a scene-file error; returns `(key, message)`. The message must name the
/// file.
fn err_of(r: hfgi::Result<Scene>) -> (Option<String>, String) {
    match r {
        Ok(_) => panic!("expected an error, the scene loaded"),
        Err(e) => {
            let msg = e.to_string();
            match e {
                Error::SceneFile { file, key, .. } => {
                    assert!(msg.starts_with(&format!("{file}: ")), "message does not start with the file: {msg}");
                    (key, msg)
                }
                other => panic!("expected Error::SceneFile, got {other:?}"),
            }
        }
    }
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message should mention {p:?}: {msg}");
    }
}

fn assert_same_scene(a: &Scene, b: &Scene) {
    assert_eq!(a.field, b.field);
    assert_eq!(a.texel_size, b.texel_size);
    assert_eq!(a.wrap, b.wrap);
    assert_eq!(a.material, b.material);
    assert_eq!(a.environment, b.environment);
    assert_eq!(a.key_lights, b.key_lights);
    assert_eq!(a.gi, b.gi);
    assert_eq!(a.camera, b.camera);
}

/// Luminance of an RGB triple (Rec. 709).
fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Irradiance on a horizontal surface from SH radiance coefficients.
fn horizontal_irradiance(c: &[[f64; 3]]) -> [f64; 3] {
    let n = (c.len() as f64).sqrt() as usize;
    let cc = zh::rotate(n, &zh::clamped_cosine(n), [0.0, 0.0, 1.0]);
    [0, 1, 2].map(|ch| c.iter().zip(&cc).map(|(c, w)| c[ch] * w).sum())
}

fn write_png_rgb(path: &Path, w: u32, h: u32, px: &[u8]) {
    let f = std::fs::File::create(path).unwrap();
    image::codecs::png::PngEncoder::new(f).write_image(px, w, h, ExtendedColorType::Rgb8).unwrap();
}

// ---------------------------------------------------------------------------------------------
// Example scenes and defaults

#[test]
fn every_example_scene_loads() {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let scene = load_scene(&path, &[]).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(scene.field.width() * scene.field.height() <= 256 * 256, "{}: field too large", path.display());
        let lit = !scene.key_lights.is_empty() || !scene.environment.sh.is_empty() || !scene.local_lights.is_empty();
        assert!(lit, "{}: unlit", path.display());
        names.push(path.file_name().unwrap().to_string_lossy().to_string());
    }
    names.sort();
    assert_eq!(
        names,
        [
            "boulders.toml",
            "bumps.toml",
            "city.toml",
            "cliff.toml",
            "craters.toml",
            "day.toml",
            "default.toml",
            "lanterns.toml",
            "terrain-bspline.toml",
            "water.toml"
        ]
    );
}

#[test]
fn example_scenes_have_their_features() {
    let load = |n: &str| load_scene(&scenes_dir().join(n), &[]).unwrap();
    let city = load("city.toml");
    assert_eq!(city.material.specular, Some([0.04; 3]));
    assert_eq!(city.material.exponent, 64.0);
    assert!(city.key_lights[0].direction.z < 0.2, "low sun");
    let day = load("day.toml");
    let hfgi::scene::animated::Animation::Day(p) = &day.animation else { panic!("day.toml: {:?}", day.animation) };
    assert_eq!((p.day_frames, p.max_elevation_deg, p.orbit_turns), (12, 60.0, 0.25));
    let cliff = load("cliff.toml");
    assert_eq!(cliff.environment.sh, Preset::Overcast.sh());
    assert_eq!(cliff.key_lights.len(), 1);
    assert!((cliff.key_lights[0].direction.length() - 1.0).abs() < 1e-12);
    let t = load("terrain-bspline.toml");
    assert_eq!(t.gi.interpolation, Interpolation::Bspline);
    assert_eq!(t.gi.pyramid, PyramidMode::Pyramid);
    assert_eq!(t.gi.subsample, 2);
    assert_eq!((t.field.width(), t.field.height()), (256, 192));
    let craters = load("craters.toml");
    assert_eq!(craters.environment.sh, Preset::Sky.sh());
    assert_eq!((craters.camera.width, craters.camera.height), (1280, 720));
}

#[test]
fn default_scene_is_the_empty_file_and_default_toml() {
    let d = default_scene().unwrap();
    assert_same_scene(&d, &parse("").unwrap());
    assert_same_scene(&d, &parse("# only a comment\n").unwrap());
    assert_same_scene(&d, &load_scene(&scenes_dir().join("default.toml"), &[]).unwrap());

    let fbm = Generator::default_for("fbm").unwrap().generate(256, 256).unwrap();
    assert_eq!(d.field, fbm);
    assert_eq!(d.texel_size, 1.0);
    assert!(!d.wrap);
    assert_eq!(d.material, Material::default());
    assert_eq!(d.environment.sh, Preset::Sky.sh());
    assert_eq!(d.environment.sh.len(), 64);
    assert_eq!(d.gi, GiSettings::default());
    let (lo, hi) = d.field.range();
    assert_eq!(d.camera, Camera::default_for(256, 256, 1.0, lo as f64, hi as f64));

    assert_eq!(d.key_lights.len(), 1);
    let k = &d.key_lights[0];
    let (el, az) = (35f64.to_radians(), 200f64.to_radians());
    let want = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
    for (a, b) in k.direction.to_array().iter().zip(want) {
        assert!((a - b).abs() < 1e-12);
    }
    assert!((k.angular_radius - 3f64.to_radians()).abs() < 1e-15);
    assert_eq!(k.radiance, DEFAULT_KEY_RADIANCE);
}

#[test]
fn default_key_light_matches_the_sky_irradiance() {
    let d = default_scene().unwrap();
    let sky = luminance(horizontal_irradiance(&d.environment.sh));
    let k = &d.key_lights[0];
    // A cap fully above the horizon: ∫cap cosθ dω = π sin²α · cos(θ_centre).
    let key = luminance(k.radiance) * PI * k.angular_radius.sin().powi(2) * k.direction.z;
    let ratio = key / sky;
    assert!((0.8..1.25).contains(&ratio), "key {key} vs sky {sky}");
}

#[test]
fn empty_tables_mean_defaults_and_lighting_rules() {
    let d = default_scene().unwrap();
    let s = parse("[heightfield]\n[material]\n[gi]\n[camera]\n").unwrap();
    assert_same_scene(&d, &s);
    // An empty [environment] is the sky; with no key light given, there is none.
    let s = parse("[environment]\n").unwrap();
    assert_eq!(s.environment.sh, Preset::Sky.sh());
    assert!(s.key_lights.is_empty());
    // Key lights only: no environment light. An empty [[key_light]] is the default sun.
    let s = parse("[[key_light]]\n").unwrap();
    assert!(s.environment.sh.is_empty());
    assert_eq!(s.key_lights, d.key_lights);
    // key_light = [] and no environment: no light at all.
    let s = parse("key_light = []\n").unwrap();
    assert!(s.environment.sh.is_empty() && s.key_lights.is_empty());
}

#[test]
fn values_are_read() {
    let s = parse(
        r#"
        [heightfield]
        generator = "cones:count=2"
        size = [40, 30]
        texel_size = 0.5
        height_scale = 2.0
        wrap = true
        [material]
        albedo = [0.1, 0.2, 0.3]
        specular = [0.5, 0.5, 0.5]
        exponent = 10
        [environment]
        sh = [[1, 2, 3], [0, 0, 0], [0.5, 0.5, 0.5], [0, 0, 0]]
        intensity = 2
        [[key_light]]
        direction = [0, 0, 2]
        angular_radius_deg = 90
        radiance = [1, 2, 3]
        [[key_light]]
        elevation_deg = 0
        azimuth_deg = 90
        [gi]
        sh_order = 6
        azimuths = 8
        key_light_azimuths = 2
        level_step = 1
        level_offset = 0
        subsample = 4
        interpolation = "bspline"
        pyramid = "pyramid"
        [camera]
        position = [1, 2, 3]
        target = [4, 5, 6]
        fov_deg = 60
        width = 64
        height = 48
        exposure = -1.5
        "#,
    )
    .unwrap();
    let gen = Generator::default_for("cones").unwrap();
    let Generator::Cones { seed, radius, slope, .. } = gen else { unreachable!() };
    let base = Generator::Cones { seed, count: 2, radius, slope }.generate(40, 30).unwrap();
    assert_eq!((s.field.width(), s.field.height()), (40, 30));
    // Generated heights are in texel units: × texel_size × height_scale.
    for (a, b) in s.field.data().iter().zip(base.data()) {
        assert_eq!(*a, b * 1.0f32);
    }
    assert!(s.wrap);
    assert_eq!(s.texel_size, 0.5);
    assert_eq!(s.material.albedo, Albedo::Constant([0.1, 0.2, 0.3]));
    assert_eq!(s.material.specular, Some([0.5; 3]));
    assert_eq!(s.material.exponent, 10.0);
    assert_eq!(s.environment.sh, vec![[2.0, 4.0, 6.0], [0.0; 3], [1.0; 3], [0.0; 3]]);
    assert_eq!(s.key_lights.len(), 2);
    assert_eq!(s.key_lights[0].direction.to_array(), [0.0, 0.0, 1.0]);
    assert!((s.key_lights[0].angular_radius - PI / 2.0).abs() < 1e-15);
    assert_eq!(s.key_lights[0].radiance, [1.0, 2.0, 3.0]);
    let d1 = s.key_lights[1].direction;
    assert!(d1.x.abs() < 1e-12 && (d1.y - 1.0).abs() < 1e-12 && d1.z.abs() < 1e-12);
    assert_eq!(
        s.gi,
        GiSettings {
            sh_order: 6,
            azimuths: 8,
            key_light_azimuths: 2,
            level_step: 1,
            level_offset: 0,
            subsample: 4,
            interpolation: Interpolation::Bspline,
            pyramid: PyramidMode::Pyramid,
            bounces: 0,
            amortize: true,
            glossy_pyramid: hfgi::scene::model::GlossyPyramid::Scalar,
            ..GiSettings::default()
        }
    );
    assert_eq!(s.camera.position.to_array(), [1.0, 2.0, 3.0]);
    assert_eq!(s.camera.target.to_array(), [4.0, 5.0, 6.0]);
    assert_eq!((s.camera.fov_deg, s.camera.width, s.camera.height, s.camera.exposure), (60.0, 64, 48, -1.5));
}

#[test]
fn height_scale_and_texel_size_scale_generated_heights() {
    let base = parse("[heightfield]\nsize = 32\n").unwrap().field;
    let s = parse("[heightfield]\nsize = 32\nheight_scale = 2.0\ntexel_size = 1.5\n").unwrap();
    for (a, b) in s.field.data().iter().zip(base.data()) {
        assert_eq!(*a, b * 3.0);
    }
    // Camera defaults follow the field's world size.
    let (lo, hi) = s.field.range();
    assert_eq!(s.camera, Camera::default_for(32, 32, 1.5, lo as f64, hi as f64));
}

#[test]
fn quality_presets_resolve_every_knob_and_explicit_knobs_override_them() {
    use hfgi::scene::model::{ElevationBasis, Horizon, Level0, OmegaMin, Quality, ScanReach};
    let d = parse("").unwrap().gi;
    assert_eq!(d, GiSettings::preset(Quality::Default));
    assert_eq!((d.level0, d.horizon, d.omega_min), (Level0::Bilinear, Horizon::Samples, OmegaMin::Tangent));
    let p = parse("[gi]\nquality = \"paper\"\n").unwrap().gi;
    assert_eq!((p.azimuths, p.level_step, p.level_offset, p.near_steps), (32, 4, 2, 0));
    assert_eq!((p.level0, p.horizon, p.scan_reach), (Level0::Bspline, Horizon::Bspline, ScanReach::Side));
    assert_eq!((p.omega_min, p.elevation_basis), (OmegaMin::Asin, ElevationBasis::Nlp));
    let h = parse("[gi]\nquality = \"high\"\nazimuths = 24\n").unwrap().gi;
    assert_eq!(h.quality, Quality::High);
    assert_eq!(h.azimuths, 24, "an explicit knob overrides the preset");
    assert_eq!(GiSettings { azimuths: 64, ..h.clone() }, GiSettings::preset(Quality::High));
    let u = parse_with("", &["gi.quality=ultra", "gi.level0=bspline"]).unwrap().gi;
    assert_eq!((u.quality, u.level0, u.sh_order), (Quality::Ultra, Level0::Bspline, 8));
    // The ladder is monotone in every sampling knob.
    let ladder: Vec<GiSettings> =
        [Quality::Draft, Quality::Default, Quality::High, Quality::Ultra].map(GiSettings::preset).to_vec();
    for w in ladder.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        assert!(b.azimuths > a.azimuths && b.level_step >= a.level_step && b.level_offset >= a.level_offset);
        assert!(b.near_steps > a.near_steps && b.subsample <= a.subsample && b.sh_order >= a.sh_order);
    }
    // The later bounces' azimuths: every preset's m but `default`'s, every 2nd of its 32
    // (docs/performance.md §32), capped at an explicit smaller m, or set.
    for g in &ladder {
        let want = if g.quality == Quality::Default { g.azimuths / 2 } else { g.azimuths };
        assert_eq!(g.azimuths_later, want, "{:?}", g.quality);
    }
    assert_eq!((h.azimuths_later, h.scan_azimuths(1), h.scan_azimuths(2)), (64, 24, 24));
    let l = parse("[gi]\nazimuths_later = 8\n").unwrap().gi;
    assert_eq!((l.scan_azimuths(1), l.scan_azimuths(2), l.scan_azimuths(3)), (32, 8, 8));
    let err = parse("[gi]\nazimuths_later = 3\n").unwrap_err().to_string();
    assert!(err.contains("gi.azimuths_later") && err.contains("4..=256"), "{err}");
    let err = parse("[gi]\nquality = \"best\"\n").unwrap_err().to_string();
    assert!(err.contains("gi.quality") && err.contains("ultra"), "{err}");
    let err = parse("[gi]\nnear_steps = 65\n").unwrap_err().to_string();
    assert!(err.contains("gi.near_steps") && err.contains("0..=64"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Overrides

#[test]
fn override_integer() {
    let s = parse_with("", &["gi.azimuths=64"]).unwrap();
    assert_eq!(s.gi.azimuths, 64);
    assert_eq!(s.key_lights.len(), 1, "the default lighting stays");
}

#[test]
fn override_array_string_and_bare_string() {
    let s = parse_with("", &["material.albedo=[0.5,0.5,0.5]"]).unwrap();
    assert_eq!(s.material.albedo, Albedo::Constant([0.5; 3]));
    let s = parse_with("", &["heightfield.generator=\"cones\"", "heightfield.size=64"]).unwrap();
    assert_eq!(s.field, Generator::default_for("cones").unwrap().generate(64, 64).unwrap());
    // Text that is not a TOML value is a string: no quotes needed.
    let s = parse_with("", &["heightfield.generator=cones:count=3,seed=2", "heightfield.size=[48, 32]"]).unwrap();
    let want: Generator = "cones:count=3,seed=2".parse().unwrap();
    assert_eq!(s.field, want.generate(48, 32).unwrap());
    let s = parse_with("", &["gi.interpolation=bspline", "gi.pyramid = pyramid", "heightfield.wrap=true"]).unwrap();
    assert_eq!((s.gi.interpolation, s.gi.pyramid, s.wrap), (Interpolation::Bspline, PyramidMode::Pyramid, true));
}

#[test]
fn override_key_light_elements_and_tables() {
    // An element of the default key light array.
    let s = parse_with("", &["key_light.0.radiance=[1,1,1]"]).unwrap();
    assert_eq!(s.key_lights[0].radiance, [1.0; 3]);
    // One past the end appends a light with default values.
    let s = parse_with("", &["key_light.1.elevation_deg=10"]).unwrap();
    assert_eq!(s.key_lights.len(), 2);
    assert!((s.key_lights[1].direction.z - 10f64.to_radians().sin()).abs() < 1e-12);
    // direction replaces the default angles of the inserted default light.
    let s = parse_with("", &["key_light.0.direction=[0,0,1]"]).unwrap();
    assert_eq!(s.key_lights[0].direction.to_array(), [0.0, 0.0, 1.0]);
    // Creating the array from nothing.
    let s = parse_with("[environment]\n", &["key_light.0.angular_radius_deg=5"]).unwrap();
    assert_eq!(s.key_lights.len(), 1);
    // A whole table as an inline table; the environment preset of the default scene.
    let s = parse_with("", &["gi={azimuths=16, subsample=2}", "environment.preset=overcast"]).unwrap();
    assert_eq!((s.gi.azimuths, s.gi.subsample), (16, 2));
    assert_eq!(s.environment.sh, Preset::Overcast.sh());
    assert_eq!(s.key_lights.len(), 1);
    // Later overrides win.
    let s = parse_with("[gi]\nazimuths = 8\n", &["gi.azimuths=16", "gi.azimuths=24"]).unwrap();
    assert_eq!(s.gi.azimuths, 24);
    // Overrides apply to files too.
    let s = load_scene(&scenes_dir().join("city.toml"), &["camera.width=320".to_string()]).unwrap();
    assert_eq!(s.camera.width, 320);
}

#[test]
fn override_errors() {
    let (key, msg) = err_of(parse_with("", &["gi.azimuths"]));
    assert_eq!(key, None);
    assert_mentions(&msg, &["test.toml", "--set gi.azimuths", "key.path=value"]);
    let (_, msg) = err_of(parse_with("", &["gi..azimuths=3"]));
    assert_mentions(&msg, &["not a bare key"]);
    let (key, msg) = err_of(parse_with("", &["key_light.5.radiance=[1,1,1]"]));
    assert_eq!(key.as_deref(), Some("key_light.5.radiance"));
    assert_mentions(&msg, &["index 5", "key_light", "1 element"]);
    // A missing table is created, so this is a type error on gi.azimuths...
    let (key, msg) = err_of(parse_with("", &["gi.azimuths.x=3"]));
    assert_eq!(key.as_deref(), Some("gi.azimuths"));
    assert_mentions(&msg, &["invalid type", "--set gi.azimuths.x=3"]);
    // ...and descending into a scalar is an error of the override itself.
    let (key, msg) = err_of(parse_with("", &["gi.azimuths=8", "gi.azimuths.x=3"]));
    assert_eq!(key.as_deref(), Some("gi.azimuths.x"));
    assert_mentions(&msg, &["cannot set", "an integer"]);
    // An unknown key set by an override names the key and the override.
    let (key, msg) = err_of(parse_with("", &["gi.azimuth=64"]));
    assert_eq!(key.as_deref(), Some("gi.azimuth"));
    assert_mentions(&msg, &["unknown key `gi.azimuth`", "azimuths", "--set gi.azimuth=64"]);
    // An out-of-range override.
    let (key, msg) = err_of(parse_with("", &["gi.azimuths=1000"]));
    assert_eq!(key.as_deref(), Some("gi.azimuths"));
    assert_mentions(&msg, &["1000", "4..=256", "--set gi.azimuths=1000"]);
}

// ---------------------------------------------------------------------------------------------
// Errors

#[test]
fn unknown_keys_are_named() {
    let (key, msg) = err_of(parse("[lights]\n"));
    assert_eq!(key.as_deref(), Some("lights"));
    assert_mentions(&msg, &["test.toml: ", "unknown key `lights`", "heightfield", "key_light", "camera"]);
    let (key, msg) = err_of(parse("title = \"x\"\n"));
    assert_eq!(key.as_deref(), Some("title"));
    assert_mentions(&msg, &["unknown key `title`"]);
    let (key, msg) = err_of(parse("[gi]\nazimuth = 64\n"));
    assert_eq!(key.as_deref(), Some("gi.azimuth"));
    assert_mentions(&msg, &["unknown key `gi.azimuth`", "sh_order", "azimuths"]);
    let (key, msg) = err_of(parse("[[key_light]]\n[[key_light]]\ncolour = [1, 1, 1]\n"));
    assert_eq!(key.as_deref(), Some("key_light.1.colour"));
    assert_mentions(&msg, &["unknown key `key_light.1.colour`", "radiance"]);
    for (table, bad) in [("heightfield", "seed"), ("material", "roughness"), ("environment", "file"), ("camera", "fov")]
    {
        let (key, msg) = err_of(parse(&format!("[{table}]\n{bad} = 1\n")));
        assert_eq!(key.as_deref(), Some(format!("{table}.{bad}").as_str()));
        assert_mentions(&msg, &[&format!("unknown key `{table}.{bad}`")]);
    }
}

/// `gi.shading_storage` (docs/scene-format.md): `auto` in every preset, f32 planes with full-rate
/// GI and RGBE when it is sub-sampled (`draft` is, at 2×); `f32` and `rgbe` hold at any
/// sub-sampling; `hfgi plan`'s knob line prints the resolved format.
#[test]
fn shading_storage_auto_follows_the_sub_sampling() {
    use hfgi::scene::model::{ShadingFormat as F, ShadingStorage as S};
    for q in ["draft", "default", "paper", "high", "ultra"] {
        let s = parse_with("", &[format!("gi.quality=\"{q}\"").as_str()]).unwrap();
        assert_eq!(s.gi.shading_storage, S::Auto, "{q}");
        let want = if s.gi.subsample > 1 { F::Rgbe } else { F::F32 };
        assert_eq!(s.gi.shading_format(), want, "{q}, subsample {}", s.gi.subsample);
    }
    let cases = [
        ("auto", 1, F::F32),
        ("auto", 2, F::Rgbe),
        ("auto", 4, F::Rgbe),
        ("f32", 1, F::F32),
        ("f32", 4, F::F32),
        ("rgbe", 1, F::Rgbe),
        ("rgbe", 2, F::Rgbe),
    ];
    for (storage, sub, want) in cases {
        let (st, su) = (format!("gi.shading_storage=\"{storage}\""), format!("gi.subsample={sub}"));
        let s = parse_with("", &[st.as_str(), su.as_str()]).unwrap();
        assert_eq!(s.gi.shading_format(), want, "{storage}, subsample {sub}");
        assert!(s.gi.describe().contains(&format!(" shading_storage={want} ")), "{}", s.gi.describe());
    }
}

#[test]
fn out_of_range_values_name_key_and_value() {
    let cases: [(&str, &str, &[&str]); 9] = [
        ("[gi]\nazimuths = 2\n", "gi.azimuths", &["2", "4..=256"]),
        ("[gi]\nshading_storage = \"f16\"\n", "gi.shading_storage", &["f16", "`auto`, `f32` or `rgbe`"]),
        ("[gi]\nsubsample = 3\n", "gi.subsample", &["3", "1, 2 or 4"]),
        ("[gi]\nsh_order = 9\n", "gi.sh_order", &["9", "2..=8"]),
        ("[material]\nalbedo = [2, 0, 0]\n", "material.albedo", &["[2, 0, 0]", "[0, 1]"]),
        ("[[key_light]]\nangular_radius_deg = 0\n", "key_light.0.angular_radius_deg", &["= 0", "[0.001, 90]"]),
        ("[[key_light]]\nangular_radius_deg = 120\n", "key_light.0.angular_radius_deg", &["120", "[0.001, 90]"]),
        ("[camera]\nfov_deg = 0\n", "camera.fov_deg", &["= 0", "[0.01, 179]"]),
        ("[camera]\nwidth = 10000\n", "camera.width", &["10000", "1..=8192"]),
    ];
    for (text, want_key, parts) in cases {
        let (key, msg) = err_of(parse(text));
        assert_eq!(key.as_deref(), Some(want_key), "{msg}");
        assert_mentions(&msg, &[want_key]);
        assert_mentions(&msg, parts);
    }
    let more: [(&str, &str); 12] = [
        ("[heightfield]\ntexel_size = 0\n", "heightfield.texel_size"),
        ("[heightfield]\nheight_scale = nan\n", "heightfield.height_scale"),
        ("[heightfield]\nsize = 1\n", "heightfield.size"),
        ("[heightfield]\nsize = [64, 100000]\n", "heightfield.size"),
        ("[heightfield]\ngenerator = \"mountains\"\n", "heightfield.generator"),
        ("[heightfield]\ngenerator = \"fbm:octaves=99\"\n", "heightfield.generator"),
        ("[material]\nspecular = [-1, 0, 0]\n", "material.specular"),
        ("[material]\nexponent = 0\n", "material.exponent"),
        ("[environment]\nintensity = -1\n", "environment.intensity"),
        ("[environment]\npreset = \"dusk\"\n", "environment.preset"),
        ("[[key_light]]\ndirection = [0, 0, 0]\n", "key_light.0.direction"),
        ("[[key_light]]\nradiance = [1, inf, 1]\n", "key_light.0.radiance"),
    ];
    for (text, want_key) in more {
        let (key, msg) = err_of(parse(text));
        assert_eq!(key.as_deref(), Some(want_key), "{msg}");
        assert_mentions(&msg, &[want_key]);
    }
    let (key, msg) = err_of(parse("[camera]\nposition = [1, 2, 3]\ntarget = [1, 2, 3]\n"));
    assert_eq!(key.as_deref(), Some("camera.target"));
    assert_mentions(&msg, &["must differ"]);
    let (key, _) = err_of(parse("[gi]\ninterpolation = \"cubic\"\n"));
    assert_eq!(key.as_deref(), Some("gi.interpolation"));
    let (key, _) = err_of(parse("[gi]\nbounces = 17\n"));
    assert_eq!(key.as_deref(), Some("gi.bounces"));
}

#[test]
fn wrong_types_name_the_key() {
    let (key, msg) = err_of(parse("[gi]\nazimuths = \"many\"\n"));
    assert_eq!(key.as_deref(), Some("gi.azimuths"));
    assert_mentions(&msg, &["invalid type", "many"]);
    let (key, msg) = err_of(parse("[gi]\nazimuths = -4\n"));
    assert_eq!(key.as_deref(), Some("gi.azimuths"));
    assert_mentions(&msg, &["-4"]);
    let (key, msg) = err_of(parse("[material]\nalbedo = [0.5, 0.5]\n"));
    assert_eq!(key.as_deref(), Some("material.albedo"));
    assert_mentions(&msg, &["length 2"]);
    let (key, msg) = err_of(parse("[key_light]\nelevation_deg = 10\n"));
    assert_eq!(key.as_deref(), Some("key_light"));
    assert_mentions(&msg, &["[[key_light]]"]);
    let (key, _) = err_of(parse("gi = 5\n"));
    assert_eq!(key.as_deref(), Some("gi"));
    let (key, _) = err_of(parse("[heightfield]\nsize = \"big\"\n"));
    assert_eq!(key.as_deref(), Some("heightfield.size"));
    let (key, _) = err_of(parse("[heightfield]\nsize = [1, 2, 3]\n"));
    assert_eq!(key.as_deref(), Some("heightfield.size"));
}

#[test]
fn bad_toml_syntax_reports_the_line() {
    let (key, msg) = err_of(parse("[gi]\nazimuths = 32\nsubsample = = 2\n"));
    assert_eq!(key, None);
    assert_mentions(&msg, &["test.toml", "line 3"]);
    let (_, msg) = err_of(parse("[gi]\nazimuths = 1\n[gi]\n"));
    assert_mentions(&msg, &["line 3"]);
}

#[test]
fn conflicting_keys_are_errors() {
    let (key, msg) = err_of(parse("[[key_light]]\ndirection = [0, 0, 1]\nelevation_deg = 30\n"));
    assert_eq!(key.as_deref(), Some("key_light.0.direction"));
    assert_mentions(&msg, &["direction", "elevation_deg", "not both"]);
    let (_, msg) = err_of(parse("[environment]\npreset = \"sky\"\nsh = [[1, 1, 1]]\n"));
    assert_mentions(&msg, &["only one of", "sh", "preset"]);
    let (_, msg) = err_of(parse("[heightfield]\ngenerator = \"fbm\"\nfile = \"h.png\"\n"));
    assert_mentions(&msg, &["generator", "file", "not both"]);
    let (_, msg) = err_of(parse("[material]\nalbedo = [1, 1, 1]\nalbedo_map = \"a.png\"\n"));
    assert_mentions(&msg, &["albedo_map", "not both"]);
    let (key, _) = err_of(parse("[heightfield]\nfile = \"h.png\"\nsize = 64\n"));
    assert_eq!(key.as_deref(), Some("heightfield.size"));
    let (key, _) = err_of(parse("[heightfield]\nraw_size = [4, 4]\n"));
    assert_eq!(key.as_deref(), Some("heightfield.raw_size"));
}

#[test]
fn environment_sh_counts() {
    let triples = |n: usize| (0..n).map(|_| "[0.1, 0.2, 0.3]").collect::<Vec<_>>().join(", ");
    let (key, msg) = err_of(parse(&format!("[environment]\nsh = [{}]\n", triples(5))));
    assert_eq!(key.as_deref(), Some("environment.sh"));
    assert_mentions(&msg, &["5 coefficient", "perfect-square"]);
    let (_, msg) = err_of(parse(&format!("[environment]\nsh = [{}]\n", triples(81))));
    assert_mentions(&msg, &["81"]);
    err_of(parse("[environment]\nsh = []\n"));
    for n in [1, 4, 9, 16, 25, 36, 49, 64] {
        let s = parse(&format!("[environment]\nsh = [{}]\nintensity = 0.5\n", triples(n))).unwrap();
        assert_eq!(s.environment.sh.len(), n);
        assert!((s.environment.sh[0][1] - 0.1).abs() < 1e-15);
    }
    let (key, _) = err_of(parse("[environment]\nsh = [[1, 1, nan]]\n"));
    assert_eq!(key.as_deref(), Some("environment.sh.0"));
}

#[test]
fn garbage_never_panics() {
    let inputs = [
        "[",
        "]]",
        "a = ",
        "[gi]\nazimuths = 1e400\n",
        "[gi]\nazimuths = 99999999999999\n",
        "[gi]\nsh_order = 4294967300\n",
        "[heightfield]\nsize = -3\n",
        "[heightfield]\nsize = [0, 0]\n",
        "[heightfield]\nsize = 18446744073709551615\n",
        "[heightfield]\ntexel_size = inf\n",
        "[heightfield]\nheight_scale = 1e300\n",
        "[material]\nexponent = 1e300\n",
        "[material]\nspecular = [1e300, 0, 0]\n",
        "[[key_light]]\ndirection = [0, 0, 0]\n",
        "[[key_light]]\nelevation_deg = 91\n",
        "[[key_light]]\nazimuth_deg = nan\n",
        "[camera]\nexposure = 1e300\n",
        "[camera]\nposition = [nan, 0, 0]\n",
        "[camera]\nheight = 0\n",
        "[environment]\nsh = [[1, 2, 3, 4]]\n",
        "[environment]\nsh = 3\n",
        "[environment]\nmap = 3\n",
        "[heightfield]\nfile = \"/nonexistent/h.png\"\n",
        "[environment]\nmap = \"/nonexistent/env.exr\"\n",
        "[material]\nalbedo_map = \"/nonexistent/a.png\"\n",
        "key_light = [1, 2]\n",
        "key_light = \"x\"\n",
        "[[key_light]]\n[key_light.x]\n",
    ];
    for text in inputs {
        let r = std::panic::catch_unwind(|| parse(text));
        let r = r.unwrap_or_else(|_| panic!("panicked on {text:?}"));
        let (_, msg) = err_of(r);
        assert!(msg.starts_with("test.toml: "), "{msg}");
    }
}

// ---------------------------------------------------------------------------------------------
// Files referenced by the scene

#[test]
fn relative_paths_resolve_against_the_scene_folder() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("scenes");
    std::fs::create_dir_all(sub.join("data")).unwrap();
    let field = Generator::default_for("sines").unwrap().generate(24, 16).unwrap();
    save_png16(&field, &sub.join("data/h.png")).unwrap();
    let scene_path = sub.join("s.toml");
    std::fs::write(&scene_path, "[heightfield]\nfile = \"data/h.png\"\nheight_scale = 3.0\n").unwrap();
    let s = load_scene(&scene_path, &[]).unwrap();
    assert_eq!((s.field.width(), s.field.height()), (24, 16));
    let (lo, hi) = s.field.range();
    assert!(hi - lo > 2.9 && hi - lo < 3.01, "PNG 0..1 times height_scale 3: {lo}..{hi}");
    // The same relative path is not found from another folder, and the error names both files.
    let other = dir.path().join("elsewhere.toml");
    std::fs::write(&other, "[heightfield]\nfile = \"data/h.png\"\n").unwrap();
    let e = load_scene(&other, &[]).expect_err("missing file");
    let msg = e.to_string();
    assert_mentions(&msg, &["elsewhere.toml", "heightfield.file", "data/h.png"]);
    // parse_scene resolves against base_dir.
    let s = parse_scene("[heightfield]\nfile = \"h.png\"\n", &sub.join("data"), "x.toml", &[]).unwrap();
    assert_eq!(s.field.width(), 24);
    // raw files with raw_size.
    hfgi::scene::load::save_raw(&field, &sub.join("data/h.raw")).unwrap();
    std::fs::write(&scene_path, "[heightfield]\nfile = \"data/h.raw\"\nraw_size = [24, 16]\n").unwrap();
    assert_eq!(load_scene(&scene_path, &[]).unwrap().field, field);
    // A missing scene file is an I/O error naming it.
    let e = load_scene(&dir.path().join("nope.toml"), &[]).err().unwrap();
    assert!(matches!(e, Error::Io { .. }) && e.to_string().contains("nope.toml"));
}

#[test]
fn albedo_map_is_srgb_decoded_and_must_match_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u32, 16u32);
    let mut px = vec![0u8; (w * h * 3) as usize];
    px[0..3].copy_from_slice(&[255, 128, 0]);
    write_png_rgb(&dir.path().join("albedo.png"), w, h, &px);
    let text = "[heightfield]\nsize = [32, 16]\n[material]\nalbedo_map = \"albedo.png\"\n";
    let s = parse_scene(text, dir.path(), "m.toml", &[]).unwrap();
    let Albedo::Map(map) = &s.material.albedo else { panic!("expected a map") };
    assert_eq!(map.len(), 32 * 16);
    assert_eq!(map[0][0], 1.0);
    assert!((map[0][1] - 0.215_861).abs() < 1e-5, "sRGB 128 → {}", map[0][1]);
    assert_eq!(map[0][2], 0.0);
    assert_eq!(map[1], [0.0; 3]);

    // Wrong size: the message names both sizes.
    let text = "[heightfield]\nsize = 64\n[material]\nalbedo_map = \"albedo.png\"\n";
    let (key, msg) = err_of(parse_scene(text, dir.path(), "m.toml", &[]));
    assert_eq!(key.as_deref(), Some("material.albedo_map"));
    assert_mentions(&msg, &["32×16", "64×64", "albedo.png"]);

    // Grey PNGs are accepted; 16-bit ones are not.
    let grey = dir.path().join("grey.png");
    let f = std::fs::File::create(&grey).unwrap();
    image::codecs::png::PngEncoder::new(f).write_image(&vec![255u8; 32 * 16], 32, 16, ExtendedColorType::L8).unwrap();
    let text = "[heightfield]\nsize = [32, 16]\n[material]\nalbedo_map = \"grey.png\"\n";
    let s = parse_scene(text, dir.path(), "m.toml", &[]).unwrap();
    assert_eq!(s.material.albedo, Albedo::Map(vec![[1.0; 3]; 32 * 16]));
    let field = Generator::default_for("fbm").unwrap().generate(32, 16).unwrap();
    save_png16(&field, &dir.path().join("deep.png")).unwrap();
    let text = "[heightfield]\nsize = [32, 16]\n[material]\nalbedo_map = \"deep.png\"\n";
    let (_, msg) = err_of(parse_scene(text, dir.path(), "m.toml", &[]));
    assert_mentions(&msg, &["8-bit"]);
    std::fs::write(dir.path().join("junk.png"), b"not a png").unwrap();
    let text = "[heightfield]\nsize = [32, 16]\n[material]\nalbedo_map = \"junk.png\"\n";
    err_of(parse_scene(text, dir.path(), "m.toml", &[]));
}

#[test]
fn the_documented_example_loads() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md")).unwrap();
    let after = &doc[doc.find("## Annotated example").expect("section")..];
    let start = after.find("```toml\n").expect("toml block") + "```toml\n".len();
    let text = &after[start..start + after[start..].find("```").unwrap()];
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("data")).unwrap();
    let field = Generator::default_for("craters").unwrap().generate(64, 48).unwrap();
    save_png16(&field, &dir.path().join("data/craters.png")).unwrap();
    write_png_rgb(&dir.path().join("data/albedo.png"), 64, 48, &vec![200u8; 64 * 48 * 3]);
    let px = equirect(32, 16, |d| [1.0 + d[2] as f32; 3]);
    write_rgb_layers(&dir.path().join("data/sky.exr"), 32, 16, &[("", &px)]).unwrap();
    let path = dir.path().join("example.toml");
    std::fs::write(&path, text).unwrap();
    let s = load_scene(&path, &[]).unwrap();
    assert_eq!((s.field.width(), s.field.height(), s.texel_size), (64, 48, 0.5));
    assert_eq!(s.key_lights.len(), 2);
    assert_eq!(s.environment.sh.len(), 64);
    assert!(matches!(s.material.albedo, Albedo::Map(_)));
    assert_eq!(s.gi.interpolation, Interpolation::Bspline);
    assert_eq!((s.camera.width, s.camera.height), (1920, 1080));
}

// ---------------------------------------------------------------------------------------------
// Environment maps and presets

/// Pixels of an equirectangular map given radiance as a function of direction.
fn equirect(w: usize, h: usize, f: impl Fn([f64; 3]) -> [f32; 3]) -> Vec<[f32; 3]> {
    let mut out = Vec::with_capacity(w * h);
    for v in 0..h {
        let theta = PI * (v as f64 + 0.5) / h as f64;
        for u in 0..w {
            let phi = 2.0 * PI * (u as f64 + 0.5) / w as f64;
            out.push(f([theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]));
        }
    }
    out
}

#[test]
fn constant_map_projects_to_the_dc_term() {
    let want = (4.0 * PI).sqrt();
    // (w, h, bound on |c_k|, k ≥ 1). The conventions' pixel solid angle sinθ·(π/h)·(2π/w) is the
    // midpoint rule in θ, so c_0 is √(4π)·(π/2h)/sin(π/2h): relative error 4.0e-4 (absolute
    // 1.4e-3) at h = 32; the zonal terms carry the same O((l/h)²) error, largest for l = 6
    // (measured 5.2e-3 at 64×32, 3.2e-4 at 256×128).
    for (w, h, others) in [(64, 32, 1e-2), (256, 128, 5e-4)] {
        let px = vec![[1.0f32; 3]; w * h];
        let c = project_equirect(w, h, &px, 8, false);
        assert_eq!(c.len(), 64);
        let exact = want * (PI / (2.0 * h as f64)) / (PI / (2.0 * h as f64)).sin();
        for ch in 0..3 {
            assert!(((c[0][ch] - want) / want).abs() < 1e-3, "c0 = {} vs {want}", c[0][ch]);
            assert!((c[0][ch] - exact).abs() < 1e-9, "c0 = {} vs midpoint value {exact}", c[0][ch]);
            for (k, ck) in c.iter().enumerate().skip(1) {
                assert!(ck[ch].abs() < others, "{w}×{h}: c{k} = {}", ck[ch]);
            }
        }
        // The progress bar (hidden when stderr is not a terminal) does not change the result.
        assert_eq!(project_equirect(w, h, &px, 8, true), c);
        // Odd bands and m ≠ 0 terms vanish by symmetry.
        for l in 0..8i32 {
            for m in -l..=l {
                if m != 0 || l % 2 == 1 {
                    assert!(c[sh::index(l, m)][0].abs() < 1e-9, "c({l},{m}) = {}", c[sh::index(l, m)][0]);
                }
            }
        }
    }
}

#[test]
fn basis_function_maps_project_to_unit_vectors() {
    let (w, h, n) = (256, 128, 8);
    let mut worst = 0.0f64;
    for k in 0..n * n {
        let px = equirect(w, h, |d| {
            let y = sh::eval(n, d)[k] as f32;
            [y, -y, 2.0 * y]
        });
        let c = project_equirect(w, h, &px, n, false);
        for (j, cj) in c.iter().enumerate() {
            let e = if j == k { 1.0 } else { 0.0 };
            let err = (cj[0] - e).abs().max((cj[1] + e).abs()).max((cj[2] - 2.0 * e).abs() / 2.0);
            worst = worst.max(err);
        }
    }
    // Measured: 3.8e-4 at 256×128 (midpoint rule in θ and φ, f32 pixels).
    assert!(worst < 5e-4, "worst coefficient error {worst}");
}

#[test]
fn row_zero_is_the_zenith() {
    // Only the top row lit: the field points along +z.
    let (w, h) = (32, 16);
    let mut px = vec![[0.0f32; 3]; w * h];
    for p in &mut px[..w] {
        *p = [1.0; 3];
    }
    let c = project_equirect(w, h, &px, 2, false);
    assert!(c[2][0] > 0.0 && c[2][0] > 10.0 * c[1][0].abs().max(c[3][0].abs()));
    // Column u is φ = 2π(u + 0.5)/w: a map equal to x projects onto y_1^1 (index 3).
    let px = equirect(64, 32, |d| [d[0] as f32; 3]);
    let c = project_equirect(64, 32, &px, 2, false);
    let want = (4.0 * PI / 3.0).sqrt();
    assert!((c[3][0] - want).abs() < 2e-3 * want, "{:?}", c);
    assert!(c[1][0].abs() < 1e-4 && c[2][0].abs() < 1e-4);
}

#[test]
fn exr_environment_map_loads_and_projects() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 32);
    let px = equirect(w, h, |d| [1.0 + d[2] as f32, 0.5, 0.25]);
    write_rgb_layers(&dir.path().join("env.exr"), w, h, &[("", &px)]).unwrap();
    let (lw, lh, read) = load_equirect_exr(&dir.path().join("env.exr")).unwrap();
    assert_eq!((lw, lh), (w, h));
    assert_eq!(read, px);
    let s = parse_scene("[environment]\nmap = \"env.exr\"\nintensity = 2\n", dir.path(), "e.toml", &[]).unwrap();
    assert_eq!(s.environment.sh.len(), PRESET_ORDER * PRESET_ORDER);
    let c = project_equirect(w, h, &px, 8, false);
    for (a, b) in s.environment.sh.iter().zip(&c) {
        for ch in 0..3 {
            assert!((a[ch] - 2.0 * b[ch]).abs() < 1e-12);
        }
    }
    let sqrt4pi = (4.0 * PI).sqrt();
    assert!((s.environment.sh[0][1] - 2.0 * 0.5 * sqrt4pi).abs() < 2e-3);
    assert!((s.environment.sh[2][0] - 2.0 * (4.0 * PI / 3.0).sqrt()).abs() < 5e-3);

    // Channels other than R, G, B: the error lists them.
    hfgi::io::exr::write_scalar(&dir.path().join("y.exr"), w, h, "Y", &vec![1.0; w * h]).unwrap();
    let (key, msg) = err_of(parse_scene("[environment]\nmap = \"y.exr\"\n", dir.path(), "e.toml", &[]));
    assert_eq!(key.as_deref(), Some("environment.map"));
    assert_mentions(&msg, &["y.exr", "[Y]", "R, G and B"]);
    // Non-finite pixels are rejected.
    let mut bad = px.clone();
    bad[w + 3][1] = f32::NAN;
    write_rgb_layers(&dir.path().join("nan.exr"), w, h, &[("", &bad)]).unwrap();
    let e = load_equirect_exr(&dir.path().join("nan.exr")).err().unwrap();
    assert!(matches!(e, Error::NonFinite { x: 3, y: 1, .. }), "{e}");
}

#[test]
fn presets() {
    let u = Preset::Uniform.sh();
    assert!((u[0][0] - (4.0 * PI).sqrt()).abs() < 1e-9);
    assert!(u[1..].iter().all(|c| c.iter().all(|x| x.abs() < 1e-9)));
    // Overcast: horizontal irradiance 7π/9 from (1 + 2cosθ)/3 above the horizon.
    let e = horizontal_irradiance(&Preset::Overcast.sh());
    // (The order-8 clamped cosine is truncated too: 2.4424 vs 2.4435.)
    assert!((e[0] - 7.0 * PI / 9.0).abs() < 2e-3, "{e:?}");
    // The sky is bluer overhead than at the horizon, and its glow is toward the default sun.
    let sky = Preset::Sky.sh();
    let at = |d: [f64; 3], ch: usize| sh::reconstruct(8, &sky.iter().map(|c| c[ch]).collect::<Vec<_>>(), d);
    assert!(at([0.0, 0.0, 1.0], 2) > at([0.0, 0.0, 1.0], 0));
    let s = Preset::sky_sun_direction();
    let anti = [-s[0], -s[1], s[2]];
    assert!(at(s, 0) > 1.5 * at(anti, 0));
    assert!(at([0.0, 0.0, -1.0], 1) < 0.3);
    // Every preset's order-8 expansion is positive everywhere.
    for p in Preset::ALL {
        let c = p.sh();
        for i in 0..60 {
            for j in 0..120 {
                let d = sh::eval_angles(8, PI * (i as f64 + 0.5) / 60.0, 2.0 * PI * (j as f64 + 0.5) / 120.0);
                for ch in 0..3 {
                    let v: f64 = d.iter().zip(&c).map(|(y, c)| y * c[ch]).sum();
                    assert!(v > 0.0, "{p} negative ({v}) at ({i}, {j})");
                }
            }
        }
    }
    assert_eq!("Overcast".parse::<Preset>().unwrap(), Preset::Overcast);
    assert!("dusk".parse::<Preset>().is_err());
}
