//! The page layout, world-to-picture coordinates and drawing one scene part.

use crowdtouch::crowd::environment::{Part, Placement};
use crowdtouch::geom::{Rect, Vec2};
use std::fmt::Write;

/// Drawing scale: the map fits in this many pixels across …
pub(super) const MAP_W_PX: f64 = 960.0;
/// … and this many down.
pub(super) const MAP_H_PX: f64 = 540.0;
pub(super) const MARGIN_PX: f64 = 14.0;
pub(super) const TITLE_PX: f64 = 46.0;
pub(super) const FOOTER_PX: f64 = 44.0;
pub(super) const PANEL_PX: f64 = 250.0;

/// World to picture coordinates.
#[derive(Copy, Clone)]
pub(super) struct View {
    pub(super) bounds: Rect,
    pub(super) px_per_m: f64,
    pub(super) x0: f64,
    pub(super) y0: f64,
}

impl View {
    pub(super) fn x(&self, x: f64) -> f64 {
        self.x0 + (x - self.bounds.min[0]) * self.px_per_m
    }
    pub(super) fn y(&self, y: f64) -> f64 {
        self.y0 + (y - self.bounds.min[1]) * self.px_per_m
    }
    pub(super) fn pt(&self, p: Vec2) -> String {
        format!("{:.1},{:.1}", self.x(p.x), self.y(p.y))
    }
    pub(super) fn w(&self) -> f64 {
        self.bounds.width() * self.px_per_m
    }
    pub(super) fn h(&self) -> f64 {
        self.bounds.height() * self.px_per_m
    }
}

/// Writes one part (at `pl`) with the given attributes.
pub(super) fn part_svg(
    s: &mut String,
    v: &View,
    part: &Part,
    pl: &Placement,
    class: &str,
    attrs: &str,
) {
    match part {
        Part::Polygon(poly) => {
            let pts: Vec<String> = poly
                .vertices()
                .iter()
                .map(|&p| v.pt(pl.to_world(p)))
                .collect();
            let _ = writeln!(
                s,
                r#"<polygon class="{class}" points="{}" {attrs}/>"#,
                pts.join(" ")
            );
        }
        Part::Circle(c) => {
            let p = pl.to_world(c.centre);
            let _ = writeln!(
                s,
                r#"<circle class="{class}" cx="{:.1}" cy="{:.1}" r="{:.1}" {attrs}/>"#,
                v.x(p.x),
                v.y(p.y),
                c.radius_m * v.px_per_m
            );
        }
    }
}
