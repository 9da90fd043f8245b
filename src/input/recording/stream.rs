//! A recording read a frame at a time: [`RecordingStream`]. What it holds does
//! not grow with the length of the recording: one line, one frame, the
//! decoder's state and at most [`MAX_WARNINGS`](super::MAX_WARNINGS) warnings.

use super::error::{OnBadFrame, RecordingError};
use super::evdev_header::DeviceHeader;
use super::evemu::{is_evemu_line, parse_evemu_desc, EvemuReader};
use super::hid_stream::HidReader;
use super::jsonl::JsonlReader;
use super::libinput_yaml::YamlReader;
use super::lines::{LineFault, LineReader, Source};
use super::shipped::RECORDINGS;
use super::warnings::{RecordingIssue, Warnings};
use crate::input::SurfaceInfo;
use crate::located::ReadError;
use crate::vocab::{Micros, TouchFrame};
use std::io::{BufReader, Cursor};
use std::path::{Path, PathBuf};

/// Longest time between two frames taken at face value, in µs (a day). A longer
/// jump is a clock fault (a recorder mixing clocks, a corrupted timestamp): it is
/// reported as a warning at its line and shortened to [`JUMP_REPLAYED_US`], and
/// the frames after it move earlier by the difference.
pub const MAX_TIME_JUMP_US: u64 = 86_400_000_000;

/// What a jump longer than [`MAX_TIME_JUMP_US`] is shortened to, in µs (1 s).
pub const JUMP_REPLAYED_US: u64 = 1_000_000;

/// Buffer of a recording file's reader, in bytes.
const FILE_BUFFER_BYTES: usize = 64 * 1024;

/// Which reader a text needs.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Format {
    Jsonl,
    Evemu,
    LibinputYaml,
    HidRecorder,
}

/// The reader of the format (each holds a frame or two and its decoder: boxed).
enum Reader {
    Jsonl(Box<JsonlReader>),
    Evemu(Box<EvemuReader>),
    Yaml(Box<YamlReader>),
    Hid(Box<HidReader>),
    /// The source was lost going back to the start.
    Gone,
}

/// A recording read a frame at a time, in any of the formats
/// [`read_recording`](super::read_recording) reads, with the same frames, errors
/// and warnings; it can go back to its start to be played again.
///
/// Frames come normalised to the unit square with their life-cycle flags
/// derived, timed relative to the start, a time jump over
/// [`MAX_TIME_JUMP_US`] shortened to [`JUMP_REPLAYED_US`]; contacts still down
/// after the last frame end `CANCELLED` in one more frame.
pub struct RecordingStream {
    path: PathBuf,
    on_bad: OnBadFrame,
    /// The device header of a separate evemu description, kept for [`Self::rewind`].
    desc: Option<DeviceHeader>,
    surface: SurfaceInfo,
    reader: Reader,
    frame: TouchFrame,
    warnings: Warnings,
    /// Time of the previous frame, as its reader gave it.
    prev_t: Option<Micros>,
    /// Time taken out by shortened jumps.
    shift: Micros,
    frames: u64,
    line: usize,
    /// A reading error ended the stream.
    failed: bool,
}

impl std::fmt::Debug for RecordingStream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecordingStream")
            .field("path", &self.path)
            .field("surface", &self.surface)
            .field("frames", &self.frames)
            .field("line", &self.line)
            .finish_non_exhaustive()
    }
}

impl RecordingStream {
    /// Opens a recording file and reads its header.
    ///
    /// # Errors
    /// [`RecordingError`]: I/O, a header that is wrong or missing, an unknown
    /// format (gzip data included), a device that is not supported, no frame
    /// to come ([`RecordingError::Empty`], for the formats that know it then).
    pub fn open(path: &Path, on_bad: OnBadFrame) -> Result<RecordingStream, RecordingError> {
        // A regular file only: a FIFO or a device is refused at the open, never
        // waited on (its lines would be capped, its open would not).
        let file = crate::located::open_regular(path).map_err(|e| match e {
            ReadError::Io { path, source } => RecordingError::Io { path, source },
            ReadError::NotRegular { path, kind } => RecordingError::Io {
                path,
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("{kind}, not a regular file"),
                ),
            },
            e => RecordingError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::other(e.to_string()),
            },
        })?;
        let src = BufReader::with_capacity(FILE_BUFFER_BYTES, file);
        RecordingStream::from_source(Box::new(src), path, on_bad)
    }

    /// [`RecordingStream::open`], or — when no such file exists and its name is
    /// one of the shipped recordings — the copy compiled into the binary.
    ///
    /// # Errors
    /// As [`RecordingStream::open`].
    pub fn load(path: &Path, on_bad: OnBadFrame) -> Result<RecordingStream, RecordingError> {
        if !path.exists() {
            if let Some(name) = path.file_name().and_then(|n| n.to_str()) {
                if let Some((_, text)) = RECORDINGS.iter().find(|(n, _)| *n == name) {
                    let src = Cursor::new(text.as_bytes());
                    return RecordingStream::from_source(Box::new(src), path, on_bad);
                }
            }
        }
        RecordingStream::open(path, on_bad)
    }

    /// A recording held in memory; `name` is used in errors.
    ///
    /// # Errors
    /// As [`RecordingStream::open`].
    pub fn from_bytes(
        bytes: Vec<u8>,
        name: &Path,
        on_bad: OnBadFrame,
    ) -> Result<RecordingStream, RecordingError> {
        RecordingStream::from_source(Box::new(Cursor::new(bytes)), name, on_bad)
    }

    /// An evemu event stream whose device header is the description `desc`
    /// (see [`read_evemu_with_desc`](super::read_evemu_with_desc)).
    ///
    /// # Errors
    /// As [`RecordingStream::open`]; problems of the description are located in
    /// it ("in the device description").
    pub fn evemu_with_desc(
        desc: &str,
        events: Vec<u8>,
        name: &Path,
        on_bad: OnBadFrame,
    ) -> Result<RecordingStream, RecordingError> {
        let mut w = Warnings::default();
        let hdr = parse_evemu_desc(desc, name, &mut w)?;
        let lines = LineReader::new(Box::new(Cursor::new(events)));
        RecordingStream::from_lines(lines, name, on_bad, Some(hdr), w)
    }

    fn from_source(
        src: Box<dyn Source>,
        path: &Path,
        on_bad: OnBadFrame,
    ) -> Result<RecordingStream, RecordingError> {
        let lines = LineReader::new(src);
        RecordingStream::from_lines(lines, path, on_bad, None, Warnings::default())
    }

    /// Detects the format (an evemu text when `desc` is given) and reads the header.
    fn from_lines(
        mut lines: LineReader,
        path: &Path,
        on_bad: OnBadFrame,
        desc: Option<DeviceHeader>,
        mut warnings: Warnings,
    ) -> Result<RecordingStream, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        };
        if lines.peek_start().map_err(io)?.starts_with(&[0x1f, 0x8b]) {
            return Err(RecordingError::UnknownFormat {
                path: path.to_path_buf(),
                found: "gzip data; decompress it first".to_string(),
            });
        }
        let format = match desc {
            Some(_) => Format::Evemu,
            None => match detect(&mut lines, path)? {
                Ok(Some(f)) => f,
                Ok(None) => {
                    return Err(RecordingError::Empty {
                        path: path.to_path_buf(),
                    })
                }
                Err(found) => {
                    return Err(RecordingError::UnknownFormat {
                        path: path.to_path_buf(),
                        found,
                    })
                }
            },
        };
        lines.rewind().map_err(io)?;
        let (reader, surface) = match format {
            Format::Jsonl => {
                let (r, s) = JsonlReader::open(lines, path, on_bad)?;
                (Reader::Jsonl(Box::new(r)), s)
            }
            Format::Evemu => {
                let (r, s) = EvemuReader::open(lines, desc.as_ref(), path, on_bad, &mut warnings)?;
                (Reader::Evemu(Box::new(r)), s)
            }
            Format::LibinputYaml => {
                let (r, s) = YamlReader::open(lines, path, on_bad, &mut warnings)?;
                (Reader::Yaml(Box::new(r)), s)
            }
            Format::HidRecorder => {
                let (r, s) = HidReader::open(lines, path, on_bad)?;
                (Reader::Hid(Box::new(r)), s)
            }
        };
        Ok(RecordingStream {
            path: path.to_path_buf(),
            on_bad,
            desc,
            surface,
            reader,
            frame: TouchFrame::default(),
            warnings,
            prev_t: None,
            shift: Micros::ZERO,
            frames: 0,
            line: 0,
            failed: false,
        })
    }

    /// The recorded surface.
    pub fn surface(&self) -> &SurfaceInfo {
        &self.surface
    }

    /// The file (or name) read.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames handed out since the start (or the last [`Self::rewind`]).
    pub fn frames_read(&self) -> u64 {
        self.frames
    }

    /// The line of the last frame handed out (for evdev formats, of the event
    /// that closed it).
    pub fn line(&self) -> usize {
        self.line
    }

    /// The next frame, or `None` after the last.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad frame with [`OnBadFrame::Stop`] (with
    /// [`OnBadFrame::Skip`] it is skipped and a warning noted),
    /// [`RecordingError::Empty`] at the end when there was no frame,
    /// [`RecordingError::Io`]. After an error the stream ends.
    pub fn next_frame(&mut self) -> Result<Option<&TouchFrame>, RecordingError> {
        if self.failed {
            return Ok(None);
        }
        let (path, out, w) = (&self.path, &mut self.frame, &mut self.warnings);
        let got = match &mut self.reader {
            Reader::Jsonl(r) => r.next(path, out, w),
            Reader::Evemu(r) => r.next(path, out, w),
            Reader::Yaml(r) => r.next(path, out, w),
            Reader::Hid(r) => r.next(path, out, w),
            Reader::Gone => Ok(None),
        };
        let line = match got {
            Ok(Some(line)) => line,
            Ok(None) => {
                self.warnings.close();
                return Ok(None);
            }
            Err(e) => {
                self.failed = true;
                return Err(e);
            }
        };
        self.line = line;
        let t = self.frame.t;
        if let Some(prev) = self.prev_t {
            let jump = t.saturating_since(prev);
            if jump.0 > MAX_TIME_JUMP_US {
                self.warnings.push(
                    line,
                    format!(
                        "timestamp jumps by {}; a jump of more than a day is taken for a \
                         clock fault and replayed as {} s",
                        long_duration(jump),
                        JUMP_REPLAYED_US / 1_000_000
                    ),
                );
                self.shift = self.shift + Micros(jump.0 - JUMP_REPLAYED_US);
            }
        }
        self.prev_t = Some(t);
        self.frame.t = t - self.shift;
        self.frames += 1;
        Ok(Some(&self.frame))
    }

    /// The warnings noted since the last call (skipped frames, time jumps,
    /// decoder counters at the end). No allocation when there is none.
    pub fn take_warnings(&mut self) -> Vec<RecordingIssue> {
        self.warnings.take()
    }

    /// Goes back to the first frame (the header is read again).
    ///
    /// # Errors
    /// As [`RecordingStream::open`].
    pub fn rewind(&mut self) -> Result<(), RecordingError> {
        let lines = match std::mem::replace(&mut self.reader, Reader::Gone) {
            Reader::Jsonl(r) => Some((*r).into_lines()),
            Reader::Evemu(r) => Some((*r).into_lines()),
            Reader::Yaml(r) => (*r).into_lines(),
            Reader::Hid(r) => Some((*r).into_lines()),
            Reader::Gone => None,
        };
        let Some(mut lines) = lines else {
            self.failed = true;
            return Err(RecordingError::Io {
                path: self.path.clone(),
                source: std::io::Error::other("the reader lost its source"),
            });
        };
        if let Err(source) = lines.rewind() {
            self.failed = true;
            return Err(RecordingError::Io {
                path: self.path.clone(),
                source,
            });
        }
        let desc = self.desc.take();
        let fresh =
            RecordingStream::from_lines(lines, &self.path, self.on_bad, desc, Warnings::default());
        match fresh {
            Ok(s) => {
                *self = s;
                Ok(())
            }
            Err(e) => {
                self.failed = true;
                Err(e)
            }
        }
    }

    /// Reads every frame into a [`Recording`](super::Recording), failing with
    /// [`RecordingError::TooLarge`] once more than `limit` bytes were read.
    pub(super) fn collect(
        mut self,
        limit: Option<u64>,
    ) -> Result<super::Recording, RecordingError> {
        let mut frames = Vec::new();
        let mut warnings = Vec::new();
        while let Some(f) = self.next_frame()? {
            frames.push(*f);
            if let Some(limit) = limit {
                let read = self.consumed();
                if read > limit {
                    return Err(RecordingError::TooLarge {
                        path: self.path,
                        size: read,
                        limit,
                    });
                }
            }
            warnings.append(&mut self.warnings.take());
        }
        warnings.append(&mut self.warnings.take());
        Ok(super::Recording {
            surface: self.surface,
            frames,
            warnings,
        })
    }

    /// Bytes read from the source so far.
    fn consumed(&self) -> u64 {
        match &self.reader {
            Reader::Jsonl(r) => r.consumed(),
            Reader::Evemu(r) => r.consumed(),
            Reader::Yaml(r) => r.consumed(),
            Reader::Hid(r) => r.consumed(),
            Reader::Gone => 0,
        }
    }
}

/// A duration of at least a day, for messages.
fn long_duration(d: Micros) -> String {
    const DAY_US: f64 = 86_400e6;
    let days = d.0 as f64 / DAY_US;
    if days >= 365.25 {
        format!("{:.0} years", days / 365.25)
    } else {
        format!("{days:.1} days")
    }
}

/// Detects the format from the first meaningful line (or, for YAML, the
/// top-level `version:` and `devices:` keys). `Ok(Err(start))` when it is none
/// of them; `Ok(Ok(None))` for a text with no meaningful line.
fn detect(
    lines: &mut LineReader,
    path: &Path,
) -> Result<Result<Option<Format>, String>, RecordingError> {
    let first = loop {
        match lines.next_line() {
            Ok(Some((_, l))) => {
                let t = l.trim();
                if !t.is_empty() && !t.starts_with('#') {
                    break t;
                }
            }
            Ok(None) => return Ok(Ok(None)),
            Err(f) => return Err(f.at(path, lines.line())),
        }
    };
    if first.starts_with('{') {
        return Ok(Ok(Some(Format::Jsonl)));
    }
    // hid-recorder writes the descriptor (`R:`) first, after an optional `D:`.
    if first.starts_with("R:") || first.starts_with("D:") {
        return Ok(Ok(Some(Format::HidRecorder)));
    }
    if is_evemu_line(first) {
        return Ok(Ok(Some(Format::Evemu)));
    }
    let found: String = first.chars().take(40).collect();
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    lines.rewind().map_err(io)?;
    let (mut version, mut devices) = (false, false);
    loop {
        match lines.next_line() {
            Ok(Some((_, l))) => {
                version |= l.starts_with("version:");
                devices |= l.starts_with("devices:");
                if version && devices {
                    return Ok(Ok(Some(Format::LibinputYaml)));
                }
            }
            Ok(None) => return Ok(Err(found)),
            Err(LineFault::TooLong) => lines.skip_rest().map_err(io)?,
            Err(f) => return Err(f.at(path, lines.line())),
        }
    }
}
