//! Agent-to-goal assignment as the controllers use it: a solver and the positions it
//! reads its costs from, reused from call to call.
//!
//! mesh-formation-control section 6.1: "In this work, the source points correspond to
//! the locations of the agents and the target points are the vertices of the mesh Vf
//! at the current simulation step. [...] This provides a set of point-to-point
//! correspondences between the agents and the target formation, which is recalculated
//! at every time step." Weights of 1 on every source and target make the
//! transportation problem an exact one-to-one assignment.

use crate::crowd::assign::{AssignError, PointCosts, PointMetric, Solver};
use crate::geom::Vec2;

/// A reusable assignment: solver workspace and the positions behind the costs.
///
/// The costs are computed from the positions on demand ([`PointCosts`], the
/// solver's geometric fast path): no `agents × goals` matrix is filled each frame,
/// and each agent's cheapest goals come from a spatial index. The answer is the
/// exact optimum, the same as on the full matrix.
pub struct Assigner {
    solver: Solver,
    costs: PointCosts,
    warm: bool,
}

impl Assigner {
    /// An assigner with the given cost function.
    pub fn new(metric: PointMetric) -> Assigner {
        Assigner {
            solver: Solver::new(),
            costs: PointCosts::new(metric),
            warm: false,
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
        self.costs.set(agents, goals);
        let result = if self.warm {
            self.solver.solve_warm_with(&self.costs)
        } else {
            self.solver.solve_with(&self.costs)
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

    /// Total cost of the last solution.
    pub fn total_cost(&self) -> f64 {
        self.solver.total_cost(&self.costs)
    }
}
