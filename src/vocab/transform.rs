//! A formation transform as published: its progress every tick (`transform`
//! messages) and its summary at the end (`transform_end`), to clients subscribed to
//! `transform`.

use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The objective measures of formation-transform section 5.1.
#[derive(Copy, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformMeasures {
    /// `I_d`, eq. 17 (bits).
    pub i_d: f64,
    /// `σ_min_dis`, eq. 24 (m).
    pub sigma_min_dis_m: f64,
    /// `σ_curr_eft`, eq. 26 (m).
    pub sigma_curr_eft_m: f64,
}

/// One tick of a running transform (shared in an `Arc`, recycled by the engine).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TransformView {
    /// The formation the crowd is going to.
    pub formation: Arc<str>,
    /// `transform`.
    pub method: &'static str,
    /// The pairing cost (`least_effort`, `euclidean`, `manhattan`).
    pub cost: &'static str,
    /// Tick sequence number (as in the snapshot).
    pub seq: u64,
    /// Fraction of agents at their targets, `[0, 1]`.
    pub progress: f64,
    /// Simulated time since the transform started (s).
    pub elapsed_s: f64,
    /// The measures now.
    pub measures: TransformMeasures,
    /// The smallest distance between two agents now (m).
    pub min_distance_m: f64,
    /// Pairs of agents closer than two radii now.
    pub overlapping_pairs: u32,
    /// Subgroups the crowd was clustered into.
    pub subgroups: u32,
    /// Each agent's subgroup, `0..subgroups`, in the snapshot's agent order
    /// (formation-transform section 3.4's affinity propagation; shared for the run).
    pub agent_subgroups: Arc<Vec<u32>>,
    /// The desired walking speed it runs at (m/s).
    pub speed_m_s: f64,
}

/// How a transform ended.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransformOutcome {
    /// Every agent arrived.
    Arrived,
    /// The timeout passed first.
    TimedOut,
    /// A touch on the crowd took it back to direct control.
    Touched,
    /// A newer formation request replaced it.
    Superseded,
    /// A reset or resize dropped it.
    Dropped,
}

impl TransformOutcome {
    /// The name on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            TransformOutcome::Arrived => "arrived",
            TransformOutcome::TimedOut => "timed_out",
            TransformOutcome::Touched => "touched",
            TransformOutcome::Superseded => "superseded",
            TransformOutcome::Dropped => "dropped",
        }
    }
}

/// A transform summarised when it ends (the crowd-level run summary).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TransformSummary {
    /// The formation it went to.
    pub formation: String,
    /// The pairing cost.
    pub cost: String,
    /// How it ended.
    pub outcome: TransformOutcome,
    /// Agents.
    pub agents: u32,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub simulated_s: f64,
    /// Agents at their targets at the end, as a fraction.
    pub arrived_fraction: f64,
    /// The smallest distance between two agents at any step (m).
    pub min_distance_m: f64,
    /// Distinct pairs that were closer than two radii at some step.
    pub overlapping_pairs: u64,
    /// Pairs of agents that exchanged targets to undo a head-on block.
    pub swaps: u64,
    /// Mean distance walked (m).
    pub mean_travel_m: f64,
    /// Largest distance walked (m).
    pub max_travel_m: f64,
    /// The measures averaged over the steps.
    pub mean: TransformMeasures,
    /// Subgroups.
    pub subgroups: u32,
    /// The desired walking speed it ran at (m/s).
    pub speed_m_s: f64,
}
