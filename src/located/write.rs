//! The one writer of files a person or a client names (track files, gesture
//! libraries): the bytes go to a new temporary file beside the target, are synced,
//! and are put in place in one step, so a reader — or a daemon stopped by SIGTERM
//! half-way — never leaves half a file behind.

use std::io::Write as _;
use std::path::Path;

/// Why [`place`] did not write.
#[derive(Debug)]
pub enum PlaceError {
    /// The file exists and was not to be replaced.
    Exists,
    /// Writing failed.
    Io(std::io::Error),
}

impl std::fmt::Display for PlaceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlaceError::Exists => f.write_str("it exists"),
            PlaceError::Io(e) => write!(f, "{e}"),
        }
    }
}

/// Writes `bytes` to a new temporary file beside `path` (`O_EXCL`: never an
/// existing file, a FIFO or a link) and syncs it, then puts it in place: renamed
/// over `path` with `overwrite`; else hard-linked to `path`, which fails when
/// `path` exists (no window between a check and the write), with a
/// check-then-rename where the filesystem has no hard links. A reader never sees
/// half a file.
///
/// # Errors
/// [`PlaceError::Exists`] without `overwrite` when `path` exists;
/// [`PlaceError::Io`] when the temporary file cannot be written or moved.
pub fn place(bytes: &[u8], path: &Path, overwrite: bool) -> Result<(), PlaceError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(PlaceError::Io(e));
    }
    let placed = if overwrite {
        std::fs::rename(&tmp, path).map_err(PlaceError::Io)
    } else {
        match std::fs::hard_link(&tmp, path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(PlaceError::Exists),
            // No hard links here (vfat, some network filesystems).
            Err(_) if std::fs::symlink_metadata(path).is_ok() => Err(PlaceError::Exists),
            Err(_) => std::fs::rename(&tmp, path).map_err(PlaceError::Io),
        }
    };
    let _ = std::fs::remove_file(&tmp);
    placed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_replaced_only_when_asked_and_no_temporary_file_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("lib.bin");
        place(b"one", &p, false).unwrap();
        assert!(matches!(place(b"two", &p, false), Err(PlaceError::Exists)));
        assert_eq!(std::fs::read(&p).unwrap(), b"one");
        place(b"three", &p, true).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"three");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn a_missing_directory_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/lib.bin");
        assert!(matches!(place(b"x", &p, true), Err(PlaceError::Io(_))));
    }
}
