//! [`MotionError`]: why a crowd motion's features could not be computed, blended or
//! synthesised.

use crate::crowd::assign::AssignError;

/// Why a crowd motion could not be normalised, analysed, blended or synthesised.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// A motion without trajectories, or a synthesis without agents.
    #[error("{0} is empty")]
    Empty(&'static str),
    /// A raw trajectory with fewer than two samples.
    #[error("trajectory {agent} has {samples} sample(s); at least 2 are needed")]
    TooShort {
        /// The trajectory.
        agent: usize,
        /// Its number of samples.
        samples: usize,
    },
    /// A NaN or infinite coordinate.
    #[error("{what} {index}, sample {sample} is NaN or infinite")]
    NotFinite {
        /// What holds it (`trajectory`, `agent`, `mean`, `basis vector`, ...).
        what: &'static str,
        /// Its index.
        index: usize,
        /// The sample (or entry) within it.
        sample: usize,
    },
    /// A value out of its range (a duration, a weight, a scale, a parameter).
    #[error("{what} is {value}, which is not allowed ({why})")]
    BadValue {
        /// The value's name.
        what: &'static str,
        /// The value.
        value: f64,
        /// The range it must lie in.
        why: &'static str,
    },
    /// The crowd's starting positions all coincide: no spread to normalise by.
    #[error("the crowd's starting positions coincide (RMS radius {rms_radius:e}); no spread to normalise by")]
    ZeroSpread {
        /// The starting RMS radius found.
        rms_radius: f64,
    },
    /// Data of the wrong size (a basis vector not `TRAJ_DIM` long, a mixture whose
    /// dimension is not the basis's, ...).
    #[error("{what}: expected {expected} values, found {found}")]
    Dimension {
        /// What has the wrong size.
        what: &'static str,
        /// The size expected.
        expected: usize,
        /// The size found.
        found: usize,
    },
    /// A Gaussian component whose covariance is not positive definite.
    #[error("Gaussian component {component}: covariance is not positive definite")]
    NotPositiveDefinite {
        /// The component.
        component: usize,
    },
    /// A mixture of zero components was asked for.
    #[error("a Gaussian mixture needs at least one component")]
    NoComponents,
    /// Matching agents to trajectories (or components) failed.
    #[error("assignment failed: {0}")]
    Assign(#[from] AssignError),
}
