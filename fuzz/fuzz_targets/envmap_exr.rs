//! Bytes → an `.exr` file → `hfgi::scene::envmap::load_equirect_exr`, and a map it accepts
//! (up to 256×256 pixels: cost) projected to SH as a scene would (`project_equirect`); the loader's size and pixel
//! count must agree.
#![no_main]

use hfgi::scene::envmap::{load_equirect_exr, project_equirect, PRESET_ORDER};
use libfuzzer_sys::fuzz_target;

fuzz_target!(init: hfgi_fuzz::init("envmap_exr"), |data: &[u8]| {
    let path = hfgi_fuzz::write_input("env.exr", data);
    if let Ok((w, h, rgb)) = load_equirect_exr(&path) {
        assert_eq!(rgb.len(), w * h, "load_equirect_exr: {w}×{h} map with {} pixels", rgb.len());
        if w * h <= 256 * 256 {
            let c = project_equirect(w, h, &rgb, PRESET_ORDER, false);
            assert_eq!(c.len(), PRESET_ORDER * PRESET_ORDER);
        }
    }
});
