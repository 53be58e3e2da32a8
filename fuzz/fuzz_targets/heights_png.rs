//! Bytes → a `.png` file → `hfgi::scene::load::load_heightfield` (sides up to 512).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: hfgi_fuzz::init("heights_png"), |data: &[u8]| {
    let path = hfgi_fuzz::write_input("in.png", data);
    let _ = hfgi::scene::load::load_heightfield(&path, &hfgi_fuzz::load_options());
});
