//! Exact one-to-one assignment of agents to goals (mesh-formation-control section 6.1,
//! eq. 2): the cost sources (a matrix, or costs computed from positions), the solver,
//! the least-effort cost of formation-transform section 3.2, and the [`Assigner`] the
//! controllers and the assignment worker reuse from call to call.
//!
//! The problem is the transportation problem of section 6.1 with unit supply and
//! demand weights, i.e. the linear assignment problem
//!
//! ```text
//!   minimise   sum_i c[i][sigma(i)]     over injections sigma: rows -> cols (rows <= cols)
//! ```
//!
//! which [`Solver`] solves exactly (shortest augmenting paths with dual prices; the
//! method is described in `solver.rs`). One file per job:
//!
//! * `costs` — where the costs come from: [`CostSource`], a [`CostMatrix`] filled by a
//!   [`CostProvider`], or [`PointCosts`];
//! * `points` — [`PointCosts`], the geometric fast path (bucket grid, ring search);
//! * `candidates` — sort keys and the streaming selection of a row's cheapest columns;
//! * `solver` — [`Solver`]: options, workspaces, cold and warm solves, the certificate;
//! * `seeded` — solves started from given column prices, and the duals of a solve;
//! * `coarse` — [`CoarseToFine`]: square squared-distance instances solved on nested
//!   random subsets, each level started from the prices of the one below;
//! * `pricing` — rows priced against the column prices, candidate lists and thresholds;
//! * `auction` — the auction and the row reduction that initialise the prices;
//! * `augment` — exact Dijkstra over the candidate lists (sparse strategy);
//! * `dense` — Dijkstra over full rows (dense strategy, and the safety net);
//! * `heaps` — the searches' priority queues;
//! * `cancel` — [`Cancel`]: the check a long solve polls to give up when its input
//!   is stale or the daemon is stopping;
//! * `error` — [`AssignError`];
//! * `layouts` — [`Layout`]: the instances benchmarks and tests solve;
//! * `least_effort` — [`LeastEffort`], the cost of formation-transform eq. 3;
//! * `normalise` — [`AffineMap`]: centring and equalising the spread of a square
//!   squared-distance instance, which keeps its optimum and makes it fast;
//! * `agents_to_goals` — [`Assigner`]: agents to goal points from their positions,
//!   warm-started from call to call (what the controllers and the worker run).

mod agents_to_goals;
mod auction;
mod augment;
mod cancel;
mod candidates;
mod coarse;
mod costs;
mod dense;
mod error;
mod heaps;
mod layouts;
mod least_effort;
mod normalise;
mod points;
mod pricing;
mod seeded;
mod solver;
#[cfg(test)]
mod tests;

pub use agents_to_goals::Assigner;
pub use cancel::{Cancel, POLL_WORK};
pub use coarse::{CoarseStats, CoarseToFine};
pub use costs::{CostMatrix, CostProvider, CostSource, Distance, SquaredDistance};
pub use error::AssignError;
pub use layouts::Layout;
pub use least_effort::{mean_edge_lengths, LeastEffort, LeastEffortCosts};
pub use normalise::{AffineMap, SPREAD_FLOOR};
pub use points::{PointCosts, PointMetric, GOALS_PER_BUCKET};
pub use solver::{SolveStats, Solver, Strategy, EPS_REL};
