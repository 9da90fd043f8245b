//! The invariants of a solved field (tests, `crowdtouch bench fmm`).

use super::grid::Grid;

/// Relative slack of the neighbour bound of [`sanity_check`] (rounding level).
pub const SANITY_REL_SLACK: f64 = 1e-9;

/// Checks the invariants of a field `phi` solved on `grid` with `cost`: one entry
/// per cell, no NaN, no negative value, `+inf` on every blocked cell, and for every
/// pair of 4-adjacent finite cells `|Φ_i − Φ_j| ≤ h · C_max` with `C_max` the largest
/// finite cost, up to [`SANITY_REL_SLACK`]. (The local bound `h · max(C_i, C_j)`
/// holds for marched cells but not inside a point source's initial band, whose
/// line integrals cross several cells: measured up to 2.1 times it on random costs.)
///
/// # Errors
/// `Err(cell)` with the index of the first cell that breaks an invariant
/// (`usize::MAX` for a size mismatch).
pub fn sanity_check(grid: &Grid, cost: &[f64], phi: &[f64]) -> Result<(), usize> {
    if cost.len() != grid.len() || phi.len() != grid.len() {
        return Err(usize::MAX);
    }
    let h = grid.cell_m;
    let cmax = cost
        .iter()
        .copied()
        .filter(|c| c.is_finite())
        .fold(0.0, f64::max);
    let bound = h * cmax * (1.0 + SANITY_REL_SLACK);
    for i in 0..grid.len() {
        let v = phi[i];
        if v.is_nan() || v < 0.0 || (cost[i] == f64::INFINITY && v != f64::INFINITY) {
            return Err(i);
        }
        if !v.is_finite() {
            continue;
        }
        let (c, r) = (i % grid.cols, i / grid.cols);
        for j in [
            (c + 1 < grid.cols).then(|| i + 1),
            (r + 1 < grid.rows).then(|| i + grid.cols),
        ]
        .into_iter()
        .flatten()
        {
            if phi[j].is_finite() && (phi[j] - v).abs() > bound {
                return Err(i);
            }
        }
    }
    Ok(())
}
