//! Where the solver reads its costs: the [`CostSource`] trait and its two
//! implementations, a dense [`CostMatrix`] (filled from positions by a [`CostProvider`]:
//! [`SquaredDistance`], [`Distance`]) and [`PointCosts`], which compute each entry from
//! the positions when it is needed.

use super::error::AssignError;
use super::points::{PointCosts, PointMetric};
use crate::geom::Vec2;

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
/// Euclidean metric of its reference \[7\]; squaring favours even travel lengths).
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

/// Where the solver reads its costs: a [`CostMatrix`], or [`PointCosts`] that
/// compute each entry from positions when it is needed (no `rows × cols` matrix in
/// memory, and a full row costs a pass over the goals, which stay in cache, instead
/// of a pass over a matrix that does not).
///
/// Entries must not be NaN or `-inf` (a solve reports them as
/// [`AssignError::NotFinite`]); `+inf` is an unreachable pair.
pub trait CostSource {
    /// Number of rows (agents).
    fn rows(&self) -> usize;
    /// Number of columns (goals).
    fn cols(&self) -> usize;
    /// Entry `(i, j)`.
    fn get(&self, i: usize, j: usize) -> f64;
    /// Row `i`: borrowed from the source, or computed into `buf` (resized to
    /// [`CostSource::cols`]; no allocation when its capacity suffices).
    fn row<'a>(&'a self, i: usize, buf: &'a mut Vec<f64>) -> &'a [f64];
    /// The positions behind the costs, when the source has them: the solver then
    /// finds each row's cheapest columns through their spatial index instead of a
    /// pass over the row.
    fn points(&self) -> Option<&PointCosts> {
        None
    }
    /// Checks the source before a solve (a matrix is checked during the first pass).
    ///
    /// # Errors
    /// [`AssignError::NotFinite`].
    fn validate(&self) -> Result<(), AssignError> {
        Ok(())
    }
}

impl CostSource for CostMatrix {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.cols + j]
    }
    #[inline]
    fn row<'a>(&'a self, i: usize, _buf: &'a mut Vec<f64>) -> &'a [f64] {
        &self.data[i * self.cols..(i + 1) * self.cols]
    }
}

impl CostSource for PointCosts {
    fn rows(&self) -> usize {
        self.ax.len()
    }
    fn cols(&self) -> usize {
        self.gx.len()
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        let (dx, dy) = (self.ax[i] - self.gx[j], self.ay[i] - self.gy[j]);
        let d2 = dx * dx + dy * dy;
        match self.metric {
            PointMetric::Squared => d2,
            PointMetric::Euclidean => d2.sqrt(),
        }
    }
    fn points(&self) -> Option<&PointCosts> {
        Some(self)
    }
    fn validate(&self) -> Result<(), AssignError> {
        if self.finite {
            return Ok(());
        }
        let bad =
            |x: &[f64], y: &[f64]| (0..x.len()).find(|&k| !(x[k].is_finite() && y[k].is_finite()));
        if let Some(row) = bad(&self.ax, &self.ay) {
            return Err(AssignError::NotFinite { row, col: 0 });
        }
        let col = bad(&self.gx, &self.gy).unwrap_or(0);
        Err(AssignError::NotFinite { row: 0, col })
    }
    fn row<'a>(&'a self, i: usize, buf: &'a mut Vec<f64>) -> &'a [f64] {
        let (ax, ay) = (self.ax[i], self.ay[i]);
        buf.resize(self.gx.len(), 0.0);
        let it = buf.iter_mut().zip(self.gx.iter().zip(&self.gy));
        match self.metric {
            PointMetric::Squared => {
                for (o, (&gx, &gy)) in it {
                    let (dx, dy) = (ax - gx, ay - gy);
                    *o = dx * dx + dy * dy;
                }
            }
            PointMetric::Euclidean => {
                for (o, (&gx, &gy)) in it {
                    let (dx, dy) = (ax - gx, ay - gy);
                    *o = (dx * dx + dy * dy).sqrt();
                }
            }
        }
        buf
    }
}
