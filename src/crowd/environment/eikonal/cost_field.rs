//! The unit cost `C` of every cell (mesh-formation-control eqs. 3, 4 and 7) and
//! coarser copies of a cost grid.

use super::error::EikonalError;
use super::grid::{check_len, validate_cost, Grid};

/// Weight `α` of path length in eq. 3/4, in cost units per metre.
///
/// mesh-formation-control section 6.2.1 names the weights `α`, `β`, `γ` of eq. 3 but
/// gives no values (it refers to its reference \[6\], Treuille et al., *Continuum
/// Crowds*, 2006, for how the terms are calculated). These defaults are ours: equal
/// weights of 1 in cost units per metre, per second and per second of discomfort.
/// With `g = 0` and a uniform travel speed the unit cost is constant, so the
/// assignment is that of shortest path length whatever the weights.
pub const DEFAULT_ALPHA_PER_M: f64 = 1.0;
/// Weight `β` of travel time in eq. 3/4, in cost units per second (see
/// [`DEFAULT_ALPHA_PER_M`] for the provenance: ours, the paper gives none).
pub const DEFAULT_BETA_PER_S: f64 = 1.0;
/// Weight `γ` of discomfort in eq. 3/4, in cost units per second per unit of
/// discomfort (see [`DEFAULT_ALPHA_PER_M`]: ours, the paper gives none).
pub const DEFAULT_GAMMA_PER_S: f64 = 1.0;

/// Weights of the unit cost (eq. 3/4).
///
/// # Units
/// `alpha` per metre of path, `beta` per second of travel, `gamma` per second per
/// unit of discomfort; all in the same cost unit.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CostWeights {
    /// `α`, weight of path length (cost per metre).
    pub alpha_per_m: f64,
    /// `β`, weight of travel time (cost per second).
    pub beta_per_s: f64,
    /// `γ`, weight of discomfort (cost per second per unit of discomfort).
    pub gamma_per_s: f64,
}

impl Default for CostWeights {
    fn default() -> CostWeights {
        CostWeights {
            alpha_per_m: DEFAULT_ALPHA_PER_M,
            beta_per_s: DEFAULT_BETA_PER_S,
            gamma_per_s: DEFAULT_GAMMA_PER_S,
        }
    }
}

/// Per-cell scene inputs of the cost field, one entry per cell each.
#[derive(Copy, Clone, Debug)]
pub struct CostInputs<'a> {
    /// Cells agents cannot enter.
    pub blocked: &'a [bool],
    /// `TravelSpeed(x)`: 1 in open space, the patch's relative speed in travel-speed
    /// patches (mesh-formation-control Table 1), 0 for impassable. Dimensionless.
    pub speed_factor: &'a [f64],
    /// Discomfort `g` (dimensionless, `≥ 0`), e.g. from [`discomfort_into`](super::discomfort_into); `None`
    /// for none.
    pub discomfort: Option<&'a [f64]>,
}

/// Fills `out` with the unit cost of every cell.
///
/// # Formula
/// mesh-formation-control eq. 7 (eq. 4 with the scene's travel speed):
///
/// ```text
///   C = (α f + β + γ g) / (f · TravelSpeed(x))
/// ```
///
/// from eq. 3, `α ∫ ds + β ∫ dt + γ ∫ g dt` with `ds = f dt`. As in the paper the
/// travel speed divides all three terms. Blocked cells and cells with
/// `TravelSpeed = 0` get `+inf`.
///
/// # Units
/// `preferred_speed_m_s` (`f`) in m/s; the result in cost units per metre.
///
/// # Errors
/// [`EikonalError::SizeMismatch`] for a slice of the wrong length;
/// [`EikonalError::InvalidInput`] for a weight that is negative or not finite, for
/// `α f + β ≤ 0` (the cost must be positive), for a speed that is not finite and
/// positive, or for a speed factor or discomfort that is negative or not finite.
///
/// # Example
/// ```
/// use crowdtouch::crowd::environment::eikonal::{cost_field_into, CostInputs, CostWeights, Grid};
/// use crowdtouch::geom::Vec2;
/// let grid = Grid::new(2, 1, 0.5, Vec2::zeros()).unwrap();
/// let mut c = [0.0; 2];
/// let inputs = CostInputs { blocked: &[false, false], speed_factor: &[1.0, 0.33], discomfort: None };
/// cost_field_into(&grid, CostWeights::default(), 1.4, inputs, &mut c).unwrap();
/// // α = β = 1: (1.4 + 1) / 1.4 per metre in the open, divided by 0.33 when crawling.
/// assert!((c[0] - 2.4 / 1.4).abs() < 1e-12);
/// assert!((c[1] - c[0] / 0.33).abs() < 1e-12);
/// ```
pub fn cost_field_into(
    grid: &Grid,
    weights: CostWeights,
    preferred_speed_m_s: f64,
    inputs: CostInputs<'_>,
    out: &mut [f64],
) -> Result<(), EikonalError> {
    check_len("blocked", grid, inputs.blocked.len())?;
    check_len("speed_factor", grid, inputs.speed_factor.len())?;
    if let Some(g) = inputs.discomfort {
        check_len("discomfort", grid, g.len())?;
    }
    check_len("out", grid, out.len())?;
    let bad = |what| EikonalError::InvalidInput { what, index: 0 };
    let w_ok = |w: f64| w.is_finite() && w >= 0.0;
    if !w_ok(weights.alpha_per_m) {
        return Err(bad("alpha"));
    }
    if !w_ok(weights.beta_per_s) {
        return Err(bad("beta"));
    }
    if !w_ok(weights.gamma_per_s) {
        return Err(bad("gamma"));
    }
    let f = preferred_speed_m_s;
    if !(f.is_finite() && f > 0.0) {
        return Err(bad("preferred_speed_m_s"));
    }
    let base = weights.alpha_per_m * f + weights.beta_per_s;
    if !(base > 0.0 && base.is_finite()) {
        return Err(bad("alpha * f + beta"));
    }
    for i in 0..grid.len() {
        let s = inputs.speed_factor[i];
        if !(s.is_finite() && s >= 0.0) {
            return Err(EikonalError::InvalidInput {
                what: "speed_factor",
                index: i,
            });
        }
        let g = inputs.discomfort.map_or(0.0, |g| g[i]);
        if !(g.is_finite() && g >= 0.0) {
            return Err(EikonalError::InvalidInput {
                what: "discomfort",
                index: i,
            });
        }
        out[i] = if inputs.blocked[i] || s == 0.0 {
            f64::INFINITY
        } else {
            // A tiny speed factor may overflow to +inf: that is "blocked", not NaN.
            (base + weights.gamma_per_s * g) / (f * s)
        };
    }
    Ok(())
}

/// A coarser copy of a cost grid: `factor × factor` cells become one.
///
/// A coarse cell is blocked if any of its fine cells is (so no path crosses a wall
/// that the fine grid blocks; gaps narrower than `factor` cells close), else its cost
/// is the mean of its fine cells. Fine cells past the last whole block count where
/// they exist. Returns the coarse grid (same origin, `factor` times the cell size)
/// and writes its costs into `out`.
///
/// # Errors
/// [`EikonalError::InvalidInput`] for `factor == 0`; [`validate_cost`]'s errors.
pub fn coarsen(
    grid: &Grid,
    cost: &[f64],
    factor: usize,
    out: &mut Vec<f64>,
) -> Result<Grid, EikonalError> {
    if factor == 0 {
        return Err(EikonalError::InvalidInput {
            what: "factor",
            index: 0,
        });
    }
    validate_cost(grid, cost)?;
    let coarse = Grid::new(
        grid.cols.div_ceil(factor),
        grid.rows.div_ceil(factor),
        grid.cell_m * factor as f64,
        grid.origin,
    )?;
    out.clear();
    out.resize(coarse.len(), 0.0);
    let mut count = vec![0u32; coarse.len()];
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let k = coarse.index(c / factor, r / factor);
            out[k] += cost[grid.index(c, r)];
            count[k] += 1;
        }
    }
    for (v, &n) in out.iter_mut().zip(&count) {
        // +inf stays +inf (any blocked fine cell blocks the coarse cell).
        *v /= n as f64;
    }
    Ok(coarse)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

    #[test]
    fn cost_field_follows_eq_7() {
        let grid = Grid::new(3, 1, 1.0, Vec2::zeros()).unwrap();
        let w = CostWeights::default();
        let mut out = vec![0.0; 3];
        cost_field_into(
            &grid,
            w,
            1.5,
            CostInputs {
                blocked: &[false, false, true],
                speed_factor: &[1.0, 0.5, 1.0],
                discomfort: Some(&[0.0, 2.0, 0.0]),
            },
            &mut out,
        )
        .unwrap();
        // (α f + β + γ g) / (f · s) with α = β = γ = 1, f = 1.5.
        assert!((out[0] - 2.5 / 1.5).abs() < 1e-15);
        assert!((out[1] - 4.5 / 0.75).abs() < 1e-15);
        assert_eq!(out[2], f64::INFINITY);
    }

    #[test]
    fn coarsen_blocks_conservatively_and_averages() {
        let grid = Grid::new(5, 4, 0.1, Vec2::new(1.0, 1.0)).unwrap();
        let mut cost: Vec<f64> = (0..20).map(|i| 1.0 + i as f64).collect();
        cost[grid.index(3, 0)] = f64::INFINITY;
        let mut out = Vec::new();
        let coarse = coarsen(&grid, &cost, 2, &mut out).unwrap();
        assert_eq!((coarse.cols(), coarse.rows()), (3, 2));
        assert!((coarse.cell_m() - 0.2).abs() < 1e-15);
        assert_eq!(coarse.origin(), grid.origin());
        // (0, 0) covers fine cells 0, 1, 5, 6.
        assert!((out[0] - (1.0 + 2.0 + 6.0 + 7.0) / 4.0).abs() < 1e-12);
        assert_eq!(out[1], f64::INFINITY);
        // The last column covers one fine column.
        assert!((out[2] - (5.0 + 10.0) / 2.0).abs() < 1e-12);
        assert!(coarsen(&grid, &cost, 0, &mut out).is_err());
    }
}
