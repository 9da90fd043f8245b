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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn points(rng: &mut SplitMix64, n: usize, side: f64, dx: f64) -> Vec<Vec2> {
        (0..n)
            .map(|_| Vec2::new(dx + side * rng.unit(), side * rng.unit()))
            .collect()
    }

    /// The plan gives each agent the target its pairing chose, every target once,
    /// and the subgroups of the paired targets.
    #[test]
    fn plan_permutes_the_targets_by_the_pairing() {
        let mut rng = SplitMix64::new(0x91a);
        let (s, t) = (
            points(&mut rng, 60, 1.0, 0.0),
            points(&mut rng, 60, 1.5, 2.0),
        );
        for cost in [
            PairCost::LeastEffort { lambda: 0.5 },
            PairCost::Euclidean,
            PairCost::Manhattan,
        ] {
            let ap = ApParams::default();
            let plan = TransformPlan::new(&s, &t, cost, Some(&ap), Cancel::NEVER)
                .unwrap()
                .unwrap();
            let to = pair(&s, &t, cost, Cancel::NEVER).unwrap();
            assert_eq!(plan.sources_m, s);
            assert_eq!(plan.cost, cost);
            for (i, &j) in to.iter().enumerate() {
                assert_eq!(plan.targets_m[i], t[j as usize]);
            }
            let mut sorted: Vec<(u64, u64)> = plan
                .targets_m
                .iter()
                .map(|p| (p.x.to_bits(), p.y.to_bits()))
                .collect();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), 60);
            let g = subgroups(&s, &plan.targets_m, &ap, Cancel::NEVER).unwrap();
            assert_eq!(plan.subgroups, g);
            let off = TransformPlan::new(&s, &t, cost, None, Cancel::NEVER)
                .unwrap()
                .unwrap();
            assert_eq!(off.subgroups, Subgroups::single(60));
            assert_eq!(off.targets_m, plan.targets_m);
        }
    }

    #[test]
    fn errors_and_cancellation() {
        let p = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)];
        let nan = [Vec2::new(0.0, 0.0), Vec2::new(f64::NAN, 1.0)];
        let le = PairCost::LeastEffort { lambda: 0.5 };
        assert!(matches!(
            TransformPlan::new(&nan, &p, le, None, Cancel::NEVER),
            Err(TransformError::Pair(AssignError::NotFinite { .. }))
        ));
        assert!(matches!(
            TransformPlan::new(&[], &[], le, None, Cancel::NEVER),
            Err(TransformError::Pair(AssignError::Empty))
        ));
        let stop = || true;
        let mut rng = SplitMix64::new(1);
        let (s, t) = (
            points(&mut rng, 300, 1.0, 0.0),
            points(&mut rng, 300, 1.0, 0.5),
        );
        let r = TransformPlan::new(&s, &t, le, Some(&ApParams::default()), Cancel::new(&stop));
        assert!(matches!(r, Ok(None)));
    }
}
