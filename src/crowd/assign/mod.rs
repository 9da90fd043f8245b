//! Exact one-to-one assignment of agents to goals (mesh-formation-control section 6.1,
//! eq. 2): the cost sources (a matrix, or costs computed from positions), the solver,
//! the least-effort cost of formation-transform section 3.2, and the [`Assigner`] the
//! controllers and the assignment worker reuse from call to call.

mod assigner;
mod least_effort;
mod solver;

pub use assigner::Assigner;
pub use least_effort::{mean_edge_lengths, LeastEffort};
pub use solver::{
    AssignError, CostMatrix, CostProvider, CostSource, Distance, PointCosts, PointMetric,
    SolveStats, Solver, SquaredDistance, Strategy, EPS_REL, GOALS_PER_BUCKET,
};
