//! Writes the seed corpora `fuzz/seeds/<target>/` (committed; tools/fuzz copies them into the
//! working corpus `fuzz/corpus/<target>/`). Run from the repository root, not instrumented:
//!
//! ```text
//! cargo run --release --manifest-path fuzz/Cargo.toml --example gen_seeds
//! ```
//!
//! - `scene_file`: the example scenes `scenes/*.toml` and `scenes/hard/*.toml`, plus scenes
//!   that read the fixture files of `hfgi_fuzz::fixtures` (every height format, an albedo map,
//!   an environment map) and use the tables the examples leave out;
//! - `set_override`: `--set` lines from tests/scene_file.rs and docs/scene-format.md, one file
//!   per group (each line one override);
//! - `heights_png`, `heights_exr`, `heights_tiff`, `heights_raw`, `envmap_exr`: tiny valid
//!   files written with the `image`, `exr` and `tiff` crates' encoders (as the tests write
//!   theirs), and a few that each loader must reject (wrong colour type, channels or sample
//!   type, 1×1, wrong length).
//!
//! Files already in a seed folder and not written here (minimised crash inputs added by hand)
//! are left as they are.

use std::path::{Path, PathBuf};

use hfgi_fuzz::{exr, exr_encoding, geotiff, png, png_gray, raw_f32, tiff_compression, write_file};
use hfgi_fuzz::{ExrSamples, TiffSamples};
use image::ExtendedColorType;

/// Scenes reading the fixtures, and tables the example scenes do not use.
const SCENES: &[(&str, &str)] = &[
    ("file-png8.toml", "[heightfield]\nfile = \"h8.png\"\nheight_scale = 20\n"),
    ("file-png16.toml", "[heightfield]\nfile = \"h16.png\"\ntexel_size = 2\nheight_offset = -3\n"),
    ("file-exr.toml", "[heightfield]\nfile = \"h.exr\"\nwrap = true\n"),
    ("file-tif-lowest.toml", "[heightfield]\nfile = \"h.tif\"\nnodata = \"lowest\"\n"),
    ("file-tif-fill.toml", "[heightfield]\nfile = \"h.tif\"\nnodata = -2.5\ntexel_size = 1.0\n"),
    ("file-tif-reject.toml", "[heightfield]\nfile = \"h.tif\"\n"),
    ("file-raw.toml", "[heightfield]\nfile = \"h.raw\"\nraw_size = [8, 8]\nheight_scale = 0.5\n"),
    (
        "albedo-map.toml",
        "[heightfield]\nfile = \"h8.png\"\n\n[material]\nalbedo_map = \"albedo.png\"\nspecular = [0.04, 0.04, 0.04]\nexponent = 64\n",
    ),
    (
        "env-map.toml",
        "[heightfield]\ngenerator = \"sines\"\nsize = 16\n\n[environment]\nmap = \"env.exr\"\nintensity = 0.5\n",
    ),
    (
        "env-sh.toml",
        "[heightfield]\ngenerator = \"cliff:height=0.3\"\nsize = [24, 16]\n\n[environment]\nsh = [[1, 1, 1], [0, 0.2, 0], [0.1, 0.1, 0.1], [0, 0, 0.3]]\n\n[[key_light]]\ndirection = [1, 0, 1]\nangular_radius_deg = 5\nradiance = [100, 90, 80]\n",
    ),
    (
        "everything.toml",
        r#"[heightfield]
generator = "craters:count=3,seed=4"
size = [40, 32]
texel_size = 0.25
height_scale = 2

[material]
albedo = [0.2, 0.4, 0.6]

[environment]
preset = "overcast"

[[key_light]]
elevation_deg = 10
azimuth_deg = -45

[[key_light]]
elevation_deg = 80

[gi]
quality = "high"
sh_order = 4
azimuths = 16
interpolation = "bspline"
pyramid = "pyramid"
bounces = 2
amortize = true

[camera]
position = [0, -40, 30]
target = [20, 16, 0]
fov_deg = 50
width = 320
height = 200
exposure = -1

[animation]
kind = "bumps"
count = 4
radius = 0.1
amplitude = 0.2
period = 60
travel = 0.3
shape = "gaussian"
"#,
    ),
    (
        "syntax-error.toml",
        "[heightfield]\nsize = [32, \n[gi]\nazimuths = 8\n",
    ),
];

/// `--set` lines, one file per group (tests/scene_file.rs, docs/scene-format.md).
const OVERRIDES: &[(&str, &str)] = &[
    ("gi.txt", "gi.azimuths=64\ngi.quality=ultra\ngi.level0=bspline\n"),
    ("material.txt", "material.albedo=[0.5,0.5,0.5]\nmaterial.albedo.0=0.25\n"),
    ("generator.txt", "heightfield.generator=\"cones\"\nheightfield.size=64\n"),
    ("generator-params.txt", "heightfield.generator=cones:count=3,seed=2\nheightfield.size=[48, 32]\n"),
    ("interp.txt", "gi.interpolation=bspline\ngi.pyramid = pyramid\nheightfield.wrap=true\n"),
    ("key-light.txt", "key_light.0.radiance=[1,1,1]\nkey_light.1.elevation_deg=10\n"),
    (
        "key-light-dir.txt",
        "key_light.0.direction=[0,0,1]\nkey_light.1.direction=[0,0,1]\nkey_light.1.angular_radius_deg=30\n",
    ),
    ("inline-table.txt", "gi={azimuths=16, subsample=2}\nenvironment.preset=overcast\n"),
    ("repeat.txt", "gi.azimuths=16\ngi.azimuths=24\ncamera.width=320\n"),
    ("city.txt", "key_light.0.elevation_deg=5\nkey_light.0.radiance=[2000,1500,900]\n"),
    ("craters.txt", "heightfield.generator=craters:count=20\nenvironment.preset=overcast\n"),
    ("bspline-table.txt", "gi={ azimuths = 64, interpolation = \"bspline\" }\n"),
    ("animation.txt", "animation.kind=water\nanimation.rain_rate=2\nheightfield.size=32\n"),
    ("animation-off.txt", "animation.kind=none\n"),
    ("files.txt", "heightfield.file=h8.png\nmaterial.albedo_map=albedo.png\nenvironment.map=env.exr\n"),
    ("file-raw.txt", "heightfield.file=\"h.raw\"\nheightfield.raw_size=8\n"),
    ("bad.txt", "gi..azimuths=3\nkey_light.5.radiance=[1,1,1]\ngi.azimuths.x=3\ngi.azimuth=64\n"),
    ("bad-range.txt", "gi.azimuths=1000\ngi.azimuths=8\n"),
];

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let seeds = root.join("seeds");
    let out = |target: &str, name: &str| -> PathBuf { seeds.join(target).join(name) };
    let mut count = 0usize;
    let mut put = |target: &str, name: &str, bytes: &[u8]| {
        write_file(&out(target, name), bytes);
        count += 1;
    };

    // scene_file: the example scenes, then the fixture scenes.
    let scenes = root.parent().expect("repository root").join("scenes");
    for (dir, prefix) in [(scenes.clone(), ""), (scenes.join("hard"), "hard-")] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .expect("read scenes/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        for p in files {
            let name = format!("{prefix}{}", p.file_name().expect("name").to_string_lossy());
            put("scene_file", &name, &std::fs::read(&p).expect("read scene"));
        }
    }
    for (name, text) in SCENES {
        put("scene_file", name, text.as_bytes());
    }
    for (name, text) in OVERRIDES {
        put("set_override", name, text.as_bytes());
    }

    // Height fields.
    put("heights_png", "gray8-4x3.png", &png_gray(4, 3, false));
    put("heights_png", "gray16-5x3.png", &png_gray(5, 3, true));
    put("heights_png", "gray8-16x16.png", &png_gray(16, 16, false));
    put("heights_png", "gray16-9x7.png", &png_gray(9, 7, true));
    put("heights_png", "rgb8-2x2.png", &png(2, 2, &[7u8; 12], ExtendedColorType::Rgb8));
    put("heights_png", "gray8-1x1.png", &png_gray(1, 1, false));

    for (name, w, h, channels, samples, enc) in [
        ("y-f32-5x3.exr", 5, 3, &["Y"][..], ExrSamples::F32, "none"),
        ("r-f16-5x3.exr", 5, 3, &["R", "G", "B"][..], ExrSamples::F16, "none"),
        ("height-f32-zip-16x16.exr", 16, 16, &["height"][..], ExrSamples::F32, "zip"),
        ("y-f16-rle-8x8.exr", 8, 8, &["Y", "Z"][..], ExrSamples::F16, "rle"),
        ("y-u32-4x4.exr", 4, 4, &["Y"][..], ExrSamples::U32, "none"),
        ("no-height-4x4.exr", 4, 4, &["G", "depth.Z"][..], ExrSamples::F32, "none"),
        ("y-f32-1x1.exr", 1, 1, &["Y"][..], ExrSamples::F32, "none"),
    ] {
        put("heights_exr", name, &exr(w, h, channels, samples, exr_encoding(enc)));
    }

    for (name, samples, compression, nodata) in [
        ("f32-none-nodata.tif", TiffSamples::F32, "none", Some("-4")),
        ("f32-lzw-nan.tif", TiffSamples::F32, "lzw", Some("nan")),
        ("f32-packbits.tif", TiffSamples::F32, "packbits", None),
        ("i16-lzw-nodata.tif", TiffSamples::I16, "lzw", Some("-16")),
        ("i16-none.tif", TiffSamples::I16, "none", None),
        ("u16-deflate.tif", TiffSamples::U16, "deflate", None),
        ("u16-deflate-nodata.tif", TiffSamples::U16, "deflate", Some("0")),
    ] {
        put("heights_tiff", name, &geotiff(6, 4, samples, tiff_compression(compression), nodata));
    }

    // heights_raw: 4 bytes of size (u16 LE each, side = 1 + v % 64), then the samples.
    for (name, w, h, file_w, file_h) in
        [("4x3.raw", 4u16, 3u16, 4, 3), ("8x8.raw", 8, 8, 8, 8), ("64x2.raw", 64, 2, 64, 2), ("short.raw", 5, 5, 4, 5)]
    {
        let mut bytes = Vec::new();
        bytes.extend_from_slice(&(w - 1).to_le_bytes());
        bytes.extend_from_slice(&(h - 1).to_le_bytes());
        bytes.extend_from_slice(&raw_f32(file_w, file_h));
        put("heights_raw", name, &bytes);
    }

    for (name, w, h, channels, samples, enc) in [
        ("rgb-f32-16x8.exr", 16, 8, &["R", "G", "B"][..], ExrSamples::F32, "none"),
        ("rgb-f16-zip-8x4.exr", 8, 4, &["R", "G", "B"][..], ExrSamples::F16, "zip"),
        ("rgba-u32-rle-4x2.exr", 4, 2, &["R", "G", "B", "A"][..], ExrSamples::U32, "rle"),
        ("layer-sky-8x4.exr", 8, 4, &["sky.R", "sky.G", "sky.B", "Y"][..], ExrSamples::F32, "none"),
        ("no-rgb-4x2.exr", 4, 2, &["R", "G"][..], ExrSamples::F16, "none"),
    ] {
        put("envmap_exr", name, &exr(w, h, channels, samples, exr_encoding(enc)));
    }

    println!("wrote {count} seed files under {}", seeds.display());
}
