//! Reading a whole recording into memory, for tools and tests: the frames of a
//! [`RecordingStream`] collected into a [`Recording`]. Replays stream instead.

use super::error::{OnBadFrame, RecordingError};
use super::recording_type::Recording;
use super::stream::RecordingStream;
use std::path::Path;

/// Largest recording file [`read_recording`] accepts, in bytes (64 MiB).
///
/// Only the readers that hold a whole recording in memory have a limit: a
/// [`RecordingStream`] (what replays use) reads files of any length in memory
/// that does not depend on it.
pub const MAX_RECORDING_BYTES: u64 = 64 * 1024 * 1024;

/// Reads and decodes a recording file, detecting its format.
///
/// Every frame is kept (about 2.3 KB each): tools and tests use this; replays
/// use a [`RecordingStream`].
///
/// # Errors
/// [`RecordingError`]: I/O, size over [`MAX_RECORDING_BYTES`], text that is not
/// UTF-8, and everything [`parse_recording`] reports.
pub fn read_recording(path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.len() > MAX_RECORDING_BYTES {
            return Err(RecordingError::TooLarge {
                path: path.to_path_buf(),
                size: meta.len(),
                limit: MAX_RECORDING_BYTES,
            });
        }
    }
    RecordingStream::open(path, on_bad)?.collect(Some(MAX_RECORDING_BYTES))
}

/// Decodes a recording held in memory; `name` is used in errors.
///
/// # Errors
/// [`RecordingError::Parse`] (with [`OnBadFrame::Stop`]), `UnknownFormat`,
/// `Unsupported` (no multi-touch axes, unknown version) and `Empty`.
pub fn parse_recording(
    text: &str,
    name: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    RecordingStream::from_bytes(text.as_bytes().to_vec(), name, on_bad)?.collect(None)
}

/// Decodes an evemu event stream whose device header is in a separate description.
///
/// `desc` is the `.desc`/`.prop` text (`N:`/`I:`/`P:`/`B:`/`A:` lines); `events`
/// the `E:` lines. Header lines inside `events` are ignored, the description is
/// authoritative. Line numbers in errors refer to `events`, or to `desc` when the
/// message says "in the device description".
///
/// # Errors
/// As [`parse_recording`].
pub fn read_evemu_with_desc(
    desc: &str,
    events: &str,
    name: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    RecordingStream::evemu_with_desc(desc, events.as_bytes().to_vec(), name, on_bad)?.collect(None)
}

/// Reads a whole recording from disk, or — when no such file exists and its name
/// is one of the shipped recordings — from the copy compiled into the binary
/// ([`RecordingStream::load`] reads it a frame at a time).
///
/// # Errors
/// The reader's error for the file (or the embedded copy).
pub fn load_recording(path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    if path.exists() {
        return read_recording(path, on_bad);
    }
    RecordingStream::load(path, on_bad)?.collect(None)
}
