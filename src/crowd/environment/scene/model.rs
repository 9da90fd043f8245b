//! The validated scene: obstacles, travel-speed patches, things moving along their
//! paths, formation checkpoints.

use super::file::{v, PathDef, PathMode};
use super::index::PartIndex;
use super::shape::{Part, Placement};
use crate::geom::{Rect, Vec2};
use crate::vocab::MotionType;

/// A static obstacle.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    /// Name.
    pub name: String,
    /// Convex parts (world frame).
    pub parts: Vec<Part>,
}

/// The terrain at a point: what agents do there and how fast they go.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Terrain {
    /// Motion type.
    pub motion: MotionType,
    /// Travel speed relative to running (dimensionless, > 0).
    pub speed_factor: f64,
}

impl Terrain {
    /// Open ground: run at full speed.
    pub const OPEN: Terrain = Terrain {
        motion: MotionType::Run,
        speed_factor: 1.0,
    };
}

/// A static travel-speed patch.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// Name.
    pub name: String,
    /// Motion and speed inside.
    pub terrain: Terrain,
    /// Trajectory length of a single-step motion (m).
    pub motion_length_m: Option<f64>,
    /// Convex parts (world frame).
    pub parts: Vec<Part>,
}

/// What a moving thing is, validated.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum DynamicKind {
    /// Impassable.
    Obstacle,
    /// A moving patch.
    Patch(Terrain),
}

/// Position and heading of a moving thing at some time.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Pose {
    /// Position of the thing's frame origin (m).
    pub position: Vec2,
    /// Direction of travel (rad, counter-clockwise from +x).
    pub heading_rad: f64,
}

/// A validated path: waypoints with their cumulative arc length.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionPath {
    waypoints: Vec<Vec2>,
    /// Arc length at each waypoint of the traversal (the looped closing segment or
    /// the way back included), m.
    cumulative_m: Vec<f64>,
    speed_m_s: f64,
    mode: PathMode,
    start_s: f64,
    rotate: bool,
}

impl MotionPath {
    pub(super) fn new(def: &PathDef) -> MotionPath {
        let mut pts: Vec<Vec2> = def.waypoints_m.iter().map(|&p| v(p)).collect();
        match def.mode {
            PathMode::Looped => {
                if let Some(&first) = pts.first() {
                    pts.push(first);
                }
            }
            PathMode::PingPong => {
                let back: Vec<Vec2> = pts.iter().rev().skip(1).copied().collect();
                pts.extend(back);
            }
        }
        let mut cumulative_m = Vec::with_capacity(pts.len());
        let mut s = 0.0;
        for (i, p) in pts.iter().enumerate() {
            if i > 0 {
                s += (p - pts[i - 1]).norm();
            }
            cumulative_m.push(s);
        }
        MotionPath {
            waypoints: pts,
            cumulative_m,
            speed_m_s: def.speed_m_s,
            mode: def.mode,
            start_s: def.start_s,
            rotate: def.rotate,
        }
    }

    /// The traversal's waypoints (closing point or return trip included), m.
    pub fn points(&self) -> &[Vec2] {
        &self.waypoints
    }

    /// Length of one full traversal (m).
    pub fn period_m(&self) -> f64 {
        self.cumulative_m.last().copied().unwrap_or(0.0)
    }

    /// Looped or ping-pong.
    pub fn mode(&self) -> PathMode {
        self.mode
    }

    /// The pose at time `t_s`: a pure function of time, no clock is read.
    ///
    /// # Formula
    /// `s = (speed · (t + start)) mod period`, then linear interpolation between the
    /// waypoints bracketing arc length `s`; the heading is that segment's direction.
    ///
    /// # Units
    /// `t_s` in seconds; position in metres; heading in radians.
    ///
    /// A non-finite `t_s` gives the pose at the path's start.
    pub fn at(&self, t_s: f64) -> Pose {
        let period = self.period_m();
        let start = Pose {
            position: self.waypoints.first().copied().unwrap_or_else(Vec2::zeros),
            heading_rad: 0.0,
        };
        if period.is_nan() || period <= 0.0 || self.waypoints.len() < 2 {
            return start;
        }
        let raw = self.speed_m_s * (t_s + self.start_s);
        let s = if raw.is_finite() {
            raw.rem_euclid(period)
        } else {
            0.0
        };
        // First segment whose end is past s (skipping zero-length segments).
        let i = self
            .cumulative_m
            .partition_point(|&c| c <= s)
            .clamp(1, self.waypoints.len() - 1);
        let (a, b) = (self.waypoints[i - 1], self.waypoints[i]);
        let (ca, cb) = (self.cumulative_m[i - 1], self.cumulative_m[i]);
        let f = if cb > ca {
            ((s - ca) / (cb - ca)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = b - a;
        Pose {
            position: a + d * f,
            heading_rad: if d.norm_squared() > 0.0 {
                d.y.atan2(d.x)
            } else {
                0.0
            },
        }
    }
}

/// A moving obstacle or patch.
#[derive(Clone, Debug, PartialEq)]
pub struct Dynamic {
    /// Name.
    pub name: String,
    /// Obstacle or patch.
    pub kind: DynamicKind,
    /// Convex parts in the thing's own frame.
    pub parts: Vec<Part>,
    /// Its path.
    pub path: MotionPath,
}

impl Dynamic {
    /// Where the parts are at `t_s`.
    pub fn placement_at(&self, t_s: f64) -> Placement {
        let pose = self.path.at(t_s);
        Placement::new(
            pose.position,
            if self.path.rotate {
                pose.heading_rad
            } else {
                0.0
            },
        )
    }

    /// The pose at `t_s` (see [`MotionPath::at`]).
    pub fn at(&self, t_s: f64) -> Pose {
        self.path.at(t_s)
    }
}

/// A formation checkpoint (mesh-formation-control section 7.3).
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// Name.
    pub name: String,
    /// The region (world frame).
    pub region: Part,
    /// Formation to switch to.
    pub formation: String,
    /// Line and column of `formation` in the scene file (0 when unknown).
    pub formation_at: (usize, usize),
}

impl Checkpoint {
    /// Whether the crowd passed over this checkpoint between two ticks: the centroid
    /// was outside the region and the segment from `prev_centroid` to `centroid`
    /// enters it (so a fast crowd cannot jump over a thin checkpoint). Staying
    /// inside does not trigger again.
    pub fn crossed(&self, prev_centroid: Vec2, centroid: Vec2) -> bool {
        !self.region.contains(prev_centroid)
            && self.region.segment_entry(prev_centroid, centroid).is_some()
    }
}

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub(super) name: String,
    pub(super) bounds: Rect,
    pub(super) obstacles: Vec<Obstacle>,
    pub(super) patches: Vec<Patch>,
    pub(super) dynamic: Vec<Dynamic>,
    pub(super) checkpoints: Vec<Checkpoint>,
    /// The static parts by grid cell, for the per-agent queries.
    pub(super) index: PartIndex,
}

impl Scene {
    /// Scene name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// World bounds (m).
    pub fn bounds(&self) -> Rect {
        self.bounds
    }
    /// Static obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }
    /// Static patches.
    pub fn patches(&self) -> &[Patch] {
        &self.patches
    }
    /// Moving obstacles and patches.
    pub fn dynamic(&self) -> &[Dynamic] {
        &self.dynamic
    }
    /// Formation checkpoints.
    pub fn checkpoints(&self) -> &[Checkpoint] {
        &self.checkpoints
    }
}
