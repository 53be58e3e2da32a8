//! Bytes → an `.exr` file → `hfgi::scene::load::load_heightfield` (sides up to 512).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: hfgi_fuzz::init("heights_exr"), |data: &[u8]| {
    let path = hfgi_fuzz::write_input("in.exr", data);
    let _ = hfgi::scene::load::load_heightfield(&path, &hfgi_fuzz::load_options());
});
