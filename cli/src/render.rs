//! `hfgi render`: its arguments, the frames it renders and times, and the files it writes.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::Args;
use hfgi::frame::view::{ViewOptions, ViewPass};
use hfgi::frame::{Renderer, ShadingLayers};
use hfgi::scene::model::Scene;
use hfgi::vk::{Context, Recorder, StageTimer};

use super::{bench, check_outputs, checked_exposure, context, load_scene_or_default, print_single_timings, DeviceArgs};

#[derive(Args)]
pub(crate) struct RenderArgs {
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

/// Prints the warm frame's stage times, and beside them the first frame's excess: on drivers
/// that compile a pipeline at its first dispatch (lavapipe), that is the compilation (with a
/// cold Mesa shader cache, `MESA_SHADER_CACHE_DISABLE=true`, its full cost). Stages that repeat
/// (one per bounce) are matched in order.
fn print_timings(ctx: &Context, first: &StageTimer, warm: &StageTimer) {
    let (f, w) = match (first.timings(ctx), warm.timings(ctx)) {
        (Ok(f), Ok(w)) => (f, w),
        (Err(e), _) | (_, Err(e)) => return eprintln!("  no stage timings: {e}"),
    };
    let lavapipe = ctx.info().kind == ash::vk::PhysicalDeviceType::CPU;
    let clock = if lavapipe { "lavapipe: CPU time, not a GPU time" } else { "GPU time" };
    eprintln!("  stage times of the second frame ({clock}); + the first frame's excess (first-dispatch compilation):");
    let (mut total, mut extra) = (0.0, 0.0);
    for (k, (stage, ms)) in w.iter().enumerate() {
        let cold = f.get(k).filter(|(s, _)| s == stage).map_or(*ms, |(_, c)| *c);
        eprintln!("  {stage:<24} {ms:9.3} ms   + {:9.3} ms", cold - ms);
        total += ms;
        extra += cold - ms;
    }
    eprintln!("  {:<24} {total:9.3} ms   + {extra:9.3} ms", "frame");
}

/// Records what `record` records into one submit timed by `timer`, and waits.
fn record_timed(ctx: &Context, timer: &mut StageTimer, record: impl FnOnce(&mut Recorder)) -> Result<()> {
    ctx.submit_and_wait(|cmd| {
        record(&mut Recorder::new(ctx, cmd, Some(timer)));
        Ok(())
    })?;
    Ok(())
}

pub(crate) fn render(a: RenderArgs) -> Result<()> {
    let scene = load_scene_or_default(a.scene.as_deref(), &a.overrides)?;
    let exposure = checked_exposure(a.exposure, scene.camera.exposure)?;
    let outputs: Vec<&Path> = std::iter::once(&a.out)
        .chain([&a.view_exr, &a.shading_exr, &a.shading_png, &a.indirect_png, &a.heights_png].into_iter().flatten())
        .map(PathBuf::as_path)
        .collect();
    check_outputs(&outputs, a.scene.as_deref(), &a.overrides)?;
    let ctx = context(&a.device)?;
    let (w, h) = (scene.field.width(), scene.field.height());
    // The same checks `hfgi plan` runs, before any GPU work.
    hfgi::frame::memory::check_device(&scene, ctx.info()).context("checking the scene against the device")?;
    let gi = &scene.gi;
    eprintln!(
        "device: {} ({}); field {w}×{h}; n={} m={} k_v={} o_v={} subsample={} {} {}",
        ctx.info().name,
        ctx.info().driver,
        gi.sh_order,
        bench::azimuths_label(gi),
        gi.level_step,
        gi.level_offset,
        gi.subsample,
        gi.interpolation,
        gi.pyramid
    );
    let renderer = Renderer::new(&ctx, &scene).context("creating the renderer")?;
    let view = match ViewPass::for_renderer(&ctx, &scene, &renderer, &ViewOptions::default()) {
        Ok(v) => v,
        Err(e) => {
            renderer.destroy(&ctx);
            return Err(anyhow::Error::new(e).context("creating the view pass"));
        }
    };
    let (vw, vh) = view.size();
    eprintln!("view: {vw}×{vh}, {}× MSAA, {:?}", view.samples(), view.color_format());
    let (layers, image) = render_frames(&ctx, &scene, renderer, view)?;
    ctx.check_validation()?;
    let (vw, vh) = (vw as usize, vh as usize);
    write_render_outputs(&a, &scene, &layers, (vw, vh, &image), exposure)
}

/// Renders the frames of `hfgi render` and prints their stage times and the GPU memory; then
/// destroys `renderer` and `view` (also on failure). The shading layers and the view image.
fn render_frames(
    ctx: &Context,
    scene: &Scene,
    mut renderer: Renderer,
    view: ViewPass,
) -> Result<(ShadingLayers, Vec<[f32; 3]>)> {
    // Two GI frames of the same passes (the second with the heights marked changed, so that
    // amortisation does not halve it): the first pays each pipeline's first-dispatch compilation
    // on drivers that compile lazily (lavapipe), the second is the frame's time. Then the view,
    // in its own submit: after a draw, lavapipe's timestamps around compute work read near zero
    // while the work still takes its time (docs/performance.md §3).
    let capacity = 32 + 5 * scene.gi.bounces;
    let mut timers: Vec<StageTimer> = Vec::new();
    let made = (0..3).try_for_each(|k| -> Result<()> {
        timers.push(StageTimer::new(ctx, if k < 2 { capacity } else { 2 })?);
        Ok(())
    });
    let run = made.and_then(|_| {
        let [first, warm, raster] = &mut timers[..] else { unreachable!("three timers") };
        record_timed(ctx, first, |rec| renderer.record(rec))?;
        renderer.mark_heights_changed();
        record_timed(ctx, warm, |rec| renderer.record(rec))?;
        // The view pass records its own compute → vertex/fragment barrier first.
        record_timed(ctx, raster, |rec| view.record(rec))
    });
    let read = run.and_then(|_| Ok((renderer.read_layers(ctx)?, view.read_hdr(ctx)?)));
    if let [first, warm, raster] = &timers[..] {
        print_timings(ctx, first, warm);
        print_single_timings(ctx, raster);
    }
    eprintln!("  GPU memory: {:.2} MiB", (renderer.memory_bytes() + view.memory_bytes()) as f64 / 1048576.0);
    view.destroy(ctx);
    renderer.destroy(ctx);
    timers.iter_mut().for_each(|t| t.destroy(ctx));
    read
}

/// Writes the outputs of `hfgi render`: the view `image` (`vw`×`vh`) and what the flags ask
/// for of the shading `layers` and the heights.
fn write_render_outputs(
    a: &RenderArgs,
    scene: &Scene,
    layers: &ShadingLayers,
    (vw, vh, image): (usize, usize, &[[f32; 3]]),
    exposure: f32,
) -> Result<()> {
    let (w, h) = (scene.field.width(), scene.field.height());
    // Every output or none (docs/robustness.md).
    let mut wrote = Vec::new();
    hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        hfgi::io::png::write_tonemapped(&a.out, vw, vh, image, exposure)?;
        wrote.push(a.out.display().to_string());
        if let Some(path) = &a.view_exr {
            hfgi::io::exr::write_rgb_layers(path, vw, vh, &[("", image)])?;
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
