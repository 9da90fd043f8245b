//! Track files for the edit mode, the config and the `edit` tools: read (capped,
//! format from the extension or the first line, errors naming `file:line`) and
//! written (never over an existing file unless asked). The daemon does this on its
//! formation thread or at config load, never on the control thread.

use super::format::{self as io, Format, ReadOptions};
use crate::crowd::edit::TrackSet;
use crate::located::{read_capped, ReadError as FileError};
use std::io::Write as _;
use std::path::Path;

/// The largest track file read (bytes).
pub const MAX_TRACK_FILE_BYTES: u64 = 256 << 20;

/// Reads a track file: `format` `None` detects it. The error names the file and,
/// where it is one line's fault, the line.
///
/// # Errors
/// A message for a person: the file cannot be read, is too large or not text, or a
/// line is wrong, or the tracks break [`TrackSet::validate`].
pub fn read_tracks(
    path: &Path,
    format: Option<Format>,
    opts: &ReadOptions,
) -> Result<(TrackSet, Format), String> {
    let shown = path.display();
    let text = read_capped(path, MAX_TRACK_FILE_BYTES).map_err(|e| match e {
        FileError::Io { source, .. } if source.kind() == std::io::ErrorKind::InvalidData => {
            format!("{shown}: not UTF-8 text")
        }
        e => e.to_string(),
    })?;
    let format = format.unwrap_or_else(|| io::detect(path, &text));
    let set = io::read(&text, format, opts).map_err(|e| match e.line {
        0 => format!("{shown}: {}", e.what),
        l => format!("{shown}:{l}: {}", e.what),
    })?;
    set.validate().map_err(|e| format!("{shown}: {e}"))?;
    Ok((set, format))
}

/// Writes `set` to `path` in `format`: to a temporary file beside it, renamed into
/// place, so a reader never sees half a file. An existing file is replaced only
/// with `overwrite`.
///
/// # Errors
/// A message naming the file: it exists (without `overwrite`) or cannot be written.
pub fn write_tracks(
    set: &TrackSet,
    path: &Path,
    format: Format,
    opts: &ReadOptions,
    overwrite: bool,
) -> Result<(), String> {
    let shown = path.display();
    if !overwrite && path.exists() {
        return Err(format!("{shown} exists; give overwrite to replace it"));
    }
    let text = io::write(set, format, opts);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let written = std::fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(text.as_bytes()).and_then(|()| f.sync_all()))
        .and_then(|()| std::fs::rename(&tmp, path));
    written.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{shown}: cannot write: {e}")
    })
}
