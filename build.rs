//! Compiles every shader in `glsl/` to SPIR-V (see tools/hfgi-glsl) and embeds it, with the
//! constants of `src/constants.rs` defined in every shader (one source for host and GPU).

mod constants {
    #![allow(dead_code)]
    include!("src/constants.rs");
}

fn main() {
    // The manifest directory at run time, not `env!` (baked in when the build script itself was
    // compiled): a build script binary reused from another checkout sharing the target
    // directory would otherwise compile that checkout's shaders.
    let root = std::path::PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR")).join("glsl");
    println!("cargo:rerun-if-changed={}", root.display());
    println!("cargo:rerun-if-changed=src/constants.rs");
    let defines: Vec<(String, String)> = constants::GLSL_DEFINES
        .iter()
        .map(|(name, v, unsigned)| (format!("HFGI_{name}"), format!("{v}{}", if *unsigned { "u" } else { "" })))
        .collect();
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR")).join("shaders.rs");
    let shaders = match hfgi_glsl::compile_tree(&root, &defines) {
        Ok(s) => s,
        Err(e) => {
            // Cargo prints this; the message starts with file:line from glslang.
            eprintln!("{e}");
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
            std::process::exit(1);
        }
    };
    for s in &shaders {
        println!("cargo:rerun-if-changed={}", s.source.display());
    }
    if let Err(e) = hfgi_glsl::write_module(&shaders, &out) {
        eprintln!("{e}");
        std::process::exit(1);
    }
}
