//! Why a field or a cost could not be computed.

/// Why a field or a cost could not be computed.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum EikonalError {
    /// The grid has no cells, too many cells, or a cell size or origin that is not
    /// finite and positive.
    #[error("invalid grid: {cols}×{rows} cells")]
    InvalidGrid {
        /// Columns requested.
        cols: usize,
        /// Rows requested.
        rows: usize,
    },
    /// A per-cell slice does not have one entry per cell.
    #[error("{what} has {got} entries, the grid has {expected} cells")]
    SizeMismatch {
        /// Which input.
        what: &'static str,
        /// Number of cells of the grid.
        expected: usize,
        /// Number of entries given.
        got: usize,
    },
    /// A cell cost is NaN.
    #[error("cost of cell {cell} is NaN")]
    CostNan {
        /// Index of the first offending cell.
        cell: usize,
    },
    /// A cell cost is zero or negative (costs are positive; `+inf` blocks the cell).
    #[error("cost of cell {cell} is not positive")]
    CostNotPositive {
        /// Index of the first offending cell.
        cell: usize,
    },
    /// No source was given.
    #[error("no source")]
    NoSource,
    /// A source point is NaN or infinite.
    #[error("source {index} is not finite")]
    SourceNotFinite {
        /// Index of the source in the caller's list.
        index: usize,
    },
    /// A source lies outside the grid (point) or is not a cell index (cell set).
    #[error("source {index} is outside the grid")]
    SourceOutside {
        /// Index of the source in the caller's list.
        index: usize,
    },
    /// A source lies in a blocked cell.
    #[error("source {index} is in a blocked cell")]
    SourceBlocked {
        /// Index of the source in the caller's list.
        index: usize,
    },
    /// A point to read (agent or goal) is NaN or infinite.
    #[error("point {point} is not finite")]
    PointNotFinite {
        /// Index of the point in the caller's list.
        point: usize,
    },
    /// A parameter or per-cell input is NaN, infinite or out of range.
    #[error("{what} is invalid (entry {index})")]
    InvalidInput {
        /// Which parameter or input.
        what: &'static str,
        /// Entry index for per-cell or per-agent inputs, 0 for scalars.
        index: usize,
    },
    /// The caller's [`Cancel`](crate::crowd::assign::Cancel) check said the
    /// fields are no longer wanted (checked before each march).
    #[error("cancelled: the input is stale or the daemon is stopping")]
    Cancelled,
}
