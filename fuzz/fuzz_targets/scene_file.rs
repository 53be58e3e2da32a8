//! Scene-file text → `hfgi::scene::file::parse_scene`, with the target's own folder (holding
//! the fixtures of `hfgi_fuzz::fixtures`) as the base for relative file names. Inputs that
//! `hfgi_fuzz::scene_is_cheap` rejects (a generated field above 256², a path leaving the
//! folder) are skipped for their cost; everything else must give `Ok` or `Err`, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(
    init: {
        hfgi_fuzz::init("scene_file");
        hfgi_fuzz::write_scene_fixtures();
    },
    |data: &[u8]| {
        // `load_scene` reads the file as UTF-8 text; other bytes are an I/O error there.
        let Ok(text) = std::str::from_utf8(data) else { return };
        if !hfgi_fuzz::scene_is_cheap(text, &[]) {
            return;
        }
        let _ = hfgi::scene::file::parse_scene(text, hfgi_fuzz::dir(), "fuzz.toml", &[]);
    }
);
