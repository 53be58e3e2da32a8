//! Group markers, legend swatches and the pixel rectangles that labels and the legend avoid.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::BackendCoord;

use super::{plot_err, TextBackend, PALETTE};

/// Marker shapes, cycled once the palette has been used up.
#[derive(Clone, Copy)]
pub(super) enum Marker {
    Circle,
    Triangle,
    Cross,
}

pub(super) fn group_style(index: usize) -> (RGBColor, Marker) {
    let marker = match (index / PALETTE.len()) % 3 {
        0 => Marker::Circle,
        1 => Marker::Triangle,
        _ => Marker::Cross,
    };
    (PALETTE[index % PALETTE.len()], marker)
}

/// A group's marker at pixel `c` (for the legend; the series draw the same shapes).
pub(super) fn draw_marker(
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
pub(super) enum Swatch {
    Marker(RGBColor, Marker),
    Front,
    Reference,
}

/// Pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rect {
    pub(super) x0: i32,
    pub(super) y0: i32,
    pub(super) x1: i32,
    pub(super) y1: i32,
}

impl Rect {
    pub(super) fn around((x, y): BackendCoord, r: i32) -> Self {
        Rect { x0: x - r, y0: y - r, x1: x + r + 1, y1: y + r + 1 }
    }
    pub(super) fn intersects(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

/// Small rectangles along a polyline, for counting what a legend box would hide.
pub(super) fn sample_polyline(path: &[BackendCoord], out: &mut Vec<Rect>) {
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
