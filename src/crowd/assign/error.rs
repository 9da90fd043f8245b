//! Why an assignment could not be computed.

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
    /// The caller's [`Cancel`](super::Cancel) check said the solve is no longer
    /// wanted; nothing was assigned, and the next warm solve starts cold.
    #[error("assignment cancelled: its input is stale or the daemon is stopping")]
    Cancelled,
}
