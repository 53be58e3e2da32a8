//! `hfgi pyramid`: a height field and its pyramid levels as images (docs/pyramid.md).

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::Args;
use hfgi::frame::pyramid::{HeightPyramid, PyramidMode};
use hfgi::scene::generators::Generator;
use hfgi::scene::load::{load_heightfield, LoadOptions};
use hfgi::scene::HeightField;
use hfgi::vk::{Recorder, StageTimer};

use super::{context, print_single_timings, DeviceArgs};

#[derive(Args)]
pub struct PyramidArgs {
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

pub fn pyramid(a: PyramidArgs) -> Result<()> {
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
    print_single_timings(&ctx, &timer);
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
