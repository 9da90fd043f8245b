//! The scene file as written: the RON model serde reads (format and rules in the
//! scene module's documentation), before any validation.

use crate::geom::{Rect, Vec2};
use crate::vocab::MotionType;
use serde::{Deserialize, Serialize};

/// The scene format version this build reads.
pub const SCENE_VERSION: u32 = 1;

/// A point in the file, `(x, y)` in metres.
pub type PointM = [f64; 2];

/// A file point as a vector.
pub(super) fn v(p: PointM) -> Vec2 {
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
