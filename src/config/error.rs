//! Why a config could not be used, or could not be edited.

pub use crate::located::Issue as ConfigIssue;
use crate::located::{format_issues, ReadError};
use std::path::PathBuf;

/// Why a config could not be used.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be read.
    #[error("{path}: cannot read config: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_CONFIG_BYTES`](crate::config::MAX_CONFIG_BYTES).
    #[error("{path}: config is {size} bytes, more than the {max} byte limit")]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
    /// The file is not a regular file, grew past the cap, is not UTF-8 text, or its
    /// read was stopped.
    #[error("cannot read config: {0}")]
    Unreadable(ReadError),
    /// The text is not a valid config; every problem found is listed.
    #[error("{}", format_issues(.path, .issues))]
    Invalid {
        /// File (or `<embedded>` / `<text>`).
        path: PathBuf,
        /// Problems, in file order.
        issues: Vec<ConfigIssue>,
    },
}

impl From<ReadError> for Error {
    fn from(e: ReadError) -> Error {
        match e {
            ReadError::Io { path, source } => Error::Io { path, source },
            ReadError::TooLarge { path, size, max } => Error::TooLarge { path, size, max },
            e => Error::Unreadable(e),
        }
    }
}

/// Why [`set_calibration_matrix`](crate::config::set_calibration_matrix) could not
/// write a matrix into config text.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// The text given is not a valid config; the message is the config's own.
    #[error(transparent)]
    InvalidText(Error),
    /// Input `input` is missing or is not a `Device` input.
    #[error("inputs[{input}] is not a Device input")]
    NotDevice {
        /// Index in `inputs`.
        input: usize,
    },
    /// The text cannot be edited safely: `reason` says what was not found where
    /// it should be (no `:` after `matrix`, no `(` after `Some`, unbalanced
    /// brackets, …).
    #[error("{reason}")]
    CannotEdit {
        /// What was missing, as printed.
        reason: &'static str,
    },
    /// The edited text is not a valid config (it is not returned). The config's
    /// message is part of this one, so it is not also given as the source.
    #[error("the edited config is invalid: {0}")]
    InvalidResult(Error),
}
