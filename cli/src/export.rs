//! `hfgi export`: a scene resolved to plain data (heights as raw f32, lighting and material as
//! TOML), for tools outside this crate — the Mitsuba 3 peer check (`tools/mitsuba_check.py`,
//! docs/accuracy.md §5) reads it.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use hfgi::scene::model::Albedo;

use super::load_scene_or_default;

#[derive(Args)]
pub struct ExportArgs {
    /// Scene file (TOML, docs/scene-format.md). Without it, the default scene.
    scene: Option<PathBuf>,
    /// Override a scene setting, e.g. `--set heightfield.size=128`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Output folder: `heights.f32` (W·H little-endian float32, row-major, world units) and
    /// `scene.toml` (width, height, texel_size, wrap, albedo, environment SH as n² RGB rows,
    /// key lights, gi.sh_order, gi.bounces).
    #[arg(long, default_value = "out/export")]
    out: PathBuf,
}

fn rgb(v: [f64; 3]) -> String {
    format!("[{:e}, {:e}, {:e}]", v[0], v[1], v[2])
}

pub fn export(a: ExportArgs) -> Result<()> {
    let scene = load_scene_or_default(a.scene.as_deref(), &a.overrides)?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let albedo = match &scene.material.albedo {
        Albedo::Constant(c) => [c[0] as f64, c[1] as f64, c[2] as f64],
        Albedo::Map(_) => anyhow::bail!("hfgi export: albedo maps are not exported (use a constant albedo)"),
    };
    let mut heights = Vec::with_capacity(w * h * 4);
    for y in 0..h {
        for x in 0..w {
            heights.extend_from_slice(&scene.field.get(x, y).to_le_bytes());
        }
    }
    let n = scene.gi.sh_order;
    let mut t = String::new();
    writeln!(t, "# hfgi export: the resolved scene (CONVENTIONS.md units).")?;
    writeln!(t, "width = {w}\nheight = {h}\ntexel_size = {:e}\nwrap = {}", scene.texel_size, scene.wrap)?;
    writeln!(t, "albedo = {}\nsh_order = {n}\nbounces = {}", rgb(albedo), scene.gi.bounces)?;
    let sh: Vec<String> = (0..n * n).map(|k| rgb(scene.environment.sh.get(k).copied().unwrap_or([0.0; 3]))).collect();
    writeln!(t, "environment_sh = [\n  {},\n]", sh.join(",\n  "))?;
    for l in &scene.key_lights {
        let d = l.direction.normalize();
        writeln!(t, "\n[[key_light]]\ndirection = {}", rgb(d.to_array()))?;
        writeln!(t, "angular_radius = {:e}\nradiance = {}", l.angular_radius, rgb(l.radiance))?;
    }
    // Local lights and sphere blockers (CONVENTIONS.md "Lighting"), world units.
    for l in &scene.local_lights {
        writeln!(t, "\n[[local_light]]\nposition = {}", rgb(l.position.to_array()))?;
        writeln!(t, "radius = {:e}\nradiance = {}", l.radius, rgb(l.radiance))?;
    }
    for b in &scene.spheres {
        writeln!(
            t,
            "\n[[sphere]]\ncenter = {}\nradius = {:e}\nalbedo = {}",
            rgb(b.center.to_array()),
            b.radius,
            rgb(b.albedo)
        )?;
    }
    let (hp, sp) = (a.out.join("heights.f32"), a.out.join("scene.toml"));
    super::check_outputs(&[hp.as_path(), sp.as_path()], a.scene.as_deref(), &a.overrides)?;
    // Both files or neither (docs/robustness.md).
    hfgi::io::atomic::all_or_nothing(|| -> Result<()> {
        hfgi::io::atomic::write_bytes(&hp, &heights)?;
        hfgi::io::atomic::write_bytes(&sp, t.as_bytes())?;
        Ok(())
    })?;
    eprintln!("wrote {} ({w}×{h} float32) and {}", hp.display(), sp.display());
    Ok(())
}
