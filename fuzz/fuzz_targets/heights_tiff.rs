//! Bytes → a `.tif` file → `hfgi::scene::load::load_heightfield_meta` (sides up to 512). The
//! input's length modulo 3 picks the NoData mode (reject, fill with the lowest sample, fill with
//! -1), so that the fuzzer reaches every path by appending bytes, which a TIFF ignores.
#![no_main]

use hfgi::scene::load::{LoadOptions, NoData};
use libfuzzer_sys::fuzz_target;

fuzz_target!(init: hfgi_fuzz::init("heights_tiff"), |data: &[u8]| {
    let path = hfgi_fuzz::write_input("in.tif", data);
    let nodata = match data.len() % 3 {
        0 => NoData::Reject,
        1 => NoData::Lowest,
        _ => NoData::Value(-1.0),
    };
    let opts = LoadOptions { nodata, ..hfgi_fuzz::load_options() };
    let _ = hfgi::scene::load::load_heightfield_meta(&path, &opts);
});
