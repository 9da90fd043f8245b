//! Agent-to-goal assignment as the controllers use it: a solver, its cost matrix and
//! a cost function, reused from call to call.
//!
//! mesh-formation-control section 6.1: "In this work, the source points correspond to
//! the locations of the agents and the target points are the vertices of the mesh Vf
//! at the current simulation step. [...] This provides a set of point-to-point
//! correspondences between the agents and the target formation, which is recalculated
//! at every time step." Weights of 1 on every source and target make the
//! transportation problem an exact one-to-one assignment.

use super::assign::{AssignError, CostMatrix, CostProvider, Distance, Solver, SquaredDistance};
use crate::config::AssignmentCost;
use crate::geom::Vec2;

/// A reusable assignment: solver workspace, cost matrix and cost function.
pub struct Assigner {
    solver: Solver,
    costs: CostMatrix,
    cost: AssignmentCost,
    warm: bool,
}

impl Assigner {
    /// An assigner with the given cost function.
    pub fn new(cost: AssignmentCost) -> Assigner {
        Assigner {
            solver: Solver::new(),
            costs: CostMatrix::new(0, 0),
            cost,
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
        self.costs.resize(agents.len(), goals.len());
        match self.cost {
            AssignmentCost::SquaredDistance => SquaredDistance.fill(agents, goals, &mut self.costs),
            AssignmentCost::Distance => Distance.fill(agents, goals, &mut self.costs),
        }
        let result = if self.warm {
            self.solver.solve_warm(&self.costs)
        } else {
            self.solver.solve(&self.costs)
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
