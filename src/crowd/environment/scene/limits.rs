//! The limits and tolerances a scene is validated against.

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
