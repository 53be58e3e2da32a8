//! `hfgi animate`: one renderer (and one water simulation or moving bumps), then per frame
//! advance the animation, record the frame, write `frame_NNNN.png` and, optionally, a GIF
//! streamed frame by frame; frames and GIF are committed together (docs/dynamic.md,
//! docs/robustness.md).

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use hfgi::frame::view::{ViewOptions, ViewPass};
use hfgi::frame::water::WaterSim;
use hfgi::frame::Renderer;
use hfgi::io::gif::GifStream;
use hfgi::scene::animated::{Animation, MovingBumps};
use hfgi::scene::boulders::Boulders;
use hfgi::scene::day::DayCycle;
use hfgi::scene::model::Scene;
use hfgi::vk::{Context, Recorder, StageTimer};

use super::{check_outputs, checked_exposure, context, median, DeviceArgs};

#[derive(Args)]
pub struct AnimateArgs {
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

/// Most frames `hfgi animate` renders in one run.
const MAX_FRAMES: u32 = 100_000;
/// Most bytes of frames (PNG at ≤ 3 bytes per pixel, GIF at ≤ 1) `hfgi animate` writes.
const MAX_ANIMATION_BYTES: f64 = 64.0 * 1024.0 * 1024.0 * 1024.0;

/// Bounds `animate`'s work before any is done (docs/robustness.md, "Bounded inputs and work"):
/// the frame count, and the bytes the frames would take on disk.
fn check_animation_work(frames: u32, camera: (u32, u32), gif: bool) -> Result<()> {
    if frames == 0 {
        bail!("--frames 0: expected at least 1 frame");
    }
    if frames > MAX_FRAMES {
        bail!(
            "--frames {frames}: expected at most {MAX_FRAMES} frames in one run (each frame is a full render \
             and a PNG; render longer animations in several runs)"
        );
    }
    let per_pixel = if gif { 4.0 } else { 3.0 };
    let bytes = f64::from(frames) * f64::from(camera.0) * f64::from(camera.1) * per_pixel;
    if bytes > MAX_ANIMATION_BYTES {
        bail!(
            "--frames {frames} at {}×{} pixels could write up to {:.1} GiB of frames{}; the limit is {:.0} GiB: \
             use fewer frames or a smaller camera.width/camera.height",
            camera.0,
            camera.1,
            bytes / 1073741824.0,
            if gif { " and GIF" } else { "" },
            MAX_ANIMATION_BYTES / 1073741824.0
        );
    }
    Ok(())
}

/// What advances the heights between frames.
enum Driver {
    Water(Box<WaterSim>),
    Bumps(MovingBumps),
    /// The sun, sky and camera move through the renderer's live inputs; the heights stay.
    Day(DayCycle),
    /// The spheres roll through the renderer's live inputs; the heights stay.
    Boulders(Boulders),
}

/// The GPU objects of an animation, destroyed together ([`Passes::destroy`]).
struct Passes {
    renderer: Renderer,
    driver: Option<Driver>,
    view: Option<ViewPass>,
    timer: Option<StageTimer>,
}

impl Passes {
    fn destroy(self, ctx: &Context) {
        if let Some(Driver::Water(sim)) = self.driver {
            sim.destroy(ctx);
        }
        if let Some(v) = self.view {
            v.destroy(ctx);
        }
        if let Some(mut t) = self.timer {
            t.destroy(ctx);
        }
        self.renderer.destroy(ctx);
    }

    /// Creates the driver, the view pass and the timer after the renderer; on failure what was
    /// created is destroyed.
    fn create(ctx: &Context, scene: &Scene) -> Result<Passes> {
        let renderer = Renderer::new(ctx, scene).context("creating the renderer")?;
        let mut p = Passes { renderer, driver: None, view: None, timer: None };
        match p.complete(ctx, scene) {
            Ok(()) => Ok(p),
            Err(e) => {
                p.destroy(ctx);
                Err(e)
            }
        }
    }

    fn complete(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let (w, h) = (scene.field.width(), scene.field.height());
        let driver = match &scene.animation {
            Animation::Water(p) => {
                // The scene's heights are the initial surface: z = (height − rest_level) / scale.
                let initial: Vec<f32> =
                    scene.field.data().iter().map(|&v| ((f64::from(v) - p.rest_level) / p.scale) as f32).collect();
                Driver::Water(Box::new(WaterSim::new(ctx, w, h, p.clone(), &initial).context("creating the water")?))
            }
            Animation::Bumps(p) => Driver::Bumps(
                MovingBumps::new(p.clone(), scene.field.clone(), scene.texel_size, scene.wrap)
                    .context("creating the bumps")?,
            ),
            Animation::Day(p) => Driver::Day(DayCycle::new(p.clone(), scene).context("creating the day")?),
            Animation::Boulders(p) => {
                Driver::Boulders(Boulders::new(p.clone(), scene).context("creating the boulders")?)
            }
            Animation::None => {
                bail!("animation.kind = \"none\": expected \"water\", \"bumps\", \"day\" or \"boulders\"")
            }
        };
        let steps = self.steps_of(&driver);
        self.driver = Some(driver);
        // Near/far planes: the first frame's range, widened for water by the waves a drop can
        // raise (4 × the drop amplitude, in world units); bumps update it every frame.
        let (lo, hi) = scene.field.range();
        let margin = match &scene.animation {
            Animation::Water(p) => (4.0 * p.rain.amplitude.abs().max(1.0) * p.scale.abs()) as f32,
            _ => 0.0,
        };
        let mut view = ViewPass::for_renderer(ctx, scene, &self.renderer, &ViewOptions::default())
            .context("creating the view pass")?;
        let ranged = view.set_height_range(lo - margin, hi + margin);
        self.view = Some(view);
        ranged?;
        self.timer = Some(StageTimer::new(ctx, steps + 32 + 5 * scene.gi.bounces)?);
        Ok(())
    }

    fn steps_of(&self, driver: &Driver) -> u32 {
        match driver {
            Driver::Water(sim) => sim.params().steps_per_frame,
            Driver::Bumps(_) | Driver::Day(_) | Driver::Boulders(_) => 0,
        }
    }
}

/// The wall-clock time of each frame's GI submit, listed with the stages.
const GI_WALL: &str = "frame (GI submit, wall)";

/// Per-stage times of every frame, and why there are none (a device without timestamps).
#[derive(Default)]
struct Timings {
    stage_ms: Vec<(String, Vec<f64>)>,
    note: Option<String>,
}

impl Timings {
    /// Sums the scopes of one stage within a frame (several water steps) and appends the
    /// frame's time per stage.
    fn add_frame(&mut self, t: Vec<(String, f64)>) {
        let mut frame: Vec<(String, f64)> = Vec::new();
        for (name, ms) in t {
            match frame.iter_mut().find(|(n, _)| *n == name) {
                Some((_, acc)) => *acc += ms,
                None => frame.push((name, ms)),
            }
        }
        for (name, ms) in frame {
            match self.stage_ms.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push(ms),
                None => self.stage_ms.push((name, vec![ms])),
            }
        }
    }

    fn print(self, ctx: &Context, frames: u32) {
        let lavapipe = ctx.info().kind == ash::vk::PhysicalDeviceType::CPU;
        let label = if lavapipe { " (lavapipe: CPU time, not a GPU time)" } else { "" };
        match self.note {
            Some(note) if self.stage_ms.is_empty() => eprintln!("no stage timings: {note}"),
            _ => {
                eprintln!("median per-stage time over {frames} frames, {} ({}):", ctx.info().name, ctx.info().driver);
                for (stage, mut v) in self.stage_ms {
                    eprintln!("  {stage:<24} {:9.3} ms{label} ({} frames)", median(&mut v), v.len());
                }
                if lavapipe {
                    eprintln!(
                        "  (lavapipe: compute timestamps after the first draw read near zero, docs/performance.md §3; \
                         `{GI_WALL}` is the reliable figure)"
                    );
                }
            }
        }
    }
}

/// Records frame `f` (advancing the animation first) and waits for it; returns the wall-clock
/// milliseconds of the GI submit (without the view).
fn record_frame(ctx: &Context, p: &mut Passes, f: u32) -> Result<f64> {
    let (Some(driver), Some(view), Some(timer)) = (p.driver.as_mut(), p.view.as_mut(), p.timer.as_mut()) else {
        bail!("the animation's passes are incomplete");
    };
    match driver {
        Driver::Bumps(b) => {
            let field = b.heights_at(u64::from(f))?;
            p.renderer.update_heights(ctx, &field)?;
            let (lo, hi) = field.range();
            view.set_height_range(lo, hi)?;
        }
        Driver::Day(day) => {
            // Live inputs: recorded by the next `record` (no submit, no new pipeline).
            let frame = day.frame(u64::from(f), &p.renderer.live_scene().key_lights);
            p.renderer.set_key_lights(&frame.key_lights)?;
            p.renderer.set_environment(&frame.environment)?;
            p.renderer.set_camera(&frame.camera)?;
            view.set_camera(&frame.camera)?;
        }
        Driver::Boulders(b) => {
            let spheres = b.frame(u64::from(f));
            p.renderer.set_spheres(&spheres)?;
            view.set_spheres(ctx, &spheres)?;
        }
        Driver::Water(_) => {}
    }
    let renderer = &mut p.renderer;
    let start = std::time::Instant::now();
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, Some(timer));
        if let Driver::Water(sim) = driver {
            for _ in 0..sim.params().steps_per_frame {
                sim.record_step(&mut rec, renderer.heights_buffer())?;
            }
            renderer.mark_heights_changed();
        }
        renderer.record(&mut rec);
        Ok(())
    })?;
    let gi_ms = start.elapsed().as_secs_f64() * 1e3;
    // The view in its own submit: on lavapipe the compute timestamps after a draw in the same
    // command buffer read near zero (docs/performance.md §3), so the GI stages are timed alone.
    ctx.submit_and_wait(|cmd| {
        view.record(&mut Recorder::new(ctx, cmd, None));
        Ok(())
    })?;
    Ok(gi_ms)
}

/// Renders every frame and writes it. Frames and GIF are committed together at the end, or not
/// at all; the GIF is streamed to its temporary file frame by frame, so memory holds one frame
/// (docs/robustness.md).
fn render_frames(ctx: &Context, a: &AnimateArgs, p: &mut Passes, exposure: f32, timings: &mut Timings) -> Result<()> {
    let bar = indicatif::ProgressBar::new(u64::from(a.frames));
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} {wide_bar} {pos}/{len} frames [{elapsed} < {eta}]")
    {
        bar.set_style(style);
    }
    bar.set_message("animate");
    let mut gif: Option<GifStream> = None;
    let run = hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        for f in 0..a.frames {
            let gi_ms = record_frame(ctx, p, f)?;
            if let Some(timer) = &p.timer {
                match timer.timings(ctx) {
                    Ok(t) => timings.add_frame(t),
                    Err(e) => timings.note = Some(e.to_string()),
                }
            }
            timings.add_frame(vec![(GI_WALL.to_string(), gi_ms)]);
            let view = p.view.as_ref().context("the view pass")?;
            let (fw, fh) = view.size();
            let (fw, fh) = (fw as usize, fh as usize);
            let rgb = view.read_hdr(ctx)?;
            hfgi::io::png::write_tonemapped(&a.out.join(format!("frame_{f:04}.png")), fw, fh, &rgb, exposure)?;
            if let Some(path) = &a.gif {
                let stream = match gif.as_mut() {
                    Some(g) => g,
                    None => gif.insert(GifStream::create(path, fw, fh, a.fps)?),
                };
                stream.push(&hfgi::io::gif::tonemap_rgba8(&rgb, exposure)?)?;
            }
            bar.inc(1);
        }
        if let Some(g) = gif.take() {
            g.finish()?;
        }
        Ok(())
    });
    bar.finish_and_clear();
    run
}

pub fn animate(a: AnimateArgs) -> Result<()> {
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
    check_animation_work(a.frames, (scene.camera.width, scene.camera.height), a.gif.is_some())?;
    let exposure = checked_exposure(a.exposure, scene.camera.exposure)?;
    let ctx = context(&a.device)?;
    let (w, h) = (scene.field.width(), scene.field.height());
    // The same checks `hfgi plan` runs, before any GPU work.
    hfgi::frame::memory::check_device(&scene, ctx.info()).context("checking the scene against the device")?;
    eprintln!(
        "device: {} ({}); field {w}×{h}; animation {}; {} frames",
        ctx.info().name,
        ctx.info().driver,
        scene.animation.kind(),
        a.frames
    );
    let mut passes = Passes::create(&ctx, &scene)?;
    let pipelines_before = ctx.pipelines_created();
    let mut timings = Timings::default();
    let run = render_frames(&ctx, &a, &mut passes, exposure, &mut timings);
    let pipelines_after = ctx.pipelines_created();
    let stats = passes.renderer.stats();
    let memory = passes.renderer.memory_bytes() + passes.view.as_ref().map_or(0, |v| v.memory_bytes());
    passes.destroy(&ctx);
    run?;
    ctx.check_validation()?;
    eprintln!("wrote {}/frame_0000.png … frame_{:04}.png ({} frames)", a.out.display(), a.frames - 1, a.frames);
    if let Some(path) = &a.gif {
        eprintln!("wrote {} ({} fps)", path.display(), a.fps);
    }
    eprintln!("frames: {}", a.frames);
    eprintln!("renderer stats: frames {}, pyramid_builds {}", stats.frames, stats.pyramid_builds);
    eprintln!("pipelines created: {pipelines_before} before the loop, {pipelines_after} after");
    eprintln!("GPU memory (renderer + view): {:.2} MiB", memory as f64 / 1048576.0);
    timings.print(&ctx, a.frames);
    if pipelines_after != pipelines_before {
        bail!("pipelines were created during the frame loop ({pipelines_before} → {pipelines_after})");
    }
    Ok(())
}
