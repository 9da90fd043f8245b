//! Travel costs for large crowds: goals grouped in clusters that share one
//! fast-marching field, with an exact Euclidean correction inside each cluster.
//!
//! One field per goal ([`EikonalCosts`]) costs one march per goal: about 0.9 s for
//! 1,000 goals on the 16 cm planning grid of a 16 m × 9 m scene, and the field cache
//! cannot hold them all. [`ClusterCosts`] marches one field per cluster of goals
//! instead (a few dozen), and corrects its value for each goal of the cluster with
//! the straight last leg of the path.
//!
//! # Formula
//! mesh-formation-control eq. 6 gives `c_ij = Φ_j(a_i)`, the travel cost from agent
//! `i` to goal `j`. Goals are bucketed on a square lattice of side
//! [`ClusterCosts::cluster_m`]; a cluster is the goals of one bucket that can all
//! be reached in a straight line from its source `s` (the centre of the free cell
//! nearest the bucket centre) at about the unit cost of `s`
//! ([`CLUSTER_COST_TOLERANCE`]); a goal hidden from it, or across a patch edge,
//! starts another cluster of the bucket, from its own cell. One field `Φ_s` is marched per cluster. For agent
//! `a`, let `v` be its **anchor**: `a` itself when the straight segment `a → s`
//! crosses no blocked cell, else the first cell centre on `a`'s path down `Φ_s`
//! (steepest 8-neighbour) from which `s` is in a straight line — the last corner
//! the path turns round. Then
//!
//! ```text
//!   c_ij ≈ Φ_s(a) − Φ_s(v) + r · |v − g_j|,      r = Φ_s(v) / |v − s|
//! ```
//!
//! `Φ_s(a) − Φ_s(v)` is the path up to the anchor, shared by every goal of the
//! cluster, and `r · |v − g_j|` the straight last leg to the goal at the mean unit
//! cost `r` of the leg `v → s` (the cell cost at `s` when `v` is within one cell of
//! `s`). With `g_j = s` this is `Φ_s(a)`, the per-goal value; with a uniform cost
//! around the cluster it is the exact travel cost whenever the path to `g_j` turns
//! last at the same anchor as the path to `s`. It is approximate where the cost
//! varies along the last leg (crowd density, a patch edge inside a cluster) and
//! where the goals of one cluster lie on both sides of an anchor's shadow.
//!
//! **Measured** (test `clustered_assignment_is_near_the_per_goal_optimum` in
//! `tests/environment.rs`): the assignment solved on these costs, totalled on the
//! exact per-goal costs, is within a few tenths of a percent of the per-goal
//! optimum in every shipped scene (figures and the command in
//! `docs/scenes-and-formations.md`).
//!
//! **Tie-break** ([`ClusterCosts::set_tie_break`], off by default): every entry
//! may carry `+ ε · |a_i − g_j|²`; the assignment is then optimal for that sum, and
//! its travel cost is within `ε · (D(σ*) − D(σ_ε))` of the travel optimum (see the
//! method).
//!
//! # Complexity
//! One march per cluster (cached by source cell while the cost grid stays, so a
//! drifting formation re-marches only the clusters whose source changed), one
//! bilinear read and one straight-line test per agent and cluster, one parent walk
//! per cell and cluster for hidden agents (memoised per cell), and `O(1)` per entry
//! (one square root): the solver reads entries from the per-(agent, cluster) table,
//! never from an `agents × goals` matrix.

use super::costs::EikonalCosts;
use super::error::EikonalError;
use super::grid::Grid;
use super::reads::sample;
use super::segment::segment_cost;
use crate::crowd::assign::{Cancel, CostSource};
use crate::geom::Vec2;

/// Default side of the cluster lattice (m), the project's choice: a 4 m × 3 m
/// formation makes 12–50 clusters, and the assignment stays within 0.26 % of the
/// per-goal optimum in every shipped scene (test
/// `clustered_assignment_is_near_the_per_goal_optimum`).
pub const DEFAULT_CLUSTER_M: f64 = 1.0;

/// Most clusters per fill: beyond it the lattice side is doubled until the goals
/// fit. The provider's field cache must hold this many fields for every agent's
/// route to stay readable after a fill.
pub const MAX_CLUSTERS: usize = 192;

/// Work counters of [`ClusterCosts`], cumulative since creation.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct ClusterStats {
    /// Fills.
    pub fills: u64,
    /// Clusters over all fills.
    pub clusters: u64,
    /// Agent–cluster pairs whose agent is hidden from the source (anchor walked).
    pub hidden_pairs: u64,
    /// Cells whose anchor was found by a walk (memoised per cluster).
    pub cells_walked: u64,
}

/// Assignment costs from goal clusters (see the module doc): a [`CostSource`] for
/// [`Solver::solve_with`](crate::crowd::assign::Solver::solve_with).
#[derive(Clone, Debug, Default)]
pub struct ClusterCosts {
    cluster_m: f64,
    /// Side used by the last fill (doubled from `cluster_m` when there were more
    /// than [`MAX_CLUSTERS`] clusters).
    used_m: f64,
    /// Per cluster: source point (a free cell centre) and its cell.
    sources: Vec<Vec2>,
    source_cells: Vec<usize>,
    /// Per cluster: the next cluster of the same bucket (`u32::MAX`: none).
    next_in_bucket: Vec<u32>,
    /// Per bucket: its first cluster (`u32::MAX`: none).
    bucket_first: Vec<u32>,
    buckets: (usize, usize),
    /// Per goal: position and cluster (positions in `f32`: the distances of the
    /// correction are computed in single precision, 4 at a time; `get` and `row`
    /// give the same bits).
    gx: Vec<f32>,
    gy: Vec<f32>,
    goal_cluster: Vec<u32>,
    /// Goals in cluster order: cluster `c` holds `order[start[c]..start[c + 1]]`,
    /// at `(ogx, ogy)` (contiguous, so a row is computed one cluster at a time).
    order: Vec<u32>,
    start: Vec<u32>,
    ogx: Vec<f32>,
    ogy: Vec<f32>,
    agents: usize,
    /// Per (agent, cluster), index `agent * clusters + cluster`: the entry is
    /// `base + rate · |v − g|`.
    base: Vec<f64>,
    rate: Vec<f64>,
    vx: Vec<f32>,
    vy: Vec<f32>,
    /// Per cell: anchor cell found for the current cluster, valid where `memo_stamp`
    /// equals `stamp`.
    memo: Vec<u32>,
    memo_stamp: Vec<u32>,
    stamp: u32,
    chain: Vec<u32>,
    stats: ClusterStats,
    /// Weight `ε` of the tie-break `ε · |a_i − g_j|²` (s/m²; 0: none).
    tie_break: f64,
    /// Per agent: position (single precision, as the goals).
    ax: Vec<f32>,
    ay: Vec<f32>,
}

impl ClusterCosts {
    /// A provider with lattice side `cluster_m` (m).
    ///
    /// # Errors
    /// [`EikonalError::InvalidInput`] when `cluster_m` is not finite and positive.
    pub fn new(cluster_m: f64) -> Result<ClusterCosts, EikonalError> {
        if !(cluster_m.is_finite() && cluster_m > 0.0) {
            return Err(EikonalError::InvalidInput {
                what: "cluster_m",
                index: 0,
            });
        }
        Ok(ClusterCosts {
            cluster_m,
            used_m: cluster_m,
            ..ClusterCosts::default()
        })
    }

    /// The lattice side asked for (m).
    pub fn cluster_m(&self) -> f64 {
        self.cluster_m
    }

    /// The lattice side of the last fill (m).
    pub fn used_cluster_m(&self) -> f64 {
        self.used_m
    }

    /// Number of clusters of the last fill.
    pub fn clusters(&self) -> usize {
        self.sources.len()
    }

    /// The source point of goal `j`'s cluster in the last fill: the field to
    /// descend for its route ([`EikonalCosts::descent`]).
    pub fn source_of(&self, j: usize) -> Vec2 {
        self.sources[self.goal_cluster[j] as usize]
    }

    /// The source of the cluster holding a goal at `g` in the last fill, found
    /// through its bucket (`None`: no cluster of that bucket reaches `g` in a
    /// straight line).
    pub fn source_near(&self, costs: &EikonalCosts, g: Vec2) -> Option<Vec2> {
        let b = self.bucket(costs.grid(), g, self.used_m)?;
        let mut c = *self.bucket_first.get(b)?;
        while c != u32::MAX {
            if fits(costs, self.source_cells[c as usize], g) {
                return Some(self.sources[c as usize]);
            }
            c = self.next_in_bucket[c as usize];
        }
        None
    }

    /// Work counters.
    pub fn stats(&self) -> ClusterStats {
        self.stats
    }

    /// Computes the costs of `agents × goals` with the fields of `costs` (its grid,
    /// cost and field cache; the fields marched stay cached).
    ///
    /// # Errors
    /// [`EikonalCosts::fields`]' errors (a point not finite, outside the grid, or
    /// stuck in an obstacle), agents numbered first; the costs are unspecified then.
    pub fn fill(
        &mut self,
        costs: &EikonalCosts,
        agents: &[Vec2],
        goals: &[Vec2],
    ) -> Result<(), EikonalError> {
        self.fill_cancellable(costs, agents, goals, Cancel::NEVER)
    }

    /// [`Self::fill`] that gives up when `cancel` says so, checked before each
    /// cluster's field.
    ///
    /// # Errors
    /// As [`Self::fill`], and [`EikonalError::Cancelled`].
    pub fn fill_cancellable(
        &mut self,
        costs: &EikonalCosts,
        agents: &[Vec2],
        goals: &[Vec2],
        cancel: Cancel<'_>,
    ) -> Result<(), EikonalError> {
        self.stats.fills += 1;
        self.gx.clear();
        self.gy.clear();
        self.gx.extend(goals.iter().map(|g| g.x as f32));
        self.gy.extend(goals.iter().map(|g| g.y as f32));
        self.agents = agents.len();
        self.ax.clear();
        self.ay.clear();
        self.ax.extend(agents.iter().map(|a| a.x as f32));
        self.ay.extend(agents.iter().map(|a| a.y as f32));
        // Goals must be valid sources before they are clustered.
        costs.validate_points(agents, goals)?;
        let mut side = self.cluster_m;
        loop {
            self.cluster(costs, goals, side);
            if self.sources.len() <= MAX_CLUSTERS {
                break;
            }
            side *= 2.0;
        }
        self.used_m = side;
        let k = self.sources.len();
        self.sort_goals();
        self.stats.clusters += k as u64;
        let n = agents.len() * k;
        for v in [&mut self.base, &mut self.rate] {
            v.clear();
            v.resize(n, 0.0);
        }
        for v in [&mut self.vx, &mut self.vy] {
            v.clear();
            v.resize(n, 0.0);
        }
        let grid = *costs.grid();
        if self.memo.len() != grid.len() {
            self.memo = vec![0; grid.len()];
            self.memo_stamp = vec![0; grid.len()];
            self.stamp = 0;
        }
        let sources = std::mem::take(&mut self.sources);
        let r = costs.fields_cancellable(
            &sources,
            agents,
            |c, phi| {
                self.pairs(costs, &grid, phi, c, sources[c], agents);
            },
            cancel,
        );
        self.sources = sources;
        r
    }

    /// Groups the goals into clusters on a lattice of side `side`.
    fn cluster(&mut self, costs: &EikonalCosts, goals: &[Vec2], side: f64) {
        let grid = costs.grid();
        let extent = Vec2::new(grid.cols() as f64, grid.rows() as f64) * grid.cell_m();
        let nb = (
            ((extent.x / side).ceil() as usize).max(1),
            ((extent.y / side).ceil() as usize).max(1),
        );
        self.buckets = nb;
        self.bucket_first.clear();
        self.bucket_first.resize(nb.0 * nb.1, u32::MAX);
        self.sources.clear();
        self.source_cells.clear();
        self.next_in_bucket.clear();
        self.goal_cluster.clear();
        for &g in goals {
            let b = self.bucket(grid, g, side).expect("validated goal");
            let mut c = self.bucket_first[b];
            let mut last = u32::MAX;
            while c != u32::MAX {
                if fits(costs, self.source_cells[c as usize], g) {
                    break;
                }
                last = c;
                c = self.next_in_bucket[c as usize];
            }
            if c == u32::MAX {
                // A new cluster: from the bucket centre when it is the bucket's first
                // and reaches g, else from g's own cell.
                let (bc, br) = (b % nb.0, b / nb.0);
                let centre = grid.origin() + Vec2::new(bc as f64 + 0.5, br as f64 + 0.5) * side;
                let own = costs.source_cell_of(g).expect("validated goal");
                let cell = match costs.source_cell_of(centre) {
                    Some(cell) if last == u32::MAX && fits(costs, cell, g) => cell,
                    _ => own,
                };
                c = self.sources.len() as u32;
                self.sources.push(grid.center(cell));
                self.source_cells.push(cell);
                self.next_in_bucket.push(u32::MAX);
                if last == u32::MAX {
                    self.bucket_first[b] = c;
                } else {
                    self.next_in_bucket[last as usize] = c;
                }
            }
            self.goal_cluster.push(c);
        }
    }

    /// Lists the goals cluster by cluster (a counting sort).
    fn sort_goals(&mut self) {
        let k = self.sources.len();
        self.start.clear();
        self.start.resize(k + 1, 0);
        for &c in &self.goal_cluster {
            self.start[c as usize + 1] += 1;
        }
        for c in 0..k {
            self.start[c + 1] += self.start[c];
        }
        let m = self.goal_cluster.len();
        self.order.clear();
        self.order.resize(m, 0);
        self.ogx.clear();
        self.ogx.resize(m, 0.0);
        self.ogy.clear();
        self.ogy.resize(m, 0.0);
        // `start[c]` walks through cluster c's slots, then is restored.
        for (j, &c) in self.goal_cluster.iter().enumerate() {
            let t = self.start[c as usize] as usize;
            self.order[t] = j as u32;
            self.ogx[t] = self.gx[j];
            self.ogy[t] = self.gy[j];
            self.start[c as usize] += 1;
        }
        for c in (1..=k).rev() {
            self.start[c] = self.start[c - 1];
        }
        self.start[0] = 0;
    }

    /// The bucket of `p` on a lattice of side `side` (clamped to the grid).
    fn bucket(&self, grid: &Grid, p: Vec2, side: f64) -> Option<usize> {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return None;
        }
        let d = (p - grid.origin()) / side;
        let bc = (d.x.max(0.0) as usize).min(self.buckets.0 - 1);
        let br = (d.y.max(0.0) as usize).min(self.buckets.1 - 1);
        Some(br * self.buckets.0 + bc)
    }

    /// The per-agent values of cluster `c` with source `s` and field `phi`.
    fn pairs(
        &mut self,
        costs: &EikonalCosts,
        grid: &Grid,
        phi: &[f64],
        c: usize,
        s: Vec2,
        agents: &[Vec2],
    ) {
        let k = self.source_cells.len();
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.memo_stamp.fill(0);
            self.stamp = 1;
        }
        let source_cost = costs.cost()[self.source_cells[c]];
        let h = grid.cell_m();
        for (i, &a) in agents.iter().enumerate() {
            let phi_a = sample(grid, phi, a);
            let x = i * k + c;
            if !phi_a.is_finite() {
                // No path from this agent to the cluster.
                (self.base[x], self.rate[x]) = (f64::INFINITY, 0.0);
                (self.vx[x], self.vy[x]) = (a.x as f32, a.y as f32);
                continue;
            }
            // The agent is its own anchor when its cell's centre reaches s.
            let own = grid.cell_of(a).expect("agents lie in the grid");
            let cell = self.anchor(costs, grid, phi, s, own);
            let (v, phi_v) = if cell == own {
                (a, phi_a)
            } else {
                self.stats.hidden_pairs += 1;
                (grid.center(cell), phi[cell])
            };
            let d = (v - s).norm();
            let rate = if d > h && phi_v.is_finite() {
                phi_v / d
            } else {
                source_cost
            };
            // Φ(a) − Φ(v): the path up to the anchor (0 when a is its own anchor).
            self.base[x] = if v == a { 0.0 } else { phi_a - phi_v };
            self.rate[x] = rate;
            self.vx[x] = v.x as f32;
            self.vy[x] = v.y as f32;
        }
    }

    /// The anchor cell of cell `x`: the first cell on the steepest 8-neighbour
    /// descent of `phi` from `x` (`x` itself included) whose centre reaches `s` in a
    /// straight line (memoised per cell for this cluster).
    fn anchor(
        &mut self,
        costs: &EikonalCosts,
        grid: &Grid,
        phi: &[f64],
        s: Vec2,
        x: usize,
    ) -> usize {
        let mut x = x;
        self.chain.clear();
        let found = loop {
            if self.memo_stamp[x] == self.stamp {
                break self.memo[x] as usize;
            }
            self.chain.push(x as u32);
            self.stats.cells_walked += 1;
            if phi[x].is_finite() && clear(costs, grid.center(x), s) {
                break x;
            }
            match steepest_neighbour(grid, phi, x) {
                Some(y) => x = y,
                None => break x,
            }
        };
        for &y in &self.chain {
            self.memo[y as usize] = found as u32;
            self.memo_stamp[y as usize] = self.stamp;
        }
        found
    }

    #[inline]
    fn entry(&self, i: usize, j: usize) -> f64 {
        let x = i * self.source_cells.len() + self.goal_cluster[j] as usize;
        let (gx, gy) = (self.gx[j], self.gy[j]);
        let c = self.base[x] + self.rate[x] * dist(self.vx[x], self.vy[x], gx, gy);
        if self.tie_break == 0.0 {
            c
        } else {
            c + self.tie_break * dist2(self.ax[i], self.ay[i], gx, gy)
        }
    }

    /// Sets the weight `ε` of the tie-break added to every entry (s/m²; 0, the
    /// default: none); it applies from the next read.
    ///
    /// # Formula
    /// The entry becomes `c_ij + ε · |a_i − g_j|²` (`c_ij` the clustered travel cost
    /// of the module doc). On a square problem `Σ_i |a_i − g_σ(i)|²` is
    /// `Σ|a|² + Σ|g|² − 2 Σ a_i · g_σ(i)`, so the term ranks assignments by how well
    /// they keep the crowd's layout, and breaks the ties of agents whose travel
    /// costs differ by a constant (hidden behind the same corner). Let `σ_ε` be
    /// optimal for the sum, `σ*` for the travel cost alone, `C` and `D` the total
    /// travel cost and the total squared distance of an assignment. Then
    ///
    /// ```text
    ///   C(σ*) ≤ C(σ_ε) ≤ C(σ*) + ε · (D(σ*) − D(σ_ε))
    /// ```
    ///
    /// (optimality of `σ_ε` for `C + εD`): the travel cost given up is at most `ε`
    /// times the squared distance it saves.
    ///
    /// # Units
    /// `ε` in cost units (s) per m².
    ///
    /// # Errors
    /// [`EikonalError::InvalidInput`] when `eps` is not finite and non-negative
    /// (the weight is unchanged then).
    ///
    /// ```
    /// use crowdtouch::crowd::environment::eikonal::ClusterCosts;
    /// let mut c = ClusterCosts::new(1.0).unwrap();
    /// assert!(c.set_tie_break(0.05).is_ok());
    /// assert_eq!(c.tie_break(), 0.05);
    /// assert!(c.set_tie_break(-1.0).is_err());
    /// ```
    pub fn set_tie_break(&mut self, eps: f64) -> Result<(), EikonalError> {
        if !(eps.is_finite() && eps >= 0.0) {
            return Err(EikonalError::InvalidInput {
                what: "tie_break",
                index: 0,
            });
        }
        self.tie_break = eps;
        Ok(())
    }

    /// The weight `ε` of the tie-break (s/m²; [`Self::set_tie_break`]).
    pub fn tie_break(&self) -> f64 {
        self.tie_break
    }
}

/// `|v − g|` in single precision (m), widened.
#[inline(always)]
fn dist(vx: f32, vy: f32, gx: f32, gy: f32) -> f64 {
    let (dx, dy) = (vx - gx, vy - gy);
    f64::from((dx * dx + dy * dy).sqrt())
}

/// `|a − g|²` in single precision (m²), widened.
#[inline(always)]
fn dist2(ax: f32, ay: f32, gx: f32, gy: f32) -> f64 {
    let (dx, dy) = (ax - gx, ay - gy);
    f64::from(dx * dx + dy * dy)
}

/// Largest relative difference between the mean unit cost of the straight leg from
/// a cluster's source to one of its goals and the unit cost at the source: a goal
/// across a patch edge starts a cluster of its own, so the correction's single
/// rate holds inside every cluster.
pub const CLUSTER_COST_TOLERANCE: f64 = 0.25;

/// Whether goal `g` can join the cluster of source cell `s`: the straight leg
/// `s → g` crosses no blocked cell, and its mean unit cost is within
/// [`CLUSTER_COST_TOLERANCE`] of the cost at `s`.
fn fits(costs: &EikonalCosts, s: usize, g: Vec2) -> bool {
    let sp = costs.grid().center(s);
    let leg = segment_cost(costs.grid(), costs.cost(), sp, g);
    let len = (g - sp).norm();
    if !leg.is_finite() {
        return false;
    }
    len < 1e-9 || (leg / (len * costs.cost()[s]) - 1.0).abs() <= CLUSTER_COST_TOLERANCE
}

/// Whether the straight segment `a → b` crosses no blocked cell.
fn clear(costs: &EikonalCosts, a: Vec2, b: Vec2) -> bool {
    segment_cost(costs.grid(), costs.cost(), a, b).is_finite()
}

/// The 8-neighbour of `x` with the smallest finite `Φ` below `Φ(x)` (a diagonal only
/// when both cells it cuts past are finite), or `None` at a local minimum.
fn steepest_neighbour(grid: &Grid, phi: &[f64], x: usize) -> Option<usize> {
    let (cols, rows) = (grid.cols() as isize, grid.rows() as isize);
    let (c, r) = ((x % grid.cols()) as isize, (x / grid.cols()) as isize);
    let at = |c: isize, r: isize| -> f64 {
        if c < 0 || r < 0 || c >= cols || r >= rows {
            f64::INFINITY
        } else {
            phi[(r * cols + c) as usize]
        }
    };
    let mut best = (phi[x], None);
    for (dc, dr) in [
        (1, 0),
        (-1, 0),
        (0, 1),
        (0, -1),
        (1, 1),
        (1, -1),
        (-1, 1),
        (-1, -1),
    ] {
        let v = at(c + dc, r + dr);
        if dc != 0 && dr != 0 && !(at(c + dc, r).is_finite() && at(c, r + dr).is_finite()) {
            continue;
        }
        if v < best.0 {
            best = (v, Some(((r + dr) * cols + c + dc) as usize));
        }
    }
    best.1
}

impl CostSource for ClusterCosts {
    fn rows(&self) -> usize {
        self.agents
    }
    fn cols(&self) -> usize {
        self.gx.len()
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        self.entry(i, j)
    }
    fn row<'a>(&'a self, i: usize, buf: &'a mut Vec<f64>) -> &'a [f64] {
        let (k, m) = (self.source_cells.len(), self.gx.len());
        // Computed cluster by cluster into the upper half of `buf` (contiguous, the
        // arithmetic vectorises), then scattered into goal order in the lower half.
        buf.resize(2 * m, 0.0);
        let (out, tmp) = buf.split_at_mut(m);
        for c in 0..k {
            let x = i * k + c;
            let (base, rate, vx, vy) = (self.base[x], self.rate[x], self.vx[x], self.vy[x]);
            let (eps, ax, ay) = (self.tie_break, self.ax[i], self.ay[i]);
            let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
            let goals = tmp[a..b]
                .iter_mut()
                .zip(&self.ogx[a..b])
                .zip(&self.ogy[a..b]);
            // The same operations as `entry`, so both give the same bits.
            if eps == 0.0 {
                for ((o, &gx), &gy) in goals {
                    *o = base + rate * dist(vx, vy, gx, gy);
                }
            } else {
                for ((o, &gx), &gy) in goals {
                    *o = base + rate * dist(vx, vy, gx, gy) + eps * dist2(ax, ay, gx, gy);
                }
            }
        }
        for (&j, &v) in self.order.iter().zip(tmp.iter()) {
            out[j as usize] = v;
        }
        &buf[..m]
    }
    fn validate(&self) -> Result<(), crate::crowd::assign::AssignError> {
        // Entries are finite or +inf by construction (an agent no field reaches).
        Ok(())
    }
}
