//! The scene sampled on a regular grid: what a planner (fast marching, the
//! environment field) reads per cell.
//!
//! ```text
//!  origin + (0, rows·cell_m)
//!     +-----+-----+-----+
//!     | 2,0 | 2,1 | 2,2 |   cell (row, col) covers
//!     +-----+-----+-----+   origin + [col, col+1)·cell_m  ×  origin + [row, row+1)·cell_m
//!     | 1,0 | 1,1 | 1,2 |   and is sampled at its centre;
//!     +-----+-----+-----+   index = row · cols + col
//!     | 0,0 | 0,1 | 0,2 |
//!     +-----+-----+-----+
//!  origin            origin + (cols·cell_m, 0)
//! ```

use super::model::{DynamicKind, Scene, Terrain};
use super::shape::Placement;
use crate::geom::{Rect, Vec2};
use crate::vocab::MotionType;

/// Most cells a grid may have.
pub const MAX_GRID_CELLS: usize = 1 << 22;

/// Why a grid could not be made.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GridError {
    /// A cell size, origin or bounds that is not finite and positive.
    #[error("grid cell size and origin must be finite, the cell size positive")]
    BadGeometry,
    /// No cells, or more than [`MAX_GRID_CELLS`].
    #[error("grid must have 1..={MAX_GRID_CELLS} cells")]
    BadSize,
}

/// The scene rasterised at one time: per-cell obstacle, terrain and distance.
///
/// Every per-cell vector has `cols × rows` entries, indexed `row · cols + col`.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneGrid {
    /// Cells along x.
    pub cols: usize,
    /// Cells along y.
    pub rows: usize,
    /// Cell side (m).
    pub cell_m: f64,
    /// World position of the grid's minimum corner (m).
    pub origin: Vec2,
    /// The cell's centre is inside (or on) an obstacle.
    pub blocked: Vec<bool>,
    /// Travel speed relative to running at the cell centre: the patch's factor
    /// (mesh-formation-control eq. 7, `TravelSpeed(x)`), 1.0 in the open, 0.0 in a
    /// blocked cell.
    pub speed_factor: Vec<f64>,
    /// Motion type at the cell centre ([`MotionType::Run`] in the open and in
    /// blocked cells).
    pub motion: Vec<MotionType>,
    /// Signed distance from the cell centre to the nearest obstacle (m): negative
    /// inside, `f64::INFINITY` when the scene has no obstacles.
    pub obstacle_distance_m: Vec<f64>,
    placements: Vec<Placement>,
}

impl SceneGrid {
    /// An empty grid of `cols × rows` cells of side `cell_m` from `origin`.
    ///
    /// # Errors
    /// [`GridError`] for a bad size or geometry.
    pub fn new(
        cols: usize,
        rows: usize,
        cell_m: f64,
        origin: Vec2,
    ) -> Result<SceneGrid, GridError> {
        if !(cell_m.is_finite() && cell_m > 0.0 && origin.x.is_finite() && origin.y.is_finite()) {
            return Err(GridError::BadGeometry);
        }
        let n = cols.checked_mul(rows).ok_or(GridError::BadSize)?;
        if n == 0 || n > MAX_GRID_CELLS {
            return Err(GridError::BadSize);
        }
        Ok(SceneGrid {
            cols,
            rows,
            cell_m,
            origin,
            blocked: vec![false; n],
            speed_factor: vec![1.0; n],
            motion: vec![MotionType::Run; n],
            obstacle_distance_m: vec![f64::INFINITY; n],
            placements: Vec::new(),
        })
    }

    /// A grid covering `bounds` with cells of side `cell_m` (the last row and
    /// column may stick out past the bounds).
    ///
    /// # Errors
    /// [`GridError`] for a bad size or geometry.
    pub fn for_bounds(bounds: Rect, cell_m: f64) -> Result<SceneGrid, GridError> {
        let (w, h) = (bounds.width(), bounds.height());
        if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0 && cell_m > 0.0) {
            return Err(GridError::BadGeometry);
        }
        let (c, r) = ((w / cell_m).ceil(), (h / cell_m).ceil());
        if (c * r).is_nan() || c * r > MAX_GRID_CELLS as f64 {
            return Err(GridError::BadSize);
        }
        SceneGrid::new(
            c as usize,
            r as usize,
            cell_m,
            Vec2::new(bounds.min[0], bounds.min[1]),
        )
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }

    /// Whether the grid has no cells (never, for a constructed grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of cell (`col`, `row`).
    pub fn index(&self, col: usize, row: usize) -> usize {
        row * self.cols + col
    }

    /// Centre of cell (`col`, `row`) (m).
    pub fn cell_centre(&self, col: usize, row: usize) -> Vec2 {
        self.origin + Vec2::new(col as f64 + 0.5, row as f64 + 0.5) * self.cell_m
    }

    /// The cell (`col`, `row`) containing `p`, if inside the grid.
    pub fn cell_of(&self, p: Vec2) -> Option<(usize, usize)> {
        let c = ((p.x - self.origin.x) / self.cell_m).floor();
        let r = ((p.y - self.origin.y) / self.cell_m).floor();
        (c >= 0.0 && r >= 0.0 && c < self.cols as f64 && r < self.rows as f64)
            .then_some((c as usize, r as usize))
    }

    /// Fills every cell from `scene` at `t_s`. Reuses the buffers: no allocation
    /// once the grid has been filled for a scene of this size.
    ///
    /// # Complexity
    /// O(cells × parts).
    pub(super) fn fill(&mut self, scene: &Scene, t_s: f64) {
        let n = self.len();
        self.blocked.resize(n, false);
        self.speed_factor.resize(n, 1.0);
        self.motion.resize(n, MotionType::Run);
        self.obstacle_distance_m.resize(n, f64::INFINITY);
        self.placements.clear();
        self.placements
            .extend(scene.dynamic().iter().map(|d| d.placement_at(t_s)));
        for row in 0..self.rows {
            for col in 0..self.cols {
                let i = self.index(col, row);
                let p = self.cell_centre(col, row);
                let mut d = f64::INFINITY;
                for o in scene.obstacles() {
                    for part in &o.parts {
                        d = d.min(part.signed_distance(p));
                    }
                }
                let mut terrain = Terrain::OPEN;
                for patch in scene.patches() {
                    if patch.parts.iter().any(|part| part.contains(p)) {
                        terrain = patch.terrain;
                    }
                }
                for (dy, pl) in scene.dynamic().iter().zip(&self.placements) {
                    let local = pl.to_local(p);
                    match dy.kind {
                        DynamicKind::Obstacle => {
                            for part in &dy.parts {
                                d = d.min(part.signed_distance(local));
                            }
                        }
                        DynamicKind::Patch(t) => {
                            if dy.parts.iter().any(|part| part.contains(local)) {
                                terrain = t;
                            }
                        }
                    }
                }
                let blocked = d <= 0.0;
                self.blocked[i] = blocked;
                self.obstacle_distance_m[i] = d;
                if blocked {
                    self.speed_factor[i] = 0.0;
                    self.motion[i] = MotionType::Run;
                } else {
                    self.speed_factor[i] = terrain.speed_factor;
                    self.motion[i] = terrain.motion;
                }
            }
        }
    }
}
