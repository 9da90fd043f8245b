//! Geometry aliases shared by the cores.
//!
//! The world is a plane in metres: x to the right, y away from the viewer (down the
//! table in surface terms). [`Vec2`] is a world position or vector in metres (or
//! metres per second for velocities, named in the field). Surface coordinates are the
//! unit square `[0, 1]²` of the touch surface after calibration, x right, y down.

/// A world position or displacement in metres (velocities in m/s where named).
pub type Vec2 = nalgebra::Vector2<f64>;

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
