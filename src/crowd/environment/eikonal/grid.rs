//! The uniform grid the fields live on (cells, centres, bilinear stencils) and the
//! checks of per-cell inputs against it.

// NaN-aware comparisons (`!(a >= b)` is true for NaN) are deliberate in validation.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::error::EikonalError;
use crate::geom::Vec2;

/// Largest number of cells a grid may have, counting the solver's border of two
/// cells on each side (indices are `u32`).
pub const MAX_CELLS: usize = u32::MAX as usize;

/// Width, in cells, of the border around the solver's padded arrays
/// ([`Fmm`](super::Fmm)): two, so that the second-order stencil's far neighbour of
/// any cell is inside the arrays and no stencil needs a bounds test.
pub(super) const PAD: usize = 2;

/// A uniform grid of square cells over the world plane.
///
/// # Units
/// `cell_m` and `origin` (the outer corner of cell (0, 0)) are in world metres.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Grid {
    pub(super) cols: usize,
    pub(super) rows: usize,
    pub(super) cell_m: f64,
    pub(super) origin: Vec2,
}

impl Grid {
    /// A grid of `cols × rows` cells of side `cell_m` metres whose corner of cell
    /// (0, 0) is at `origin`.
    ///
    /// # Errors
    /// [`EikonalError::InvalidGrid`] if a dimension is zero, the cell count with the
    /// solver's border of two cells on each side exceeds [`MAX_CELLS`], or `cell_m` / `origin` are not finite (and `cell_m > 0`).
    pub fn new(cols: usize, rows: usize, cell_m: f64, origin: Vec2) -> Result<Grid, EikonalError> {
        let ok = cols > 0
            && rows > 0
            && cols
                .checked_add(2 * PAD)
                .zip(rows.checked_add(2 * PAD))
                .and_then(|(c, r)| c.checked_mul(r))
                .is_some_and(|n| n <= MAX_CELLS)
            && cell_m.is_finite()
            && cell_m > 0.0
            && origin.x.is_finite()
            && origin.y.is_finite()
            && (origin.x + cols as f64 * cell_m).is_finite()
            && (origin.y + rows as f64 * cell_m).is_finite();
        if !ok {
            return Err(EikonalError::InvalidGrid { cols, rows });
        }
        Ok(Grid {
            cols,
            rows,
            cell_m,
            origin,
        })
    }

    /// Number of columns (x).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of rows (y).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }

    /// Always false (a grid has at least one cell); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Cell side in metres.
    pub fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// World position (metres) of the outer corner of cell (0, 0).
    pub fn origin(&self) -> Vec2 {
        self.origin
    }

    /// Index of cell (`col`, `row`).
    #[inline]
    pub fn index(&self, col: usize, row: usize) -> usize {
        row * self.cols + col
    }

    /// World position (metres) of the centre of cell `index`.
    pub fn center(&self, index: usize) -> Vec2 {
        let (c, r) = (index % self.cols, index / self.cols);
        self.origin
            + Vec2::new(
                (c as f64 + 0.5) * self.cell_m,
                (r as f64 + 0.5) * self.cell_m,
            )
    }

    /// Whether `p` lies inside the grid or on its border.
    pub fn contains(&self, p: Vec2) -> bool {
        let (fx, fy) = self.frac(p);
        fx >= 0.0 && fy >= 0.0 && fx <= self.cols as f64 && fy <= self.rows as f64
    }

    /// Index of the cell containing `p` (points on the far border belong to the last
    /// cell), or `None` outside the grid or for a non-finite point.
    pub fn cell_of(&self, p: Vec2) -> Option<usize> {
        if !self.contains(p) {
            return None;
        }
        let (fx, fy) = self.frac(p);
        let c = (fx as usize).min(self.cols - 1);
        let r = (fy as usize).min(self.rows - 1);
        Some(self.index(c, r))
    }

    /// Position of `p` in cell units from the origin corner.
    #[inline]
    pub(super) fn frac(&self, p: Vec2) -> (f64, f64) {
        (
            (p.x - self.origin.x) / self.cell_m,
            (p.y - self.origin.y) / self.cell_m,
        )
    }

    /// The bilinear stencil of `p`: the lower-left cell (col, row) of the 2×2 block of
    /// cell centres around `p` (clamped to the grid) and the weights `(tx, ty)` of
    /// the upper neighbours, each in `[0, 1]`. On a one-cell-wide axis the upper
    /// neighbour is the cell itself.
    #[inline]
    pub(super) fn stencil(&self, p: Vec2) -> (usize, usize, f64, f64) {
        let (fx, fy) = self.frac(p);
        let axis = |f: f64, n: usize| -> (usize, f64) {
            if n == 1 {
                return (0, 0.0);
            }
            let g = (f - 0.5).clamp(0.0, (n - 1) as f64);
            let i = (g as usize).min(n - 2);
            (i, g - i as f64)
        };
        let (c, tx) = axis(fx, self.cols);
        let (r, ty) = axis(fy, self.rows);
        (c, r, tx, ty)
    }

    /// Indices of the 2×2 stencil cells of `p` in the order (c, r), (c+1, r),
    /// (c, r+1), (c+1, r+1) (repeated on one-cell-wide axes).
    #[inline]
    pub(super) fn stencil_cells(&self, p: Vec2) -> ([usize; 4], f64, f64) {
        let (c, r, tx, ty) = self.stencil(p);
        let c1 = (c + 1).min(self.cols - 1);
        let r1 = (r + 1).min(self.rows - 1);
        (
            [
                self.index(c, r),
                self.index(c1, r),
                self.index(c, r1),
                self.index(c1, r1),
            ],
            tx,
            ty,
        )
    }
}

/// Checks that a per-cell slice has one entry per cell of `grid`.
pub(super) fn check_len(what: &'static str, grid: &Grid, got: usize) -> Result<(), EikonalError> {
    if got != grid.len() {
        return Err(EikonalError::SizeMismatch {
            what,
            expected: grid.len(),
            got,
        });
    }
    Ok(())
}

/// Checks a cost grid: one entry per cell, each positive (`+inf` = blocked), none NaN.
///
/// # Errors
/// [`EikonalError::SizeMismatch`], [`EikonalError::CostNan`] or
/// [`EikonalError::CostNotPositive`] for the first offending cell.
pub fn validate_cost(grid: &Grid, cost: &[f64]) -> Result<(), EikonalError> {
    check_len("cost", grid, cost.len())?;
    for (cell, &c) in cost.iter().enumerate() {
        if c.is_nan() {
            return Err(EikonalError::CostNan { cell });
        }
        if !(c > 0.0) {
            return Err(EikonalError::CostNotPositive { cell });
        }
    }
    Ok(())
}
