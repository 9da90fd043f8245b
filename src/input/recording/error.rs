//! What goes wrong reading a recording, and what a reader does about a bad frame.

use std::fmt;
use std::path::{Path, PathBuf};

/// What a reader does with a bad frame.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum OnBadFrame {
    /// Fail with [`RecordingError::Parse`].
    #[default]
    Stop,
    /// Skip the frame and record a [`RecordingIssue`](super::RecordingIssue).
    Skip,
}

/// Why a well-formed recording cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UnsupportedReason {
    /// The device has no `ABS_MT_POSITION_X/Y` axes.
    NoMultiTouch,
    /// A format version this reader does not know.
    Version {
        /// Format name.
        format: &'static str,
        /// Version found.
        version: i64,
    },
}

impl fmt::Display for UnsupportedReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UnsupportedReason::NoMultiTouch => write!(
                f,
                "the device has no multi-touch axes (ABS_MT_POSITION_X/Y); single-touch \
                 devices are not supported"
            ),
            UnsupportedReason::Version { format, version } => {
                write!(f, "{format} version {version} is not supported")
            }
        }
    }
}

/// Why a recording could not be read.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_RECORDING_BYTES`](super::MAX_RECORDING_BYTES).
    #[error("{}: {size} bytes is more than the {limit}-byte limit for a recording", path.display())]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Size found (at least; reading stops past the limit).
        size: u64,
        /// The limit.
        limit: u64,
    },
    /// Malformed content.
    #[error("{}:{line}: {}", path.display(), crate::located::Escaped(message))]
    Parse {
        /// File.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong, and in which field; it may quote the file (the message
        /// escapes control characters).
        message: String,
    },
    /// Not a format this module reads.
    #[error(
        "{}: unknown recording format (starts with `{}`); expected crowdtouch JSON \
         Lines, evemu, libinput record YAML or hid-recorder",
        path.display(), crate::located::Escaped(found)
    )]
    UnknownFormat {
        /// File.
        path: PathBuf,
        /// The start of the first meaningful line, as read (the message escapes its
        /// control characters: a file must not drive the terminal).
        found: String,
    },
    /// Well-formed, but describes something not supported.
    #[error("{}: {reason}", path.display())]
    Unsupported {
        /// File.
        path: PathBuf,
        /// Why.
        reason: UnsupportedReason,
    },
    /// No frame at all.
    #[error("{}: the recording holds no frame", path.display())]
    Empty {
        /// File.
        path: PathBuf,
    },
}

impl RecordingError {
    /// A [`RecordingError::Parse`] at `line` of `path`: what every reader reports.
    pub fn parse(path: &Path, line: usize, message: impl Into<String>) -> RecordingError {
        RecordingError::Parse {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }
}
