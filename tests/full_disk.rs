//! Every command's outputs survive a full disk (docs/robustness.md, "Atomic, checked outputs"):
//! a small tmpfs is mounted, each output path is given previous content, the rest of the disk
//! is filled, and the command runs with its outputs there. It must fail with the disk's error,
//! leave every previous file byte for byte as it was, and leave no temporary file.
//!
//! Mounting needs root (CI runs as root). Elsewhere the test says it was skipped; with
//! `HFGI_REQUIRE_TMPFS=1` (set by `.ci/run`) a failed mount fails the test instead.

mod common;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tmpfs mounted on a fresh folder, unmounted on drop.
struct Tmpfs {
    dir: tempfile::TempDir,
}

impl Tmpfs {
    fn mount(kib: u32) -> Option<Tmpfs> {
        let dir = tempfile::tempdir().unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={kib}k"), "tmpfs"])
            .arg(dir.path())
            .status()
            .is_ok_and(|s| s.success());
        if ok {
            return Some(Tmpfs { dir });
        }
        let why = "cannot mount a tmpfs (needs root)";
        assert!(std::env::var("HFGI_REQUIRE_TMPFS").as_deref() != Ok("1"), "{why}, and HFGI_REQUIRE_TMPFS=1");
        eprintln!("skipped: {why}");
        None
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Fills the disk: writes until the file system says it is full.
    fn fill(&self) {
        let mut f = std::fs::File::create(self.path().join("filler")).unwrap();
        let chunk = vec![0xA5u8; 4096];
        while f.write_all(&chunk).and_then(|()| f.flush()).is_ok() {}
        let _ = f.sync_all();
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

/// Every file under `dir` (recursively) with its content.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().map(Result::unwrap) {
        let p = e.path();
        if p.is_dir() {
            out.extend(snapshot(&p));
        } else if p.file_name().is_some_and(|n| n != "filler") {
            out.push((p.clone(), std::fs::read(&p).unwrap()));
        }
    }
    out.sort();
    out
}

/// Runs `hfgi args…` (`{}` in an argument is the tmpfs path) with `targets` holding previous
/// content on a full tmpfs; asserts the failure and that nothing changed.
fn survives_a_full_disk(args: &[&str], targets: &[&str]) {
    let Some(fs) = Tmpfs::mount(1024) else { return };
    let root = fs.path().display().to_string();
    for t in targets {
        let p = fs.path().join(t);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, format!("previous content of {t}")).unwrap();
    }
    fs.fill();
    let before = snapshot(fs.path());
    let args: Vec<String> = args.iter().map(|a| a.replace("{}", &root)).collect();
    let o = Command::new(common::hfgi_exe()).args(&args).env("RUST_BACKTRACE", "0").output().unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(!o.status.success(), "{args:?} succeeded on a full disk:\n{text}");
    assert!(text.contains("No space left on device") && !text.contains("panicked"), "{args:?}:\n{text}");
    let after = snapshot(fs.path());
    assert_eq!(
        before.iter().map(|(p, _)| p).collect::<Vec<_>>(),
        after.iter().map(|(p, _)| p).collect::<Vec<_>>(),
        "{args:?}: files appeared or vanished (temporary files left?)"
    );
    for ((p, a), (_, b)) in before.iter().zip(&after) {
        assert!(a == b, "{args:?}: {} changed", p.display());
    }
}

const SMALL: [&str; 8] =
    ["--set", "heightfield.size=8", "--set", "camera.width=16", "--set", "camera.height=12", "--set", "gi.bounces=1"];

fn with_small(args: &[&'static str]) -> Vec<&'static str> {
    args.iter().copied().chain(SMALL).collect()
}

#[test]
fn render_outputs_survive_a_full_disk() {
    let args = with_small(&[
        "render",
        "--out",
        "{}/render.png",
        "--view-exr",
        "{}/view.exr",
        "--shading-exr",
        "{}/shading.exr",
        "--shading-png",
        "{}/shading.png",
        "--indirect-png",
        "{}/indirect.png",
        "--heights-png",
        "{}/heights.png",
    ]);
    let targets = ["render.png", "view.exr", "shading.exr", "shading.png", "indirect.png", "heights.png"];
    survives_a_full_disk(&args, &targets);
}

#[test]
fn reference_outputs_survive_a_full_disk() {
    let args =
        with_small(&["reference", "--azimuths", "8", "--shading-exr", "{}/ref.exr", "--shading-png", "{}/ref.png"]);
    survives_a_full_disk(&args, &["ref.exr", "ref.png"]);
}

#[test]
fn animation_frames_and_gif_survive_a_full_disk() {
    let args =
        with_small(&["animate", "scenes/water.toml", "--frames", "2", "--out", "{}/frames", "--gif", "{}/a.gif"]);
    survives_a_full_disk(&args, &["frames/frame_0000.png", "frames/frame_0001.png", "a.gif"]);
}

#[test]
fn pyramid_export_and_spirv_outputs_survive_a_full_disk() {
    survives_a_full_disk(
        &["pyramid", "--out", "{}/p", "--size", "16"],
        &["p/heights.png", "p/heights.exr", "p/pyramid.png", "p/pyramid.exr"],
    );
    survives_a_full_disk(
        &["export", "--out", "{}/e", "--set", "heightfield.size=64"],
        &["e/heights.f32", "e/scene.toml"],
    );
    let first = hfgi::shaders::ALL[0].name;
    let spv = format!("spirv/{first}.spv");
    survives_a_full_disk(&["spirv", "--out", "{}/spirv"], &[spv.as_str()]);
}

#[test]
fn bench_outputs_survive_a_full_disk() {
    let args = [
        "bench",
        "--scenes",
        "scenes/default.toml",
        "--size",
        "8",
        "--quick",
        "--frames",
        "1",
        "--reference-azimuths",
        "8",
        "--out",
        "{}/bench",
    ];
    survives_a_full_disk(&args, &["bench/results.csv", "bench/results.md", "bench/pareto-default.png"]);
}
