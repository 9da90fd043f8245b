//! Track files for the edit mode, the config and the `edit` tools: read (a regular
//! file, capped while read, format from the extension or the first line, errors
//! naming `file:line`) and written (never over an existing file unless asked).
//! The daemon reads and writes only entries of its edit directory, by name
//! ([`read_track_entry`], [`write_track_entry`]), on its formation thread or at
//! config load, never on the control thread; the messages it sends to clients
//! never quote the file's text.

use super::csv::read_csv_flat;
use super::format::{self as io, Format, ReadOptions};
use super::ReadError;
use crate::crowd::edit::{FlatTracks, TrackSet, Tracks};
use crate::located::{
    check_entry_name, place, read_entry_text, read_text, EntryError, PlaceError,
    ReadError as FileError,
};
use std::path::Path;

/// The largest track file read (bytes).
pub const MAX_TRACK_FILE_BYTES: u64 = 256 << 20;

/// Reads a track file: `format` `None` detects it. The error names the file and,
/// where it is one line's fault, the line.
///
/// # Errors
/// A message for a person: the file cannot be read, is not a regular file, is too
/// large or not text, or a line is wrong, or the tracks break
/// [`TrackSet::validate`].
pub fn read_tracks(
    path: &Path,
    format: Option<Format>,
    opts: &ReadOptions,
) -> Result<(TrackSet, Format), String> {
    read_file_as(path, format, |text, f| io::read(text, f, opts))
}

/// [`read_tracks`] into the compact [`FlatTracks`], for reading without editing
/// (`edit check`): CSV straight from the text, the other formats through a
/// [`TrackSet`].
///
/// # Errors
/// As [`read_tracks`].
pub fn read_tracks_flat(
    path: &Path,
    format: Option<Format>,
    opts: &ReadOptions,
) -> Result<(FlatTracks, Format), String> {
    read_file_as(path, format, |text, f| match f {
        Format::Csv => read_csv_flat(text, opts.csv_step_s),
        _ => io::read(text, f, opts).map(|set| FlatTracks::from(&set)),
    })
}

/// The file at `path` read capped, its format detected unless given, parsed by
/// `parse` and validated; errors name the file and line.
fn read_file_as<T: Tracks>(
    path: &Path,
    format: Option<Format>,
    parse: impl FnOnce(&str, Format) -> Result<T, ReadError>,
) -> Result<(T, Format), String> {
    let shown = path.display();
    let text = read_text(path, MAX_TRACK_FILE_BYTES).map_err(|e| e.to_string())?;
    let format = format.unwrap_or_else(|| io::detect(path, &text));
    let set = parse(&text, format).map_err(|e| match e.line {
        0 => format!("{shown}: {}", e.what),
        l => format!("{shown}:{l}: {}", e.what),
    })?;
    drop(text);
    set.validate().map_err(|e| format!("{shown}: {e}"))?;
    Ok((set, format))
}

/// Reads entry `entry` of the edit directory `dir` for a client's `edit.load`:
/// the name is checked (no `/`, no leading `.`, [`check_entry_name`]), the entry
/// must be a regular file and not a symbolic link, the read is capped at
/// [`MAX_TRACK_FILE_BYTES`] and gives up when `stop` returns true (polled every
/// MiB).
///
/// # Errors
/// A message for the client naming the entry (never the directory's path), the
/// line and what is wrong, with every piece of the file's text it would quote
/// replaced by `…` ([`without_quotes`]).
pub fn read_track_entry(
    dir: &Path,
    entry: &str,
    opts: &ReadOptions,
    stop: &dyn Fn() -> bool,
) -> Result<TrackSet, String> {
    let text = read_entry_text(dir, entry, MAX_TRACK_FILE_BYTES, stop)
        .map_err(|e| entry_error(entry, &e))?;
    let format = io::detect(Path::new(entry), &text);
    let set = io::read(&text, format, opts).map_err(|e| {
        let what = without_quotes(&e.what);
        match e.line {
            0 => format!("{entry}: {what}"),
            l => format!("{entry}:{l}: {what}"),
        }
    })?;
    set.validate()
        .map_err(|e| format!("{entry}: {}", without_quotes(&e.to_string())))?;
    Ok(set)
}

/// A read error of an entry, for a client: the entry's name instead of its path.
fn entry_error(entry: &str, e: &EntryError) -> String {
    match e {
        EntryError::Name(n) => format!("not an entry name: {n}"),
        EntryError::Read(r) => match r {
            FileError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
                format!("{entry}: no such entry in the edit directory")
            }
            FileError::Io { source, .. } => format!("{entry}: cannot read: {source}"),
            FileError::NotRegular { kind, .. } => format!("{entry}: {kind}, not a regular file"),
            FileError::TooLarge { size, max, .. } => {
                format!("{entry}: {size} bytes, more than the {max} byte limit")
            }
            FileError::GrewPastCap { max, .. } => {
                format!("{entry}: more than the {max} byte limit was read (the file grew)")
            }
            FileError::NotUtf8 { offset, .. } => {
                format!("{entry}: not UTF-8 text (byte {offset})")
            }
            FileError::Stopped { .. } => {
                format!("{entry}: reading stopped (the daemon is stopping)")
            }
        },
    }
}

/// `what` with every quoted piece (between backquotes or double quotes, which is
/// how the track readers and JSON's errors quote a file's text) replaced by `…`,
/// and control characters dropped: what a client is told of a line never holds
/// the line's bytes.
pub fn without_quotes(what: &str) -> String {
    let mut out = String::with_capacity(what.len());
    let mut open: Option<char> = None;
    for c in what.chars() {
        match open {
            Some(q) if c == q => {
                out.push(c);
                open = None;
            }
            Some(_) => {}
            None if c == '`' || c == '"' => {
                out.push(c);
                out.push('…');
                open = Some(c);
            }
            None if c.is_control() => {}
            None => out.push(c),
        }
    }
    if open.is_some() {
        out.push(open.unwrap_or('"'));
    }
    out
}

/// Writes `set` (JSON Lines) to entry `entry` of the edit directory `dir` for a
/// client's `edit.save`: the name is checked, the text goes to a temporary file
/// in `dir` and is linked into place; an existing entry is replaced only with
/// `overwrite` (the config's `edit.allow_overwrite` and the client both asked).
///
/// # Errors
/// A message naming the entry: not a name, it exists, or it cannot be written.
pub fn write_track_entry(
    set: &TrackSet,
    dir: &Path,
    entry: &str,
    opts: &ReadOptions,
    overwrite: bool,
) -> Result<(), String> {
    check_entry_name(entry).map_err(|n| format!("not an entry name: {n}"))?;
    let text = io::write(set, Format::Jsonl, opts);
    // What `edit.load` would take the entry for: a `.csv` or `.txt` name would not
    // read back.
    let read_as = io::detect(Path::new(entry), &text);
    if read_as != Format::Jsonl {
        return Err(format!(
            "{entry}: edit.save writes JSON Lines, which a name ending in .{} would not read back as; name it .jsonl",
            Path::new(entry)
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default()
        ));
    }
    place(text.as_bytes(), &dir.join(entry), overwrite).map_err(|e| match e {
        PlaceError::Exists => format!("{entry} exists; saving does not replace it"),
        PlaceError::Io(e) => format!("{entry}: cannot write: {e}"),
    })
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
    let text = io::write(set, format, opts);
    place(text.as_bytes(), path, overwrite).map_err(|e| match e {
        PlaceError::Exists => format!("{shown} exists; give overwrite to replace it"),
        PlaceError::Io(e) => format!("{shown}: cannot write: {e}"),
    })
}

#[cfg(test)]
mod entry_tests {
    use super::*;
    use crate::crowd::edit::Track;
    use crate::geom::Vec2;

    fn set() -> TrackSet {
        TrackSet {
            tracks: vec![Track::linked(
                1,
                vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)],
                vec![0.0, 0.5],
            )],
            step_s: 0.5,
        }
    }

    /// An error about a line never holds the line: finding 1's
    /// ``frame `root:*:…` is not a number`` names the entry and line only.
    #[test]
    fn an_entry_that_does_not_parse_is_named_without_its_text() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("shadow.txt"), "root:*:20228:0:99999:7:::\n").unwrap();
        let e = read_track_entry(dir.path(), "shadow.txt", &ReadOptions::default(), &|| false)
            .unwrap_err();
        assert!(e.starts_with("shadow.txt:1: "), "{e}");
        assert!(!e.contains("root"), "{e}");
        assert!(!e.contains(&dir.path().display().to_string()), "{e}");
        std::fs::write(
            dir.path().join("bad.jsonl"),
            "{\"format\":\"secret-words\"}\n",
        )
        .unwrap();
        let e = read_track_entry(dir.path(), "bad.jsonl", &ReadOptions::default(), &|| false)
            .unwrap_err();
        assert!(!e.contains("secret"), "{e}");
    }

    #[test]
    fn quoted_text_and_control_characters_are_left_out() {
        assert_eq!(
            without_quotes("frame `root:*:1` is not a number"),
            "frame `…` is not a number"
        );
        assert_eq!(
            without_quotes("invalid type: string \"a\\u{1b}b\", expected"),
            "invalid type: string \"…\", expected"
        );
        assert_eq!(without_quotes("open `abc"), "open `…`");
        assert_eq!(without_quotes("a\u{1b}[2Jb"), "a[2Jb");
    }

    /// Saving never replaces an entry without `overwrite`; with it, it does; a name
    /// that is a path is refused and nothing is written.
    #[test]
    fn saving_creates_entries_and_replaces_only_when_allowed() {
        // The entries' directory inside the test's own: its parent is the test's
        // too (not a shared /tmp another program may write `out.jsonl` into).
        let root = tempfile::tempdir().unwrap();
        std::fs::create_dir(root.path().join("entries")).unwrap();
        let dir = tempfile::TempDir::new_in(root.path().join("entries")).unwrap();
        let o = ReadOptions::default();
        write_track_entry(&set(), dir.path(), "a.jsonl", &o, false).unwrap();
        let before = std::fs::read(dir.path().join("a.jsonl")).unwrap();
        let mut other = set();
        other.tracks[0].id = 7;
        let e = write_track_entry(&other, dir.path(), "a.jsonl", &o, false).unwrap_err();
        assert_eq!(e, "a.jsonl exists; saving does not replace it");
        assert_eq!(std::fs::read(dir.path().join("a.jsonl")).unwrap(), before);
        write_track_entry(&other, dir.path(), "a.jsonl", &o, true).unwrap();
        let back = read_track_entry(dir.path(), "a.jsonl", &o, &|| false).unwrap();
        assert_eq!(back.tracks[0].id, 7);
        let e = write_track_entry(&set(), dir.path(), "out.csv", &o, false).unwrap_err();
        assert!(e.starts_with("out.csv: edit.save writes JSON Lines"), "{e}");
        let e = write_track_entry(&set(), dir.path(), "../out.jsonl", &o, true).unwrap_err();
        assert!(e.starts_with("not an entry name"), "{e}");
        assert!(!dir.path().parent().unwrap().join("out.jsonl").exists());
        assert!(!root.path().join("out.jsonl").exists());
        // Only the entry is left: no temporary file.
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }
}
