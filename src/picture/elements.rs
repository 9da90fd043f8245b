//! The things several pictures draw, in world metres through a [`Frame`]: agents,
//! tracks, hulls, meshes, obstacles; and the furniture around them: metre axes, a
//! scale bar, chart axes, legend swatches and colour bars.

use super::canvas::{Canvas, Frame, Paint, PathData};
use super::scale::{nice_step, ticks};
use super::style;
use super::text::num;
use crate::geom::Vec2;

/// Agents as dots of radius `r_px`.
pub fn agents(c: &mut Canvas, f: &Frame, pts: &[Vec2], r_px: f64, paint: &Paint) {
    for p in pts {
        c.circle(f.pt(*p), r_px, paint);
    }
}

/// A track (a path walked) as an open line.
pub fn track(c: &mut Canvas, f: &Frame, pts: &[Vec2], paint: &Paint) {
    c.polyline(pts.iter().map(|p| f.pt(*p)), paint);
}

/// A closed outline: a hull, a formation's outline, a polygonal obstacle.
pub fn hull(c: &mut Canvas, f: &Frame, pts: &[Vec2], paint: &Paint) {
    c.polygon(pts.iter().map(|p| f.pt(*p)), paint);
}

/// A disc obstacle (or an agent drawn at its size): centre and radius in metres.
pub fn disc(c: &mut Canvas, f: &Frame, centre: Vec2, radius_m: f64, paint: &Paint) {
    c.circle(f.pt(centre), f.len(radius_m), paint);
}

/// A triangle mesh, one closed triangle per face. Faces naming a missing vertex
/// are skipped.
pub fn mesh(c: &mut Canvas, f: &Frame, vertices: &[Vec2], triangles: &[[u32; 3]], paint: &Paint) {
    for t in triangles {
        let corners: Option<Vec<(f64, f64)>> = t
            .iter()
            .map(|&i| vertices.get(i as usize).map(|p| f.pt(*p)))
            .collect();
        if let Some(corners) = corners {
            c.polygon(corners, paint);
        }
    }
}

/// Axes in metres around a frame: its outline, ticks every [`nice_step`] of the
/// longer side (about `n` of them) with labels under and left of it, and the axis
/// names `x (m)`, `y (m)`.
pub fn metre_axes(c: &mut Canvas, f: &Frame, n: usize) {
    let w = f.world;
    let step = nice_step(w.width().max(w.height()), n);
    let label = |v: f64| {
        let v = if v.abs() < step * 1e-6 { 0.0 } else { v };
        if step >= 1.0 {
            format!("{v:.0}")
        } else {
            format!("{v:.1}")
        }
    };
    let axis = Paint::stroke(style::AXIS, style::LINE_PX);
    let (left, top) = (f.left_px, f.top_px);
    let (right, bottom) = (left + f.width_px(), top + f.height_px());
    c.open_group(r#"class="axes""#);
    c.rect(left, top, f.width_px(), f.height_px(), &axis);
    for x in ticks(w.min[0], w.max[0], step) {
        let px = f.x(x);
        c.line((px, bottom), (px, bottom + 5.0), &axis);
        c.text(
            (px, bottom + 19.0),
            style::SMALL_PX,
            style::AXIS,
            r#"text-anchor="middle""#,
            &label(x),
        );
    }
    for y in ticks(w.min[1], w.max[1], step) {
        let py = f.y(y);
        c.line((left - 5.0, py), (left, py), &axis);
        c.text(
            (left - 8.0, py + 4.0),
            style::SMALL_PX,
            style::AXIS,
            r#"text-anchor="end""#,
            &label(y),
        );
    }
    c.text(
        ((left + right) / 2.0, bottom + 34.0),
        style::BODY_PX,
        style::INK,
        r#"text-anchor="middle""#,
        "x (m)",
    );
    c.text_up(
        (14.0, (top + bottom) / 2.0),
        style::BODY_PX,
        style::INK,
        "y (m)",
    );
    c.close_group();
}

/// A scale bar of two alternating halves at `(x, y)` (px), a quarter of the
/// frame's width rounded to a 1–2–5 length, labelled 0, half and the length.
pub fn scale_bar(c: &mut Canvas, f: &Frame, at: (f64, f64)) {
    let len_m = nice_step(f.world.width() / 4.0, 1);
    let half_px = f.len(len_m / 2.0);
    let (x, y) = at;
    c.open_group(r#"class="scale-bar""#);
    c.rect(
        x,
        y,
        half_px,
        6.0,
        &Paint::fill_stroke(style::INK, style::INK, 1.0),
    );
    c.rect(
        x + half_px,
        y,
        half_px,
        6.0,
        &Paint::fill_stroke(style::PAGE, style::INK, 1.0),
    );
    let size = style::SMALL_PX;
    c.text((x, y + 19.0), size, style::INK, "", "0");
    c.text(
        (x + half_px, y + 19.0),
        size,
        style::INK,
        r#"text-anchor="middle""#,
        &num(len_m / 2.0),
    );
    c.text(
        (x + 2.0 * half_px, y + 19.0),
        size,
        style::INK,
        r#"text-anchor="end""#,
        &format!("{} m", num(len_m)),
    );
    c.close_group();
}

/// A chart's plotting area: page box and the value ranges it shows. `x` runs
/// left to right from `x_range.0`, `y` bottom to top from `y_range.0`.
#[derive(Copy, Clone, Debug)]
pub struct Chart {
    /// Page box of the plotting area: left, top, right, bottom (px).
    pub left: f64,
    /// Top edge (px).
    pub top: f64,
    /// Right edge (px).
    pub right: f64,
    /// Bottom edge (px).
    pub bottom: f64,
    /// Values at the left and right edges.
    pub x_range: (f64, f64),
    /// Values at the bottom and top edges.
    pub y_range: (f64, f64),
}

impl Chart {
    /// The page x of value `v`.
    pub fn x(&self, v: f64) -> f64 {
        self.left
            + (self.right - self.left) * (v - self.x_range.0) / (self.x_range.1 - self.x_range.0)
    }
    /// The page y of value `v`.
    pub fn y(&self, v: f64) -> f64 {
        self.bottom
            - (self.bottom - self.top) * (v - self.y_range.0) / (self.y_range.1 - self.y_range.0)
    }

    /// The panel: a bold heading centred `heading_dy` px above the area, grid
    /// lines at the y ticks, tick marks at the x ticks, both labelled (`x_labels`,
    /// `y_labels` give each tick's text), the left and bottom axis lines, and the
    /// axis names.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_axes(
        &self,
        c: &mut Canvas,
        heading: (&str, f64),
        x_ticks: &[(f64, String)],
        y_ticks: &[(f64, String)],
        x_name: &str,
        y_name: (&str, f64),
    ) {
        let mid = 0.5 * (self.left + self.right);
        c.text(
            (mid, self.top - heading.1),
            style::BODY_PX,
            style::INK,
            r#"text-anchor="middle" font-weight="bold""#,
            heading.0,
        );
        let grid = Paint::stroke(style::GRID, style::LINE_PX);
        let axis = Paint::stroke(style::AXIS, style::LINE_PX);
        for (v, label) in y_ticks {
            let y = self.y(*v);
            c.line((self.left, y), (self.right, y), &grid);
            c.text(
                (self.left - 5.0, y + 4.0),
                style::SMALL_PX,
                style::AXIS,
                r#"text-anchor="end""#,
                label,
            );
        }
        for (v, label) in x_ticks {
            let x = self.x(*v);
            c.line((x, self.bottom), (x, self.bottom + 4.0), &axis);
            c.text(
                (x, self.bottom + 17.0),
                style::SMALL_PX,
                style::AXIS,
                r#"text-anchor="middle""#,
                label,
            );
        }
        let mut d = PathData::new();
        d.polyline([
            (self.left, self.top),
            (self.left, self.bottom),
            (self.right, self.bottom),
        ]);
        c.path(&d, &axis);
        c.text(
            (mid, self.bottom + 34.0),
            style::SMALL_PX,
            style::INK,
            r#"text-anchor="middle""#,
            x_name,
        );
        c.text_up(
            (y_name.1, 0.5 * (self.top + self.bottom)),
            style::SMALL_PX,
            style::INK,
            y_name.0,
        );
    }
}

/// A legend swatch: what a key shows beside its label.
#[derive(Clone, Debug)]
pub enum Swatch<'a> {
    /// A line `len_px` long.
    Line {
        /// How it is drawn.
        paint: &'a Paint,
        /// Its length (px).
        len_px: f64,
    },
    /// A dot.
    Dot {
        /// How it is drawn.
        paint: &'a Paint,
        /// Its radius (px).
        r_px: f64,
    },
    /// A square patch.
    Patch {
        /// How it is drawn.
        paint: &'a Paint,
        /// Its side (px).
        size_px: f64,
    },
}

/// One legend entry at `(x, y)` (the swatch's left edge, the text's middle line)
/// with its label `gap_px` after the swatch; returns the x after the label's
/// start (where a next entry in a row may go is up to the caller).
pub fn legend_entry(
    c: &mut Canvas,
    at: (f64, f64),
    swatch: &Swatch,
    gap_px: f64,
    size_px: f64,
    label: &str,
) -> f64 {
    let (x, y) = at;
    let w = match swatch {
        Swatch::Line { paint, len_px } => {
            c.line((x, y), (x + len_px, y), paint);
            *len_px
        }
        Swatch::Dot { paint, r_px } => {
            c.circle((x + r_px, y), *r_px, paint);
            2.0 * r_px
        }
        Swatch::Patch { paint, size_px } => {
            c.rect(x, y - size_px / 2.0, *size_px, *size_px, paint);
            *size_px
        }
    };
    let tx = x + w + gap_px;
    c.text((tx, y + size_px / 3.0), size_px, style::INK, "", label);
    tx
}

/// Which way a colour bar runs from `colour(0)` to `colour(1)`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Left to right.
    Across,
    /// Top to bottom.
    Down,
}

/// A colour bar of `bands` equal blocks from `colour(0)` to `colour(1)`, with the
/// bar's box; `at` is its top left corner and `size` its width and height (px).
pub fn colour_bar(
    c: &mut Canvas,
    at: (f64, f64),
    size: (f64, f64),
    bands: usize,
    direction: Direction,
    colour: &dyn Fn(f64) -> String,
) {
    let (x, y) = at;
    let (w, h) = size;
    let n = bands.max(1);
    c.open_group(r#"class="colour-bar" shape-rendering="crispEdges""#);
    for k in 0..n {
        let u = (k as f64 + 0.5) / n as f64;
        let paint = Paint::fill(&colour(u));
        match direction {
            Direction::Across => {
                let bw = w / n as f64;
                c.rect(x + k as f64 * bw, y, bw, h, &paint);
            }
            Direction::Down => {
                let bh = h / n as f64;
                c.rect(x, y + k as f64 * bh, w, bh, &paint);
            }
        }
    }
    c.close_group();
    c.rect(x, y, w, h, &Paint::stroke(style::INK, 0.8));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Rect;

    fn frame() -> Frame {
        Frame {
            world: Rect {
                min: [0.0, 0.0],
                max: [4.0, 2.0],
            },
            px_per_m: 100.0,
            left_px: 50.0,
            top_px: 40.0,
            y_up: true,
        }
    }

    #[test]
    fn a_mesh_draws_one_triangle_per_face_and_skips_bad_faces() {
        let mut c = Canvas::new(500.0, 300.0);
        let v = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ];
        mesh(
            &mut c,
            &frame(),
            &v,
            &[[0, 1, 2], [0, 1, 7]],
            &Paint::stroke("#000", 1.0),
        );
        let s = c.finish();
        assert_eq!(s.matches("<polygon").count(), 1);
        // y up: world (0, 1) is 1 m below the top edge at y = 2 m.
        assert!(s.contains(r#"points="50,240 150,240 50,140""#), "{s}");
    }

    #[test]
    fn metre_axes_label_every_step_inside_the_frame() {
        let mut c = Canvas::new(500.0, 300.0);
        metre_axes(&mut c, &frame(), 4);
        let s = c.finish();
        // Steps of 1 m over 4 m: x at 0..4, y at 0..2.
        for l in ["0", "1", "2", "3", "4"] {
            assert!(s.contains(&format!(">{l}</text>")), "{l}");
        }
        assert_eq!(s.matches("<line").count(), 5 + 3);
        assert!(s.contains(">x (m)</text>") && s.contains(">y (m)</text>"));
    }

    #[test]
    fn a_chart_maps_its_ranges_onto_its_box() {
        let ch = Chart {
            left: 10.0,
            top: 20.0,
            right: 110.0,
            bottom: 220.0,
            x_range: (0.0, 10.0),
            y_range: (0.0, 2.0),
        };
        assert_eq!((ch.x(0.0), ch.x(10.0), ch.x(5.0)), (10.0, 110.0, 60.0));
        assert_eq!((ch.y(0.0), ch.y(2.0), ch.y(0.5)), (220.0, 20.0, 170.0));
    }

    #[test]
    fn a_colour_bar_has_one_block_per_band_and_a_box() {
        let mut c = Canvas::new(100.0, 50.0);
        colour_bar(
            &mut c,
            (0.0, 0.0),
            (60.0, 10.0),
            6,
            Direction::Across,
            &|u| super::super::scale::heat(u),
        );
        let s = c.finish();
        assert_eq!(s.matches("<rect").count(), 1 + 6 + 1);
    }
}
