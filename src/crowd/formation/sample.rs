//! Target points sampled inside a formation (formation-transform section 3.1).
//! CONTRACT ONLY.

use super::shapes::{Formation, Placement};
use crate::geom::Vec2;

/// How points are sampled in a shape.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SampleParams {
    /// Two points closer than this do not fit (m): usually two agent radii.
    pub min_spacing_m: f64,
    /// Iterations of the force-based relaxation.
    pub relax_iterations: u32,
}

/// Why a shape could not be sampled.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// More agents than fit at the minimum spacing.
    #[error("{agents} agents do not fit in formation `{name}` ({area_m2:.2} m²) at {spacing_m} m apart: at most {fit} do")]
    TooMany {
        /// The formation.
        name: String,
        /// Asked for.
        agents: usize,
        /// What fits.
        fit: usize,
        /// Its area (m²).
        area_m2: f64,
        /// The spacing (m).
        spacing_m: f64,
    },
}

impl Formation {
    /// Exactly `n` points inside the shape laid out by `place`: grid sampling, the
    /// count made exact by roulette-wheel removal or addition, then force-based
    /// relaxation (section 3.1). `Ok(None)` when `cancel` returned `true`.
    ///
    /// # Errors
    /// [`SampleError::TooMany`].
    pub fn sample(
        &self,
        place: &Placement,
        n: usize,
        p: &SampleParams,
        seed: u64,
        cancel: &dyn Fn() -> bool,
    ) -> Result<Option<Vec<Vec2>>, SampleError> {
        let _ = (place, n, p, seed, cancel);
        todo!()
    }
}
