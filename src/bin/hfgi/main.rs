//! `hfgi` — command-line front end of the hfgi library.

mod bench;
mod export;
mod plot;
mod reference;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use hfgi::frame::pyramid::{HeightPyramid, PyramidMode};
use hfgi::frame::view::{ViewOptions, ViewPass};
use hfgi::frame::water::WaterSim;
use hfgi::frame::Renderer;
use hfgi::scene::animated::{Animation, MovingBumps};
use hfgi::scene::generators::Generator;
use hfgi::scene::load::{load_heightfield, LoadOptions};
use hfgi::scene::HeightField;
use hfgi::vk::{Context, ContextOptions, Recorder, StageTimer};

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
    Animate(AnimateArgs),
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
    /// key lights, bounces). The Mitsuba 3 peer check (tools/mitsuba_check.py) reads it.
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
    Pyramid(PyramidArgs),
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
struct RenderArgs {
    /// Scene file (TOML, docs/scene-format.md). Without it, the default scene.
    scene: Option<PathBuf>,
    /// Override a scene setting, e.g. `--set gi.azimuths=64 --set material.albedo=[0.5,0.5,0.5]`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// View image from the scene camera (PNG, tone-mapped with the exposure).
    #[arg(long, default_value = "out/render.png")]
    out: PathBuf,
    /// Also write the view image as linear float32 RGB (EXR, default layer).
    #[arg(long, value_name = "FILE")]
    view_exr: Option<PathBuf>,
    /// Also write the shading texture as a layered float32 EXR.
    #[arg(long, value_name = "FILE")]
    shading_exr: Option<PathBuf>,
    /// Also write the shading texture's total, tone-mapped, as a top-down PNG (one pixel per texel).
    #[arg(long, value_name = "FILE")]
    shading_png: Option<PathBuf>,
    /// Also write the indirect light of the shading texture (diffuse + glossy indirect, all
    /// bounces) as a tone-mapped PNG seen from above.
    #[arg(long, value_name = "FILE")]
    indirect_png: Option<PathBuf>,
    /// Also write the height field as a grey PNG (black = lowest, white = highest).
    #[arg(long, value_name = "FILE")]
    heights_png: Option<PathBuf>,
    /// Exposure in stops for the PNG (default: the scene camera's), e.g. `--exposure=-1.5`.
    #[arg(long, allow_hyphen_values = true)]
    exposure: Option<f32>,
    #[command(flatten)]
    device: DeviceArgs,
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
}

#[derive(Args)]
struct AnimateArgs {
    /// Scene file (TOML) with an [animation] table (docs/scene-format.md).
    scene: PathBuf,
    /// Number of frames to render (≥ 1).
    #[arg(long)]
    frames: u32,
    /// Output folder for frame_0000.png, frame_0001.png, … (created if missing).
    #[arg(long, default_value = "out/animate")]
    out: PathBuf,
    /// Override a scene setting, e.g. `--set animation.kind=water --set animation.rain_rate=1`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Also write the frames as an animated GIF (looping).
    #[arg(long, value_name = "FILE")]
    gif: Option<PathBuf>,
    /// Frame rate of the GIF, in (0, 100].
    #[arg(long, default_value_t = 25.0)]
    fps: f64,
    /// Exposure in stops for the frames (default: the scene camera's).
    #[arg(long, allow_hyphen_values = true)]
    exposure: Option<f32>,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Args)]
struct PyramidArgs {
    /// Output folder (created if missing).
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Height field file: .png (8/16-bit grey), .exr (Y, R or height channel), .raw/.f32 (needs --raw-size).
    #[arg(long, conflicts_with = "generator")]
    heights: Option<PathBuf>,
    /// Procedural height field: fbm, sines, cones, cliff, craters, city, optionally with
    /// parameters, e.g. `fbm:seed=7,octaves=6`.
    #[arg(long, default_value = "fbm")]
    generator: String,
    /// Size of a generated field, `N` or `WxH`.
    #[arg(long, default_value = "256")]
    size: String,
    /// Size of a .raw/.f32 file, `WxH`.
    #[arg(long)]
    raw_size: Option<String>,
    /// Multiplies every height read from a file.
    #[arg(long, default_value_t = 1.0)]
    height_scale: f32,
    /// Pyramid level step k_v (levels per halving of resolution, ≥ 1).
    #[arg(long, default_value_t = 4)]
    level_step: u32,
    /// Pyramid storage: `stack` (paper) or `pyramid` (B-spline on the fly).
    #[arg(long, default_value = "stack")]
    pyramid: String,
    /// Treat the field as periodic.
    #[arg(long)]
    wrap: bool,
    #[command(flatten)]
    device: DeviceArgs,
}

fn parse_size(s: &str, what: &str) -> Result<(usize, usize)> {
    let parse = |t: &str| t.trim().parse::<usize>().with_context(|| format!("{what} {s:?}: expected N or WxH"));
    match s.split_once(['x', 'X', '×']) {
        Some((w, h)) => Ok((parse(w)?, parse(h)?)),
        None => {
            let n = parse(s)?;
            Ok((n, n))
        }
    }
}

pub(crate) fn context(d: &DeviceArgs) -> Result<Context> {
    let opts = ContextOptions { validation: d.validation.then_some(true), device_filter: d.device.clone() };
    Context::headless_with(&opts).context("creating the Vulkan context")
}

fn print_timings(ctx: &Context, timer: &StageTimer) {
    match timer.timings(ctx) {
        Ok(t) => {
            let lavapipe = ctx.info().kind == ash::vk::PhysicalDeviceType::CPU;
            let label = if lavapipe { " (lavapipe: CPU time, not a GPU time)" } else { "" };
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

fn render(a: RenderArgs) -> Result<()> {
    let scene = load_scene_or_default(a.scene.as_deref(), &a.overrides)?;
    let outputs: Vec<&Path> = std::iter::once(&a.out)
        .chain([&a.view_exr, &a.shading_exr, &a.shading_png, &a.indirect_png, &a.heights_png].into_iter().flatten())
        .map(PathBuf::as_path)
        .collect();
    check_outputs(&outputs, a.scene.as_deref(), &a.overrides)?;
    let ctx = context(&a.device)?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let max = ctx.info().max_image_dimension_2d as usize;
    if w > max || h > max {
        bail!("height field {w}×{h} exceeds this device's maxImageDimension2D {max}");
    }
    let gi = &scene.gi;
    eprintln!(
        "device: {} ({}); field {w}×{h}; n={} m={} k_v={} o_v={} subsample={} {} {}",
        ctx.info().name,
        ctx.info().driver,
        gi.sh_order,
        gi.azimuths,
        gi.level_step,
        gi.level_offset,
        gi.subsample,
        gi.interpolation,
        gi.pyramid
    );
    let mut renderer = Renderer::new(&ctx, &scene).context("creating the renderer")?;
    let view = match ViewPass::for_renderer(&ctx, &scene, &renderer, &ViewOptions::default()) {
        Ok(v) => v,
        Err(e) => {
            renderer.destroy(&ctx);
            return Err(anyhow::Error::new(e).context("creating the view pass"));
        }
    };
    let (vw, vh) = view.size();
    eprintln!("view: {vw}×{vh}, {}× MSAA, {:?}", view.samples(), view.color_format());
    let mut timer = StageTimer::new(&ctx, 32 + 5 * scene.gi.bounces)?;
    let run = ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, Some(&mut timer));
        renderer.record(&mut rec);
        // The view pass records its own compute → vertex/fragment barrier first.
        view.record(&mut rec);
        Ok(())
    });
    let read = run.and_then(|_| Ok((renderer.read_layers(&ctx)?, view.read_hdr(&ctx)?)));
    print_timings(&ctx, &timer);
    eprintln!("  GPU memory: {:.2} MiB", (renderer.memory_bytes() + view.memory_bytes()) as f64 / 1048576.0);
    view.destroy(&ctx);
    renderer.destroy(&ctx);
    timer.destroy(&ctx);
    let (layers, image) = read?;
    ctx.check_validation()?;
    let exposure = a.exposure.unwrap_or(scene.camera.exposure);
    let (vw, vh) = (vw as usize, vh as usize);
    // Every output or none (docs/robustness.md).
    let mut wrote = Vec::new();
    hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        hfgi::io::png::write_tonemapped(&a.out, vw, vh, &image, exposure)?;
        wrote.push(a.out.display().to_string());
        if let Some(path) = &a.view_exr {
            hfgi::io::exr::write_rgb_layers(path, vw, vh, &[("", &image)])?;
            wrote.push(path.display().to_string());
        }
        if let Some(path) = &a.shading_png {
            hfgi::io::png::write_tonemapped(path, w, h, &layers.total, exposure)?;
            wrote.push(path.display().to_string());
        }
        if let Some(path) = &a.indirect_png {
            let ind: Vec<[f32; 3]> = layers
                .indirect
                .iter()
                .zip(&layers.indirect_glossy)
                .map(|(d, g)| [d[0] + g[0], d[1] + g[1], d[2] + g[2]])
                .collect();
            hfgi::io::png::write_tonemapped(path, w, h, &ind, exposure)?;
            wrote.push(path.display().to_string());
        }
        if let Some(path) = &a.heights_png {
            hfgi::io::png::write_gray_normalized(path, w, h, scene.field.data())?;
            wrote.push(path.display().to_string());
        }
        if let Some(path) = &a.shading_exr {
            hfgi::io::exr::write_rgb_layers(
                path,
                w,
                h,
                &[
                    ("", &layers.total),
                    ("direct", &layers.direct),
                    ("indirect", &layers.indirect),
                    ("glossy", &layers.glossy),
                ],
            )?;
            wrote.push(path.display().to_string());
        }
        Ok(())
    })?;
    for p in wrote {
        eprintln!("wrote {p}");
    }
    Ok(())
}

fn plan(a: PlanArgs) -> Result<()> {
    if a.frames == 0 {
        bail!("--frames 0: expected at least 1 frame");
    }
    let scene = load_scene_or_default(a.scene.as_deref(), &a.overrides)?;
    scene.gi.validate().context("checking the [gi] settings")?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let name = a.scene.as_ref().map_or("default scene".to_string(), |p| p.display().to_string());
    let animated = scene.animation != Animation::None;
    let motion = if animated {
        format!(", animation {} (new heights every frame)", scene.animation.kind())
    } else {
        String::new()
    };
    println!("scene {name}: {w}×{h}, gi.bounces = {}, gi.amortize = {}{motion}", scene.gi.bounces, scene.gi.amortize);
    println!("resolved knobs: {}", scene.gi.describe());
    let planner = hfgi::frame::Planner::new(&scene);
    for f in 0..u64::from(a.frames) {
        let p = planner.plan(&hfgi::frame::FrameState { heights_changed: f == 0 || animated, frame_index: f });
        if f == 0 {
            print!("{}", p.passes_text());
        }
        print!("{p}");
    }
    Ok(())
}

/// The picture of the current frame: `(width, height, linear RGB)`, the rasterised view image.
fn frame_rgb(ctx: &Context, view: &ViewPass) -> hfgi::Result<(usize, usize, Vec<[f32; 3]>)> {
    let (w, h) = view.size();
    Ok((w as usize, h as usize, view.read_hdr(ctx)?))
}

/// What advances the heights between frames.
enum Driver {
    Water(Box<WaterSim>),
    Bumps(MovingBumps),
}

fn median(v: &mut [f64]) -> f64 {
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

fn animate(a: AnimateArgs) -> Result<()> {
    if a.frames == 0 {
        bail!("--frames 0: expected at least 1 frame");
    }
    if !(a.fps.is_finite() && a.fps > 0.0 && a.fps <= 100.0) {
        bail!("--fps {}: expected a number in (0, 100]", a.fps);
    }
    let scene = hfgi::scene::file::load_scene(&a.scene, &a.overrides)
        .with_context(|| format!("loading scene {}", a.scene.display()))?;
    let first = a.out.join("frame_0000.png");
    check_outputs(
        &std::iter::once(&first).chain(&a.gif).map(PathBuf::as_path).collect::<Vec<_>>(),
        Some(&a.scene),
        &a.overrides,
    )?;
    if scene.animation == Animation::None {
        bail!(
            "{}: the scene does not move ([animation] kind = \"none\"); add an [animation] table \
             (docs/scene-format.md) or e.g. --set animation.kind=water",
            a.scene.display()
        );
    }
    let exposure = a.exposure.unwrap_or(scene.camera.exposure);
    if !exposure.is_finite() {
        bail!("--exposure {exposure}: expected a finite number of stops");
    }
    let ctx = context(&a.device)?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let max = ctx.info().max_image_dimension_2d as usize;
    if w > max || h > max {
        bail!("height field {w}×{h} exceeds this device's maxImageDimension2D {max}");
    }
    eprintln!(
        "device: {} ({}); field {w}×{h}; animation {}; {} frames",
        ctx.info().name,
        ctx.info().driver,
        scene.animation.kind(),
        a.frames
    );
    let mut renderer = Renderer::new(&ctx, &scene).context("creating the renderer")?;
    let driver = match &scene.animation {
        Animation::Water(p) => {
            // The scene's heights are the initial surface: z = (height − rest_level) / scale.
            let initial: Vec<f32> =
                scene.field.data().iter().map(|&v| ((f64::from(v) - p.rest_level) / p.scale) as f32).collect();
            WaterSim::new(&ctx, w, h, p.clone(), &initial).map(|s| Driver::Water(Box::new(s)))
        }
        Animation::Bumps(p) => {
            MovingBumps::new(p.clone(), scene.field.clone(), scene.texel_size, scene.wrap).map(Driver::Bumps)
        }
        Animation::None => Err(hfgi::Error::param("animation.kind", "\"none\"", "\"water\" or \"bumps\"")),
    };
    let mut driver = match driver {
        Ok(d) => d,
        Err(e) => {
            renderer.destroy(&ctx);
            return Err(e).context("creating the animation");
        }
    };
    let steps = match &driver {
        Driver::Water(sim) => sim.params().steps_per_frame,
        Driver::Bumps(_) => 0,
    };
    // Near/far planes: the first frame's range, widened for water by the waves a drop can
    // raise (4 × the drop amplitude, in world units); bumps update it every frame.
    let (lo, hi) = scene.field.range();
    let margin = match &scene.animation {
        Animation::Water(p) => (4.0 * p.rain.amplitude.abs().max(1.0) * p.scale.abs()) as f32,
        _ => 0.0,
    };
    let mut view = match ViewPass::for_renderer(&ctx, &scene, &renderer, &ViewOptions::default())
        .and_then(|mut v| v.set_height_range(lo - margin, hi + margin).map(|_| v))
    {
        Ok(v) => v,
        Err(e) => {
            if let Driver::Water(sim) = driver {
                sim.destroy(&ctx);
            }
            renderer.destroy(&ctx);
            return Err(anyhow::Error::new(e).context("creating the view pass"));
        }
    };
    let mut timer = match StageTimer::new(&ctx, steps + 32 + 5 * scene.gi.bounces) {
        Ok(t) => t,
        Err(e) => {
            if let Driver::Water(sim) = driver {
                sim.destroy(&ctx);
            }
            renderer.destroy(&ctx);
            return Err(e.into());
        }
    };

    let pipelines_before = ctx.pipelines_created();
    let bar = indicatif::ProgressBar::new(u64::from(a.frames));
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} {wide_bar} {pos}/{len} frames [{elapsed} < {eta}]")
    {
        bar.set_style(style);
    }
    bar.set_message("animate");
    let mut stage_ms: Vec<(String, Vec<f64>)> = Vec::new();
    let mut timing_note = None;
    let mut gif_frames = Vec::new();
    let run = (|| -> Result<()> {
        for f in 0..a.frames {
            if let Driver::Bumps(b) = &driver {
                let field = b.heights_at(u64::from(f))?;
                renderer.update_heights(&ctx, &field)?;
                let (lo, hi) = field.range();
                view.set_height_range(lo, hi)?;
            }
            ctx.submit_and_wait(|cmd| {
                let mut rec = Recorder::new(&ctx, cmd, Some(&mut timer));
                if let Driver::Water(sim) = &mut driver {
                    for _ in 0..steps {
                        sim.record_step(&mut rec, renderer.heights_buffer())?;
                    }
                    renderer.mark_heights_changed();
                }
                renderer.record(&mut rec);
                view.record(&mut rec);
                Ok(())
            })?;
            match timer.timings(&ctx) {
                Ok(t) => {
                    // Sum the scopes of one stage within the frame (several water steps).
                    let mut frame: Vec<(String, f64)> = Vec::new();
                    for (name, ms) in t {
                        match frame.iter_mut().find(|(n, _)| *n == name) {
                            Some((_, acc)) => *acc += ms,
                            None => frame.push((name, ms)),
                        }
                    }
                    for (name, ms) in frame {
                        match stage_ms.iter_mut().find(|(n, _)| *n == name) {
                            Some((_, v)) => v.push(ms),
                            None => stage_ms.push((name, vec![ms])),
                        }
                    }
                }
                Err(e) => timing_note = Some(e.to_string()),
            }
            let (fw, fh, rgb) = frame_rgb(&ctx, &view)?;
            let path = a.out.join(format!("frame_{f:04}.png"));
            hfgi::io::png::write_tonemapped(&path, fw, fh, &rgb, exposure)?;
            if a.gif.is_some() {
                gif_frames.push((fw, fh, hfgi::io::gif::tonemap_rgba8(&rgb, exposure)?));
            }
            bar.inc(1);
        }
        Ok(())
    })();
    bar.finish_and_clear();
    let pipelines_after = ctx.pipelines_created();
    let stats = renderer.stats();
    let memory = renderer.memory_bytes() + view.memory_bytes();
    if let Driver::Water(sim) = driver {
        sim.destroy(&ctx);
    }
    view.destroy(&ctx);
    renderer.destroy(&ctx);
    timer.destroy(&ctx);
    run?;
    ctx.check_validation()?;
    eprintln!("wrote {}/frame_0000.png … frame_{:04}.png ({} frames)", a.out.display(), a.frames - 1, a.frames);
    if let (Some(path), Some((fw, fh, _))) = (&a.gif, gif_frames.first()) {
        let (fw, fh) = (*fw, *fh);
        let frames: Vec<Vec<u8>> = gif_frames.into_iter().map(|(_, _, f)| f).collect();
        hfgi::io::gif::write_gif(path, fw, fh, &frames, a.fps)?;
        eprintln!("wrote {} ({} fps)", path.display(), a.fps);
    }
    eprintln!("frames: {}", a.frames);
    eprintln!("renderer stats: frames {}, pyramid_builds {}", stats.frames, stats.pyramid_builds);
    eprintln!("pipelines created: {pipelines_before} before the loop, {pipelines_after} after");
    eprintln!("GPU memory (renderer + view): {:.2} MiB", memory as f64 / 1048576.0);
    let lavapipe = ctx.info().kind == ash::vk::PhysicalDeviceType::CPU;
    let label = if lavapipe { " (lavapipe: CPU time, not a GPU time)" } else { "" };
    match timing_note {
        Some(note) if stage_ms.is_empty() => eprintln!("no stage timings: {note}"),
        _ => {
            eprintln!("median per-stage time over {} frames, {} ({}):", a.frames, ctx.info().name, ctx.info().driver);
            for (stage, mut v) in stage_ms {
                eprintln!("  {stage:<24} {:9.3} ms{label} ({} frames)", median(&mut v), v.len());
            }
        }
    }
    if pipelines_after != pipelines_before {
        bail!("pipelines were created during the frame loop ({pipelines_before} → {pipelines_after})");
    }
    Ok(())
}

fn load_field(a: &PyramidArgs, max_dim: u32) -> Result<HeightField> {
    if let Some(path) = &a.heights {
        let raw_size = a.raw_size.as_deref().map(|s| parse_size(s, "--raw-size")).transpose()?;
        let opts = LoadOptions { height_scale: a.height_scale, raw_size, max_dim, ..LoadOptions::default() };
        return load_heightfield(path, &opts).with_context(|| format!("loading height field {}", path.display()));
    }
    let (w, h) = parse_size(&a.size, "--size")?;
    let gen: Generator = a.generator.parse().with_context(|| format!("--generator {:?}", a.generator))?;
    gen.generate(w, h).with_context(|| format!("generating {}×{} field with {:?}", w, h, a.generator))
}

fn pyramid(a: PyramidArgs) -> Result<()> {
    let mode: PyramidMode = a.pyramid.parse().context("--pyramid")?;
    let [heights_png, heights_exr, pyramid_exr, pyramid_png] =
        ["heights.png", "heights.exr", "pyramid.exr", "pyramid.png"].map(|n| a.out.join(n));
    let inputs: Vec<&Path> = a.heights.iter().map(PathBuf::as_path).collect();
    hfgi::io::atomic::check_outputs(
        &[&heights_png, &heights_exr, &pyramid_exr, &pyramid_png].map(PathBuf::as_path),
        &inputs,
    )?;
    let ctx = context(&a.device)?;
    let field = load_field(&a, ctx.info().max_image_dimension_2d)?;
    let (w, h) = (field.width(), field.height());
    eprintln!("device: {} ({}), field {w}×{h}, k_v = {}, {mode}", ctx.info().name, ctx.info().driver, a.level_step);

    let pyr =
        HeightPyramid::new(&ctx, w, h, (w, h), a.level_step, mode, a.wrap).context("creating the height pyramid")?;
    pyr.upload(&ctx, &field)?;
    let mut timer = StageTimer::new(&ctx, 32)?;
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, Some(&mut timer));
        pyr.record(&mut rec);
        Ok(())
    })?;
    print_timings(&ctx, &timer);
    eprintln!("  pyramid memory: {:.2} MiB ({} levels)", pyr.memory_bytes() as f64 / 1048576.0, pyr.layout().count());

    // The four files together or none (docs/robustness.md).
    let written = hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        hfgi::io::png::write_gray_normalized(&heights_png, w, h, field.data())?;
        hfgi::io::exr::write_scalar(&heights_exr, w, h, "height", field.data())?;

        // Levels, each B-spline resampled to full resolution (the stack, or the same filter on the fly).
        let count = pyr.layout().count();
        let mut planes = Vec::with_capacity(count);
        for i in 0..count {
            let plane = match mode {
                PyramidMode::Stack => pyr.read_stack(&ctx, i)?,
                PyramidMode::Pyramid => {
                    let q: Vec<[f32; 3]> = (0..w * h).map(|k| [i as f32, (k % w) as f32, (k / w) as f32]).collect();
                    pyr.probe(&ctx, &q)?
                }
            };
            planes.push(plane);
        }
        let names: Vec<String> = (0..count).map(|i| format!("level_{i:02}")).collect();
        let layers: Vec<hfgi::io::exr::Layer> = planes
            .iter()
            .zip(&names)
            .map(|(p, n)| hfgi::io::exr::Layer { name: n.as_str(), channels: vec![("height", p.as_slice())] })
            .collect();
        hfgi::io::exr::write_layers(&pyramid_exr, w, h, &layers)?;
        let sheet = contact_sheet(&planes, w, h, field.range());
        hfgi::io::png::write_tonemapped(&pyramid_png, sheet.1, sheet.2, &sheet.0, 0.0)?;
        Ok(())
    });
    pyr.destroy(&ctx);
    timer.destroy(&ctx);
    written?;
    ctx.check_validation()?;
    eprintln!("wrote {}/{{heights.png, heights.exr, pyramid.png, pyramid.exr}}", a.out.display());
    Ok(())
}

/// Every k-th level side by side (4 per row), grey-scaled by the field's range.
fn contact_sheet(planes: &[Vec<f32>], w: usize, h: usize, range: (f32, f32)) -> (Vec<[f32; 3]>, usize, usize) {
    let step = (planes.len() / 8).max(1);
    let picks: Vec<&Vec<f32>> = planes.iter().step_by(step).take(8).collect();
    let cols = picks.len().min(4);
    let rows = picks.len().div_ceil(cols);
    let (sw, sh) = (cols * (w + 4), rows * (h + 4));
    let mut img = vec![[0.0f32; 3]; sw * sh];
    let span = (range.1 - range.0).max(f32::MIN_POSITIVE);
    for (n, p) in picks.iter().enumerate() {
        let (ox, oy) = ((n % cols) * (w + 4) + 2, (n / cols) * (h + 4) + 2);
        for y in 0..h {
            for x in 0..w {
                // Linear value whose sRGB encoding is proportional to the height.
                let g = ((p[y * w + x] - range.0) / span).clamp(0.0, 1.0);
                let lin = if g <= 0.04045 { g / 12.92 } else { ((g + 0.055) / 1.055).powf(2.4) };
                img[(oy + y) * sw + ox + x] = [lin; 3];
            }
        }
    }
    (img, sw, sh)
}

fn devices() -> Result<()> {
    let list = Context::list_devices().context("listing Vulkan devices")?;
    if list.is_empty() {
        bail!("no Vulkan 1.3 device found; install mesa-vulkan-drivers for lavapipe");
    }
    for (name, kind) in &list {
        println!("{name} ({kind:?})");
    }
    let ctx = Context::headless_with(&ContextOptions { validation: Some(false), device_filter: None })?;
    let i = ctx.info();
    println!(
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
    Ok(())
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
    for s in hfgi::shaders::ALL {
        let path = out.join(format!("{}.spv", s.name));
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        hfgi::io::atomic::write_bytes(&path, bytemuck::cast_slice::<u32, u8>(s.words))?;
        println!("{}", path.display());
    }
    Ok(())
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Render(a) => render(a),
        Command::Animate(a) => animate(a),
        Command::Reference(a) => reference::reference(a),
        Command::Bench(a) => bench::bench(a),
        Command::Export(a) => export::export(a),
        Command::Plan(a) => plan(a),
        Command::Pyramid(a) => pyramid(a),
        Command::Devices => devices(),
        Command::Spirv { out } => spirv(&out),
    }
}
