//! The library the daemon ships with: `config/gestures/library.ctgl`, embedded in
//! the binary like the scenes and read with [`read_library`] at start.
//!
//! The file is built from the crowd simulator's motions and the gesture generator
//! (`gesture::synth`) by `crowdtouch library build` (`crowd::motion::build_library`
//! with its default parameters); `tests/gesture_library.rs` checks that the
//! committed file is exactly what the build gives.

use super::error::LibraryError;
use super::format::read_library;
use super::model::Library;

/// The shipped library's file name, under `config/gestures/`, as errors name it.
pub const SHIPPED_NAME: &str = "library.ctgl";

/// The shipped library's bytes.
pub const SHIPPED_BYTES: &[u8] = include_bytes!("../../../config/gestures/library.ctgl");

/// Reads the shipped library from its bytes, naming it [`SHIPPED_NAME`], under
/// [`LoadPolicy::Complete`](super::LoadPolicy::Complete).
///
/// # Errors
/// As [`read_library`]: a shipped file that is corrupt, empty or missing a class.
pub fn shipped_from(bytes: &[u8]) -> Result<Library, LibraryError> {
    read_library(bytes, SHIPPED_NAME)
}

/// The shipped library ([`SHIPPED_BYTES`]).
///
/// # Errors
/// As [`shipped_from`] (a test keeps the shipped file valid).
pub fn shipped() -> Result<Library, LibraryError> {
    shipped_from(SHIPPED_BYTES)
}
