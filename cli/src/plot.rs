//! Error-versus-time scatter plots with a Pareto front, for `hfgi bench`.
//!
//! Rendering uses plotters' bitmap backend into an in-memory RGB buffer that the `image` crate
//! encodes as PNG. Text is rasterised with `ab_glyph` (pure Rust) from a TrueType font read at run
//! time from a well-known system path (Debian: `fonts-dejavu-core`), so nothing here links a system
//! library. The text goes through [`TextBackend`], a thin wrapper around the bitmap backend, because
//! plotters' own `ab_glyph` text drawing ignores glyph side bearings ("16" comes out as "1 6").
//! Without a font the plot is still drawn, only without any text.

use std::cell::RefCell;
use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use ab_glyph::{point, Font, FontVec, GlyphId, PxScale, ScaleFont};
use anyhow::{anyhow, Context};
use plotters::backend::DrawingBackend;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{self as pb, BackendColor, BackendCoord, DrawingErrorKind};

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

/// Environment variable naming a TTF/OTF file to use instead of the built-in search list.
const FONT_ENV: &str = "HFGI_PLOT_FONT";

/// Fonts tried in order (Debian/Ubuntu, Fedora, Arch, other common layouts, macOS, Windows).
const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/usr/share/fonts/truetype/noto/NotoSans-Regular.ttf",
    "/Library/Fonts/Arial.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

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

/// Finds and parses a font once per process.
fn load_font() -> Result<&'static FontVec, String> {
    static FONT: OnceLock<Result<FontVec, String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let mut candidates: Vec<PathBuf> = Vec::new();
        if let Some(p) = std::env::var_os(FONT_ENV).filter(|p| !p.is_empty()) {
            candidates.push(PathBuf::from(p));
        }
        candidates.extend(FONT_CANDIDATES.iter().map(PathBuf::from));
        candidates
            .iter()
            .find_map(|c| std::fs::read(c).ok().and_then(|bytes| FontVec::try_from_vec(bytes).ok()))
            .ok_or_else(|| {
                format!(
                    "none of {} and the usual fallbacks exists or parses; install fonts-dejavu-core or set {FONT_ENV}",
                    FONT_CANDIDATES[0]
                )
            })
    })
    .as_ref()
    .map_err(Clone::clone)
}

/// Horizontal layout of one line of text: glyphs with their caret x, the advance width, the
/// ascent (baseline offset from the top) and the line height, all in pixels.
struct Layout {
    glyphs: Vec<(GlyphId, f32)>,
    width: f32,
    ascent: f32,
    height: f32,
    scale: PxScale,
}

fn layout(font: &FontVec, size: f64, text: &str) -> Layout {
    let scale = PxScale::from(size as f32);
    let scaled = font.as_scaled(scale);
    let mut glyphs = Vec::with_capacity(text.len());
    let mut caret = 0.0f32;
    let mut prev: Option<GlyphId> = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = prev {
            caret += scaled.kern(p, id);
        }
        glyphs.push((id, caret));
        caret += scaled.h_advance(id);
        prev = Some(id);
    }
    Layout { glyphs, width: caret, ascent: scaled.ascent(), height: scaled.ascent() - scaled.descent(), scale }
}

/// The bitmap backend with text drawn by `ab_glyph` from `font`; with no font, text is not drawn.
struct TextBackend<'a> {
    inner: BitMapBackend<'a>,
    font: Option<&'static FontVec>,
}

type InnerError<'a> = <BitMapBackend<'a> as DrawingBackend>::ErrorType;

impl<'a> DrawingBackend for TextBackend<'a> {
    type ErrorType = InnerError<'a>;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: pb::BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }
    fn draw_rect<S: pb::BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: pb::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_path(path, style)
    }
    fn draw_circle<S: pb::BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: pb::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.fill_polygon(vert, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }

    fn draw_text<TStyle: pb::BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let color = style.color();
        let Some(font) = self.font else { return Ok(()) };
        if color.alpha == 0.0 || text.is_empty() {
            return Ok(());
        }
        let lay = layout(font, style.size(), text);
        let (w, h) = (lay.width.ceil() as i32, lay.height.ceil() as i32);
        let anchor = style.anchor();
        let dx = match anchor.h_pos {
            HPos::Left => 0,
            HPos::Right => -w,
            HPos::Center => -w / 2,
        };
        let dy = match anchor.v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let transform = style.transform();
        for &(id, x) in &lay.glyphs {
            let Some(outline) = font.outline_glyph(id.with_scale_and_position(lay.scale, point(x, lay.ascent))) else {
                continue;
            };
            let bounds = outline.px_bounds();
            let inner = &mut self.inner;
            let mut result = Ok(());
            outline.draw(|gx, gy, coverage| {
                if result.is_err() || coverage <= 0.0 {
                    return;
                }
                let local = (bounds.min.x as i32 + gx as i32 + dx, bounds.min.y as i32 + gy as i32 + dy);
                let (tx, ty) = transform.transform(local.0, local.1);
                let c = BackendColor { alpha: color.alpha * f64::from(coverage.min(1.0)), rgb: color.rgb };
                result = inner.draw_pixel((pos.0 + tx, pos.1 + ty), c);
            });
            result?;
        }
        Ok(())
    }

    fn estimate_text_size<TStyle: pb::BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        Ok(match self.font {
            Some(font) => {
                let lay = layout(font, style.size(), text);
                (lay.width.ceil() as u32, lay.height.ceil() as u32)
            }
            None => ((style.size() * 0.6 * text.chars().count() as f64) as u32, style.size() as u32),
        })
    }
}

fn plot_err<E: Display>(e: E) -> anyhow::Error {
    anyhow!("plotting failed: {e}")
}

/// Log-axis range covering `values` with some margin, widened to whole decades so that the axis
/// always has tick marks (and nudged outwards so the end decades survive rounding in plotters'
/// tick placement).
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return (1.0 - 1e-9, 10.0 + 1e-8);
    }
    let lo = 10f64.powf((lo / 1.25).log10().floor()) * (1.0 - 1e-9);
    let hi = 10f64.powf((hi * 1.25).log10().ceil()) * (1.0 + 1e-9);
    if lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo {
        (lo, hi)
    } else {
        (1.0 - 1e-9, 10.0 + 1e-8)
    }
}

/// Tick label for a log axis: plain decimals for moderate magnitudes, `1e-5` style otherwise.
fn format_tick(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return format!("{v}");
    }
    let exp = v.abs().log10().floor() as i32;
    if (-3..=4).contains(&exp) {
        let decimals = (2 - exp).max(0) as usize;
        trim_zeros(format!("{v:.decimals$}"))
    } else {
        let mantissa = v / 10f64.powi(exp);
        let (mantissa, exp) = if mantissa.abs() >= 9.995 { (mantissa / 10.0, exp + 1) } else { (mantissa, exp) };
        format!("{}e{exp}", trim_zeros(format!("{mantissa:.2}")))
    }
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn truncate_label(label: &str) -> String {
    if label.chars().count() <= MAX_LABEL_CHARS {
        label.to_string()
    } else {
        let mut s: String = label.chars().take(MAX_LABEL_CHARS - 1).collect();
        s.push('…');
        s
    }
}

/// Marker shapes, cycled once the palette has been used up.
#[derive(Clone, Copy)]
enum Marker {
    Circle,
    Triangle,
    Cross,
}

fn group_style(index: usize) -> (RGBColor, Marker) {
    let marker = match (index / PALETTE.len()) % 3 {
        0 => Marker::Circle,
        1 => Marker::Triangle,
        _ => Marker::Cross,
    };
    (PALETTE[index % PALETTE.len()], marker)
}

/// A group's marker at pixel `c` (for the legend; the series draw the same shapes).
fn draw_marker(
    root: &DrawingArea<TextBackend<'_>, Shift>,
    c: BackendCoord,
    color: RGBColor,
    marker: Marker,
) -> anyhow::Result<()> {
    let (fill, stroke) = (color.mix(0.85).filled(), color.stroke_width(2));
    match marker {
        Marker::Circle => root.draw(&Circle::new(c, 5, fill)),
        Marker::Triangle => root.draw(&TriangleMarker::new(c, 6, fill)),
        Marker::Cross => root.draw(&Cross::new(c, 5, stroke)),
    }
    .map_err(plot_err)
}

/// What a legend entry shows left of its text.
enum Swatch {
    Marker(RGBColor, Marker),
    Front,
    Reference,
}

/// Pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl Rect {
    fn around((x, y): BackendCoord, r: i32) -> Self {
        Rect { x0: x - r, y0: y - r, x1: x + r + 1, y1: y + r + 1 }
    }
    fn intersects(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

/// Small rectangles along a polyline, for counting what a legend box would hide.
fn sample_polyline(path: &[BackendCoord], out: &mut Vec<Rect>) {
    for w in path.windows(2) {
        let (a, b) = (w[0], w[1]);
        let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()) / 6).max(1);
        for s in 0..=steps {
            let x = a.0 + (b.0 - a.0) * s / steps;
            let y = a.1 + (b.1 - a.1) * s / steps;
            out.push(Rect::around((x, y), 2));
        }
    }
}

/// The chart [`draw`] plots into: log time (x) against log error (y).
type Chart<'a, 'b> = ChartContext<'a, TextBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// Pixel ranges of the plotting area (x, y).
type Area = (std::ops::Range<i32>, std::ops::Range<i32>);

#[allow(clippy::too_many_arguments)]
fn draw(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_basic_and_sorted_by_time() {
        // 0: slow, accurate; 1: fast, inaccurate; 2: dominated by 3; 3: middle.
        let pts = [(10.0, 0.01), (1.0, 1.0), (6.0, 0.5), (5.0, 0.1)];
        assert_eq!(pareto_front(&pts), vec![1, 3, 0]);
    }

    #[test]
    fn front_ties() {
        // Same time: only the lower error survives.
        assert_eq!(pareto_front(&[(1.0, 0.5), (1.0, 0.2)]), vec![1]);
        // Same error: only the faster survives.
        assert_eq!(pareto_front(&[(2.0, 0.2), (1.0, 0.2)]), vec![1]);
        // Same error as a faster point but slower, plus a strictly better slower point.
        assert_eq!(pareto_front(&[(1.0, 0.2), (2.0, 0.2), (3.0, 0.1)]), vec![0, 2]);
    }

    #[test]
    fn front_duplicates_are_all_kept() {
        let pts = [(2.0, 0.1), (1.0, 0.5), (2.0, 0.1), (3.0, 0.3)];
        assert_eq!(pareto_front(&pts), vec![1, 0, 2]);
    }

    #[test]
    fn front_skips_non_finite() {
        let pts =
            [(f64::NAN, 0.0), (1.0, f64::NAN), (2.0, 0.5), (f64::INFINITY, 0.0), (3.0, f64::NEG_INFINITY), (4.0, 0.1)];
        assert_eq!(pareto_front(&pts), vec![2, 5]);
        assert!(pareto_front(&[]).is_empty());
        assert!(pareto_front(&[(f64::NAN, f64::NAN)]).is_empty());
    }

    #[test]
    fn front_matches_brute_force() {
        // Deterministic pseudo-random points on a coarse grid (many ties and duplicates).
        let mut state = 0x2545_f491_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % 7) as f64
        };
        for _ in 0..200 {
            let pts: Vec<(f64, f64)> = (0..12).map(|_| (next(), next())).collect();
            let dominated = |i: usize| {
                pts.iter().any(|q| {
                    let p = pts[i];
                    q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1)
                })
            };
            let mut expected: Vec<usize> = (0..pts.len()).filter(|&i| !dominated(i)).collect();
            expected
                .sort_by(|&a, &b| pts[a].0.total_cmp(&pts[b].0).then(pts[a].1.total_cmp(&pts[b].1)).then(a.cmp(&b)));
            assert_eq!(pareto_front(&pts), expected, "{pts:?}");
        }
    }

    #[test]
    fn tick_format() {
        assert_eq!(format_tick(1.0), "1");
        assert_eq!(format_tick(20.0), "20");
        assert_eq!(format_tick(0.001), "0.001");
        assert_eq!(format_tick(0.002), "0.002");
        assert_eq!(format_tick(1e-5), "1e-5");
        assert_eq!(format_tick(3e-7), "3e-7");
        assert_eq!(format_tick(1e6), "1e6");
        assert_eq!(format_tick(10000.0), "10000");
    }

    fn sample_points() -> Vec<Point> {
        let mut pts = Vec::new();
        for (i, n) in [16, 32, 64, 128, 256].iter().enumerate() {
            let t = 0.4 * 2f64.powi(i as i32);
            pts.push(Point {
                label: format!("sh order 4, {n} dirs"),
                time_ms: t,
                error: 0.08 / (1.0 + i as f64).powf(1.5),
                group: "spherical harmonics".into(),
            });
            pts.push(Point {
                label: format!("horizon {n}"),
                time_ms: t * 1.7,
                error: 0.05 / (1.0 + i as f64).powi(2),
                group: "horizon-based".into(),
            });
            pts.push(Point {
                label: format!("ray march {n}"),
                time_ms: t * 6.0,
                error: 0.2 / (1.0 + 2.0 * i as f64).powi(2),
                group: "ray marching".into(),
            });
        }
        pts.push(Point { label: "broken".into(), time_ms: f64::NAN, error: 0.1, group: "ray marching".into() });
        pts.push(Point { label: "exact".into(), time_ms: 3.0, error: 0.0, group: "horizon-based".into() });
        pts
    }

    fn decode(path: &Path) -> image::DynamicImage {
        let bytes = std::fs::read(path).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
        image::load_from_memory_with_format(&bytes, image::ImageFormat::Png).unwrap()
    }

    /// Copies a test image out for inspection when the named variable is set.
    fn keep(path: &Path, var: &str) {
        if let Some(out) = std::env::var_os(var) {
            std::fs::copy(path, out).unwrap();
        }
    }

    #[test]
    fn plot_writes_decodable_png() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pareto.png");
        let note = pareto_plot(
            &path,
            "Indirect light: error vs. time",
            "time per frame (ms)",
            "RMSE",
            &sample_points(),
            Some(250.0),
        )
        .unwrap();
        let img = decode(&path).to_rgb8();
        assert_eq!(img.dimensions(), (WIDTH, HEIGHT));
        // Something beyond the white background and grey grid was drawn.
        assert!(img.pixels().any(|p| p.0 == [0, 0, 0]));
        let note = note.expect("two points are skipped");
        assert!(note.contains("skipped 2 of 17"), "{note}");
        keep(&path, "HFGI_PLOT_TEST_OUT");
    }

    #[test]
    fn plot_without_font_and_degenerate_input() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no-text.png");
        let mut notes = Vec::new();
        draw(&path, "t", "x", "y", &sample_points(), Some(-1.0), None, &mut notes).unwrap();
        assert_eq!(decode(&path).width(), WIDTH);
        assert!(notes.iter().any(|n| n.contains("reference")), "{notes:?}");
        keep(&path, "HFGI_PLOT_TEST_OUT_NOTEXT");

        // Nothing plottable, a single point and identical points must not fail either.
        for pts in [
            vec![],
            vec![Point { label: "a".into(), time_ms: 2.0, error: 0.5, group: "g".into() }],
            vec![Point { label: String::new(), time_ms: 2.0, error: 0.5, group: String::new() }; 3],
        ] {
            let note = pareto_plot(&path, "", "x", "y", &pts, None).unwrap();
            decode(&path);
            assert_eq!(note.is_some_and(|n| n.contains("no plottable")), pts.is_empty());
        }
    }
}
