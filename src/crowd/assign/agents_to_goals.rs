//! Agent-to-goal assignment as the controllers use it: a solver and the positions it
//! reads its costs from, reused from call to call.
//!
//! mesh-formation-control section 6.1: "In this work, the source points correspond to
//! the locations of the agents and the target points are the vertices of the mesh Vf
//! at the current simulation step. [...] This provides a set of point-to-point
//! correspondences between the agents and the target formation, which is recalculated
//! at every time step." Weights of 1 on every source and target make the
//! transportation problem an exact one-to-one assignment.

use super::normalise::AffineMap;
use crate::crowd::assign::{AssignError, Cancel, PointCosts, PointMetric, SolveStats, Solver};
use crate::geom::Vec2;

/// A reusable assignment: solver workspace and the positions behind the costs.
///
/// The costs are computed from the positions on demand ([`PointCosts`], the
/// solver's geometric fast path): no `agents × goals` matrix is filled each frame,
/// and each agent's cheapest goals come from a spatial index. The answer is the
/// exact optimum, the same as on the full matrix.
///
/// With the squared distance and as many agents as goals, the positions are first
/// mapped by [`AffineMap::equalising`] (centred, and stretched to the same spread):
/// the optimum is the same permutation, and a crowd dragged off its formation,
/// pinched or stretched becomes an instance the fast path solves as quickly as a
/// uniform one.
pub struct Assigner {
    solver: Solver,
    costs: PointCosts,
    warm: bool,
    /// The mapped positions (reused).
    mapped_agents: Vec<Vec2>,
    mapped_goals: Vec<Vec2>,
}

impl Assigner {
    /// An assigner with the given cost function.
    pub fn new(metric: PointMetric) -> Assigner {
        Assigner {
            solver: Solver::new(),
            costs: PointCosts::new(metric),
            warm: false,
            mapped_agents: Vec::new(),
            mapped_goals: Vec::new(),
        }
    }

    /// Forgets the previous solution (the next solve is cold).
    pub fn forget(&mut self) {
        self.warm = false;
    }

    /// Solves agents → goals and writes the goal index of each agent into `goal_of`.
    ///
    /// Warm-started from the previous call when the sizes are unchanged.
    ///
    /// # Errors
    /// The solver's [`AssignError`]; `goal_of` is left untouched then.
    pub fn solve(
        &mut self,
        agents: &[Vec2],
        goals: &[Vec2],
        goal_of: &mut Vec<u32>,
    ) -> Result<(), AssignError> {
        self.solve_cancellable(agents, goals, goal_of, Cancel::NEVER)
    }

    /// [`Assigner::solve`] that gives up when `cancel` says so
    /// ([`Solver::solve_with_cancel`]): [`AssignError::Cancelled`], `goal_of`
    /// untouched, and the next solve is cold.
    ///
    /// # Errors
    /// As [`Assigner::solve`], and [`AssignError::Cancelled`].
    pub fn solve_cancellable(
        &mut self,
        agents: &[Vec2],
        goals: &[Vec2],
        goal_of: &mut Vec<u32>,
        cancel: Cancel<'_>,
    ) -> Result<(), AssignError> {
        let map = match self.costs.metric() {
            PointMetric::Squared => AffineMap::equalising(agents, goals),
            PointMetric::Euclidean => None,
        };
        match map {
            Some(map) => {
                self.mapped_agents.clear();
                self.mapped_agents
                    .extend(agents.iter().map(|&p| map.agent(p)));
                self.mapped_goals.clear();
                self.mapped_goals.extend(goals.iter().map(|&p| map.goal(p)));
                self.costs.set(&self.mapped_agents, &self.mapped_goals);
            }
            None => self.costs.set(agents, goals),
        }
        let result = if self.warm {
            self.solver.solve_warm_with_cancel(&self.costs, cancel)
        } else {
            self.solver.solve_with_cancel(&self.costs, cancel)
        };
        let a = match result {
            Ok(a) => a,
            Err(e) => {
                self.warm = false;
                return Err(e);
            }
        };
        self.warm = true;
        goal_of.clear();
        goal_of.extend(a.iter().map(|&g| g as u32));
        Ok(())
    }

    /// Checks the dual certificate of the last solution (`Solver::verify_optimal`) on
    /// the instance solved, i.e. after the mapping: optimal there is optimal for the
    /// given positions (see [`AffineMap`]). `O(agents · goals)`; for tests and
    /// benchmarks.
    pub fn verify_optimal(&self, tol: f64) -> bool {
        self.solver.verify_optimal(&self.costs, tol)
    }

    /// The solver's work counters of the last solve.
    pub fn stats(&self) -> SolveStats {
        self.solver.stats()
    }
}
