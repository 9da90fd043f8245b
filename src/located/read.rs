//! Reading the text files people hand the daemon, with a size cap.

use std::path::{Path, PathBuf};

/// Why a text file could not be read. Each file kind wraps it into its own error
/// with its own words (`cannot read config`, `cannot read scene`).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than the cap.
    #[error("{path}: {size} bytes, more than the {max} byte limit")]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
}

/// Reads a text file (config, scene, ...) of at most `max_bytes` bytes.
///
/// # Errors
/// [`ReadError::Io`] when it cannot be read, [`ReadError::TooLarge`] past the cap.
pub fn read_capped(path: &Path, max_bytes: u64) -> Result<String, ReadError> {
    let meta = std::fs::metadata(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if meta.len() > max_bytes {
        return Err(ReadError::TooLarge {
            path: path.to_path_buf(),
            size: meta.len(),
            max: max_bytes,
        });
    }
    std::fs::read_to_string(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })
}
