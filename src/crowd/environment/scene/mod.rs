//! The scene: world bounds, obstacles, travel-speed patches, moving things and
//! formation checkpoints, loaded from strict RON and validated.
//!
//! The model follows mesh-formation-control (Henry, Shum, Komura 2014): obstacles are
//! convex, a concave obstacle is a union of convex parts, and separate obstacles are
//! at least one agent diameter apart (section 5) so the control mesh cannot get stuck;
//! patches carry a motion type and a travel speed factor (section 6.2.3, Table 1);
//! checkpoints switch the crowd's formation when it passes over them (section 7.3).
//!
//! # File format
//! ```ron
//! (
//!     version: 1,
//!     name: "one tree",
//!     bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
//!     obstacles: [
//!         (name: "tree", parts: [Circle(centre_m: (4.0, 4.5), radius_m: 0.4)]),
//!         (name: "L wall", parts: [
//!             Polygon(vertices_m: [(8.0, 2.0), (9.0, 2.0), (9.0, 7.0), (8.0, 7.0)]),
//!             Polygon(vertices_m: [(8.0, 6.0), (12.0, 6.0), (12.0, 7.0), (8.0, 7.0)]),
//!         ]),
//!     ],
//!     patches: [
//!         (name: "pond", motion: swim, parts: [Circle(centre_m: (13.0, 3.0), radius_m: 1.0)]),
//!         (name: "low fence", motion: jump, motion_length_m: Some(1.0),
//!          parts: [Polygon(vertices_m: [(2.0, 1.0), (2.4, 1.0), (2.4, 3.0), (2.0, 3.0)])]),
//!     ],
//!     dynamic: [
//!         (name: "car", kind: Obstacle,
//!          parts: [Polygon(vertices_m: [(-1.0, -0.5), (1.0, -0.5), (1.0, 0.5), (-1.0, 0.5)])],
//!          path: (waypoints_m: [(2.0, 8.0), (14.0, 8.0)], speed_m_s: 2.0, mode: ping_pong)),
//!     ],
//!     checkpoints: [
//!         (name: "gate", formation: "arrow",
//!          region: Polygon(vertices_m: [(6.0, 0.5), (7.0, 0.5), (7.0, 2.0), (6.0, 2.0)])),
//!     ],
//! )
//! ```
//!
//! # What is an error
//! Every problem is reported (not just the first), with file, line, column and the
//! dotted field path (`obstacles[2].parts[0].vertices_m`):
//! * a `version` other than [`SCENE_VERSION`], an unknown field, a syntax error;
//! * a non-finite number anywhere; bounds with `min >= max`;
//! * a polygon with fewer than 3 or more than [`MAX_POLYGON_VERTICES`] vertices, with
//!   (near) zero area ([`MIN_POLYGON_AREA_M2`]), with a repeated vertex, or not
//!   convex (exact `orient2d`: some vertex strictly outside an edge); a circle with a
//!   radius ≤ 0;
//! * an obstacle, patch or checkpoint not entirely inside the bounds; a dynamic thing
//!   whose parts leave the bounds at some waypoint;
//! * parts of two different static obstacles that overlap, or whose gap is less than
//!   one agent diameter (`2 × agent_radius_m`, the validation parameter);
//! * a patch speed factor ≤ 0 or above [`MAX_SPEED_FACTOR`]; a path speed ≤ 0;
//! * a single-step patch (jump, climb up, climb down) without `motion_length_m`, or
//!   whose smallest width exceeds it (section 6.2.3: its length is limited to the
//!   length of the motion's trajectory); `motion_length_m` on a cyclic motion;
//! * a path with fewer than 2 waypoints or no length; an empty checkpoint formation;
//! * more than [`MAX_SCENE_ITEMS`] obstacles, patches, dynamic things or checkpoints.
//!
//! # What is allowed
//! * Parts of the same obstacle overlap freely (that is how a concave obstacle is
//!   built); polygons in either orientation; collinear vertices on an edge.
//! * Obstacles touching or lying along the world bounds.
//! * Patches overlapping each other (the last one in the file wins, dynamic patches
//!   over static ones) and overlapping obstacles (the obstacle wins: blocked).
//! * Dynamic obstacles crossing static ones or each other: their gaps are not checked,
//!   only their bounds.
//!
//! Nothing here panics on any input, reads a clock, or touches a file except
//! [`Scene::load`].

use crate::geom::{Rect, Vec2};
use crate::located::{self, format_issues, Issue, Located, ReadError};
use crate::vocab::MotionType;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

pub mod grid;
pub mod shape;
mod shipped;
#[cfg(test)]
mod tests;

pub use grid::{GridError, SceneGrid};
pub use shape::{BoundaryPoint, Circle, ConvexPolygon, Part, Placement};
pub use shipped::{load_scene, SCENES};

/// The scene format version this build reads.
pub const SCENE_VERSION: u32 = 1;
/// Largest scene file read (bytes).
pub const MAX_SCENE_BYTES: u64 = 4 << 20;
/// Most obstacles, patches, dynamic things or checkpoints (each).
pub const MAX_SCENE_ITEMS: usize = 4096;
/// Most parts in one obstacle, patch or dynamic thing.
pub const MAX_PARTS: usize = 64;
/// Most vertices in one polygon (validation is quadratic in it).
pub const MAX_POLYGON_VERTICES: usize = 256;
/// Most waypoints on one path.
pub const MAX_WAYPOINTS: usize = 1024;
/// A polygon smaller than this is degenerate (m²).
pub const MIN_POLYGON_AREA_M2: f64 = 1e-9;
/// A path shorter than this does not move (m).
pub const MIN_PATH_LENGTH_M: f64 = 1e-6;
/// Largest travel speed factor a patch may have (moving walkways are faster than
/// running, Table 1's jump is 1.24).
pub const MAX_SPEED_FACTOR: f64 = 10.0;
/// Slack when comparing a patch width with its motion length, and a part with the
/// bounds (m).
pub const LENGTH_TOLERANCE_M: f64 = 1e-9;
/// Agent radius used when no config says otherwise (m), as `crowd.agent_radius_m`
/// in `config/crowdtouch.ron`.
pub const DEFAULT_AGENT_RADIUS_M: f64 = 0.15;
/// A point counts as projected out once it is this close to its margin (m).
pub const PROJECT_TOLERANCE_M: f64 = 1e-9;
/// Rounds of "push out of the deepest part" before the ring search in
/// [`Scene::project_out`].
pub const MAX_PROJECT_ROUNDS: usize = 16;
/// Smallest ring step of the fallback search in [`Scene::project_out`] (m).
pub const MIN_RING_STEP_M: f64 = 0.02;

// ---------------------------------------------------------------------------
// File format (serde)

/// A point in the file, `(x, y)` in metres.
pub type PointM = [f64; 2];

fn v(p: PointM) -> Vec2 {
    Vec2::new(p[0], p[1])
}

/// One convex piece as written in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum PartDef {
    /// A convex polygon, either orientation.
    Polygon {
        /// Vertices (m), in order around the polygon.
        vertices_m: Vec<PointM>,
    },
    /// A disc.
    Circle {
        /// Centre (m).
        centre_m: PointM,
        /// Radius (m).
        radius_m: f64,
    },
}

/// A static obstacle: the union of its convex parts (one part for a convex one).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleDef {
    /// Name, shown in messages.
    #[serde(default)]
    pub name: String,
    /// Convex parts; they may overlap each other.
    pub parts: Vec<PartDef>,
}

/// A travel-speed patch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchDef {
    /// Name, shown in messages.
    #[serde(default)]
    pub name: String,
    /// What agents do inside.
    pub motion: MotionType,
    /// Travel speed relative to running; `None` takes Table 1's value.
    #[serde(default)]
    pub speed_factor: Option<f64>,
    /// Length of a single-step motion's trajectory (m): required for jump and climb,
    /// not allowed otherwise.
    #[serde(default)]
    pub motion_length_m: Option<f64>,
    /// Convex parts (their union is the patch).
    pub parts: Vec<PartDef>,
}

/// How a path repeats.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathMode {
    /// Last waypoint back to the first, and round again.
    Looped,
    /// There and back along the same waypoints.
    PingPong,
}

/// A path through waypoints at a constant speed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathDef {
    /// Waypoints (m), at least two.
    pub waypoints_m: Vec<PointM>,
    /// Speed along the path (m/s).
    pub speed_m_s: f64,
    /// Looped or ping-pong.
    pub mode: PathMode,
    /// Time already travelled at t = 0 (s): staggers things on the same path.
    #[serde(default)]
    pub start_s: f64,
    /// Turn the parts to face the direction of travel (the part frame's +x is
    /// forward); otherwise they only translate.
    #[serde(default)]
    pub rotate: bool,
}

/// What a moving thing is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum DynamicKindDef {
    /// Impassable.
    Obstacle,
    /// A moving travel-speed patch (a raft, a moving walkway).
    Patch {
        /// Motion inside.
        motion: MotionType,
        /// Speed factor; `None` takes Table 1's value.
        #[serde(default)]
        speed_factor: Option<f64>,
        /// As for [`PatchDef::motion_length_m`].
        #[serde(default)]
        motion_length_m: Option<f64>,
    },
}

/// An obstacle or patch moving along a path.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicDef {
    /// Name, shown in messages.
    #[serde(default)]
    pub name: String,
    /// Obstacle or patch.
    pub kind: DynamicKindDef,
    /// Convex parts in the thing's own frame: its origin follows the path.
    pub parts: Vec<PartDef>,
    /// The path.
    pub path: PathDef,
}

/// A formation checkpoint (mesh-formation-control section 7.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointDef {
    /// Name, shown in messages.
    #[serde(default)]
    pub name: String,
    /// The region the crowd's centroid must enter.
    pub region: PartDef,
    /// Name of the formation to switch to.
    pub formation: String,
}

/// A scene file as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Format version; must be [`SCENE_VERSION`].
    pub version: u32,
    /// Scene name.
    #[serde(default)]
    pub name: String,
    /// World rectangle (m).
    pub bounds_m: Rect,
    /// Static obstacles.
    #[serde(default)]
    pub obstacles: Vec<ObstacleDef>,
    /// Static travel-speed patches.
    #[serde(default)]
    pub patches: Vec<PatchDef>,
    /// Moving obstacles and patches.
    #[serde(default)]
    pub dynamic: Vec<DynamicDef>,
    /// Formation checkpoints.
    #[serde(default)]
    pub checkpoints: Vec<CheckpointDef>,
}

// ---------------------------------------------------------------------------
// Errors

/// What is wrong with one field of a scene.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// The text does not parse as a scene (syntax, unknown or missing field, type).
    #[error("{message}")]
    Syntax {
        /// The parser's message.
        message: String,
    },
    /// Unsupported format version.
    #[error("version {found} is not supported (this build reads version {SCENE_VERSION})")]
    UnsupportedVersion {
        /// The version in the file.
        found: u32,
    },
    /// A NaN or infinite number.
    #[error("numbers must be finite")]
    NonFinite,
    /// Bounds with `min >= max` on an axis.
    #[error("bounds must have min < max on both axes")]
    EmptyBounds,
    /// Too few polygon vertices.
    #[error("a polygon needs at least 3 vertices, got {count}")]
    TooFewVertices {
        /// Vertices given.
        count: usize,
    },
    /// More than a limit of something.
    #[error("at most {max} {what}, got {count}")]
    TooMany {
        /// What is counted.
        what: &'static str,
        /// How many there are.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// A polygon with (near) zero area.
    #[error("polygon has zero area ({area_m2:e} m²); its vertices are collinear or repeated")]
    ZeroArea {
        /// Its area (m²).
        area_m2: f64,
    },
    /// A polygon that is not convex.
    #[error("polygon is not convex at vertex {vertex} (split a concave shape into convex parts)")]
    NonConvex {
        /// Index of the offending vertex (repeated, or outside an edge).
        vertex: usize,
    },
    /// A circle radius ≤ 0.
    #[error("radius must be positive, got {radius_m} m")]
    NonPositiveRadius {
        /// The radius (m).
        radius_m: f64,
    },
    /// A speed or speed factor ≤ 0.
    #[error("speed must be positive, got {value}")]
    NonPositiveSpeed {
        /// The value.
        value: f64,
    },
    /// A speed factor above [`MAX_SPEED_FACTOR`].
    #[error("speed factor must be at most {MAX_SPEED_FACTOR}, got {value}")]
    SpeedTooHigh {
        /// The value.
        value: f64,
    },
    /// An obstacle, patch or checkpoint with no parts.
    #[error("needs at least one part")]
    NoParts,
    /// Something not inside the world bounds.
    #[error("lies outside the world bounds")]
    OutsideBounds,
    /// Parts of two different obstacles overlap.
    #[error("overlaps {other} (parts of one obstacle may overlap; separate obstacles may not)")]
    Overlap {
        /// The other obstacle, `obstacles[i] "name"`.
        other: String,
    },
    /// Two obstacles closer than an agent diameter.
    #[error("is {gap_m:.3} m from {other}, less than one agent diameter ({min_gap_m:.3} m)")]
    GapTooSmall {
        /// The other obstacle.
        other: String,
        /// The gap (m).
        gap_m: f64,
        /// The smallest allowed gap (m).
        min_gap_m: f64,
    },
    /// A single-step motion without its motion length.
    #[error(
        "{motion} is a single-step motion: give motion_length_m, the length of its trajectory"
    )]
    MissingMotionLength {
        /// The motion.
        motion: &'static str,
    },
    /// A motion length on a cyclic motion.
    #[error("motion_length_m applies only to jump, climb_up and climb_down, not {motion}")]
    MotionLengthNotApplicable {
        /// The motion.
        motion: &'static str,
    },
    /// A motion length ≤ 0.
    #[error("motion length must be positive, got {value} m")]
    NonPositiveMotionLength {
        /// The value (m).
        value: f64,
    },
    /// A single-step patch longer than its motion.
    #[error("patch is {width_m:.3} m across at its narrowest, longer than its motion ({motion_length_m:.3} m): the motion would play more than once")]
    PatchLongerThanMotion {
        /// Smallest width of the part (m).
        width_m: f64,
        /// The motion length (m).
        motion_length_m: f64,
    },
    /// A path that does not go anywhere.
    #[error("a path needs at least 2 waypoints and a positive length")]
    PathTooShort,
    /// A checkpoint naming no formation.
    #[error("formation name is empty")]
    EmptyFormation,
    /// A checkpoint naming a formation the config does not define.
    #[error("no formation is called `{name}`; the config defines {known}")]
    UnknownFormation {
        /// The name.
        name: String,
        /// The names there are, comma-separated.
        known: String,
    },
}

/// One problem, located in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneIssue {
    /// Dotted field path (`obstacles[1].parts[0].vertices_m`), empty when unknown.
    pub field: String,
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub column: usize,
    /// What is wrong.
    pub problem: Problem,
}

/// Why a scene could not be used.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read scene: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_SCENE_BYTES`].
    #[error("{path}: scene is {size} bytes, more than the {max} byte limit")]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
    /// The scene is invalid; every problem found is listed, one per line, as
    /// `file:line:col: field: what`.
    #[error("{}", format_issues(.path, .issues))]
    Invalid {
        /// File (or `<text>`).
        path: PathBuf,
        /// Problems, in file order.
        issues: Vec<SceneIssue>,
    },
}

impl Located for SceneIssue {
    fn line(&self) -> usize {
        self.line
    }
    fn column(&self) -> usize {
        self.column
    }
    fn fmt_what(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl fmt::Display for SceneIssue {
    /// `field: what` (the place is added by [`SceneError`]).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}", self.problem)
        } else {
            write!(f, "{}: {}", self.field, self.problem)
        }
    }
}

// ---------------------------------------------------------------------------
// The validated scene

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
    fn new(def: &PathDef) -> MotionPath {
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

    /// Whether the parts turn with the path.
    pub fn rotates(&self) -> bool {
        self.rotate
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

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    name: String,
    bounds: Rect,
    obstacles: Vec<Obstacle>,
    patches: Vec<Patch>,
    dynamic: Vec<Dynamic>,
    checkpoints: Vec<Checkpoint>,
}

/// Collects `(field, problem)` pairs during validation.
struct Problems(Vec<(String, Problem)>);

impl Problems {
    fn push(&mut self, field: impl Into<String>, p: Problem) {
        self.0.push((field.into(), p));
    }
}

fn finite2(p: PointM) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// Validates one part; `Some(part)` when it is usable.
fn build_part(def: &PartDef, field: &str, out: &mut Problems) -> Option<Part> {
    match def {
        PartDef::Polygon { vertices_m } => {
            let f = format!("{field}.vertices_m");
            if vertices_m.len() < 3 {
                out.push(
                    f,
                    Problem::TooFewVertices {
                        count: vertices_m.len(),
                    },
                );
                return None;
            }
            if vertices_m.len() > MAX_POLYGON_VERTICES {
                out.push(
                    f,
                    Problem::TooMany {
                        what: "polygon vertices",
                        count: vertices_m.len(),
                        max: MAX_POLYGON_VERTICES,
                    },
                );
                return None;
            }
            if !vertices_m.iter().all(|&p| finite2(p)) {
                out.push(f, Problem::NonFinite);
                return None;
            }
            let mut pts: Vec<Vec2> = vertices_m.iter().map(|&p| v(p)).collect();
            let twice = shape::signed_twice_area(&pts);
            let area_m2 = 0.5 * twice.abs();
            if area_m2.is_nan() || area_m2 < MIN_POLYGON_AREA_M2 {
                out.push(f, Problem::ZeroArea { area_m2 });
                return None;
            }
            let reversed = twice < 0.0;
            if reversed {
                pts.reverse();
            }
            if let Some(k) = shape::non_convex_vertex(&pts) {
                let vertex = if reversed { pts.len() - 1 - k } else { k };
                out.push(f, Problem::NonConvex { vertex });
                return None;
            }
            match ConvexPolygon::new(pts) {
                Some(p) => Some(Part::Polygon(p)),
                None => {
                    out.push(f, Problem::NonConvex { vertex: 0 });
                    None
                }
            }
        }
        PartDef::Circle { centre_m, radius_m } => {
            if !finite2(*centre_m) {
                out.push(format!("{field}.centre_m"), Problem::NonFinite);
                return None;
            }
            if !radius_m.is_finite() {
                out.push(format!("{field}.radius_m"), Problem::NonFinite);
                return None;
            }
            if *radius_m <= 0.0 {
                out.push(
                    format!("{field}.radius_m"),
                    Problem::NonPositiveRadius {
                        radius_m: *radius_m,
                    },
                );
                return None;
            }
            Some(Part::Circle(Circle {
                centre: v(*centre_m),
                radius_m: *radius_m,
            }))
        }
    }
}

/// The field to report a whole-part problem on (its first field).
fn part_field(def: &PartDef, field: &str) -> String {
    match def {
        PartDef::Polygon { .. } => format!("{field}.vertices_m"),
        PartDef::Circle { .. } => format!("{field}.centre_m"),
    }
}

fn inside_bounds(r: &Rect, b: &Rect) -> bool {
    let t = LENGTH_TOLERANCE_M;
    r.min[0] >= b.min[0] - t
        && r.min[1] >= b.min[1] - t
        && r.max[0] <= b.max[0] + t
        && r.max[1] <= b.max[1] + t
}

fn build_parts(
    defs: &[PartDef],
    field: &str,
    bounds: Option<&Rect>,
    out: &mut Problems,
) -> Vec<Part> {
    if defs.is_empty() {
        out.push(format!("{field}.parts"), Problem::NoParts);
    }
    if defs.len() > MAX_PARTS {
        out.push(
            format!("{field}.parts"),
            Problem::TooMany {
                what: "parts",
                count: defs.len(),
                max: MAX_PARTS,
            },
        );
        return Vec::new();
    }
    let mut parts = Vec::with_capacity(defs.len());
    for (j, d) in defs.iter().enumerate() {
        let pf = format!("{field}.parts[{j}]");
        if let Some(p) = build_part(d, &pf, out) {
            if let Some(b) = bounds {
                if !inside_bounds(&p.aabb(), b) {
                    out.push(part_field(d, &pf), Problem::OutsideBounds);
                }
            }
            parts.push(p);
        }
    }
    parts
}

fn build_terrain(
    motion: MotionType,
    speed_factor: Option<f64>,
    motion_length_m: Option<f64>,
    field: &str,
    out: &mut Problems,
) -> (Terrain, Option<f64>) {
    let speed = speed_factor.unwrap_or_else(|| motion.default_speed_factor());
    let sf = format!("{field}.speed_factor");
    if !speed.is_finite() {
        out.push(sf, Problem::NonFinite);
    } else if speed <= 0.0 {
        out.push(sf, Problem::NonPositiveSpeed { value: speed });
    } else if speed > MAX_SPEED_FACTOR {
        out.push(sf, Problem::SpeedTooHigh { value: speed });
    }
    let lf = format!("{field}.motion_length_m");
    match (motion.is_single_step(), motion_length_m) {
        (true, None) => out.push(
            format!("{field}.motion"),
            Problem::MissingMotionLength {
                motion: motion.as_str(),
            },
        ),
        (false, Some(_)) => out.push(
            lf,
            Problem::MotionLengthNotApplicable {
                motion: motion.as_str(),
            },
        ),
        (true, Some(l)) if !l.is_finite() => out.push(lf, Problem::NonFinite),
        (true, Some(l)) if l <= 0.0 => out.push(lf, Problem::NonPositiveMotionLength { value: l }),
        _ => {}
    }
    (
        Terrain {
            motion,
            speed_factor: speed,
        },
        motion_length_m,
    )
}

fn check_motion_length(
    parts: &[Part],
    defs: &[PartDef],
    len: Option<f64>,
    field: &str,
    out: &mut Problems,
) {
    let Some(l) = len.filter(|l| l.is_finite() && *l > 0.0) else {
        return;
    };
    for (j, (p, d)) in parts.iter().zip(defs).enumerate() {
        let w = p.min_width_m();
        if w > l + LENGTH_TOLERANCE_M {
            out.push(
                part_field(d, &format!("{field}.parts[{j}]")),
                Problem::PatchLongerThanMotion {
                    width_m: w,
                    motion_length_m: l,
                },
            );
        }
    }
}

fn describe(i: usize, name: &str) -> String {
    if name.is_empty() {
        format!("obstacles[{i}]")
    } else {
        format!("obstacles[{i}] {name:?}")
    }
}

impl Scene {
    /// Reads and validates a scene file (size-capped at [`MAX_SCENE_BYTES`]).
    /// `agent_radius_m` sets the smallest gap between obstacles (one diameter).
    ///
    /// # Errors
    /// [`SceneError::Io`], [`SceneError::TooLarge`] or [`SceneError::Invalid`] with
    /// every problem.
    pub fn load(path: &Path, agent_radius_m: f64) -> Result<Scene, SceneError> {
        let text = located::read_capped(path, MAX_SCENE_BYTES).map_err(|e| match e {
            ReadError::TooLarge { path, size, max } => SceneError::TooLarge { path, size, max },
            ReadError::Io { path, source } => SceneError::Io { path, source },
        })?;
        Scene::from_str(&text, path, agent_radius_m)
    }

    /// Parses and validates scene text; `path` is used in messages only.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] listing every problem with line, column and field.
    #[allow(clippy::should_implement_trait)]
    pub fn from_str(text: &str, path: &Path, agent_radius_m: f64) -> Result<Scene, SceneError> {
        let file: SceneFile =
            located::parse_strict(text).map_err(|i: Issue| SceneError::Invalid {
                path: path.to_path_buf(),
                issues: vec![SceneIssue {
                    field: i.field,
                    line: i.line,
                    column: i.column,
                    problem: Problem::Syntax { message: i.message },
                }],
            })?;
        let scene = Scene::from_file(&file, agent_radius_m).map_err(|problems| {
            let mut issues: Vec<SceneIssue> = problems
                .into_iter()
                .map(|(field, problem)| {
                    let (line, column) = located::locate_field(text, &field).unwrap_or((0, 0));
                    SceneIssue {
                        field,
                        line,
                        column,
                        problem,
                    }
                })
                .collect();
            issues.sort_by_key(|i| (i.line, i.column));
            SceneError::Invalid {
                path: path.to_path_buf(),
                issues,
            }
        });
        let mut scene = scene?;
        for (i, c) in scene.checkpoints.iter_mut().enumerate() {
            c.formation_at = located::locate_field(text, &format!("checkpoints[{i}].formation"))
                .unwrap_or((0, 0));
        }
        Ok(scene)
    }

    /// Checks that every checkpoint names one of the `known` formations (`start` and
    /// the formation library's names, as `FormationLibrary::known_names` lists them);
    /// `path` is the scene file, for messages.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] with a [`Problem::UnknownFormation`] per checkpoint
    /// that names an unknown one, at its `formation` field.
    pub fn check_formations(&self, path: &Path, known: &[&str]) -> Result<(), SceneError> {
        let issues: Vec<SceneIssue> = self
            .checkpoints
            .iter()
            .enumerate()
            .filter(|(_, c)| !known.contains(&c.formation.as_str()))
            .map(|(i, c)| SceneIssue {
                field: format!("checkpoints[{i}].formation"),
                line: c.formation_at.0,
                column: c.formation_at.1,
                problem: Problem::UnknownFormation {
                    name: c.formation.clone(),
                    known: known.join(", "),
                },
            })
            .collect();
        if issues.is_empty() {
            Ok(())
        } else {
            Err(SceneError::Invalid {
                path: path.to_path_buf(),
                issues,
            })
        }
    }

    /// Validates a parsed scene. A non-finite or non-positive `agent_radius_m` is
    /// taken as [`DEFAULT_AGENT_RADIUS_M`].
    ///
    /// # Errors
    /// Every `(field path, problem)` found.
    pub fn from_file(f: &SceneFile, agent_radius_m: f64) -> Result<Scene, Vec<(String, Problem)>> {
        let radius = if agent_radius_m.is_finite() && agent_radius_m > 0.0 {
            agent_radius_m
        } else {
            DEFAULT_AGENT_RADIUS_M
        };
        let min_gap_m = 2.0 * radius;
        let mut out = Problems(Vec::new());
        if f.version != SCENE_VERSION {
            out.push("version", Problem::UnsupportedVersion { found: f.version });
        }
        let b = f.bounds_m;
        let bounds_ok = if !(finite2(b.min) && finite2(b.max)) {
            out.push("bounds_m", Problem::NonFinite);
            false
        } else if !(b.min[0] < b.max[0] && b.min[1] < b.max[1]) {
            out.push("bounds_m", Problem::EmptyBounds);
            false
        } else {
            true
        };
        let bounds = bounds_ok.then_some(&b);
        for (what, count) in [
            ("obstacles", f.obstacles.len()),
            ("patches", f.patches.len()),
            ("dynamic", f.dynamic.len()),
            ("checkpoints", f.checkpoints.len()),
        ] {
            if count > MAX_SCENE_ITEMS {
                out.push(
                    what,
                    Problem::TooMany {
                        what,
                        count,
                        max: MAX_SCENE_ITEMS,
                    },
                );
            }
        }
        if !out.0.is_empty() && f.obstacles.len().max(f.patches.len()) > MAX_SCENE_ITEMS {
            return Err(out.0);
        }

        let obstacles: Vec<Obstacle> = f
            .obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| Obstacle {
                name: o.name.clone(),
                parts: build_parts(&o.parts, &format!("obstacles[{i}]"), bounds, &mut out),
            })
            .collect();
        // Separate obstacles: no overlap, gap at least one agent diameter (section 5).
        let boxes: Vec<Vec<Rect>> = obstacles
            .iter()
            .map(|o| o.parts.iter().map(Part::aabb).collect())
            .collect();
        let near = |a: &Rect, b: &Rect| {
            a.min[0] <= b.max[0] + min_gap_m
                && b.min[0] <= a.max[0] + min_gap_m
                && a.min[1] <= b.max[1] + min_gap_m
                && b.min[1] <= a.max[1] + min_gap_m
        };
        for i in 0..obstacles.len() {
            for k in 0..i {
                let mut worst: Option<Problem> = None;
                'pairs: for (pi, p) in obstacles[i].parts.iter().enumerate() {
                    for (pk, q) in obstacles[k].parts.iter().enumerate() {
                        if !near(&boxes[i][pi], &boxes[k][pk]) {
                            continue;
                        }
                        let other = describe(k, &obstacles[k].name);
                        if p.overlaps(q) {
                            worst = Some(Problem::Overlap { other });
                            break 'pairs;
                        }
                        let gap_m = p.gap_m(q);
                        if gap_m < min_gap_m - LENGTH_TOLERANCE_M {
                            let better = match &worst {
                                Some(Problem::GapTooSmall { gap_m: g, .. }) => gap_m < *g,
                                _ => true,
                            };
                            if better {
                                worst = Some(Problem::GapTooSmall {
                                    other,
                                    gap_m,
                                    min_gap_m,
                                });
                            }
                        }
                    }
                }
                if let Some(p) = worst {
                    out.push(format!("obstacles[{i}].parts"), p);
                }
            }
        }

        let patches: Vec<Patch> = f
            .patches
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let field = format!("patches[{i}]");
                let parts = build_parts(&p.parts, &field, bounds, &mut out);
                let (terrain, motion_length_m) = build_terrain(
                    p.motion,
                    p.speed_factor,
                    p.motion_length_m,
                    &field,
                    &mut out,
                );
                if parts.len() == p.parts.len() {
                    check_motion_length(&parts, &p.parts, motion_length_m, &field, &mut out);
                }
                Patch {
                    name: p.name.clone(),
                    terrain,
                    motion_length_m,
                    parts,
                }
            })
            .collect();

        let dynamic: Vec<Dynamic> = f
            .dynamic
            .iter()
            .enumerate()
            .map(|(i, d)| build_dynamic(i, d, bounds, &mut out))
            .collect();

        let checkpoints: Vec<Checkpoint> = f
            .checkpoints
            .iter()
            .enumerate()
            .filter_map(|(i, c)| {
                let field = format!("checkpoints[{i}]");
                if c.formation.trim().is_empty() {
                    out.push(format!("{field}.formation"), Problem::EmptyFormation);
                }
                let rf = format!("{field}.region");
                let region = build_part(&c.region, &rf, &mut out)?;
                if let Some(b) = bounds {
                    if !inside_bounds(&region.aabb(), b) {
                        out.push(part_field(&c.region, &rf), Problem::OutsideBounds);
                    }
                }
                Some(Checkpoint {
                    name: c.name.clone(),
                    region,
                    formation: c.formation.clone(),
                    formation_at: (0, 0),
                })
            })
            .collect();

        if out.0.is_empty() {
            Ok(Scene {
                name: f.name.clone(),
                bounds: b,
                obstacles,
                patches,
                dynamic,
                checkpoints,
            })
        } else {
            Err(out.0)
        }
    }

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

    /// Invariant checker for tests: every part is valid, every polygon convex and
    /// counter-clockwise, every speed factor in range.
    ///
    /// # Errors
    /// A description of the first broken invariant.
    pub fn sanity_check(&self) -> Result<(), String> {
        let all_parts = self
            .obstacles
            .iter()
            .flat_map(|o| o.parts.iter())
            .chain(self.patches.iter().flat_map(|p| p.parts.iter()))
            .chain(self.dynamic.iter().flat_map(|d| d.parts.iter()))
            .chain(self.checkpoints.iter().map(|c| &c.region));
        for part in all_parts {
            match part {
                Part::Polygon(p) => {
                    if shape::signed_twice_area(p.vertices()) <= 0.0 {
                        return Err("polygon not counter-clockwise".into());
                    }
                    if shape::non_convex_vertex(p.vertices()).is_some() {
                        return Err("polygon not convex".into());
                    }
                }
                Part::Circle(c) => {
                    if c.radius_m.is_nan() || c.radius_m <= 0.0 {
                        return Err("circle radius not positive".into());
                    }
                }
            }
        }
        for p in &self.patches {
            let s = p.terrain.speed_factor;
            if !(s > 0.0 && s <= MAX_SPEED_FACTOR) {
                return Err(format!("patch speed factor {s} out of range"));
            }
        }
        Ok(())
    }
}

fn build_dynamic(i: usize, d: &DynamicDef, bounds: Option<&Rect>, out: &mut Problems) -> Dynamic {
    let field = format!("dynamic[{i}]");
    let parts = build_parts(&d.parts, &field, None, out);
    let kind = match d.kind {
        DynamicKindDef::Obstacle => DynamicKind::Obstacle,
        DynamicKindDef::Patch {
            motion,
            speed_factor,
            motion_length_m,
        } => {
            let kf = format!("{field}.kind");
            let (terrain, len) = build_terrain(motion, speed_factor, motion_length_m, &kf, out);
            if parts.len() == d.parts.len() {
                check_motion_length(&parts, &d.parts, len, &field, out);
            }
            DynamicKind::Patch(terrain)
        }
    };
    let pf = format!("{field}.path");
    let p = &d.path;
    let mut path_ok = true;
    if p.waypoints_m.len() > MAX_WAYPOINTS {
        out.push(
            format!("{pf}.waypoints_m"),
            Problem::TooMany {
                what: "waypoints",
                count: p.waypoints_m.len(),
                max: MAX_WAYPOINTS,
            },
        );
        path_ok = false;
    } else if !p.waypoints_m.iter().all(|&w| finite2(w)) {
        out.push(format!("{pf}.waypoints_m"), Problem::NonFinite);
        path_ok = false;
    } else {
        let len: f64 = p
            .waypoints_m
            .windows(2)
            .map(|w| (v(w[1]) - v(w[0])).norm())
            .sum();
        if p.waypoints_m.len() < 2 || len.is_nan() || len < MIN_PATH_LENGTH_M {
            out.push(format!("{pf}.waypoints_m"), Problem::PathTooShort);
            path_ok = false;
        }
    }
    if !p.speed_m_s.is_finite() || !p.start_s.is_finite() {
        let f = if p.speed_m_s.is_finite() {
            "start_s"
        } else {
            "speed_m_s"
        };
        out.push(format!("{pf}.{f}"), Problem::NonFinite);
        path_ok = false;
    } else if p.speed_m_s <= 0.0 {
        out.push(
            format!("{pf}.speed_m_s"),
            Problem::NonPositiveSpeed { value: p.speed_m_s },
        );
    }
    // Inside the bounds at every waypoint; between waypoints too, by convexity of
    // the bounds (a rotating thing is checked by its reach in every direction).
    if let (Some(b), true) = (bounds, path_ok && parts.len() == d.parts.len()) {
        let outside = p.waypoints_m.iter().any(|&w| {
            let w = v(w);
            parts.iter().any(|part| {
                let r = if p.rotate {
                    let reach = part.reach_m();
                    Rect {
                        min: [w.x - reach, w.y - reach],
                        max: [w.x + reach, w.y + reach],
                    }
                } else {
                    let a = part.aabb();
                    Rect {
                        min: [a.min[0] + w.x, a.min[1] + w.y],
                        max: [a.max[0] + w.x, a.max[1] + w.y],
                    }
                };
                !inside_bounds(&r, b)
            })
        });
        if outside {
            out.push(format!("{pf}.waypoints_m"), Problem::OutsideBounds);
        }
    }
    Dynamic {
        name: d.name.clone(),
        kind,
        parts,
        path: MotionPath::new(p),
    }
}
