//! One row of `transform compare`: a variant's pairing, mover and run.

use super::shared::Recorded;
use super::transform_scenario::Facts;
use crowdtouch::crowd::transform::{MoveParams, Mover, PairCost};

/// One row of the comparison, one seed's run.
pub struct Variant {
    /// Its name in the table.
    pub name: &'static str,
    /// The pairing cost.
    pub cost: PairCost,
    /// What moves the agents, and how.
    pub params: MoveParams,
    /// How long its pairing and subgroups took (ms; 0 for a shared one).
    pub prepare_ms: f64,
    /// The run.
    pub rec: Recorded,
    /// What the run showed of its scenario.
    pub facts: Facts,
    /// The pairing's two terms of eq. 3 (`Σ|s t|²`, `Σ(δs − δt)²`, m²) and the
    /// fraction of agents it sends elsewhere than the travel-only pairing.
    pub terms: (f64, f64, f64),
}

impl Variant {
    /// Mutual-information feedback (eqs. 18–19).
    pub fn feedback(&self) -> bool {
        self.params.feedback
    }

    /// What moves the agents.
    pub fn mover(&self) -> Mover {
        self.params.mover
    }
}
