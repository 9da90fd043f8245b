//! The shipped scenes (`config/scenes/`), compiled into the binary so a config can
//! name them from any directory.

use super::model::Scene;
use super::problem::SceneError;
use std::path::Path;

/// The shipped scenes (`config/scenes/`), by file name.
pub const SCENES: [(&str, &str); 7] = [
    (
        "corridor.ron",
        include_str!("../../../../config/scenes/corridor.ron"),
    ),
    (
        "four_blocks.ron",
        include_str!("../../../../config/scenes/four_blocks.ron"),
    ),
    (
        "multiple_paths.ron",
        include_str!("../../../../config/scenes/multiple_paths.ron"),
    ),
    (
        "obstacle_course.ron",
        include_str!("../../../../config/scenes/obstacle_course.ron"),
    ),
    (
        "single_block.ron",
        include_str!("../../../../config/scenes/single_block.ron"),
    ),
    (
        "street.ron",
        include_str!("../../../../config/scenes/street.ron"),
    ),
    (
        "woodland.ron",
        include_str!("../../../../config/scenes/woodland.ron"),
    ),
];

/// Reads and validates a scene from disk, or — when no such file exists and its name
/// is one of the shipped scenes — from the copy compiled into the binary.
/// `agent_radius_m` as in [`Scene::load`].
///
/// # Errors
/// The scene's [`SceneError`] for the file (or the embedded copy).
pub fn load_scene(path: &Path, agent_radius_m: f64) -> Result<Scene, SceneError> {
    if !path.exists() {
        if let Some(name) = path.file_name().and_then(|n| n.to_str()) {
            if let Some((_, text)) = SCENES.iter().find(|(n, _)| *n == name) {
                return Scene::from_str(text, path, agent_radius_m);
            }
        }
    }
    Scene::load(path, agent_radius_m)
}
