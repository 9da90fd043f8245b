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
//! The flow is solved by the primal network simplex of [`Simplex`]: every cell
//! supplies its agents and demands its goals, and a surplus node supplies the goals
//! no agent takes (joined to every goal cell at no cost), so a crowd with more goals
//! than agents leaves the goals it pleases empty. Arc costs are integers
//! (`COST_SCALE` units per second of travel). The optimal flow is then cut into one
//! path per agent, each ending at a goal of the cell it reaches.
//!
//! # Complexity
//!
//! Each pivot walks one cycle of the spanning tree and moves one subtree. On the
//! planning grids of the shipped scenes (about 5,600 cells and 45,000 arcs) a solve
//! of 5,000 agents is about 13,000 pivots and tens of milliseconds whatever the
//! crowd size (`cargo bench --bench fmm -- planner/obstacle_course/5000`), against `O(agents × goals)`
//! per pass for the solvers over pairs.

use super::grid::Grid;
use super::segment::segment_cost;
use super::simplex::{Simplex, SimplexError};
use crate::crowd::assign::Cancel;
use crate::geom::Vec2;

/// Integer cost units per second of travel: a 16 cm arc at 1 s/m is 16,000 units,
/// so rounding moves an arc by at most 3·10⁻⁵ of its cost.
const COST_SCALE: f64 = 1e5;
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
    /// Arcs of the graph (both directions of each neighbour pair).
    pub arcs: usize,
    /// Simplex pivots.
    pub pivots: u64,
    /// Total travel cost of the assignment on the graph (s).
    pub graph_cost_s: f64,
}

/// Min-cost flow on the planning grid (see the module doc). Keeps its graph between
/// solves while the cost grid stays ([`GridTransport::set_grid`]).
#[derive(Default)]
pub struct GridTransport {
    cells: usize,
    /// Arcs out of cell `v` are `first[v]..first[v + 1]`, to `head[a]` at `cost[a]`
    /// units; `first` is empty before [`GridTransport::set_grid`].
    first: Vec<u32>,
    head: Vec<u32>,
    cost: Vec<i64>,
    /// Connected part of each cell (`u32::MAX`: blocked).
    part: Vec<u32>,
    parts: usize,
    part_agents: Vec<usize>,
    part_goals: Vec<usize>,
    /// Goals by cell: those of cell `c` are `goal_list[goal_start[c]..]`, taken
    /// from the end of each cell's run.
    goal_start: Vec<u32>,
    goal_list: Vec<u32>,
    /// The surplus node's arc to each goal cell (`u32::MAX`: none).
    surplus_arc: Vec<u32>,
    stats: TransportStats,
    simplex: Simplex,
    supply: Vec<i64>,
    /// Goals of each cell the agents take (those the surplus does not fill).
    open_goals: Vec<i64>,
    /// Flow left on each arc while the paths are cut, and the next arc to try per cell.
    left: Vec<i64>,
    current: Vec<u32>,
    /// The cells of agent `i`'s path are `path_cells[path_start[i]..path_start[i + 1]]`.
    path_cells: Vec<u32>,
    path_start: Vec<u32>,
}

impl GridTransport {
    /// An empty transport; call [`GridTransport::set_grid`] before solving.
    pub fn new() -> GridTransport {
        GridTransport::default()
    }

    /// Work counters of the last solve.
    pub fn stats(&self) -> TransportStats {
        self.stats
    }

    /// The path of agent `i` in the last solve: the cells from its own to its goal's,
    /// a cheapest path of the graph between them (every arc of an optimal flow has
    /// reduced cost 0, so a path along the flow costs the difference of its ends'
    /// potentials, the least any path can). Empty when `i` is out of range.
    pub fn path(&self, i: usize) -> &[u32] {
        match (self.path_start.get(i), self.path_start.get(i + 1)) {
            (Some(&a), Some(&b)) => &self.path_cells[a as usize..b as usize],
            _ => &[],
        }
    }

    /// The free cell of the last [`GridTransport::set_grid`] whose centre is
    /// nearest `p` (the first in index order on a tie), searched ring by ring around
    /// `p`'s cell: where an agent or goal inside an obstacle stands for the
    /// transport. `None` when `p` is outside `grid` or no cell is free.
    pub fn nearest_free(&self, grid: &Grid, p: Vec2) -> Option<u32> {
        let start = grid.cell_of(p)?;
        if self.part.len() != grid.len() {
            return None;
        }
        let (cols, rows) = (grid.cols() as isize, grid.rows() as isize);
        let (c0, r0) = (
            (start % grid.cols()) as isize,
            (start / grid.cols()) as isize,
        );
        let h = grid.cell_m();
        let mut best: Option<(f64, usize)> = None;
        let consider = |c: isize, r: isize, best: &mut Option<(f64, usize)>| {
            if c < 0 || r < 0 || c >= cols || r >= rows {
                return;
            }
            let i = (r * cols + c) as usize;
            if self.part[i] == u32::MAX {
                return;
            }
            let d = (grid.center(i) - p).norm();
            if best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                *best = Some((d, i));
            }
        };
        for k in 0..cols.max(rows) {
            // Every cell of ring k is at least (k − ½) cells from p.
            if best.is_some_and(|(d, _)| (k as f64 - 0.5) * h > d) {
                break;
            }
            for r in r0 - k..=r0 + k {
                if r == r0 - k || r == r0 + k {
                    for c in c0 - k..=c0 + k {
                        consider(c, r, &mut best);
                    }
                } else {
                    consider(c0 - k, r, &mut best);
                    consider(c0 + k, r, &mut best);
                }
            }
        }
        best.map(|(_, i)| i as u32)
    }

    /// Builds the graph for `grid` with unit cost `cost` (s/m per cell, `+inf`
    /// blocked; eq. 7).
    ///
    /// # Panics
    /// If `cost` does not have one entry per cell of `grid`.
    ///
    /// # Complexity
    /// One [`segment_cost`] per neighbour pair: about 45,000 for a 100 × 56 grid.
    pub fn set_grid(&mut self, grid: &Grid, cost: &[f64]) {
        let n = grid.len();
        assert_eq!(cost.len(), n, "one cost per cell");
        let (cols, rows) = (grid.cols() as isize, grid.rows() as isize);
        let free = |c: isize, r: isize| -> bool {
            c >= 0 && r >= 0 && c < cols && r < rows && cost[(r * cols + c) as usize].is_finite()
        };
        // Each neighbour pair once, with its cost in integer units.
        let mut edges: Vec<(u32, u32, i64)> = Vec::with_capacity(n * OFFSETS.len());
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
                        let units = (s * COST_SCALE).round().max(1.0) as i64;
                        edges.push((u as u32, v as u32, units));
                    }
                }
            }
        }
        self.first.clear();
        self.first.resize(n + 1, 0);
        for &(u, v, _) in &edges {
            self.first[u as usize + 1] += 1;
            self.first[v as usize + 1] += 1;
        }
        for v in 0..n {
            self.first[v + 1] += self.first[v];
        }
        let m = 2 * edges.len();
        self.head.clear();
        self.head.resize(m, 0);
        self.cost.clear();
        self.cost.resize(m, 0);
        self.current.clear();
        self.current.extend_from_slice(&self.first[..n]);
        for &(u, v, c) in &edges {
            for (t, h) in [(u, v), (v, u)] {
                let a = self.current[t as usize] as usize;
                self.current[t as usize] += 1;
                self.head[a] = h;
                self.cost[a] = c;
            }
        }
        // Connected parts (arcs are symmetric), for the feasibility check.
        self.part.clear();
        self.part.resize(n, u32::MAX);
        self.parts = 0;
        let mut stack = Vec::new();
        for (s, c) in cost.iter().enumerate() {
            if self.part[s] != u32::MAX || !c.is_finite() {
                continue;
            }
            let p = self.parts as u32;
            self.parts += 1;
            self.part[s] = p;
            stack.push(s);
            while let Some(u) = stack.pop() {
                for a in self.first[u] as usize..self.first[u + 1] as usize {
                    let w = self.head[a] as usize;
                    if self.part[w] == u32::MAX {
                        self.part[w] = p;
                        stack.push(w);
                    }
                }
            }
        }
        self.cells = n;
        self.stats = TransportStats {
            arcs: m,
            ..TransportStats::default()
        };
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
        self.stats.pivots = 0;
        self.stats.graph_cost_s = 0.0;
        // Grid arcs first, so simplex arc `a` is grid arc `a`.
        self.simplex.reset(n + 1);
        for u in 0..n {
            for a in self.first[u] as usize..self.first[u + 1] as usize {
                self.simplex.add_arc(u as u32, self.head[a], self.cost[a]);
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
        // The surplus node `n` supplies the goals no agent takes.
        self.supply[n] = (goals - agents) as i64;
        self.surplus_arc.clear();
        self.surplus_arc.resize(n, u32::MAX);
        if goals > agents {
            for c in 0..n {
                if self.open_goals[c] > 0 {
                    self.surplus_arc[c] = self.simplex.add_arc(n as u32, c as u32, 0) as u32;
                }
            }
        }
        let solved = self.simplex.solve(&self.supply, || cancel.cancelled());
        self.stats.pivots = self.simplex.pivots;
        solved.map_err(|e| match e {
            SimplexError::Cancelled => TransportError::Cancelled,
            // Parts were checked and costs are positive: a defect if it happens.
            SimplexError::Infeasible | SimplexError::Unbounded => {
                TransportError::Unbalanced { cell: n as u32 }
            }
        })?;
        for c in 0..n {
            if self.surplus_arc[c] != u32::MAX {
                self.open_goals[c] -= self.simplex.flow(self.surplus_arc[c] as usize);
            }
        }
        self.cut_paths(agent_cells, goal_cells, out)?;
        Ok(self.stats)
    }

    /// Cuts the optimal flow into one path per agent: each agent follows arcs with
    /// flow left until a cell with a goal left, which it takes.
    fn cut_paths(
        &mut self,
        agent_cells: &[u32],
        goal_cells: &[u32],
        out: &mut Vec<u32>,
    ) -> Result<(), TransportError> {
        let n = self.cells;
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
        self.current.clear();
        self.current.extend_from_slice(&self.first[..n]);
        self.left.clear();
        self.left
            .extend((0..self.head.len()).map(|a| self.simplex.flow(a)));
        let mut units: i64 = 0;
        out.clear();
        self.path_cells.clear();
        self.path_start.clear();
        self.path_start.push(0);
        for &start in agent_cells {
            let mut u = start as usize;
            self.path_cells.push(start);
            // A path has at most one arc per cell: flows of an optimum have no cycle
            // of positive cost, and every arc costs at least one unit.
            for _ in 0..=n {
                if self.open_goals[u] > 0 {
                    break;
                }
                let end = self.first[u + 1] as usize;
                let mut a = self.current[u] as usize;
                while a < end && self.left[a] <= 0 {
                    a += 1;
                }
                if a == end {
                    return Err(TransportError::Unbalanced { cell: u as u32 });
                }
                self.current[u] = a as u32;
                self.left[a] -= 1;
                units += self.cost[a];
                u = self.head[a] as usize;
                self.path_cells.push(u as u32);
            }
            if self.open_goals[u] <= 0 {
                return Err(TransportError::Unbalanced { cell: u as u32 });
            }
            self.open_goals[u] -= 1;
            let at = &mut self.goal_start[u];
            *at -= 1;
            out.push(self.goal_list[*at as usize]);
            self.path_start.push(self.path_cells.len() as u32);
        }
        self.stats.graph_cost_s = units as f64 / COST_SCALE;
        Ok(())
    }

    fn check_parts(
        &mut self,
        agent_cells: &[u32],
        goal_cells: &[u32],
    ) -> Result<(), TransportError> {
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
    fn total_and_optimum(
        t: &GridTransport,
        agents: &[u32],
        goals: &[u32],
        out: &[u32],
    ) -> (i64, i64) {
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
        out.iter()
            .all(|&j| (j as usize) < goals && !std::mem::replace(&mut seen[j as usize], true))
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
        let free: Vec<u32> = (0..cost.len() as u32)
            .filter(|&c| cost[c as usize].is_finite())
            .collect();
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
                .map(|_| {
                    grid.index((rng.next_u64() % 6) as usize, (rng.next_u64() % 9) as usize) as u32
                })
                .collect();
            let picks: Vec<usize> = (0..n + round)
                .map(|_| (rng.next_u64() % 1000) as usize)
                .collect();
            let goals = free_cells(&cost, &picks);
            let mut out = Vec::new();
            let stats = t.solve(&agents, &goals, &mut out, Cancel::NEVER).unwrap();
            assert!(injective(&out, goals.len()));
            let (total, best) = total_and_optimum(&t, &agents, &goals, &out);
            assert_eq!(total, best, "round {round}");
            let units = COST_SCALE;
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
        let err = t
            .solve(&agents, &goals[..1], &mut out, Cancel::NEVER)
            .unwrap_err();
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

    #[test]
    fn a_point_in_an_obstacle_stands_at_the_nearest_free_cell() {
        let (grid, mut cost) = walled();
        // A thick block: points deep inside are several cells from free ground.
        for r in 3..8 {
            for c in 2..6 {
                cost[grid.index(c, r)] = f64::INFINITY;
            }
        }
        let mut t = GridTransport::new();
        assert_eq!(
            t.nearest_free(&grid, Vec2::new(1.5, -1.5)),
            None,
            "no grid yet"
        );
        t.set_grid(&grid, &cost);
        let mut rng = crate::rng::SplitMix64::new(5);
        for _ in 0..200 {
            let p = grid.origin()
                + Vec2::new(rng.uniform(0.0, 14.0 * 0.2), rng.uniform(0.0, 9.0 * 0.2));
            // Brute force over every free cell.
            let want = (0..grid.len())
                .filter(|&i| cost[i].is_finite())
                .min_by(|&a, &b| {
                    let (da, db) = ((grid.center(a) - p).norm(), (grid.center(b) - p).norm());
                    da.total_cmp(&db).then(a.cmp(&b))
                })
                .map(|i| i as u32);
            assert_eq!(t.nearest_free(&grid, p), want, "at {p:?}");
        }
        let outside = grid.origin() - Vec2::new(1.0, 1.0);
        assert_eq!(t.nearest_free(&grid, outside), None);
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
