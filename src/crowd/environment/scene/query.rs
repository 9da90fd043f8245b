//! Geometry queries on a scene at time `t_s`: which obstacle holds a point, the
//! nearest boundary, signed distance, projection out of obstacles, segment hits and
//! visibility, the terrain under a point, checkpoint crossings, rasterisation.

use super::grid::SceneGrid;
use super::index::INDEX_REACH_M;
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

/// A scene at one time, its moving parts placed once: the queries the control
/// thread asks for every agent in a tick, without working out the moving parts'
/// poses for each ([`Scene::at`]). Each answer is the one the [`Scene`] method of
/// the same name gives at that time.
#[derive(Copy, Clone, Debug)]
pub struct SceneAt<'a> {
    scene: &'a Scene,
    t_s: f64,
    placements: &'a [Placement],
}

impl SceneAt<'_> {
    /// [`Scene::closer_than`].
    pub fn closer_than(&self, p: Vec2, margin_m: f64) -> bool {
        self.scene
            .closer_than_with(p, margin_m, |i| self.placements[i])
    }

    /// [`Scene::terrain_at`].
    pub fn terrain_at(&self, p: Vec2) -> Terrain {
        self.scene.terrain_at_with(p, |i| self.placements[i])
    }

    /// [`Scene::visible`].
    pub fn visible(&self, a: Vec2, b: Vec2) -> bool {
        self.scene
            .segment_hit_with(a, b, |i| self.placements[i])
            .is_none()
    }

    /// [`Scene::project_out`] (rare: only for an agent that came too near).
    pub fn project_out(&self, p: Vec2, margin_m: f64) -> Vec2 {
        self.scene.project_out(p, margin_m, self.t_s)
    }
}

impl Scene {
    /// The scene at `t_s` with its moving parts placed into `placements` (a buffer
    /// the caller keeps, so placing allocates nothing once it has grown).
    pub fn at<'a>(&'a self, t_s: f64, placements: &'a mut Vec<Placement>) -> SceneAt<'a> {
        placements.clear();
        placements.extend(self.dynamic.iter().map(|d| d.placement_at(t_s)));
        SceneAt {
            scene: self,
            t_s,
            placements,
        }
    }

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
        let consider = |best: &mut Option<ObstacleHit>,
                        id: ObstacleId,
                        j: usize,
                        part: &Part,
                        pl: &Placement| {
            let b = part.boundary_point(pl.to_local(p));
            if best.is_none_or(|h| b.signed_distance_m < h.boundary.signed_distance_m) {
                *best = Some(ObstacleHit {
                    id,
                    part: j,
                    boundary: BoundaryPoint {
                        point: pl.to_world(b.point),
                        normal: pl.rotate(b.normal),
                        signed_distance_m: b.signed_distance_m,
                    },
                });
            }
        };
        // The static parts near p answer alone when one is nearer than the index's
        // reach: every part within the reach is listed, in file order, so the first
        // nearest part is the one the full scan finds (as in `signed_distance`).
        let indexed = match self.index.obstacles_near(p) {
            Some(near) => {
                for &(o, j) in near {
                    let part = &self.obstacles[o as usize].parts[j as usize];
                    consider(
                        &mut best,
                        ObstacleId::Static(o as usize),
                        j as usize,
                        part,
                        &Placement::IDENTITY,
                    );
                }
                best.is_some_and(|h| h.boundary.signed_distance_m < INDEX_REACH_M)
            }
            None => false,
        };
        if !indexed {
            best = None;
            for (i, o) in self.obstacles.iter().enumerate() {
                for (j, part) in o.parts.iter().enumerate() {
                    consider(
                        &mut best,
                        ObstacleId::Static(i),
                        j,
                        part,
                        &Placement::IDENTITY,
                    );
                }
            }
        }
        for (i, d) in self.dynamic.iter().enumerate() {
            if d.kind == DynamicKind::Obstacle {
                let pl = d.placement_at(t_s);
                for (j, part) in d.parts.iter().enumerate() {
                    consider(&mut best, ObstacleId::Dynamic(i), j, part, &pl);
                }
            }
        }
        best
    }

    /// Signed distance from `p` to the obstacles at `t_s` (m): the minimum over all
    /// parts, negative inside one, `f64::INFINITY` with no obstacles. Exact outside
    /// the obstacles; inside a union of overlapping parts it is the depth in the
    /// deepest part.
    pub fn signed_distance(&self, p: Vec2, t_s: f64) -> f64 {
        let every_static = || {
            let parts = self.obstacles.iter().flat_map(|o| &o.parts);
            parts.fold(f64::INFINITY, |d, part| d.min(part.signed_distance(p)))
        };
        // The parts near p answer alone when one is nearer than the index's reach.
        let mut d = match self.index.obstacles_near(p) {
            Some(near) => {
                let d = near.iter().fold(f64::INFINITY, |d, &(o, j)| {
                    let part = &self.obstacles[o as usize].parts[j as usize];
                    d.min(part.signed_distance(p))
                });
                if d < INDEX_REACH_M {
                    d
                } else {
                    every_static()
                }
            }
            None => every_static(),
        };
        for dy in &self.dynamic {
            if dy.kind == DynamicKind::Obstacle {
                let local = dy.placement_at(t_s).to_local(p);
                for part in &dy.parts {
                    // No point of the part is nearer than |local| − reach.
                    if local.norm() - part.reach_m() < d {
                        d = d.min(part.signed_distance(local));
                    }
                }
            }
        }
        d
    }

    /// Whether `p` is nearer than `margin_m` to an obstacle at `t_s` (inside one
    /// included): `signed_distance(p, t_s) < margin_m`, answered from the parts near
    /// `p` when the margin is within the index's reach (the per-agent test of the
    /// control thread).
    pub fn closer_than(&self, p: Vec2, margin_m: f64, t_s: f64) -> bool {
        self.closer_than_with(p, margin_m, |i| self.dynamic[i].placement_at(t_s))
    }

    fn closer_than_with(
        &self,
        p: Vec2,
        margin_m: f64,
        placement: impl Fn(usize) -> Placement,
    ) -> bool {
        let near = |part: &Part, local: Vec2| part.signed_distance(local) < margin_m;
        let static_hit = match self.index.obstacles_near_clear(p) {
            // Every point of the cell is at least `clear` (> 0) from every static
            // part: outside them all, and not within a margin up to `clear`.
            Some((clear, _)) if clear > 0.0 && margin_m <= clear => false,
            Some((_, list)) if margin_m <= INDEX_REACH_M => list
                .iter()
                .any(|&(o, j)| near(&self.obstacles[o as usize].parts[j as usize], p)),
            _ => self
                .obstacles
                .iter()
                .any(|o| o.parts.iter().any(|part| near(part, p))),
        };
        static_hit
            || self.dynamic.iter().enumerate().any(|(i, dy)| {
                dy.kind == DynamicKind::Obstacle && {
                    let pl = placement(i);
                    // Nearer than the margin needs |p − origin| < reach + margin.
                    let within = self.index.dynamic_reach_m(i) + margin_m.max(0.0);
                    (p - pl.position).norm_squared() < within * within && {
                        let local = pl.to_local(p);
                        dy.parts.iter().any(|part| near(part, local))
                    }
                }
            })
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
        self.segment_hit_with(a, b, |i| self.dynamic[i].placement_at(t_s))
    }

    fn segment_hit_with(
        &self,
        a: Vec2,
        b: Vec2,
        placement: impl Fn(usize) -> Placement,
    ) -> Option<(f64, ObstacleId)> {
        let mut best: Option<(f64, ObstacleId)> = None;
        let mut consider = |id: ObstacleId, part: &Part, pl: &Placement| {
            if let Some(s) = part.segment_entry(pl.to_local(a), pl.to_local(b)) {
                if best.is_none_or(|(bs, _)| s < bs) {
                    best = Some((s, id));
                }
            }
        };
        for (i, o) in self.obstacles.iter().enumerate() {
            for part in &o.parts {
                consider(ObstacleId::Static(i), part, &Placement::IDENTITY);
            }
        }
        for (i, d) in self.dynamic.iter().enumerate() {
            if d.kind == DynamicKind::Obstacle {
                let pl = placement(i);
                for part in &d.parts {
                    consider(ObstacleId::Dynamic(i), part, &pl);
                }
            }
        }
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
        self.terrain_at_with(p, |i| self.dynamic[i].placement_at(t_s))
    }

    /// Whether the terrain changes with time: some patch moves. Without one,
    /// [`terrain_at`](Self::terrain_at) answers a point alike at every time.
    pub fn terrain_moves(&self) -> bool {
        self.dynamic
            .iter()
            .any(|d| matches!(d.kind, DynamicKind::Patch(_)))
    }

    fn terrain_at_with(&self, p: Vec2, placement: impl Fn(usize) -> Placement) -> Terrain {
        let mut t = Terrain::OPEN;
        match self.index.patches_at(p) {
            // In file order, so the last patch containing p wins as below.
            Some((covers, near)) => {
                let mut near = near;
                if let (true, Some((&(i, _), rest))) = (covers, near.split_first()) {
                    t = self.patches[i as usize].terrain;
                    near = rest;
                }
                for &(i, j) in near {
                    let patch = &self.patches[i as usize];
                    if patch.parts[j as usize].contains(p) {
                        t = patch.terrain;
                    }
                }
            }
            None => {
                for patch in &self.patches {
                    if patch.parts.iter().any(|part| part.contains(p)) {
                        t = patch.terrain;
                    }
                }
            }
        }
        for (i, d) in self.dynamic.iter().enumerate() {
            if let DynamicKind::Patch(terrain) = d.kind {
                let pl = placement(i);
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
