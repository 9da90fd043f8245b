//! Reading a solved field: `Φ` at a point by bilinear interpolation (eq. 6) and the
//! direction of steepest descent.

use super::grid::Grid;
use crate::geom::Vec2;

/// Gradient magnitude, in cost units per metre, below which the bilinear gradient
/// counts as degenerate and [`descent_direction`] falls back to the steepest
/// neighbour (rounding level for costs of order 1 per metre).
pub const DEGENERATE_GRADIENT_PER_M: f64 = 1e-9;

/// `Φ` at world point `p` by bilinear interpolation of the cell-centre values.
///
/// # Formula
/// mesh-formation-control eq. 6, `C_{A,v} = Φ_v(A_pos)`, read bilinearly from the
/// four cell centres around `p` (clamped at the grid border). Corners with `+inf`
/// (blocked or unreachable) are left out and the remaining weights renormalised, so
/// a point beside a wall reads the free side; `+inf` only when every corner with a
/// non-zero weight is infinite.
///
/// # Units
/// `p` in metres; result in the units of `phi`.
///
/// # Panics
/// If `phi` does not have one entry per cell.
///
/// # Example
/// ```
/// use crowdtouch::crowd::environment::eikonal::{sample, Grid};
/// use crowdtouch::geom::Vec2;
/// let grid = Grid::new(2, 2, 1.0, Vec2::zeros()).unwrap();
/// // Centres at (0.5, 0.5), (1.5, 0.5), (0.5, 1.5), (1.5, 1.5).
/// let phi = [0.0, 1.0, 2.0, f64::INFINITY];
/// assert!((sample(&grid, &phi, Vec2::new(1.0, 0.5)) - 0.5).abs() < 1e-12);
/// // The infinite corner is left out: weights 1/4 each on the other three.
/// assert!((sample(&grid, &phi, Vec2::new(1.0, 1.0)) - 1.0).abs() < 1e-12);
/// ```
pub fn sample(grid: &Grid, phi: &[f64], p: Vec2) -> f64 {
    assert_eq!(phi.len(), grid.len(), "field size");
    let (cells, tx, ty) = grid.stencil_cells(p);
    let w = [
        (1.0 - tx) * (1.0 - ty),
        tx * (1.0 - ty),
        (1.0 - tx) * ty,
        tx * ty,
    ];
    let mut sum = 0.0;
    let mut wsum = 0.0;
    for k in 0..4 {
        let v = phi[cells[k]];
        if w[k] > 0.0 && v.is_finite() {
            sum += w[k] * v;
            wsum += w[k];
        }
    }
    if wsum > 0.0 {
        sum / wsum
    } else {
        // Every weighted corner is infinite, or p sits exactly on a corner whose
        // value is infinite.
        let mut best = f64::INFINITY;
        for k in 0..4 {
            if w[k] > 0.0 {
                best = best.min(phi[cells[k]]);
            }
        }
        best
    }
}

/// The direction in which `Φ` decreases fastest at `p`: a unit vector, or `None` at
/// a source (`Φ = 0` at the nearest cell) or where no neighbour is reachable.
///
/// # Formula
/// `−∇Φ / |∇Φ|` with `∇Φ` the gradient of the bilinear interpolant (eq. 6) when all
/// four corners around `p` are finite, their 3×3 neighbourhood is free of infinite
/// cells and `|∇Φ| ≥` [`DEGENERATE_GRADIENT_PER_M`]. Otherwise (beside a wall, an
/// unreachable cell, or a flat spot) the direction from `p` to the centre of the
/// 8-neighbour of the nearest cell with the smallest `Φ`; a diagonal neighbour only
/// counts when both cells it cuts past are finite, so the step never clips a
/// blocked corner.
///
/// # Units
/// `p` in metres; the result is dimensionless.
///
/// # Panics
/// If `phi` does not have one entry per cell.
pub fn descent_direction(grid: &Grid, phi: &[f64], p: Vec2) -> Option<Vec2> {
    assert_eq!(phi.len(), grid.len(), "field size");
    let near = grid.cell_of(p).or_else(|| {
        // Outside the grid: use the nearest border cell.
        let (fx, fy) = grid.frac(p);
        if !(fx.is_finite() && fy.is_finite()) {
            return None;
        }
        let c = (fx.max(0.0) as usize).min(grid.cols - 1);
        let r = (fy.max(0.0) as usize).min(grid.rows - 1);
        Some(grid.index(c, r))
    })?;
    if phi[near] == 0.0 {
        return None;
    }
    let (cells, tx, ty) = grid.stencil_cells(p);
    let (nc, nr) = (near % grid.cols, near / grid.cols);
    let neighbourhood_finite = || {
        let (c0, r0) = (cells[0] % grid.cols, cells[0] / grid.cols);
        let (c1, r1) = (cells[3] % grid.cols, cells[3] / grid.cols);
        for r in r0.saturating_sub(1)..=(r1 + 1).min(grid.rows - 1) {
            for c in c0.saturating_sub(1)..=(c1 + 1).min(grid.cols - 1) {
                if !phi[grid.index(c, r)].is_finite() {
                    return false;
                }
            }
        }
        true
    };
    if cells.iter().all(|&i| phi[i].is_finite()) && neighbourhood_finite() {
        let [v00, v10, v01, v11] = cells.map(|i| phi[i]);
        let h = grid.cell_m;
        let gx = if cells[1] != cells[0] {
            ((v10 - v00) * (1.0 - ty) + (v11 - v01) * ty) / h
        } else {
            0.0
        };
        let gy = if cells[2] != cells[0] {
            ((v01 - v00) * (1.0 - tx) + (v11 - v10) * tx) / h
        } else {
            0.0
        };
        let g = Vec2::new(gx, gy);
        let n = g.norm();
        if n >= DEGENERATE_GRADIENT_PER_M {
            return Some(-g / n);
        }
    }
    // Steepest finite neighbour of the nearest cell.
    let at = |c: isize, r: isize| -> f64 {
        if c < 0 || r < 0 || c >= grid.cols as isize || r >= grid.rows as isize {
            f64::INFINITY
        } else {
            phi[grid.index(c as usize, r as usize)]
        }
    };
    let (ci, ri) = (nc as isize, nr as isize);
    let mut best = (phi[near], None);
    for dr in -1..=1isize {
        for dc in -1..=1isize {
            if dc == 0 && dr == 0 {
                continue;
            }
            if dc != 0 && dr != 0 && !(at(ci + dc, ri).is_finite() && at(ci, ri + dr).is_finite()) {
                continue;
            }
            let v = at(ci + dc, ri + dr);
            if v < best.0 {
                best = (v, Some(grid.index((ci + dc) as usize, (ri + dr) as usize)));
            }
        }
    }
    let target = match best.1 {
        Some(j) => grid.center(j),
        // The nearest cell is a local minimum of the finite values but not a source
        // (p off-centre in a source's neighbour): head for its centre.
        None if phi[near].is_finite() => grid.center(near),
        None => return None,
    };
    let d = target - p;
    let n = d.norm();
    if n > 0.0 {
        Some(d / n)
    } else {
        None
    }
}
