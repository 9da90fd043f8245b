//! Geometry queries on a scene at time `t_s`: which obstacle holds a point, the
//! nearest boundary, signed distance, projection out of obstacles, segment hits and
//! visibility, the terrain under a point, checkpoint crossings, rasterisation.

use super::grid::SceneGrid;
use super::model::{Checkpoint, DynamicKind, Scene, Terrain};
use super::shape::{BoundaryPoint, Part, Placement};
use crate::geom::Vec2;

/// A point counts as projected out once it is this close to its margin (m).
pub const PROJECT_TOLERANCE_M: f64 = 1e-9;
/// Rounds of "push out of the deepest part" before the ring search in
/// [`Scene::project_out`].
pub const MAX_PROJECT_ROUNDS: usize = 16;
/// Smallest ring step of the fallback search in [`Scene::project_out`] (m).
pub const MIN_RING_STEP_M: f64 = 0.02;

/// Which obstacle a query found.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ObstacleId {
    /// `obstacles[i]`.
    Static(usize),
    /// `dynamic[i]` (an obstacle kind).
    Dynamic(usize),
}

/// The nearest obstacle boundary to a point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ObstacleHit {
    /// Which obstacle.
    pub id: ObstacleId,
    /// Index of the part within it.
    pub part: usize,
    /// Nearest boundary point, outward normal and signed distance (world frame).
    pub boundary: BoundaryPoint,
}

impl Scene {
    /// Calls `f(id, part index, part, placement)` for every obstacle part at time
    /// `t_s`: static ones at the identity placement, dynamic obstacles where their
    /// path puts them.
    pub fn for_each_obstacle_part(
        &self,
        t_s: f64,
        mut f: impl FnMut(ObstacleId, usize, &Part, &Placement),
    ) {
        for (i, o) in self.obstacles.iter().enumerate() {
            for (j, p) in o.parts.iter().enumerate() {
                f(ObstacleId::Static(i), j, p, &Placement::IDENTITY);
            }
        }
        for (i, d) in self.dynamic.iter().enumerate() {
            if d.kind == DynamicKind::Obstacle {
                let pl = d.placement_at(t_s);
                for (j, p) in d.parts.iter().enumerate() {
                    f(ObstacleId::Dynamic(i), j, p, &pl);
                }
            }
        }
    }

    /// The obstacle containing `p` at `t_s` (boundary included), if any.
    pub fn obstacle_at(&self, p: Vec2, t_s: f64) -> Option<ObstacleId> {
        let mut found = None;
        self.for_each_obstacle_part(t_s, |id, _, part, pl| {
            if found.is_none() && part.contains(pl.to_local(p)) {
                found = Some(id);
            }
        });
        found
    }

    /// The nearest obstacle boundary to `p` at `t_s`: the part with the smallest
    /// signed distance (the deepest one when `p` is inside several). `None` when
    /// the scene has no obstacles.
    ///
    /// # Units
    /// Metres.
    pub fn nearest_obstacle(&self, p: Vec2, t_s: f64) -> Option<ObstacleHit> {
        let mut best: Option<ObstacleHit> = None;
        self.for_each_obstacle_part(t_s, |id, j, part, pl| {
            let b = part.boundary_point(pl.to_local(p));
            if best.is_none_or(|h| b.signed_distance_m < h.boundary.signed_distance_m) {
                best = Some(ObstacleHit {
                    id,
                    part: j,
                    boundary: BoundaryPoint {
                        point: pl.to_world(b.point),
                        normal: pl.rotate(b.normal),
                        signed_distance_m: b.signed_distance_m,
                    },
                });
            }
        });
        best
    }

    /// Signed distance from `p` to the obstacles at `t_s` (m): the minimum over all
    /// parts, negative inside one, `f64::INFINITY` with no obstacles. Exact outside
    /// the obstacles; inside a union of overlapping parts it is the depth in the
    /// deepest part.
    pub fn signed_distance(&self, p: Vec2, t_s: f64) -> f64 {
        let mut d = f64::INFINITY;
        self.for_each_obstacle_part(t_s, |_, _, part, pl| {
            d = d.min(part.signed_distance(pl.to_local(p)));
        });
        d
    }

    /// Moves `p` to a nearby point at least `margin_m` from every obstacle at
    /// `t_s`; a point already that far is returned unchanged.
    ///
    /// Pushes the point out of the deepest part to the part's boundary plus the
    /// margin, a few rounds (one round for a point in one convex obstacle: the
    /// nearest free point); when rounds bounce between overlapping or close parts, it
    /// searches rings of growing radius around `p` for the nearest free point. A
    /// negative or non-finite margin is taken as zero; a non-finite `p` is returned
    /// as it is.
    ///
    /// # Units
    /// Metres.
    pub fn project_out(&self, p: Vec2, margin_m: f64, t_s: f64) -> Vec2 {
        let margin = if margin_m.is_finite() {
            margin_m.max(0.0)
        } else {
            0.0
        };
        if !(p.x.is_finite() && p.y.is_finite()) {
            return p;
        }
        let free = |q: Vec2| self.signed_distance(q, t_s) >= margin - PROJECT_TOLERANCE_M;
        let mut q = p;
        for _ in 0..MAX_PROJECT_ROUNDS {
            let Some(hit) = self.nearest_obstacle(q, t_s) else {
                return q;
            };
            if hit.boundary.signed_distance_m >= margin - PROJECT_TOLERANCE_M {
                return q;
            }
            q = hit.boundary.point + hit.boundary.normal * margin;
        }
        if free(q) {
            return q;
        }
        // Ring search around p, nearest ring first.
        let step = margin.max(MIN_RING_STEP_M);
        let diag = self.bounds.width().hypot(self.bounds.height()) + 2.0 * margin;
        let rings = ((diag / step).ceil() as usize).clamp(1, 100_000);
        const DIRECTIONS: usize = 64;
        let (mut best, mut best_d) = (q, self.signed_distance(q, t_s));
        for k in 1..=rings {
            let r = k as f64 * step;
            for j in 0..DIRECTIONS {
                let a = std::f64::consts::TAU * j as f64 / DIRECTIONS as f64;
                let c = p + Vec2::new(a.cos(), a.sin()) * r;
                let d = self.signed_distance(c, t_s);
                if d >= margin - PROJECT_TOLERANCE_M {
                    return c;
                }
                if d > best_d {
                    (best, best_d) = (c, d);
                }
            }
        }
        best
    }

    /// The first obstacle the segment `a`–`b` meets at `t_s`, with the entry
    /// parameter `s ∈ [0, 1]` (the point `a + s·(b − a)`); `s = 0` when `a` is inside.
    pub fn segment_hit(&self, a: Vec2, b: Vec2, t_s: f64) -> Option<(f64, ObstacleId)> {
        let mut best: Option<(f64, ObstacleId)> = None;
        self.for_each_obstacle_part(t_s, |id, _, part, pl| {
            if let Some(s) = part.segment_entry(pl.to_local(a), pl.to_local(b)) {
                if best.is_none_or(|(bs, _)| s < bs) {
                    best = Some((s, id));
                }
            }
        });
        best
    }

    /// Whether `b` is visible from `a` at `t_s` (no obstacle on the segment).
    pub fn visible(&self, a: Vec2, b: Vec2, t_s: f64) -> bool {
        self.segment_hit(a, b, t_s).is_none()
    }

    /// The terrain under `p` at `t_s`: the last static patch containing it, overridden
    /// by the last dynamic patch containing it, else open ground
    /// ([`Terrain::OPEN`]). Obstacles are not consulted (see
    /// [`obstacle_at`](Self::obstacle_at)).
    pub fn terrain_at(&self, p: Vec2, t_s: f64) -> Terrain {
        let mut t = Terrain::OPEN;
        for patch in &self.patches {
            if patch.parts.iter().any(|part| part.contains(p)) {
                t = patch.terrain;
            }
        }
        for d in &self.dynamic {
            if let DynamicKind::Patch(terrain) = d.kind {
                let pl = d.placement_at(t_s);
                let local = pl.to_local(p);
                if d.parts.iter().any(|part| part.contains(local)) {
                    t = terrain;
                }
            }
        }
        t
    }

    /// The checkpoints the crowd passed between two ticks, in file order (see
    /// [`Checkpoint::crossed`]).
    pub fn crossed_checkpoints(
        &self,
        prev_centroid: Vec2,
        centroid: Vec2,
    ) -> impl Iterator<Item = &Checkpoint> + '_ {
        self.checkpoints
            .iter()
            .filter(move |c| c.crossed(prev_centroid, centroid))
    }

    /// Rasterises the scene at `t_s` into `grid`, reusing its buffers (see
    /// [`SceneGrid`]).
    pub fn rasterize_into(&self, grid: &mut SceneGrid, t_s: f64) {
        grid.fill(self, t_s);
    }
}
