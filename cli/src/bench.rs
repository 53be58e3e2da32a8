//! `hfgi bench`: what accuracy costs in time (docs/accuracy.md). Sweeps the algorithm's knobs
//! one at a time around the scene's settings (plus an azimuths × level-step grid, the paper's
//! figure 10), and for every configuration records the per-stage GPU time (median of repeated
//! frames after warm-up), the GPU memory, and the relative L2 error per layer against both
//! ground truths; it also times the brute-force reference on the same scene.

mod output;
mod sweep;

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use hfgi::frame::Renderer;
use hfgi::reference::truth::{TruthOutput, TruthSettings};
use hfgi::scene::model::{GiSettings, Scene};
use hfgi::vk::{Context, Recorder, StageTimer};

use super::{context, load_scene_or_default, DeviceArgs};

pub(crate) use output::azimuths_label;
use output::write_outputs;
use sweep::{ablation, configs};

#[derive(Args)]
pub struct BenchArgs {
    /// Scene files (comma-separated). Default: the default scene, craters and city blocks.
    #[arg(long, value_delimiter = ',', default_value = "scenes/default.toml,scenes/craters.toml,scenes/city.toml")]
    pub(crate) scenes: Vec<PathBuf>,
    /// Field size (texels per side) the scenes are rendered at (heightfield.size); 0 keeps each
    /// scene's own size (e.g. the non-square scenes/hard/steep.toml). Default 128 (64 with --quick).
    #[arg(long)]
    pub(crate) size: Option<u32>,
    /// What to sweep: `knobs` (one knob at a time around the scene's settings plus the m × k grid
    /// of figure 10), `ablation` (the paper's settings, each accuracy fix of docs/accuracy.md §4
    /// alone, all of them) or `presets` (gi.quality draft → ultra, and the paper).
    #[arg(long, default_value = "knobs")]
    pub(crate) sweep: Sweep,
    /// Override a setting of every scene, e.g. `--set gi.sh_order=4`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) overrides: Vec<String>,
    /// Keep only these knobs of the sweep (comma-separated names of the `knob` column, e.g.
    /// `level_offset,azimuths`); the baseline is always kept.
    #[arg(long, value_delimiter = ',')]
    pub(crate) only: Vec<String>,
    /// Timed frames per configuration (after one warm-up frame); the median is reported.
    #[arg(long, default_value_t = 5)]
    pub(crate) frames: u32,
    /// Bounces of the baseline configuration (the sweep over bounces covers 0..=3).
    #[arg(long, default_value_t = 1)]
    pub(crate) bounces: u32,
    /// Remove the scenes' key lights (environment light only): the references see a key light
    /// as its order-n SH projection, the pipeline as its window (docs/direct.md §5), so key
    /// lights add a convention difference to the error.
    #[arg(long)]
    pub(crate) no_key_lights: bool,
    /// A small sweep (for tests and quick looks): fewer values per knob, no grid.
    #[arg(long)]
    pub(crate) quick: bool,
    /// Azimuths of the ground truth (CONVENTIONS.md: at least 256).
    #[arg(long, default_value_t = 256)]
    pub(crate) reference_azimuths: u32,
    /// Output folder: results.csv, results.md, pareto-<scene>.png.
    #[arg(long, default_value = "out/bench")]
    pub(crate) out: PathBuf,
    /// Also write each exact reference to DIR/reference-<scene>-n<order>.exr (the layers of
    /// `hfgi reference --shading-exr`, diffuse, with the most bounces any configuration uses),
    /// e.g. for tools/peer_ratio.py.
    #[arg(long)]
    pub(crate) save_references: bool,
    /// Skip the SH-visibility reference (its error columns read "—"), which halves the
    /// reference time when only the error against the exact truth is wanted.
    #[arg(long)]
    pub(crate) no_sh_visibility: bool,
    /// Timing only (no references, any device): the median frame per stage, fps and memory over
    /// table 1's grid (256², 512², 1024², or `--size`; sub-sampling 4×, 2×, 1×; 1–3 bounces)
    /// on the first of `--scenes` (default: the default scene), cheapest first, until `--budget`
    /// seconds are spent. Writes timing.csv and timing.md.
    #[arg(long)]
    pub(crate) timing: bool,
    /// With `--timing`: seconds after which no further configuration is started.
    #[arg(long, default_value_t = 600)]
    pub(crate) budget: u64,
    #[command(flatten)]
    pub(crate) device: DeviceArgs,
}

impl BenchArgs {
    fn field_size(&self) -> u32 {
        self.size.unwrap_or(if self.quick { 64 } else { 128 })
    }
    fn size_label(&self) -> String {
        match self.field_size() {
            0 => "each scene's own size".into(),
            n => format!("{n}²"),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Sweep {
    Knobs,
    Ablation,
    Presets,
}

/// What a scene holds beyond the height field that has knobs of its own.
#[derive(Clone, Copy)]
struct Content {
    local_lights: bool,
    spheres: bool,
}

/// One configuration's measurements.
struct Row {
    scene: String,
    knob: String,
    gi: GiSettings,
    stages: Vec<(String, f64)>,
    total_ms: f64,
    memory: u64,
    /// Relative L2 (direct, indirect, total) against the exact and the SH-visibility truth.
    exact: [f64; 3],
    shvis: [f64; 3],
}

/// Relative L2 (CONVENTIONS.md) of `x` against the reference `r`; NaN where `r` is zero.
fn rel_l2(x: &[[f32; 3]], r: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in x.iter().zip(r) {
        for c in 0..3 {
            num += (a[c] as f64 - b[c]).powi(2);
            den += b[c] * b[c];
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        f64::NAN
    }
}

/// A scene's ground truths at each SH order: (order, exact, exact ms, SH-visibility unless
/// `--no-sh-visibility`), with `max_b` bounces. Records the times at the scene's own order in
/// `references` and, with `--save-references`, writes each exact truth to
/// `DIR/reference-<name>-n<order>.exr`.
#[allow(clippy::too_many_arguments)]
fn truths(
    ctx: &Context,
    a: &BenchArgs,
    scene: &Scene,
    name: &str,
    orders: &[usize],
    max_b: u32,
    bar: &indicatif::ProgressBar,
    references: &mut Vec<(String, Option<f64>, Option<f64>)>,
) -> Result<Vec<Truths>> {
    let mut truths: Vec<Truths> = Vec::new();
    for &n in orders {
        bar.set_message(format!("{name}: references at order {n}"));
        let mut truth_scene = scene.clone();
        truth_scene.gi.bounces = max_b;
        truth_scene.gi.sh_order = n;
        let ts = TruthSettings { azimuths: a.reference_azimuths, ..Default::default() };
        // The exact reference depends on the order only through the lighting: without key
        // lights and with no environment bands between two orders it is the same.
        let same = |m: usize| {
            let (lo, hi) = (m.min(n), m.max(n));
            scene.key_lights.is_empty()
                && scene
                    .environment
                    .sh
                    .iter()
                    .skip(lo * lo)
                    .take(hi * hi - lo * lo)
                    .all(|c| c.iter().all(|v| *v == 0.0))
        };
        let (exact, exact_ms) = match truths.iter().find(|(m, _, _, _)| same(*m)) {
            Some((_, e, ms, _)) => (clone_truth(e), *ms),
            None => hfgi::frame::truth::render_truth_gpu_timed(ctx, &truth_scene, &ts, &mut |_, _| {})?,
        };
        bar.inc(1);
        if a.save_references {
            let path = a.out.join(format!("reference-{name}-n{n}.exr"));
            super::reference::write_truth_exr(&path, &exact)?;
        }
        let (shvis, shvis_ms) = if a.no_sh_visibility {
            (None, None)
        } else {
            let shv_settings = TruthSettings { sh_visibility: true, ..ts };
            let (t, ms) = hfgi::frame::truth::render_truth_gpu_timed(ctx, &truth_scene, &shv_settings, &mut |_, _| {})?;
            bar.inc(1);
            (Some(t), ms)
        };
        if n == scene.gi.sh_order || (truths.is_empty() && !orders.contains(&scene.gi.sh_order)) {
            references.push((name.to_string(), exact_ms, shvis_ms));
        }
        truths.push((n, exact, exact_ms, shvis));
    }
    Ok(truths)
}

/// One SH order's ground truths: (order, exact, exact ms, SH-visibility).
type Truths = (usize, TruthOutput, Option<f64>, Option<TruthOutput>);

fn clone_truth(t: &TruthOutput) -> TruthOutput {
    TruthOutput::assemble(t.width, t.height, t.direct.clone(), t.indirect_bounces.clone())
}

/// Reference layers for `bounces` bounces: (direct, indirect, total).
fn truth_layers(t: &TruthOutput, bounces: u32) -> [Vec<[f64; 3]>; 3] {
    let b = t.indirect_bounces.iter().take(bounces as usize).cloned().collect();
    let a = TruthOutput::assemble(t.width, t.height, t.direct.clone(), b);
    [a.direct, a.indirect, a.total]
}

/// Median milliseconds per stage, GPU memory in bytes, and the last frame's layers.
pub(crate) type Measurement = (Vec<(String, f64)>, u64, hfgi::frame::ShadingLayers);

/// Renders `scene` `1 + frames` times (every stage each frame) and returns the median time per
/// stage (summed over a stage's repeats within a frame), the memory and the layers.
pub(crate) fn measure(ctx: &Context, scene: &Scene, frames: u32) -> Result<Measurement> {
    let mut r = Renderer::new(ctx, scene)?;
    let stages = 8 + 5 * scene.gi.bounces;
    let mut timer = match StageTimer::new(ctx, stages) {
        Ok(t) => t,
        Err(e) => {
            r.destroy(ctx);
            return Err(e.into());
        }
    };
    let mut per_stage: Vec<(String, Vec<f64>)> = Vec::new();
    let run = (|| -> Result<hfgi::frame::ShadingLayers> {
        for f in 0..=frames {
            r.mark_heights_changed();
            ctx.submit_and_wait(|cmd| {
                let mut rec = Recorder::new(ctx, cmd, Some(&mut timer));
                r.record(&mut rec);
                Ok(())
            })?;
            if f == 0 {
                continue; // warm-up
            }
            let mut frame: Vec<(String, f64)> = Vec::new();
            for (name, ms) in timer.timings(ctx)? {
                match frame.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, acc)) => *acc += ms,
                    None => frame.push((name, ms)),
                }
            }
            for (name, ms) in frame {
                match per_stage.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, v)) => v.push(ms),
                    None => per_stage.push((name, vec![ms])),
                }
            }
        }
        Ok(r.read_layers(ctx)?)
    })();
    let memory = r.memory_bytes();
    timer.destroy(ctx);
    r.destroy(ctx);
    let layers = run?;
    Ok((per_stage.into_iter().map(|(n, mut v)| (n, super::median(&mut v))).collect(), memory, layers))
}

/// Most timed frames per configuration (the median of a few is what the bench reports).
const MAX_BENCH_FRAMES: u32 = 1000;

/// Every file `bench` writes (results.csv, results.md, a Pareto plot per scene) checked
/// against its inputs (every scene and the files they read) before any work.
fn check_bench_outputs(a: &BenchArgs) -> Result<()> {
    let mut outputs = vec![a.out.join("results.csv"), a.out.join("results.md")];
    let mut inputs = Vec::new();
    for path in &a.scenes {
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        outputs.push(a.out.join(format!("pareto-{stem}.png")));
        inputs.extend(hfgi::scene::file::input_files(Some(path), &a.overrides));
    }
    let outputs: Vec<&std::path::Path> = outputs.iter().map(|p| p.as_path()).collect();
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    hfgi::io::atomic::check_outputs(&outputs, &inputs)?;
    Ok(())
}

pub fn bench(a: BenchArgs) -> Result<()> {
    if !(1..=MAX_BENCH_FRAMES).contains(&a.frames) {
        bail!("--frames {}: expected 1..={MAX_BENCH_FRAMES} timed frames per configuration", a.frames);
    }
    if a.timing {
        return super::timing::run(&a, a.budget);
    }
    check_bench_outputs(&a)?;
    let ctx = context(&a.device)?;
    let info = ctx.info().clone();
    let lavapipe = info.kind == ash::vk::PhysicalDeviceType::CPU;
    let clock = if lavapipe { "lavapipe (CPU time, not a GPU time)" } else { "GPU timestamps" };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    eprintln!(
        "bench on {} ({}), {} fields, {} timed frames per configuration",
        info.name,
        info.driver,
        a.size_label(),
        a.frames
    );
    let mut rows: Vec<Row> = Vec::new();
    let mut references: Vec<(String, Option<f64>, Option<f64>)> = Vec::new();
    for path in &a.scenes {
        let (name, scene) = bench_scene(&a, path)?;
        let cfgs = scene_configs(&a, &scene);
        let max_b = cfgs.iter().map(|(_, g)| g.bounces).max().unwrap_or(0);
        let mut orders: Vec<usize> = cfgs.iter().map(|(_, g)| g.sh_order).collect();
        orders.sort();
        orders.dedup();
        let per_order = if a.no_sh_visibility { 1 } else { 2 };
        let bar = indicatif::ProgressBar::new(cfgs.len() as u64 + per_order * orders.len() as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} {wide_bar} {pos}/{len} [{elapsed} < {eta}]") {
            bar.set_style(style);
        }
        let truths = truths(&ctx, &a, &scene, &name, &orders, max_b, &bar, &mut references)?;
        for (knob, gi) in cfgs {
            bar.set_message(format!("{name}: {knob}"));
            rows.push(measure_row(&ctx, &scene, &name, knob, gi, a.frames, &truths)?);
            bar.inc(1);
        }
        bar.finish_and_clear();
        ctx.check_validation()?;
        // After every scene, so that a long run that is stopped keeps what it measured.
        write_outputs(&a, &rows, &references, &info, clock)?;
    }
    Ok(())
}

/// The scene at `path` as benched, with its name (the file stem): at the bench's field size
/// and bounces with the `--set` overrides, diffuse, without key lights with `--no-key-lights`.
fn bench_scene(a: &BenchArgs, path: &std::path::Path) -> Result<(String, Scene)> {
    let size = a.field_size();
    let mut overrides = vec![format!("gi.bounces={}", a.bounces)];
    if size > 0 {
        overrides.push(format!("heightfield.size={size}"));
    }
    overrides.extend(a.overrides.iter().cloned());
    let mut scene = load_scene_or_default(Some(path), &overrides)?;
    // The ground truth treats surfaces as diffuse: benchmark diffuse materials.
    scene.material.specular = None;
    if a.no_key_lights {
        scene.key_lights.clear();
    }
    let name = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    Ok((name, scene))
}

/// The configurations `(knob, settings)` of `--sweep` for `scene`, kept to the baseline and
/// the `--only` knobs when given.
fn scene_configs(a: &BenchArgs, scene: &Scene) -> Vec<(String, GiSettings)> {
    let cfgs = match a.sweep {
        Sweep::Knobs => {
            let content = Content { local_lights: !scene.local_lights.is_empty(), spheres: !scene.spheres.is_empty() };
            configs(&scene.gi, a.quick, scene.wrap, content)
        }
        Sweep::Ablation => ablation(&scene.gi, false),
        Sweep::Presets => ablation(&scene.gi, true),
    };
    cfgs.into_iter()
        .enumerate()
        .filter(|(i, (knob, _))| *i == 0 || a.only.is_empty() || a.only.iter().any(|o| o == knob))
        .map(|(_, c)| c)
        .collect()
}

/// The row of configuration `gi` (`knob`) of `scene` (`name`): its stage times over `frames`
/// timed frames, its memory and its errors against the `truths` at its order.
fn measure_row(
    ctx: &Context,
    scene: &Scene,
    name: &str,
    knob: String,
    gi: GiSettings,
    frames: u32,
    truths: &[Truths],
) -> Result<Row> {
    let mut s = scene.clone();
    s.gi = gi.clone();
    s.gi.amortize = false;
    let (stages, memory, layers) = measure(ctx, &s, frames).with_context(|| format!("{name}: {knob}"))?;
    let (_, exact, _, shvis) = truths.iter().find(|(n, _, _, _)| *n == gi.sh_order).expect("reference");
    let got = [&layers.direct, &layers.indirect, &layers.total];
    let err = |r: &[Vec<[f64; 3]>; 3]| [0, 1, 2].map(|i| rel_l2(got[i], &r[i]));
    let e = truth_layers(exact, gi.bounces);
    let v = shvis.as_ref().map_or([f64::NAN; 3], |t| err(&truth_layers(t, gi.bounces)));
    let total_ms = stages.iter().map(|(_, ms)| ms).sum();
    Ok(Row { scene: name.to_string(), knob, gi, stages, total_ms, memory, exact: err(&e), shvis: v })
}
