//! The scene as published: its obstacles, travel-speed patches, moving things and
//! checkpoints (`scene`, when the scene changes), and where the moving things are
//! (`scene_poses`, every tick while any move), to clients subscribed to `scene`.
//!
//! Plain data in world metres (parts of moving things in their own frame, placed by
//! their pose: `world = position + R(heading) · local`).

use super::motion::MotionType;
use crate::geom::{Rect, Vec2};

/// One convex piece of an obstacle, patch or checkpoint.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeView {
    /// A convex polygon, counter-clockwise (m).
    Polygon(Vec<Vec2>),
    /// A disc.
    Circle {
        /// Centre (m).
        centre: Vec2,
        /// Radius (m).
        radius_m: f64,
    },
}

/// The ground inside a patch (mesh-formation-control section 6.2.3, Table 1).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TerrainView {
    /// What agents do there.
    pub motion: MotionType,
    /// Travel speed relative to running.
    pub speed_factor: f64,
}

/// An obstacle or a patch: its name, its parts, and for a patch its ground.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneItemView {
    /// Name from the scene file (may be empty).
    pub name: String,
    /// `None` for an obstacle.
    pub terrain: Option<TerrainView>,
    /// Convex parts: world frame for static things, the thing's own frame for moving ones.
    pub parts: Vec<ShapeView>,
}

/// A formation checkpoint (mesh-formation-control section 7.3).
#[derive(Clone, Debug, PartialEq)]
pub struct CheckpointView {
    /// Name.
    pub name: String,
    /// The formation the crowd switches to when its centroid enters the region.
    pub formation: String,
    /// The region (world frame).
    pub region: ShapeView,
}

/// The scene in use (or none), published when it changes.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneView {
    /// Tick sequence number when this scene took effect.
    pub seq: u64,
    /// The scene's name; `None` when the daemon runs without a scene.
    pub name: Option<String>,
    /// The scene's bounds (m); the world rectangle when there is no scene.
    pub bounds: Rect,
    /// Static obstacles.
    pub obstacles: Vec<SceneItemView>,
    /// Static travel-speed patches.
    pub patches: Vec<SceneItemView>,
    /// Moving obstacles and patches (parts in their own frame); their poses come in
    /// [`ScenePoses`], in this order.
    pub dynamic: Vec<SceneItemView>,
    /// Formation checkpoints.
    pub checkpoints: Vec<CheckpointView>,
}

/// Where the scene's moving things are at one tick (recycled by the engine).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScenePoses {
    /// Tick sequence number (as in the snapshot).
    pub seq: u64,
    /// Scene time (s): what the moving things' paths are evaluated at.
    pub t_s: f64,
    /// Per moving thing, in [`SceneView::dynamic`]'s order: position (m) and
    /// heading (rad, counter-clockwise from +x) of its frame.
    pub poses: Vec<(Vec2, f64)>,
}
