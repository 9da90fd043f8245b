//! The crowd's environment (mesh-formation-control sections 5 and 6.2): the scene
//! (obstacles, travel-speed patches, moving things, checkpoints), the potential field
//! that pushes the mesh off obstacles, fast marching ([`eikonal`]) and the planner
//! that assigns goals by travel cost and routes agents around obstacles.

pub mod eikonal;
mod planner;
mod potential;
mod scene;

pub use planner::{
    steer_target, PlanError, Planner, PlannerParams, DEFAULT_DENSITY_REFRESH_S,
    DEFAULT_PLAN_CELL_M, DEFAULT_TIE_BREAK_S_PER_M2, MAX_ROUTE_STEPS,
};
pub use potential::{
    displace_vertices, field_at, magnitude, part_field, FieldError, FieldGrid, FieldParams,
    CENTRE_EPSILON_M, MESH_FIELD_RANGE_M,
};
pub use scene::{
    load_scene, BoundaryPoint, Checkpoint, CheckpointDef, Circle, ConvexPolygon, Dynamic,
    DynamicDef, DynamicKind, DynamicKindDef, GridError, MotionPath, Obstacle, ObstacleDef,
    ObstacleHit, ObstacleId, Part, PartDef, Patch, PatchDef, PathDef, PathMode, Placement, PointM,
    Pose, Problem, Scene, SceneAt, SceneError, SceneFile, SceneGrid, SceneIssue, Terrain,
    DEFAULT_AGENT_RADIUS_M, LENGTH_TOLERANCE_M, MAX_GRID_CELLS, MAX_PARTS, MAX_POLYGON_VERTICES,
    MAX_PROJECT_ROUNDS, MAX_SCENE_BYTES, MAX_SCENE_ITEMS, MAX_SPEED_FACTOR, MAX_WAYPOINTS,
    MIN_PATH_LENGTH_M, MIN_POLYGON_AREA_M2, MIN_RING_STEP_M, PROJECT_TOLERANCE_M, SCENES,
    SCENE_VERSION, TOUCH_TOLERANCE_M,
};
