//! What an SVG picture draws, without how: every shape in page coordinates.
//!
//! The document is parsed with `roxmltree`; path data, point lists, lengths and
//! transform lists with `svgtypes`. Every `transform` of an element and of all its
//! ancestors is applied (and the root's `viewBox`, mapped onto its `width` and
//! `height` as `preserveAspectRatio="xMidYMid meet"` does), so a picture drawn in
//! world metres inside `<g transform="matrix(...)">` gives the same page points as
//! one drawn in pixels.
//!
//! Shapes are sorted into kinds by what they are on the page, not by the element
//! that drew them:
//!
//! * [`Kind::Circle`]: `<circle>` and `<ellipse>`: the centre, then the two radii
//!   (the lengths of the transformed x and y radius vectors).
//! * [`Kind::Rect`]: any closed ring of four vertices whose edges are horizontal and
//!   vertical on the page: a `<rect>`, a `<polygon>` or a path's `h`/`v` subpath
//!   alike. The corner with the smallest x and y, then the one with the largest.
//! * [`Kind::Line`]: every other vertex list: `<line>`, `<polyline>`, `<polygon>`,
//!   each subpath of a `<path>` (a path of many `M` subpaths is many lines). Curves
//!   contribute their control points and end point, `S`/`T` with the reflected
//!   control point written out; arcs their centre and end point. A closed list
//!   (`<polygon>`, `Z`) is a ring: its repeated closing vertex is dropped.
//! * [`Kind::Text`]: `<text>`: its anchor (`x`, `y`, or its first positioned
//!   `<tspan>`'s) and its text with whitespace collapsed and every number rounded
//!   to 3 decimals, so `1.50` and `1.5` read the same.
//! * [`Kind::Title`]: the text of `<title>` (a tooltip), without position.
//!
//! Ignored: everything inside `<defs>`, `<clipPath>`, `<pattern>`, `<marker>`,
//! `<mask>`, `<symbol>` and gradients (except what a `<use>` places), `<style>`,
//! `<script>`, `<metadata>`, `<desc>`, and every style attribute (fill, stroke,
//! widths, fonts, opacity, classes, ids, `clip-path`, `display`).

use roxmltree::{Document, Node, ParsingOptions};
use svgtypes::{Length, LengthUnit, PathParser, PathSegment, PointsParser};
use svgtypes::{TransformListParser, TransformListToken, ViewBox};

/// Two numbers closer than this are the same number where a shape's structure is
/// read (a ring's repeated closing vertex, a rectangle's horizontal and vertical
/// edges): far below any drawn precision, above floating-point noise.
const SAME_NUMBER: f64 = 1e-6;

/// A page point (x right, y down, in the root's user units mapped to its size).
pub type Point = (f64, f64);

/// An affine map `x' = a x + c y + e`, `y' = b x + d y + f`, as SVG writes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
    pub e: f64,
    pub f: f64,
}

impl Affine {
    pub const IDENTITY: Affine = Affine {
        a: 1.0,
        b: 0.0,
        c: 0.0,
        d: 1.0,
        e: 0.0,
        f: 0.0,
    };

    pub fn translate(tx: f64, ty: f64) -> Affine {
        Affine {
            e: tx,
            f: ty,
            ..Affine::IDENTITY
        }
    }

    pub fn scale(sx: f64, sy: f64) -> Affine {
        Affine {
            a: sx,
            d: sy,
            ..Affine::IDENTITY
        }
    }

    /// `self` after `inner`: `self.then_inner(inner).apply(p) == self.apply(inner.apply(p))`.
    pub fn then_inner(&self, inner: &Affine) -> Affine {
        Affine {
            a: self.a * inner.a + self.c * inner.b,
            b: self.b * inner.a + self.d * inner.b,
            c: self.a * inner.c + self.c * inner.d,
            d: self.b * inner.c + self.d * inner.d,
            e: self.a * inner.e + self.c * inner.f + self.e,
            f: self.b * inner.e + self.d * inner.f + self.f,
        }
    }

    pub fn apply(&self, (x, y): Point) -> Point {
        (
            self.a * x + self.c * y + self.e,
            self.b * x + self.d * y + self.f,
        )
    }

    /// The linear part only (a radius, a difference of two points).
    fn apply_vector(&self, (x, y): Point) -> Point {
        (self.a * x + self.c * y, self.b * x + self.d * y)
    }

    /// An SVG `transform` attribute (`matrix`, `translate`, `scale`, `rotate` with
    /// or without a centre, `skewX`, `skewY`, in a list applied right to left).
    pub fn parse(text: &str) -> Result<Affine, String> {
        let mut m = Affine::IDENTITY;
        for token in TransformListParser::from(text) {
            let t = match token.map_err(|e| format!("transform {text:?}: {e}"))? {
                TransformListToken::Matrix { a, b, c, d, e, f } => Affine { a, b, c, d, e, f },
                TransformListToken::Translate { tx, ty } => Affine::translate(tx, ty),
                TransformListToken::Scale { sx, sy } => Affine::scale(sx, sy),
                TransformListToken::Rotate { angle } => {
                    let (s, c) = angle.to_radians().sin_cos();
                    Affine {
                        a: c,
                        b: s,
                        c: -s,
                        d: c,
                        e: 0.0,
                        f: 0.0,
                    }
                }
                TransformListToken::SkewX { angle } => Affine {
                    c: angle.to_radians().tan(),
                    ..Affine::IDENTITY
                },
                TransformListToken::SkewY { angle } => Affine {
                    b: angle.to_radians().tan(),
                    ..Affine::IDENTITY
                },
            };
            m = m.then_inner(&t);
        }
        Ok(m)
    }
}

/// What kind of thing a shape is on the page (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    Circle,
    Rect,
    Line,
    Text,
    Title,
}

impl Kind {
    pub const ALL: [Kind; 5] = [
        Kind::Circle,
        Kind::Rect,
        Kind::Line,
        Kind::Text,
        Kind::Title,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Circle => "circle",
            Kind::Rect => "rect",
            Kind::Line => "line",
            Kind::Text => "text",
            Kind::Title => "title",
        }
    }
}

/// One drawn shape, in page coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    pub kind: Kind,
    /// Circle: the centre, then `(rx, ry)`. Rect: the min corner, then the max
    /// corner. Line: the vertices. Text: the anchor. Title: none.
    pub points: Vec<Point>,
    /// A line that is a ring (`<polygon>`, a subpath ended by `Z`).
    pub closed: bool,
    /// Text and title: the normalised text ([`normalise_text`]); otherwise empty.
    pub text: String,
    /// The element that drew it and its line in the document, for messages.
    pub element: &'static str,
    pub line: u32,
}

impl Shape {
    /// The point the comparison files a shape under: it moves by at most as much as
    /// the shape's points do (a circle's centre, a rect's min corner, a text's
    /// anchor, the mean of a line's vertices, which neither the direction a line is
    /// written in nor a ring's first vertex changes).
    pub fn key(&self) -> Point {
        match self.kind {
            Kind::Line => {
                let n = self.points.len().max(1) as f64;
                let (sx, sy) = self
                    .points
                    .iter()
                    .fold((0.0, 0.0), |(sx, sy), &(x, y)| (sx + x, sy + y));
                (sx / n, sy / n)
            }
            Kind::Title => (0.0, 0.0),
            _ => self.points.first().copied().unwrap_or((0.0, 0.0)),
        }
    }

    /// The shape as a message shows it: kind, coordinates (one decimal; at most 6
    /// vertices of a line), text, and where it was drawn.
    pub fn describe(&self) -> String {
        let p = |(x, y): Point| format!("({x:.2}, {y:.2})");
        let what = match self.kind {
            Kind::Circle => format!(
                "circle at {} r {:.2}{}",
                p(self.points[0]),
                self.points[1].0,
                if (self.points[1].0 - self.points[1].1).abs() > SAME_NUMBER {
                    format!(" × {:.2}", self.points[1].1)
                } else {
                    String::new()
                }
            ),
            Kind::Rect => format!("rect {} to {}", p(self.points[0]), p(self.points[1])),
            Kind::Line => {
                let n = self.points.len();
                let shown: Vec<String> = self.points.iter().take(6).map(|&q| p(q)).collect();
                format!(
                    "{} of {n} vertices: {}{}",
                    if self.closed { "ring" } else { "line" },
                    shown.join(" "),
                    if n > 6 { " …" } else { "" }
                )
            }
            Kind::Text => format!("text {:?} at {}", self.text, p(self.points[0])),
            Kind::Title => format!("title {:?}", self.text),
        };
        format!("{what} (<{}> on line {})", self.element, self.line)
    }
}

/// Every shape `svg` draws, in document order.
pub fn shapes(svg: &str) -> Result<Vec<Shape>, String> {
    let doc = Document::parse_with_options(
        svg,
        ParsingOptions {
            allow_dtd: true,
            ..ParsingOptions::default()
        },
    )
    .map_err(|e| format!("not XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "svg" {
        return Err(format!(
            "the root element is <{}>, not <svg>",
            root.tag_name().name()
        ));
    }
    let viewport = Viewport::of_root(root)?;
    let newlines = svg
        .bytes()
        .enumerate()
        .filter(|&(_, b)| b == b'\n')
        .map(|(i, _)| i)
        .collect();
    let mut walk = Walk {
        doc: &doc,
        newlines,
        viewport,
        out: Vec::new(),
        use_depth: 0,
    };
    let m = viewport.to_page.then_inner(&transform_of(root)?);
    walk.children(root, &m)?;
    Ok(walk.out)
}

/// The root's user space: its size (what percentages refer to) and its map onto
/// the page.
#[derive(Clone, Copy, Debug)]
struct Viewport {
    width: f64,
    height: f64,
    to_page: Affine,
}

impl Viewport {
    fn of_root(root: Node) -> Result<Viewport, String> {
        let view_box = match root.attribute("viewBox") {
            Some(v) => Some(
                v.parse::<ViewBox>()
                    .map_err(|e| format!("viewBox {v:?}: {e:?}"))?,
            ),
            None => None,
        };
        // The root's width and height in pixels, when given absolutely.
        let size = |name: &str| -> Result<Option<f64>, String> {
            match root.attribute(name) {
                None => Ok(None),
                Some(v) => {
                    let l = v
                        .parse::<Length>()
                        .map_err(|e| format!("<svg {name}={v:?}>: {e}"))?;
                    Ok(absolute_px(l))
                }
            }
        };
        let (w, h) = (size("width")?, size("height")?);
        Ok(match view_box {
            Some(vb) => {
                let to_page = match (w, h) {
                    (Some(w), Some(h)) if vb.w > 0.0 && vb.h > 0.0 => {
                        let s = (w / vb.w).min(h / vb.h);
                        let (tx, ty) = ((w - vb.w * s) / 2.0, (h - vb.h * s) / 2.0);
                        Affine::translate(tx - vb.x * s, ty - vb.y * s)
                            .then_inner(&Affine::scale(s, s))
                    }
                    _ => Affine::translate(-vb.x, -vb.y),
                };
                Viewport {
                    width: vb.w,
                    height: vb.h,
                    to_page,
                }
            }
            None => Viewport {
                width: w.unwrap_or(0.0),
                height: h.unwrap_or(0.0),
                to_page: Affine::IDENTITY,
            },
        })
    }
}

/// A length in pixels, or `None` for a percentage or a font-relative unit.
fn absolute_px(l: Length) -> Option<f64> {
    let per = match l.unit {
        LengthUnit::None | LengthUnit::Px => 1.0,
        LengthUnit::In => 96.0,
        LengthUnit::Cm => 96.0 / 2.54,
        LengthUnit::Mm => 96.0 / 25.4,
        LengthUnit::Pt => 96.0 / 72.0,
        LengthUnit::Pc => 16.0,
        LengthUnit::Em | LengthUnit::Ex | LengthUnit::Percent => return None,
    };
    Some(l.number * per)
}

/// Which way a percentage length is measured.
#[derive(Clone, Copy)]
enum Axis {
    X,
    Y,
    /// A radius: the normalised diagonal, as SVG defines it.
    Diagonal,
}

/// Elements whose content is never drawn where it stands.
fn is_not_drawn(name: &str) -> bool {
    matches!(
        name,
        "defs"
            | "clipPath"
            | "pattern"
            | "marker"
            | "mask"
            | "symbol"
            | "linearGradient"
            | "radialGradient"
            | "filter"
            | "style"
            | "script"
            | "metadata"
            | "desc"
    )
}

fn transform_of(node: Node) -> Result<Affine, String> {
    node.attribute("transform")
        .map_or(Ok(Affine::IDENTITY), Affine::parse)
}

struct Walk<'a, 'input> {
    doc: &'a Document<'input>,
    /// Byte offsets of the document's line ends, for line numbers.
    newlines: Vec<usize>,
    viewport: Viewport,
    out: Vec<Shape>,
    /// `<use>` inside `<use>`: a cycle guard.
    use_depth: usize,
}

impl Walk<'_, '_> {
    fn children(&mut self, node: Node, m: &Affine) -> Result<(), String> {
        for child in node.children().filter(Node::is_element) {
            self.element(child, m)?;
        }
        Ok(())
    }

    fn line_of(&self, node: Node) -> u32 {
        let before = self.newlines.partition_point(|&i| i < node.range().start);
        u32::try_from(before + 1).unwrap_or(u32::MAX)
    }

    /// A length attribute in user units (0 when absent).
    fn length(&self, node: Node, name: &str, axis: Axis) -> Result<f64, String> {
        let Some(v) = node.attribute(name) else {
            return Ok(0.0);
        };
        // Text positions may be lists: the first one is the anchor.
        let first = v
            .split(|c: char| c.is_whitespace() || c == ',')
            .find(|s| !s.is_empty())
            .unwrap_or("0");
        let l = first.parse::<Length>().map_err(|e| {
            format!(
                "<{} {name}={v:?}> on line {}: {e}",
                node.tag_name().name(),
                self.line_of(node)
            )
        })?;
        if l.unit == LengthUnit::Percent {
            let (w, h) = (self.viewport.width, self.viewport.height);
            let whole = match axis {
                Axis::X => w,
                Axis::Y => h,
                Axis::Diagonal => ((w * w + h * h) / 2.0).sqrt(),
            };
            return Ok(l.number / 100.0 * whole);
        }
        absolute_px(l).ok_or_else(|| {
            format!(
                "<{} {name}={v:?}> on line {}: a font-relative length",
                node.tag_name().name(),
                self.line_of(node)
            )
        })
    }

    fn push(&mut self, node: Node, kind: Kind, points: Vec<Point>, closed: bool, text: String) {
        self.out.push(Shape {
            kind,
            points,
            closed,
            text,
            element: element_name(node.tag_name().name()),
            line: self.line_of(node),
        });
    }

    /// A vertex list in page coordinates: a rect when it is one on the page, a
    /// line otherwise.
    fn push_vertices(&mut self, node: Node, mut points: Vec<Point>, closed: bool) {
        if closed && points.len() > 1 {
            let (first, last) = (points[0], points[points.len() - 1]);
            if (first.0 - last.0).abs() <= SAME_NUMBER && (first.1 - last.1).abs() <= SAME_NUMBER {
                points.pop();
            }
        }
        if closed {
            if let Some(r) = axis_aligned_rect(&points) {
                self.push(node, Kind::Rect, r.to_vec(), true, String::new());
                return;
            }
        }
        self.push(node, Kind::Line, points, closed, String::new());
    }

    fn element(&mut self, node: Node, parent: &Affine) -> Result<(), String> {
        let name = node.tag_name().name();
        if is_not_drawn(name) {
            return Ok(());
        }
        if name == "title" {
            let text = normalise_text(&all_text(node));
            self.push(node, Kind::Title, Vec::new(), false, text);
            return Ok(());
        }
        let m = parent.then_inner(&transform_of(node)?);
        let len = |w: &Self, attr: &str, axis: Axis| w.length(node, attr, axis);
        match name {
            "circle" | "ellipse" => {
                let c = (len(self, "cx", Axis::X)?, len(self, "cy", Axis::Y)?);
                let (rx, ry) = if name == "circle" {
                    let r = len(self, "r", Axis::Diagonal)?;
                    (r, r)
                } else {
                    (len(self, "rx", Axis::X)?, len(self, "ry", Axis::Y)?)
                };
                let radius = |v: Point| {
                    let (x, y) = m.apply_vector(v);
                    x.hypot(y)
                };
                let points = vec![m.apply(c), (radius((rx, 0.0)), radius((0.0, ry)))];
                self.push(node, Kind::Circle, points, false, String::new());
            }
            "line" => {
                let a = (len(self, "x1", Axis::X)?, len(self, "y1", Axis::Y)?);
                let b = (len(self, "x2", Axis::X)?, len(self, "y2", Axis::Y)?);
                self.push_vertices(node, vec![m.apply(a), m.apply(b)], false);
            }
            "polyline" | "polygon" => {
                let points = PointsParser::from(node.attribute("points").unwrap_or(""))
                    .map(|p| m.apply(p))
                    .collect();
                self.push_vertices(node, points, name == "polygon");
            }
            "rect" => {
                let (x, y) = (len(self, "x", Axis::X)?, len(self, "y", Axis::Y)?);
                let (w, h) = (len(self, "width", Axis::X)?, len(self, "height", Axis::Y)?);
                let corners = [(x, y), (x + w, y), (x + w, y + h), (x, y + h)];
                self.push_vertices(node, corners.iter().map(|&p| m.apply(p)).collect(), true);
            }
            "path" => {
                let d = node.attribute("d").unwrap_or("");
                let subpaths = subpaths(d)
                    .map_err(|e| format!("<path> on line {}: d {e}", self.line_of(node)))?;
                for (points, closed) in subpaths {
                    let points = points.into_iter().map(|p| m.apply(p)).collect();
                    self.push_vertices(node, points, closed);
                }
            }
            "text" => {
                let mut at = (len(self, "x", Axis::X)?, len(self, "y", Axis::Y)?);
                if node.attribute("x").is_none() && node.attribute("y").is_none() {
                    if let Some(span) = node.descendants().find(|n| {
                        n.tag_name().name() == "tspan"
                            && (n.attribute("x").is_some() || n.attribute("y").is_some())
                    }) {
                        at = (
                            self.length(span, "x", Axis::X)?,
                            self.length(span, "y", Axis::Y)?,
                        );
                    }
                }
                let text = normalise_text(&all_text(node));
                self.push(node, Kind::Text, vec![m.apply(at)], false, text);
                // A <title> inside a text is a tooltip of its own.
                for t in node
                    .descendants()
                    .filter(|n| n.tag_name().name() == "title")
                {
                    let text = normalise_text(&all_text(t));
                    self.push(t, Kind::Title, Vec::new(), false, text);
                }
            }
            "use" => {
                let href = node
                    .attribute("href")
                    .or_else(|| node.attribute(("http://www.w3.org/1999/xlink", "href")))
                    .unwrap_or("");
                let id = href.strip_prefix('#').unwrap_or(href);
                let target = self
                    .doc
                    .descendants()
                    .find(|n| n.attribute("id") == Some(id))
                    .ok_or_else(|| {
                        format!("<use> on line {}: no element {href:?}", self.line_of(node))
                    })?;
                if self.use_depth > 16 {
                    return Err(format!(
                        "<use> on line {}: nested too deep",
                        self.line_of(node)
                    ));
                }
                let at = Affine::translate(len(self, "x", Axis::X)?, len(self, "y", Axis::Y)?);
                let m = m.then_inner(&at);
                self.use_depth += 1;
                // A symbol or a group placed by <use> is drawn there, whatever holds it.
                let r = if matches!(target.tag_name().name(), "symbol" | "g" | "svg") {
                    let m = m.then_inner(&transform_of(target)?);
                    self.children(target, &m)
                } else {
                    self.element(target, &m)
                };
                self.use_depth -= 1;
                r?;
            }
            "svg" => {
                // A nested viewport: placed at x, y (its own viewBox scaling is not
                // applied; the pictures have none).
                let at = Affine::translate(len(self, "x", Axis::X)?, len(self, "y", Axis::Y)?);
                self.children(node, &m.then_inner(&at))?;
            }
            "image" | "foreignObject" => {}
            // g, a, switch and anything unknown: a container.
            _ => self.children(node, &m)?,
        }
        Ok(())
    }
}

/// The element names the shapes can come from, as `'static` strings.
fn element_name(name: &str) -> &'static str {
    match name {
        "circle" => "circle",
        "ellipse" => "ellipse",
        "line" => "line",
        "polyline" => "polyline",
        "polygon" => "polygon",
        "rect" => "rect",
        "path" => "path",
        "text" => "text",
        "title" => "title",
        _ => "element",
    }
}

/// The four vertices of a ring, when its edges are horizontal and vertical in turn:
/// its min and max corners.
fn axis_aligned_rect(points: &[Point]) -> Option<[Point; 2]> {
    if points.len() != 4 {
        return None;
    }
    let same = |a: f64, b: f64| (a - b).abs() <= SAME_NUMBER;
    let edge = |i: usize| {
        let (p, q) = (points[i], points[(i + 1) % 4]);
        (same(p.0, q.0), same(p.1, q.1))
    };
    // Either edges 0 and 2 horizontal and 1 and 3 vertical, or the other way round.
    let horizontal_first = (0..4).all(|i| if i % 2 == 0 { edge(i).1 } else { edge(i).0 });
    let vertical_first = (0..4).all(|i| if i % 2 == 0 { edge(i).0 } else { edge(i).1 });
    if !(horizontal_first || vertical_first) {
        return None;
    }
    let (mut lo, mut hi) = (points[0], points[0]);
    for &(x, y) in points {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    Some([lo, hi])
}

/// The subpaths of path data with every command made absolute: each subpath's
/// vertices (curves: control points and end point; arcs: centre and end point)
/// and whether `Z` closed it. A subpath of a lone `M` draws nothing and is left out.
pub fn subpaths(d: &str) -> Result<Vec<(Vec<Point>, bool)>, String> {
    let mut out: Vec<(Vec<Point>, bool)> = Vec::new();
    let mut current: Vec<Point> = Vec::new();
    let flush = |current: &mut Vec<Point>, closed: bool, out: &mut Vec<(Vec<Point>, bool)>| {
        if current.len() >= 2 || (closed && !current.is_empty()) {
            out.push((std::mem::take(current), closed));
        }
        current.clear();
    };
    let (mut cur, mut start) = ((0.0, 0.0), (0.0, 0.0));
    // The last cubic's second control point and the last quadratic's control point,
    // for S and T (reflected about the current point), when the segment before was
    // of that kind.
    let (mut last_cubic, mut last_quad): (Option<Point>, Option<Point>) = (None, None);
    for seg in PathParser::from(d) {
        let seg = seg.map_err(|e| {
            let head: String = d.chars().take(60).collect();
            format!("{head:?}: {e}")
        })?;
        let c0 = cur;
        let rel = move |abs: bool, x: f64, y: f64| {
            if abs {
                (x, y)
            } else {
                (c0.0 + x, c0.1 + y)
            }
        };
        // A drawing command straight after Z starts a subpath at the last M.
        if current.is_empty()
            && !matches!(
                seg,
                PathSegment::MoveTo { .. } | PathSegment::ClosePath { .. }
            )
        {
            current.push(start);
        }
        let (mut cubic, mut quad) = (None, None);
        match seg {
            PathSegment::MoveTo { abs, x, y } => {
                flush(&mut current, false, &mut out);
                cur = rel(abs, x, y);
                start = cur;
                current.push(cur);
            }
            PathSegment::LineTo { abs, x, y } => {
                cur = rel(abs, x, y);
                current.push(cur);
            }
            PathSegment::HorizontalLineTo { abs, x } => {
                cur = (if abs { x } else { cur.0 + x }, cur.1);
                current.push(cur);
            }
            PathSegment::VerticalLineTo { abs, y } => {
                cur = (cur.0, if abs { y } else { cur.1 + y });
                current.push(cur);
            }
            PathSegment::CurveTo {
                abs,
                x1,
                y1,
                x2,
                y2,
                x,
                y,
            } => {
                let (c1, c2, p) = (rel(abs, x1, y1), rel(abs, x2, y2), rel(abs, x, y));
                current.extend([c1, c2, p]);
                cubic = Some(c2);
                cur = p;
            }
            PathSegment::SmoothCurveTo { abs, x2, y2, x, y } => {
                let c1 = reflect(last_cubic, cur);
                let (c2, p) = (rel(abs, x2, y2), rel(abs, x, y));
                current.extend([c1, c2, p]);
                cubic = Some(c2);
                cur = p;
            }
            PathSegment::Quadratic { abs, x1, y1, x, y } => {
                let (q, p) = (rel(abs, x1, y1), rel(abs, x, y));
                current.extend([q, p]);
                quad = Some(q);
                cur = p;
            }
            PathSegment::SmoothQuadratic { abs, x, y } => {
                let q = reflect(last_quad, cur);
                let p = rel(abs, x, y);
                current.extend([q, p]);
                quad = Some(q);
                cur = p;
            }
            PathSegment::EllipticalArc {
                abs,
                rx,
                ry,
                x_axis_rotation,
                large_arc,
                sweep,
                x,
                y,
            } => {
                let p = rel(abs, x, y);
                if let Some(c) = arc_centre(cur, p, rx, ry, x_axis_rotation, large_arc, sweep) {
                    current.push(c);
                }
                current.push(p);
                cur = p;
            }
            PathSegment::ClosePath { .. } => {
                flush(&mut current, true, &mut out);
                cur = start;
            }
        }
        (last_cubic, last_quad) = (cubic, quad);
    }
    flush(&mut current, false, &mut out);
    Ok(out)
}

/// The control point `S` or `T` implies: the last one reflected about the current
/// point, or the current point when the segment before was of another kind.
fn reflect(last: Option<Point>, cur: Point) -> Point {
    match last {
        Some((x, y)) => (2.0 * cur.0 - x, 2.0 * cur.1 - y),
        None => cur,
    }
}

/// The centre of an SVG arc from `p0` to `p1` (SVG 1.1 implementation notes F.6.5,
/// radii scaled up when too small, F.6.6), or `None` for a degenerate arc drawn
/// as a straight line.
fn arc_centre(
    p0: Point,
    p1: Point,
    rx: f64,
    ry: f64,
    rotation_deg: f64,
    large_arc: bool,
    sweep: bool,
) -> Option<Point> {
    let (mut rx, mut ry) = (rx.abs(), ry.abs());
    if rx == 0.0 || ry == 0.0 || p0 == p1 {
        return None;
    }
    let (s, c) = rotation_deg.to_radians().sin_cos();
    let (dx, dy) = ((p0.0 - p1.0) / 2.0, (p0.1 - p1.1) / 2.0);
    let (x1, y1) = (c * dx + s * dy, -s * dx + c * dy);
    let lambda = (x1 * x1) / (rx * rx) + (y1 * y1) / (ry * ry);
    if lambda > 1.0 {
        rx *= lambda.sqrt();
        ry *= lambda.sqrt();
    }
    let num = rx * rx * ry * ry - rx * rx * y1 * y1 - ry * ry * x1 * x1;
    let den = rx * rx * y1 * y1 + ry * ry * x1 * x1;
    let mut k = (num / den).max(0.0).sqrt();
    if large_arc == sweep {
        k = -k;
    }
    let (cx1, cy1) = (k * rx * y1 / ry, -k * ry * x1 / rx);
    Some((
        c * cx1 - s * cy1 + (p0.0 + p1.0) / 2.0,
        s * cx1 + c * cy1 + (p0.1 + p1.1) / 2.0,
    ))
}

/// The text of an element and its descendants, without the tooltips of `<title>`.
fn all_text(node: Node) -> String {
    let mut s = String::new();
    for d in node.descendants() {
        if d.is_text()
            && !d
                .ancestors()
                .take_while(|a| *a != node)
                .any(|a| a.tag_name().name() == "title")
        {
            s.push_str(d.text().unwrap_or(""));
        }
    }
    s
}

/// Text as the comparison reads it: whitespace collapsed and trimmed (as SVG draws
/// it), every number (`-12`, `3.50`, `.5`, with `-` or `−` before it when no letter
/// or digit precedes the sign) rounded to 3 decimals and written without trailing
/// zeros, so a change of number formatting is not a change of data.
pub fn normalise_text(raw: &str) -> String {
    let collapsed = raw.split_whitespace().collect::<Vec<_>>().join(" ");
    let chars: Vec<char> = collapsed.chars().collect();
    let mut out = String::with_capacity(collapsed.len());
    let mut i = 0;
    while i < chars.len() {
        let starts_number = chars[i].is_ascii_digit()
            || (chars[i] == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit));
        if !starts_number {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let begin = i;
        while i < chars.len() && chars[i].is_ascii_digit() {
            i += 1;
        }
        if i + 1 < chars.len() && chars[i] == '.' && chars[i + 1].is_ascii_digit() {
            i += 1;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
        }
        let digits: String = chars[begin..i].iter().collect();
        let mut value: f64 = digits.parse().unwrap_or(0.0);
        // A sign straight before the number, not a hyphen inside a word.
        if let Some(&sign) = out.chars().last().as_ref() {
            if sign == '-' || sign == '−' {
                let before = out.chars().rev().nth(1);
                if !before.is_some_and(char::is_alphanumeric) {
                    out.pop();
                    value = -value;
                }
            }
        }
        out.push_str(&number(value));
    }
    out
}

/// A number rounded to 3 decimals, without trailing zeros or a negative zero.
fn number(v: f64) -> String {
    let s = format!("{:.3}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}
