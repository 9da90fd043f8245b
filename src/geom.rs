//! Geometry aliases shared by the cores.
//!
//! The world is a plane in metres: x to the right, y away from the viewer (down the
//! table in surface terms). [`Vec2`] is a world position or vector in metres (or
//! metres per second for velocities, named in the field). Surface coordinates are the
//! unit square `[0, 1]²` of the touch surface after calibration, x right, y down.

/// A world position or displacement in metres (velocities in m/s where named).
pub type Vec2 = nalgebra::Vector2<f64>;

/// `u × v = u.x v.y − u.y v.x`: twice the signed area of the triangle `0, u, v`
/// (positive when `v` is counter-clockwise of `u`).
#[inline]
pub fn cross(u: Vec2, v: Vec2) -> f64 {
    u.x * v.y - u.y * v.x
}

/// Twice the signed area of the polygon `p` (m²; counter-clockwise positive), by
/// the shoelace formula.
pub fn twice_signed_area(p: &[Vec2]) -> f64 {
    (0..p.len())
        .map(|i| cross(p[i], p[(i + 1) % p.len()]))
        .sum()
}

/// The point of segment `a`–`b` nearest to `p`, with its parameter in `[0, 1]`
/// (`a` for a segment of no length).
#[inline]
pub fn nearest_on_segment(a: Vec2, b: Vec2, p: Vec2) -> (Vec2, f64) {
    let d = b - a;
    let len2 = d.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * s, s)
}

/// Squared distance from `p` to the segment `a`–`b` (m²).
#[inline]
pub fn segment_distance_squared(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    (nearest_on_segment(a, b, p).0 - p).norm_squared()
}

/// An axis-aligned rectangle in world metres.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Rect {
    /// Minimum corner (metres).
    pub min: [f64; 2],
    /// Maximum corner (metres).
    pub max: [f64; 2],
}

impl Rect {
    /// Width in metres.
    pub fn width(&self) -> f64 {
        self.max[0] - self.min[0]
    }
    /// Height in metres.
    pub fn height(&self) -> f64 {
        self.max[1] - self.min[1]
    }
    /// Centre point.
    pub fn center(&self) -> Vec2 {
        Vec2::new(
            0.5 * (self.min[0] + self.max[0]),
            0.5 * (self.min[1] + self.max[1]),
        )
    }
    /// Whether `p` lies inside or on the border.
    pub fn contains(&self, p: Vec2) -> bool {
        p.x >= self.min[0] && p.x <= self.max[0] && p.y >= self.min[1] && p.y <= self.max[1]
    }
}
