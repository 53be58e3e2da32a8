//! Regression tests for the classes of hostile input of docs/robustness.md, through the
//! command line: unbounded inputs and work, late checks, unhelpful messages, a stdout that
//! cannot be written, and the animation's outputs (frames and a streamed GIF, together).

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn run(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(common::hfgi_exe());
    c.args(args).env("RUST_BACKTRACE", "0");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run hfgi")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Fails with a message containing every `want`, no panic, no Vulkan device opened (no
/// `device:` line: the check came before any work), and every line short.
fn rejected_early(args: &[&str], want: &[&str]) -> String {
    let o = run(args, &[]);
    let t = text(&o);
    assert!(!o.status.success(), "{args:?} succeeded:\n{t}");
    assert!(!t.contains("panicked") && !t.contains("device:"), "{args:?}:\n{t}");
    for w in want {
        assert!(t.contains(w), "{args:?}: the message lacks {w:?}:\n{t}");
    }
    assert!(t.lines().all(|l| l.chars().count() <= 1100), "{args:?}: a line is too long:\n{t}");
    t
}

#[test]
fn a_scene_that_is_a_device_or_too_large_is_rejected_before_reading() {
    rejected_early(&["plan", "/dev/zero"], &["/dev/zero", "not a regular file"]);
    rejected_early(&["render", "/dev/zero"], &["/dev/zero", "not a regular file"]);
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.toml");
    std::fs::write(&big, vec![b'#'; (hfgi::scene::file::MAX_SCENE_BYTES + 1) as usize]).unwrap();
    rejected_early(&["plan", big.to_str().unwrap()], &["big.toml", "at most 1048576 bytes"]);
    // A height file that is a directory, through --set.
    let d = dir.path().display().to_string();
    rejected_early(&["plan", "--set", &format!("heightfield.file=\"{d}/x.png\"")], &["x.png"]);
    std::fs::create_dir(dir.path().join("h.png")).unwrap();
    rejected_early(&["plan", "--set", &format!("heightfield.file=\"{d}/h.png\"")], &["h.png", "directory"]);
}

#[test]
fn unbounded_work_is_rejected_with_its_cost() {
    rejected_early(
        &["reference", "--march", "--step", "1e-9", "--set", "heightfield.size=128"],
        &["ray steps", "years", "--step"],
    );
    rejected_early(
        &["animate", "scenes/water.toml", "--frames", "4294967295", "--gif", "x.gif"],
        &["--frames", "100000"],
    );
    rejected_early(
        &[
            "animate",
            "scenes/water.toml",
            "--frames",
            "100000",
            "--set",
            "camera.width=8192",
            "--set",
            "camera.height=8192",
        ],
        &["GiB", "camera.width"],
    );
}

#[test]
fn bad_values_are_rejected_before_any_work_with_short_messages() {
    rejected_early(&["render", "--exposure", "nan"], &["--exposure", "[-64, 64]"]);
    rejected_early(&["reference", "--exposure=-1e30"], &["--exposure"]);
    rejected_early(&["render", "--set", "camera.exposure=100"], &["camera.exposure", "[-64, 64]"]);
    // 1e300 is rejected by every magnitude key, and echoed as 1.00000e300, not 301 digits.
    for key in ["key_light.0.radiance=[1e300,1,1]", "material.specular=[1e300,0,0]", "heightfield.height_offset=1e300"]
    {
        let t = rejected_early(&["plan", "--set", key], &["e300"]);
        assert!(!t.contains("0000000000000000000000"), "{t}");
    }
    // A 200 KB line is not echoed back.
    let dir = tempfile::tempdir().unwrap();
    let long = dir.path().join("long.toml");
    std::fs::write(&long, format!("x = \"{}\" junk\n", "a".repeat(200_000))).unwrap();
    let t = rejected_early(&["plan", long.to_str().unwrap()], &["TOML parse error", "characters in all"]);
    assert!(t.len() < 2000, "{} bytes of message", t.len());
}

#[test]
fn plan_rejects_what_render_would_reject_for_the_device() {
    // 4096² in stack mode: the height pyramid's levels buffer is above lavapipe's 128 MiB
    // maxStorageBufferRange; `plan` says so (it used to call it valid), and so does `render`,
    // before creating the renderer.
    let o = run(&["plan", "--set", "heightfield.size=4096"], &[]);
    let t = text(&o);
    let on_device = !t.contains("no Vulkan device opened");
    if on_device {
        assert!(!o.status.success() && t.contains("maxStorageBufferRange"), "{t}");
        let r = run(&["render", "--set", "heightfield.size=4096", "--out", "/tmp/hfgi-never.png"], &[]);
        let rt = text(&r);
        assert!(!r.status.success() && rt.contains("maxStorageBufferRange"), "{rt}");
        assert!(!rt.contains("view:"), "render created passes before the check:\n{rt}");
    }
    // Without a device: the estimate only.
    let o = run(&["plan", "--no-device"], &[]);
    let t = text(&o);
    assert!(o.status.success() && t.contains("GPU memory:") && t.contains("largest buffer"), "{t}");
}

#[test]
fn vulkan_setup_failures_name_the_driver_manifest_and_the_device_flag() {
    let env = [("VK_DRIVER_FILES", "/nonexistent/hfgi-no-driver.json"), ("VK_ICD_FILENAMES", "")];
    let o = run(&["render", "--set", "heightfield.size=8", "--out", "/tmp/hfgi-never.png"], &env);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("VK_DRIVER_FILES") && t.contains("missing") && t.contains("hfgi devices"), "{t}");
    let o =
        run(&["render", "--device", "no-such-gpu", "--set", "heightfield.size=8", "--out", "/tmp/hfgi-never.png"], &[]);
    let t = text(&o);
    assert!(!o.status.success() && t.contains("--device \"no-such-gpu\""), "{t}");
    assert!(!t.contains("HFGI_DEVICE"), "the message blames HFGI_DEVICE for --device:\n{t}");
}

#[test]
fn a_stdout_that_cannot_be_written_is_an_error() {
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let o = Command::new(common::hfgi_exe())
        .args(["plan", "--no-device"])
        .env("RUST_BACKTRACE", "0")
        .stdout(full)
        .output()
        .unwrap();
    let t = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "exit 0 with a failing stdout:\n{t}");
    assert!(t.contains("writing to standard output") && !t.contains("panicked"), "{t}");
}

#[test]
fn animate_commits_frames_and_a_streamed_gif_together() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frames");
    let gif = dir.path().join("a.gif");
    let o = run(
        &[
            "animate",
            "scenes/water.toml",
            "--frames",
            "3",
            "--out",
            out.to_str().unwrap(),
            "--gif",
            gif.to_str().unwrap(),
            "--set",
            "heightfield.size=16",
            "--set",
            "camera.width=24",
            "--set",
            "camera.height=16",
        ],
        &[],
    );
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    for f in 0..3 {
        assert!(out.join(format!("frame_{f:04}.png")).is_file(), "{t}");
    }
    let mut decoder = gif::DecodeOptions::new().read_info(std::fs::File::open(&gif).unwrap()).unwrap();
    let mut frames = 0;
    while decoder.read_next_frame().unwrap().is_some() {
        frames += 1;
    }
    assert_eq!(frames, 3);
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .chain(std::fs::read_dir(&out).unwrap())
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    assert!(Path::new(&gif).metadata().unwrap().len() > 0);
}
