//! The assignment of a large crowd as a transport on the planning grid.
//!
//! mesh-formation-control section 6.2 prices every agent–goal pair by its travel cost
//! `Φ_j(a_i)` (eq. 6) and solves the transportation problem of section 6.1 over those
//! pairs (eq. 2). When the cost of a pair is the cheapest path between two cells of a
//! graph, that problem is a min-cost flow on the graph itself (Beckmann's
//! formulation of transport at distance cost): each agent's cell supplies one unit,
//! each goal's cell takes up to one unit per goal, every arc between neighbouring
//! cells carries any amount at its travel cost, and the optimal flow, cut into paths,
//! is an optimal assignment for the graph's path costs. The graph here is the
//! planning grid with 16 neighbours per cell (the 8 nearest and the 8 a knight's
//! move away), each arc priced by [`segment_cost`] (the line integral of the eq. 7
//! unit cost along the straight segment between the cell centres; an arc that
//! crosses a blocked cell is left out).
//!
//! # What is approximated
//!
//! Against the eq. 6 costs of the pairs (what [`ClusterCosts`](super::ClusterCosts)
//! and [`EikonalCosts`](super::EikonalCosts) give), two things differ: the graph's
//! paths turn only at cell centres in 16 directions (a straight path between two
//! centres costs up to 2.7 % more on the graph, at 13° off an axis; 0 % along the
//! 16 directions), and every agent and goal stands at its cell's centre. The
//! planner measures the result on the eq. 6 costs it would otherwise solve
//! exactly (docs/scenes-and-formations.md).
//!
//! # Method
//!
//! Cost scaling with push and relabel (Goldberg and Tarjan, "Finding minimum-cost
//! circulations by successive approximation", 1990; the `refine` of Goldberg, "An
//! efficient implementation of a scaling minimum-cost flow algorithm", 1997): arc
//! costs are integers (`COST_SCALE` units per second of travel, times the node
//! count so that a flow that is ε-optimal with `ε < 1` is optimal), `ε` starts at
//! the largest arc cost and is divided by `ALPHA` per phase, and each phase pushes
//! the excess of the phase's saturated arcs along admissible arcs (reduced cost
//! below 0), relabelling a node when none is left. A super sink takes one unit per
//! goal, so a crowd with more goals than agents leaves the goals it pleases empty.
//!
//! # Complexity
//!
//! `O(n² m log(n C))` in the worst case (`n` cells, `m` arcs, `C` the largest
//! arc cost); on the planning grids of the shipped scenes (about 5,600 cells and
//! 80,000 arcs) a solve is tens of milliseconds whatever the crowd size, against
//! `O(agents × goals)` per pass for the solvers over pairs.

use super::grid::Grid;
use super::segment::segment_cost;
use super::simplex::{Simplex, SimplexError};
use crate::crowd::assign::{Cancel, POLL_WORK};
use crate::geom::Vec2;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// Integer cost units per second of travel (before the node-count factor): a
/// 16 cm arc at 1 s/m is 16,000 units, so rounding moves an arc by at most 3·10⁻⁵.
const COST_SCALE: f64 = 1e5;
/// Factor `ε` is divided by between phases.
const ALPHA: i64 = 8;
/// One of each pair of opposite neighbour offsets `(dc, dr)` of the 16-neighbourhood.
const OFFSETS: [(isize, isize); 8] = [
    (1, 0),
    (0, 1),
    (1, 1),
    (1, -1),
    (2, 1),
    (1, 2),
    (2, -1),
    (1, -2),
];

/// Why a transport could not be solved.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TransportError {
    /// An agent or goal cell index is outside the grid the arcs were built for.
    #[error("{what} {index} is in cell {cell}, outside the grid of {cells} cells")]
    CellOutside {
        /// `"agent"` or `"goal"`.
        what: &'static str,
        /// Index of the agent or goal.
        index: usize,
        /// The cell given.
        cell: u32,
        /// Cells of the grid.
        cells: usize,
    },
    /// An agent or goal has no free cell to stand in (see [`cells_of`]).
    #[error("{what} {index} has no free cell near it")]
    NoFreeCell {
        /// `"agent"` or `"goal"`.
        what: &'static str,
        /// Index of the agent or goal.
        index: usize,
    },
    /// More agents than goals.
    #[error("{agents} agents and only {goals} goals")]
    TooFewGoals {
        /// Agents given.
        agents: usize,
        /// Goals given.
        goals: usize,
    },
    /// Some agents stand where fewer goals can be reached than there are agents (a
    /// blocked cell, or a part of the grid walled off from enough goals).
    #[error("agent {agent} (cell {cell}) cannot reach a goal of its own: its part of the grid has {agents} agents and {goals} goals")]
    Unreachable {
        /// The first such agent.
        agent: usize,
        /// Its cell.
        cell: u32,
        /// Agents in its part of the grid.
        agents: usize,
        /// Goals in its part of the grid.
        goals: usize,
    },
    /// The flow found does not cut into paths (a flow without conservation at
    /// `cell`): a defect of the solver, reported rather than trusted.
    #[error("the flow is not balanced at cell {cell}")]
    Unbalanced {
        /// The cell where a path could not go on.
        cell: u32,
    },
    /// [`GridTransport::set_grid`] has not been called.
    #[error("no grid: set_grid was not called")]
    NoGrid,
    /// The caller's [`Cancel`] check fired.
    #[error("transport cancelled")]
    Cancelled,
}

/// Work counters of the last solve.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct TransportStats {
    /// Arcs of the graph (both directions of each neighbour pair, without residuals).
    pub arcs: usize,
    /// Scaling phases.
    pub phases: u32,
    /// Pushes.
    pub pushes: u64,
    /// Relabels.
    pub relabels: u64,
    /// Total travel cost of the assignment on the graph (s).
    pub graph_cost_s: f64,
}

/// Min-cost flow on the planning grid (see the module doc). Keeps its graph between
/// solves while the cost grid stays ([`GridTransport::set_grid`]).
#[derive(Default)]
pub struct GridTransport {
    cells: usize,
    /// Arcs of node `v` are `first[v]..first[v + 1]` (node `cells` is the sink).
    first: Vec<u32>,
    head: Vec<u32>,
    cost: Vec<i64>,
    cap: Vec<i32>,
    rev: Vec<u32>,
    /// What an arc is: a grid arc (`GRID`), its residual (`RESIDUAL`), a cell's arc
    /// to the sink (`SINK`) or the sink's residual back (`RESIDUAL`).
    kind: Vec<u8>,
    /// The arc of each cell to the sink.
    sink_arc: Vec<u32>,
    /// Connected part of each cell (`u32::MAX`: blocked).
    part: Vec<u32>,
    parts: usize,
    max_cost: i64,
    price: Vec<i64>,
    excess: Vec<i64>,
    current: Vec<u32>,
    queued: Vec<bool>,
    queue: VecDeque<u32>,
    /// Distances (in units of ε) of the global price update, and its queue.
    dist: Vec<i64>,
    heap: BinaryHeap<Reverse<(i64, u32)>>,
    part_agents: Vec<usize>,
    part_goals: Vec<usize>,
    goal_start: Vec<u32>,
    goal_list: Vec<u32>,
    stats: TransportStats,
    simplex: Simplex,
    /// The simplex arc of each grid arc (`u32::MAX` for other arcs).
    simplex_arc: Vec<u32>,
    supply: Vec<i64>,
    /// Goals of each cell the agents may take (those the surplus does not fill).
    open_goals: Vec<i64>,
}

const GRID: u8 = 0;
const RESIDUAL: u8 = 1;
const SINK: u8 = 2;

impl GridTransport {
    /// An empty transport; call [`GridTransport::set_grid`] before solving.
    pub fn new() -> GridTransport {
        GridTransport::default()
    }

    /// Work counters of the last solve.
    pub fn stats(&self) -> TransportStats {
        self.stats
    }

    /// Builds the graph for `grid` with unit cost `cost` (s/m per cell, `+inf`
    /// blocked; eq. 7).
    ///
    /// # Complexity
    /// One [`segment_cost`] per arc: about 45,000 for a 100 × 56 grid.
    pub fn set_grid(&mut self, grid: &Grid, cost: &[f64]) {
        let n = grid.len();
        assert_eq!(cost.len(), n, "one cost per cell");
        let (cols, rows) = (grid.cols() as isize, grid.rows() as isize);
        let free = |c: isize, r: isize| -> bool {
            c >= 0 && r >= 0 && c < cols && r < rows && cost[(r * cols + c) as usize].is_finite()
        };
        // Undirected edges with their cost, found once per pair.
        let mut edges: Vec<(u32, u32, f64)> = Vec::with_capacity(n * OFFSETS.len());
        for r in 0..rows {
            for c in 0..cols {
                if !free(c, r) {
                    continue;
                }
                let u = (r * cols + c) as usize;
                for &(dc, dr) in &OFFSETS {
                    if !free(c + dc, r + dr) {
                        continue;
                    }
                    let v = ((r + dr) * cols + c + dc) as usize;
                    let s = segment_cost(grid, cost, grid.center(u), grid.center(v));
                    if s.is_finite() && s > 0.0 {
                        edges.push((u as u32, v as u32, s));
                    }
                }
            }
        }
        let nodes = n + 1;
        let scale = COST_SCALE * nodes as f64;
        let mut degree = vec![0u32; nodes + 1];
        for &(u, v, _) in &edges {
            degree[u as usize] += 2;
            degree[v as usize] += 2;
        }
        for (u, d) in degree.iter_mut().enumerate().take(n) {
            if cost[u].is_finite() {
                *d += 1;
            }
        }
        degree[n] = cost.iter().filter(|c| c.is_finite()).count() as u32;
        self.first.clear();
        self.first.push(0);
        for v in 0..nodes {
            let f = self.first[v] + degree[v];
            self.first.push(f);
        }
        let m = self.first[nodes] as usize;
        self.head.clear();
        self.head.resize(m, 0);
        self.cost.clear();
        self.cost.resize(m, 0);
        self.cap.clear();
        self.cap.resize(m, 0);
        self.rev.clear();
        self.rev.resize(m, 0);
        self.kind.clear();
        self.kind.resize(m, RESIDUAL);
        let mut fill: Vec<u32> = self.first[..nodes].to_vec();
        let mut add = |tail: usize, head: usize, c: i64, k: u8, this: &mut GridTransport| {
            let a = fill[tail] as usize;
            fill[tail] += 1;
            let b = fill[head] as usize;
            fill[head] += 1;
            this.head[a] = head as u32;
            this.cost[a] = c;
            this.kind[a] = k;
            this.rev[a] = b as u32;
            this.head[b] = tail as u32;
            this.cost[b] = -c;
            this.kind[b] = RESIDUAL;
            this.rev[b] = a as u32;
            a
        };
        self.max_cost = 1;
        for &(u, v, s) in &edges {
            let c = ((s * COST_SCALE).round().max(1.0) * nodes as f64) as i64;
            debug_assert!(c as f64 <= scale * 1e6);
            self.max_cost = self.max_cost.max(c);
            add(u as usize, v as usize, c, GRID, self);
            add(v as usize, u as usize, c, GRID, self);
        }
        self.sink_arc.clear();
        self.sink_arc.resize(n, u32::MAX);
        for u in 0..n {
            if cost[u].is_finite() {
                self.sink_arc[u] = add(u, n, 0, SINK, self) as u32;
            }
        }
        // Connected parts (arcs are symmetric), for the feasibility check.
        self.part.clear();
        self.part.resize(n, u32::MAX);
        self.parts = 0;
        let mut stack = Vec::new();
        for s in 0..n {
            if self.part[s] != u32::MAX || !cost[s].is_finite() {
                continue;
            }
            let p = self.parts as u32;
            self.parts += 1;
            self.part[s] = p;
            stack.push(s);
            while let Some(u) = stack.pop() {
                for a in self.first[u] as usize..self.first[u + 1] as usize {
                    let w = self.head[a] as usize;
                    if self.kind[a] == GRID && self.part[w] == u32::MAX {
                        self.part[w] = p;
                        stack.push(w);
                    }
                }
            }
        }
        self.cells = n;
        self.stats.arcs = 2 * edges.len();
        self.price.clear();
        self.price.resize(nodes, 0);
        self.excess.clear();
        self.excess.resize(nodes, 0);
        self.current.clear();
        self.current.resize(nodes, 0);
        self.queued.clear();
        self.queued.resize(nodes, false);
        self.dist.clear();
        self.dist.resize(nodes, 0);
    }

    /// Assigns agent `i`, standing in cell `agent_cells[i]`, the goal `out[i]` among
    /// the goals in cells `goal_cells`, minimising the total graph travel cost (see
    /// the module doc).
    ///
    /// # Errors
    /// [`TransportError`]: no grid, a cell outside it, fewer goals than agents, an
    /// agent in a blocked cell or a part of the grid with too few goals, or
    /// cancelled. `out` is unspecified then.
    pub fn solve(
        &mut self,
        agent_cells: &[u32],
        goal_cells: &[u32],
        out: &mut Vec<u32>,
        cancel: Cancel<'_>,
    ) -> Result<TransportStats, TransportError> {
        if self.first.is_empty() {
            return Err(TransportError::NoGrid);
        }
        let n = self.cells;
        let (agents, goals) = (agent_cells.len(), goal_cells.len());
        if agents > goals {
            return Err(TransportError::TooFewGoals { agents, goals });
        }
        for (what, cells) in [("agent", agent_cells), ("goal", goal_cells)] {
            if let Some((index, &cell)) = cells.iter().enumerate().find(|(_, &c)| c as usize >= n) {
                return Err(TransportError::CellOutside {
                    what,
                    index,
                    cell,
                    cells: n,
                });
            }
        }
        self.check_parts(agent_cells, goal_cells)?;
        if std::env::var_os("CT_TRANSPORT_SCALING").is_none() {
            return self.solve_by_simplex(agent_cells, goal_cells, out, cancel);
        }
        self.stats = TransportStats {
            arcs: self.stats.arcs,
            ..TransportStats::default()
        };
        // Flow 0, every grid arc open to the whole crowd, each cell's sink arc to
        // its goals.
        let big = agents as i32;
        for (&k, c) in self.kind.iter().zip(self.cap.iter_mut()) {
            *c = if k == GRID { big } else { 0 };
        }
        for &g in goal_cells {
            let a = self.sink_arc[g as usize];
            if a != u32::MAX {
                self.cap[a as usize] += 1;
            }
        }
        self.excess.iter_mut().for_each(|e| *e = 0);
        for &c in agent_cells {
            self.excess[c as usize] += 1;
        }
        self.excess[n] = -(agents as i64);
        self.price.iter_mut().for_each(|p| *p = 0);
        let mut eps = self.max_cost;
        let mut work = 0u64;
        loop {
            eps = (eps / ALPHA).max(1);
            let t0 = std::time::Instant::now();
            let (p0, r0) = (self.stats.pushes, self.stats.relabels);
            self.refine(eps, &mut work, cancel)?;
            if std::env::var_os("CT_TRANSPORT_TRACE").is_some() {
                eprintln!("eps {eps}: {:?} pushes {} relabels {}", t0.elapsed(), self.stats.pushes - p0, self.stats.relabels - r0);
            }
            self.stats.phases += 1;
            if eps == 1 {
                break;
            }
        }
        self.decompose(agent_cells, goal_cells, out)?;
        Ok(self.stats)
    }

    /// [`GridTransport::solve`] by the network simplex: supplies `agents − goals`
    /// per cell, and a node that supplies the goals no agent takes, joined to every
    /// goal cell at no cost.
    fn solve_by_simplex(
        &mut self,
        agent_cells: &[u32],
        goal_cells: &[u32],
        out: &mut Vec<u32>,
        cancel: Cancel<'_>,
    ) -> Result<TransportStats, TransportError> {
        let n = self.cells;
        self.stats = TransportStats {
            arcs: self.stats.arcs,
            ..TransportStats::default()
        };
        self.simplex.reset(n + 1);
        self.simplex_arc.clear();
        self.simplex_arc.resize(self.head.len(), u32::MAX);
        for u in 0..n {
            for a in self.first[u] as usize..self.first[u + 1] as usize {
                if self.kind[a] == GRID {
                    self.simplex_arc[a] = self.simplex.add_arc(u as u32, self.head[a], self.cost[a]) as u32;
                }
            }
        }
        self.supply.clear();
        self.supply.resize(n + 1, 0);
        self.open_goals.clear();
        self.open_goals.resize(n, 0);
        for &c in agent_cells {
            self.supply[c as usize] += 1;
        }
        for &g in goal_cells {
            self.supply[g as usize] -= 1;
            self.open_goals[g as usize] += 1;
        }
        self.supply[n] = (goal_cells.len() - agent_cells.len()) as i64;
        // The surplus node's arcs, one per goal cell, remembered in `goal_start`.
        self.goal_start.clear();
        self.goal_start.resize(n + 1, u32::MAX);
        if self.supply[n] > 0 {
            for c in 0..n {
                if self.open_goals[c] > 0 {
                    self.goal_start[c] = self.simplex.add_arc(n as u32, c as u32, 0) as u32;
                }
            }
        }
        self.simplex
            .solve(&self.supply, || cancel.cancelled())
            .map_err(|e| match e {
                SimplexError::Cancelled => TransportError::Cancelled,
                _ => TransportError::Unbalanced { cell: n as u32 },
            })?;
        self.stats.pushes = self.simplex.pivots;
        for c in 0..n {
            if self.goal_start[c] != u32::MAX {
                self.open_goals[c] -= self.simplex.flow(self.goal_start[c] as usize);
            }
        }
        // Goals by cell, taken from the end of each cell's run.
        self.goal_start.clear();
        self.goal_start.resize(n + 1, 0);
        for &g in goal_cells {
            self.goal_start[g as usize + 1] += 1;
        }
        for c in 0..n {
            self.goal_start[c + 1] += self.goal_start[c];
        }
        self.goal_list.clear();
        self.goal_list.resize(goal_cells.len(), 0);
        for (j, &g) in goal_cells.iter().enumerate() {
            let at = &mut self.goal_start[g as usize];
            self.goal_list[*at as usize] = j as u32;
            *at += 1;
        }
        for c in 0..n {
            self.current[c] = self.first[c];
        }
        // Each agent follows arcs with flow left until a cell with an open goal.
        self.excess.clear();
        self.excess.resize(self.head.len(), 0);
        for (a, &k) in self.simplex_arc.iter().enumerate() {
            if k != u32::MAX {
                self.excess[a] = self.simplex.flow(k as usize);
            }
        }
        let mut cost_units: i64 = 0;
        out.clear();
        for &start in agent_cells {
            let mut u = start as usize;
            loop {
                if self.open_goals[u] > 0 {
                    self.open_goals[u] -= 1;
                    let at = &mut self.goal_start[u];
                    *at -= 1;
                    out.push(self.goal_list[*at as usize]);
                    break;
                }
                let end = self.first[u + 1] as usize;
                let mut a = self.current[u] as usize;
                while a < end && self.excess[a] <= 0 {
                    a += 1;
                }
                if a == end {
                    return Err(TransportError::Unbalanced { cell: u as u32 });
                }
                self.current[u] = a as u32;
                self.excess[a] -= 1;
                cost_units += self.cost[a];
                u = self.head[a] as usize;
            }
        }
        self.stats.graph_cost_s = cost_units as f64 / (COST_SCALE * (n + 1) as f64);
        // `excess` holds arc flows here; the scaling path sizes it per node again.
        self.excess.clear();
        self.excess.resize(n + 1, 0);
        Ok(self.stats)
    }

    fn check_parts(&mut self, agent_cells: &[u32], goal_cells: &[u32]) -> Result<(), TransportError> {
        self.part_agents.clear();
        self.part_agents.resize(self.parts, 0);
        self.part_goals.clear();
        self.part_goals.resize(self.parts, 0);
        for &g in goal_cells {
            let p = self.part[g as usize];
            if p != u32::MAX {
                self.part_goals[p as usize] += 1;
            }
        }
        for &a in agent_cells {
            let p = self.part[a as usize];
            if p != u32::MAX {
                self.part_agents[p as usize] += 1;
            }
        }
        for (agent, &cell) in agent_cells.iter().enumerate() {
            let p = self.part[cell as usize];
            let (a, g) = if p == u32::MAX {
                (1, 0)
            } else {
                (self.part_agents[p as usize], self.part_goals[p as usize])
            };
            if a > g {
                return Err(TransportError::Unreachable {
                    agent,
                    cell,
                    agents: a,
                    goals: g,
                });
            }
        }
        Ok(())
    }

    /// One phase: makes the flow `eps`-optimal (Goldberg 1997, `refine`).
    fn refine(&mut self, eps: i64, work: &mut u64, cancel: Cancel<'_>) -> Result<(), TransportError> {
        let nodes = self.cells + 1;
        // Saturate every residual arc of reduced cost below -ε: the flow is then
        // ε-optimal and no longer balanced.
        for v in 0..nodes {
            let pv = self.price[v];
            for a in self.first[v] as usize..self.first[v + 1] as usize {
                let d = self.cap[a];
                if d > 0 {
                    let w = self.head[a] as usize;
                    if self.cost[a] + pv - self.price[w] < -eps {
                        self.cap[a] = 0;
                        self.cap[self.rev[a] as usize] += d;
                        self.excess[v] -= i64::from(d);
                        self.excess[w] += i64::from(d);
                    }
                }
            }
        }
        self.queue.clear();
        for v in 0..nodes {
            self.current[v] = self.first[v];
            self.queued[v] = self.excess[v] > 0;
            if self.queued[v] {
                self.queue.push_back(v as u32);
            }
        }
        self.update_prices(eps);
        let mut relabels_since_update = 0usize;
        while let Some(v) = self.queue.pop_front() {
            let v = v as usize;
            self.queued[v] = false;
            let end = self.first[v + 1] as usize;
            while self.excess[v] > 0 {
                let pv = self.price[v];
                let mut a = self.current[v] as usize;
                while a < end {
                    let d = self.cap[a];
                    if d > 0 {
                        let w = self.head[a] as usize;
                        if self.cost[a] + pv - self.price[w] < 0 {
                            let d = i64::from(d).min(self.excess[v]);
                            self.cap[a] -= d as i32;
                            self.cap[self.rev[a] as usize] += d as i32;
                            self.excess[v] -= d;
                            let before = self.excess[w];
                            self.excess[w] += d;
                            self.stats.pushes += 1;
                            if before <= 0 && self.excess[w] > 0 && !self.queued[w] {
                                self.queued[w] = true;
                                self.queue.push_back(w as u32);
                            }
                            if self.excess[v] == 0 {
                                break;
                            }
                        }
                    }
                    a += 1;
                }
                *work += (a - self.current[v] as usize) as u64 + 1;
                self.current[v] = a as u32;
                if self.excess[v] > 0 {
                    self.relabel(v, eps);
                    relabels_since_update += 1;
                    if relabels_since_update >= nodes * update_every() {
                        relabels_since_update = 0;
                        self.update_prices(eps);
                    }
                }
                if *work >= POLL_WORK {
                    *work = 0;
                    if cancel.cancelled() {
                        return Err(TransportError::Cancelled);
                    }
                }
            }
        }
        Ok(())
    }

    /// The global price update (Goldberg 1997, section 5.2): with the length of a
    /// residual arc `ℓ = ⌊c_p / ε⌋ + 1` (at least 0 in an ε-optimal flow), `d(v)`
    /// the shortest length from `v` to a node short of flow, and `p(v) -= ε d(v)`,
    /// every arc stays ε-optimal and every node with excess gets a path of
    /// admissible arcs to a node short of flow. The search stops once every node
    /// with excess is reached; the nodes not reached then move with the last
    /// distance reached, which keeps ε-optimality as well.
    fn update_prices(&mut self, eps: i64) {
        let nodes = self.cells + 1;
        let mut waiting = 0usize;
        for v in 0..nodes {
            self.dist[v] = i64::MAX;
            if self.excess[v] > 0 {
                waiting += 1;
            }
        }
        self.heap.clear();
        for v in 0..nodes {
            if self.excess[v] < 0 {
                self.dist[v] = 0;
                self.heap.push(Reverse((0, v as u32)));
            }
        }
        let mut reached = 0i64;
        while let Some(Reverse((d, w))) = self.heap.pop() {
            let w = w as usize;
            if d > self.dist[w] {
                continue;
            }
            reached = d;
            if self.excess[w] > 0 {
                waiting -= 1;
                if waiting == 0 {
                    break;
                }
            }
            // Residual arcs into w: the reverses of w's own arcs.
            let pw = self.price[w];
            for b in self.first[w] as usize..self.first[w + 1] as usize {
                let a = self.rev[b] as usize;
                if self.cap[a] <= 0 {
                    continue;
                }
                let v = self.head[b] as usize;
                let cp = self.cost[a] + self.price[v] - pw;
                let nd = d + (cp.div_euclid(eps) + 1).max(0);
                if nd < self.dist[v] {
                    self.dist[v] = nd;
                    self.heap.push(Reverse((nd, v as u32)));
                }
            }
        }
        for v in 0..nodes {
            let d = self.dist[v].min(reached);
            self.price[v] -= eps * d;
            self.current[v] = self.first[v];
        }
    }

    /// Lowers the price of `v` as far as keeps every residual arc out of it
    /// `eps`-optimal, which makes one of them admissible.
    fn relabel(&mut self, v: usize, eps: i64) {
        let (s, e) = (self.first[v] as usize, self.first[v + 1] as usize);
        let mut best = i64::MIN;
        for a in s..e {
            if self.cap[a] > 0 {
                best = best.max(self.price[self.head[a] as usize] - self.cost[a]);
            }
        }
        // A node with excess always has a residual arc out (the flow that brought
        // the excess can go back), so `best` is finite.
        debug_assert!(best > i64::MIN);
        self.price[v] = best - eps;
        self.current[v] = s as u32;
        self.stats.relabels += 1;
    }

    /// Cuts the flow into one path per agent and gives each agent a goal of the
    /// cell its path ends in.
    fn decompose(
        &mut self,
        agent_cells: &[u32],
        goal_cells: &[u32],
        out: &mut Vec<u32>,
    ) -> Result<(), TransportError> {
        let n = self.cells;
        // Goals by cell (counting sort).
        self.goal_start.clear();
        self.goal_start.resize(n + 1, 0);
        for &g in goal_cells {
            self.goal_start[g as usize + 1] += 1;
        }
        for c in 0..n {
            self.goal_start[c + 1] += self.goal_start[c];
        }
        self.goal_list.clear();
        self.goal_list.resize(goal_cells.len(), 0);
        for (j, &g) in goal_cells.iter().enumerate() {
            let at = &mut self.goal_start[g as usize];
            self.goal_list[*at as usize] = j as u32;
            *at += 1;
        }
        // `goal_start[c]` is now the end of cell c's goals: take them from the end.
        for c in 0..n {
            self.current[c] = self.first[c];
        }
        let big = agent_cells.len() as i32;
        let mut cost_units: i64 = 0;
        out.clear();
        for &start in agent_cells {
            let mut u = start as usize;
            loop {
                let s = self.sink_arc[u] as usize;
                if self.cap[self.rev[s] as usize] > 0 {
                    // The sink arc's flow is its residual back.
                    self.cap[self.rev[s] as usize] -= 1;
                    let at = &mut self.goal_start[u];
                    *at -= 1;
                    out.push(self.goal_list[*at as usize]);
                    break;
                }
                let end = self.first[u + 1] as usize;
                let mut a = self.current[u] as usize;
                while a < end && !(self.kind[a] == GRID && self.cap[a] < big) {
                    a += 1;
                }
                if a == end {
                    // Flow conservation says a node with flow in has flow out.
                    return Err(TransportError::Unbalanced { cell: u as u32 });
                }
                self.current[u] = a as u32;
                self.cap[a] += 1;
                cost_units += self.cost[a];
                u = self.head[a] as usize;
            }
        }
        self.stats.graph_cost_s = cost_units as f64 / (COST_SCALE * (n + 1) as f64);
        Ok(())
    }
}

/// The cells of `points` (the `what` of [`TransportError::NoFreeCell`]), each
/// moved to a free cell by `snap` (the planner passes
/// [`EikonalCosts::source_cell_of`](super::EikonalCosts::source_cell_of)).
///
/// # Errors
/// [`TransportError::NoFreeCell`] for the first point `snap` finds no cell for.
pub fn cells_of(
    what: &'static str,
    points: &[Vec2],
    snap: impl Fn(Vec2) -> Option<usize>,
    out: &mut Vec<u32>,
) -> Result<(), TransportError> {
    out.clear();
    for (index, &p) in points.iter().enumerate() {
        let cell = snap(p).ok_or(TransportError::NoFreeCell { what, index })?;
        out.push(cell as u32);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::assign::{CostMatrix, Solver};
    use proptest::prelude::*;
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    /// Path costs (integer units) from `s` to every cell over the grid arcs,
    /// by Dijkstra: an independent reading of the graph the flow runs on.
    fn dijkstra(t: &GridTransport, s: usize) -> Vec<i64> {
        let mut d = vec![i64::MAX; t.cells];
        let mut heap = BinaryHeap::new();
        d[s] = 0;
        heap.push(Reverse((0i64, s)));
        while let Some(Reverse((du, u))) = heap.pop() {
            if du > d[u] {
                continue;
            }
            for a in t.first[u] as usize..t.first[u + 1] as usize {
                if t.kind[a] != GRID {
                    continue;
                }
                let (w, nd) = (t.head[a] as usize, du + t.cost[a]);
                if nd < d[w] {
                    d[w] = nd;
                    heap.push(Reverse((nd, w)));
                }
            }
        }
        d
    }

    /// The total path cost of `out` and the optimum over every assignment (the
    /// exact solver on the Dijkstra costs), in integer units.
    fn total_and_optimum(t: &GridTransport, agents: &[u32], goals: &[u32], out: &[u32]) -> (i64, i64) {
        let mut m = CostMatrix::new(agents.len(), goals.len());
        let mut total = 0;
        for (i, &a) in agents.iter().enumerate() {
            let d = dijkstra(t, a as usize);
            for (j, &g) in goals.iter().enumerate() {
                m.row_mut(i)[j] = d[g as usize] as f64;
            }
            total += d[goals[out[i] as usize] as usize];
        }
        let mut s = Solver::new();
        let best: f64 = s
            .solve(&m)
            .unwrap()
            .iter()
            .enumerate()
            .map(|(i, &j)| m.row(i)[j])
            .sum();
        (total, best as i64)
    }

    fn injective(out: &[u32], goals: usize) -> bool {
        let mut seen = vec![false; goals];
        out.iter().all(|&j| (j as usize) < goals && !std::mem::replace(&mut seen[j as usize], true))
    }

    /// A 14 × 9 grid of 20 cm cells with a wall (open at the top) and a slow patch.
    fn walled() -> (Grid, Vec<f64>) {
        let grid = Grid::new(14, 9, 0.2, Vec2::new(1.0, -2.0)).unwrap();
        let mut cost = vec![1.0; grid.len()];
        for r in 2..9 {
            cost[grid.index(6, r)] = f64::INFINITY;
        }
        for r in 0..5 {
            for c in 9..12 {
                cost[grid.index(c, r)] = 3.0;
            }
        }
        (grid, cost)
    }

    fn free_cells(cost: &[f64], picks: &[usize]) -> Vec<u32> {
        let free: Vec<u32> = (0..cost.len() as u32).filter(|&c| cost[c as usize].is_finite()).collect();
        picks.iter().map(|&p| free[p % free.len()]).collect()
    }

    #[test]
    fn the_assignment_is_the_optimum_of_the_graph_path_costs() {
        let (grid, cost) = walled();
        let mut t = GridTransport::new();
        t.set_grid(&grid, &cost);
        let mut rng = crate::rng::SplitMix64::new(7);
        for round in 0..6 {
            let n = 10 + 8 * round;
            // Agents left of the wall, goals anywhere; several per cell.
            let agents: Vec<u32> = (0..n)
                .map(|_| grid.index((rng.next_u64() % 6) as usize, (rng.next_u64() % 9) as usize) as u32)
                .collect();
            let picks: Vec<usize> = (0..n + round).map(|_| (rng.next_u64() % 1000) as usize).collect();
            let goals = free_cells(&cost, &picks);
            let mut out = Vec::new();
            let stats = t.solve(&agents, &goals, &mut out, Cancel::NEVER).unwrap();
            assert!(injective(&out, goals.len()));
            let (total, best) = total_and_optimum(&t, &agents, &goals, &out);
            assert_eq!(total, best, "round {round}");
            let units = COST_SCALE * (grid.len() + 1) as f64;
            assert!((stats.graph_cost_s - total as f64 / units).abs() < 1e-9);
        }
    }

    #[test]
    fn agents_walled_off_from_their_goals_are_named() {
        let (grid, mut cost) = walled();
        for r in 0..2 {
            cost[grid.index(6, r)] = f64::INFINITY;
        }
        let mut t = GridTransport::new();
        t.set_grid(&grid, &cost);
        let agents = [grid.index(12, 4) as u32, grid.index(1, 1) as u32];
        let goals = [grid.index(13, 1) as u32, grid.index(13, 2) as u32];
        let mut out = Vec::new();
        assert_eq!(
            t.solve(&agents, &goals, &mut out, Cancel::NEVER),
            Err(TransportError::Unreachable {
                agent: 1,
                cell: grid.index(1, 1) as u32,
                agents: 1,
                goals: 0
            })
        );
        let blocked = [grid.index(6, 5) as u32];
        assert!(matches!(
            t.solve(&blocked, &goals, &mut out, Cancel::NEVER),
            Err(TransportError::Unreachable { agent: 0, .. })
        ));
        let err = t.solve(&agents, &goals[..1], &mut out, Cancel::NEVER).unwrap_err();
        assert_eq!(err.to_string(), "2 agents and only 1 goals");
        let outside = [grid.len() as u32 + 3];
        assert_eq!(
            t.solve(&agents[..1], &outside, &mut out, Cancel::NEVER),
            Err(TransportError::CellOutside {
                what: "goal",
                index: 0,
                cell: grid.len() as u32 + 3,
                cells: grid.len()
            })
        );
        assert_eq!(
            GridTransport::new().solve(&agents, &goals, &mut out, Cancel::NEVER),
            Err(TransportError::NoGrid)
        );
    }

    #[test]
    fn a_cancelled_transport_stops() {
        let grid = Grid::new(60, 40, 0.1, Vec2::zeros()).unwrap();
        let cost = vec![1.0; grid.len()];
        let mut t = GridTransport::new();
        t.set_grid(&grid, &cost);
        let agents: Vec<u32> = (0..400).map(|i| (i * 3) as u32).collect();
        let goals: Vec<u32> = (0..400).map(|i| (grid.len() - 1 - i * 5) as u32).collect();
        let check = || true;
        let mut out = Vec::new();
        assert_eq!(
            t.solve(&agents, &goals, &mut out, Cancel::new(&check)),
            Err(TransportError::Cancelled)
        );
        // And solves the same instance afterwards.
        t.solve(&agents, &goals, &mut out, Cancel::NEVER).unwrap();
        assert!(injective(&out, goals.len()));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Random walls and patches, random crowds: never a panic; a solve either
        /// names why it cannot assign or gives the optimum of the graph's path costs.
        #[test]
        fn transport_is_optimal_or_says_why(
            cols in 2usize..9,
            rows in 2usize..8,
            cells in proptest::collection::vec(0u8..6, 72),
            agent_picks in proptest::collection::vec(0usize..72, 1..14),
            extra_goals in proptest::collection::vec(0usize..72, 0..4),
        ) {
            let grid = Grid::new(cols, rows, 0.16, Vec2::new(-0.5, 0.25)).unwrap();
            let cost: Vec<f64> = (0..grid.len())
                .map(|i| match cells[i] { 0 => f64::INFINITY, 1 => 2.5, k => 0.5 + f64::from(k) * 0.1 })
                .collect();
            let mut t = GridTransport::new();
            t.set_grid(&grid, &cost);
            let n = grid.len();
            let agents: Vec<u32> = agent_picks.iter().map(|&p| (p % n) as u32).collect();
            let goals: Vec<u32> = agent_picks
                .iter()
                .rev()
                .chain(&extra_goals)
                .map(|&p| ((p * 7 + 3) % n) as u32)
                .collect();
            let mut out = Vec::new();
            match t.solve(&agents, &goals, &mut out, Cancel::NEVER) {
                Ok(_) => {
                    prop_assert!(injective(&out, goals.len()));
                    let (total, best) = total_and_optimum(&t, &agents, &goals, &out);
                    prop_assert_eq!(total, best);
                }
                Err(TransportError::Unreachable { agent, .. }) => {
                    // The exact solver agrees that no assignment has finite cost.
                    let p = t.part[agents[agent] as usize];
                    let reach = |c: u32| p != u32::MAX && t.part[c as usize] == p;
                    let mine = agents.iter().filter(|&&c| reach(c)).count().max(1);
                    prop_assert!(goals.iter().filter(|&&c| reach(c)).count() < mine);
                }
                Err(e) => prop_assert!(false, "unexpected error {e}"),
            }
        }
    }
}

#[cfg(test)]
mod timing {
    use super::*;
    #[test]
    #[ignore]
    fn timing_5000() {
        let grid = Grid::new(100, 56, 0.16, Vec2::zeros()).unwrap();
        let mut cost = vec![1.0; grid.len()];
        for r in 10..50 {
            cost[grid.index(50, r)] = f64::INFINITY;
        }
        let mut t = GridTransport::new();
        let t0 = std::time::Instant::now();
        t.set_grid(&grid, &cost);
        eprintln!("build {:?}", t0.elapsed());
        let mut rng = crate::rng::SplitMix64::new(3);
        for n in [200usize, 1000, 5000] {
            let agents: Vec<u32> = (0..n)
                .map(|_| grid.index((rng.next_u64() % 30) as usize, 10 + (rng.next_u64() % 30) as usize) as u32)
                .collect();
            let goals: Vec<u32> = (0..n)
                .map(|_| grid.index(70 + (rng.next_u64() % 25) as usize, 10 + (rng.next_u64() % 30) as usize) as u32)
                .collect();
            let mut out = Vec::new();
            let t0 = std::time::Instant::now();
            let st = t.solve(&agents, &goals, &mut out, Cancel::NEVER).unwrap();
            eprintln!("{n}: {:?} {st:?}", t0.elapsed());
        }
    }
}
fn update_every() -> usize {
    std::env::var("CT_UPD").ok().and_then(|v| v.parse().ok()).unwrap_or(1)
}
