//! The command line documents every command and option, and reports bad input with context.

mod common;

use std::process::Command;

fn hfgi(args: &[&str]) -> (bool, String) {
    let out = Command::new(common::hfgi_exe()).args(args).output().expect("run hfgi");
    (out.status.success(), format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr)))
}

#[test]
fn help_documents_every_command_and_option() {
    let (ok, top) = hfgi(&["--help"]);
    assert!(ok, "{top}");
    for cmd in ["render", "plan", "pyramid", "devices", "spirv", "HFGI_DEVICE", "HFGI_VALIDATION"] {
        assert!(top.contains(cmd), "`hfgi --help` does not mention {cmd}:\n{top}");
    }
    let (ok, render) = hfgi(&["render", "--help"]);
    assert!(ok, "{render}");
    for opt in [
        "[SCENE]",
        "--set",
        "--out",
        "--view-exr",
        "--shading-exr",
        "--shading-png",
        "--heights-png",
        "--exposure",
        "--device",
        "--validation",
    ] {
        assert!(render.contains(opt), "`hfgi render --help` does not document {opt}:\n{render}");
    }
    let (ok, pyramid) = hfgi(&["pyramid", "--help"]);
    assert!(ok, "{pyramid}");
    for opt in [
        "--out",
        "--heights",
        "--generator",
        "--size",
        "--raw-size",
        "--height-scale",
        "--level-step",
        "--pyramid",
        "--wrap",
        "--device",
        "--validation",
    ] {
        assert!(pyramid.contains(opt), "`hfgi pyramid --help` does not document {opt}:\n{pyramid}");
    }
    let (ok, plan) = hfgi(&["plan", "--help"]);
    assert!(ok, "{plan}");
    for opt in ["[SCENE]", "--set", "--frames", "no GPU", "docs/plan.md"] {
        assert!(plan.contains(opt), "`hfgi plan --help` does not document {opt}:\n{plan}");
    }
    let (ok, spirv) = hfgi(&["spirv", "--help"]);
    assert!(ok && spirv.contains("--out"), "{spirv}");
    let (ok, devices) = hfgi(&["devices", "--help"]);
    assert!(ok && devices.contains("Vulkan devices"), "{devices}");
}

#[test]
fn bad_input_is_an_error_with_context_not_a_panic() {
    let (ok, msg) = hfgi(&["pyramid", "--heights", "/nonexistent/field.png", "--out", "/tmp/hfgi-cli-test"]);
    assert!(!ok);
    assert!(msg.contains("/nonexistent/field.png") && !msg.contains("panicked"), "{msg}");
    let (ok, msg) = hfgi(&["pyramid", "--size", "1x1", "--out", "/tmp/hfgi-cli-test"]);
    assert!(!ok);
    assert!(msg.contains("1×1") && !msg.contains("panicked"), "{msg}");
    let (ok, msg) = hfgi(&["pyramid", "--pyramid", "tower", "--out", "/tmp/hfgi-cli-test"]);
    assert!(!ok && msg.contains("tower") && msg.contains("stack"), "{msg}");
    let (ok, msg) = hfgi(&["render", "--set", "gi.azimuths=2", "--out", "/tmp/hfgi-cli-test/x.png"]);
    assert!(!ok && msg.contains("gi.azimuths") && msg.contains('2') && !msg.contains("panicked"), "{msg}");
    let (ok, msg) = hfgi(&["render", "/nonexistent/scene.toml"]);
    assert!(!ok && msg.contains("/nonexistent/scene.toml") && !msg.contains("panicked"), "{msg}");
}

#[test]
fn render_writes_the_view_png_and_exr_and_the_shading_texture() {
    let dir = tempfile::tempdir().unwrap();
    let (png, exr) = (dir.path().join("r.png"), dir.path().join("s.exr"));
    let (view_exr, shading_png) = (dir.path().join("v.exr"), dir.path().join("s.png"));
    let (ok, msg) = hfgi(&[
        "render",
        "scenes/craters.toml",
        "--set",
        "heightfield.size=48",
        "--set",
        "gi.azimuths=8",
        "--set",
        "camera.width=80",
        "--set",
        "camera.height=50",
        "--set",
        "camera.position=[-10.0, -10.0, 40.0]",
        "--set",
        "camera.target=[23.5, 23.5, 0.0]",
        "--out",
        png.to_str().unwrap(),
        "--view-exr",
        view_exr.to_str().unwrap(),
        "--shading-exr",
        exr.to_str().unwrap(),
        "--shading-png",
        shading_png.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    for stage in ["visibility.environment", "shade.direct", "view.raster"] {
        assert!(msg.contains(stage), "no stage timing for {stage}:\n{msg}");
    }
    // The view image has the camera's size; the shading PNG the field's.
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (80, 50));
    let img = image::open(&shading_png).unwrap();
    assert_eq!((img.width(), img.height()), (48, 48));
    let (w, h, channels) = hfgi::io::exr::read_layers(&view_exr).unwrap();
    assert_eq!((w, h), (80, 50));
    let names: Vec<&str> = channels.iter().map(|(l, c, _)| if l.is_empty() { c.as_str() } else { "" }).collect();
    assert_eq!(names, ["B", "G", "R"], "view EXR channels");
    let g = &channels[1].2;
    assert!(g.iter().all(|v| v.is_finite() && *v >= 0.0), "view EXR values");
    assert!(g.iter().any(|v| *v > 0.0) && g.contains(&0.0), "the field and the background are in view");
    let (w, h, channels) = hfgi::io::exr::read_layers(&exr).unwrap();
    assert_eq!((w, h), (48, 48));
    let names: Vec<String> =
        channels.iter().map(|(l, c, _)| if l.is_empty() { c.clone() } else { format!("{l}.{c}") }).collect();
    for layer in ["", "direct.", "indirect.", "glossy."] {
        for c in ["R", "G", "B"] {
            let e = format!("{layer}{c}");
            assert!(names.contains(&e), "channel {e} missing from {names:?}");
        }
    }
    let r = &channels.iter().find(|(l, c, _)| l.is_empty() && c == "R").unwrap().2;
    assert!(r.iter().all(|v| v.is_finite() && *v >= 0.0) && r.iter().any(|v| *v > 0.0));
}

#[test]
fn reference_writes_the_layers_and_matches_the_cpu_version() {
    let dir = tempfile::tempdir().unwrap();
    let (gpu, cpu) = (dir.path().join("gpu.exr"), dir.path().join("cpu.exr"));
    let common = ["--set", "heightfield.size=16", "--set", "gi.bounces=1", "--azimuths", "32"];
    for (path, extra) in [(&gpu, None), (&cpu, Some("--cpu"))] {
        let mut args = vec!["reference", "scenes/craters.toml", "--shading-exr", path.to_str().unwrap()];
        args.extend(common);
        args.extend(extra);
        let (ok, msg) = hfgi(&args);
        assert!(ok, "{msg}");
        assert!(msg.contains("reference took"), "{msg}");
    }
    let read = |p: &std::path::Path| {
        let (w, h, ch) = hfgi::io::exr::read_layers(p).unwrap();
        assert_eq!((w, h), (16, 16));
        ch
    };
    let (g, c) = (read(&gpu), read(&cpu));
    for layer in ["", "direct", "indirect", "glossy"] {
        for chan in ["R", "G", "B"] {
            let find =
                |v: &[hfgi::io::exr::ExrChannel]| v.iter().find(|(l, n, _)| l == layer && n == chan).unwrap().2.clone();
            let (a, b) = (find(&g), find(&c));
            let (num, den) = a.iter().zip(&b).fold((0.0f64, 0.0f64), |(n, d), (x, y)| {
                (n + (*x as f64 - *y as f64).powi(2), d + (*y as f64).powi(2))
            });
            let rel = if den > 0.0 { (num / den).sqrt() } else { num.sqrt() };
            assert!(rel <= 1e-4, "layer {layer:?}.{chan}: GPU vs CPU reference {rel:e}");
        }
    }
    let (ok, msg) = hfgi(&["reference", "--cpu", "--set", "heightfield.size=65", "--shading-exr", "/tmp/hfgi-x.exr"]);
    assert!(!ok && msg.contains("64²") && !msg.contains("panicked"), "{msg}");
    let (ok, msg) = hfgi(&["reference", "--azimuths", "2", "--shading-exr", "/tmp/hfgi-x.exr"]);
    assert!(!ok && msg.contains("azimuths") && !msg.contains("panicked"), "{msg}");
}

#[test]
fn bench_writes_csv_markdown_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let (ok, msg) = hfgi(&[
        "bench",
        "--scenes",
        "scenes/default.toml",
        "--size",
        "16",
        "--quick",
        "--frames",
        "2",
        "--reference-azimuths",
        "32",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in ["azimuths", "level_step", "total_ms", "memory_bytes", "exact_total", "shvis_total", "stages"] {
        assert!(header.contains(&col), "column {col} missing: {header:?}");
    }
    let rows: Vec<&str> = lines.collect();
    assert!(rows.len() >= 10, "{} configurations", rows.len());
    let total_col = header.iter().position(|c| *c == "exact_total").unwrap();
    let baseline: Vec<&str> = rows[0].split(',').collect();
    let err: f64 = baseline[total_col].parse().unwrap();
    assert!(err.is_finite() && err > 0.0 && err < 1.0, "baseline error {err}");
    let md = std::fs::read_to_string(out.join("results.md")).unwrap();
    assert!(md.contains("Brute-force reference") && md.contains("| baseline |"), "{md}");
    let png = image::open(out.join("pareto-default.png")).unwrap();
    assert!(png.width() >= 400);
}

/// Output paths are checked before any work (no device is opened: the `device:` line is never
/// printed) and a rejected command changes nothing (docs/robustness.md, "atomic, checked outputs").
#[test]
fn outputs_that_cannot_work_are_rejected_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    let heights = dir.path().join("h.f32");
    std::fs::write(&heights, vec![0u8; 4 * 4 * 4]).unwrap();
    let text = "[heightfield]\nfile = \"h.f32\"\nraw_size = [4, 4]\n";
    std::fs::write(&scene, text).unwrap();
    let s = scene.to_str().unwrap();
    // The scene file itself, the height file it reads, and a directory as the output.
    for (args, what) in [
        (vec!["render", s, "--out", s], "scene.toml"),
        (vec!["render", s, "--shading-exr", heights.to_str().unwrap()], "h.f32"),
        (vec!["reference", s, "--shading-exr", dir.path().to_str().unwrap()], "not a directory"),
        (vec!["render", s, "--shading-png", "/tmp/../tmp/x.png", "--indirect-png", "/tmp/x.png"], "x.png"),
        // `export` into the scene's own folder would overwrite the scene with its export.
        (vec!["export", s, "--out", dir.path().to_str().unwrap()], "scene.toml"),
    ] {
        let (ok, msg) = hfgi(&args);
        assert!(!ok && msg.contains(what) && !msg.contains("device:") && !msg.contains("panicked"), "{args:?}: {msg}");
    }
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), text);
    assert_eq!(std::fs::read(&heights).unwrap(), vec![0u8; 64]);
    let mut left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    left.sort();
    assert_eq!(left, ["h.f32", "scene.toml"], "nothing else is left in the folder");
}

/// `hfgi bench --save-references --no-sh-visibility`: the SH-visibility columns are NaN and the
/// saved exact reference is byte-identical to `hfgi reference`'s for the same settings.
#[test]
fn bench_saves_exact_references_and_skips_sh_visibility() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let common = ["--set", "heightfield.size=16", "--set", "gi.bounces=1"];
    let (ok, msg) = hfgi(
        &[
            &["bench", "--sweep", "presets", "--only", "quality=draft", "--scenes", "scenes/hard/terraces.toml"][..],
            &["--size", "16", "--frames", "1", "--reference-azimuths", "32", "--save-references", "--no-sh-visibility"],
            &["--out", out.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(ok, "{msg}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let (ex, sv) = (
        header.iter().position(|c| *c == "exact_total").unwrap(),
        header.iter().position(|c| *c == "shvis_total").unwrap(),
    );
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "paper and draft:\n{csv}");
    for r in &rows {
        assert!(r[ex].parse::<f64>().unwrap() > 0.0, "{r:?}");
        assert_eq!(r[sv], "NaN", "no SH-visibility reference: {r:?}");
    }
    // The saved reference is the one `hfgi reference` writes for the same settings.
    let saved = std::fs::read(out.join("reference-terraces-n4.exr")).unwrap();
    let cli = dir.path().join("cli.exr");
    let (ok, msg) = hfgi(
        &[
            &["reference", "scenes/hard/terraces.toml", "--azimuths", "32", "--shading-exr", cli.to_str().unwrap()][..],
            &common,
        ]
        .concat(),
    );
    assert!(ok, "{msg}");
    assert!(saved == std::fs::read(&cli).unwrap(), "bench's saved reference differs from `hfgi reference`");
}

/// `hfgi bench --timing`: every configuration of the grid at a tiny size, no references; the
/// CSV has one row per configuration with a positive frame time and the device, the Markdown
/// says how the times were taken.
#[test]
fn bench_timing_runs_the_grid_without_references() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (ok, text) = hfgi(&["bench", "--timing", "--size", "16", "--frames", "1", "--out", out]);
    assert!(ok, "{text}");
    assert!(!text.contains("reference"), "--timing computed references: {text}");
    let csv = std::fs::read_to_string(dir.path().join("timing.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 9, "3 sub-samplings × 3 bounces:\n{csv}");
    for (row, (sub, b)) in rows.iter().zip([4, 2, 1].iter().flat_map(|s| (1..=3).map(move |b| (*s, b)))) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!((f[0], f[1], f[2]), ("16", &*sub.to_string(), &*b.to_string()), "{row}");
        assert!(f[3].parse::<f64>().unwrap() > 0.0, "{row}");
    }
    let md = std::fs::read_to_string(dir.path().join("timing.md")).unwrap();
    assert!(md.contains("median of 1 frames after 1 warm-up") && md.contains("Device:"), "{md}");
    // The default planes follow each row's sub-sampling (`auto`: f32 at 1×, RGBE at 2× and 4×,
    // written out here rather than asked of the code), so the header, shared by every row,
    // does not name one format.
    assert!(!md.lines().next().unwrap().contains("shading_storage="), "{md}");
    for sub in [4, 2, 1] {
        let planes = if sub == 1 { "f32" } else { "rgbe" };
        let rows: Vec<&str> = md.lines().filter(|l| l.starts_with(&format!("| 16² | {sub}× |"))).collect();
        assert_eq!(rows.len(), 3, "{md}");
        assert!(rows.iter().all(|l| l.contains(&format!("| {planes} |"))), "{sub}×: {md}");
    }
}
