//! What a recognised gesture makes the crowd do, as published: the recognition
//! (class, weight, neighbours) carried by the `gesture` end event, the motion's life
//! (`gesture_motion`), and every agent's planned trajectory (`plan`, and the
//! `demo_motion` that `library collect` shows before a person draws).

use crate::geom::Vec2;
use serde::{Deserialize, Serialize};

/// The outcome of recognising a gesture (gesture-driven section 7.1).
#[derive(Clone, Debug, PartialEq)]
pub struct Recognition {
    /// The motion class recognised: the class with the largest summed weight among
    /// the neighbours (`translate`, `twist`, ...).
    pub class: String,
    /// That class's share of the neighbours' weights, in `[0, 1]`.
    pub weight: f64,
    /// The K nearest library gestures, nearest first.
    pub neighbours: Vec<NeighbourView>,
    /// Time spent blending and synthesising the motion (µs; 0 when none was made).
    pub synth_us: u64,
    /// Agents the motion was synthesised for.
    pub agents: u32,
}

/// One neighbour of a recognition.
#[derive(Clone, Debug, PartialEq)]
pub struct NeighbourView {
    /// Its motion class.
    pub class: String,
    /// Its weighted DTW distance to the gesture (eq. 12; 0 for an exact match).
    pub distance: f64,
    /// Its weight in the blend (eq. 18; the weights sum to 1).
    pub weight: f64,
    /// Where the library entry came from (`generated`, or a recording's name).
    pub origin: String,
}

/// The life of a gesture's crowd motion.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionPhase {
    /// Agents walk to their trajectories' starts.
    Approach,
    /// Agents follow their trajectories.
    Follow,
    /// The motion played to its end; direct control resumes around the crowd.
    Done,
    /// The motion was stopped (a touch on the crowd, a reset, a newer gesture).
    Cancelled,
}

impl MotionPhase {
    /// Lower-case name, as on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            MotionPhase::Approach => "approach",
            MotionPhase::Follow => "follow",
            MotionPhase::Done => "done",
            MotionPhase::Cancelled => "cancelled",
        }
    }
}

/// What a [`PlanView`] shows.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum PlanOrigin {
    /// The motion a recognised gesture started (`plan`).
    Gesture {
        /// The gesture's id (as in its `gesture` events).
        id: u32,
    },
    /// A library motion shown by `library collect` for a person to draw (`demo_motion`).
    Demo {
        /// The motion's index in the library's motions.
        motion: u32,
    },
}

/// Every agent's planned trajectory, published once when a motion is planned
/// (shared in an `Arc`, to clients subscribed to `plan` only).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanView {
    /// A gesture's plan or a demonstration.
    pub origin: PlanOrigin,
    /// Its motion class.
    pub class: String,
    /// How long the motion plays once the agents are at their starts (s).
    pub duration_s: f64,
    /// Samples per agent, evenly spaced in time over `duration_s`.
    pub samples: u32,
    /// World positions (m), agent-major: agent `a`'s sample `k` is
    /// `points[a * samples + k]`; agent `a` is the snapshot's agent `a`.
    pub points: Vec<Vec2>,
}

impl PlanView {
    /// Agents planned (whole trajectories in `points`).
    pub fn agents(&self) -> usize {
        match self.samples {
            0 => 0,
            s => self.points.len() / s as usize,
        }
    }

    /// Agent `a`'s trajectory (empty past the last agent).
    pub fn trajectory(&self, a: usize) -> &[Vec2] {
        let s = self.samples as usize;
        self.points.get(a * s..(a + 1) * s).unwrap_or(&[])
    }
}
