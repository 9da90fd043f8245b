//! Exact one-to-one assignment of agents (rows) to goal points (columns).
//!
//! The control thread assigns every agent to one goal point of the formation each
//! frame, minimising the total cost. This is the transportation problem of
//! mesh-formation-control section 6.1 (eq. 2) with unit supply and demand weights,
//! i.e. the linear assignment problem
//!
//! ```text
//!   minimise   sum_i c[i][sigma(i)]     over injections sigma: rows -> cols (rows <= cols)
//! ```
//!
//! # Algorithm
//!
//! A shortest-augmenting-path (SAP) solver with dual prices, in the Jonker–Volgenant
//! family, with two ways of searching for augmenting paths:
//!
//! * **Dense** ([`Strategy::Dense`]): each free row runs a Dijkstra search over the full
//!   reduced-cost matrix (`c[i][j] - u[i] - v[j] >= 0`), scanning whole contiguous rows.
//!   `O(rows * cols)` per scanned row; used for small problems and as the exact fallback.
//! * **Sparse with pricing** ([`Strategy::Sparse`], the default for large problems): one
//!   streaming pass over the matrix keeps, per row, the `k` columns of smallest reduced
//!   cost `c[i][j] - v[j]` (plus each column's cheapest row, so no column is orphaned).
//!   Augmenting paths are searched on that candidate graph with a binary heap. A pricing
//!   pass then re-checks, against the *full* rows, every row whose dual changed; rows
//!   that are no longer tight are freed, their candidate lists rebuilt, and re-augmented.
//!   Because Dijkstra only ever lowers column prices, a row whose matched column was
//!   not touched cannot become violated, so later pricing passes only touch the rows
//!   the searches went through. When no row is violated the full dual certificate
//!   holds and the assignment is optimal. A bounded number of rounds, after which
//!   (or after a search that finds no path in the candidate graph) the solver re-prices
//!   everything and finishes densely, keeps it exact in every case.
//!
//! Warm start ([`Solver::solve_warm`]) keeps the column prices `v` and the assignment of
//! the previous frame, re-prices every row against the new costs, keeps the pairs that
//! are still tight and re-augments only the freed rows.
//!
//! Rectangular problems (rows < cols) are exact: every column price starts at 0 and is
//! only lowered, except that a column freed by a warm start or a pricing pass is raised
//! back to 0 (re-checking the rows it could now undercut), so at every augmentation all
//! free columns have the maximal price — the dual condition of unassigned columns.
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

use crate::geom::Vec2;

/// Relative tolerance of the tightness and dual-feasibility tests.
///
/// A matched pair counts as tight, and an edge as dual-feasible, when its reduced cost
/// is at least `-EPS_REL * scale`, where `scale` is the largest magnitude among the
/// finite costs and the column prices. The returned assignment is therefore optimal to
/// within about `rows * EPS_REL * scale` of total cost (rounding level).
pub const EPS_REL: f64 = 1e-12;

/// Default number of cheapest candidate columns kept per row by [`Strategy::Sparse`].
pub const DEFAULT_CANDIDATES: usize = 10;

/// Slots per row for extra candidate edges (column coverage, rectangular repairs).
const EXTRA_SLOTS: usize = 6;

/// Pricing rounds of the sparse strategy before it finishes densely.
const MAX_ROUNDS: u32 = 16;

/// [`Strategy::Auto`] solves densely up to this many columns.
const AUTO_DENSE_MAX_COLS: usize = 128;

/// Width of the blocks the streaming row scans test at once.
const LANES: usize = 8;

/// "No row / no column" in the matching arrays.
const NONE: usize = usize::MAX;
/// "No row" in compact `u32` arrays.
const NO_ROW: u32 = u32::MAX;
/// "Not in the heap".
const ABSENT: u32 = u32::MAX;

// ---------------------------------------------------------------------------------
// Cost matrix and providers
// ---------------------------------------------------------------------------------

/// Dense row-major cost matrix: rows are agents, columns are goals, `rows <= cols`.
///
/// Entries are costs in the caller's unit (m² for [`SquaredDistance`], m for
/// [`Distance`]). `+inf` marks an unreachable goal; NaN and `-inf` are rejected by the
/// solver.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CostMatrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl CostMatrix {
    /// A zero-filled `rows × cols` matrix.
    ///
    /// # Panics
    /// If `rows * cols` overflows `usize` or cannot be allocated.
    pub fn new(rows: usize, cols: usize) -> CostMatrix {
        CostMatrix {
            rows,
            cols,
            data: vec![0.0; rows.checked_mul(cols).expect("cost matrix size overflow")],
        }
    }

    /// A `rows × cols` matrix with entry `(r, c)` set to `f(r, c)`.
    ///
    /// # Panics
    /// As [`CostMatrix::new`].
    pub fn from_fn(rows: usize, cols: usize, mut f: impl FnMut(usize, usize) -> f64) -> CostMatrix {
        let mut m = CostMatrix::new(rows, cols);
        for r in 0..rows {
            for (c, e) in m.row_mut(r).iter_mut().enumerate() {
                *e = f(r, c);
            }
        }
        m
    }

    /// Changes the dimensions, keeping the allocation when it is large enough.
    /// The contents afterwards are unspecified (callers refill every entry).
    ///
    /// # Panics
    /// As [`CostMatrix::new`].
    pub fn resize(&mut self, rows: usize, cols: usize) {
        let n = rows.checked_mul(cols).expect("cost matrix size overflow");
        self.data.resize(n, 0.0);
        self.rows = rows;
        self.cols = cols;
    }

    /// Number of rows (agents).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns (goals).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Entry `(r, c)`.
    ///
    /// # Panics
    /// If `r >= rows()` or `c >= cols()`.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        assert!(c < self.cols, "column {c} out of range");
        self.data[r * self.cols + c]
    }

    /// Sets entry `(r, c)`.
    ///
    /// # Panics
    /// If `r >= rows()` or `c >= cols()`.
    pub fn set(&mut self, r: usize, c: usize, v: f64) {
        assert!(c < self.cols, "column {c} out of range");
        self.data[r * self.cols + c] = v;
    }

    /// Row `r` as a slice of `cols()` entries.
    ///
    /// # Panics
    /// If `r >= rows()`.
    pub fn row(&self, r: usize) -> &[f64] {
        &self.data[r * self.cols..(r + 1) * self.cols]
    }

    /// Row `r` as a mutable slice of `cols()` entries.
    ///
    /// # Panics
    /// If `r >= rows()`.
    pub fn row_mut(&mut self, r: usize) -> &mut [f64] {
        &mut self.data[r * self.cols..(r + 1) * self.cols]
    }

    /// All entries, row-major.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }
}

/// Fills a cost matrix from agent and goal positions.
///
/// Implementations resize `out` to `agents.len() × goals.len()` and write every entry;
/// they must not produce NaN or `-inf` (use `+inf` for unreachable goals).
pub trait CostProvider {
    /// Writes `out[i][j]` = cost of sending agent `i` to goal `j`.
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix);
}

/// Squared Euclidean distance cost, `|a - g|²` in m².
///
/// # Formula
/// `c_ij = (a_i - g_j)·(a_i - g_j)` (mesh-formation-control section 6.1 with the
/// Euclidean metric of its reference [7]; squaring favours even travel lengths).
///
/// # Complexity
/// `O(agents * goals)`, no allocation when `out` is already large enough.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct SquaredDistance;

/// Euclidean distance cost, `|a - g|` in metres.
///
/// # Formula
/// `c_ij = |a_i - g_j|` (mesh-formation-control section 6.1, Euclidean metric).
///
/// # Complexity
/// `O(agents * goals)`, no allocation when `out` is already large enough.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct Distance;

impl CostProvider for SquaredDistance {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {
        out.resize(agents.len(), goals.len());
        for (r, a) in agents.iter().enumerate() {
            for (e, g) in out.row_mut(r).iter_mut().zip(goals) {
                let (dx, dy) = (a.x - g.x, a.y - g.y);
                *e = dx * dx + dy * dy;
            }
        }
    }
}

impl CostProvider for Distance {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {
        out.resize(agents.len(), goals.len());
        for (r, a) in agents.iter().enumerate() {
            for (e, g) in out.row_mut(r).iter_mut().zip(goals) {
                let (dx, dy) = (a.x - g.x, a.y - g.y);
                *e = (dx * dx + dy * dy).sqrt();
            }
        }
    }
}

// ---------------------------------------------------------------------------------
// Errors, options, statistics
// ---------------------------------------------------------------------------------

/// Why an assignment could not be computed.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum AssignError {
    /// The matrix has no rows.
    #[error("assignment problem has no rows")]
    Empty,
    /// More agents than goals: a one-to-one assignment of every row is impossible.
    #[error("assignment problem has more rows ({rows}) than columns ({cols})")]
    MoreRowsThanCols {
        /// Number of rows (agents).
        rows: usize,
        /// Number of columns (goals).
        cols: usize,
    },
    /// An entry is NaN or `-inf` (the first one in row-major order).
    #[error("cost ({row}, {col}) is NaN or -inf")]
    NotFinite {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// No complete assignment with finite cost exists. `row` is the first row found
    /// that cannot be served: the lowest-index all-`+inf` row if there is one,
    /// otherwise the row whose augmenting path search failed.
    #[error("no assignment with finite cost exists: row {row} cannot be served")]
    Infeasible {
        /// The row that cannot be served.
        row: usize,
    },
}

/// How [`Solver`] searches for augmenting paths. All strategies return an optimal
/// assignment; they differ only in speed.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Dense for small problems (at most 128 columns), sparse with pricing otherwise.
    #[default]
    Auto,
    /// Dijkstra over full rows (classic dense shortest augmenting path).
    Dense,
    /// Dijkstra over per-row candidate lists, with full-row pricing passes and a dense
    /// finish if the candidate graph is insufficient.
    Sparse,
}

/// Work counters of the last solve (for benchmarks and tuning; not part of the result).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Whether the previous duals and assignment were reused.
    pub warm: bool,
    /// Rows still assigned after the first pricing pass of a warm start.
    pub kept_rows: usize,
    /// Full-row pricing checks (one per row per pass).
    pub rows_priced: u64,
    /// Sparse pricing rounds.
    pub rounds: u32,
    /// Augmenting path searches.
    pub augmentations: u64,
    /// Rows scanned inside the searches.
    pub rows_scanned: u64,
    /// Whether the dense finish was needed.
    pub dense_finish: bool,
}

// ---------------------------------------------------------------------------------
// Indexed binary min-heap over columns
// ---------------------------------------------------------------------------------

/// Binary min-heap of columns keyed by tentative distance, with decrease-key.
/// Capacity is reserved for every column, so it never allocates after sizing.
#[derive(Clone, Debug, Default)]
struct ColHeap {
    key: Vec<f64>,
    col: Vec<u32>,
    pos: Vec<u32>,
}

impl ColHeap {
    fn size_for(&mut self, cols: usize) {
        self.key = Vec::with_capacity(cols);
        self.col = Vec::with_capacity(cols);
        self.pos.clear();
        self.pos.resize(cols, ABSENT);
    }

    fn clear(&mut self) {
        for &c in &self.col {
            self.pos[c as usize] = ABSENT;
        }
        self.key.clear();
        self.col.clear();
    }

    #[inline]
    fn push_or_decrease(&mut self, c: u32, k: f64) {
        let p = self.pos[c as usize];
        let at = if p == ABSENT {
            self.key.push(k);
            self.col.push(c);
            self.key.len() - 1
        } else {
            p as usize
        };
        self.sift_up(at, c, k);
    }

    #[inline]
    fn sift_up(&mut self, mut at: usize, c: u32, k: f64) {
        while at > 0 {
            let parent = (at - 1) / 2;
            let pk = self.key[parent];
            if pk <= k {
                break;
            }
            let pc = self.col[parent];
            self.key[at] = pk;
            self.col[at] = pc;
            self.pos[pc as usize] = at as u32;
            at = parent;
        }
        self.key[at] = k;
        self.col[at] = c;
        self.pos[c as usize] = at as u32;
    }

    #[inline]
    fn pop(&mut self) -> Option<(f64, u32)> {
        let top_k = *self.key.first()?;
        let top_c = self.col[0];
        self.pos[top_c as usize] = ABSENT;
        let (lk, lc) = match (self.key.pop(), self.col.pop()) {
            (Some(k), Some(c)) => (k, c),
            _ => return Some((top_k, top_c)),
        };
        if !self.key.is_empty() {
            let n = self.key.len();
            let mut at = 0;
            loop {
                let l = 2 * at + 1;
                if l >= n {
                    break;
                }
                let r = l + 1;
                let m = if r < n && self.key[r] < self.key[l] { r } else { l };
                let mk = self.key[m];
                if mk >= lk {
                    break;
                }
                let mc = self.col[m];
                self.key[at] = mk;
                self.col[at] = mc;
                self.pos[mc as usize] = at as u32;
                at = m;
            }
            self.key[at] = lk;
            self.col[at] = lc;
            self.pos[lc as usize] = at as u32;
        }
        Some((top_k, top_c))
    }
}

// ---------------------------------------------------------------------------------
// Row kernels
// ---------------------------------------------------------------------------------

/// Validates a row: index of the first NaN / `-inf`, the largest finite magnitude,
/// and whether any entry is finite.
fn validate_row(row: &[f64]) -> (Option<usize>, f64, bool) {
    let mut bad = false;
    let mut finite = false;
    let mut mx = [0.0f64; LANES];
    let chunks = row.chunks_exact(LANES);
    let tail = chunks.remainder();
    for ch in chunks {
        for (m, &c) in mx.iter_mut().zip(ch) {
            bad |= !(c > f64::NEG_INFINITY);
            finite |= c < f64::INFINITY;
            let a = if c < f64::INFINITY { c.abs() } else { 0.0 };
            *m = if a > *m { a } else { *m };
        }
    }
    for &c in tail {
        bad |= !(c > f64::NEG_INFINITY);
        finite |= c < f64::INFINITY;
        if c < f64::INFINITY && c.abs() > mx[0] {
            mx[0] = c.abs();
        }
    }
    let first_bad = if bad {
        row.iter().position(|&c| !(c > f64::NEG_INFINITY))
    } else {
        None
    };
    (first_bad, mx.iter().fold(0.0, |a: f64, &b| a.max(b)), finite)
}

/// Inserts `(w, c)` into the ascending list `ws[..len]` of capacity `k`, dropping the
/// largest entry when full.
#[inline]
fn topk_insert(ws: &mut [f64], cs: &mut [u32], len: &mut usize, k: usize, w: f64, c: u32) {
    let mut p = if *len < k {
        *len += 1;
        *len - 1
    } else {
        k - 1
    };
    while p > 0 && ws[p - 1] > w {
        ws[p] = ws[p - 1];
        cs[p] = cs[p - 1];
        p -= 1;
    }
    ws[p] = w;
    cs[p] = c;
}

/// The `ws.len()` smallest finite reduced costs `row[j] - v[j]` (ascending, ties to
/// the lower column) with their columns. Returns how many were found.
///
/// # Complexity
/// One streaming pass; blocks of [`LANES`] entries are tested against the current
/// threshold at once, so the selection work is only done for the few improving entries.
fn topk_row(row: &[f64], v: &[f64], ws: &mut [f64], cs: &mut [u32]) -> usize {
    let k = ws.len();
    let mut len = 0usize;
    let mut thr = f64::INFINITY;
    let rch = row.chunks_exact(LANES);
    let vch = v.chunks_exact(LANES);
    let (rt, vt) = (rch.remainder(), vch.remainder());
    let mut base = 0u32;
    for (r, vv) in rch.zip(vch) {
        let mut hit = false;
        for (a, b) in r.iter().zip(vv) {
            hit |= a - b < thr;
        }
        if hit {
            for (l, (a, b)) in r.iter().zip(vv).enumerate() {
                let w = a - b;
                if w < thr {
                    topk_insert(ws, cs, &mut len, k, w, base + l as u32);
                    if len == k {
                        thr = ws[k - 1];
                    }
                }
            }
        }
        base += LANES as u32;
    }
    for (l, (a, b)) in rt.iter().zip(vt).enumerate() {
        let w = a - b;
        if w < thr {
            topk_insert(ws, cs, &mut len, k, w, base + l as u32);
            if len == k {
                thr = ws[k - 1];
            }
        }
    }
    len
}

// ---------------------------------------------------------------------------------
// Solver
// ---------------------------------------------------------------------------------

/// Exact assignment solver with reusable workspaces, dual prices and warm start.
///
/// Workspaces are sized on the first solve and whenever the dimensions change; solving
/// again with the same dimensions does not allocate.
#[derive(Clone, Debug, Default)]
pub struct Solver {
    strategy: Strategy,
    /// Candidates per row (sparse strategy).
    k: usize,
    /// Candidate slots per row: `k` best + [`EXTRA_SLOTS`].
    cap: usize,
    rows: usize,
    cols: usize,
    /// Whether `x`, `u`, `v` hold a complete optimal solution of the last problem.
    solved: bool,
    /// Tolerance of the current solve (absolute).
    eps: f64,
    u: Vec<f64>,
    v: Vec<f64>,
    /// Row -> column.
    x: Vec<usize>,
    /// Column -> row.
    y: Vec<usize>,
    // Candidate graph, `cap` slots per row: `[0, len)` the k best, `[k, k + elen)` extras.
    cand_col: Vec<u32>,
    cand_cost: Vec<f64>,
    cand_len: Vec<u32>,
    extra_len: Vec<u32>,
    topw: Vec<f64>,
    col_best: Vec<f64>,
    col_best_row: Vec<u32>,
    // Search workspaces (per column).
    dist: Vec<f64>,
    pred: Vec<u32>,
    seen: Vec<u32>,
    done: Vec<u32>,
    epoch: u32,
    heap: ColHeap,
    scanned: Vec<u32>,
    dd: Vec<f64>,
    vm: Vec<f64>,
    // Row sets.
    free_rows: Vec<u32>,
    dirty: Vec<bool>,
    dirty_rows: Vec<u32>,
    raise: Vec<u32>,
    stats: SolveStats,
}

impl Solver {
    /// A solver with [`Strategy::Auto`] and [`DEFAULT_CANDIDATES`] candidates per row.
    pub fn new() -> Solver {
        Solver::with_strategy(Strategy::Auto)
    }

    /// A solver using `strategy`.
    pub fn with_strategy(strategy: Strategy) -> Solver {
        Solver::with_options(strategy, DEFAULT_CANDIDATES)
    }

    /// A solver using `strategy` that keeps `candidates` (at least 1) cheapest columns
    /// per row in the sparse strategy. Fewer candidates mean cheaper searches but more
    /// pricing rounds; the result is optimal either way.
    pub fn with_options(strategy: Strategy, candidates: usize) -> Solver {
        let k = candidates.max(1);
        Solver {
            strategy,
            k,
            cap: k + EXTRA_SLOTS,
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

    /// Cold solve: ignores any previous state. Returns row -> column.
    ///
    /// # Formula
    /// Minimises `sum_i c[i][sigma(i)]` over injections (mesh-formation-control section
    /// 6.1, eq. 2 with unit weights). On success the duals `u`, `v` satisfy
    /// `c[i][j] - u[i] - v[j] >= -eps` everywhere, `== 0` on assigned pairs, and
    /// unassigned columns carry the maximal `v` ([`Solver::verify_optimal`]).
    ///
    /// # Units
    /// Costs in any unit; indices only in the result.
    ///
    /// # Complexity
    /// Dense strategy `O(rows² · cols)` worst case. Sparse strategy: a few streaming
    /// passes over the matrix plus heap searches on `k`-sparse rows; on geometric
    /// instances roughly `O(rows · cols)` passes dominate. No allocation when the
    /// dimensions equal those of the previous call.
    ///
    /// # Errors
    /// [`AssignError::Empty`], [`AssignError::MoreRowsThanCols`],
    /// [`AssignError::NotFinite`] (first NaN/`-inf` in row-major order),
    /// [`AssignError::Infeasible`]. After an error [`Solver::assignment`] is empty and
    /// the next warm solve is cold.
    pub fn solve(&mut self, costs: &CostMatrix) -> Result<&[usize], AssignError> {
        self.check_dims(costs)?;
        self.size_for(costs.rows(), costs.cols());
        self.v.fill(0.0);
        self.x.fill(NONE);
        self.y.fill(NONE);
        self.stats = SolveStats::default();
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
        self.check_dims(costs)?;
        if !self.solved || costs.rows() != self.rows || costs.cols() != self.cols {
            return self.solve(costs);
        }
        // Keep the prices bounded over long runs: shift so that max v = 0 (all
        // reduced costs are unchanged; free columns of a rectangular problem are
        // already at the maximum, 0).
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
        self.finish(costs)
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
    pub fn total_cost(&self, costs: &CostMatrix) -> f64 {
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
    /// injection is cheaper by more than `rows * 2 * tol`.
    ///
    /// # Complexity
    /// `O(rows · cols)`, no allocation.
    pub fn verify_optimal(&self, costs: &CostMatrix, tol: f64) -> bool {
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
            for (c, vj) in costs.row(i).iter().zip(&self.v) {
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
    fn debug_tolerance(&self) -> f64 {
        let vmax = self.v.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        1e3 * EPS_REL * (self.eps / EPS_REL).max(vmax) + f64::MIN_POSITIVE
    }

    fn check_dims(&mut self, costs: &CostMatrix) -> Result<(), AssignError> {
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
        self.solved = false;
        self.rows = rows;
        self.cols = cols;
        self.u.resize(rows, 0.0);
        self.v.resize(cols, 0.0);
        self.x.resize(rows, NONE);
        self.y.resize(cols, NONE);
        self.cand_col.resize(rows * self.cap, 0);
        self.cand_cost.resize(rows * self.cap, 0.0);
        self.cand_len.resize(rows, 0);
        self.extra_len.resize(rows, 0);
        self.topw.resize(self.k, 0.0);
        self.col_best.resize(cols, f64::INFINITY);
        self.col_best_row.resize(cols, NO_ROW);
        self.dist.resize(cols, 0.0);
        self.pred.resize(cols, 0);
        self.seen.clear();
        self.seen.resize(cols, 0);
        self.done.clear();
        self.done.resize(cols, 0);
        self.epoch = 0;
        self.heap.size_for(cols);
        self.scanned = Vec::with_capacity(cols);
        self.dd.resize(cols, 0.0);
        self.vm.resize(cols, 0.0);
        self.free_rows = Vec::with_capacity(rows);
        self.dirty.clear();
        self.dirty.resize(rows, false);
        self.dirty_rows = Vec::with_capacity(rows);
        self.raise = Vec::with_capacity(rows + cols);
    }

    fn use_sparse(&self) -> bool {
        match self.strategy {
            Strategy::Dense => false,
            Strategy::Sparse => true,
            Strategy::Auto => self.cols > AUTO_DENSE_MAX_COLS,
        }
    }

    /// Common driver of cold and warm solves (state: prices `v`, partial matching).
    fn finish(&mut self, costs: &CostMatrix) -> Result<&[usize], AssignError> {
        self.solved = false;
        match self.run(costs) {
            Ok(()) => {
                for (i, &j) in self.x.iter().enumerate() {
                    self.u[i] = costs.get(i, j) - self.v[j];
                }
                self.solved = true;
                debug_assert!(
                    self.verify_optimal(costs, self.debug_tolerance()),
                    "assignment certificate failed"
                );
                Ok(&self.x)
            }
            Err(e) => {
                // Leave a consistent (cold) state behind.
                self.x.fill(NONE);
                self.y.fill(NONE);
                Err(e)
            }
        }
    }

    fn run(&mut self, costs: &CostMatrix) -> Result<(), AssignError> {
        self.validate(costs)?;
        let sparse = self.use_sparse();
        let warm = self.stats.warm;
        self.price_all(costs, sparse);
        if warm {
            self.stats.kept_rows = self.x.iter().filter(|&&j| j != NONE).count();
        }
        if sparse {
            loop {
                if self.free_rows.is_empty() {
                    return Ok(());
                }
                if self.stats.rounds == MAX_ROUNDS {
                    break;
                }
                self.stats.rounds += 1;
                let mut ok = true;
                for idx in 0..self.free_rows.len() {
                    let i = self.free_rows[idx] as usize;
                    if !self.sparse_augment(costs, i) {
                        ok = false;
                        break;
                    }
                }
                if !ok {
                    break;
                }
                self.price_dirty(costs);
            }
            // Dense finish: make the duals feasible on the whole matrix again, then
            // augment the remaining free rows over full rows.
            self.stats.dense_finish = true;
            for &i in &self.dirty_rows {
                self.dirty[i as usize] = false;
            }
            self.dirty_rows.clear();
            self.price_all(costs, false);
        }
        self.dense_all(costs)
    }

    /// Validation pass: NaN / -inf, all-+inf rows, tolerance scale.
    fn validate(&mut self, costs: &CostMatrix) -> Result<(), AssignError> {
        let mut scale = 0.0f64;
        let mut first_unservable = None;
        for i in 0..costs.rows() {
            let (bad, mx, finite) = validate_row(costs.row(i));
            if let Some(col) = bad {
                return Err(AssignError::NotFinite { row: i, col });
            }
            if !finite && first_unservable.is_none() {
                first_unservable = Some(i);
            }
            scale = scale.max(mx);
        }
        if let Some(row) = first_unservable {
            return Err(AssignError::Infeasible { row });
        }
        let vmax = self.v.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        self.eps = EPS_REL * scale.max(vmax);
        Ok(())
    }

    /// Pricing pass over every row: frees rows that are not tight, greedily assigns
    /// free rows whose cheapest column is free, collects the free rows, and (when
    /// `build`) rebuilds every candidate list plus the column-coverage extras.
    fn price_all(&mut self, costs: &CostMatrix, build: bool) {
        self.free_rows.clear();
        if build {
            self.col_best.fill(f64::INFINITY);
            self.col_best_row.fill(NO_ROW);
        }
        for i in 0..self.rows {
            self.price_row(costs, i, build);
            if build {
                let row = costs.row(i);
                for ((b, br), &c) in self.col_best.iter_mut().zip(&mut self.col_best_row).zip(row) {
                    let better = c < *b;
                    *b = if better { c } else { *b };
                    *br = if better { i as u32 } else { *br };
                }
            }
        }
        self.stats.rows_priced += self.rows as u64;
        if build {
            self.extra_len.fill(0);
            for j in 0..self.cols {
                let r = self.col_best_row[j];
                if r == NO_ROW {
                    continue;
                }
                let r = r as usize;
                let e = self.extra_len[r] as usize;
                if e < EXTRA_SLOTS {
                    let s = r * self.cap + self.k + e;
                    self.cand_col[s] = j as u32;
                    self.cand_cost[s] = self.col_best[j];
                    self.extra_len[r] += 1;
                }
            }
        }
        self.raise_free_columns(costs);
    }

    /// Pricing pass over the rows whose duals changed since they were last priced.
    fn price_dirty(&mut self, costs: &CostMatrix) {
        self.free_rows.clear();
        for idx in 0..self.dirty_rows.len() {
            let i = self.dirty_rows[idx] as usize;
            self.dirty[i] = false;
            self.price_row(costs, i, true);
        }
        self.stats.rows_priced += self.dirty_rows.len() as u64;
        self.dirty_rows.clear();
        self.raise_free_columns(costs);
    }

    /// Prices row `i` against the full row: keeps it if its pair is tight, else frees
    /// it; a free row takes its cheapest column if that column is free. With `build`,
    /// the row's candidate list becomes its `k` cheapest reduced costs.
    fn price_row(&mut self, costs: &CostMatrix, i: usize, build: bool) {
        let row = costs.row(i);
        let (min_w, arg) = if build {
            let base = i * self.cap;
            let k = self.k;
            let cs = &mut self.cand_col[base..base + k];
            let len = topk_row(row, &self.v, &mut self.topw, cs);
            for (cc, &c) in self.cand_cost[base..base + len].iter_mut().zip(cs.iter()) {
                *cc = row[c as usize];
            }
            self.cand_len[i] = len as u32;
            if len == 0 {
                (f64::INFINITY, NONE)
            } else {
                (self.topw[0], cs[0] as usize)
            }
        } else {
            let mut best = f64::INFINITY;
            let mut arg = NONE;
            for (j, (c, vj)) in row.iter().zip(&self.v).enumerate() {
                let w = c - vj;
                if w < best {
                    best = w;
                    arg = j;
                }
            }
            (best, arg)
        };
        let xi = self.x[i];
        if xi != NONE {
            let wx = row[xi] - self.v[xi];
            if wx <= min_w + self.eps {
                return;
            }
            self.x[i] = NONE;
            self.y[xi] = NONE;
            if self.rows < self.cols {
                self.raise.push(xi as u32);
            }
        }
        if arg != NONE && self.y[arg] == NONE {
            self.x[i] = arg;
            self.y[arg] = i;
        } else {
            self.free_rows.push(i as u32);
        }
    }

    /// Rectangular problems only: raises the price of every freed column back to the
    /// maximum (0) and frees the assigned rows this makes non-tight, transitively.
    fn raise_free_columns(&mut self, costs: &CostMatrix) {
        while let Some(j) = self.raise.pop() {
            let j = j as usize;
            if self.y[j] != NONE || self.v[j] >= 0.0 {
                continue;
            }
            self.v[j] = 0.0;
            for r in 0..self.rows {
                let xr = self.x[r];
                if xr == NONE {
                    continue;
                }
                let c = costs.get(r, j);
                if c < costs.get(r, xr) - self.v[xr] - self.eps {
                    self.x[r] = NONE;
                    self.y[xr] = NONE;
                    self.raise.push(xr as u32);
                    self.free_rows.push(r as u32);
                    // Let the row see the column that undercut it.
                    let e = self.extra_len[r] as usize;
                    if e < EXTRA_SLOTS {
                        let s = r * self.cap + self.k + e;
                        self.cand_col[s] = j as u32;
                        self.cand_cost[s] = c;
                        self.extra_len[r] += 1;
                    }
                }
            }
        }
    }

    fn next_epoch(&mut self) -> u32 {
        if self.epoch == u32::MAX {
            self.seen.fill(0);
            self.done.fill(0);
            self.epoch = 0;
        }
        self.epoch += 1;
        self.epoch
    }

    #[inline]
    fn mark_dirty(&mut self, i: usize) {
        if !self.dirty[i] {
            self.dirty[i] = true;
            self.dirty_rows.push(i as u32);
        }
    }

    /// Dijkstra on the candidate graph from free row `i0`; on success updates the
    /// prices of the settled columns, flips the path, and returns true.
    fn sparse_augment(&mut self, costs: &CostMatrix, i0: usize) -> bool {
        let ep = self.next_epoch();
        self.stats.augmentations += 1;
        self.heap.clear();
        self.scanned.clear();
        self.relax(i0, 0.0, ep);
        let (dstar, sink) = loop {
            let Some((dk, j)) = self.heap.pop() else {
                return false;
            };
            let j = j as usize;
            self.done[j] = ep;
            self.scanned.push(j as u32);
            let i = self.y[j];
            if i == NONE {
                break (dk, j);
            }
            self.stats.rows_scanned += 1;
            self.mark_dirty(i);
            let off = dk - (costs.get(i, j) - self.v[j]);
            self.relax(i, off, ep);
        };
        for &k in &self.scanned {
            let k = k as usize;
            self.v[k] += self.dist[k] - dstar;
        }
        self.flip_path(sink, i0);
        self.mark_dirty(i0);
        true
    }

    /// Relaxes the candidate edges of row `i` with distance offset `off`.
    #[inline]
    fn relax(&mut self, i: usize, off: f64, ep: u32) {
        let base = i * self.cap;
        let len = self.cand_len[i] as usize;
        let elen = self.extra_len[i] as usize;
        let ranges = [(base, base + len), (base + self.k, base + self.k + elen)];
        for (lo, hi) in ranges {
            for (&k, &c) in self.cand_col[lo..hi].iter().zip(&self.cand_cost[lo..hi]) {
                let ku = k as usize;
                if self.done[ku] == ep {
                    continue;
                }
                let nd = off + (c - self.v[ku]);
                if self.seen[ku] != ep || nd < self.dist[ku] {
                    self.seen[ku] = ep;
                    self.dist[ku] = nd;
                    self.pred[ku] = i as u32;
                    self.heap.push_or_decrease(k, nd);
                }
            }
        }
    }

    /// Flips the alternating path ending at free column `sink` back to row `i0`.
    fn flip_path(&mut self, sink: usize, i0: usize) {
        let mut j = sink;
        loop {
            let i = self.pred[j] as usize;
            let prev = self.x[i];
            self.y[j] = i;
            self.x[i] = j;
            if i == i0 {
                break;
            }
            j = prev;
        }
    }

    /// Dense augmentation of every free row, in index order.
    fn dense_all(&mut self, costs: &CostMatrix) -> Result<(), AssignError> {
        self.free_rows.sort_unstable();
        for idx in 0..self.free_rows.len() {
            let i = self.free_rows[idx] as usize;
            if !self.dense_augment(costs, i) {
                return Err(AssignError::Infeasible { row: i });
            }
        }
        self.free_rows.clear();
        Ok(())
    }

    /// Dijkstra over full rows from free row `i0` (requires dual feasibility on the
    /// whole matrix). Settled columns get `d = +inf` and a masked price of `-inf`, so
    /// the relaxation loop runs branch-free over all columns and never touches them.
    fn dense_augment(&mut self, costs: &CostMatrix, i0: usize) -> bool {
        self.stats.augmentations += 1;
        self.scanned.clear();
        let row0 = costs.row(i0);
        for (((d, vm), p), (&c, &vj)) in self
            .dd
            .iter_mut()
            .zip(&mut self.vm)
            .zip(&mut self.pred)
            .zip(row0.iter().zip(&self.v))
        {
            *vm = vj;
            *d = c - vj;
            *p = i0 as u32;
        }
        let (dstar, sink) = loop {
            let mut best = f64::INFINITY;
            let mut bj = NONE;
            for (j, &d) in self.dd.iter().enumerate() {
                if d < best {
                    best = d;
                    bj = j;
                }
            }
            if bj == NONE {
                return false;
            }
            self.dist[bj] = best;
            self.dd[bj] = f64::INFINITY;
            self.vm[bj] = f64::NEG_INFINITY;
            self.scanned.push(bj as u32);
            let i = self.y[bj];
            if i == NONE {
                break (best, bj);
            }
            self.stats.rows_scanned += 1;
            let row = costs.row(i);
            let off = best - (row[bj] - self.v[bj]);
            let iu = i as u32;
            for ((d, p), (&c, &vm)) in self
                .dd
                .iter_mut()
                .zip(&mut self.pred)
                .zip(row.iter().zip(&self.vm))
            {
                let h = c - vm + off;
                if h < *d {
                    *d = h;
                    *p = iu;
                }
            }
        };
        for &k in &self.scanned {
            let k = k as usize;
            self.v[k] += self.dist[k] - dstar;
        }
        self.flip_path(sink, i0);
        true
    }

    /// Identity of every internal buffer (pointer, capacity), to check that repeated
    /// same-size solves do not reallocate.
    #[cfg(test)]
    fn buffer_fingerprint(&self) -> Vec<(usize, usize)> {
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
            f(&self.cand_len),
            f(&self.extra_len),
            f(&self.topw),
            f(&self.col_best),
            f(&self.col_best_row),
            f(&self.dist),
            f(&self.pred),
            f(&self.seen),
            f(&self.done),
            f(&self.heap.key),
            f(&self.heap.col),
            f(&self.heap.pos),
            f(&self.scanned),
            f(&self.dd),
            f(&self.vm),
            f(&self.free_rows),
            f(&self.dirty),
            f(&self.dirty_rows),
            f(&self.raise),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::Strategy as Algo;
    use super::*;
    use proptest::prelude::{prop_assert, prop_oneof, proptest, Just, TestCaseError};
    use proptest::strategy::Strategy as _;
    use proptest::test_runner::{Config as ProptestConfig, RngSeed};

    /// Small deterministic PRNG (splitmix64) for the larger instances.
    struct SplitMix(u64);
    impl SplitMix {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn unit(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        }
    }

    fn points(rng: &mut SplitMix, n: usize) -> Vec<Vec2> {
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

    fn check_against_brute(s: &mut Solver, c: &CostMatrix, warm: bool) -> Result<(), TestCaseError> {
        let want = brute_force(c).expect("instances are feasible by construction");
        let res = if warm { s.solve_warm(c).map(|_| ()) } else { s.solve(c).map(|_| ()) };
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

    fn run_chain(rows: usize, cols: usize, seed: u64, strategy: Algo) {
        let mut rng = SplitMix(seed);
        let mut agents = points(&mut rng, rows);
        let mut goals = points(&mut rng, cols);
        let mut c = CostMatrix::new(0, 0);
        let mut s = Solver::with_strategy(strategy);
        SquaredDistance.fill(&agents, &goals, &mut c);
        s.solve(&c).unwrap();
        assert!(s.verify_optimal(&c, 1e-9), "cold {rows}x{cols} {strategy:?}");
        let mut cold = Solver::with_strategy(Algo::Dense);
        for frame in 0..20 {
            for p in goals.iter_mut().chain(agents.iter_mut().take(rows / 10)) {
                p.x += 0.04 * (rng.unit() - 0.5);
                p.y += 0.04 * (rng.unit() - 0.5);
            }
            SquaredDistance.fill(&agents, &goals, &mut c);
            s.solve_warm(&c).unwrap();
            assert!(s.stats().warm);
            assert!(s.verify_optimal(&c, 1e-9), "warm frame {frame} {rows}x{cols} {strategy:?}");
            if frame % 5 == 0 {
                cold.solve(&c).unwrap();
                assert!(cold.verify_optimal(&c, 1e-9));
                let (a, b) = (s.total_cost(&c), cold.total_cost(&c));
                assert!((a - b).abs() < 1e-9, "frame {frame}: warm {a} cold {b}");
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
        let mut rng = SplitMix(5);
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
            let mut rng = SplitMix(seed);
            let ints: Vec<i64> = (0..rows * cols).map(|_| (rng.next_u64() % 100) as i64).collect();
            let c = CostMatrix::from_fn(rows, cols, |i, j| ints[i * cols + j] as f64);
            let neg = Matrix::from_vec(rows, cols, ints.iter().map(|&x| -x).collect()).unwrap();
            let (best, _) = kuhn_munkres(&neg);
            for mut s in solvers() {
                s.solve(&c).unwrap();
                assert_eq!(s.total_cost(&c), -best as f64, "{:?}", s.strategy());
                assert!(s.verify_optimal(&c, 0.0));
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
            assert_eq!(s.solve_warm(&c), Err(AssignError::NotFinite { row: 2, col: 0 }));
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
        let mut rng = SplitMix(9);
        let (mut a, g) = (points(&mut rng, 300), points(&mut rng, 300));
        let mut c = CostMatrix::new(0, 0);
        for strategy in [Algo::Dense, Algo::Sparse] {
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
        let goals = [Vec2::new(3.0, 4.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
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
