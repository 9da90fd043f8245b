//! The page layout and drawing one scene part through the world frame.

use crowdtouch::crowd::environment::{Part, Placement};
use crowdtouch::picture::{Canvas, Frame, Paint};

/// Drawing scale: the map fits in this many pixels across …
pub(super) const MAP_W_PX: f64 = 960.0;
/// … and this many down.
pub(super) const MAP_H_PX: f64 = 540.0;
pub(super) const MARGIN_PX: f64 = 14.0;
pub(super) const TITLE_PX: f64 = 46.0;
pub(super) const FOOTER_PX: f64 = 44.0;
pub(super) const PANEL_PX: f64 = 250.0;

/// Draws one part (at `pl`).
pub(super) fn part(c: &mut Canvas, f: &Frame, part: &Part, pl: &Placement, paint: &Paint) {
    match part {
        Part::Polygon(poly) => {
            c.polygon(poly.vertices().iter().map(|&p| f.pt(pl.to_world(p))), paint);
        }
        Part::Circle(d) => c.circle(f.pt(pl.to_world(d.centre)), f.len(d.radius_m), paint),
    }
}
