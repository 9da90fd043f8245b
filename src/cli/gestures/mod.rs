//! Gestures and the gesture library: `gesture`, `library` (build, new, import,
//! add, remove, show, eval, test sets, collect).

pub mod classes;
pub mod gesture;
pub mod library;
pub mod library_build;
pub mod library_collect;
pub mod library_edit;
pub mod library_eval;
pub mod library_file;
