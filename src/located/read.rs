//! Reading the files people and clients name: regular files only, capped while
//! reading, and — for the daemon — stoppable between chunks.
//!
//! Every reader of a named file (config, scenes, formation bitmaps, gesture
//! libraries, track files, edit scripts, recordings) opens it here:
//!
//! * opened with `O_NONBLOCK | O_NOCTTY` (and `O_CLOEXEC`, std's default), so a
//!   FIFO with no writer does not block the open and a terminal is never made the
//!   controlling one;
//! * the opened descriptor is `fstat`ed and anything but a regular file is refused,
//!   naming what it is (`is a FIFO`, `is a character device`, `is a directory`);
//! * a reported size over the cap is refused at once (a 10 GB sparse file costs
//!   nothing);
//! * the read goes through the cap: never more than `cap + 1` bytes are read, so a
//!   file that grows while it is read is refused too;
//! * [`read_text_stoppable`] polls a stop check every [`READ_CHUNK_BYTES`].
//!
//! Clients never name paths: they name entries of a directory the operator set
//! ([`check_entry_name`], [`entry_path`], [`read_entry_text`]); an entry that is a
//! symbolic link is refused (`O_NOFOLLOW`), so no entry leads out of the directory.

use std::fs::File;
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// How much [`read_text_stoppable`] reads between two polls of its stop check
/// (bytes): 1 MiB, a few milliseconds from the page cache.
pub const READ_CHUNK_BYTES: usize = 1 << 20;

/// The longest entry name a client may give (bytes).
pub const MAX_ENTRY_NAME_BYTES: usize = 128;

/// Why a named file could not be read. Each file kind wraps it into its own error
/// with its own words (`cannot read config`, `cannot read scene`).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The path names something other than a regular file (a FIFO, a device, a
    /// directory, a socket; a symbolic link where links are refused).
    #[error("{path}: {kind}, not a regular file")]
    NotRegular {
        /// File.
        path: PathBuf,
        /// What it is: `is a FIFO`, `is a character device`, `is a directory`, ...
        kind: &'static str,
    },
    /// The file reports a size larger than the cap.
    #[error("{path}: {size} bytes, more than the {max} byte limit")]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
    /// More than the cap was read (the file grew while it was read).
    #[error("{path}: more than the {max} byte limit was read (the file grew)")]
    GrewPastCap {
        /// File.
        path: PathBuf,
        /// The limit.
        max: u64,
    },
    /// A text file that is not UTF-8.
    #[error("{path}: not UTF-8 text (byte {offset})")]
    NotUtf8 {
        /// File.
        path: PathBuf,
        /// Offset of the first byte that is not UTF-8.
        offset: usize,
    },
    /// The stop check asked the read to end (the daemon is stopping).
    #[error("{path}: reading stopped")]
    Stopped {
        /// File.
        path: PathBuf,
    },
}

/// Why a client's entry name is not one (a name of a file in a directory, never
/// a path).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// Empty.
    #[error("the name is empty")]
    Empty,
    /// Longer than [`MAX_ENTRY_NAME_BYTES`].
    #[error("the name is {len} bytes, more than {MAX_ENTRY_NAME_BYTES}")]
    TooLong {
        /// Its length (bytes).
        len: usize,
    },
    /// Holds a `/`: a path, not a name.
    #[error("the name holds `/` at byte {at}: give the name of a file in the edit directory, not a path")]
    Slash {
        /// Byte offset.
        at: usize,
    },
    /// Starts with `.` (`.`, `..`, hidden and temporary files).
    #[error("the name starts with `.`: `.`, `..` and hidden files are not entries")]
    Dot,
    /// A character outside `A-Z a-z 0-9 . _ -` (NUL and control characters
    /// included).
    #[error("the name holds {ch} at byte {at}; a name is made of A-Z a-z 0-9 . _ -")]
    BadChar {
        /// The character, escaped (`'\0'`, `'é'`).
        ch: String,
        /// Byte offset.
        at: usize,
    },
}

/// What a file that is not regular is, for [`ReadError::NotRegular`].
fn kind_of(ft: std::fs::FileType) -> &'static str {
    if ft.is_dir() {
        "is a directory"
    } else if ft.is_fifo() {
        "is a FIFO"
    } else if ft.is_char_device() {
        "is a character device"
    } else if ft.is_block_device() {
        "is a block device"
    } else if ft.is_socket() {
        "is a socket"
    } else if ft.is_symlink() {
        "is a symbolic link"
    } else {
        "is not a regular file"
    }
}

/// Opens `path` for reading without blocking on a FIFO and without following a
/// final symbolic link when `nofollow`, and refuses anything but a regular file.
/// Returns the file and the size it reports.
fn open_checked(path: &Path, nofollow: bool) -> Result<(File, u64), ReadError> {
    let mut flags = libc::O_NONBLOCK | libc::O_NOCTTY;
    if nofollow {
        flags |= libc::O_NOFOLLOW;
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(flags)
        .open(path)
        .map_err(|source| {
            if nofollow && source.raw_os_error() == Some(libc::ELOOP) {
                ReadError::NotRegular {
                    path: path.to_path_buf(),
                    kind: "is a symbolic link",
                }
            } else {
                ReadError::Io {
                    path: path.to_path_buf(),
                    source,
                }
            }
        })?;
    let meta = file.metadata().map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if !meta.file_type().is_file() {
        return Err(ReadError::NotRegular {
            path: path.to_path_buf(),
            kind: kind_of(meta.file_type()),
        });
    }
    Ok((file, meta.len()))
}

/// Opens a regular file to be read as a stream (recordings, whose lines are
/// capped by their reader): FIFOs, devices and directories are refused at once.
///
/// # Errors
/// [`ReadError::Io`] when it cannot be opened, [`ReadError::NotRegular`].
pub fn open_regular(path: &Path) -> Result<File, ReadError> {
    open_checked(path, false).map(|(f, _)| f)
}

/// The whole read: regular file, reported size, then at most `max_bytes + 1`
/// bytes read in chunks of [`READ_CHUNK_BYTES`], `stop` polled before each.
fn read_impl(
    path: &Path,
    max_bytes: u64,
    nofollow: bool,
    stop: &dyn Fn() -> bool,
) -> Result<Vec<u8>, ReadError> {
    let (file, size) = open_checked(path, nofollow)?;
    if size > max_bytes {
        return Err(ReadError::TooLarge {
            path: path.to_path_buf(),
            size,
            max: max_bytes,
        });
    }
    // The reported size is within the cap; a file that grows meanwhile is caught
    // by the take below.
    let mut bytes = Vec::with_capacity(size as usize);
    let mut capped = file.take(max_bytes.saturating_add(1));
    loop {
        if stop() {
            return Err(ReadError::Stopped {
                path: path.to_path_buf(),
            });
        }
        let before = bytes.len();
        let n = (&mut capped)
            .take(READ_CHUNK_BYTES as u64)
            .read_to_end(&mut bytes)
            .map_err(|source| ReadError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        if bytes.len() as u64 > max_bytes {
            return Err(ReadError::GrewPastCap {
                path: path.to_path_buf(),
                max: max_bytes,
            });
        }
        if n == 0 || bytes.len() - before < READ_CHUNK_BYTES {
            return Ok(bytes);
        }
    }
}

fn into_text(path: &Path, bytes: Vec<u8>) -> Result<String, ReadError> {
    String::from_utf8(bytes).map_err(|e| ReadError::NotUtf8 {
        path: path.to_path_buf(),
        offset: e.utf8_error().valid_up_to(),
    })
}

/// Reads a regular file of at most `max_bytes` bytes.
///
/// # Errors
/// [`ReadError`]: cannot be opened or read, not a regular file, larger than the cap
/// (reported or read).
pub fn read_bytes(path: &Path, max_bytes: u64) -> Result<Vec<u8>, ReadError> {
    read_impl(path, max_bytes, false, &|| false)
}

/// Reads a regular UTF-8 text file (config, scene, ...) of at most `max_bytes`
/// bytes.
///
/// # Errors
/// As [`read_bytes`], and [`ReadError::NotUtf8`].
pub fn read_text(path: &Path, max_bytes: u64) -> Result<String, ReadError> {
    read_text_stoppable(path, max_bytes, &|| false)
}

/// [`read_text`] that polls `stop` every [`READ_CHUNK_BYTES`] and gives up when it
/// returns true (the daemon's reads, stopped at shutdown).
///
/// # Errors
/// As [`read_text`], and [`ReadError::Stopped`].
pub fn read_text_stoppable(
    path: &Path,
    max_bytes: u64,
    stop: &dyn Fn() -> bool,
) -> Result<String, ReadError> {
    let bytes = read_impl(path, max_bytes, false, stop)?;
    into_text(path, bytes)
}

/// Checks that `name` is an entry name a client may give: not empty, at most
/// [`MAX_ENTRY_NAME_BYTES`], made of `A-Z a-z 0-9 . _ -`, not starting with `.`
/// (so never `.`, `..`, a path, a NUL or a control character).
///
/// # Errors
/// [`NameError`] saying what is wrong and where.
pub fn check_entry_name(name: &str) -> Result<(), NameError> {
    if name.is_empty() {
        return Err(NameError::Empty);
    }
    if name.len() > MAX_ENTRY_NAME_BYTES {
        return Err(NameError::TooLong { len: name.len() });
    }
    if let Some(at) = name.find('/') {
        return Err(NameError::Slash { at });
    }
    if name.starts_with('.') {
        return Err(NameError::Dot);
    }
    if let Some((at, ch)) = name
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Err(NameError::BadChar {
            ch: format!("{:?}", ch),
            at,
        });
    }
    Ok(())
}

/// The path of entry `name` in `dir`, once the name is checked
/// ([`check_entry_name`]).
///
/// # Errors
/// [`NameError`].
pub fn entry_path(dir: &Path, name: &str) -> Result<PathBuf, NameError> {
    check_entry_name(name)?;
    Ok(dir.join(name))
}

/// Reads entry `name` of `dir` as text, as [`read_text_stoppable`] does, refusing
/// an entry that is a symbolic link (`O_NOFOLLOW`): the name holds no `/`, so the
/// entry is the only component that could lead out of `dir`.
///
/// # Errors
/// [`EntryError::Name`] for a name that is not one, else [`EntryError::Read`].
pub fn read_entry_text(
    dir: &Path,
    name: &str,
    max_bytes: u64,
    stop: &dyn Fn() -> bool,
) -> Result<String, EntryError> {
    let path = entry_path(dir, name)?;
    let bytes = read_impl(&path, max_bytes, true, stop)?;
    Ok(into_text(&path, bytes)?)
}

/// Why an entry of a directory could not be read.
#[derive(Debug, thiserror::Error)]
pub enum EntryError {
    /// The name is not an entry name.
    #[error(transparent)]
    Name(#[from] NameError),
    /// The entry could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
}
