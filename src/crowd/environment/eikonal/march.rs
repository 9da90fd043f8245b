//! Fast marching: the solver of `|∇Φ| = C` (mesh-formation-control eq. 5) with its
//! padded workspace, from point or cell sources.
//!
//! # Solver
//!
//! [`Fmm`] is Sethian's heap-based fast marching method: cells are frozen in order of
//! increasing `Φ`, each trial value solves the upwind discretisation of eq. 5 from its
//! frozen neighbours. With [`Order::Second`] a direction uses the second-order
//! one-sided difference `(3Φ − 4Φ₁ + Φ₂) / 2h` when the two cells upwind in that
//! direction are frozen and monotone (`Φ₂ ≤ Φ₁`), and the first-order difference
//! otherwise. Cells within [`SOURCE_INIT_RADIUS_CELLS`] of a point source start from
//! the exact line integral of the cost from the source, so reads near the source are
//! right.
//!
//! # Accuracy
//!
//! Uniform unit cost, point source, 1 m square (tests): max / mean error of `Φ`
//! against the Euclidean distance is 0.85–1.35 h / 0.4–0.7 h with first order and
//! 0.27–0.32 h / 0.1 h with second order (n = 32…128); the point source's kink
//! keeps the max norm at O(h). Around a wall end the second-order value is 0.5 %
//! above the exact shortest path, first order 1.35 %.

use super::error::EikonalError;
use super::grid::{check_len, validate_cost, Grid, PAD};
use super::heap::{Heap, Trial};
use super::segment::segment_cost;
use crate::geom::Vec2;

/// Radius, in cells, around a point source within which cells start from the exact
/// line integral of the cost instead of being marched.
pub const SOURCE_INIT_RADIUS_CELLS: f64 = 2.0;

/// Accuracy of the upwind differences.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Order {
    /// First-order upwind differences everywhere.
    First,
    /// Second-order one-sided differences where the two cells upwind are frozen and
    /// monotone, first order elsewhere (the default).
    #[default]
    Second,
}

/// What `Φ = 0` is attached to.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Sources<'a> {
    /// World points (metres). Cells within [`SOURCE_INIT_RADIUS_CELLS`] of a point
    /// start from the exact line integral of the cost along the straight segment
    /// (when it crosses no blocked cell).
    Points(&'a [Vec2]),
    /// Cell indices: `Φ = 0` at the centre of each cell of the set.
    Cells(&'a [usize]),
}

/// A march that froze at least `1 / SEQUENTIAL_FRACTION` of the grid writes its
/// result out and resets row by row ([`Fmm::finish`]).
const SEQUENTIAL_FRACTION: usize = 8;

/// Fast-marching solver for `|∇Φ| = C` with its reusable workspace.
///
/// # Formula
/// mesh-formation-control eq. 5, `‖∇Φ(x)‖ = C(x)`, discretised upwind (Sethian): at
/// each cell, with `Φ_x`, `Φ_y` the smaller frozen neighbour along each axis,
/// `Σ_d k_d (Φ − t_d)² = (C h)²` where `(k, t) = (1, Φ₁)` (first order) or
/// `(9/4, (4Φ₁ − Φ₂)/3)` (second order); an axis whose `t` exceeds the
/// one-dimensional solution of the other is dropped.
///
/// # Units
/// `C` in cost units per metre, `h` in metres, `Φ` in cost units.
///
/// # Complexity
/// `O(N log N)` for `N` reached cells; no allocation once the workspace has grown
/// to the grid size. The workspace keeps the grid padded by a border of two
/// cells: the cost (`+inf` on the border) and the frozen values (`+inf` where not
/// frozen). A stencil is then two loads and a minimum per axis, without a state test
/// or a bounds test, and a march touches 16 bytes per cell in its front (random
/// access is what costs: the front is a ring across every row of the grid).
///
/// # Example
/// ```
/// use crowdtouch::crowd::environment::eikonal::{Fmm, Grid, Sources};
/// use crowdtouch::geom::Vec2;
/// let grid = Grid::new(64, 64, 0.1, Vec2::zeros()).unwrap();
/// let cost = vec![1.0; grid.len()];
/// let mut phi = vec![0.0; grid.len()];
/// let src = [Vec2::new(3.2, 3.2)];
/// Fmm::new().solve_into(&grid, &cost, Sources::Points(&src), &mut phi).unwrap();
/// // Uniform unit cost: Φ is the Euclidean distance (second order, a few mm here).
/// let p = grid.center(grid.index(60, 10));
/// assert!((phi[grid.index(60, 10)] - (p - src[0]).norm()).abs() < 0.02);
/// ```
#[derive(Clone, Debug, Default)]
pub struct Fmm {
    order: Order,
    pub(super) heap: Heap,
    /// `(cols, rows)` the padded arrays are laid out for.
    dims: (usize, usize),
    /// The cost times the cell size (`C h`, the right-hand side of the stencil) on
    /// the padded grid; `+inf` on the border and on blocked cells.
    rhs: Vec<f64>,
    /// Frozen `Φ` on the padded grid; `+inf` where not frozen (always on the border).
    frozen: Vec<f64>,
    /// `(padded index, cell)` of every cell a march froze, to write out and reset.
    pub(super) touched: Vec<(u32, u32)>,
    pub(super) marched: u64,
}

/// Where a march stops early: when every marked target cell is frozen.
pub(super) struct Targets<'a> {
    pub(super) mark: &'a [u32],
    pub(super) stamp: u32,
    pub(super) count: usize,
}

impl Fmm {
    /// A solver with second-order stencils ([`Order::Second`]).
    pub fn new() -> Fmm {
        Fmm::default()
    }

    /// A solver with the given stencil order.
    pub fn with_order(order: Order) -> Fmm {
        Fmm {
            order,
            ..Fmm::default()
        }
    }

    /// The stencil order.
    pub fn order(&self) -> Order {
        self.order
    }

    /// Cells frozen since the solver was created (a work counter for profiling).
    pub fn cells_marched(&self) -> u64 {
        self.marched
    }

    /// Solves eq. 5 on `grid` with per-cell `cost` from `sources` and writes `Φ` into
    /// `out` (one entry per cell; `+inf` where no path exists).
    ///
    /// # Errors
    /// [`validate_cost`]'s errors; [`EikonalError::SizeMismatch`] for `out`;
    /// [`EikonalError::NoSource`], [`EikonalError::SourceNotFinite`],
    /// [`EikonalError::SourceOutside`], [`EikonalError::SourceBlocked`]. `out` is
    /// unspecified after an error.
    pub fn solve_into(
        &mut self,
        grid: &Grid,
        cost: &[f64],
        sources: Sources<'_>,
        out: &mut [f64],
    ) -> Result<(), EikonalError> {
        validate_cost(grid, cost)?;
        check_len("out", grid, out.len())?;
        validate_sources(grid, cost, sources)?;
        self.load(grid, cost);
        out.fill(f64::INFINITY);
        self.march(grid, cost, sources, None);
        self.finish(out);
        Ok(())
    }

    /// Lays the workspace out for `grid` (on a size change) and copies `cost` (valid,
    /// one entry per cell) into it; every value `+inf`, the heap empty.
    pub(super) fn load(&mut self, grid: &Grid, cost: &[f64]) {
        self.reset();
        let (cols, rows) = (grid.cols, grid.rows);
        let wp = cols + 2 * PAD;
        if self.dims != (cols, rows) {
            let n = wp * (rows + 2 * PAD);
            for v in [&mut self.rhs, &mut self.frozen] {
                v.clear();
                v.resize(n, f64::INFINITY);
            }
            self.dims = (cols, rows);
        }
        let h = grid.cell_m;
        for r in 0..rows {
            let start = (r + PAD) * wp + PAD;
            let dst = &mut self.rhs[start..start + cols];
            for (d, &c) in dst.iter_mut().zip(&cost[r * cols..(r + 1) * cols]) {
                *d = c * h;
            }
        }
    }

    /// Whether a march that froze `touched` cells is better written out and reset
    /// row by row than cell by cell: sequential passes are cheap, scattered ones pay
    /// a cache miss per line.
    fn sequential(&self, touched: usize) -> bool {
        touched >= (self.dims.0 * self.dims.1) / SEQUENTIAL_FRACTION
    }

    /// Puts every frozen value back to `+inf` and empties the heap.
    fn reset(&mut self) {
        if self.sequential(self.touched.len()) {
            let (cols, rows) = self.dims;
            let wp = cols + 2 * PAD;
            for r in 0..rows {
                let start = (r + PAD) * wp + PAD;
                self.frozen[start..start + cols].fill(f64::INFINITY);
            }
        } else {
            for &(p, _) in &self.touched {
                self.frozen[p as usize] = f64::INFINITY;
            }
        }
        self.touched.clear();
        self.heap.clear();
    }

    /// Ends a march: writes the frozen values into `phi` and resets the workspace.
    /// Either every cell is written (`+inf` where not frozen) or only the frozen
    /// ones, so every other cell of `phi` must be `+inf` already.
    pub(super) fn finish(&mut self, phi: &mut [f64]) {
        if self.sequential(self.touched.len()) {
            let (cols, rows) = self.dims;
            let wp = cols + 2 * PAD;
            for r in 0..rows {
                let start = (r + PAD) * wp + PAD;
                phi[r * cols..(r + 1) * cols].copy_from_slice(&self.frozen[start..start + cols]);
            }
        } else {
            for &(p, i) in &self.touched {
                phi[i as usize] = self.frozen[p as usize];
            }
        }
        self.reset();
    }

    /// The march itself. Sources are validated; the workspace is loaded with the
    /// grid's cost ([`Fmm::load`]) and reset. Returns whether the march ran to
    /// exhaustion. The values stay in the workspace until [`Fmm::finish`].
    pub(super) fn march(
        &mut self,
        grid: &Grid,
        cost: &[f64],
        sources: Sources<'_>,
        targets: Option<Targets<'_>>,
    ) -> bool {
        match self.order {
            Order::First => self.march_with::<false>(grid, cost, sources, targets),
            Order::Second => self.march_with::<true>(grid, cost, sources, targets),
        }
    }

    /// [`Fmm::march`] with the stencil order fixed at compile time.
    fn march_with<const SECOND: bool>(
        &mut self,
        grid: &Grid,
        cost: &[f64],
        sources: Sources<'_>,
        targets: Option<Targets<'_>>,
    ) -> bool {
        let h = grid.cell_m;
        let cols = grid.cols;
        let wp = cols + 2 * PAD;
        let padded = |c: usize, r: usize| (r + PAD) * wp + c + PAD;
        let mut remaining = targets.as_ref().map_or(usize::MAX, |t| t.count);
        let is_target =
            |t: &Option<Targets<'_>>, i: usize| t.as_ref().is_some_and(|t| t.mark[i] == t.stamp);
        // Initial frozen band.
        let mut band = |p: usize, i: usize, v: f64| {
            if self.frozen[p] == f64::INFINITY {
                self.touched.push((p as u32, i as u32));
            }
            if v < self.frozen[p] {
                self.frozen[p] = v;
            }
        };
        match sources {
            Sources::Cells(cells) => {
                for &i in cells {
                    band(padded(i % cols, i / cols), i, 0.0);
                }
            }
            Sources::Points(points) => {
                let r = SOURCE_INIT_RADIUS_CELLS;
                let reach = r.ceil() as isize;
                for &s in points {
                    let (fx, fy) = grid.frac(s);
                    let c0 = (fx.floor() as isize).min(grid.cols as isize - 1);
                    let r0 = (fy.floor() as isize).min(grid.rows as isize - 1);
                    for rr in (r0 - reach).max(0)..=(r0 + reach).min(grid.rows as isize - 1) {
                        for cc in (c0 - reach).max(0)..=(c0 + reach).min(grid.cols as isize - 1) {
                            let (cu, ru) = (cc as usize, rr as usize);
                            let i = grid.index(cu, ru);
                            if cost[i] == f64::INFINITY {
                                continue;
                            }
                            let centre = grid.center(i);
                            let d = centre - s;
                            let own = cc == c0 && rr == r0;
                            if !own && d.norm_squared() > (r * h) * (r * h) {
                                continue;
                            }
                            let v = segment_cost(grid, cost, s, centre);
                            if v == f64::INFINITY {
                                // The straight segment crosses a blocked cell: march it.
                                continue;
                            }
                            band(padded(cu, ru), i, v);
                        }
                    }
                }
            }
        }
        // Count targets inside the band, then push the band's neighbours.
        let band = self.touched.len();
        for k in 0..band {
            if is_target(&targets, self.touched[k].1 as usize) {
                remaining -= 1;
            }
        }
        if remaining == 0 {
            self.marched += band as u64;
            return false;
        }
        for k in 0..band {
            let (p, i) = self.touched[k];
            self.update_neighbours::<SECOND>(cols, p as usize, i as usize);
        }
        let mut frozen = band;
        while let Some(t) = self.heap.pop() {
            let p = t.padded as usize;
            if self.frozen[p] != f64::INFINITY {
                continue; // a stale entry: the cell froze at a lower value
            }
            self.frozen[p] = f64::from_bits(t.key);
            frozen += 1;
            let i = t.cell as usize;
            self.touched.push((t.padded, t.cell));
            if is_target(&targets, i) {
                remaining -= 1;
                if remaining == 0 {
                    self.marched += frozen as u64;
                    let fz = &self.frozen;
                    return self
                        .heap
                        .items
                        .iter()
                        .all(|t| fz[t.padded as usize] != f64::INFINITY);
                }
            }
            self.update_neighbours::<SECOND>(cols, p, i);
        }
        self.marched += frozen as u64;
        true
    }

    /// Recomputes the trial value of each non-frozen, unblocked 4-neighbour of the
    /// cell with padded index `p` and grid index `i` in a grid of `cols` columns. (A
    /// neighbour across the grid's edge is a border cell, with `+inf` cost, so its
    /// wrapped grid index is never used.)
    #[inline]
    fn update_neighbours<const SECOND: bool>(&mut self, cols: usize, p: usize, i: usize) {
        let wp = cols + 2 * PAD;
        self.update::<SECOND>(wp, p - 1, i.wrapping_sub(1));
        self.update::<SECOND>(wp, p + 1, i.wrapping_add(1));
        self.update::<SECOND>(wp, p - wp, i.wrapping_sub(cols));
        self.update::<SECOND>(wp, p + wp, i.wrapping_add(cols));
    }

    /// Recomputes the trial value of the cell with padded index `p`, grid index `n`;
    /// `wp` is the padded row length.
    #[inline(always)]
    fn update<const SECOND: bool>(&mut self, wp: usize, p: usize, n: usize) {
        let rhs = self.rhs[p];
        if self.frozen[p] != f64::INFINITY || rhs == f64::INFINITY {
            return;
        }
        let v = self.local::<SECOND>(rhs, p, wp);
        self.heap.push(Trial {
            key: v.to_bits(),
            padded: p as u32,
            cell: n as u32,
        });
    }

    /// One axis of the upwind stencil at padded index `p` with stride `s` (1 along x,
    /// the padded row length along y): `(k, t)` of the smaller frozen neighbour, `t =
    /// +inf` when neither is frozen.
    #[inline]
    fn axis<const SECOND: bool>(&self, p: usize, s: usize) -> (f64, f64) {
        let fz = &self.frozen;
        let (lo, hi) = (fz[p - s], fz[p + s]);
        let (a1, far) = if lo <= hi {
            (lo, fz[p - 2 * s])
        } else {
            (hi, fz[p + 2 * s])
        };
        // (`a1 < inf`: with both neighbours and the far one unfrozen, 4·inf − inf
        // would be NaN.)
        if SECOND && far <= a1 && a1 < f64::INFINITY {
            (2.25, (4.0 * a1 - far) * (1.0 / 3.0))
        } else {
            (1.0, a1)
        }
    }

    /// Trial value of the cell with padded index `p` whose cost times the cell size
    /// is `rhs`, from its frozen neighbours; `wp` is the padded row length.
    #[inline]
    fn local<const SECOND: bool>(&self, rhs: f64, p: usize, wp: usize) -> f64 {
        let (kx, tx) = self.axis::<SECOND>(p, 1);
        let (ky, ty) = self.axis::<SECOND>(p, wp);
        let ((k1, t1), (k2, t2)) = if tx <= ty {
            ((kx, tx), (ky, ty))
        } else {
            ((ky, ty), (kx, tx))
        };
        // 1/√k: 1 (first order) or 2/3 (second order, k = 9/4).
        let w1 = if k1 == 1.0 { 1.0 } else { 2.0 / 3.0 };
        let one = t1 + rhs * w1;
        if one <= t2 {
            // Also the case t2 = +inf (one axis only), and +inf when neither is frozen.
            return one;
        }
        // k1 (Φ - t1)² + k2 (Φ - t2)² = rhs²; f(t2) < 0 here so the larger root
        // exceeds t2 and the discriminant is positive.
        let ks = k1 + k2;
        let b_half = k1 * t1 + k2 * t2;
        let cc = k1 * t1 * t1 + k2 * t2 * t2 - rhs * rhs;
        let disc = (b_half * b_half - ks * cc).max(0.0);
        let v = (b_half + disc.sqrt()) / ks;
        if v >= t2 {
            v
        } else {
            one
        }
    }
}

/// Checks the sources of a solve against the grid and the cost.
fn validate_sources(grid: &Grid, cost: &[f64], sources: Sources<'_>) -> Result<(), EikonalError> {
    match sources {
        Sources::Points(points) => {
            if points.is_empty() {
                return Err(EikonalError::NoSource);
            }
            for (source, &p) in points.iter().enumerate() {
                if !(p.x.is_finite() && p.y.is_finite()) {
                    return Err(EikonalError::SourceNotFinite { index: source });
                }
                let cell = grid
                    .cell_of(p)
                    .ok_or(EikonalError::SourceOutside { index: source })?;
                if cost[cell] == f64::INFINITY {
                    return Err(EikonalError::SourceBlocked { index: source });
                }
            }
        }
        Sources::Cells(cells) => {
            if cells.is_empty() {
                return Err(EikonalError::NoSource);
            }
            for (source, &cell) in cells.iter().enumerate() {
                if cell >= grid.len() {
                    return Err(EikonalError::SourceOutside { index: source });
                }
                if cost[cell] == f64::INFINITY {
                    return Err(EikonalError::SourceBlocked { index: source });
                }
            }
        }
    }
    Ok(())
}
