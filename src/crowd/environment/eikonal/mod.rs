//! Eikonal travel cost: fast marching on a uniform grid, the environment-aware cost
//! field, bilinear reads, descent directions and an assignment cost provider.
//!
//! mesh-formation-control section 6.2: the cost of sending an agent to a goal is the
//! value at the agent's position of a potential field `Φ` that is zero at the goal
//! and solves the Eikonal equation `|∇Φ| = C` (eq. 5), with the unit cost `C` of
//! eq. 7 built from the agent's preferred speed, a discomfort term and the scene's
//! travel speed. Values are read by bilinear interpolation (eq. 6), and agents reach
//! their goal by descending `Φ`.
//!
//! This module takes plain per-cell grids (cost, speed factor, blocked flags,
//! obstacle distance), so any scene rasteriser can feed it.
//!
//! # Layout
//!
//! ```text
//!   origin ─► +-----+-----+-----+   x → (cols)
//!             | 0,0 | 1,0 | 2,0 |   cell (c, r) has index r * cols + c and its
//!             +-----+-----+-----+   centre at origin + ((c + ½) h, (r + ½) h)
//!             | 0,1 | 1,1 | 2,1 |   (h = cell size in metres). Values live at
//!             +-----+-----+-----+   cell centres.
//!   y ↓ (rows)
//! ```
//!
//! # Files
//!
//! `grid` (the grid and per-cell input checks), `march` (the solver, [`Fmm`]) and
//! `heap` (its queue), `segment` (cost along a straight line), `reads` ([`sample`],
//! [`descent_direction`]), `sanity` ([`sanity_check`]), `cost_field` (eq. 7 and
//! [`coarsen`]), `discomfort`, `costs` (the assignment provider, [`EikonalCosts`]),
//! `clusters` (goal clusters sharing a field, [`ClusterCosts`], for large crowds),
//! `transport` (the assignment of a large crowd as a min-cost flow on the grid,
//! [`GridTransport`]), `bench` (the benchmark instance), `error`.

mod bench;
mod clusters;
mod cost_field;
mod costs;
mod discomfort;
mod error;
mod grid;
mod heap;
mod march;
mod reads;
mod sanity;
mod segment;
mod simplex;
#[cfg(test)]
mod tests;
mod transport;

pub use bench::{bench_instance, BENCH_CELL_M};
pub use clusters::{
    ClusterCosts, ClusterStats, CLUSTER_COST_TOLERANCE, DEFAULT_CLUSTER_M, MAX_CLUSTERS,
};
pub use cost_field::{
    coarsen, cost_field_into, CostInputs, CostWeights, DEFAULT_ALPHA_PER_M, DEFAULT_BETA_PER_S,
    DEFAULT_GAMMA_PER_S,
};
pub use costs::{
    EikonalCosts, EikonalOptions, EikonalStats, FieldSources, DEFAULT_CACHE_FIELDS,
    SNAP_RADIUS_CELLS,
};
pub use discomfort::{
    discomfort_into, DiscomfortParams, DEFAULT_DENSITY_DISCOMFORT_M2, DEFAULT_OBSTACLE_DISCOMFORT,
    DEFAULT_OBSTACLE_RANGE_M,
};
pub use error::EikonalError;
pub use grid::{validate_cost, Grid, MAX_CELLS};
pub use march::{Fmm, Order, Sources, SOURCE_INIT_RADIUS_CELLS};
pub use reads::{descent_direction, sample, DEGENERATE_GRADIENT_PER_M};
pub use sanity::{sanity_check, SANITY_REL_SLACK};
pub use segment::segment_cost;
pub use transport::{cells_of, GridTransport, TransportError, TransportStats};
