//! `hfgi reference`: the brute-force ground truth (docs/accuracy.md §1).

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::Args;
use hfgi::reference::truth::{render_truth, TruthOutput, TruthSettings};

use super::{context, load_scene_or_default, DeviceArgs};

#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML, docs/scene-format.md). Without it, the default scene.
    scene: Option<PathBuf>,
    /// Override a scene setting, e.g. `--set gi.bounces=2`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// The shading texture of the reference: float32 EXR with layers `direct`, `indirect`,
    /// `glossy` (zero: the reference treats surfaces as diffuse) and the total in R, G, B.
    #[arg(long, value_name = "FILE", default_value = "out/reference.exr")]
    shading_exr: PathBuf,
    /// Also the total, tone-mapped, seen from above.
    #[arg(long, value_name = "FILE")]
    shading_png: Option<PathBuf>,
    /// The SH-visibility reference (exact visibility projected to order n, shaded like the
    /// pipeline) instead of the exact one.
    #[arg(long)]
    sh_visibility: bool,
    /// Uniformly spaced azimuths (CONVENTIONS.md: at least 256).
    #[arg(long, default_value_t = 256)]
    azimuths: u32,
    /// March the surface at --step instead of intersecting the bilinear patches exactly (the
    /// march's error halves with each halving of the step; docs/accuracy.md §1).
    #[arg(long)]
    march: bool,
    /// March step in texels, with --march.
    #[arg(long, default_value_t = 0.125, requires = "march")]
    step: f64,
    /// Gauss–Legendre nodes per elevation interval (CONVENTIONS.md: at least 16).
    #[arg(long, default_value_t = 16)]
    nodes: u32,
    /// Gauss–Legendre nodes over a key light's azimuth range (exact reference) and over a
    /// local light's, per receiver (both references).
    #[arg(long, default_value_t = 64)]
    cap_nodes: u32,
    /// Run the f64 CPU version instead of the GPU one (fields up to 64²; for checking).
    #[arg(long)]
    cpu: bool,
    /// Exposure in stops for --shading-png (default: the scene camera's).
    #[arg(long, allow_hyphen_values = true)]
    exposure: Option<f32>,
    #[command(flatten)]
    device: DeviceArgs,
}

fn progress_bar(what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(1);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} {wide_bar} {percent}% [{elapsed} < {eta}]") {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar
}

pub fn reference(a: ReferenceArgs) -> Result<()> {
    let scene = load_scene_or_default(a.scene.as_deref(), &a.overrides)?;
    let exposure = super::checked_exposure(a.exposure, scene.camera.exposure)?;
    let outputs: Vec<&Path> = std::iter::once(&a.shading_exr).chain(&a.shading_png).map(PathBuf::as_path).collect();
    super::check_outputs(&outputs, a.scene.as_deref(), &a.overrides)?;
    let settings = TruthSettings {
        azimuths: a.azimuths,
        step: a.step,
        nodes: a.nodes,
        sh_visibility: a.sh_visibility,
        march: a.march,
        cap_nodes: a.cap_nodes,
    };
    settings.validate().context("reference settings")?;
    settings.check_work(&scene).context("reference settings")?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let kind = if a.sh_visibility { "SH-visibility" } else { "exact" };
    // Sphere blockers (docs/accuracy.md §1): opaque, they do not reflect; both versions.
    let spheres = match scene.spheres.len() {
        0 => String::new(),
        1 => ", 1 sphere blocker".to_string(),
        k => format!(", {k} sphere blockers"),
    };
    let bar = progress_bar(&format!("{kind} reference"));
    let mut on_progress = |done: u64, total: u64| {
        bar.set_length(total);
        bar.set_position(done);
    };
    let started = std::time::Instant::now();
    let out: TruthOutput = if a.cpu {
        if w * h > 64 * 64 {
            anyhow::bail!("--cpu: the f64 CPU reference is for fields up to 64² texels; this field is {w}×{h}");
        }
        eprintln!("{kind} reference on the CPU (f64), field {w}×{h}, {} bounces{spheres}", scene.gi.bounces);
        render_truth(&scene, &settings, &mut on_progress)?
    } else {
        let ctx = context(&a.device)?;
        let rays = if a.march { format!("march at {} texel", a.step) } else { "exact intersection".to_string() };
        eprintln!(
            "{kind} reference on {} ({}), field {w}×{h}, {} bounces, {} azimuths, {rays}, {} nodes{spheres}",
            ctx.info().name,
            ctx.info().driver,
            scene.gi.bounces,
            a.azimuths,
            a.nodes
        );
        let r = hfgi::frame::truth::render_truth_gpu(&ctx, &scene, &settings, &mut on_progress);
        ctx.check_validation()?;
        r?
    };
    bar.finish_and_clear();
    eprintln!("reference took {:.2} s (wall clock)", started.elapsed().as_secs_f64());
    // Both outputs or neither (docs/robustness.md).
    hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        write_truth_exr(&a.shading_exr, &out)?;
        if let Some(p) = &a.shading_png {
            hfgi::io::png::write_tonemapped(p, w, h, &f32s(&out.total), exposure)?;
        }
        Ok(())
    })?;
    for p in std::iter::once(&a.shading_exr).chain(&a.shading_png) {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

fn f32s(v: &[[f64; 3]]) -> Vec<[f32; 3]> {
    v.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect()
}

/// Writes a ground truth as `hfgi render --shading-exr` lays out its layers: total (R, G, B),
/// direct, indirect and glossy (zero: the truth is diffuse), in f32.
pub(crate) fn write_truth_exr(path: &Path, t: &TruthOutput) -> Result<()> {
    let (total, direct, indirect) = (f32s(&t.total), f32s(&t.direct), f32s(&t.indirect));
    let glossy = vec![[0f32; 3]; t.width * t.height];
    let layers = [("", &total[..]), ("direct", &direct[..]), ("indirect", &indirect[..]), ("glossy", &glossy[..])];
    hfgi::io::exr::write_rgb_layers(path, t.width, t.height, &layers)?;
    Ok(())
}
