//! The layering the brief and docs/integration.md promise, checked on the sources: the library
//! crate carries no command-line crates (they live in `cli/`, package `hfgi-cli`), and the CPU
//! twins (`src/reference`) with the rules, math and scene modules below them never import the
//! GPU code (`frame`, `vk`).

use std::path::Path;

#[test]
fn the_library_has_no_command_line_dependencies() {
    let text = std::fs::read_to_string("Cargo.toml").unwrap();
    let manifest: toml::Table = text.parse().unwrap();
    let deps = manifest["dependencies"].as_table().expect("[dependencies]");
    for cli in ["clap", "plotters", "plotters-backend", "indicatif", "anyhow", "ab_glyph"] {
        assert!(!deps.contains_key(cli), "the library depends on {cli}: it belongs to cli/Cargo.toml");
    }
    let members = manifest["workspace"]["members"].as_array().unwrap();
    assert!(members.iter().any(|m| m.as_str() == Some("cli")), "cli/ is a workspace member");
    let cli: toml::Table = std::fs::read_to_string("cli/Cargo.toml").unwrap().parse().unwrap();
    assert!(cli["dependencies"].as_table().unwrap().contains_key("clap"));
}

/// Non-comment lines of every `.rs` file under `dir` that contain one of `needles`.
fn offending_lines(dir: &Path, needles: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(offending_lines(&path, needles));
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            for (i, line) in text.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                if needles.iter().any(|n| code.contains(n)) {
                    out.push(format!("{}:{}: {}", path.display(), i + 1, line.trim()));
                }
            }
        }
    }
    out
}

#[test]
fn the_cpu_twins_and_the_rules_never_import_the_gpu_code() {
    let needles = ["crate::frame", "crate::vk", "super::frame", "ash::", "gpu_allocator"];
    for dir in ["src/reference", "src/rules", "src/math", "src/scene"] {
        let bad = offending_lines(Path::new(dir), &needles);
        assert!(bad.is_empty(), "{dir} imports GPU code:\n{}", bad.join("\n"));
    }
}

#[test]
fn library_code_draws_no_progress_bar() {
    let bad = offending_lines(Path::new("src"), &["indicatif", "ProgressBar"]);
    assert!(bad.is_empty(), "progress goes through hfgi::progress:\n{}", bad.join("\n"));
}
