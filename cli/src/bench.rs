//! `hfgi bench`: what accuracy costs in time (docs/accuracy.md). Sweeps the algorithm's knobs
//! one at a time around the scene's settings (plus an azimuths × level-step grid, the paper's
//! figure 10), and for every configuration records the per-stage GPU time (median of repeated
//! frames after warm-up), the GPU memory, and the relative L2 error per layer against both
//! ground truths; it also times the brute-force reference on the same scene.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use hfgi::frame::Renderer;
use hfgi::reference::truth::{TruthOutput, TruthSettings};
use hfgi::scene::model::{
    BlockerExp, BlockerKeyLights, BlockerLogCap, BlockerShading, GiSettings, Horizon, Interpolation, Level0,
    PyramidMode, Quality, Scene, VisibilityMethod,
};
use hfgi::vk::{Context, Recorder, StageTimer};

use super::{context, load_scene_or_default, plot, DeviceArgs};

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

/// The configurations: the baseline, then one knob at a time, the four presets, then (full
/// sweep) the m × k grid; swept horizons (`gi.visibility = "sweep"`) unless the field wraps;
/// the local lights' azimuths when the scene has local lights; the sphere blockers' settings
/// when it has spheres.
fn configs(base: &GiSettings, quick: bool, base_wraps: bool, content: Content) -> Vec<(String, GiSettings)> {
    let mut c = Configs { base, out: vec![("baseline".to_string(), base.clone())] };
    c.knobs(quick);
    // Swept horizons (docs/direct.md §7), at the default near reach and along it.
    if !base_wraps {
        c.sweep(quick);
    }
    if content.spheres {
        c.blockers();
    }
    if content.local_lights {
        let ks: &[u32] = if quick { &[4] } else { &[2, 4, 8, 16, 32] };
        for &k in ks {
            c.push("local_light_azimuths", &|g| g.local_light_azimuths = k);
        }
    }
    // The presets, marked on the Pareto plot (one group each).
    for q in [Quality::Draft, Quality::Default, Quality::High, Quality::Ultra] {
        c.push(&format!("quality={q}"), &|g| *g = base.with_quality(q));
    }
    if !quick {
        for m in [8, 16, 32, 64, 128] {
            for k in [1, 2, 4, 8] {
                c.push("grid m×k", &|g| {
                    g.azimuths = m;
                    g.level_step = k;
                });
            }
        }
    }
    c.out
}

/// The configurations of [`configs`] as they are listed, around `base`.
struct Configs<'a> {
    base: &'a GiSettings,
    out: Vec<(String, GiSettings)>,
}

impl Configs<'_> {
    /// `base` changed by `f`, under `knob`, unless it is `base` or listed already.
    fn push(&mut self, knob: &str, f: &dyn Fn(&mut GiSettings)) {
        let mut g = self.base.clone();
        f(&mut g);
        if g != *self.base && !self.out.iter().any(|(_, o)| *o == g) {
            self.out.push((knob.to_string(), g));
        }
    }

    /// The scan's and the shading's knobs, one at a time.
    fn knobs(&mut self, quick: bool) {
        let ms: &[u32] = if quick { &[8, 16] } else { &[4, 8, 16, 32, 64, 128] };
        for &m in ms {
            self.push("azimuths", &|g| g.azimuths = m);
        }
        // The later bounces' azimuths (at most m; docs/performance.md §12).
        let later: &[u32] = if quick { &[8] } else { &[4, 8, 16, 32, 64] };
        for &m in later {
            self.push("azimuths_later", &|g| g.azimuths_later = m);
        }
        let ks: &[u32] = if quick { &[2] } else { &[1, 2, 4, 8, 16] };
        for &k in ks {
            self.push("level_step", &|g| g.level_step = k);
        }
        let os: &[u32] = if quick { &[0] } else { &[0, 1, 2, 3, 4, 5, 6, 8] };
        for &o in os {
            self.push("level_offset", &|g| g.level_offset = o);
        }
        if !quick {
            for o in [0, 2, 4, 6] {
                self.push("radiance_level_offset", &|g| g.radiance_level_offset = o);
            }
        }
        for s in [1, 2, 4] {
            self.push("subsample", &|g| g.subsample = s);
        }
        for i in [Interpolation::Linear, Interpolation::Bspline] {
            self.push("interpolation", &|g| g.interpolation = i);
        }
        let ns: &[usize] = if quick { &[3] } else { &[3, 4, 5, 6] };
        for &n in ns {
            self.push("sh_order", &|g| g.sh_order = n);
        }
        for p in [PyramidMode::Stack, PyramidMode::Pyramid] {
            self.push("pyramid", &|g| g.pyramid = p);
        }
        for b in 0..=3 {
            self.push("bounces", &|g| g.bounces = b);
        }
    }

    /// Swept horizons, and their near reach.
    fn sweep(&mut self, quick: bool) {
        self.push("visibility", &|g| g.visibility = VisibilityMethod::Sweep);
        let rs: &[u32] = if quick { &[0] } else { &[0, 4, 8, 32, 64] };
        for &r in rs {
            self.push("sweep_near", &|g| {
                g.visibility = VisibilityMethod::Sweep;
                g.sweep_near = r;
            });
        }
    }

    /// The sphere blockers' settings.
    fn blockers(&mut self) {
        let base = self.base;
        for e in [0.05, 0.1, 0.2, 0.5] {
            self.push("blocker_epsilon", &|g| g.blocker_epsilon = e);
        }
        self.push("blocker_ratio", &|g| g.blocker_ratio = !base.blocker_ratio);
        for x in [BlockerExp::Quadrature, BlockerExp::Linear] {
            self.push("blocker_exp", &|g| g.blocker_exp = x);
        }
        for m in [BlockerShading::Log, BlockerShading::LogField, BlockerShading::LogBrdf, BlockerShading::Primal] {
            self.push("blocker_shading", &|g| g.blocker_shading = m);
        }
        self.push("blocker_log_cap", &|g| g.blocker_log_cap = BlockerLogCap::Matched);
        self.push("blocker_key_lights", &|g| g.blocker_key_lights = BlockerKeyLights::Product);
        for m in [BlockerShading::LogField, BlockerShading::LogBrdf] {
            self.push("blocker_log_cap", &|g| {
                g.blocker_log_cap = BlockerLogCap::Matched;
                g.blocker_shading = m;
            });
        }
    }
}

fn with_preset(scene: &GiSettings, preset: Quality) -> GiSettings {
    scene.with_quality(preset)
}

/// The ablation of docs/accuracy.md §4: the paper, each fix alone on the paper's settings, all
/// fixes (the `default` preset); then the preset ladder.
fn ablation(base: &GiSettings, presets_only: bool) -> Vec<(String, GiSettings)> {
    let paper = with_preset(base, Quality::Paper);
    let mut out = vec![("paper".to_string(), paper.clone())];
    if !presets_only {
        let all = with_preset(base, Quality::Default);
        let fix = |name: &str, f: &dyn Fn(&mut GiSettings)| {
            let mut g = paper.clone();
            f(&mut g);
            (name.to_string(), g)
        };
        out.push(fix("level0=bilinear", &|g| g.level0 = all.level0));
        out.push(fix("horizon=samples", &|g| g.horizon = all.horizon));
        out.push(fix(&format!("near_steps={}", all.near_steps), &|g| g.near_steps = all.near_steps));
        out.push(fix("scan_reach=diagonal", &|g| g.scan_reach = all.scan_reach));
        out.push(fix("omega_min=tangent", &|g| g.omega_min = all.omega_min));
        out.push(fix("elevation_basis=legendre", &|g| g.elevation_basis = all.elevation_basis));
    }
    for q in [Quality::Draft, Quality::Default, Quality::High, Quality::Ultra] {
        out.push((format!("quality={q}"), with_preset(base, q)));
    }
    out
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

/// Per-stage times of the paper's settings and the presets (columns), if the sweep has them.
fn stage_table(md: &mut String, rows: Vec<&Row>) {
    let cols: Vec<&Row> = rows.into_iter().filter(|r| r.knob == "paper" || r.knob.starts_with("quality=")).collect();
    if cols.is_empty() {
        return;
    }
    let mut stages: Vec<&str> = Vec::new();
    for r in &cols {
        for (n, _) in &r.stages {
            if !stages.contains(&n.as_str()) {
                stages.push(n);
            }
        }
    }
    let _ = writeln!(md, "\nTime per stage (ms) of the paper's settings and the presets:\n");
    let _ = writeln!(md, "| stage | {} |", cols.iter().map(|r| r.knob.as_str()).collect::<Vec<_>>().join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(cols.len()));
    for st in stages {
        let cells: Vec<String> = cols
            .iter()
            .map(|r| r.stages.iter().find(|(n, _)| n == st).map_or("—".into(), |(_, ms)| format!("{ms:.2}")))
            .collect();
        let _ = writeln!(md, "| {st} | {} |", cells.join(" | "));
    }
    let totals: Vec<String> = cols.iter().map(|r| format!("**{:.1}**", r.total_ms)).collect();
    let _ = writeln!(md, "| **frame** | {} |", totals.join(" | "));
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

fn settings_label(g: &GiSettings) -> String {
    let fixes = if g.level0 == Level0::Bspline && g.near_steps == 0 && g.horizon == Horizon::Bspline {
        String::new()
    } else {
        format!(" l0={} hz={} near={} reach={} ωmin={}", g.level0, g.horizon, g.near_steps, g.scan_reach, g.omega_min)
    };
    let probes = if g.radial_probes > 0 || g.radial_probes_later > 0 {
        format!(" probes={}/{}", g.radial_probes, g.radial_probes_later)
    } else {
        String::new()
    };
    let sweep = match g.visibility {
        VisibilityMethod::Sweep => format!(" sweep near={}", g.sweep_near),
        VisibilityMethod::Ladder => String::new(),
    };
    let d = GiSettings::default();
    let blockers = if (g.blocker_epsilon, g.blocker_ratio, g.blocker_exp, g.blocker_shading, g.blocker_log_cap)
        != (d.blocker_epsilon, d.blocker_ratio, d.blocker_exp, d.blocker_shading, d.blocker_log_cap)
        || g.blocker_key_lights != d.blocker_key_lights
    {
        format!(
            " ε={} ratio={} exp={} {} cap={} keys={}",
            g.blocker_epsilon,
            g.blocker_ratio,
            g.blocker_exp,
            g.blocker_shading,
            g.blocker_log_cap,
            g.blocker_key_lights
        )
    } else {
        String::new()
    };
    let default_local = d.local_light_azimuths;
    let local = if g.local_light_azimuths != default_local {
        format!(" local_az={}", g.local_light_azimuths)
    } else {
        String::new()
    };
    let m = azimuths_label(g);
    format!(
        "n={} m={m} k={} o={} s={} {} {} b={}{fixes}{probes}{sweep}{local}{blockers}",
        g.sh_order, g.level_step, g.level_offset, g.subsample, g.interpolation, g.pyramid, g.bounces
    )
}

/// `m`, or `m/m_later` when the later bounces scan with fewer azimuths (`gi.azimuths_later`):
/// the bench's labels and `hfgi render`'s settings line.
pub(crate) fn azimuths_label(g: &GiSettings) -> String {
    match g.scan_azimuths(2) {
        later if g.bounces > 1 && later != g.azimuths => format!("{}/{later}", g.azimuths),
        _ => g.azimuths.to_string(),
    }
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

fn write_outputs(
    a: &BenchArgs,
    rows: &[Row],
    references: &[(String, Option<f64>, Option<f64>)],
    info: &hfgi::vk::DeviceInfo,
    clock: &str,
) -> Result<()> {
    let csv_path = a.out.join("results.csv");
    hfgi::io::atomic::write_bytes(&csv_path, results_csv(rows, info).as_bytes())?;

    // Markdown: per scene, the table; the reference times; the m × k grid.
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Device: {} ({}), times: {clock}, field {}, {} timed frames (median) after 1 warm-up.\n",
        info.name,
        info.driver,
        a.size_label(),
        a.frames
    );
    for (scene, ex, sv) in references {
        scene_table(&mut md, rows, (scene, ex, sv), clock);
        stage_table(&mut md, rows.iter().filter(|r| &r.scene == scene).collect());
        grid_table(&mut md, rows, scene);
        // Error against time, Pareto front marked.
        pareto_plot(a, rows, scene, *ex, clock)?;
        let _ = writeln!(md, "\n![{scene}: error against time](pareto-{scene}.png)\n");
    }
    let md_path = a.out.join("results.md");
    hfgi::io::atomic::write_bytes(&md_path, md.as_bytes())?;
    eprintln!("wrote {}, {} and the plots", csv_path.display(), md_path.display());
    Ok(())
}

/// An error for the Markdown tables: `1.2345e-3`, or "—" where it is not finite.
fn fmt_e(e: f64) -> String {
    if e.is_finite() {
        format!("{e:.4e}")
    } else {
        "—".into()
    }
}

/// results.csv: one row per configuration.
fn results_csv(rows: &[Row], info: &hfgi::vk::DeviceInfo) -> String {
    let mut csv = String::from(
        "scene,knob,sh_order,azimuths,level_step,level_offset,subsample,interpolation,pyramid,bounces,total_ms,\
         memory_bytes,exact_direct,exact_indirect,exact_total,shvis_direct,shvis_indirect,shvis_total,stages,device,driver,knobs\n",
    );
    for r in rows {
        let g = &r.gi;
        let stages: Vec<String> = r.stages.iter().map(|(n, ms)| format!("{n}={ms:.4}")).collect();
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{:.4},{},{},{},{},{},{},{},{},\"{}\",\"{}\",\"{}\"",
            r.scene,
            r.knob,
            g.sh_order,
            g.azimuths,
            g.level_step,
            g.level_offset,
            g.subsample,
            g.interpolation,
            g.pyramid,
            g.bounces,
            r.total_ms,
            r.memory,
            r.exact[0],
            r.exact[1],
            r.exact[2],
            r.shvis[0],
            r.shvis[1],
            r.shvis[2],
            stages.join(";"),
            info.name,
            info.driver,
            g.describe()
        );
    }
    csv
}

/// A scene's section of results.md: its reference times (`ex`, `sv`: exact and SH-visibility)
/// and one table row per configuration.
fn scene_table(md: &mut String, rows: &[Row], (scene, ex, sv): (&str, &Option<f64>, &Option<f64>), clock: &str) {
    let t = |v: &Option<f64>| v.map_or("no timestamps".into(), |ms| format!("{ms:.1} ms"));
    let _ =
        writeln!(md, "### {scene}\n\nBrute-force reference: exact {}, SH-visibility {} ({}).\n", t(ex), t(sv), clock);
    let _ = writeln!(
        md,
        "| knob | settings | time (ms) | speed-up vs exact reference | memory (MiB) | err exact: direct / indirect / total | err SH-vis: direct / indirect / total |\n|---|---|---|---|---|---|---|"
    );
    for r in rows.iter().filter(|r| r.scene == scene) {
        let speed = ex.map_or("—".into(), |ms| format!("{:.0}×", ms / r.total_ms));
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} | {} | {:.2} | {} / {} / {} | {} / {} / {} |",
            r.knob,
            settings_label(&r.gi),
            r.total_ms,
            speed,
            r.memory as f64 / 1048576.0,
            fmt_e(r.exact[0]),
            fmt_e(r.exact[1]),
            fmt_e(r.exact[2]),
            fmt_e(r.shvis[0]),
            fmt_e(r.shvis[1]),
            fmt_e(r.shvis[2])
        );
    }
}

/// Figure 10: total error against the exact reference as m and k grow, where the sweep of
/// `scene` has the m × k grid.
fn grid_table(md: &mut String, rows: &[Row], scene: &str) {
    // Every row that differs from the baseline in m and k only (the grid, the baseline and
    // the single-knob rows of m and k).
    let base = rows.iter().find(|r| r.scene == scene && r.knob == "baseline").map(|r| r.gi.clone());
    let grid: Vec<&Row> = rows
        .iter()
        .filter(|r| {
            r.scene == scene
                && base.as_ref().is_some_and(|b| {
                    GiSettings { azimuths: b.azimuths, level_step: b.level_step, ..r.gi.clone() } == *b
                })
        })
        .collect();
    if rows.iter().any(|r| r.scene == scene && r.knob == "grid m×k") {
        let mut ms: Vec<u32> = grid.iter().map(|r| r.gi.azimuths).collect();
        ms.sort();
        ms.dedup();
        let mut ks: Vec<u32> = grid.iter().map(|r| r.gi.level_step).collect();
        ks.sort();
        ks.dedup();
        let _ = writeln!(md, "\nTotal error against the exact reference (figure 10): rows m, columns k.\n");
        let _ = writeln!(md, "| m \\ k | {} |", ks.iter().map(|k| k.to_string()).collect::<Vec<_>>().join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(ks.len()));
        for m in &ms {
            let cells: Vec<String> = ks
                .iter()
                .map(|k| {
                    grid.iter()
                        .find(|r| r.gi.azimuths == *m && r.gi.level_step == *k)
                        .map_or("—".into(), |r| format!("{} ({:.1} ms)", fmt_e(r.exact[2]), r.total_ms))
                })
                .collect();
            let _ = writeln!(md, "| {m} | {} |", cells.join(" | "));
        }
    }
}

/// pareto-<scene>.png: the total error of `scene`'s configurations against their time, the
/// exact reference's time `ex` marked.
fn pareto_plot(a: &BenchArgs, rows: &[Row], scene: &str, ex: Option<f64>, clock: &str) -> Result<()> {
    let points: Vec<plot::Point> = rows
        .iter()
        .filter(|r| r.scene == scene)
        .map(|r| plot::Point {
            label: settings_label(&r.gi),
            time_ms: r.total_ms,
            error: r.exact[2],
            group: r.knob.clone(),
        })
        .collect();
    let png = a.out.join(format!("pareto-{scene}.png"));
    let note = plot::pareto_plot(
        &png,
        &format!("{scene}: total error vs time ({clock})"),
        "time per frame (ms)",
        "relative L2 error vs exact reference",
        &points,
        ex,
    )?;
    if let Some(n) = note {
        eprintln!("{}: {n}", png.display());
    }
    Ok(())
}
