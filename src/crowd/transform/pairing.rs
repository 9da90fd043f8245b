//! Pair assignment (formation-transform section 3.2). CONTRACT ONLY: to be written.

use crate::crowd::assign::{AssignError, Cancel};
use crate::geom::Vec2;

/// The cost that pairs agents with targets (formation-transform section 3.2; the
/// alternatives of section 5.2).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum PairCost {
    /// `ΔE(i, j)` of eq. 3 with this `λ` in `[0, 1]`.
    LeastEffort {
        /// `λ` of eq. 3.
        lambda: f64,
    },
    /// The Euclidean distance `|s_i t_j|`.
    Euclidean,
    /// The Manhattan distance `|x_i − x_j| + |y_i − y_j|`.
    Manhattan,
}

impl PairCost {
    /// `least-effort`, `euclidean` or `manhattan`.
    pub fn name(&self) -> &'static str {
        todo!()
    }

    /// The cost named `name` (as [`PairCost::name`] writes it), least effort with `lambda`.
    pub fn parse(name: &str, lambda: f64) -> Option<PairCost> {
        let _ = (name, lambda);
        todo!()
    }
}

/// The exact pairing minimising the sum of `cost` (eq. 6): `target_of[i]` is the
/// index in `targets` of agent `i`'s target. `sources.len() == targets.len()`.
///
/// # Errors
/// What the solver reports; [`AssignError::Cancelled`] when `cancel` said so.
pub fn pair(
    sources: &[Vec2],
    targets: &[Vec2],
    cost: PairCost,
    cancel: Cancel<'_>,
) -> Result<Vec<u32>, AssignError> {
    let _ = (sources, targets, cost, cancel);
    todo!()
}
