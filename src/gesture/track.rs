//! A gesture as captured: every finger's samples on the glass, in millimetres, with
//! their times. The input of recognition (`features`), produced by the capture on
//! the control thread, by the gesture generator and by recordings read from files.

use crate::geom::Vec2;
use crate::vocab::Micros;

/// Most fingers one gesture holds (gesture-driven section 5.1 allows any N; a table
/// reports at most ten per hand pair).
pub const MAX_GESTURE_FINGERS: usize = 10;

/// One sample of a finger: when (CLOCK_MONOTONIC, or a recording's time) and where
/// on the glass (mm, x right, y down).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TrackSample {
    /// When the finger was here (µs).
    pub t: Micros,
    /// Where, on the glass (mm).
    pub mm: Vec2,
}

/// One finger's trajectory, times ascending (gesture-driven eq. 1: `g_n(t)`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TouchTrack {
    /// The samples, oldest first.
    pub samples: Vec<TrackSample>,
}

/// A whole gesture: the trajectories of every finger that took part
/// (gesture-driven eq. 1, `G_raw`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GestureTracks {
    /// One track per finger, in the order they landed.
    pub fingers: Vec<TouchTrack>,
}

impl GestureTracks {
    /// When the first finger landed, and when the last sample was taken (`None`
    /// when there is no sample).
    pub fn span(&self) -> Option<(Micros, Micros)> {
        let first = self
            .fingers
            .iter()
            .filter_map(|f| f.samples.first())
            .map(|s| s.t)
            .min()?;
        let last = self
            .fingers
            .iter()
            .filter_map(|f| f.samples.last())
            .map(|s| s.t)
            .max()?;
        Some((first, last))
    }
}
