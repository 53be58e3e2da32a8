//! `hfgi` — command-line front end of the hfgi library.

mod animate;
mod bench;
mod export;
mod plot;
mod pyramid;
mod reference;
mod render;
mod timing;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use hfgi::scene::animated::Animation;
use hfgi::vk::{Context, ContextOptions, StageTimer};

use render::{render, RenderArgs};

/// Real-time global illumination on dynamic height fields (Nowrouzezahrai & Snyder 2009), on Vulkan.
///
/// Environment: HFGI_DEVICE=<substring> picks the Vulkan device (default: discrete > integrated >
/// virtual > CPU); HFGI_VALIDATION=1 enables the validation layer and fails on any message;
/// VK_DRIVER_FILES pins a driver (tools/env.sh pins lavapipe).
#[derive(Parser)]
#[command(name = "hfgi", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file (or the default scene) and write the view image.
    ///
    /// Computes the shading texture, then rasterises the height field from the scene camera
    /// (`[camera]`: camera.width × camera.height pixels, MSAA up to 8×; docs/view.md) and writes
    /// that view image tone-mapped as a PNG (--out) and, with --view-exr, as linear float32 RGB.
    /// With --shading-exr it writes the per-texel shading texture with float32 layers `direct`,
    /// `indirect`, `glossy` and the total in R, G, B (docs/conventions.md); --shading-png writes
    /// the total tone-mapped, seen from above (one pixel per texel). Prints the per-stage GPU
    /// timings and memory. Scene format: docs/scene-format.md.
    Render(RenderArgs),
    /// Render an animated scene (its [animation] table: water or moving bumps) frame by frame.
    ///
    /// Creates one renderer (and one water simulation), then per frame advances the animation,
    /// records the frame and writes DIR/frame_0000.png, frame_0001.png, …; optionally an
    /// animated GIF. Prints the renderer's counters, the pipelines created before and after the
    /// loop, and the median per-stage time. See docs/dynamic.md.
    Animate(animate::AnimateArgs),
    /// Compute the brute-force ground truth of a scene (docs/accuracy.md §1).
    ///
    /// Intersects rays exactly with the full-resolution bilinear surface (no pyramid, no
    /// sub-sampling; --march --step S marches it instead) over --azimuths directions, lights it
    /// with the environment SH and the key lights as true caps, integrates elevations with
    /// Gauss–Legendre, and
    /// writes the shading texture in the layers `render` writes (direct, indirect = 1..bounces
    /// diffuse bounces, glossy = 0, total). The exact reference by default; --sh-visibility
    /// projects the exact visibility and indirect radiance to order-n SH first. On the GPU
    /// (compute) with a progress bar; --cpu runs the f64 CPU version (fields up to 64²).
    Reference(reference::ReferenceArgs),
    /// Measure what accuracy costs in time (docs/accuracy.md).
    ///
    /// For each scene (rendered at --size² texels, surfaces treated as diffuse): computes the
    /// exact and the SH-visibility ground truth on the GPU (timed), then sweeps the algorithm's
    /// knobs one at a time around the scene's settings — azimuths m, level step k, level
    /// offset o, sub-sampling, interpolation, SH order, pyramid mode, bounces — plus an m × k
    /// grid (the paper's figure 10). Every configuration: per-stage time (median of --frames
    /// frames after a warm-up), GPU memory, relative L2 error per layer against both
    /// references. Writes DIR/results.csv, DIR/results.md and DIR/pareto-<scene>.png (error
    /// against time, Pareto front marked). lavapipe times are labelled as CPU times.
    Bench(bench::BenchArgs),
    /// Write a scene resolved to plain data for outside tools: DIR/heights.f32 (raw float32,
    /// row-major, world units) and DIR/scene.toml (size, texel size, albedo, environment SH,
    /// key lights, local lights, spheres, bounces). The Mitsuba 3 peer check (tools/mitsuba_check.py) reads it.
    Export(export::ExportArgs),
    /// Print the passes and the stages a frame records, with the reason for each (no GPU).
    ///
    /// Plans the scene as `Renderer::new` and `Renderer::record` do (docs/plan.md) without
    /// creating a Vulkan context: first the passes created (and the ones left out, with why),
    /// then for each frame the ordered stage list with the reason for each stage and the stages
    /// left out. Frame 0 has new heights; with --frames N the later frames are static (so
    /// `gi.amortize` alternates direct and indirect shading), or have new heights every frame
    /// when the scene has an [animation].
    Plan(PlanArgs),
    /// Write a height field and its pyramid levels as images (heights.png/.exr, pyramid.png/.exr).
    Pyramid(pyramid::PyramidArgs),
    /// List the Vulkan devices and which one hfgi would choose.
    Devices,
    /// Write the embedded SPIR-V of every shader to a folder (for hosts building their own pipelines).
    Spirv {
        /// Output folder.
        #[arg(long, default_value = "out/spirv")]
        out: PathBuf,
    },
}

#[derive(Args)]
pub(crate) struct DeviceArgs {
    /// Vulkan device name substring (overrides HFGI_DEVICE).
    #[arg(long)]
    device: Option<String>,
    /// Enable the Vulkan validation layer and fail on any message.
    #[arg(long)]
    validation: bool,
}

#[derive(Args)]
struct PlanArgs {
    /// Scene file (TOML, docs/scene-format.md). Without it, the default scene.
    scene: Option<PathBuf>,
    /// Override a scene setting, e.g. `--set gi.bounces=2 --set gi.amortize=false`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Number of frames to plan (≥ 1): frame 0 with new heights, then static frames.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// Vulkan device name substring to check the scene against (default: the device `render`
    /// would choose, when one can be opened).
    #[arg(long)]
    device: Option<String>,
    /// Do not open a Vulkan device: plan and estimate the memory only.
    #[arg(long, conflicts_with = "device")]
    no_device: bool,
    /// List every buffer of the renderer's estimate, largest first (name and MiB).
    #[arg(long)]
    buffers: bool,
    /// Print the stage table first: every stage's name, the pass that records it and its rule
    /// (src/frame/stages.rs, the table the planner and the recorder read).
    #[arg(long)]
    stages: bool,
}

pub(crate) fn context(d: &DeviceArgs) -> Result<Context> {
    let opts = ContextOptions {
        validation: d.validation.then_some(true),
        device_filter: d.device.clone(),
        sync_validation: None,
    };
    let what = match &d.device {
        Some(name) => format!("creating the Vulkan context for --device {name:?}"),
        None => "creating the Vulkan context".to_string(),
    };
    Context::headless_with(&opts).context(what)
}

/// Prints the stage times of one recording (it includes first-dispatch compilation on lazy
/// drivers; `hfgi render` times a second frame instead).
pub(crate) fn print_single_timings(ctx: &Context, timer: &StageTimer) {
    match timer.timings(ctx) {
        Ok(t) => {
            let lavapipe = ctx.info().kind == ash::vk::PhysicalDeviceType::CPU;
            let label = if lavapipe {
                " (lavapipe: CPU time, not a GPU time; first dispatch: includes compilation)"
            } else {
                ""
            };
            for (stage, ms) in t {
                eprintln!("  {stage:<24} {ms:9.3} ms{label}");
            }
        }
        Err(e) => eprintln!("  no stage timings: {e}"),
    }
}

/// The scene file at `path` (or the default scene) with `--set` overrides applied.
pub(crate) fn load_scene_or_default(path: Option<&Path>, overrides: &[String]) -> Result<hfgi::scene::model::Scene> {
    match path {
        Some(p) => {
            hfgi::scene::file::load_scene(p, overrides).with_context(|| format!("loading scene {}", p.display()))
        }
        None => hfgi::scene::file::parse_scene("", Path::new("."), "default scene", overrides)
            .context("building the default scene"),
    }
}

/// The exposure to use (`--exposure`, else the scene camera's), checked before any work.
pub(crate) fn checked_exposure(flag: Option<f32>, scene: f32) -> Result<f32> {
    let e = flag.unwrap_or(scene);
    let m = hfgi::scene::model::limits::MAX_EXPOSURE_STOPS as f32;
    if !(e.is_finite() && e.abs() <= m) {
        let what = if flag.is_some() { "--exposure" } else { "camera.exposure" };
        bail!("{what} {e}: expected a finite number of stops in [-{m}, {m}]");
    }
    Ok(e)
}

/// Most frames `hfgi plan` lists.
const MAX_PLAN_FRAMES: u32 = 10_000;

fn plan(a: PlanArgs) -> Result<()> {
    if !(1..=MAX_PLAN_FRAMES).contains(&a.frames) {
        bail!("--frames {}: expected 1..={MAX_PLAN_FRAMES} frames (static frames repeat after two)", a.frames);
    }
    let scene = load_scene_or_default(a.scene.as_deref(), &a.overrides)?;
    scene.gi.validate().context("checking the [gi] settings")?;
    let memory = plan_memory(&scene, &a)?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let name = a.scene.as_ref().map_or("default scene".to_string(), |p| p.display().to_string());
    let animated = matches!(scene.animation, Animation::Water(_) | Animation::Bumps(_));
    let motion = if animated {
        format!(", animation {} (new heights every frame)", scene.animation.kind())
    } else if let Animation::Day(_) = scene.animation {
        // The day moves lights and camera through the live inputs, which this static plan does
        // not simulate (`hfgi animate` prints the stages each frame recorded).
        ", animation day (lights and camera move; heights static; planned here as static frames)".to_string()
    } else {
        String::new()
    };
    let mut text = format!(
        "scene {name}: {w}×{h}, gi.bounces = {}, gi.amortize = {}{motion}\n",
        scene.gi.bounces, scene.gi.amortize
    );
    text += &format!("resolved knobs: {}\n", scene.gi.describe());
    if a.stages {
        text += &hfgi::frame::stages::table_text();
    }
    let planner = hfgi::frame::Planner::new(&scene);
    for f in 0..u64::from(a.frames) {
        let p = planner.plan(&hfgi::frame::FrameState {
            heights_changed: f == 0 || animated,
            frame_index: f,
            ..Default::default()
        });
        if f == 0 {
            text += &p.passes_text();
        }
        text += &p.to_string();
    }
    text += &memory;
    write_stdout(&text)
}

/// `plan`'s memory section: the estimate without a device ([`hfgi::frame::memory`]), then —
/// unless `--no-device` — the checks `render` runs against the device, when one can be opened.
fn plan_memory(scene: &hfgi::scene::model::Scene, a: &PlanArgs) -> Result<String> {
    use hfgi::frame::memory;
    let renderer = memory::renderer(scene).context("estimating the renderer's GPU memory")?;
    let view = memory::view(scene, &hfgi::frame::view::ViewOptions::default())
        .context("estimating the view pass's GPU memory")?;
    let mib = |b: u64| b as f64 / 1048576.0;
    let mut text = format!(
        "GPU memory: {:.2} MiB = renderer {:.2} MiB + view ≤ {:.2} MiB (at most 8× MSAA; docs/plan.md)\n",
        mib(renderer.total() + view.total()),
        mib(renderer.total()),
        mib(view.total())
    );
    let planes = renderer.exported_planes();
    let rest = renderer.total() - planes;
    text += &format!(
        "  renderer = exported shading planes {:.2} MiB + inputs and intermediates {:.2} MiB ({:.2} MB: \
         what the paper's table 1 counts)\n",
        mib(planes),
        mib(rest),
        rest as f64 / 1e6
    );
    if a.buffers {
        let mut all = renderer.buffers.clone();
        all.sort_by(|x, y| y.1.cmp(&x.1).then_with(|| x.0.cmp(&y.0)));
        for (name, b) in &all {
            text += &format!("  {name:<32} {:>9.3} MiB\n", mib(*b));
        }
        for (name, owner) in &renderer.aliases {
            text += &format!("  {name:<32} {:>9} in {owner} (shared; docs/pyramid.md)\n", "—");
        }
    } else if let Some((name, b)) = renderer.largest() {
        text += &format!("  largest buffer: {name} {:.2} MiB\n", mib(*b));
    }
    if a.no_device {
        return Ok(text);
    }
    let opts = ContextOptions { validation: Some(false), device_filter: a.device.clone(), sync_validation: None };
    match Context::headless_with(&opts) {
        Ok(ctx) => {
            memory::check_device(scene, ctx.info())
                .with_context(|| format!("checking the scene against {}", ctx.info().name))?;
            let heap = mib(ctx.info().device_local_heap_bytes);
            text += &format!("device {}: fits (largest device-local heap {heap:.0} MiB)\n", ctx.info().name);
        }
        Err(e) if a.device.is_some() => return Err(anyhow::Error::new(e).context("opening --device")),
        Err(e) => text += &format!("no Vulkan device opened ({e}): memory not checked against a heap\n"),
    }
    Ok(text)
}

/// The median of `v` (sorted in place); NaN when empty.
pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn devices() -> Result<()> {
    let list = Context::list_devices().context("listing Vulkan devices")?;
    if list.is_empty() {
        bail!("no Vulkan 1.3 device found; install mesa-vulkan-drivers for lavapipe");
    }
    let mut text = String::new();
    for (name, kind) in &list {
        text += &format!("{name} ({kind:?})\n");
    }
    let ctx = Context::headless_with(&ContextOptions {
        validation: Some(false),
        device_filter: None,
        sync_validation: None,
    })?;
    let i = ctx.info();
    text += &format!(
        "chosen: {} — driver {}, Vulkan {}.{}.{}, maxImageDimension2D {}, timestamps: {}",
        i.name,
        i.driver,
        i.api_version.0,
        i.api_version.1,
        i.api_version.2,
        i.max_image_dimension_2d,
        if i.timestamp_valid_bits > 0 {
            format!("{} bits, {} ns/tick", i.timestamp_valid_bits, i.timestamp_period)
        } else {
            "none".into()
        }
    );
    write_stdout(&text)
}

/// Rejects output paths that cannot work (a directory, an input of the scene, the same file
/// twice, a folder that cannot be written) before any work; creates missing folders.
pub fn check_outputs(outputs: &[&Path], scene: Option<&Path>, overrides: &[String]) -> Result<()> {
    let inputs = hfgi::scene::file::input_files(scene, overrides);
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    hfgi::io::atomic::check_outputs(outputs, &inputs)?;
    Ok(())
}

fn spirv(out: &Path) -> Result<()> {
    let paths: Vec<PathBuf> = hfgi::shaders::ALL.iter().map(|s| out.join(format!("{}.spv", s.name))).collect();
    hfgi::io::atomic::check_outputs(&paths.iter().map(PathBuf::as_path).collect::<Vec<_>>(), &[])?;
    // Every module or none (docs/robustness.md).
    hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        for (s, path) in hfgi::shaders::ALL.iter().zip(&paths) {
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            }
            hfgi::io::atomic::write_bytes(path, bytemuck::cast_slice::<u32, u8>(s.words))?;
        }
        Ok(())
    })?;
    let list: String = paths.iter().map(|p| format!("{}\n", p.display())).collect();
    write_stdout(&list)
}

/// Writes `text` to standard output and flushes it: a failing write (a full disk, a closed
/// pipe) is an error and a non-zero exit, not ignored (docs/robustness.md, "Messages").
pub(crate) fn write_stdout(text: &str) -> Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes()).and_then(|()| out.flush()).context("writing to standard output")
}

/// The library's progress reports ([`hfgi::progress`]) as an indicatif bar on a terminal.
fn install_progress_bar() {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return;
    }
    let bar: std::sync::Mutex<Option<(String, indicatif::ProgressBar)>> = std::sync::Mutex::new(None);
    hfgi::progress::set_hook(Some(Box::new(move |p: &hfgi::progress::Progress| {
        let Ok(mut slot) = bar.lock() else { return };
        if !slot.as_ref().is_some_and(|(task, _)| task == p.task) {
            let b = indicatif::ProgressBar::new(p.total);
            if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} {bar:40} {pos}/{len} ({eta} left)") {
                b.set_style(style);
            }
            b.set_message(p.task.to_string());
            *slot = Some((p.task.to_string(), b));
        }
        if let Some((_, b)) = slot.as_ref() {
            b.set_position(p.done);
            if p.done >= p.total {
                b.finish_and_clear();
                *slot = None;
            }
        }
    })));
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    install_progress_bar();
    let result = match cli.command {
        Command::Render(a) => render(a),
        Command::Animate(a) => animate::animate(a),
        Command::Reference(a) => reference::reference(a),
        Command::Bench(a) => bench::bench(a),
        Command::Export(a) => export::export(a),
        Command::Plan(a) => plan(a),
        Command::Pyramid(a) => pyramid::pyramid(a),
        Command::Devices => devices(),
        Command::Spirv { out } => spirv(&out),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            // Every line kept short: no message echoes a 200 KB line back (docs/robustness.md).
            let mut text = format!("Error: {e}");
            let causes: Vec<String> = e.chain().skip(1).map(|c| c.to_string()).collect();
            if !causes.is_empty() {
                text += "\n\nCaused by:";
                for c in causes {
                    text += &format!("\n    {}", c.replace('\n', "\n    "));
                }
            }
            eprintln!("{}", hfgi::error::shorten_lines(&text, hfgi::error::LINE_MAX_CHARS));
            std::process::ExitCode::FAILURE
        }
    }
}
