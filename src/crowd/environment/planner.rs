//! The crowd in its environment: the planner that assigns goals with Eikonal travel
//! costs and gives agents waypoints around obstacles, and the per-agent rules the
//! control thread applies (terrain speed, staying out of obstacles).
//!
//! mesh-formation-control section 6.2: the assignment cost of agent `i` and goal `j`
//! is `Φ_j(a_i)` (eq. 6), `Φ_j` the fast-marching solution of `|∇Φ| = C` (eq. 5)
//! zero at goal `j`, with the unit cost `C` of eq. 7 from the scene rasterised at the
//! job's time (obstacles blocked, patches at their Table 1 travel speed) and a
//! discomfort term from obstacle distance and crowd density (eq. 3). "Once a point in
//! the mesh is assigned to an agent their route to the location is computed using
//! gradient descent on the field."
//!
//! # Who does what
//! * The **planner** ([`Planner`]) runs with the assignment, on the worker thread
//!   (or inline in replays): it rasterises the scene on a grid of
//!   [`DEFAULT_PLAN_CELL_M`] cells (the cell the Eikonal module recommends for
//!   assignment costs), computes the travel costs from one field per cluster of
//!   goals ([`ClusterCosts`], with [`PlannerParams::cluster_m`]; one field per goal
//!   with [`EikonalCosts`] when it is 0), solves, then for every agent whose goal is
//!   hidden behind an obstacle descends the field its cost came from (kept in the
//!   cost provider's cache, which holds every cluster's field) and keeps the
//!   farthest point of that path the agent can see as its **waypoint**.
//! * The **control thread** only does O(obstacle parts) work per agent per tick: it
//!   steers an agent straight at its goal when the goal is visible (or the agent has
//!   no waypoint), else at its waypoint; scales its speed limit by the travel speed
//!   of the patch under it ([`Scene::terrain_at`]); and after the step projects it
//!   out of obstacles by one agent radius ([`Scene::project_out`]).

use crate::crowd::assign::{
    AssignError, Cancel, CostMatrix, PointCosts, PointMetric, Solver, Strategy,
};
use crate::crowd::environment::eikonal::{
    cells_of, cost_field_into, discomfort_into, ClusterCosts, CostInputs, CostWeights,
    DiscomfortParams, EikonalCosts, EikonalError, EikonalOptions, FieldSources, Grid,
    GridTransport, TransportError, TransportStats, DEFAULT_CLUSTER_M, MAX_CLUSTERS,
};
use crate::crowd::environment::{Scene, SceneAt, SceneGrid};
use crate::geom::Vec2;
use std::sync::Arc;

/// Cell side of the planning grid (m): the Eikonal module's recommended resolution
/// for assignment costs (about 16 cm).
pub const DEFAULT_PLAN_CELL_M: f64 = 0.16;
/// The crowd-density part of the discomfort is recomputed at most this often (s of
/// scene time): it changes the cost grid, which drops every cached field.
pub const DEFAULT_DENSITY_REFRESH_S: f64 = 0.5;
/// Most descent steps (one cell each) when tracing an agent's route.
pub const MAX_ROUTE_STEPS: usize = 2048;
/// Agents whose waypoints are traced between two polls of a plan's [`Cancel`]
/// check (a waypoint is at most [`MAX_ROUTE_STEPS`] descent steps).
const WAYPOINTS_PER_POLL: usize = 64;
/// Weight `ε` of the tie-break `ε · |a_i − g_j|²` added to the clustered travel
/// costs by default (s/m²): none, the assignment is the travel-cost optimum
/// ([`ClusterCosts::set_tie_break`] for what a positive weight trades).
pub const DEFAULT_TIE_BREAK_S_PER_M2: f64 = 0.0;
/// Plans with more goals than this solve with longer candidate lists and never
/// restart a warm solve cold ([`solver_for`]) when they are solved over pairs, and
/// by default are solved as a transport on the planning grid instead
/// ([`PlannerParams::transport_above_goals`]).
pub const LARGE_PLAN_GOALS: usize = 2000;
/// Candidate lists of a large plan: `goals / LARGE_PLAN_CANDIDATES_DIV` columns per
/// row, at most [`LARGE_PLAN_CANDIDATES_MAX`].
const LARGE_PLAN_CANDIDATES_DIV: usize = 20;
/// See [`LARGE_PLAN_CANDIDATES_DIV`].
const LARGE_PLAN_CANDIDATES_MAX: usize = 256;

/// Tunables of the planner.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PlannerParams {
    /// Planning grid cell (m).
    pub cell_m: f64,
    /// Preferred speed `f` of eq. 7 (m/s): the agents' speed limit.
    pub preferred_speed_m_s: f64,
    /// Weights of eq. 3.
    pub weights: CostWeights,
    /// Discomfort from obstacles and crowd density.
    pub discomfort: DiscomfortParams,
    /// Scene time between density refreshes (s).
    pub density_refresh_s: f64,
    /// Side of the goal-cluster lattice (m): goals of one cluster share one field,
    /// corrected per goal by the straight last leg ([`ClusterCosts`]). `0`: one
    /// exact field per goal (the reference; about 0.9 s at 1,000 goals).
    pub cluster_m: f64,
    /// Weight `ε` of the tie-break `ε · |a_i − g_j|²` added to the clustered
    /// travel costs (s/m²; [`DEFAULT_TIE_BREAK_S_PER_M2`], 0: none). The plan is
    /// then optimal for travel cost + `ε · d²`, not for the travel cost alone
    /// ([`ClusterCosts::set_tie_break`]).
    pub tie_break_s_per_m2: f64,
    /// Plans with more goals than this are solved as a min-cost flow on the
    /// planning grid ([`GridTransport`]: the optimum of the grid's path costs, not
    /// of the eq. 6 costs of the pairs; docs/scenes-and-formations.md gives how far
    /// apart they are). Default `LARGE_PLAN_GOALS` (2,000); `usize::MAX`: every plan is
    /// the exact optimum of the pairs' costs.
    pub transport_above_goals: usize,
}

impl PlannerParams {
    /// The defaults for agents with speed limit `preferred_speed_m_s`.
    pub fn new(preferred_speed_m_s: f64) -> PlannerParams {
        PlannerParams {
            cell_m: DEFAULT_PLAN_CELL_M,
            preferred_speed_m_s,
            weights: CostWeights::default(),
            discomfort: DiscomfortParams::default(),
            density_refresh_s: DEFAULT_DENSITY_REFRESH_S,
            cluster_m: DEFAULT_CLUSTER_M,
            tie_break_s_per_m2: DEFAULT_TIE_BREAK_S_PER_M2,
            transport_above_goals: LARGE_PLAN_GOALS,
        }
    }
}

/// Why a plan could not be made.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// The planning grid or cost field could not be built.
    #[error("planning grid: {0}")]
    Eikonal(#[from] EikonalError),
    /// The assignment failed even with Euclidean costs.
    #[error("assignment: {0}")]
    Assign(#[from] AssignError),
    /// The scene bounds do not make a planning grid.
    #[error("scene bounds do not make a planning grid")]
    Grid,
    /// The caller's [`Cancel`] check said the plan is no longer wanted.
    #[error("plan cancelled: its input is stale or the daemon is stopping")]
    Cancelled,
}

impl PlanError {
    /// Whether the plan was given up on request ([`Planner::plan_cancellable`]).
    pub fn is_cancelled(&self) -> bool {
        matches!(self, PlanError::Cancelled)
    }
}

/// Environment-aware assignment and routing (see the module doc). Keeps every
/// workspace between plans.
pub struct Planner {
    scene: Arc<Scene>,
    params: PlannerParams,
    raster: SceneGrid,
    grid: Grid,
    blocked: Vec<bool>,
    discomfort: Vec<f64>,
    cost: Vec<f64>,
    costs: EikonalCosts,
    clusters: Option<ClusterCosts>,
    matrix: CostMatrix,
    euclidean: PointCosts,
    solver: Solver,
    /// Candidates per row the solver was made with ([`solver_for`]).
    solver_k: usize,
    warm: bool,
    agents: Vec<Vec2>,
    goals: Vec<Vec2>,
    /// The grid transport of large plans, its graph built for the current cost
    /// grid when `transport_current`.
    transport: GridTransport,
    transport_current: bool,
    agent_cells: Vec<u32>,
    goal_cells: Vec<u32>,
    /// The last plan's goal per agent when the transport made it.
    transported: Vec<u32>,
    /// Whether the last plan was made by the transport.
    by_transport: bool,
    /// Agents ordered by cell, for [`uncross`].
    order: Vec<u32>,
    rasterised: bool,
    density_t_s: f64,
    fallbacks: u64,
}

impl Planner {
    /// A planner over `scene`.
    ///
    /// # Errors
    /// [`PlanError::Grid`] when the scene bounds give no grid; [`PlanError::Eikonal`]
    /// for bad parameters.
    pub fn new(scene: Arc<Scene>, params: PlannerParams) -> Result<Planner, PlanError> {
        let b = scene.bounds();
        let raster = SceneGrid::for_bounds(b, params.cell_m).map_err(|_| PlanError::Grid)?;
        let grid = Grid::new(raster.cols, raster.rows, raster.cell_m, raster.origin)?;
        let n = grid.len();
        // The cache holds every cluster's field, so every agent's route can be read
        // after a plan.
        let options = EikonalOptions {
            sources: FieldSources::Goals,
            cache_fields: MAX_CLUSTERS,
            ..EikonalOptions::default()
        };
        let clusters = if params.cluster_m == 0.0 {
            None
        } else {
            let mut c = ClusterCosts::new(params.cluster_m)?;
            c.set_tie_break(params.tie_break_s_per_m2)?;
            Some(c)
        };
        let costs = EikonalCosts::new(grid, &vec![1.0; n], options)?;
        let mut p = Planner {
            scene,
            params,
            raster,
            grid,
            blocked: vec![false; n],
            discomfort: vec![0.0; n],
            cost: vec![1.0; n],
            costs,
            clusters,
            matrix: CostMatrix::new(0, 0),
            euclidean: PointCosts::new(PointMetric::Euclidean),
            solver: Solver::new(),
            solver_k: 0,
            warm: false,
            agents: Vec::new(),
            goals: Vec::new(),
            transport: GridTransport::new(),
            transport_current: false,
            agent_cells: Vec::new(),
            goal_cells: Vec::new(),
            transported: Vec::new(),
            by_transport: false,
            order: Vec::new(),
            rasterised: false,
            density_t_s: f64::NEG_INFINITY,
            fallbacks: 0,
        };
        p.rasterise(0.0);
        Ok(p)
    }

    /// The scene.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The travel-cost provider (its cost grid is the last plan's).
    pub fn costs(&self) -> &EikonalCosts {
        &self.costs
    }

    /// The solver's work counters of the last plan solved over pairs.
    pub fn solve_stats(&self) -> crate::crowd::assign::SolveStats {
        self.solver.stats()
    }

    /// The grid transport's counters of the last plan it made, or `None` when the
    /// last plan was solved over pairs.
    pub fn transport_stats(&self) -> Option<TransportStats> {
        self.by_transport.then(|| self.transport.stats())
    }

    /// The clustered travel costs of the last plan (`None` with one field per goal).
    pub fn cluster_costs(&self) -> Option<&ClusterCosts> {
        self.clusters.as_ref()
    }

    /// Goal clusters of the last plan (0 with one field per goal).
    pub fn clusters(&self) -> usize {
        self.clusters.as_ref().map_or(0, |c| c.clusters())
    }

    /// The planning grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Plans that fell back to Euclidean costs (a point outside the grid and stuck
    /// in an obstacle, or an infeasible travel-cost assignment).
    pub fn fallbacks(&self) -> u64 {
        self.fallbacks
    }

    /// Forgets the previous solution (the next solve is cold).
    pub fn forget(&mut self) {
        self.warm = false;
    }

    fn rasterise(&mut self, t_s: f64) {
        self.scene.rasterize_into(&mut self.raster, t_s);
        // A cell whose centre is within a quarter cell of an obstacle is blocked too,
        // so thin walls are not skipped between cell centres.
        let guard = 0.25 * self.raster.cell_m;
        for (b, (&inside, &d)) in self.blocked.iter_mut().zip(
            self.raster
                .blocked
                .iter()
                .zip(&self.raster.obstacle_distance_m),
        ) {
            *b = inside || d < guard;
        }
        self.rasterised = true;
    }

    /// Assigns `goals` to `agents` at scene time `t_s` and writes each agent's goal
    /// index into `goal_of` and its waypoint into `waypoints` (NaN: head straight for
    /// the goal).
    ///
    /// # Formula
    /// Costs `Φ_j(a_i)` (mesh-formation-control eqs. 5–7); waypoints by gradient
    /// descent on `Φ_j` (section 6.2.1). Falls back to Euclidean distance when the
    /// travel costs cannot be computed or make the assignment infeasible.
    ///
    /// # Errors
    /// [`PlanError`] when even the Euclidean assignment fails; the outputs are
    /// untouched then.
    pub fn plan(
        &mut self,
        agents: &[Vec2],
        goals: &[Vec2],
        t_s: f64,
        goal_of: &mut Vec<u32>,
        waypoints: &mut Vec<Vec2>,
    ) -> Result<(), PlanError> {
        self.plan_cancellable(agents, goals, t_s, goal_of, waypoints, Cancel::NEVER)
    }

    /// [`Planner::plan`] that gives up when `cancel` says so: checked before each
    /// cluster's field, about every [`POLL_WORK`](crate::crowd::assign::POLL_WORK)
    /// units of the solver's work, and every few agents' waypoints. A cancelled
    /// plan does not fall back to Euclidean costs, and the next one is cold.
    ///
    /// # Errors
    /// As [`Planner::plan`], and [`PlanError::Cancelled`] (the outputs are then
    /// unspecified).
    pub fn plan_cancellable(
        &mut self,
        agents: &[Vec2],
        goals: &[Vec2],
        t_s: f64,
        goal_of: &mut Vec<u32>,
        waypoints: &mut Vec<Vec2>,
        cancel: Cancel<'_>,
    ) -> Result<(), PlanError> {
        let moving = !self.scene.dynamic().is_empty();
        let density_due =
            t_s - self.density_t_s >= self.params.density_refresh_s || t_s < self.density_t_s;
        if moving || !self.rasterised {
            self.rasterise(t_s);
        }
        if moving || density_due {
            self.density_t_s = t_s;
            self.rebuild_cost(agents)?;
        }
        // Points outside the grid are read at the nearest point inside it.
        let clamp = clamp_to(self.grid_bounds());
        self.agents.clear();
        self.agents.extend(agents.iter().map(|&p| clamp(p)));
        self.goals.clear();
        self.goals.extend(goals.iter().map(|&p| clamp(p)));
        let k = candidates_for(goals.len());
        if k != self.solver_k {
            self.solver = solver_for(goals.len());
            self.solver_k = k;
            self.warm = false;
        }
        self.by_transport = false;
        let solved = match self.transport_plan(goals.len(), cancel)? {
            Some(solved) => solved,
            None => self.pair_plan(cancel)?,
        };
        if !solved {
            self.fallbacks += 1;
            self.euclidean.set(agents, goals);
            self.warm = false;
            if let Err(e) = self.solve(true, cancel) {
                return Err(match e {
                    AssignError::Cancelled => self.cancelled(),
                    e => e.into(),
                });
            }
        }
        goal_of.clear();
        if self.by_transport {
            goal_of.extend_from_slice(&self.transported);
        } else {
            goal_of.extend(self.solver.assignment().iter().map(|&g| g as u32));
        }
        waypoints.clear();
        waypoints.resize(agents.len(), Vec2::repeat(f64::NAN));
        if solved {
            for (i, &g) in goal_of.iter().enumerate() {
                if i % WAYPOINTS_PER_POLL == 0 && cancel.cancelled() {
                    return Err(self.cancelled());
                }
                let g = g as usize;
                if self.by_transport {
                    waypoints[i] = self.waypoint_along(agents[i], goals[g], i, t_s);
                    continue;
                }
                let source = match &self.clusters {
                    Some(c) => c.source_of(g),
                    None => self.goals[g],
                };
                waypoints[i] = self.waypoint(agents[i], goals[g], source, t_s);
            }
        }
        Ok(())
    }

    /// A plan of more than [`PlannerParams::transport_above_goals`] goals by the
    /// grid transport ([`Self::transport`]; its paths give the waypoints, so no
    /// field is marched). `None`: not a transport plan, or the transport could not
    /// be solved (the plan is then solved over pairs).
    fn transport_plan(
        &mut self,
        goals: usize,
        cancel: Cancel<'_>,
    ) -> Result<Option<bool>, PlanError> {
        if goals <= self.params.transport_above_goals {
            return Ok(None);
        }
        match self.transport(cancel) {
            Ok(()) => Ok(Some(true)),
            Err(TransportError::Cancelled) => Err(self.cancelled()),
            Err(e) => {
                log::debug!("planner: grid transport not possible ({e}); solving over pairs");
                Ok(None)
            }
        }
    }

    /// A plan solved over pairs: the travel costs filled, then the solver; `false`
    /// when either fails (the Euclidean fallback follows).
    fn pair_plan(&mut self, cancel: Cancel<'_>) -> Result<bool, PlanError> {
        let filled = match &mut self.clusters {
            Some(c) => c.fill_cancellable(&self.costs, &self.agents, &self.goals, cancel),
            None => {
                self.costs
                    .try_fill_cancellable(&self.agents, &self.goals, &mut self.matrix, cancel)
            }
        };
        match filled {
            Err(EikonalError::Cancelled) => Err(self.cancelled()),
            Err(_) => Ok(false),
            Ok(()) => match self.solve(false, cancel) {
                Err(AssignError::Cancelled) => Err(self.cancelled()),
                r => Ok(r.is_ok()),
            },
        }
    }

    /// Solves as a transport on the planning grid ([`GridTransport`]): every agent
    /// and goal at the free cell the travel costs snap it to.
    fn transport(&mut self, cancel: Cancel<'_>) -> Result<(), TransportError> {
        if !self.transport_current {
            self.transport.set_grid(&self.grid, &self.cost);
            self.transport_current = true;
        }
        // A point inside an obstacle (a goal on a building, an agent pushed into
        // one) stands at the nearest free cell, however far.
        let (costs, transport, grid) = (&self.costs, &self.transport, &self.grid);
        let snap = |p| {
            costs
                .source_cell_of(p)
                .or_else(|| transport.nearest_free(grid, p).map(|c| c as usize))
        };
        cells_of("agent", &self.agents, snap, &mut self.agent_cells)?;
        cells_of("goal", &self.goals, snap, &mut self.goal_cells)?;
        self.transport.solve(
            &self.agent_cells,
            &self.goal_cells,
            &mut self.transported,
            cancel,
        )?;
        uncross(
            &self.agents,
            &self.goals,
            &self.agent_cells,
            &self.goal_cells,
            &mut self.transported,
            &mut self.order,
        );
        self.by_transport = true;
        // The pair solver's prices do not belong to this assignment.
        self.warm = false;
        Ok(())
    }

    /// Solves on the travel costs, or on Euclidean distances (`euclidean`).
    fn solve(&mut self, euclidean: bool, cancel: Cancel<'_>) -> Result<(), AssignError> {
        let warm = self.warm;
        let s = &mut self.solver;
        let r = match (&self.clusters, euclidean) {
            (_, true) => s.solve_with_cancel(&self.euclidean, cancel).map(|_| ()),
            (Some(c), false) if warm => s.solve_warm_with_cancel(c, cancel).map(|_| ()),
            (Some(c), false) => s.solve_with_cancel(c, cancel).map(|_| ()),
            (None, false) if warm => s.solve_warm_with_cancel(&self.matrix, cancel).map(|_| ()),
            (None, false) => s.solve_with_cancel(&self.matrix, cancel).map(|_| ()),
        };
        self.warm = r.is_ok() && !euclidean;
        r
    }

    /// A plan given up: the next one starts cold.
    fn cancelled(&mut self) -> PlanError {
        self.warm = false;
        PlanError::Cancelled
    }

    fn rebuild_cost(&mut self, agents: &[Vec2]) -> Result<(), PlanError> {
        discomfort_into(
            &self.grid,
            &self.raster.obstacle_distance_m,
            agents,
            self.params.discomfort,
            &mut self.discomfort,
        )?;
        cost_field_into(
            &self.grid,
            self.params.weights,
            self.params.preferred_speed_m_s,
            CostInputs {
                blocked: &self.blocked,
                speed_factor: &self.raster.speed_factor,
                discomfort: Some(&self.discomfort),
            },
            &mut self.cost,
        )?;
        self.costs.set_cost(&self.cost)?;
        self.transport_current = false;
        Ok(())
    }

    fn grid_bounds(&self) -> (Vec2, Vec2) {
        let g = &self.grid;
        let lo = g.origin();
        let hi = lo + Vec2::new(g.cols() as f64, g.rows() as f64) * g.cell_m();
        let eps = 1e-6 * g.cell_m();
        (lo + Vec2::repeat(eps), hi - Vec2::repeat(eps))
    }

    /// The route of an agent at `a` to `goal` by descent on the field the last plan
    /// read its cost from (the goal's cluster, or the goal's own field), one cell
    /// per step, ending where the goal is visible; `out` gets the points after `a`.
    /// Empty when the goal is visible from `a` or no field of the last plan leads
    /// to it.
    pub fn route(&self, a: Vec2, goal: Vec2, t_s: f64, out: &mut Vec<Vec2>) {
        out.clear();
        if self.scene.visible(a, goal, t_s) {
            return;
        }
        let clamp = clamp_to(self.grid_bounds());
        let source = match &self.clusters {
            Some(c) => match c.source_near(&self.costs, clamp(goal)) {
                Some(s) => s,
                None => return,
            },
            None => clamp(goal),
        };
        let step = self.grid.cell_m();
        let mut p = clamp(a);
        for _ in 0..MAX_ROUTE_STEPS {
            let Some(d) = self.costs.descent(source, p) else {
                return;
            };
            p += d * step;
            out.push(p);
            if self.scene.visible(p, goal, t_s) {
                return;
            }
        }
    }

    /// The waypoint of agent `i` of a transport plan, at `a` bound for `goal`: as
    /// [`Self::waypoint`], the farthest point of its route that `a` sees (NaN when
    /// `a` sees its goal), the route being its path on the planning grid
    /// ([`GridTransport::path`], cell centres) instead of a field's descent.
    fn waypoint_along(&self, a: Vec2, goal: Vec2, i: usize, t_s: f64) -> Vec2 {
        let none = Vec2::repeat(f64::NAN);
        if self.scene.visible(a, goal, t_s) {
            return none;
        }
        let mut best = none;
        for &cell in self.transport.path(i).iter().skip(1).take(MAX_ROUTE_STEPS) {
            let q = self.grid.center(cell as usize);
            if !self.scene.visible(a, q, t_s) {
                break;
            }
            best = q;
            if self.scene.visible(q, goal, t_s) {
                break;
            }
        }
        best
    }

    /// The farthest point of the agent's route towards `source` (the field its cost
    /// was read from) that it can see, stopping where `goal` comes into view (NaN
    /// when the goal is visible or there is no route).
    fn waypoint(&self, a: Vec2, goal: Vec2, source: Vec2, t_s: f64) -> Vec2 {
        let none = Vec2::repeat(f64::NAN);
        if self.scene.visible(a, goal, t_s) {
            return none;
        }
        let clamp = clamp_to(self.grid_bounds());
        let step = self.grid.cell_m();
        let mut p = clamp(a);
        let mut best = none;
        for _ in 0..MAX_ROUTE_STEPS {
            let Some(d) = self.costs.descent(source, p) else {
                break;
            };
            let q = p + d * step;
            if !self.scene.visible(a, q, t_s) {
                break;
            }
            p = q;
            best = p;
            if self.scene.visible(p, goal, t_s) {
                break;
            }
        }
        best
    }
}

/// Rounds of [`uncross`] over the agents' cells and their goals' cells.
const UNCROSS_ROUNDS: usize = 3;

/// Swaps the goals of two agents when they share a cell, or their goals share one,
/// and the swap shortens the pair's total squared straight-line distance. Neither
/// swap changes the grid transport's cost (its paths start and end at cells, so
/// the two agents' paths are the same set either way), so `goal_of` stays a
/// cheapest assignment of the graph; what it removes is the crossing of
/// neighbours inside a cell that the cell-level flow cannot see. Groups are a few
/// agents each at the shipped densities, `O(Σ group²)` per round.
fn uncross(
    agents: &[Vec2],
    goals: &[Vec2],
    agent_cells: &[u32],
    goal_cells: &[u32],
    goal_of: &mut [u32],
    order: &mut Vec<u32>,
) {
    let d2 = |i: usize, j: u32| (agents[i] - goals[j as usize]).norm_squared();
    for _ in 0..UNCROSS_ROUNDS {
        let mut swaps = 0usize;
        for by_goal in [false, true] {
            let key = |i: u32, goal_of: &[u32]| {
                if by_goal {
                    goal_cells[goal_of[i as usize] as usize]
                } else {
                    agent_cells[i as usize]
                }
            };
            order.clear();
            order.extend(0..agents.len() as u32);
            order.sort_unstable_by_key(|&i| key(i, goal_of));
            let mut start = 0;
            while start < order.len() {
                let k = key(order[start], goal_of);
                let mut end = start + 1;
                while end < order.len() && key(order[end], goal_of) == k {
                    end += 1;
                }
                for x in start..end {
                    for y in x + 1..end {
                        let (i, j) = (order[x] as usize, order[y] as usize);
                        let (gi, gj) = (goal_of[i], goal_of[j]);
                        if d2(i, gj) + d2(j, gi) < d2(i, gi) + d2(j, gj) {
                            goal_of.swap(i, j);
                            swaps += 1;
                        }
                    }
                }
                start = end;
            }
        }
        if swaps == 0 {
            break;
        }
    }
}

/// Candidates per row of the planner's solver for `goals` goals (0: the solver's
/// automatic choice).
fn candidates_for(goals: usize) -> usize {
    if goals > LARGE_PLAN_GOALS {
        (goals / LARGE_PLAN_CANDIDATES_DIV).min(LARGE_PLAN_CANDIDATES_MAX)
    } else {
        0
    }
}

/// The planner's solver for `goals` goals. Up to [`LARGE_PLAN_GOALS`] the default
/// one. Above, travel costs are nearly flat along the direction of travel (the
/// reduced costs `c − v` of a row stay within a few cost spreads over hundreds of
/// goals), so the default 64 candidates per row run out again and again in the
/// auction (each refill a pass over the row); the lists are longer then
/// (`goals / 20`, at most 256), and a warm start goes on from the old prices
/// however many pairs broke, which at 5,000 agents is quicker than starting over.
/// The answer is the optimum either way.
fn solver_for(goals: usize) -> Solver {
    let mut s = Solver::with_options(Strategy::Auto, candidates_for(goals));
    s.set_warm_restarts(goals <= LARGE_PLAN_GOALS);
    s
}

fn clamp_to((lo, hi): (Vec2, Vec2)) -> impl Fn(Vec2) -> Vec2 {
    move |p: Vec2| {
        if p.x.is_finite() && p.y.is_finite() {
            Vec2::new(p.x.clamp(lo.x, hi.x), p.y.clamp(lo.y, hi.y))
        } else {
            p
        }
    }
}

/// Where the control thread steers an agent at `pos` assigned to `goal`: straight at
/// the goal when it is visible in the scene at the tick's time or there is no
/// waypoint (NaN), else at the waypoint the planner gave.
///
/// # Complexity
/// O(obstacle parts) when the agent has a waypoint, O(1) otherwise.
pub fn steer_target(scene: &SceneAt<'_>, pos: Vec2, goal: Vec2, waypoint: Vec2) -> Vec2 {
    if !waypoint.x.is_finite() || scene.visible(pos, goal) {
        goal
    } else {
        waypoint
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::environment::load_scene;
    use std::cell::Cell;
    use std::path::Path;

    /// A 12 × 12 crowd west of the single block, its formation east of it.
    fn instance() -> (Arc<Scene>, Vec<Vec2>, Vec<Vec2>) {
        let scene = load_scene(Path::new("config/scenes/single_block.ron"), 0.15).unwrap();
        let grid = |x0: f64, y0: f64, d: f64| -> Vec<Vec2> {
            (0..144)
                .map(|k| Vec2::new(x0 + (k % 12) as f64 * d, y0 + (k / 12) as f64 * d))
                .collect()
        };
        (Arc::new(scene), grid(8.0, 3.0, 0.25), grid(14.0, 3.4, 0.15))
    }

    /// Every check site returns at once: a check that fires at its n-th call is
    /// called exactly n times, in every phase of the plan (fields, solve,
    /// waypoints), and the next plan is the one a fresh planner makes.
    #[test]
    fn a_cancelled_plan_stops_at_the_first_check_that_fires() {
        let (scene, agents, goals) = instance();
        let params = PlannerParams::new(1.5);
        let (mut want_g, mut want_w) = (Vec::new(), Vec::new());
        let mut reference = Planner::new(Arc::clone(&scene), params).unwrap();
        let calls = Cell::new(0u64);
        let counting = || {
            calls.set(calls.get() + 1);
            false
        };
        reference
            .plan_cancellable(
                &agents,
                &goals,
                0.0,
                &mut want_g,
                &mut want_w,
                Cancel::new(&counting),
            )
            .unwrap();
        let total = calls.get();
        assert!(total > 10, "{total} checks in a whole plan");
        assert!(
            want_w.iter().any(|w| w.x.is_finite()),
            "some agents route around the block"
        );
        let mut p = Planner::new(Arc::clone(&scene), params).unwrap();
        let (mut g, mut w) = (Vec::new(), Vec::new());
        for n in [1, 2, total / 4, total / 2, total - 1, total] {
            calls.set(0);
            let fires = || {
                calls.set(calls.get() + 1);
                calls.get() >= n
            };
            let r = p.plan_cancellable(&agents, &goals, 0.0, &mut g, &mut w, Cancel::new(&fires));
            assert_eq!(
                r,
                Err(PlanError::Cancelled),
                "fired at check {n} of {total}"
            );
            assert!(r.unwrap_err().is_cancelled());
            assert_eq!(calls.get(), n);
            assert_eq!(p.fallbacks(), 0, "a cancelled plan does not fall back");
        }
        p.plan(&agents, &goals, 0.0, &mut g, &mut w).unwrap();
        assert_eq!(g, want_g);
        assert_eq!(
            w.iter().map(|v| v.map(f64::to_bits)).collect::<Vec<_>>(),
            want_w
                .iter()
                .map(|v| v.map(f64::to_bits))
                .collect::<Vec<_>>()
        );
    }
}
