//! Links Debian's static shaderc/glslang/SPIRV-Tools libraries (see ../../README.md, "Building").
//! With the `from-source` feature, shaderc-sys builds them itself and this script does nothing.
fn main() {
    println!("cargo:rerun-if-env-changed=SHADERC_LIB_DIR");
    if std::env::var_os("CARGO_FEATURE_FROM_SOURCE").is_some() {
        return;
    }
    let dir = std::env::var("SHADERC_LIB_DIR").unwrap_or_else(|_| "/usr/lib/x86_64-linux-gnu".to_string());
    println!("cargo:rustc-link-search=native={dir}");
    // Order matters for static archives: dependents first.
    for lib in [
        "glslang",
        "MachineIndependent",
        "GenericCodeGen",
        "OSDependent",
        "OGLCompiler",
        "SPIRV",
        "glslang-default-resource-limits",
        "SPIRV-Tools-opt",
        "SPIRV-Tools",
    ] {
        println!("cargo:rustc-link-lib=static={lib}");
    }
    println!("cargo:rustc-link-lib=dylib=stdc++");
}
