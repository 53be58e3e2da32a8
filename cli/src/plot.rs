//! Error-versus-time scatter plots with a Pareto front, for `hfgi bench`.
//!
//! Rendering uses plotters' bitmap backend into an in-memory RGB buffer that the `image` crate
//! encodes as PNG. Text is rasterised with `ab_glyph` (pure Rust) from a TrueType font read at run
//! time from a well-known system path (Debian: `fonts-dejavu-core`), so nothing here links a system
//! library. The text goes through [`TextBackend`], a thin wrapper around the bitmap backend, because
//! plotters' own `ab_glyph` text drawing ignores glyph side bearings ("16" comes out as "1 6").
//! Without a font the plot is still drawn, only without any text.

mod chart;
mod marks;
mod scale;
mod text;

use std::fmt::Display;
use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;

use chart::draw;
use text::{load_font, TextBackend};

/// One measured configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub label: String,
    pub time_ms: f64,
    pub error: f64,
    pub group: String,
}

const WIDTH: u32 = 1000;
const HEIGHT: u32 = 700;

/// Colour-blind-friendly categorical palette (matplotlib's "tab10").
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

const FRONT_COLOR: RGBColor = RGBColor(0, 0, 0);
const REFERENCE_COLOR: RGBColor = RGBColor(90, 90, 90);
const TEXT_COLOR: RGBColor = RGBColor(40, 40, 40);
const FAMILY: &str = "sans-serif";
const MAX_LABEL_CHARS: usize = 28;
const REFERENCE_LABEL: &str = "brute-force reference";

/// Scatter of error (y, log scale) against time (x, log scale) for `points`; each `group` gets
/// its own colour and a legend entry; the Pareto front (points not dominated in both time and
/// error: no other point is both faster-or-equal and more accurate-or-equal with one strict)
/// is drawn as a step line and its points are circled; `reference_ms` (if Some) is a vertical
/// dashed line labelled "brute-force reference". Non-finite or non-positive values are skipped
/// (and counted in the returned note). Size 1000×700.
pub fn pareto_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[Point],
    reference_ms: Option<f64>,
) -> anyhow::Result<Option<String>> {
    let mut notes = Vec::new();
    let font = match load_font() {
        Ok(font) => Some(font),
        Err(why) => {
            notes.push(format!("no usable font ({why}); plot drawn without any text"));
            None
        }
    };
    draw(path, title, x_label, y_label, points, reference_ms, font, &mut notes)?;
    Ok(if notes.is_empty() { None } else { Some(notes.join("; ")) })
}

/// Indices of the Pareto-optimal points (same definition), sorted by time.
///
/// A point is dominated when another point has time ≤ and error ≤ with at least one strict;
/// exact duplicates therefore do not dominate each other and are all returned. Points with a
/// non-finite coordinate are ignored. Ties in time are ordered by error, then by index.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> =
        (0..points.len()).filter(|&i| points[i].0.is_finite() && points[i].1.is_finite()).collect();
    order.sort_by(|&a, &b| {
        points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1)).then(a.cmp(&b))
    });
    let mut front = Vec::new();
    // Smallest error among all points strictly faster than the current time group.
    let mut best_faster = f64::INFINITY;
    let mut start = 0;
    while start < order.len() {
        let t = points[order[start]].0;
        let end = start + order[start..].iter().take_while(|&&i| points[i].0 == t).count();
        // Sorted by error within the group, so the group's best error comes first; members with
        // a larger error are dominated by it (equal time, strictly larger error).
        let group_best = points[order[start]].1;
        if group_best < best_faster {
            front.extend(order[start..end].iter().copied().take_while(|&i| points[i].1 == group_best));
        }
        best_faster = best_faster.min(group_best);
        start = end;
    }
    front
}

fn plot_err<E: Display>(e: E) -> anyhow::Error {
    anyhow!("plotting failed: {e}")
}

#[cfg(test)]
mod tests;
