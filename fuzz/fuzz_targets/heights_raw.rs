//! Bytes → a `.raw` file → `hfgi::scene::load::load_heightfield`: the first 4 bytes choose
//! `raw_size` (two little-endian u16, each taken into 1..=64), the rest is the file.
#![no_main]

use hfgi::scene::load::LoadOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(init: hfgi_fuzz::init("heights_raw"), |data: &[u8]| {
    if data.len() < 4 {
        return;
    }
    let side = |b: &[u8]| 1 + usize::from(u16::from_le_bytes([b[0], b[1]])) % 64;
    let (w, h) = (side(&data[0..2]), side(&data[2..4]));
    let path = hfgi_fuzz::write_input("in.raw", &data[4..]);
    let opts = LoadOptions { raw_size: Some((w, h)), ..hfgi_fuzz::load_options() };
    let _ = hfgi::scene::load::load_heightfield(&path, &opts);
});
