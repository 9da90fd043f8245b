//! What a source knows about the surface it reads: axis ranges and size.

use serde::{Deserialize, Serialize};

/// Axis range of a surface axis in device units.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisRange {
    /// Minimum value.
    pub min: f64,
    /// Maximum value.
    pub max: f64,
    /// Resolution in units per millimetre (0 = unknown).
    #[serde(default)]
    pub resolution: f64,
}

impl AxisRange {
    /// Maps a device value into `[0, 1]` (clamped).
    pub fn normalise(&self, v: f64) -> f32 {
        let span = self.max - self.min;
        if span <= 0.0 || !v.is_finite() {
            return 0.0;
        }
        (((v - self.min) / span).clamp(0.0, 1.0)) as f32
    }

    /// Physical length of the axis in millimetres, when the resolution is known.
    pub fn length_mm(&self) -> Option<f64> {
        (self.resolution > 0.0).then(|| (self.max - self.min) / self.resolution)
    }
}

/// What a source knows about the surface it reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurfaceInfo {
    /// Device name.
    pub name: String,
    /// X axis in device units.
    pub x: AxisRange,
    /// Y axis in device units.
    pub y: AxisRange,
    /// Most simultaneous contacts the device reports.
    pub max_contacts: u32,
}

impl SurfaceInfo {
    /// Physical size `(width, height)` in millimetres, when both resolutions are known.
    pub fn size_mm(&self) -> Option<(f64, f64)> {
        Some((self.x.length_mm()?, self.y.length_mm()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_normalises_and_clamps() {
        let a = AxisRange {
            min: 42.0,
            max: 1981.0,
            resolution: 0.0,
        };
        assert_eq!(a.normalise(42.0), 0.0);
        assert_eq!(a.normalise(1981.0), 1.0);
        assert_eq!(a.normalise(5000.0), 1.0);
        assert!(a.length_mm().is_none());
    }
}
