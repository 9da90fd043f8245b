//! Why a picture could not be made, and the exit code it maps to.

/// Why a picture could not be made.
#[derive(Debug, PartialEq)]
pub enum RenderError {
    /// A bad argument (exit code 2).
    Usage(String),
    /// A bad scene file or an output that cannot be written (exit code 1).
    Failed(String),
}
