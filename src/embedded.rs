//! Data compiled into the binary: the shipped recordings and scenes, so `demo` and the
//! embedded default config work from any directory and on a machine with no touchscreen.

use crate::crowd::environment::{Scene, SceneError};

use crate::input::recording::{
    parse_recording, read_recording, OnBadFrame, Recording, RecordingError,
};
use std::path::Path;

/// The shipped recordings (`config/recordings/`), by file name.
pub const RECORDINGS: [(&str, &str); 7] = [
    (
        "01-point-drag.jsonl",
        include_str!("../config/recordings/01-point-drag.jsonl"),
    ),
    (
        "02-line-drag.jsonl",
        include_str!("../config/recordings/02-line-drag.jsonl"),
    ),
    (
        "03-line-pinch.jsonl",
        include_str!("../config/recordings/03-line-pinch.jsonl"),
    ),
    (
        "04-area-drag.jsonl",
        include_str!("../config/recordings/04-area-drag.jsonl"),
    ),
    (
        "05-area-twist.jsonl",
        include_str!("../config/recordings/05-area-twist.jsonl"),
    ),
    (
        "06-two-hands.jsonl",
        include_str!("../config/recordings/06-two-hands.jsonl"),
    ),
    (
        "07-open-space-swipe.jsonl",
        include_str!("../config/recordings/07-open-space-swipe.jsonl"),
    ),
];

/// Reads a recording from disk, or — when no such file exists and its name is one of
/// the shipped recordings — from the copy compiled into the binary.
///
/// # Errors
/// The reader's error for the file (or the embedded copy).
pub fn load_recording(path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    if !path.exists() {
        if let Some(name) = path.file_name().and_then(|n| n.to_str()) {
            if let Some((_, text)) = RECORDINGS.iter().find(|(n, _)| *n == name) {
                return parse_recording(text, path, on_bad);
            }
        }
    }
    read_recording(path, on_bad)
}

/// The shipped scenes (`config/scenes/`), by file name.
pub const SCENES: [(&str, &str); 7] = [
    (
        "corridor.ron",
        include_str!("../config/scenes/corridor.ron"),
    ),
    (
        "four_blocks.ron",
        include_str!("../config/scenes/four_blocks.ron"),
    ),
    (
        "multiple_paths.ron",
        include_str!("../config/scenes/multiple_paths.ron"),
    ),
    (
        "obstacle_course.ron",
        include_str!("../config/scenes/obstacle_course.ron"),
    ),
    (
        "single_block.ron",
        include_str!("../config/scenes/single_block.ron"),
    ),
    ("street.ron", include_str!("../config/scenes/street.ron")),
    (
        "woodland.ron",
        include_str!("../config/scenes/woodland.ron"),
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
