//! A transform prepared off the control thread (formation-transform section 3): the
//! target points sampled in the shape, agents paired with them (section 3.2), the
//! subgroups clustered (section 3.4). Slow (hundreds of milliseconds at thousands of
//! agents), so the daemon's formation thread runs it and the crowd keeps moving.

use super::pairing::{pair, PairCost};
use super::subgroups::{subgroups, ApParams, Subgroups};
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
    /// `targets_m[i]` of the plan is agent `i`'s target (the targets permuted by
    /// the pairing).
    ///
    /// # Errors
    /// [`TransformError::Pair`]: what [`pair`] reports (no agents, a position that is
    /// not finite, more agents than targets).
    pub fn new(
        sources: &[Vec2],
        targets: &[Vec2],
        cost: PairCost,
        ap: Option<&ApParams>,
        cancel: Cancel<'_>,
    ) -> Result<Option<TransformPlan>, TransformError> {
        let target_of = match pair(sources, targets, cost, cancel) {
            Ok(t) => t,
            Err(AssignError::Cancelled) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        let targets_m: Vec<Vec2> = target_of.iter().map(|&j| targets[j as usize]).collect();
        let subgroups = match ap {
            None => Subgroups::single(sources.len()),
            Some(p) => match subgroups(sources, &targets_m, p, cancel) {
                Some(g) => g,
                None => return Ok(None),
            },
        };
        Ok(Some(TransformPlan {
            sources_m: sources.to_vec(),
            targets_m,
            subgroups,
            cost,
        }))
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
        let check = cancel.as_fn();
        let plan = match self.formation.sample(
            &self.placement,
            self.agents.len(),
            &self.sample,
            self.seed,
            &check,
        ) {
            Err(e) => Err(TransformError::from(e)),
            Ok(None) => return None,
            Ok(Some(targets)) => match TransformPlan::new(
                &self.agents,
                &targets,
                self.cost,
                self.subgroups.as_ref(),
                cancel,
            ) {
                Ok(Some(plan)) => Ok(plan),
                Ok(None) => return None,
                Err(e) => Err(e),
            },
        };
        Some(PreparedTransform {
            name: self.name,
            epoch: self.epoch,
            plan,
        })
    }
}
