//! A transform running: social forces with subgroup terms and mutual-information
//! feedback (formation-transform sections 3.3, 3.5). CONTRACT ONLY.

use super::measures::Measures;
use super::prepare::TransformPlan;
use crate::crowd::environment::Scene;
use crate::geom::Vec2;

/// What moves the agents.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Mover {
    /// The paper's social force model (eqs. 7–10, 21–23) with feedback (eqs. 18–19).
    #[default]
    SocialForce,
    /// ORCA (the comparison of section 5.4) on the same pairing.
    Orca,
}

/// How a transform moves the agents.
#[derive(Clone, Debug, PartialEq)]
pub struct MoveParams {
    /// What moves them.
    pub mover: Mover,
    /// Agent radius (m).
    pub radius_m: f64,
    /// `v⁰`: desired speed (m/s).
    pub desired_speed_m_s: f64,
    /// Mutual-information feedback on heading and desired speed (eqs. 18–19).
    pub feedback: bool,
    /// Subgroup attraction and cross-group repulsion (eqs. 21–23).
    pub subgroup_forces: bool,
    /// An agent within this distance of its target has arrived (m).
    pub arrive_m: f64,
    /// The transform ends after this long even if not every agent arrived (s).
    pub timeout_s: f64,
}

impl Default for MoveParams {
    fn default() -> MoveParams {
        todo!()
    }
}

/// One step's report.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Agents at their targets.
    pub arrived: usize,
    /// `arrived / agents`.
    pub arrived_fraction: f64,
    /// The measures now.
    pub measures: Measures,
    /// The smallest distance between two agents now (m).
    pub min_distance_m: f64,
    /// Pairs closer than two radii now.
    pub overlapping_pairs: usize,
}

/// A whole run, summarised.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSummary {
    /// Agents.
    pub agents: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub simulated_s: f64,
    /// Agents at their targets at the end, as a fraction.
    pub arrived_fraction: f64,
    /// The smallest distance between two agents at any step (m).
    pub min_distance_m: f64,
    /// Distinct pairs that were closer than two radii at some step.
    pub overlapping_pairs: usize,
    /// Mean distance walked (m).
    pub mean_travel_m: f64,
    /// Largest distance walked (m).
    pub max_travel_m: f64,
    /// The measures averaged over the steps.
    pub mean: Measures,
    /// Whether it ended by the timeout.
    pub timed_out: bool,
}

/// A transform in progress; the agents' positions and velocities stay the caller's.
#[derive(Clone, Debug)]
pub struct TransformRun {
    targets: Vec<Vec2>,
}

impl TransformRun {
    /// A run of `plan` with `params`, fluctuation drawn from `seed`. Allocates its
    /// buffers once.
    pub fn new(plan: &TransformPlan, params: &MoveParams, seed: u64) -> TransformRun {
        let _ = (plan, params, seed);
        todo!()
    }

    /// One step of `dt_s` seconds: forces, feedback, integration, arrival; the scene's
    /// obstacles at scene time `t_s` when given. No allocation in steady state.
    pub fn step(
        &mut self,
        positions: &mut [Vec2],
        velocities: &mut [Vec2],
        dt_s: f64,
        scene: Option<(&Scene, f64)>,
    ) -> StepReport {
        let _ = (positions, velocities, dt_s, scene);
        todo!()
    }

    /// Every agent arrived and settled, or the timeout passed.
    pub fn done(&self) -> bool {
        todo!()
    }

    /// Simulated time since the start (s).
    pub fn elapsed_s(&self) -> f64 {
        todo!()
    }

    /// Agent `i`'s target is `targets()[i]` (m).
    pub fn targets(&self) -> &[Vec2] {
        &self.targets
    }

    /// The run so far, summarised.
    pub fn summary(&self) -> RunSummary {
        todo!()
    }
}
