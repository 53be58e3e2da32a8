//! `hfgi bench --timing`: the frame's cost without references, on any device — the median of
//! timed frames after a warm-up frame, per stage and in total, frames per second and GPU memory,
//! over table 1's grid of the paper (field 256², 512², 1024² × sub-sampling 1×, 2×, 4× ×
//! 1–3 bounces; the default scene: one environment light, m = 32, one key light, m = 3).
//! Configurations run cheapest first until `--budget` seconds are spent; the rest are listed
//! as not run. Only the GI frame is timed (the renderer's stages, in a submit of their own);
//! the view pass is not (docs/performance.md §3: after a draw, lavapipe's compute timestamps
//! are not trustworthy). Writes `timing.csv` and `timing.md` to `--out`.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context as _, Result};
use hfgi::scene::model::ShadingFormat;

use super::bench::{measure, BenchArgs};
use super::{context, load_scene_or_default};

/// One configuration of the grid: (field size, sub-sampling, bounces).
type Config = (u32, u32, u32);

/// The grid, cheapest first (size, then coarser sub-sampling, then fewer bounces); `sizes`
/// replaces the paper's sizes.
fn grid(sizes: &[u32]) -> Vec<Config> {
    let mut out = Vec::new();
    for &n in sizes {
        for sub in [4, 2, 1] {
            for b in 1..=3 {
                out.push((n, sub, b));
            }
        }
    }
    out
}

/// A measured configuration.
struct Timed {
    cfg: Config,
    stages: Vec<(String, f64)>,
    total_ms: f64,
    memory: u64,
    /// The shading planes' format this row resolved to (`gi.shading_storage = "auto"` follows
    /// the row's sub-sampling).
    planes: ShadingFormat,
}

/// Runs the timing grid for `a` (scene: the first of `--scenes`; sizes: `--size` or the paper's).
pub fn run(a: &BenchArgs, budget_s: u64) -> Result<()> {
    let (csv_path, md_path) = (a.out.join("timing.csv"), a.out.join("timing.md"));
    let scene_path = a.scenes.first().map(|p| p.as_path());
    super::check_outputs(&[&csv_path, &md_path], scene_path, &a.overrides)?;
    // The scene as given, read before any work: the header's knobs.
    let knobs = per_row_knobs_removed(&load_scene_or_default(scene_path, &a.overrides)?.gi.describe());
    let ctx = context(&a.device)?;
    let info = ctx.info().clone();
    let lavapipe = info.kind == ash::vk::PhysicalDeviceType::CPU;
    let clock = if lavapipe { "lavapipe (CPU time, not a GPU time)" } else { "GPU timestamps" };
    let sizes: Vec<u32> = match a.size {
        Some(n) if n > 0 => vec![n],
        _ => vec![256, 512, 1024],
    };
    let start = Instant::now();
    let (mut done, mut skipped): (Vec<Timed>, Vec<Config>) = (Vec::new(), Vec::new());
    let bar = indicatif::ProgressBar::new(grid(&sizes).len() as u64);
    for cfg in grid(&sizes) {
        bar.inc(1);
        if start.elapsed().as_secs() >= budget_s {
            skipped.push(cfg);
            continue;
        }
        let (n, sub, b) = cfg;
        bar.set_message(format!("{n}² sub {sub}× {b} bounce(s)"));
        let mut overrides =
            vec![format!("heightfield.size={n}"), format!("gi.subsample={sub}"), format!("gi.bounces={b}")];
        overrides.extend(a.overrides.iter().cloned());
        let scene = load_scene_or_default(scene_path, &overrides)?;
        let (stages, memory, _) =
            measure(&ctx, &scene, a.frames).with_context(|| format!("timing {n}² sub {sub} b {b}"))?;
        let total_ms = stages.iter().map(|(_, ms)| ms).sum();
        done.push(Timed { cfg, stages, total_ms, memory, planes: scene.gi.shading_format() });
    }
    bar.finish_and_clear();
    let header = format!(
        "Device: {} ({}); times: {clock}, median of {} frames after 1 warm-up; scene: {}; knobs: {}; budget {budget_s} s ({:.0} s used).\n",
        info.name,
        info.driver,
        a.frames,
        scene_path.map_or("the default scene".into(), |p| p.display().to_string()),
        knobs,
        start.elapsed().as_secs_f64()
    );
    let (csv, md) = (to_csv(&done, &info.name, &info.driver), to_md(&header, &done, &skipped));
    hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        hfgi::io::atomic::write_bytes(&csv_path, csv.as_bytes())?;
        hfgi::io::atomic::write_bytes(&md_path, md.as_bytes())?;
        Ok(())
    })?;
    super::write_stdout(&md)?;
    eprintln!("wrote {} and {}", csv_path.display(), md_path.display());
    Ok(())
}

/// The knobs each row sets (`subsample`, `bounces`) or resolves by its sub-sampling
/// (`shading_storage`: the table's planes column), left out of the header.
const PER_ROW_KNOBS: [&str; 3] = ["subsample=", "bounces=", "shading_storage="];

/// The resolved knobs without [`PER_ROW_KNOBS`].
fn per_row_knobs_removed(knobs: &str) -> String {
    knobs.split(' ').filter(|k| !PER_ROW_KNOBS.iter().any(|p| k.starts_with(p))).collect::<Vec<_>>().join(" ")
}

fn to_csv(rows: &[Timed], device: &str, driver: &str) -> String {
    let mut s = String::from("size,subsample,bounces,total_ms,fps,memory_bytes,stages,device,driver\n");
    for r in rows {
        let (n, sub, b) = r.cfg;
        let stages: Vec<String> = r.stages.iter().map(|(k, ms)| format!("{k}={ms:.4}")).collect();
        let _ = writeln!(
            s,
            "{n},{sub},{b},{:.4},{:.4},{},{},\"{device}\",\"{driver}\"",
            r.total_ms,
            1000.0 / r.total_ms,
            r.memory,
            stages.join(";")
        );
    }
    s
}

fn to_md(header: &str, rows: &[Timed], skipped: &[Config]) -> String {
    let mut s = format!("{header}\n| field | sub-sampling | bounces | frame (ms) | fps | GPU memory (MiB) | shading planes | largest stages (ms) |\n|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        let (n, sub, b) = r.cfg;
        let mut top = r.stages.clone();
        top.sort_by(|x, y| y.1.total_cmp(&x.1));
        let top: Vec<String> = top.iter().take(3).map(|(k, ms)| format!("{k} {ms:.1}")).collect();
        let _ = writeln!(
            s,
            "| {n}² | {sub}× | {b} | {:.1} | {:.2} | {:.1} | {} | {} |",
            r.total_ms,
            1000.0 / r.total_ms,
            r.memory as f64 / 1048576.0,
            r.planes,
            top.join(", ")
        );
    }
    if !skipped.is_empty() {
        let list: Vec<String> = skipped.iter().map(|(n, sub, b)| format!("{n}² {sub}× {b}b")).collect();
        let _ = writeln!(s, "\nNot run (the budget was spent): {}.", list.join(", "));
    }
    s
}
