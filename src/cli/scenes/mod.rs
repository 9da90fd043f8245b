//! Scenes and formations: `scene check`, `scene render`, `formations`.

pub mod formations;
pub mod scene;
pub mod scene_render;
