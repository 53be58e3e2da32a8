//! What `hfgi bench` writes: results.csv, results.md (its tables and labels) and the Pareto plots.

use std::fmt::Write as _;

use anyhow::Result;
use hfgi::scene::model::{GiSettings, Horizon, Level0, VisibilityMethod};

use super::{BenchArgs, Row};
use crate::plot;

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

pub(super) fn write_outputs(
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
