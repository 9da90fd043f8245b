//! Crowd motion editing on track files: `edit check`, `edit apply`, `edit path`,
//! the edit pictures.

pub mod edit;
pub mod edit_apply;
pub mod edit_check;
pub mod edit_path;
pub mod edit_render;
pub mod edit_render_layers;
pub mod edit_render_legend;
pub mod edit_render_svg;
pub mod track_file;
