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
//! (step 1), keeps the pairs that are still tight, runs a short auction if more than
//! nine tenths of the rows lost their pair, otherwise a budgeted augmenting row
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
/// little use). Below that the exact searches from the old prices are cheaper.
const WARM_AUCTION_FREE_NUM: usize = 9;
/// See [`WARM_AUCTION_FREE_NUM`].
const WARM_AUCTION_FREE_DEN: usize = 10;

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
    /// Sum of the slacks of the pairs freed by pricing passes (sizes the warm auction).
    pub(super) freed_slack: f64,
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
        self.check_dims(costs)?;
        self.size_for(costs.rows(), costs.cols());
        if costs.rows() == costs.cols() {
            self.column_reduction(costs);
        } else {
            // Rectangular: free columns must keep the maximal price, so all start equal.
            self.v.fill(0.0);
        }
        self.x.fill(NONE);
        self.y.fill(NONE);
        self.stats = SolveStats::default();
        self.k_eff = self.k;
        self.finish(costs)
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
        self.check_dims(costs)?;
        if !self.solved || costs.rows() != self.rows || costs.cols() != self.cols {
            return self.solve_with(costs);
        }
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
        self.finish(costs)
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
    fn column_reduction<S: CostSource>(&mut self, costs: &S) {
        self.v.fill(f64::INFINITY);
        for i in 0..costs.rows() {
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

    fn check_dims<S: CostSource>(&mut self, costs: &S) -> Result<(), AssignError> {
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
    fn size_for(&mut self, rows: usize, cols: usize) {
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
    fn finish<S: CostSource>(&mut self, costs: &S) -> Result<&[usize], AssignError> {
        self.solved = false;
        match self.run(costs) {
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
                for &i in &self.dirty_rows {
                    self.dirty[i as usize] = false;
                }
                self.dirty_rows.clear();
                self.free_rows.clear();
                self.raise.clear();
                Err(e)
            }
        }
    }

    fn run<S: CostSource>(&mut self, costs: &S) -> Result<(), AssignError> {
        costs.validate()?;
        let sparse = self.use_sparse();
        let rect = self.rows < self.cols;
        self.v_hi = self
            .v
            .iter()
            .fold(if rect { 0.0 } else { f64::NEG_INFINITY }, |a, &b| a.max(b));
        self.price_all(costs, sparse, true)?;
        if self.stats.warm {
            self.stats.kept_rows = self.x.iter().filter(|&&j| j != NONE).count();
        }
        let many_free =
            self.free_rows.len() * WARM_AUCTION_FREE_DEN > self.rows * WARM_AUCTION_FREE_NUM;
        if sparse && (!self.stats.warm || many_free) {
            self.auction(costs);
            self.tighten(costs);
            if self.rows < self.cols {
                for j in 0..self.cols {
                    if self.y[j] == NONE && self.v[j] < 0.0 {
                        self.raise.push(j as u32);
                    }
                }
            }
            self.price_all_lists(costs);
        }
        if sparse && self.stats.warm {
            self.reduce_rows(costs);
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
                    if !self.sparse_augment(costs, i as usize) {
                        return Err(AssignError::Infeasible { row: i as usize });
                    }
                }
                self.price_dirty(costs);
            }
            // Safety net (not reached in practice): make the duals feasible on the
            // whole matrix again, then augment the remaining free rows densely.
            self.stats.dense_finish = true;
            for &i in &self.dirty_rows {
                self.dirty[i as usize] = false;
            }
            self.dirty_rows.clear();
            self.price_all(costs, false, false)?;
        }
        self.dense_all(costs)
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

#[cfg(test)]
mod tests {
    use super::Strategy as Algo;
    use super::*;
    use crate::crowd::assign::costs::{CostProvider, Distance, SquaredDistance};
    use crate::crowd::assign::points::{PointCosts, PointMetric};
    use crate::geom::Vec2;
    use crate::rng::SplitMix64;
    use proptest::prelude::{prop_assert, prop_oneof, proptest, Just, TestCaseError};
    use proptest::strategy::Strategy as _;
    use proptest::test_runner::{Config as ProptestConfig, RngSeed};

    fn points(rng: &mut SplitMix64, n: usize) -> Vec<Vec2> {
        (0..n).map(|_| Vec2::new(rng.unit(), rng.unit())).collect()
    }

    /// Minimum total cost over all injections rows -> cols (None if none is finite).
    fn brute_force(c: &CostMatrix) -> Option<f64> {
        fn rec(c: &CostMatrix, i: usize, used: &mut [bool], acc: f64, best: &mut f64) {
            if i == c.rows() {
                if acc < *best {
                    *best = acc;
                }
                return;
            }
            for j in 0..c.cols() {
                let e = c.get(i, j);
                if !used[j] && e < f64::INFINITY {
                    used[j] = true;
                    rec(c, i + 1, used, acc + e, best);
                    used[j] = false;
                }
            }
        }
        let mut best = f64::INFINITY;
        rec(c, 0, &mut vec![false; c.cols()], 0.0, &mut best);
        best.is_finite().then_some(best)
    }

    /// Every configuration worth exercising: dense, sparse with very few candidates
    /// (forces many pricing rounds and repairs), sparse default, auto.
    fn solvers() -> Vec<Solver> {
        vec![
            Solver::with_strategy(Algo::Dense),
            Solver::with_options(Algo::Sparse, 1),
            Solver::with_options(Algo::Sparse, 2),
            Solver::with_strategy(Algo::Sparse),
            Solver::new(),
        ]
    }

    fn check_against_brute(
        s: &mut Solver,
        c: &CostMatrix,
        warm: bool,
    ) -> Result<(), TestCaseError> {
        let want = brute_force(c).expect("instances are feasible by construction");
        let res = if warm {
            s.solve_warm(c).map(|_| ())
        } else {
            s.solve(c).map(|_| ())
        };
        prop_assert!(res.is_ok(), "{:?} failed: {:?}", s.strategy(), res);
        let got = s.total_cost(c);
        prop_assert!(
            (got - want).abs() <= 1e-9 * (1.0 + want.abs()),
            "{:?} (k={}) warm={}: got {} want {}",
            s.strategy(),
            s.k,
            warm,
            got,
            want
        );
        prop_assert!(s.verify_optimal(c, 1e-9));
        Ok(())
    }

    /// A feasible matrix: rows <= cols <= 8, integer (tie-heavy) or real entries, some
    /// `+inf`, and a hidden injection kept finite so a finite assignment exists.
    fn matrix() -> impl proptest::strategy::Strategy<Value = CostMatrix> {
        (1usize..=8)
            .prop_flat_map(|r| (Just(r), r..=8usize))
            .prop_flat_map(|(r, c)| {
                let entry = prop_oneof![
                    4 => (0i32..4).prop_map(f64::from),
                    4 => -10.0..10.0f64,
                    1 => Just(f64::INFINITY),
                ];
                (
                    Just(r),
                    Just(c),
                    proptest::collection::vec(entry, r * c),
                    Just((0..c).collect::<Vec<usize>>()).prop_shuffle(),
                )
            })
            .prop_map(|(r, c, data, perm)| {
                let mut m = CostMatrix::from_fn(r, c, |i, j| data[i * c + j]);
                for (i, &j) in perm.iter().take(r).enumerate() {
                    if m.get(i, j) == f64::INFINITY {
                        m.set(i, j, 3.0);
                    }
                }
                m
            })
    }

    fn config(cases: u32, seed: u64) -> ProptestConfig {
        ProptestConfig {
            cases,
            rng_seed: RngSeed::Fixed(seed),
            failure_persistence: None,
            ..ProptestConfig::default()
        }
    }

    proptest! {
        #![proptest_config(config(160, 0x00A5_5167))]

        #[test]
        fn cold_equals_brute_force(c in matrix()) {
            for mut s in solvers() {
                check_against_brute(&mut s, &c, false)?;
            }
        }
    }

    proptest! {
        #![proptest_config(config(96, 0x0005_1A7E))]

        #[test]
        fn warm_after_perturbation_equals_brute_force(
            c in matrix(),
            noise in proptest::collection::vec((0usize..64, -2i32..=2, -0.5..0.5f64), 0..12),
            frames in 1usize..4,
        ) {
            for mut s in solvers() {
                check_against_brute(&mut s, &c, false)?;
                let mut cur = c.clone();
                for f in 0..frames {
                    // Perturb some finite entries (integer steps keep ties; real steps
                    // break them), never creating an infeasible instance.
                    for (t, &(idx, step, real)) in noise.iter().enumerate() {
                        let e = (idx + 7 * t + 13 * f) % (cur.rows() * cur.cols());
                        let (i, j) = (e / cur.cols(), e % cur.cols());
                        let old = cur.get(i, j);
                        if old.is_finite() {
                            let new = if t % 2 == 0 { old + f64::from(step) } else { old + real };
                            cur.set(i, j, new);
                        }
                    }
                    check_against_brute(&mut s, &cur, true)?;
                }
            }
        }
    }

    /// Point sets for the geometric fast path: uniform, clustered (most goals in two
    /// small clumps), duplicated positions, all goals on one line, and a crowd far
    /// from its formation.
    fn layout(rng: &mut SplitMix64, n: usize, kind: u8) -> Vec<Vec2> {
        (0..n)
            .map(|k| match kind {
                0 => Vec2::new(rng.unit(), rng.unit()),
                1 => {
                    let c = if k % 3 == 0 { 0.2 } else { 0.8 };
                    Vec2::new(c + 0.01 * rng.unit(), c + 0.01 * rng.unit())
                }
                2 => Vec2::new((k % 5) as f64 * 0.25, 0.5),
                3 => Vec2::new(rng.unit(), 0.3),
                _ => Vec2::new(40.0 + rng.unit(), -7.0 + rng.unit()),
            })
            .collect()
    }

    proptest! {
        #![proptest_config(config(64, 0x09E0_FA57))]

        /// The spatial candidate lists of `PointCosts` are exactly the streamed
        /// ones: the same assignment and the same work counters as on the matrix,
        /// cold and over warm frames in which the goals move, square and
        /// rectangular, both metrics, every layout.
        #[test]
        fn point_costs_solve_exactly_as_the_matrix(
            rows in 8usize..60,
            extra in prop_oneof![Just(0usize), Just(3), Just(40)],
            candidates in prop_oneof![Just(0usize), Just(2), Just(5)],
            seed in 0u64..u64::MAX,
            agents_kind in 0u8..5,
            goals_kind in 0u8..5,
            euclid: bool,
        ) {
            let mut rng = SplitMix64::new(seed);
            let cols = rows + extra;
            let agents = layout(&mut rng, rows, agents_kind);
            let mut goals = layout(&mut rng, cols, goals_kind);
            let metric = if euclid { PointMetric::Euclidean } else { PointMetric::Squared };
            let mut pc = PointCosts::new(metric);
            let mut c = CostMatrix::new(0, 0);
            // The sparse strategy at any size (Auto turns to it above 128 columns);
            // short lists exercise the list refills.
            let solver = || Solver::with_options(Algo::Sparse, candidates);
            let (mut sp, mut sm) = (solver(), solver());
            for frame in 0..3 {
                pc.set(&agents, &goals);
                if euclid {
                    Distance.fill(&agents, &goals, &mut c);
                } else {
                    SquaredDistance.fill(&agents, &goals, &mut c);
                }
                for i in 0..rows {
                    for j in (0..cols).step_by(17) {
                        prop_assert!(pc.get(i, j).to_bits() == c.get(i, j).to_bits());
                    }
                }
                let a = sp.solve_warm_with(&pc).unwrap().to_vec();
                let b = sm.solve_warm(&c).unwrap().to_vec();
                prop_assert!(a == b, "frame {}: assignments differ", frame);
                prop_assert!(sp.stats() == sm.stats(), "frame {}: {:?} vs {:?}", frame, sp.stats(), sm.stats());
                prop_assert!(sp.verify_optimal(&c, 1e-9));
                prop_assert!(sp.verify_optimal(&pc, 1e-9));
                for g in &mut goals {
                    g.x += 0.04 * (rng.unit() - 0.5);
                    g.y += 0.04 * (rng.unit() - 0.5);
                }
            }
        }
    }

    #[test]
    fn point_costs_name_the_first_bad_position() {
        let mut pc = PointCosts::new(PointMetric::Squared);
        let mut s = Solver::new();
        let ok = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)];
        pc.set(&[ok[0], Vec2::new(f64::NAN, 0.0)], &ok);
        assert_eq!(
            s.solve_with(&pc),
            Err(AssignError::NotFinite { row: 1, col: 0 })
        );
        pc.set(&ok, &[ok[1], Vec2::new(0.0, f64::INFINITY)]);
        assert_eq!(
            s.solve_with(&pc),
            Err(AssignError::NotFinite { row: 0, col: 1 })
        );
        pc.set(&[], &ok);
        assert_eq!(s.solve_with(&pc), Err(AssignError::Empty));
        pc.set(&ok, &ok[..1]);
        assert_eq!(
            s.solve_with(&pc),
            Err(AssignError::MoreRowsThanCols { rows: 2, cols: 1 })
        );
        // The solver recovers: the next good instance solves.
        pc.set(&ok, &[ok[1], ok[0]]);
        assert_eq!(s.solve_with(&pc).unwrap(), &[1, 0]);
    }

    #[test]
    fn point_costs_do_not_reallocate_on_same_sized_frames() {
        let mut rng = SplitMix64::new(7);
        let agents = points(&mut rng, 300);
        let mut goals = points(&mut rng, 300);
        let mut pc = PointCosts::new(PointMetric::Squared);
        let mut s = Solver::new();
        pc.set(&agents, &goals);
        s.solve_with(&pc).unwrap();
        let caps = |p: &PointCosts| {
            [&p.ax, &p.ay, &p.gx, &p.gy, &p.bx, &p.by]
                .iter()
                .map(|v| (v.as_ptr() as usize, v.capacity()))
                .chain(
                    [&p.start, &p.order]
                        .iter()
                        .map(|v| (v.as_ptr() as usize, v.capacity())),
                )
                .collect::<Vec<_>>()
        };
        let (before, fp) = (caps(&pc), s.buffer_fingerprint());
        for _ in 0..5 {
            for g in &mut goals {
                g.x += 0.01 * (rng.unit() - 0.5);
            }
            pc.set(&agents, &goals);
            s.solve_warm_with(&pc).unwrap();
        }
        assert_eq!(caps(&pc), before);
        assert_eq!(s.buffer_fingerprint(), fp);
    }

    fn run_chain(rows: usize, cols: usize, seed: u64, strategy: Algo) {
        let mut rng = SplitMix64::new(seed);
        let mut agents = points(&mut rng, rows);
        let mut goals = points(&mut rng, cols);
        let mut c = CostMatrix::new(0, 0);
        let mut s = Solver::with_strategy(strategy);
        SquaredDistance.fill(&agents, &goals, &mut c);
        s.solve(&c).unwrap();
        assert!(
            s.verify_optimal(&c, 1e-9),
            "cold {rows}x{cols} {strategy:?}"
        );
        let mut cold = Solver::with_strategy(Algo::Dense);
        for frame in 0..20 {
            for p in goals.iter_mut().chain(agents.iter_mut().take(rows / 10)) {
                p.x += 0.04 * (rng.unit() - 0.5);
                p.y += 0.04 * (rng.unit() - 0.5);
            }
            SquaredDistance.fill(&agents, &goals, &mut c);
            s.solve_warm(&c).unwrap();
            assert!(s.stats().warm);
            assert!(
                s.verify_optimal(&c, 1e-9),
                "warm frame {frame} {rows}x{cols} {strategy:?}"
            );
            if frame % 5 == 0 {
                cold.solve(&c).unwrap();
                assert!(cold.verify_optimal(&c, 1e-9));
                let (a, b) = (s.total_cost(&c), cold.total_cost(&c));
                assert!((a - b).abs() < 1e-9, "frame {frame}: warm {a} cold {b}");
            }
        }
    }

    /// A medium instance: random real or small-integer costs (ties), some `+inf`
    /// entries off a hidden feasible injection.
    fn medium(rows: usize, cols: usize, seed: u64, ints: bool, inf_per_mille: u64) -> CostMatrix {
        let mut rng = SplitMix64::new(seed);
        let mut perm: Vec<usize> = (0..cols).collect();
        for i in (1..cols).rev() {
            perm.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        let mut c = CostMatrix::from_fn(rows, cols, |_, _| {
            if rng.next_u64() % 1000 < inf_per_mille {
                f64::INFINITY
            } else if ints {
                (rng.next_u64() % 6) as f64
            } else {
                10.0 * rng.unit() - 3.0
            }
        });
        for (i, &j) in perm.iter().take(rows).enumerate() {
            if c.get(i, j) == f64::INFINITY {
                c.set(i, j, 2.0);
            }
        }
        c
    }

    proptest! {
        #![proptest_config(config(48, 0x0000_3D1A))]

        /// The sparse machinery (auction, tightening, lazy lists, list refills,
        /// rectangular price raises, dense finish) against the dense solver on
        /// instances too large for brute force, cold and over warm frames.
        #[test]
        fn sparse_matches_dense_on_medium_instances(
            rows in 5usize..40,
            extra in 0usize..12,
            seed in 0u64..u64::MAX,
            ints: bool,
            inf_per_mille in prop_oneof![Just(0u64), Just(100), Just(400)],
            k in 1usize..6,
            max_rounds in prop_oneof![Just(0u32), Just(1), Just(MAX_ROUNDS)],
        ) {
            let cols = rows + extra;
            let mut dense = Solver::with_strategy(Algo::Dense);
            let mut sparse = Solver::with_options(Algo::Sparse, k);
            sparse.max_rounds = Some(max_rounds);
            let mut c = medium(rows, cols, seed, ints, inf_per_mille);
            for frame in 0..4u64 {
                dense.solve(&c).unwrap();
                let res = if frame == 0 { sparse.solve(&c) } else { sparse.solve_warm(&c) };
                prop_assert!(res.is_ok(), "{:?}", res);
                prop_assert!(sparse.verify_optimal(&c, 1e-9), "frame {}", frame);
                let (a, b) = (sparse.total_cost(&c), dense.total_cost(&c));
                prop_assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "frame {}: {} vs {}", frame, a, b);
                // Next frame: perturb the finite entries.
                let mut rng = SplitMix64::new(seed ^ (frame + 1));
                for i in 0..rows {
                    for e in c.row_mut(i) {
                        if e.is_finite() && rng.next_u64() % 3 == 0 {
                            *e += if ints { (rng.next_u64() % 3) as f64 - 1.0 } else { rng.unit() - 0.5 };
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn certificate_square_200_cold_and_warm_chain() {
        run_chain(200, 200, 1, Algo::Sparse);
        run_chain(200, 200, 2, Algo::Dense);
    }

    #[test]
    fn certificate_rectangular_300x400_cold_and_warm_chain() {
        run_chain(300, 400, 3, Algo::Sparse);
        run_chain(300, 400, 4, Algo::Dense);
    }

    #[test]
    fn sparse_with_one_candidate_matches_dense_on_200() {
        let mut rng = SplitMix64::new(5);
        let (a, g) = (points(&mut rng, 200), points(&mut rng, 230));
        let mut c = CostMatrix::new(0, 0);
        Distance.fill(&a, &g, &mut c);
        let mut sparse = Solver::with_options(Algo::Sparse, 1);
        let mut dense = Solver::with_strategy(Algo::Dense);
        sparse.solve(&c).unwrap();
        dense.solve(&c).unwrap();
        assert!(sparse.verify_optimal(&c, 1e-9));
        assert!((sparse.total_cost(&c) - dense.total_cost(&c)).abs() < 1e-9);
    }

    #[test]
    fn matches_pathfinding_kuhn_munkres_on_integer_costs() {
        use pathfinding::kuhn_munkres::kuhn_munkres;
        use pathfinding::matrix::Matrix;
        for (seed, (rows, cols)) in [(10u64, (50, 50)), (11, (50, 50)), (12, (40, 50))] {
            let mut rng = SplitMix64::new(seed);
            let ints: Vec<i64> = (0..rows * cols)
                .map(|_| (rng.next_u64() % 100) as i64)
                .collect();
            let c = CostMatrix::from_fn(rows, cols, |i, j| ints[i * cols + j] as f64);
            let neg = Matrix::from_vec(rows, cols, ints.iter().map(|&x| -x).collect()).unwrap();
            let (best, _) = kuhn_munkres(&neg);
            for mut s in solvers() {
                s.solve(&c).unwrap();
                assert_eq!(s.total_cost(&c), -best as f64, "{:?}", s.strategy());
                assert!(s.verify_optimal(&c, 1e-9));
            }
        }
    }

    #[test]
    fn errors_are_reported_not_panicked() {
        for mut s in solvers() {
            assert_eq!(s.solve(&CostMatrix::new(0, 0)), Err(AssignError::Empty));
            assert_eq!(s.solve(&CostMatrix::new(0, 3)), Err(AssignError::Empty));
            assert_eq!(
                s.solve(&CostMatrix::new(3, 2)),
                Err(AssignError::MoreRowsThanCols { rows: 3, cols: 2 })
            );
            let mut c = CostMatrix::new(3, 3);
            c.set(1, 2, f64::NAN);
            assert_eq!(s.solve(&c), Err(AssignError::NotFinite { row: 1, col: 2 }));
            c.set(1, 2, 0.0);
            c.set(2, 0, f64::NEG_INFINITY);
            assert_eq!(
                s.solve_warm(&c),
                Err(AssignError::NotFinite { row: 2, col: 0 })
            );
            assert!(s.assignment().is_empty());
            c.set(2, 0, 1.0);
            c.row_mut(1).fill(f64::INFINITY);
            assert_eq!(s.solve(&c), Err(AssignError::Infeasible { row: 1 }));
            // Square with an all-+inf column: some row is left without a finite goal.
            let mut c = CostMatrix::from_fn(3, 3, |i, j| (i + j) as f64);
            for i in 0..3 {
                c.set(i, 1, f64::INFINITY);
            }
            assert!(matches!(s.solve(&c), Err(AssignError::Infeasible { .. })));
            // Hall violation: rows 0 and 1 can only use column 0.
            let c = CostMatrix::from_fn(2, 3, |_, j| if j == 0 { 1.0 } else { f64::INFINITY });
            assert_eq!(s.solve(&c), Err(AssignError::Infeasible { row: 1 }));
            assert!(s.assignment().is_empty());
            assert!(s.total_cost(&c).is_nan());
            assert!(!s.verify_optimal(&c, 1.0));
            // Recovers after errors, warm falls back to cold.
            let c = CostMatrix::from_fn(2, 3, |i, j| ((i + 2 * j) % 3) as f64);
            assert!(s.solve_warm(&c).is_ok());
            assert!(s.verify_optimal(&c, 0.0));
        }
    }

    /// The streaming pass of the sparse strategy filters whole blocks by their
    /// smallest reduced cost, which may skip a NaN lane: a NaN or `-inf` hidden among
    /// large entries must still be reported, cold and warm, at its exact position.
    #[test]
    fn not_finite_hidden_in_a_block_is_reported() {
        let mut rng = SplitMix64::new(21);
        let (a, g) = (points(&mut rng, 300), points(&mut rng, 300));
        let mut c = CostMatrix::new(0, 0);
        for bad in [f64::NAN, f64::NEG_INFINITY] {
            for (row, col) in [(0usize, 3usize), (150, 151), (299, 297)] {
                SquaredDistance.fill(&a, &g, &mut c);
                let mut s = Solver::with_strategy(Algo::Sparse);
                s.solve(&c).unwrap();
                // The other lanes of the block are far above any candidate threshold.
                for e in &mut c.row_mut(row)[col & !7..((col & !7) + 8).min(300)] {
                    *e = 1e6;
                }
                c.set(row, col, bad);
                assert_eq!(
                    s.solve_warm(&c),
                    Err(AssignError::NotFinite { row, col }),
                    "warm {bad} at ({row}, {col})"
                );
                assert_eq!(
                    s.solve(&c),
                    Err(AssignError::NotFinite { row, col }),
                    "cold {bad} at ({row}, {col})"
                );
            }
        }
    }

    /// `+inf` is a legitimate "unreachable" cost in large (sparse) problems too, and an
    /// all-`+inf` row names its agent.
    #[test]
    fn unreachable_goals_in_a_large_problem() {
        let mut rng = SplitMix64::new(22);
        let (a, g) = (points(&mut rng, 300), points(&mut rng, 320));
        let mut c = CostMatrix::new(0, 0);
        SquaredDistance.fill(&a, &g, &mut c);
        for (i, j) in (0..300).map(|i| (i, (i * 7) % 320)) {
            c.set(i, j, f64::INFINITY);
        }
        let mut s = Solver::with_strategy(Algo::Sparse);
        s.solve(&c).unwrap();
        assert!(s.verify_optimal(&c, 1e-9));
        assert!(s
            .assignment()
            .iter()
            .enumerate()
            .all(|(i, &j)| c.get(i, j).is_finite()));
        c.row_mut(123).fill(f64::INFINITY);
        assert_eq!(s.solve_warm(&c), Err(AssignError::Infeasible { row: 123 }));
        assert_eq!(s.solve(&c), Err(AssignError::Infeasible { row: 123 }));
    }

    #[test]
    fn infinite_entries_are_avoided() {
        // The only finite assignment is the anti-diagonal.
        let c = CostMatrix::from_fn(4, 4, |i, j| if i + j == 3 { 100.0 } else { f64::INFINITY });
        for mut s in solvers() {
            assert_eq!(s.solve(&c).unwrap(), &[3, 2, 1, 0]);
            assert_eq!(s.total_cost(&c), 400.0);
        }
    }

    #[test]
    fn repeated_same_size_solves_keep_buffers() {
        let mut rng = SplitMix64::new(9);
        let mut c = CostMatrix::new(0, 0);
        for (strategy, cols) in [(Algo::Dense, 300), (Algo::Sparse, 300), (Algo::Sparse, 350)] {
            let (mut a, g) = (points(&mut rng, 300), points(&mut rng, cols));
            let mut s = Solver::with_strategy(strategy);
            SquaredDistance.fill(&a, &g, &mut c);
            s.solve(&c).unwrap();
            let fp = s.buffer_fingerprint();
            for frame in 0..6 {
                for p in &mut a {
                    p.x += 0.01 * (rng.unit() - 0.5);
                }
                SquaredDistance.fill(&a, &g, &mut c);
                if frame % 2 == 0 {
                    s.solve_warm(&c).unwrap();
                } else {
                    s.solve(&c).unwrap();
                }
                assert_eq!(fp, s.buffer_fingerprint(), "{strategy:?} frame {frame}");
            }
        }
    }

    #[test]
    fn providers_fill_expected_costs() {
        let agents = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)];
        let goals = [
            Vec2::new(3.0, 4.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        let mut c = CostMatrix::new(5, 5);
        SquaredDistance.fill(&agents, &goals, &mut c);
        assert_eq!((c.rows(), c.cols()), (2, 3));
        assert_eq!(c.row(0), &[25.0, 2.0, 1.0]);
        Distance.fill(&agents, &goals, &mut c);
        assert!((c.get(0, 0) - 5.0).abs() < 1e-12);
        assert!((c.get(0, 1) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(c.get(1, 1), 0.0);
        let mut s = Solver::new();
        assert_eq!(s.solve(&c).unwrap(), &[2, 1]);
    }

    #[test]
    fn default_solver_is_new() {
        let c = CostMatrix::from_fn(200, 200, |i, j| ((i * 31 + j * 17) % 97) as f64);
        let mut a = Solver::default();
        a.solve(&c).unwrap();
        assert_eq!(a.strategy(), Algo::Auto);
        assert!(!a.stats().dense_finish);
        assert!(a.verify_optimal(&c, 1e-9));
    }

    #[test]
    fn warm_with_changed_dimensions_is_cold() {
        let mut s = Solver::new();
        let c = CostMatrix::from_fn(3, 3, |i, j| ((i * 7 + j * 3) % 5) as f64);
        s.solve(&c).unwrap();
        let c2 = CostMatrix::from_fn(3, 4, |i, j| ((i * 5 + j * 3) % 7) as f64);
        s.solve_warm(&c2).unwrap();
        assert!(!s.stats().warm);
        assert_eq!(brute_force(&c2), Some(s.total_cost(&c2)));
        s.solve_warm(&c2).unwrap();
        assert!(s.stats().warm);
        assert_eq!(s.stats().kept_rows, 3);
    }
}
