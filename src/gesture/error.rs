//! Why a captured gesture cannot be recognised (`resample::prepare`): the one error
//! type of recognition's input boundary.

use super::track::MAX_GESTURE_FINGERS;

/// A gesture that recognition refuses, with where and what.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GestureError {
    /// No finger has any sample.
    #[error("gesture has no fingers (no finger has a sample)")]
    NoFingers,
    /// More fingers than a gesture may hold.
    #[error("gesture has {count} fingers, more than the {max} a gesture may have", max = MAX_GESTURE_FINGERS)]
    TooManyFingers {
        /// Fingers with at least one sample.
        count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("finger {finger} sample {sample} has a non-finite coordinate ({x}, {y}) mm")]
    NonFinite {
        /// Index of the finger in `GestureTracks::fingers`.
        finger: usize,
        /// Index of the sample in that finger's track.
        sample: usize,
        /// Its x (mm).
        x: f64,
        /// Its y (mm).
        y: f64,
    },
    /// One sample in the whole gesture: nothing to resample.
    #[error("gesture has a single sample (at least two are needed)")]
    SingleSample,
    /// Every sample was taken at the same instant.
    #[error("gesture lasts no time: all {samples} samples were taken at {t_us} us")]
    NoDuration {
        /// Samples in the gesture.
        samples: usize,
        /// Their common time (µs).
        t_us: u64,
    },
    /// Every finger stays on one point.
    #[error("gesture has no extent: every sample is on one point (extent {extent_mm:e} mm)")]
    NoExtent {
        /// The larger side of the resampled gesture's bounding box (mm).
        extent_mm: f64,
    },
}
