//! `--set` overrides: each line of the input is one `key.path=value`, applied to the default
//! scene (`parse_scene("", ..)`, what `hfgi render --set ...` does without a scene file) and to
//! a small scene with every table, two key lights and an animation (so that array indices,
//! inline tables and replaced tables have something to act on). Inputs that
//! `hfgi_fuzz::scene_is_cheap` rejects are skipped for their cost.
#![no_main]

use libfuzzer_sys::fuzz_target;

/// Every table, small: a 32² field, two key lights, SH lighting of order 2, water.
const SCENE: &str = r#"
[heightfield]
generator = "cones:count=3"
size = [32, 24]
texel_size = 0.5

[material]
albedo = [0.5, 0.6, 0.7]
specular = [0.1, 0.1, 0.1]
exponent = 16

[environment]
sh = [[1, 1, 1], [0, 0.1, 0], [0.2, 0.2, 0.2], [0, 0, 0.1]]

[[key_light]]
elevation_deg = 40
azimuth_deg = 120

[[key_light]]
direction = [0, 0, 1]
radiance = [10, 10, 10]

[gi]
quality = "draft"
azimuths = 8

[camera]
width = 64
height = 48

[animation]
kind = "water"
rain_rate = 0.5
"#;

fuzz_target!(
    init: {
        hfgi_fuzz::init("set_override");
        hfgi_fuzz::write_scene_fixtures();
    },
    |data: &[u8]| {
        // `--set` arguments are OS strings turned into UTF-8 by clap; other bytes never arrive.
        let Ok(text) = std::str::from_utf8(data) else { return };
        let overrides: Vec<String> = text.lines().map(str::to_string).collect();
        let dir = hfgi_fuzz::dir();
        if hfgi_fuzz::scene_is_cheap("", &overrides) {
            let _ = hfgi::scene::file::parse_scene("", dir, "<default scene>", &overrides);
        }
        if hfgi_fuzz::scene_is_cheap(SCENE, &overrides) {
            let _ = hfgi::scene::file::parse_scene(SCENE, dir, "fixed.toml", &overrides);
        }
    }
);
