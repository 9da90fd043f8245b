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

mod file;
mod grid;
mod index;
mod limits;
mod load;
mod model;
mod problem;
mod query;
mod sanity;
mod shape;
mod shipped;
#[cfg(test)]
mod tests;
mod validate;

pub use file::{
    CheckpointDef, DynamicDef, DynamicKindDef, ObstacleDef, PartDef, PatchDef, PathDef, PathMode,
    PointM, SceneFile, SCENE_VERSION,
};
pub use grid::{GridError, SceneGrid, MAX_GRID_CELLS};
pub use limits::{
    DEFAULT_AGENT_RADIUS_M, LENGTH_TOLERANCE_M, MAX_PARTS, MAX_POLYGON_VERTICES, MAX_SCENE_BYTES,
    MAX_SCENE_ITEMS, MAX_SPEED_FACTOR, MAX_WAYPOINTS, MIN_PATH_LENGTH_M, MIN_POLYGON_AREA_M2,
};
pub use model::{
    Checkpoint, Dynamic, DynamicKind, MotionPath, Obstacle, Patch, Pose, Scene, Terrain,
};
pub use problem::{Problem, SceneError, SceneIssue};
pub use query::{
    ObstacleHit, ObstacleId, SceneAt, MAX_PROJECT_ROUNDS, MIN_RING_STEP_M, PROJECT_TOLERANCE_M,
};
pub use shape::{BoundaryPoint, Circle, ConvexPolygon, Part, Placement, TOUCH_TOLERANCE_M};
pub use shipped::{load_scene, SCENES};
