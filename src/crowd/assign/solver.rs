//! [`Solver`]: exact assignment of rows (agents) to columns (goals) with dual prices,
//! reusable workspaces and warm start; its [`Strategy`] and work counters
//! ([`SolveStats`]).
//!
//! # Algorithm
//!
//! A shortest-augmenting-path (SAP) solver with dual prices in the Jonker–Volgenant
//! family (convention: reduced costs `c[i][j] - u[i] - v[j] >= 0`, zero on assigned
//! pairs; `v` are the column prices). Two ways of running it:
//!
//! * **Dense** ([`Strategy::Dense`]): each free row runs a Dijkstra search over the full
//!   reduced-cost matrix (`dense.rs`); used for small problems and as the safety net.
//! * **Sparse** ([`Strategy::Sparse`], the default above 128 columns), in four steps:
//!   1. one streaming pass over the matrix keeps, per row, the `k` columns of smallest
//!      reduced cost and a threshold below which no other column lies (`pricing.rs`);
//!   2. an auction with ε-scaling on these lists brings the prices close to optimal
//!      cheaply (`auction.rs`);
//!   3. the assigned pairs are made tight and every row is priced against its list;
//!      rows whose pair is not tight are freed;
//!   4. exact Dijkstra from each free row over the sorted lists, exact on the full
//!      matrix (`augment.rs`); rounds of repricing repeat until no row is violated (a
//!      bounded number, then a full dense finish) — at that point the full
//!      certificate holds.
//!
//! Warm start ([`Solver::solve_warm`]) keeps the assignment, the row duals and the
//! column prices of the previous frame, carries each price over by the change of its
//! assigned cost (so kept pairs start tight), prices every row against the new costs
//! (step 1), keeps the pairs that are still tight, starts over cold if the broken
//! pairs are off by more than two local cost spreads, runs a short auction if more
//! than three quarters of the rows lost their pair, otherwise a budgeted augmenting row
//! reduction (`auction.rs`), and re-augments the rows still free (step 4).
//!
//! Rectangular problems (rows < cols) are exact: every column price starts at 0 and is
//! only lowered, except that a column left free with a lowered price is raised back to
//! 0 (freeing the rows it now undercuts and weakening the list bounds it affects), so at
//! every augmentation all free columns have the maximal price — the dual condition of
//! unassigned columns.
//!
//! `+inf` entries mean "unreachable" and are never part of an assignment; no arithmetic
//! on them produces NaN (column prices stay finite).
//!
//! # Example
//!
//! ```
//! use crowdtouch::crowd::assign::{CostMatrix, Solver};
//! let mut c = CostMatrix::new(3, 3);
//! let data = [[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]];
//! for (r, row) in data.iter().enumerate() {
//!     c.row_mut(r).copy_from_slice(row);
//! }
//! let mut solver = Solver::new();
//! assert_eq!(solver.solve(&c).unwrap(), &[1, 0, 2]);
//! assert!((solver.total_cost(&c) - 5.0).abs() < 1e-12);
//! assert!(solver.verify_optimal(&c, 1e-9));
//! ```

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::cancel::{Cancel, POLL_WORK};
use super::costs::{CostMatrix, CostSource};
use super::error::AssignError;
use super::heaps::{ColHeap, Mark, PendHeap};

/// Relative tolerance of the tightness and dual-feasibility tests.
///
/// Two reduced costs `c - v` count as equal when they differ by at most `EPS_REL`
/// times the sum of the magnitudes of the costs and prices involved (rounding level),
/// so the returned assignment is optimal to within about `rows * EPS_REL * scale` of
/// total cost, `scale` the magnitude of the costs and prices.
pub const EPS_REL: f64 = 1e-12;

/// Rounding tolerance of a comparison between reduced costs `c - v` built from the
/// given magnitudes ([`EPS_REL`]).
#[inline]
pub(super) fn tol(a: f64, b: f64, c: f64, d: f64) -> f64 {
    EPS_REL * (a.abs() + b.abs() + c.abs() + d.abs())
}

/// Candidate columns kept per row by [`Strategy::Sparse`] when chosen automatically:
/// `cols / AUTO_CANDIDATES_DIV`, clamped to `[AUTO_CANDIDATES_MIN, AUTO_CANDIDATES_MAX]`.
const AUTO_CANDIDATES_DIV: usize = 40;
/// Lower clamp of the automatic candidate count.
const AUTO_CANDIDATES_MIN: usize = 24;
/// Upper clamp of the automatic candidate count.
const AUTO_CANDIDATES_MAX: usize = 64;

/// Warm solves build the candidate lists with `k * WARM_LIST_NUM / WARM_LIST_DEN`
/// entries (at least 1): the old prices are near optimal, so the searches rarely go
/// deep into a row, and shorter lists make the one full pass over the matrix cheaper.
const WARM_LIST_NUM: usize = 2;
/// See [`WARM_LIST_NUM`].
const WARM_LIST_DEN: usize = 3;

/// A warm start runs the auction first only when more than `WARM_AUCTION_FREE_NUM /
/// WARM_AUCTION_FREE_DEN` of the rows lost their pair (the old prices are then of
/// little use: travel costs in a scene during a drag keep 10–15 % of the pairs, and
/// the exact searches from there ran 10⁵ row expansions). Below that the exact
/// searches from the old prices are cheaper (a drifting formation at 1,000 agents
/// breaks about 65 % of its pairs and repairs them quicker than an auction).
const WARM_AUCTION_FREE_NUM: usize = 3;
/// See [`WARM_AUCTION_FREE_NUM`].
const WARM_AUCTION_FREE_DEN: usize = 4;

/// A warm start whose broken pairs are off by more than `WARM_COLD_SLACK` local cost
/// spreads on average (their slack against the row minimum, over the mean spread of
/// the rows' cheapest few reduced costs) starts over cold: the goals moved by several
/// spacings, the old prices mislead the searches, and repairing from them costs
/// several cold solves (a deformed formation at 5,000 agents, 55 % of the pairs broken
/// at 3.3 spreads: 1.0 s warm against 0.15 s restarted; a drifting one at 0.5
/// spreads stays warm and is quicker so).
const WARM_COLD_SLACK: f64 = 2.0;

/// Pricing rounds of the sparse strategy before it finishes densely.
pub(super) const MAX_ROUNDS: u32 = 16;

/// [`Strategy::Auto`] solves densely up to this many columns.
const AUTO_DENSE_MAX_COLS: usize = 128;

/// "No row / no column" in the matching arrays.
pub(super) const NONE: usize = usize::MAX;

/// How [`Solver`] searches for augmenting paths. All strategies return an optimal
/// assignment; they differ only in speed.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Dense for small problems (at most 128 columns), sparse otherwise.
    #[default]
    Auto,
    /// Dijkstra over full rows (classic dense shortest augmenting path).
    Dense,
    /// Auction-initialised prices, then Dijkstra over sorted per-row candidate lists
    /// with lazy full-row refills (see the module documentation).
    Sparse,
}

/// Work counters of the last solve (for benchmarks and tuning; not part of the result).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Whether the previous duals and assignment were reused.
    pub warm: bool,
    /// Rows still assigned after the first pricing pass of a warm start.
    pub kept_rows: usize,
    /// Row pricings: full-row streaming passes (list builds, dense pricing) and
    /// list-based checks.
    pub rows_priced: u64,
    /// Sparse pricing rounds.
    pub rounds: u32,
    /// Augmenting path searches.
    pub augmentations: u64,
    /// Rows scanned inside the searches.
    pub rows_scanned: u64,
    /// Auction phases run before the exact finish (sparse cold solves, and warm
    /// solves that broke many pairs).
    pub auction_phases: u32,
    /// Auction bids.
    pub bids: u64,
    /// Streaming passes fetching columns beyond a row's candidate list in searches.
    pub expansions: u64,
    /// Whether the dense finish was needed.
    pub dense_finish: bool,
    /// Whether a warm start broke so many pairs that the solve went on cold
    /// (`warm` is then false).
    pub restarted_cold: bool,
    /// Polls of the [`Cancel`] check (one per [`POLL_WORK`] units of work).
    pub polls: u64,
    /// Whether the solve started from prices the caller gave
    /// ([`Solver::solve_from_prices`]; `warm` is then true too).
    pub seeded: bool,
}

/// Exact assignment solver with reusable workspaces, dual prices and warm start.
///
/// Workspaces are sized on the first solve and whenever the dimensions change; solving
/// again with the same dimensions does not allocate. Memory is `O(rows · k + cols)`
/// (`k <= 64` candidates per row, 20 bytes each) besides the caller's matrix.
#[derive(Clone, Debug, Default)]
pub struct Solver {
    pub(super) strategy: Strategy,
    /// Requested candidates per row (0 = automatic).
    pub(super) k_opt: usize,
    /// Sparse rounds before the dense finish if not [`MAX_ROUNDS`] (tests lower it).
    pub(super) max_rounds: Option<u32>,
    /// Candidate slots per row (sparse strategy) for the current dimensions.
    pub(super) k: usize,
    /// Candidates the lists are built with in the current solve (`<= k`): `k` cold,
    /// fewer warm ([`WARM_LIST_NUM`]).
    pub(super) k_eff: usize,
    pub(super) rows: usize,
    pub(super) cols: usize,
    /// Whether `x`, `u`, `v` hold a complete optimal solution of the last problem.
    pub(super) solved: bool,
    pub(super) u: Vec<f64>,
    pub(super) v: Vec<f64>,
    /// Row -> column.
    pub(super) x: Vec<usize>,
    /// Column -> row.
    pub(super) y: Vec<usize>,
    // Candidate lists, `k` slots per row, sorted by `wb` (= c - v when built).
    pub(super) cand_col: Vec<u32>,
    pub(super) cand_cost: Vec<f64>,
    pub(super) cand_wb: Vec<f64>,
    pub(super) cand_len: Vec<u32>,
    /// Per row: every column off the list has `key(c - v, col) >= theta_key` and so
    /// `c - v >= theta` (`theta = +inf` when the list holds every finite entry).
    /// Stays valid while prices only decrease.
    pub(super) theta: Vec<f64>,
    pub(super) theta_key: Vec<u64>,
    /// Low key bits holding the column ([`key`]).
    ///
    /// [`key`]: super::candidates::key
    pub(super) mask: u64,
    /// Selection scratch, `4k` entries.
    pub(super) buf: Vec<u64>,
    /// Lower bound of every tentative distance of the current sparse search.
    pub(super) cur_min: f64,
    /// A free column reached at distance `cur_min` in the current search, or NONE.
    pub(super) early: usize,
    // Search workspaces (per column).
    pub(super) dist: Vec<f64>,
    pub(super) pred: Vec<u32>,
    /// Per column: search state of the current sparse search ([`Mark`]).
    pub(super) mark: Vec<Mark>,
    pub(super) epoch: u32,
    pub(super) heap: ColHeap,
    pub(super) pending: PendHeap,
    pub(super) scanned: Vec<u32>,
    pub(super) dd: Vec<f64>,
    pub(super) vm: Vec<f64>,
    // Row sets.
    pub(super) free_rows: Vec<u32>,
    pub(super) dirty: Vec<bool>,
    pub(super) dirty_rows: Vec<u32>,
    pub(super) raise: Vec<u32>,
    /// Free rows left to the exact searches by [`Solver::reduce_rows`].
    pub(super) deferred: Vec<u32>,
    /// A row computed by a [`CostSource`] that has no matrix (`cols` entries).
    pub(super) rowbuf: Vec<f64>,
    /// Upper bound of every column price during a solve (set when it starts, raised
    /// with any price; the spatial lists of [`PointCosts`] rely on it).
    ///
    /// [`PointCosts`]: super::PointCosts
    pub(super) v_hi: f64,
    pub(super) stats: SolveStats,
    /// Work units of the current solve (about one cost entry read or one list slot
    /// scanned each; [`POLL_WORK`]).
    pub(super) work: u64,
    /// `work` at which the next poll of the [`Cancel`] check is due.
    pub(super) next_poll: u64,
    /// Whether a poll of the current solve found it cancelled.
    pub(super) cancelled: bool,
    /// Sum of the slacks of the pairs freed by pricing passes (sizes the warm auction).
    pub(super) freed_slack: f64,
    /// Whether a warm start whose broken pairs are far off goes on from the old
    /// prices instead of starting over cold ([`WARM_COLD_SLACK`];
    /// [`Solver::set_warm_restarts`]). `false` (restarts on) by default.
    pub(super) no_warm_restarts: bool,
}

impl Solver {
    /// A solver with [`Strategy::Auto`] and an automatic number of candidates per row.
    pub fn new() -> Solver {
        Solver::with_strategy(Strategy::Auto)
    }

    /// A solver using `strategy`.
    pub fn with_strategy(strategy: Strategy) -> Solver {
        Solver::with_options(strategy, 0)
    }

    /// A solver using `strategy` that keeps `candidates` cheapest columns per row in
    /// the sparse strategy (`0` = automatic, growing with the number of columns from
    /// 24 to 64). The result is optimal for any value; it only trades list-building
    /// work against list refills.
    pub fn with_options(strategy: Strategy, candidates: usize) -> Solver {
        Solver {
            strategy,
            k_opt: candidates,
            ..Solver::default()
        }
    }

    /// Whether a warm start whose broken pairs are off by more than two local cost
    /// spreads starts over cold (the default, `true`). The answer is optimal either
    /// way; only the work differs. Travel costs of 5,000 agents in a scene break
    /// nearly every pair at each plan, and repairing from the old prices is quicker
    /// there (obstacle course, 5,000 agents: about 1.2 s against 2.0 s restarted).
    pub fn set_warm_restarts(&mut self, on: bool) {
        self.no_warm_restarts = !on;
    }

    /// The strategy in use.
    pub fn strategy(&self) -> Strategy {
        self.strategy
    }

    /// Work counters of the last solve.
    pub fn stats(&self) -> SolveStats {
        self.stats
    }

    /// Cold solve: ignores any previous duals and assignment. Returns row -> column.
    ///
    /// # Formula
    /// Minimises `sum_i c[i][sigma(i)]` over injections (mesh-formation-control section
    /// 6.1, eq. 2 with unit weights). On success the duals `u`, `v` satisfy
    /// `c[i][j] - u[i] - v[j] >= -eps` everywhere, `== 0` on assigned pairs, and
    /// unassigned columns carry the maximal `v` ([`Solver::verify_optimal`]), with
    /// `eps = EPS_REL * scale` ([`EPS_REL`]).
    ///
    /// # Units
    /// Costs in any unit; indices only in the result.
    ///
    /// # Complexity
    /// Dense strategy `O(rows² · cols)` worst case. Sparse strategy: one streaming
    /// pass over the matrix, heap searches over short sorted candidate lists, and a
    /// streaming full-row pass only for rows whose dual outgrows their list; the same
    /// worst case, far less on geometric instances. No allocation when the dimensions
    /// equal those of the previous call.
    ///
    /// # Errors
    /// [`AssignError::Empty`], [`AssignError::MoreRowsThanCols`],
    /// [`AssignError::NotFinite`] (first NaN/`-inf` in row-major order),
    /// [`AssignError::Infeasible`]. After an error [`Solver::assignment`] is empty and
    /// the next warm solve is cold.
    pub fn solve(&mut self, costs: &CostMatrix) -> Result<&[usize], AssignError> {
        self.solve_with(costs)
    }

    /// [`Solver::solve`] on any [`CostSource`] (e.g. [`PointCosts`]: the same answer
    /// as on the matrix they describe, without the matrix).
    ///
    /// # Errors
    /// As [`Solver::solve`].
    ///
    /// [`PointCosts`]: super::PointCosts
    pub fn solve_with<S: CostSource>(&mut self, costs: &S) -> Result<&[usize], AssignError> {
        self.solve_with_cancel(costs, Cancel::NEVER)
    }

    /// [`Solver::solve_with`] that gives up when `cancel` says so: the check is
    /// polled about every [`POLL_WORK`] units of work, in every phase, and a
    /// cancelled solve returns [`AssignError::Cancelled`] at the first poll that
    /// sees it. Not cancelled, the answer is the same as without the check.
    ///
    /// # Errors
    /// As [`Solver::solve`], and [`AssignError::Cancelled`].
    pub fn solve_with_cancel<S: CostSource>(
        &mut self,
        costs: &S,
        cancel: Cancel<'_>,
    ) -> Result<&[usize], AssignError> {
        self.check_dims(costs)?;
        self.size_for(costs.rows(), costs.cols());
        self.stats = SolveStats::default();
        self.start_polls();
        self.cold_start(costs, cancel);
        self.finish(costs, cancel)
    }

    /// Restarts the work count and the cancellation state for a new solve.
    pub(super) fn start_polls(&mut self) {
        self.work = 0;
        self.next_poll = POLL_WORK;
        self.cancelled = false;
    }

    /// Polls `cancel` when [`POLL_WORK`] units of work were done since the last
    /// poll; returns whether the solve is cancelled (it stays so).
    #[inline]
    pub(super) fn poll(&mut self, cancel: Cancel<'_>) -> bool {
        if self.work >= self.next_poll {
            self.next_poll = self.work + POLL_WORK;
            self.stats.polls += 1;
            if !self.cancelled && cancel.cancelled() {
                self.cancelled = true;
            }
        }
        self.cancelled
    }

    /// `Err(Cancelled)` once a poll found the solve cancelled.
    pub(super) fn halted(&self) -> Result<(), AssignError> {
        if self.cancelled {
            Err(AssignError::Cancelled)
        } else {
            Ok(())
        }
    }

    /// The cold initial state: no pairs, prices from a column reduction (square) or
    /// all 0 (rectangular: free columns must keep the maximal price, so all start
    /// equal), full-length candidate lists.
    fn cold_start<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        if costs.rows() == costs.cols() {
            self.column_reduction(costs, cancel);
        } else {
            self.v.fill(0.0);
        }
        self.x.fill(NONE);
        self.y.fill(NONE);
        self.k_eff = self.k;
    }

    /// Empties the row sets a solve works through (dirty, free, columns to raise).
    pub(super) fn clear_row_sets(&mut self) {
        for &i in &self.dirty_rows {
            self.dirty[i as usize] = false;
        }
        self.dirty_rows.clear();
        self.free_rows.clear();
        self.raise.clear();
    }

    /// Sets `v_hi` to the largest column price (at least 0 for a rectangular
    /// problem, whose free columns sit at 0).
    pub(super) fn set_price_bound(&mut self) {
        let rect = self.rows < self.cols;
        self.v_hi = self
            .v
            .iter()
            .fold(if rect { 0.0 } else { f64::NEG_INFINITY }, |a, &b| a.max(b));
    }

    /// A warm start whose prices are far off ([`WARM_COLD_SLACK`]) continues as a cold
    /// solve; the counters keep what the warm pricing pass did.
    fn restart_cold<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        self.clear_row_sets();
        self.cold_start(costs, cancel);
        self.stats.warm = false;
        self.stats.restarted_cold = true;
        self.set_price_bound();
    }

    /// Warm solve: when the dimensions equal those of the last successful solve, starts
    /// from its column prices and assignment (pairs that are still tight are kept, the
    /// rest re-augmented); otherwise a cold [`Solver::solve`]. The result is optimal
    /// either way.
    ///
    /// # Formula, Units, Errors
    /// As [`Solver::solve`].
    ///
    /// # Complexity
    /// One streaming pricing pass over the matrix plus the re-augmentation of the freed
    /// rows; no allocation.
    pub fn solve_warm(&mut self, costs: &CostMatrix) -> Result<&[usize], AssignError> {
        self.solve_warm_with(costs)
    }

    /// [`Solver::solve_warm`] on any [`CostSource`].
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_warm_with<S: CostSource>(&mut self, costs: &S) -> Result<&[usize], AssignError> {
        self.solve_warm_with_cancel(costs, Cancel::NEVER)
    }

    /// [`Solver::solve_warm_with`] that gives up when `cancel` says so (as
    /// [`Solver::solve_with_cancel`]); a cancelled warm solve leaves the next one
    /// cold.
    ///
    /// # Errors
    /// As [`Solver::solve`], and [`AssignError::Cancelled`].
    pub fn solve_warm_with_cancel<S: CostSource>(
        &mut self,
        costs: &S,
        cancel: Cancel<'_>,
    ) -> Result<&[usize], AssignError> {
        self.check_dims(costs)?;
        if !self.solved || costs.rows() != self.rows || costs.cols() != self.cols {
            return self.solve_with_cancel(costs, cancel);
        }
        self.start_polls();
        self.shift_prices(costs);
        // Keep the prices bounded over long runs: shift so that max v = 0 (reduced
        // costs are unchanged; free columns of a rectangular problem are already at
        // the maximum, 0).
        let vmax = self.v.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        if vmax.is_finite() && vmax != 0.0 {
            for e in &mut self.v {
                *e -= vmax;
            }
        }
        self.stats = SolveStats {
            warm: true,
            ..SolveStats::default()
        };
        self.freed_slack = 0.0;
        self.k_eff = (self.k * WARM_LIST_NUM / WARM_LIST_DEN).max(1);
        self.finish(costs, cancel)
    }

    /// Warm start: carries each column's price over by the change of its assigned
    /// cost, `v[j] = c_new[i][j] - u[i]` for its row `i`, so every kept pair starts
    /// tight with the old row dual. A change that splits into a row part and a column
    /// part (the whole formation moving, turning or scaling a little) then leaves the
    /// reduced costs almost as they were. Rectangular problems keep the assigned
    /// prices at or below the free columns' 0.
    fn shift_prices<S: CostSource>(&mut self, costs: &S) {
        let rect = self.rows < self.cols;
        for (i, &j) in self.x.iter().enumerate() {
            let c = costs.get(i, j);
            if c.is_finite() {
                let vj = c - self.u[i];
                self.v[j] = if rect && vj > 0.0 { 0.0 } else { vj };
            }
        }
    }

    /// The assignment of the last successful solve (row -> column); empty after an
    /// error or before the first solve.
    pub fn assignment(&self) -> &[usize] {
        if self.solved {
            &self.x
        } else {
            &[]
        }
    }

    /// Total cost of the current assignment under `costs`; NaN if there is no
    /// assignment or the dimensions differ.
    pub fn total_cost<S: CostSource>(&self, costs: &S) -> f64 {
        if !self.solved || costs.rows() != self.rows || costs.cols() != self.cols {
            return f64::NAN;
        }
        self.x
            .iter()
            .enumerate()
            .map(|(i, &j)| costs.get(i, j))
            .sum()
    }

    /// Checks the optimality certificate of the current assignment against `costs`:
    /// the assignment is an injection; reduced costs `c[i][j] - u[i] - v[j] >= -tol`
    /// for all pairs and `|c[i][j] - u[i] - v[j]| <= tol` on assigned pairs; and every
    /// unassigned column has `v[j] >= max_k v[k] - tol`. Together these prove that no
    /// injection is cheaper by more than `2 * rows * tol`.
    ///
    /// # Complexity
    /// `O(rows · cols)`, no allocation.
    pub fn verify_optimal<S: CostSource>(&self, costs: &S, tol: f64) -> bool {
        if !self.solved || costs.rows() != self.rows || costs.cols() != self.cols {
            return false;
        }
        let (rows, cols) = (self.rows, self.cols);
        for (i, &j) in self.x.iter().enumerate() {
            if j >= cols || self.y[j] != i {
                return false;
            }
        }
        let assigned = self.y.iter().filter(|&&i| i != NONE).count();
        if assigned != rows {
            return false;
        }
        for i in 0..rows {
            let ui = self.u[i];
            for (j, vj) in self.v.iter().enumerate() {
                let c = costs.get(i, j);
                // NaN fails this comparison too.
                if !(c - ui - vj >= -tol) {
                    return false;
                }
            }
            let j = self.x[i];
            let r = costs.get(i, j) - ui - self.v[j];
            if !(r.abs() <= tol) {
                return false;
            }
        }
        let vmax = self.v.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        (0..cols).all(|j| self.y[j] != NONE || self.v[j] >= vmax - tol)
    }

    // -- internals -------------------------------------------------------------------

    /// Tolerance of the debug certificate check: far above rounding, far below any
    /// real sub-optimality.
    fn debug_tolerance<S: CostSource>(&self, costs: &S) -> f64 {
        let mut scale = 0.0f64;
        for (i, &j) in self.x.iter().enumerate() {
            scale = scale.max(costs.get(i, j).abs()).max(self.u[i].abs());
        }
        for &vj in &self.v {
            scale = scale.max(vj.abs());
        }
        1e3 * EPS_REL * scale + f64::MIN_POSITIVE
    }

    /// Square problems: initial prices `v[j] = min_i c[i][j]` (Jonker–Volgenant column
    /// reduction), which removes any large per-goal cost component (e.g. a crowd far
    /// from its formation) before candidate lists are chosen. Columns without a finite
    /// entry get 0.
    fn column_reduction<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        self.v.fill(f64::INFINITY);
        for i in 0..costs.rows() {
            if self.poll(cancel) {
                return;
            }
            self.work += self.cols as u64;
            for (vj, &c) in self.v.iter_mut().zip(costs.row(i, &mut self.rowbuf)) {
                // `min` skips NaN; a `-inf` entry makes the price `-inf`, which the
                // first pass then reports as NaN in that column (the solve stops).
                *vj = vj.min(c);
            }
        }
        for vj in &mut self.v {
            if *vj == f64::INFINITY {
                *vj = 0.0;
            }
        }
    }

    pub(super) fn check_dims<S: CostSource>(&mut self, costs: &S) -> Result<(), AssignError> {
        let (rows, cols) = (costs.rows(), costs.cols());
        if rows == 0 {
            self.solved = false;
            return Err(AssignError::Empty);
        }
        if rows > cols {
            self.solved = false;
            return Err(AssignError::MoreRowsThanCols { rows, cols });
        }
        Ok(())
    }

    /// Sizes every workspace for `rows × cols`; does nothing when unchanged.
    pub(super) fn size_for(&mut self, rows: usize, cols: usize) {
        if rows == self.rows && cols == self.cols && self.x.len() == rows {
            return;
        }
        let k = if self.k_opt == 0 {
            (cols / AUTO_CANDIDATES_DIV).clamp(AUTO_CANDIDATES_MIN, AUTO_CANDIDATES_MAX)
        } else {
            self.k_opt
        };
        self.k = k;
        self.k_eff = k;
        self.solved = false;
        self.rows = rows;
        self.cols = cols;
        self.u.resize(rows, 0.0);
        self.v.resize(cols, 0.0);
        self.x.resize(rows, NONE);
        self.y.resize(cols, NONE);
        self.cand_col.resize(rows * k, 0);
        self.cand_cost.resize(rows * k, 0.0);
        self.cand_wb.resize(rows * k, 0.0);
        self.cand_len.clear();
        self.cand_len.resize(rows, 0);
        self.theta.resize(rows, f64::INFINITY);
        self.theta_key.resize(rows, 0);
        let bits = (usize::BITS - (cols.max(4 * k).max(2) - 1).leading_zeros()).min(32);
        self.mask = (1u64 << bits) - 1;
        self.buf.resize(4 * k, 0);
        self.dist.resize(cols, 0.0);
        self.pred.resize(cols, 0);
        self.mark.clear();
        self.mark.resize(cols, Mark::default());
        self.epoch = 0;
        self.heap.size_for(cols);
        self.pending.size_for(rows);
        self.scanned = Vec::with_capacity(cols);
        self.dd.resize(cols, 0.0);
        self.vm.resize(cols, 0.0);
        self.free_rows = Vec::with_capacity(rows);
        self.dirty.clear();
        self.dirty.resize(rows, false);
        self.dirty_rows = Vec::with_capacity(rows);
        self.raise = Vec::with_capacity(rows + cols);
        self.deferred = Vec::with_capacity(rows);
        self.rowbuf = Vec::with_capacity(cols);
    }

    pub(super) fn use_sparse(&self) -> bool {
        match self.strategy {
            Strategy::Dense => false,
            Strategy::Sparse => true,
            Strategy::Auto => self.cols > AUTO_DENSE_MAX_COLS,
        }
    }

    /// Common driver of cold and warm solves (state: prices `v`, partial matching).
    pub(super) fn finish<S: CostSource>(
        &mut self,
        costs: &S,
        cancel: Cancel<'_>,
    ) -> Result<&[usize], AssignError> {
        self.solved = false;
        match self.halted().and_then(|()| self.run(costs, cancel)) {
            Ok(()) => {
                for (i, &j) in self.x.iter().enumerate() {
                    self.u[i] = costs.get(i, j) - self.v[j];
                }
                self.solved = true;
                debug_assert!(
                    self.verify_optimal(costs, self.debug_tolerance(costs)),
                    "assignment certificate failed"
                );
                Ok(&self.x)
            }
            Err(e) => {
                // Leave a consistent (cold) state behind.
                self.x.fill(NONE);
                self.y.fill(NONE);
                self.clear_row_sets();
                Err(e)
            }
        }
    }

    /// The phases of a solve; every phase polls `cancel` and the solve stops with
    /// [`AssignError::Cancelled`] after the first one that saw it.
    fn run<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) -> Result<(), AssignError> {
        costs.validate()?;
        let sparse = self.use_sparse();
        self.set_price_bound();
        self.price_all(costs, sparse, true, cancel)?;
        if self.stats.warm {
            self.stats.kept_rows = self.x.iter().filter(|&&j| j != NONE).count();
            let freed = self.free_rows.len();
            let far_off = freed > 0
                && self.local_spread().is_some_and(|spread| {
                    self.freed_slack > WARM_COLD_SLACK * spread * freed as f64
                });
            if sparse && far_off && !self.no_warm_restarts {
                self.restart_cold(costs, cancel);
                self.halted()?;
                self.price_all(costs, sparse, true, cancel)?;
            }
        }
        let many_free =
            self.free_rows.len() * WARM_AUCTION_FREE_DEN > self.rows * WARM_AUCTION_FREE_NUM;
        // Prices from a coarser instance are near optimal but break about half the
        // greedy pairs; a short auction from there beats the row reduction (1,000
        // agents against synthesised starts: 7.6–8.0 ms CPU p50 against 9.9).
        let many_free = many_free || self.stats.seeded;
        if sparse && (!self.stats.warm || many_free) {
            self.auction(costs, cancel);
            self.halted()?;
            self.tighten(costs, cancel);
            self.halted()?;
            if self.rows < self.cols {
                for j in 0..self.cols {
                    if self.y[j] == NONE && self.v[j] < 0.0 {
                        self.raise.push(j as u32);
                    }
                }
            }
            self.price_all_lists(costs, cancel);
            self.halted()?;
        }
        if sparse && self.stats.warm {
            self.reduce_rows(costs, cancel);
            self.halted()?;
        }
        if sparse {
            loop {
                if self.free_rows.is_empty() {
                    return Ok(());
                }
                if self.stats.rounds >= self.max_rounds.unwrap_or(MAX_ROUNDS) {
                    break;
                }
                self.stats.rounds += 1;
                while let Some(i) = self.free_rows.pop() {
                    if !self.sparse_augment(costs, i as usize, cancel) {
                        self.halted()?;
                        return Err(AssignError::Infeasible { row: i as usize });
                    }
                }
                self.price_dirty(costs, cancel);
                self.halted()?;
            }
            // Safety net (not reached in practice): make the duals feasible on the
            // whole matrix again, then augment the remaining free rows densely.
            self.stats.dense_finish = true;
            for &i in &self.dirty_rows {
                self.dirty[i as usize] = false;
            }
            self.dirty_rows.clear();
            self.price_all(costs, false, false, cancel)?;
        }
        self.dense_all(costs, cancel)
    }

    /// Identity of every internal buffer (pointer, capacity), to check that repeated
    /// same-size solves do not reallocate.
    #[cfg(test)]
    pub(super) fn buffer_fingerprint(&self) -> Vec<(usize, usize)> {
        fn f<T>(v: &Vec<T>) -> (usize, usize) {
            (v.as_ptr() as usize, v.capacity())
        }
        vec![
            f(&self.u),
            f(&self.v),
            f(&self.x),
            f(&self.y),
            f(&self.cand_col),
            f(&self.cand_cost),
            f(&self.cand_wb),
            f(&self.cand_len),
            f(&self.theta),
            f(&self.theta_key),
            f(&self.buf),
            f(&self.dist),
            f(&self.pred),
            f(&self.mark),
            f(&self.heap.key),
            f(&self.heap.col),
            f(&self.heap.pos),
            f(&self.rowbuf),
            f(&self.pending.items),
            f(&self.scanned),
            f(&self.dd),
            f(&self.vm),
            f(&self.free_rows),
            f(&self.dirty),
            f(&self.dirty_rows),
            f(&self.raise),
            f(&self.deferred),
        ]
    }
}
