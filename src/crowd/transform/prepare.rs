//! A transform prepared off the control thread. CONTRACT ONLY.

use super::pairing::PairCost;
use super::subgroups::{ApParams, Subgroups};
use crate::crowd::assign::{AssignError, Cancel};
use crate::crowd::formation::{Formation, Placement, SampleError, SampleParams};
use crate::geom::Vec2;

/// What a transform needs: where every agent starts, where it goes, its subgroup.
#[derive(Clone, Debug)]
pub struct TransformPlan {
    /// `s_i`: agent `i`'s position when planned (m).
    pub sources_m: Vec<Vec2>,
    /// `Ψ(s_i)`: agent `i`'s target (m).
    pub targets_m: Vec<Vec2>,
    /// The subgroups ([`Subgroups::single`] when off).
    pub subgroups: Subgroups,
    /// The cost that paired them.
    pub cost: PairCost,
}

/// Why a transform could not be prepared.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TransformError {
    /// The targets could not be sampled.
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// The pairing failed.
    #[error("pairing agents with targets failed: {0}")]
    Pair(#[from] AssignError),
}

impl TransformPlan {
    /// Pairs `sources` with `targets` (same length) by `cost`, then clusters the
    /// subgroups (`ap`; `None`: one subgroup). `Ok(None)` when `cancel` said so.
    ///
    /// # Errors
    /// [`TransformError::Pair`].
    pub fn new(
        sources: &[Vec2],
        targets: &[Vec2],
        cost: PairCost,
        ap: Option<&ApParams>,
        cancel: Cancel<'_>,
    ) -> Result<Option<TransformPlan>, TransformError> {
        let _ = (sources, targets, cost, ap, cancel);
        todo!()
    }
}

/// The slow part of a transform, for the formation thread (or the tick, in replays).
#[derive(Clone, Debug)]
pub struct TransformRequest {
    /// The formation's name.
    pub name: String,
    /// The requester's epoch when asked (stale results are told apart by it).
    pub epoch: u64,
    /// The shape.
    pub formation: Formation,
    /// Where it goes.
    pub placement: Placement,
    /// Agent positions when asked (m).
    pub agents: Vec<Vec2>,
    /// The pairing cost.
    pub cost: PairCost,
    /// Subgroups (`None`: off).
    pub subgroups: Option<ApParams>,
    /// How targets are sampled.
    pub sample: SampleParams,
    /// Seed of the sampling.
    pub seed: u64,
}

/// The answer to a [`TransformRequest`].
#[derive(Clone, Debug)]
pub struct PreparedTransform {
    /// As requested.
    pub name: String,
    /// As requested.
    pub epoch: u64,
    /// The plan, or why there is none.
    pub plan: Result<TransformPlan, TransformError>,
}

impl TransformRequest {
    /// Samples the targets ([`Formation::sample`]), then [`TransformPlan::new`].
    /// `None` when `cancel` said so.
    pub fn prepare(self, cancel: Cancel<'_>) -> Option<PreparedTransform> {
        let _ = cancel;
        todo!()
    }
}
