//! Errors of the spatial and temporal editors.

use thiserror::Error;

/// Why a selection, cage, drag, retiming or obstacle adjustment was refused.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum EditError {
    /// A selection asked for a person id the track set does not hold.
    #[error("unknown person id {id}")]
    UnknownId {
        /// The id asked for.
        id: u64,
    },
    /// The selection holds fewer than 3 distinct positions: no hull encloses it.
    #[error("no hull: the selection has {distinct} distinct points, at least 3 are needed")]
    NoHull {
        /// Distinct positions selected.
        distinct: usize,
    },
    /// A lasso polygon with fewer than 3 vertices or a non-finite vertex.
    #[error("lasso has {vertices} usable vertices, at least 3 finite ones are needed")]
    BadLasso {
        /// Vertices given.
        vertices: usize,
    },
    /// A selection criterion value is not finite or empty (rectangle min > max, time
    /// window start > end).
    #[error("selection {what} is not finite or empty")]
    BadCriterion {
        /// Which criterion: `"rect"` or `"time window"`.
        what: &'static str,
    },
    /// The selection refers to a sample the track set does not have (a selection made
    /// on another set).
    #[error("selection refers to track {track} sample {sample}, which the set does not have")]
    SelectionMismatch {
        /// Track index.
        track: usize,
        /// Sample index.
        sample: usize,
    },
    /// The hull could not be built (zero area after every fallback) or a hull vertex
    /// is not finite.
    #[error("degenerate hull: {reason}")]
    DegenerateHull {
        /// What went wrong.
        reason: &'static str,
    },
    /// A drag target is NaN or infinite.
    #[error("drag target ({x}, {y}) is not finite")]
    DragNotFinite {
        /// Target x (m).
        x: f64,
        /// Target y (m).
        y: f64,
    },
    /// A drag target lies outside the world rectangle the editor was given.
    #[error("drag target ({x:.3}, {y:.3}) m is outside the world rectangle")]
    DragOutsideWorld {
        /// Target x (m).
        x: f64,
        /// Target y (m).
        y: f64,
    },
    /// A handle names a hull vertex or selected sample the cage does not have.
    #[error("unknown handle {handle}")]
    UnknownHandle {
        /// The handle, formatted.
        handle: String,
    },
    /// The constraints cannot all hold: a handle both dragged and fixed, or handles
    /// whose constraint rows are linearly dependent.
    #[error("conflicting handle constraints: {reason}")]
    ConflictingHandles {
        /// What conflicts.
        reason: &'static str,
    },
    /// A cage parameter is out of its range.
    #[error("cage parameter {what} is not finite and positive")]
    BadCageParams {
        /// Which parameter.
        what: &'static str,
    },
    /// A time target is NaN or infinite.
    #[error("time target {t_s} s is not finite")]
    TimeNotFinite {
        /// The target (s).
        t_s: f64,
    },
    /// A retiming would make a person's times non-increasing.
    #[error(
        "infeasible retiming: person {id} node {sample} would be at {t_s:.4} s, \
         not after node {previous} at {previous_s:.4} s"
    )]
    InfeasibleRetiming {
        /// The person's id.
        id: u64,
        /// The node whose time would not increase.
        sample: usize,
        /// Its time after the retiming (s).
        t_s: f64,
        /// The node before it.
        previous: usize,
        /// That node's time (s).
        previous_s: f64,
    },
}
