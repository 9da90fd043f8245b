//! A uniform grid over a scene's static obstacle and patch parts, so the per-agent
//! queries of the control thread ([`Scene::signed_distance`],
//! [`Scene::terrain_at`]) look at the few parts near a point instead of every part
//! of the scene.
//!
//! Each cell lists, in file order, the static obstacle parts within
//! [`INDEX_REACH_M`] of it and the static patch parts overlapping it (both by their
//! axis-aligned boxes, so a list may hold a part a little farther; never misses
//! one). Points outside the grid, and distance queries that find nothing nearer
//! than [`INDEX_REACH_M`], fall back to every part, so every answer is the one the
//! full scan gives. Moving obstacles and patches are not indexed: they are few and
//! culled by their parts' reach instead.
//!
//! [`Scene::signed_distance`]: super::Scene::signed_distance
//! [`Scene::terrain_at`]: super::Scene::terrain_at

use super::shape::Part;
use crate::geom::{Rect, Vec2};

/// Obstacle parts farther than this from a cell are not in its list (m). Distance
/// queries whose answer is below it are exact from the list alone (an agent's
/// radius is well below it).
pub const INDEX_REACH_M: f64 = 1.0;
/// Side of a grid cell (m) unless the scene is so large that [`MAX_INDEX_CELLS`]
/// asks for coarser ones.
const INDEX_CELL_M: f64 = 0.5;
/// Most cells of the grid.
const MAX_INDEX_CELLS: usize = 1 << 16;
/// Patch boxes are widened by this much (m) so a point on a patch's edge is in its
/// cell's list whatever the rounding.
const PATCH_SLACK_M: f64 = 1e-6;
/// How far inside a patch part a cell's corners must be for the part to cover
/// the cell (m).
const COVER_MARGIN_M: f64 = 1e-6;

/// A static part: `(item, part)` indices into the scene's obstacles or patches.
pub(super) type PartRef = (u32, u32);

/// The grid; empty (every query falls back) for a scene without static parts.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct PartIndex {
    origin: Vec2,
    cell_m: f64,
    /// `1 / cell_m`, and the grid's size as floats: the per-query cell lookup
    /// multiplies and compares only.
    per_cell_m: f64,
    nx_f: f64,
    ny_f: f64,
    nx: usize,
    ny: usize,
    obstacle_start: Vec<u32>,
    obstacle_parts: Vec<PartRef>,
    /// Per cell: a lower bound of the distance from any point of the cell to any
    /// static obstacle part (m; at most [`INDEX_REACH_M`]), from the parts' boxes.
    obstacle_clear_m: Vec<f64>,
    patch_start: Vec<u32>,
    patch_parts: Vec<PartRef>,
    /// Per cell: whether the first part of its patch list covers the whole cell
    /// (the parts before it in file order, which it overrides, are dropped from
    /// the list), so a point in the cell is in that part without a test.
    patch_covers: Vec<bool>,
    /// Per moving item, the largest reach of its parts from its frame's origin (m):
    /// no part is nearer to a point than the point's distance to the origin less it.
    dynamic_reach_m: Vec<f64>,
}

impl PartIndex {
    /// The index of the static obstacles' and patches' parts (each item's parts, in
    /// file order) over `bounds` widened by [`INDEX_REACH_M`], with the reach of
    /// each moving item's parts.
    pub(super) fn new<'a>(
        bounds: Rect,
        obstacles: impl Iterator<Item = &'a [Part]> + 'a,
        patches: impl Iterator<Item = &'a [Part]> + 'a,
        dynamic: impl Iterator<Item = &'a [Part]>,
    ) -> PartIndex {
        let dynamic_reach_m = dynamic
            .map(|parts| parts.iter().map(|p| p.reach_m()).fold(0.0, f64::max))
            .collect();
        let (w, h) = (
            bounds.width() + 2.0 * INDEX_REACH_M,
            bounds.height() + 2.0 * INDEX_REACH_M,
        );
        if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
            return PartIndex {
                dynamic_reach_m,
                ..PartIndex::default()
            };
        }
        let mut cell = INDEX_CELL_M;
        while ((w / cell).ceil() * (h / cell).ceil()) as usize > MAX_INDEX_CELLS {
            cell *= 2.0;
        }
        let mut ix = PartIndex {
            origin: Vec2::new(bounds.min[0] - INDEX_REACH_M, bounds.min[1] - INDEX_REACH_M),
            cell_m: cell,
            nx: ((w / cell).ceil() as usize).max(1),
            ny: ((h / cell).ceil() as usize).max(1),
            dynamic_reach_m,
            ..PartIndex::default()
        };
        (ix.per_cell_m, ix.nx_f, ix.ny_f) = (1.0 / cell, ix.nx as f64, ix.ny as f64);
        let obstacles: Vec<&[Part]> = obstacles.collect();
        let mut obstacle_boxes = part_boxes(obstacles.iter().copied());
        (ix.obstacle_start, ix.obstacle_parts) = ix.lists(&mut obstacle_boxes, INDEX_REACH_M);
        ix.obstacle_clear_m = ix.clearances(&obstacles);
        let patches: Vec<&[Part]> = patches.collect();
        let mut patch_boxes = part_boxes(patches.iter().copied());
        let (start, flat) = ix.lists(&mut patch_boxes, PATCH_SLACK_M);
        (ix.patch_start, ix.patch_parts, ix.patch_covers) = ix.covered(&start, &flat, &patches);
        ix
    }

    /// Per cell, the distance from the cell to the nearest box of a part in its
    /// obstacle list ([`INDEX_REACH_M`] for an empty list: every other part's box
    /// is farther), less a relative `1e-9` against rounding. A part's signed
    /// distance is at least the distance to its box, so no point of the cell is
    /// nearer to a static obstacle.
    fn clearances(&self, obstacles: &[&[Part]]) -> Vec<f64> {
        (0..self.nx * self.ny)
            .map(|c| {
                let (cx, cy) = ((c % self.nx) as f64, (c / self.nx) as f64);
                let lo = self.origin + Vec2::new(cx, cy) * self.cell_m;
                let hi = lo + Vec2::repeat(self.cell_m);
                let (a, b) = (self.obstacle_start[c], self.obstacle_start[c + 1]);
                self.obstacle_parts[a as usize..b as usize]
                    .iter()
                    .map(|&(i, j)| {
                        let bx = obstacles[i as usize][j as usize].aabb();
                        let gap = |l: f64, h: f64, bl: f64, bh: f64| (bl - h).max(l - bh).max(0.0);
                        let (gx, gy) = (
                            gap(lo.x, hi.x, bx.min[0], bx.max[0]),
                            gap(lo.y, hi.y, bx.min[1], bx.max[1]),
                        );
                        (gx * gx + gy * gy).sqrt()
                    })
                    .fold(INDEX_REACH_M, f64::min)
                    * (1.0 - 1e-9)
            })
            .collect()
    }

    /// The patch lists cut at the last part (in file order) that covers the whole
    /// cell: `(start, flat, covers)` as [`lists`](Self::lists) gives them, with
    /// `covers[c]` when cell `c`'s list begins with such a part.
    ///
    /// A part covers a cell when each of the cell's corners lies at least
    /// [`COVER_MARGIN_M`] inside it: parts are convex, so the points at least that
    /// far inside form a convex set, which then holds the whole cell; the margin
    /// is far above the rounding of a point's cell and of `contains`.
    fn covered(
        &self,
        start: &[u32],
        flat: &[PartRef],
        patches: &[&[Part]],
    ) -> (Vec<u32>, Vec<PartRef>, Vec<bool>) {
        let mut out_start = Vec::with_capacity(start.len());
        let mut out = Vec::with_capacity(flat.len());
        let mut covers = Vec::with_capacity(start.len().saturating_sub(1));
        out_start.push(0u32);
        for (c, w) in start.windows(2).enumerate() {
            let list = &flat[w[0] as usize..w[1] as usize];
            let (cx, cy) = ((c % self.nx) as f64, (c / self.nx) as f64);
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(dx, dy)| self.origin + Vec2::new(cx + dx, cy + dy) * self.cell_m);
            let covering = list.iter().rposition(|&(i, j)| {
                let part = &patches[i as usize][j as usize];
                corners
                    .iter()
                    .all(|&q| part.signed_distance(q) <= -COVER_MARGIN_M)
            });
            covers.push(covering.is_some());
            out.extend_from_slice(&list[covering.unwrap_or(0)..]);
            out_start.push(out.len() as u32);
        }
        (out_start, out, covers)
    }

    /// Per cell, in the order given, the parts whose box widened by `grow` meets it:
    /// `(start, flat)` with cell `c`'s parts at `flat[start[c]..start[c + 1]]`.
    fn lists(
        &self,
        items: &mut dyn Iterator<Item = (PartRef, Rect)>,
        grow: f64,
    ) -> (Vec<u32>, Vec<PartRef>) {
        let mut per_cell: Vec<Vec<PartRef>> = vec![Vec::new(); self.nx * self.ny];
        for (r, b) in items {
            let (x0, y0) = self.cell_xy(Vec2::new(b.min[0] - grow, b.min[1] - grow));
            let (x1, y1) = self.cell_xy(Vec2::new(b.max[0] + grow, b.max[1] + grow));
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    per_cell[cy * self.nx + cx].push(r);
                }
            }
        }
        let mut start = Vec::with_capacity(per_cell.len() + 1);
        let mut flat = Vec::new();
        start.push(0u32);
        for l in per_cell {
            flat.extend(l);
            start.push(flat.len() as u32);
        }
        (start, flat)
    }

    /// The cell of `p`, clamped to the grid.
    fn cell_xy(&self, p: Vec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell_m;
        let cx = (q.x.max(0.0) as usize).min(self.nx - 1);
        let cy = (q.y.max(0.0) as usize).min(self.ny - 1);
        (cx, cy)
    }

    /// The cell holding `p`, `None` outside the grid (or for a non-finite `p`).
    #[inline]
    fn cell(&self, p: Vec2) -> Option<usize> {
        let q = (p - self.origin) * self.per_cell_m;
        // False for NaN, and always for the empty grid (nx_f = 0).
        if !(q.x >= 0.0 && q.y >= 0.0 && q.x < self.nx_f && q.y < self.ny_f) {
            return None;
        }
        Some(q.y as usize * self.nx + q.x as usize)
    }

    /// The largest reach of moving item `i`'s parts from its frame's origin (m).
    pub(super) fn dynamic_reach_m(&self, i: usize) -> f64 {
        self.dynamic_reach_m[i]
    }

    /// The static obstacle parts that may be within [`INDEX_REACH_M`] of `p`, in
    /// file order; `None` when `p` is outside the grid (ask every part).
    #[inline]
    pub(super) fn obstacles_near(&self, p: Vec2) -> Option<&[PartRef]> {
        self.obstacles_near_clear(p).map(|(_, parts)| parts)
    }

    /// As [`obstacles_near`](Self::obstacles_near), with a lower bound of the
    /// distance from `p` to every static obstacle part (m, at most
    /// [`INDEX_REACH_M`]).
    #[inline]
    pub(super) fn obstacles_near_clear(&self, p: Vec2) -> Option<(f64, &[PartRef])> {
        let c = self.cell(p)?;
        let (a, b) = (self.obstacle_start[c], self.obstacle_start[c + 1]);
        Some((
            self.obstacle_clear_m[c],
            &self.obstacle_parts[a as usize..b as usize],
        ))
    }

    /// The static patch parts that may contain `p`, in file order, and whether the
    /// first of them surely contains it (it covers `p`'s cell; the parts it
    /// overrides are left out); `None` when `p` is outside the grid (ask every
    /// part).
    #[inline]
    pub(super) fn patches_at(&self, p: Vec2) -> Option<(bool, &[PartRef])> {
        let c = self.cell(p)?;
        let (a, b) = (self.patch_start[c], self.patch_start[c + 1]);
        Some((
            self.patch_covers[c],
            &self.patch_parts[a as usize..b as usize],
        ))
    }
}

/// Every part of `items` (each item's parts) with its reference and bounding box.
fn part_boxes<'a>(
    items: impl Iterator<Item = &'a [Part]> + 'a,
) -> impl Iterator<Item = (PartRef, Rect)> + 'a {
    items.enumerate().flat_map(|(i, parts)| {
        parts
            .iter()
            .enumerate()
            .map(move |(j, p)| ((i as u32, j as u32), p.aabb()))
    })
}
