//! The document ([`Canvas`]), how a shape is painted ([`Paint`]), path data
//! ([`PathData`]) and world metres on the page ([`Frame`]).

use super::style;
use super::text::{escape, num, px};
use crate::geom::{Rect, Vec2};
use std::fmt::Write;

/// How a shape is painted. Unset fields are left out of the element, so SVG's
/// defaults apply (black fill, no stroke).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Paint {
    /// Fill colour, `none`, or a `url(#…)`.
    pub fill: Option<String>,
    /// Opacity of the fill, 0–1.
    pub fill_opacity: Option<f64>,
    /// Stroke colour.
    pub stroke: Option<String>,
    /// Stroke width in px.
    pub stroke_width: Option<f64>,
    /// Opacity of the stroke, 0–1.
    pub stroke_opacity: Option<f64>,
    /// A `stroke-dasharray` in px, e.g. `"6 3"`.
    pub dash: Option<String>,
    /// A class naming what the shape is (`agent`, `route`, …), for readers and
    /// for tests that pick shapes out of a picture.
    pub class: Option<String>,
}

impl Paint {
    /// Filled, no stroke.
    pub fn fill(colour: &str) -> Paint {
        Paint {
            fill: Some(colour.into()),
            ..Paint::default()
        }
    }
    /// Stroked, not filled.
    pub fn stroke(colour: &str, width_px: f64) -> Paint {
        Paint {
            fill: Some("none".into()),
            stroke: Some(colour.into()),
            stroke_width: Some(width_px),
            ..Paint::default()
        }
    }
    /// Filled and stroked.
    pub fn fill_stroke(fill: &str, stroke: &str, width_px: f64) -> Paint {
        Paint {
            fill: Some(fill.into()),
            stroke: Some(stroke.into()),
            stroke_width: Some(width_px),
            ..Paint::default()
        }
    }
    /// With a fill opacity.
    pub fn fill_opacity(mut self, o: f64) -> Paint {
        self.fill_opacity = Some(o);
        self
    }
    /// With a stroke opacity.
    pub fn stroke_opacity(mut self, o: f64) -> Paint {
        self.stroke_opacity = Some(o);
        self
    }
    /// With a dash pattern (empty: solid).
    pub fn dash(mut self, d: &str) -> Paint {
        self.dash = (!d.is_empty()).then(|| d.into());
        self
    }
    /// With a class.
    pub fn class(mut self, c: &str) -> Paint {
        self.class = Some(c.into());
        self
    }

    /// The attributes, each with a leading space.
    pub fn attrs(&self) -> String {
        let mut s = String::new();
        if let Some(c) = &self.class {
            let _ = write!(s, r#" class="{}""#, escape(c));
        }
        if let Some(f) = &self.fill {
            let _ = write!(s, r#" fill="{}""#, escape(f));
        }
        if let Some(o) = self.fill_opacity {
            let _ = write!(s, r#" fill-opacity="{}""#, num(o));
        }
        if let Some(c) = &self.stroke {
            let _ = write!(s, r#" stroke="{}""#, escape(c));
        }
        if let Some(w) = self.stroke_width {
            let _ = write!(s, r#" stroke-width="{}""#, num(w));
        }
        if let Some(o) = self.stroke_opacity {
            let _ = write!(s, r#" stroke-opacity="{}""#, num(o));
        }
        if let Some(d) = &self.dash {
            let _ = write!(s, r#" stroke-dasharray="{}""#, escape(d));
        }
        s
    }
}

/// Path data in page pixels, written as it is built.
#[derive(Clone, Debug, Default)]
pub struct PathData(String);

impl PathData {
    /// An empty path.
    pub fn new() -> PathData {
        PathData::default()
    }
    /// Starts a sub-path at `p`.
    pub fn move_to(&mut self, p: (f64, f64)) -> &mut PathData {
        let _ = write!(self.0, "M{},{}", px(p.0), px(p.1));
        self
    }
    /// A straight line to `p`.
    pub fn line_to(&mut self, p: (f64, f64)) -> &mut PathData {
        let _ = write!(self.0, "L{},{}", px(p.0), px(p.1));
        self
    }
    /// A move to the first point and lines through the rest.
    pub fn polyline(&mut self, pts: impl IntoIterator<Item = (f64, f64)>) -> &mut PathData {
        for (i, p) in pts.into_iter().enumerate() {
            if i == 0 {
                self.move_to(p);
            } else {
                self.line_to(p);
            }
        }
        self
    }
    /// An axis-aligned rectangle as a closed sub-path.
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64) -> &mut PathData {
        let _ = write!(
            self.0,
            "M{} {}h{}v{}h-{}z",
            px(x),
            px(y),
            px(w),
            px(h),
            px(w)
        );
        self
    }
    /// Closes the current sub-path.
    pub fn close(&mut self) -> &mut PathData {
        self.0.push('Z');
        self
    }
    /// Whether nothing was written.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    /// The path data as written.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

/// An SVG document being drawn: page size in px, the page background, the font.
pub struct Canvas {
    out: String,
    width_px: f64,
    height_px: f64,
}

impl Canvas {
    /// A page of `width_px` × `height_px` (rounded to whole pixels), painted
    /// [`style::PAGE`].
    pub fn new(width_px: f64, height_px: f64) -> Canvas {
        let (w, h) = (width_px.round().max(1.0), height_px.round().max(1.0));
        let mut out = String::with_capacity(1 << 15);
        let _ = writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="{}" font-size="{}">"#,
            style::FONT_FAMILY,
            num(style::BODY_PX)
        );
        let _ = writeln!(
            out,
            r#"<rect class="page" x="0" y="0" width="{w:.0}" height="{h:.0}" fill="{}"/>"#,
            style::PAGE
        );
        Canvas {
            out,
            width_px: w,
            height_px: h,
        }
    }

    /// Page width (px).
    pub fn width_px(&self) -> f64 {
        self.width_px
    }
    /// Page height (px).
    pub fn height_px(&self) -> f64 {
        self.height_px
    }

    /// Writes markup as it is: `<defs>`, patterns, clip paths — what only one
    /// picture needs. The caller escapes what it writes.
    pub fn raw(&mut self, markup: &str) {
        self.out.push_str(markup);
        if !markup.ends_with('\n') {
            self.out.push('\n');
        }
    }

    /// Opens a group; `attrs` are written as they are (e.g. `class="routes"
    /// clip-path="url(#world)"`).
    pub fn open_group(&mut self, attrs: &str) {
        if attrs.is_empty() {
            self.out.push_str("<g>\n");
        } else {
            let _ = writeln!(self.out, "<g {attrs}>");
        }
    }
    /// A tooltip for the innermost open group (an SVG `<title>`), escaped.
    pub fn tooltip(&mut self, text: &str) {
        let _ = writeln!(self.out, "<title>{}</title>", escape(text));
    }

    /// Closes the innermost open group.
    pub fn close_group(&mut self) {
        self.out.push_str("</g>\n");
    }

    /// A circle centred at `c` (px).
    pub fn circle(&mut self, c: (f64, f64), r_px: f64, paint: &Paint) {
        let _ = writeln!(
            self.out,
            r#"<circle cx="{}" cy="{}" r="{}"{}/>"#,
            px(c.0),
            px(c.1),
            px(r_px),
            paint.attrs()
        );
    }

    /// A line from `a` to `b` (px).
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), paint: &Paint) {
        let _ = writeln!(
            self.out,
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}"{}/>"#,
            px(a.0),
            px(a.1),
            px(b.0),
            px(b.1),
            paint.attrs()
        );
    }

    /// An axis-aligned rectangle (px).
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, paint: &Paint) {
        let _ = writeln!(
            self.out,
            r#"<rect x="{}" y="{}" width="{}" height="{}"{}/>"#,
            px(x),
            px(y),
            px(w),
            px(h),
            paint.attrs()
        );
    }

    /// An open line through `pts`; nothing when there are fewer than two.
    pub fn polyline(&mut self, pts: impl IntoIterator<Item = (f64, f64)>, paint: &Paint) {
        self.points("polyline", pts, paint, 2);
    }

    /// A closed shape through `pts`; nothing when there are fewer than three.
    pub fn polygon(&mut self, pts: impl IntoIterator<Item = (f64, f64)>, paint: &Paint) {
        self.points("polygon", pts, paint, 3);
    }

    fn points(
        &mut self,
        tag: &str,
        pts: impl IntoIterator<Item = (f64, f64)>,
        paint: &Paint,
        min: usize,
    ) {
        let mut list = String::new();
        let mut n = 0;
        for p in pts {
            if n > 0 {
                list.push(' ');
            }
            let _ = write!(list, "{},{}", px(p.0), px(p.1));
            n += 1;
        }
        if n >= min {
            let _ = writeln!(self.out, r#"<{tag} points="{list}"{}/>"#, paint.attrs());
        }
    }

    /// A path from [`PathData`]; nothing when it is empty.
    pub fn path(&mut self, d: &PathData, paint: &Paint) {
        if !d.is_empty() {
            let _ = writeln!(self.out, r#"<path d="{}"{}/>"#, d.as_str(), paint.attrs());
        }
    }

    /// Text at `(x, y)` (the baseline), escaped. `attrs` are extra attributes
    /// written as they are (`text-anchor="end"`, `font-weight="bold"`, …).
    pub fn text(&mut self, at: (f64, f64), size_px: f64, colour: &str, attrs: &str, text: &str) {
        let sep = if attrs.is_empty() { "" } else { " " };
        let _ = writeln!(
            self.out,
            r#"<text x="{}" y="{}" font-size="{}" fill="{colour}"{sep}{attrs}>{}</text>"#,
            px(at.0),
            px(at.1),
            num(size_px),
            escape(text)
        );
    }

    /// Text turned 90° anticlockwise about `(x, y)`, centred there: a y-axis label.
    pub fn text_up(&mut self, at: (f64, f64), size_px: f64, colour: &str, text: &str) {
        let _ = writeln!(
            self.out,
            r#"<text x="{x}" y="{y}" font-size="{}" fill="{colour}" text-anchor="middle" transform="rotate(-90 {x} {y})">{}</text>"#,
            num(size_px),
            escape(text),
            x = px(at.0),
            y = px(at.1),
        );
    }

    /// The picture's title line.
    pub fn title(&mut self, at: (f64, f64), text: &str) {
        self.text(at, style::TITLE_PX, style::INK, r#"class="title""#, text);
    }

    /// A caption line under or beside what is drawn.
    pub fn caption(&mut self, at: (f64, f64), text: &str) {
        self.text(
            at,
            style::SMALL_PX,
            style::INK_SOFT,
            r#"class="caption""#,
            text,
        );
    }

    /// The finished document.
    pub fn finish(mut self) -> String {
        self.out.push_str("</svg>\n");
        self.out
    }
}

/// World metres on the page: a world box drawn at a fixed scale with its corner
/// at a page position. With `y_up` the world's y grows up the page (tracks,
/// formations, transforms); without, down the page (the table and its scenes).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Frame {
    /// The world box drawn (m).
    pub world: Rect,
    /// Scale (px per m).
    pub px_per_m: f64,
    /// Page x of the box's left edge (px).
    pub left_px: f64,
    /// Page y of the box's top edge (px).
    pub top_px: f64,
    /// Whether world y grows up the page.
    pub y_up: bool,
}

impl Frame {
    /// The page x of world x (m).
    pub fn x(&self, x_m: f64) -> f64 {
        self.left_px + (x_m - self.world.min[0]) * self.px_per_m
    }
    /// The page y of world y (m).
    pub fn y(&self, y_m: f64) -> f64 {
        if self.y_up {
            self.top_px + (self.world.max[1] - y_m) * self.px_per_m
        } else {
            self.top_px + (y_m - self.world.min[1]) * self.px_per_m
        }
    }
    /// The page point of a world point.
    pub fn pt(&self, p: Vec2) -> (f64, f64) {
        (self.x(p.x), self.y(p.y))
    }
    /// A world length (m) in px.
    pub fn len(&self, m: f64) -> f64 {
        m * self.px_per_m
    }
    /// Width of the drawn box (px).
    pub fn width_px(&self) -> f64 {
        self.world.width() * self.px_per_m
    }
    /// Height of the drawn box (px).
    pub fn height_px(&self) -> f64 {
        self.world.height() * self.px_per_m
    }
    /// The world point under a page point (the inverse of [`Frame::pt`]).
    pub fn world_of(&self, p: (f64, f64)) -> Vec2 {
        let x = self.world.min[0] + (p.0 - self.left_px) / self.px_per_m;
        let y = if self.y_up {
            self.world.max[1] - (p.1 - self.top_px) / self.px_per_m
        } else {
            self.world.min[1] + (p.1 - self.top_px) / self.px_per_m
        };
        Vec2::new(x, y)
    }
}

/// The smallest box holding every point, grown by `margin_m`; `None` when there is
/// no finite point.
pub fn extent<'a>(pts: impl IntoIterator<Item = &'a Vec2>, margin_m: f64) -> Option<Rect> {
    let mut lo = Vec2::repeat(f64::INFINITY);
    let mut hi = Vec2::repeat(f64::NEG_INFINITY);
    for p in pts {
        if p.x.is_finite() && p.y.is_finite() {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
    }
    (lo.x <= hi.x).then(|| Rect {
        min: [lo.x - margin_m, lo.y - margin_m],
        max: [hi.x + margin_m, hi.y + margin_m],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(y_up: bool) -> Frame {
        Frame {
            world: Rect {
                min: [-1.0, 2.0],
                max: [3.0, 4.0],
            },
            px_per_m: 50.0,
            left_px: 10.0,
            top_px: 20.0,
            y_up,
        }
    }

    #[test]
    fn a_frame_puts_the_world_corners_on_the_page_corners() {
        let f = frame(false);
        assert_eq!(f.pt(Vec2::new(-1.0, 2.0)), (10.0, 20.0));
        assert_eq!(f.pt(Vec2::new(3.0, 4.0)), (210.0, 120.0));
        let g = frame(true);
        assert_eq!(g.pt(Vec2::new(-1.0, 4.0)), (10.0, 20.0));
        assert_eq!(g.pt(Vec2::new(3.0, 2.0)), (210.0, 120.0));
        assert_eq!((f.width_px(), f.height_px()), (200.0, 100.0));
    }

    #[test]
    fn world_of_inverts_pt() {
        for f in [frame(false), frame(true)] {
            for p in [
                Vec2::new(0.3, 2.7),
                Vec2::new(-1.0, 4.0),
                Vec2::new(2.9, 3.1),
            ] {
                let q = f.world_of(f.pt(p));
                assert!((q - p).norm() < 1e-12, "{p:?} → {q:?}");
            }
        }
    }

    #[test]
    fn a_canvas_writes_one_document_with_its_shapes() {
        let mut c = Canvas::new(100.4, 50.0);
        c.circle((1.0, 2.0), 3.0, &Paint::fill("#123").class("agent"));
        c.polyline([(0.0, 0.0)], &Paint::stroke("#000", 1.0));
        c.polyline(
            [(0.0, 0.0), (1.25, 2.0)],
            &Paint::stroke("#000", 1.0).dash("6 3"),
        );
        c.polygon([(0.0, 0.0), (1.0, 0.0)], &Paint::fill("#000"));
        c.text((5.0, 6.0), 13.0, "#222", "", "a < b");
        let mut d = PathData::new();
        d.polyline([(0.0, 0.0), (2.0, 0.0)]).close();
        c.path(&d, &Paint::stroke("#111", 0.5));
        let s = c.finish();
        assert!(s.starts_with(r#"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="50""#));
        assert!(s.contains(r##"<circle cx="1" cy="2" r="3" class="agent" fill="#123"/>"##));
        assert_eq!(
            s.matches("<polyline").count(),
            1,
            "a one-point line is not drawn"
        );
        assert!(s.contains(r#"points="0,0 1.2,2""#));
        assert!(s.contains(r#"stroke-dasharray="6 3""#));
        assert!(!s.contains("<polygon"), "a two-point polygon is not drawn");
        assert!(s.contains(">a &lt; b</text>"));
        assert!(s.contains(r#"d="M0,0L2,0Z""#));
        assert!(s.ends_with("</svg>\n"));
    }

    #[test]
    fn extent_skips_non_finite_points_and_adds_the_margin() {
        let pts = [
            Vec2::new(1.0, 2.0),
            Vec2::new(f64::NAN, 0.0),
            Vec2::new(3.0, -1.0),
        ];
        let r = extent(&pts, 0.5).unwrap();
        assert_eq!((r.min, r.max), ([0.5, -1.5], [3.5, 2.5]));
        assert!(extent(&[Vec2::new(f64::INFINITY, 0.0)], 0.5).is_none());
    }
}
