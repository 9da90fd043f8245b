//! What the engine keeps to publish its scene (`scene_view.rs` fills it).

use super::pool::ArcPool;
use crate::vocab::ScenePoses;

/// What the engine keeps to publish its scene.
pub(super) struct SceneOut {
    /// The scene changed since it was last published (true at start).
    pub(super) changed: bool,
    /// Recycled poses.
    pub(super) poses: ArcPool<ScenePoses>,
}

impl SceneOut {
    pub(super) fn new() -> SceneOut {
        SceneOut {
            changed: true,
            poses: ArcPool::new(),
        }
    }
}
