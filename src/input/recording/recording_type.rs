//! What every reader returns: a [`Recording`], normalised and timed from its start.

use crate::input::SurfaceInfo;
use crate::vocab::{Micros, TouchFrame};

use super::warnings::RecordingIssue;

/// Delay between the last frame and the frame cancelling contacts still down, in µs.
pub const END_CANCEL_US: u64 = 1_000;

/// A recording, read and normalised.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The recorded surface.
    pub surface: SurfaceInfo,
    /// Frames in the unit square with `DOWN`/`UP`/`CANCELLED` flags derived;
    /// `t` relative to the start of the recording. Ids count from 1.
    pub frames: Vec<TouchFrame>,
    /// Problems that did not stop the reading (skipped frames, counters).
    pub warnings: Vec<RecordingIssue>,
}

impl Recording {
    /// Time from the first to the last frame.
    pub fn duration(&self) -> Micros {
        match (self.frames.first(), self.frames.last()) {
            (Some(a), Some(b)) => b.t.saturating_since(a.t),
            _ => Micros::ZERO,
        }
    }
}
