//! The chart: points by group, the Pareto front and its labels, the reference line and the legend.

use std::cell::RefCell;
use std::path::Path;

use ab_glyph::FontVec;
use anyhow::{anyhow, Context};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::BackendCoord;

use super::marks::{draw_marker, group_style, sample_polyline, Marker, Rect, Swatch};
use super::scale::{format_tick, log_range, truncate_label};
use super::{
    pareto_front, plot_err, Point, TextBackend, FAMILY, FRONT_COLOR, HEIGHT, REFERENCE_COLOR, REFERENCE_LABEL,
    TEXT_COLOR, WIDTH,
};

/// The chart [`draw`] plots into: log time (x) against log error (y).
type Chart<'a, 'b> = ChartContext<'a, TextBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// Pixel ranges of the plotting area (x, y).
type Area = (std::ops::Range<i32>, std::ops::Range<i32>);

#[allow(clippy::too_many_arguments)]
pub(super) fn draw(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[Point],
    reference_ms: Option<f64>,
    font: Option<&'static FontVec>,
    notes: &mut Vec<String>,
) -> anyhow::Result<()> {
    let text = font.is_some();
    let (kept, reference) = plottable(points, reference_ms, notes);

    let (x0, x1) = log_range(kept.iter().map(|p| p.time_ms).chain(reference));
    let (y0, y1) = log_range(kept.iter().map(|p| p.error));

    let coords: Vec<(f64, f64)> = kept.iter().map(|p| (p.time_ms, p.error)).collect();
    let front = pareto_front(&coords);

    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let backend = TextBackend { inner: BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)), font };
        let root = backend.into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let mut chart = build_chart(&root, title, (x_label, y_label), (x0..x1, y0..y1), text)?;
        let area = chart.plotting_area().get_pixel_range();
        if !text {
            let frame = Rectangle::new([(area.0.start, area.1.start), (area.0.end - 1, area.1.end - 1)], BLACK);
            root.draw(&frame).map_err(plot_err)?;
        }

        // Everything a legend box could hide, in pixels.
        let mut occupied: Vec<Rect> = coords.iter().map(|c| Rect::around(chart.backend_coord(c), 9)).collect();
        // Legend entries: the groups, then the front, then the reference.
        let mut legend_tail: Vec<(String, Swatch)> = Vec::new();

        if let Some(r) = reference {
            draw_reference(&root, &mut chart, r, (y0, y1), &area, &mut occupied)?;
            legend_tail.push((REFERENCE_LABEL.to_string(), Swatch::Reference));
        }
        if !front.is_empty() {
            draw_front_line(&mut chart, &coords, &front, x1, &mut occupied)?;
            legend_tail.insert(0, ("Pareto front".to_string(), Swatch::Front));
        }
        let mut legend = draw_groups(&mut chart, &kept)?;

        chart
            .draw_series(front.iter().map(|&i| Circle::new(coords[i], 9, FRONT_COLOR.stroke_width(2))))
            .map_err(plot_err)?;

        if text {
            label_front(&root, &chart, &kept, &coords, &front, &area, &mut occupied)?;
            legend.append(&mut legend_tail);
            draw_legend(&root, &legend, area, &occupied)?;
        }
        root.present().map_err(plot_err)?;
    }
    let img = image::RgbImage::from_raw(WIDTH, HEIGHT, buf).ok_or_else(|| anyhow!("plot buffer has the wrong size"))?;
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png).with_context(|| format!("encoding {}", path.display()))?;
    hfgi::io::atomic::write_bytes(path, png.get_ref())?;
    Ok(())
}

/// The points with a finite and positive time and error, and the reference time if it is
/// finite and positive; what is skipped is said in `notes`.
fn plottable<'p>(
    points: &'p [Point],
    reference_ms: Option<f64>,
    notes: &mut Vec<String>,
) -> (Vec<&'p Point>, Option<f64>) {
    let valid = |v: f64| v.is_finite() && v > 0.0;
    let kept: Vec<&Point> = points.iter().filter(|p| valid(p.time_ms) && valid(p.error)).collect();
    let skipped = points.len() - kept.len();
    if skipped > 0 {
        notes.push(format!(
            "skipped {skipped} of {} point(s) with a non-finite or non-positive time or error",
            points.len()
        ));
    }
    if kept.is_empty() {
        notes.push("no plottable points".to_string());
    }
    let reference = match reference_ms {
        Some(r) if valid(r) => Some(r),
        Some(r) => {
            notes.push(format!("skipped non-finite or non-positive reference time {r}"));
            None
        }
        None => None,
    };
    (kept, reference)
}

/// Each group's points (groups in order of first appearance) in its colour and marker; their
/// legend entries.
fn draw_groups(chart: &mut Chart<'_, '_>, kept: &[&Point]) -> anyhow::Result<Vec<(String, Swatch)>> {
    // Groups in order of first appearance.
    let mut groups: Vec<&str> = Vec::new();
    for p in kept {
        if !groups.contains(&p.group.as_str()) {
            groups.push(&p.group);
        }
    }
    let mut legend: Vec<(String, Swatch)> = Vec::new();
    for (index, name) in groups.iter().enumerate() {
        let (color, marker) = group_style(index);
        let members = kept.iter().filter(|p| p.group == *name).map(|p| (p.time_ms, p.error));
        let (fill, stroke) = (color.mix(0.85).filled(), color.stroke_width(2));
        match marker {
            Marker::Circle => chart.draw_series(members.map(|c| Circle::new(c, 5, fill))),
            Marker::Triangle => chart.draw_series(members.map(|c| TriangleMarker::new(c, 6, fill))),
            Marker::Cross => chart.draw_series(members.map(|c| Cross::new(c, 5, stroke))),
        }
        .map_err(plot_err)?;
        legend.push((name.to_string(), Swatch::Marker(color, marker)));
    }
    Ok(legend)
}

/// The chart over the log ranges `x` and `y` with its caption (`title`), axis descriptions
/// and mesh drawn.
fn build_chart<'a, 'b>(
    root: &'a DrawingArea<TextBackend<'b>, Shift>,
    title: &str,
    (x_label, y_label): (&str, &str),
    (x, y): (std::ops::Range<f64>, std::ops::Range<f64>),
    text: bool,
) -> anyhow::Result<Chart<'a, 'b>> {
    let mut builder = ChartBuilder::on(root);
    builder.margin(20);
    // Without a font there are no label areas at all (they would only hold text); the mesh is
    // still drawn and a frame stands in for the axes.
    if text {
        if !title.is_empty() {
            builder.caption(title, (FAMILY, 24));
        }
        builder.x_label_area_size(55).y_label_area_size(80);
    }
    let mut chart = builder.build_cartesian_2d(x.log_scale(), y.log_scale()).map_err(plot_err)?;

    // plotters' log axis can yield the top decade twice (once as the last minor tick of the
    // decade below); label each value once so it is not drawn darker than the others.
    let (x_seen, y_seen) = (RefCell::new(Vec::new()), RefCell::new(Vec::new()));
    let once = |seen: &RefCell<Vec<u64>>, v: f64| {
        let mut seen = seen.borrow_mut();
        if seen.contains(&v.to_bits()) {
            String::new()
        } else {
            seen.push(v.to_bits());
            format_tick(v)
        }
    };
    let x_fmt = |v: &f64| once(&x_seen, *v);
    let y_fmt = |v: &f64| once(&y_seen, *v);
    let mut mesh = chart.configure_mesh();
    mesh.light_line_style(RGBColor(236, 236, 236))
        .bold_line_style(RGBColor(200, 200, 200))
        .max_light_lines(4)
        .x_desc(x_label)
        .y_desc(y_label)
        .x_labels(12)
        .y_labels(12)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FAMILY, 15).into_font().color(&TEXT_COLOR))
        .axis_desc_style((FAMILY, 17).into_font().color(&TEXT_COLOR));
    mesh.draw().map_err(plot_err)?;
    Ok(chart)
}

/// The reference time `r` as a vertical dashed line over the error range `y0..y1`, labelled at
/// its top on the side with more room; the line and the label are added to `occupied`.
fn draw_reference(
    root: &DrawingArea<TextBackend<'_>, Shift>,
    chart: &mut Chart<'_, '_>,
    r: f64,
    (y0, y1): (f64, f64),
    area: &Area,
    occupied: &mut Vec<Rect>,
) -> anyhow::Result<()> {
    let style = REFERENCE_COLOR.stroke_width(2);
    chart.draw_series(DashedLineSeries::new(vec![(r, y0), (r, y1)], 10, 6, style)).map_err(plot_err)?;
    let (lx, _) = chart.backend_coord(&(r, y1));
    sample_polyline(&[(lx, area.1.start), (lx, area.1.end)], occupied);
    // Label at the top of the line, on the side with more room.
    let font = (FAMILY, 14).into_font().color(&REFERENCE_COLOR);
    let (w, h) = root.estimate_text_size(REFERENCE_LABEL, &font).map_err(plot_err)?;
    let (w, h) = (w as i32, h as i32);
    let right_half = lx > (area.0.start + area.0.end) / 2;
    let (tx, anchor) = if right_half { (lx - 6, HPos::Right) } else { (lx + 6, HPos::Left) };
    let ty = area.1.start + 6;
    let pos = plotters::style::text_anchor::Pos::new(anchor, VPos::Top);
    root.draw(&Text::new(REFERENCE_LABEL, (tx, ty), font.pos(pos))).map_err(plot_err)?;
    let x0 = if right_half { tx - w } else { tx };
    occupied.push(Rect { x0, y0: ty, x1: x0 + w, y1: ty + h });
    Ok(())
}

/// The attainable region's boundary: right from each point of `front` (indices into `coords`),
/// then down to the next, continued to the right edge `x1` at the best error; the line is added
/// to `occupied`.
fn draw_front_line(
    chart: &mut Chart<'_, '_>,
    coords: &[(f64, f64)],
    front: &[usize],
    x1: f64,
    occupied: &mut Vec<Rect>,
) -> anyhow::Result<()> {
    let mut step: Vec<(f64, f64)> = Vec::with_capacity(2 * front.len() + 1);
    for (k, &i) in front.iter().enumerate() {
        if k > 0 {
            step.push((coords[i].0, step.last().map_or(coords[i].1, |s| s.1)));
        }
        step.push(coords[i]);
    }
    if let Some(&(_, last)) = step.last() {
        step.push((x1, last));
    }
    let pixels: Vec<BackendCoord> = step.iter().map(|c| chart.backend_coord(c)).collect();
    sample_polyline(&pixels, occupied);
    chart.draw_series(LineSeries::new(step, FRONT_COLOR.stroke_width(2))).map_err(plot_err)?;
    Ok(())
}

/// Front points get their label below-left (the region under the front is empty) or else
/// above-right, wherever it overlaps nothing drawn so far (`occupied`, to which it is added);
/// otherwise none.
fn label_front(
    root: &DrawingArea<TextBackend<'_>, Shift>,
    chart: &Chart<'_, '_>,
    kept: &[&Point],
    coords: &[(f64, f64)],
    front: &[usize],
    area: &Area,
    occupied: &mut Vec<Rect>,
) -> anyhow::Result<()> {
    let font = (FAMILY, 13).into_font().color(&TEXT_COLOR);
    let inside = |r: &Rect| r.x0 >= area.0.start && r.x1 <= area.0.end && r.y0 >= area.1.start && r.y1 <= area.1.end;
    for &i in front {
        let label = truncate_label(&kept[i].label);
        if label.is_empty() {
            continue;
        }
        let (px, py) = chart.backend_coord(&coords[i]);
        let (w, h) = root.estimate_text_size(&label, &font).map_err(plot_err)?;
        let (w, h, d) = (w as i32, h as i32, 10);
        let candidates = [
            (Rect { x0: px - d - w, y0: py + d, x1: px - d, y1: py + d + h }, (px - d, py + d), HPos::Right, VPos::Top),
            (
                Rect { x0: px + d, y0: py - d - h, x1: px + d + w, y1: py - d },
                (px + d, py - d),
                HPos::Left,
                VPos::Bottom,
            ),
        ];
        let free = candidates.into_iter().find(|(r, ..)| inside(r) && !occupied.iter().any(|o| o.intersects(r)));
        if let Some((r, at, hpos, vpos)) = free {
            let anchor = plotters::style::text_anchor::Pos::new(hpos, vpos);
            root.draw(&Text::new(label, at, font.pos(anchor))).map_err(plot_err)?;
            occupied.push(r);
        }
    }
    Ok(())
}

/// Draws the legend in the corner of the plotting area `area` that hides the fewest `occupied`
/// rectangles (upper right on ties).
fn draw_legend(
    root: &DrawingArea<TextBackend<'_>, Shift>,
    entries: &[(String, Swatch)],
    area: (std::ops::Range<i32>, std::ops::Range<i32>),
    occupied: &[Rect],
) -> anyhow::Result<()> {
    if entries.is_empty() {
        return Ok(());
    }
    let font = (FAMILY, 15).into_font().color(&TEXT_COLOR);
    let (pad, swatch_w, gap, inset) = (8, 28, 8, 10);
    let mut text_w = 0;
    let mut line_h = 18;
    for (label, _) in entries {
        let (w, h) = root.estimate_text_size(label, &font).map_err(plot_err)?;
        text_w = text_w.max(w as i32);
        line_h = line_h.max(h as i32 + 4);
    }
    let (w, h) = (pad + swatch_w + gap + text_w + pad, 2 * pad + line_h * entries.len() as i32);
    let (xs, ys) = area;
    let corners = [
        (xs.end - inset - w, ys.start + inset),
        (xs.start + inset, ys.end - inset - h),
        (xs.end - inset - w, ys.end - inset - h),
        (xs.start + inset, ys.start + inset),
    ];
    let hidden = |&(x, y): &(i32, i32)| {
        let r = Rect { x0: x, y0: y, x1: x + w, y1: y + h };
        occupied.iter().filter(|o| o.intersects(&r)).count()
    };
    // `min_by_key` keeps the first minimum, so the order above is the preference on ties.
    let (x, y) = corners.iter().copied().min_by_key(hidden).unwrap_or(corners[0]);

    root.draw(&Rectangle::new([(x, y), (x + w, y + h)], WHITE.mix(0.9).filled())).map_err(plot_err)?;
    root.draw(&Rectangle::new([(x, y), (x + w, y + h)], RGBColor(160, 160, 160))).map_err(plot_err)?;
    let centered = font.pos(plotters::style::text_anchor::Pos::new(HPos::Left, VPos::Center));
    for (k, (label, swatch)) in entries.iter().enumerate() {
        let cy = y + pad + line_h * k as i32 + line_h / 2;
        let sx = x + pad;
        let mid = (sx + swatch_w / 2, cy);
        match swatch {
            Swatch::Marker(color, marker) => {
                draw_marker(root, mid, *color, *marker)?;
                Ok(())
            }
            Swatch::Front => root
                .draw(&PathElement::new(vec![(sx, cy), (sx + swatch_w, cy)], FRONT_COLOR.stroke_width(2)))
                .and_then(|_| root.draw(&Circle::new(mid, 8, FRONT_COLOR.stroke_width(2)))),
            Swatch::Reference => root
                .draw(&PathElement::new(vec![(sx, cy), (sx + swatch_w / 2 - 3, cy)], REFERENCE_COLOR.stroke_width(2)))
                .and_then(|_| {
                    root.draw(&PathElement::new(
                        vec![(sx + swatch_w / 2 + 3, cy), (sx + swatch_w, cy)],
                        REFERENCE_COLOR.stroke_width(2),
                    ))
                }),
        }
        .map_err(plot_err)?;
        root.draw(&Text::new(label.as_str(), (sx + swatch_w + gap, cy), centered.clone())).map_err(plot_err)?;
    }
    Ok(())
}
