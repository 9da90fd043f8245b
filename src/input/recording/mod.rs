//! Touch recordings: readers for the formats people have, and our own writer.
//!
//! [`read_recording`] detects the format and returns a [`Recording`]: the
//! surface, and the frames normalised to the unit square with their life-cycle
//! flags already derived, timed relative to the start of the recording.
//!
//! # Formats
//!
//! * **crowdtouch JSON Lines** (`.jsonl`, ours). Line 1 is a header,
//!   ```text
//!   {"format":"crowdtouch-touch","version":1,"device":{"name":"…",
//!    "x":{"min":0,"max":32767,"resolution":27.08},"y":{…},"max_contacts":10}}
//!   ```
//!   (`resolution` in units per mm, optional, 0 = unknown), then one frame per line:
//!   ```text
//!   {"t_us":8333,"contacts":[{"id":1,"x":1234.0,"y":2345.0}, …]}
//!   ```
//!   `x`, `y` are in device units of the header axes (values outside the range
//!   are clamped); optional per contact: `pressure` (normalised, `0..=1`),
//!   `major` / `minor` (device units of the X axis, converted to mm with its
//!   resolution; ignored with a warning when the resolution is unknown) and
//!   `palm` (bool). `t_us` is relative to the start and non-decreasing. The
//!   contacts listed are those currently down: an id present in one frame and
//!   absent from the next has lifted (reported `UP` at its last position). An
//!   optional `"cancelled":[id,…]` lists ids that ended in this frame without a
//!   clean lift (`CANCELLED` instead of `UP`). Unknown keys are ignored; blank
//!   lines and lines starting with `#` are skipped. File ids are opaque: the
//!   reader numbers contacts from 1 in order of appearance, so an id reused
//!   after a lift is a new contact.
//! * **evemu** (`evemu-record` text): header lines `N:` name, `I:`, `P:`, `B:`,
//!   `A: code min max fuzz flat [resolution]` (code in hex; old files have no
//!   resolution column), then `E: sec.usec type code value [# comment]` (type and
//!   code in hex, value decimal, possibly zero-padded or negative). Timestamps may
//!   be absolute or relative; they are made relative to the first event. Files
//!   holding only `E:` lines are paired with their `.desc` through
//!   [`read_evemu_with_desc`].
//! * **libinput record** YAML, version 1: `devices[0].evdev.absinfo` maps an
//!   axis code to `[min, max, fuzz, flat, resolution]`, and
//!   `devices[0].events[*].evdev` lists `[sec, usec, type, code, value]`. Unknown
//!   keys are ignored; only the first device is read.
//! * **hid-recorder** (raw HID): `R:` report descriptor, `N:`, `I:`, then
//!   `E: sec.usec len bytes` input reports; decoded by
//!   [`read_hid_recorder`] with the first touch collection of
//!   the descriptor.
//!
//! evemu and libinput record go through [`MtDecoder`], so they must describe a
//! multi-touch device (`ABS_MT_POSITION_X/Y`): type B when the header declares
//! `ABS_MT_SLOT`, type A (anonymous contacts closed by `SYN_MT_REPORT`, tracked
//! by the decoder) when it does not. Single-touch devices are refused with
//! [`RecordingError::Unsupported`].
//!
//! [`read_evemu_raw`] reads an evemu file without decoding it: the device's
//! [`EvdevCapabilities`] and its [`RawEvent`]s, as they would be played back.
//!
//! # Bad input
//!
//! Every reader reports what is wrong at the 1-based line where it is, and for
//! JSON Lines the field (`contacts[1].x`): a truncated line, a wrong type, a
//! timestamp going backwards, a missing header, an axis the header does not
//! declare. With [`OnBadFrame::Stop`] the first such problem is a
//! [`RecordingError::Parse`]; with [`OnBadFrame::Skip`] the frame holding it is
//! skipped (for evdev formats: every event up to and including the next
//! `SYN_REPORT`) and a [`RecordingIssue`] is recorded instead. Problems with the
//! header are always fatal. The readers never panic, whatever the input.
//!
//! # End of a recording
//!
//! Contacts still down after the last frame get a final frame, [`END_CANCEL_US`]
//! after it, that ends them as `CANCELLED`, so nothing sticks when the recording
//! is replayed.

mod evemu_writer;
mod hid_recorder;
mod shipped;

pub use evemu_writer::{write_evemu_header, EvemuTime, EvemuWriter, EVEMU_VERSION};
pub use hid_recorder::{
    decode_hid_recording, parse_hid_recorder, read_hid_recorder, HidEvent, HidRecorderLog,
    HidRecorderWriter,
};
pub use shipped::{load_recording, RECORDINGS};

use crate::input::evdev::{
    self as mt, AbsAxisInfo, EvdevCapabilities, MtAxes, MtDecoder, RawEvent, ABS_MAX, EV_CNT,
    MASK_BYTES, PROP_BYTES,
};
use crate::input::{AxisRange, SurfaceInfo};
use crate::located::json_kind;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};
use serde::Serialize;
use serde_json::{Map, Value};
use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Largest recording file [`read_recording`] accepts, in bytes (64 MiB).
pub const MAX_RECORDING_BYTES: u64 = 64 * 1024 * 1024;
/// The `format` value of a crowdtouch JSON Lines header.
pub const JSONL_FORMAT: &str = "crowdtouch-touch";
/// The JSON Lines format version this module reads and writes.
pub const JSONL_VERSION: u64 = 1;
/// Delay between the last frame and the frame cancelling contacts still down, in µs.
pub const END_CANCEL_US: u64 = 1_000;
/// Most issues a recording keeps; later ones are only counted in a last issue.
pub const MAX_WARNINGS: usize = 1_000;
/// Deepest YAML nesting (flow brackets) accepted before parsing.
const MAX_YAML_FLOW_DEPTH: usize = 64;
/// Widest YAML block indentation (columns of spaces, `-`, `?`, `:`) accepted.
const MAX_YAML_INDENT: usize = 256;
/// Device units are written with this many decimals (1e-3 units).
const WRITE_SCALE: f64 = 1_000.0;

/// A recording, read and normalised.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The recorded surface.
    pub surface: SurfaceInfo,
    /// Frames in the unit square with `DOWN`/`UP`/`CANCELLED` flags derived;
    /// `t` relative to the start of the recording. Ids count from 1.
    pub frames: Vec<TouchFrame>,
    /// Problems that did not stop the reading (skipped frames, counters).
    pub warnings: Vec<RecordingIssue>,
}

impl Recording {
    /// Time from the first to the last frame.
    pub fn duration(&self) -> Micros {
        match (self.frames.first(), self.frames.last()) {
            (Some(a), Some(b)) => b.t.saturating_since(a.t),
            _ => Micros::ZERO,
        }
    }
}

/// A problem found in a recording.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordingIssue {
    /// 1-based line in the file; 0 when the issue is about the whole file.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for RecordingIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}", self.message)
        } else {
            write!(f, "line {}: {}", self.line, self.message)
        }
    }
}

/// What a reader does with a bad frame.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum OnBadFrame {
    /// Fail with [`RecordingError::Parse`].
    #[default]
    Stop,
    /// Skip the frame and record a [`RecordingIssue`].
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
    /// The file is larger than [`MAX_RECORDING_BYTES`].
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
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// File.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong, and in which field.
        message: String,
    },
    /// Not a format this module reads.
    #[error(
        "{}: unknown recording format (starts with `{found}`); expected crowdtouch JSON \
         Lines, evemu, libinput record YAML or hid-recorder", path.display()
    )]
    UnknownFormat {
        /// File.
        path: PathBuf,
        /// The start of the first meaningful line.
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

/// Reads and decodes a recording file, detecting its format.
///
/// # Errors
/// [`RecordingError`]: I/O, size over [`MAX_RECORDING_BYTES`], text that is not
/// UTF-8, and everything [`parse_recording`] reports.
pub fn read_recording(path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    let text = read_capped(path)?;
    parse_recording(&text, path, on_bad)
}

/// Reads a text file of at most [`MAX_RECORDING_BYTES`].
fn read_capped(path: &Path) -> Result<String, RecordingError> {
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let too_large = |size| RecordingError::TooLarge {
        path: path.to_path_buf(),
        size,
        limit: MAX_RECORDING_BYTES,
    };
    if let Ok(meta) = file.metadata() {
        if meta.len() > MAX_RECORDING_BYTES {
            return Err(too_large(meta.len()));
        }
    }
    let mut bytes = Vec::new();
    file.take(MAX_RECORDING_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_RECORDING_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(RecordingError::UnknownFormat {
            path: path.to_path_buf(),
            found: "gzip data; decompress it first".to_string(),
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        RecordingError::Parse {
            path: path.to_path_buf(),
            line: 1 + good.iter().filter(|&&b| b == b'\n').count(),
            message: "the file is not UTF-8 text".to_string(),
        }
    })
}

/// Which reader a text needs.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Format {
    Jsonl,
    Evemu,
    LibinputYaml,
    HidRecorder,
}

/// Whether `line` (trimmed) is an evemu header or event line.
fn is_evemu_line(line: &str) -> bool {
    ["N:", "I:", "P:", "B:", "A:", "L:", "S:", "E:"]
        .iter()
        .any(|p| line.starts_with(p))
}

/// Detects the format from the first meaningful line (or the YAML top keys).
fn detect(text: &str) -> Result<Option<Format>, String> {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    let Some(first) = first else {
        return Ok(None);
    };
    if first.starts_with('{') {
        return Ok(Some(Format::Jsonl));
    }
    // hid-recorder writes the descriptor (`R:`) first, after an optional `D:`.
    if first.starts_with("R:") || first.starts_with("D:") {
        return Ok(Some(Format::HidRecorder));
    }
    if is_evemu_line(first) {
        return Ok(Some(Format::Evemu));
    }
    let has_top = |key: &str| text.lines().any(|l| l.starts_with(key));
    if has_top("version:") && has_top("devices:") {
        return Ok(Some(Format::LibinputYaml));
    }
    Err(first.chars().take(40).collect())
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
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    match detect(text) {
        Ok(Some(Format::Jsonl)) => parse_jsonl(text, name, on_bad),
        Ok(Some(Format::Evemu)) => parse_evemu(None, text, name, on_bad),
        Ok(Some(Format::LibinputYaml)) => parse_libinput_yaml(text, name, on_bad),
        Ok(Some(Format::HidRecorder)) => hid_recorder::read_hid_recorder(text, name, on_bad),
        Ok(None) => Err(RecordingError::Empty {
            path: name.to_path_buf(),
        }),
        Err(found) => Err(RecordingError::UnknownFormat {
            path: name.to_path_buf(),
            found,
        }),
    }
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
    parse_evemu(Some(desc), events, name, on_bad)
}

// ---------------------------------------------------------------------------
// Shared event stream (evemu, libinput record)

/// One evdev axis as a header declares it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
struct AbsInfo {
    min: i32,
    max: i32,
    resolution: i32,
    /// Line that declared it.
    line: usize,
}

/// What an evdev header says about a device.
#[derive(Clone, Debug)]
struct DeviceHeader {
    name: Option<String>,
    abs: [Option<AbsInfo>; ABS_MAX as usize + 1],
}

impl Default for DeviceHeader {
    fn default() -> Self {
        DeviceHeader {
            name: None,
            abs: [None; ABS_MAX as usize + 1],
        }
    }
}

/// Where header problems are reported.
struct HeaderCtx<'a> {
    path: &'a Path,
    /// Prefix naming the description text, when separate.
    prefix: &'static str,
}

impl HeaderCtx<'_> {
    fn err(&self, line: usize, message: impl fmt::Display) -> RecordingError {
        RecordingError::Parse {
            path: self.path.to_path_buf(),
            line,
            message: format!("{}{message}", self.prefix),
        }
    }
}

impl DeviceHeader {
    fn axis_range(&self, code: u16) -> Option<AxisRange> {
        self.abs[code as usize].map(|a| AxisRange {
            min: f64::from(a.min),
            max: f64::from(a.max),
            resolution: f64::from(a.resolution.max(0)),
        })
    }

    /// The decoder axes and surface, or why this device cannot be decoded.
    ///
    /// `line` is where the header was found to be needed (the first event).
    fn mt_axes(
        &self,
        ctx: &HeaderCtx<'_>,
        line: usize,
        default_name: &str,
        warnings: &mut Warnings,
    ) -> Result<(MtAxes, SurfaceInfo), RecordingError> {
        let unsupported = |reason| RecordingError::Unsupported {
            path: ctx.path.to_path_buf(),
            reason,
        };
        let has = |code: u16| self.abs[code as usize].is_some();
        if self.abs.iter().all(Option::is_none) {
            return Err(ctx.err(
                line,
                "missing device header: no `A:` axis line before the first event (for \
                 header-less .events files, pair them with their .desc)",
            ));
        }
        if !has(mt::ABS_MT_POSITION_X) || !has(mt::ABS_MT_POSITION_Y) {
            return Err(unsupported(UnsupportedReason::NoMultiTouch));
        }
        for code in [mt::ABS_MT_POSITION_X, mt::ABS_MT_POSITION_Y] {
            if let Some(a) = self.abs[code as usize] {
                if a.max <= a.min {
                    return Err(ctx.err(
                        a.line,
                        format_args!(
                            "axis {} has an empty range (min {}, max {})",
                            abs_name(code),
                            a.min,
                            a.max
                        ),
                    ));
                }
            }
        }
        // No ABS_MT_SLOT: protocol A (0 slots), up to a frame's worth of contacts.
        let mut slots = 0;
        let mut max_contacts = MAX_CONTACTS as u32;
        if let Some(slot) = self.abs[mt::ABS_MT_SLOT as usize] {
            if slot.max < 0 || slot.min != 0 {
                return Err(ctx.err(
                    slot.line,
                    format_args!(
                        "ABS_MT_SLOT must range from 0 (found min {}, max {})",
                        slot.min, slot.max
                    ),
                ));
            }
            let declared = slot.max as usize + 1;
            if declared > mt::MAX_SLOTS {
                warnings.push(
                    slot.line,
                    format!(
                        "the device declares {declared} slots; only the first {} are decoded",
                        mt::MAX_SLOTS
                    ),
                );
            }
            slots = declared.min(mt::MAX_SLOTS);
            max_contacts = slots as u32;
        }
        let (Some(x), Some(y)) = (
            self.axis_range(mt::ABS_MT_POSITION_X),
            self.axis_range(mt::ABS_MT_POSITION_Y),
        ) else {
            return Err(unsupported(UnsupportedReason::NoMultiTouch));
        };
        let axes = MtAxes {
            x,
            y,
            slots,
            pressure: self.axis_range(mt::ABS_MT_PRESSURE),
            touch_major: self.axis_range(mt::ABS_MT_TOUCH_MAJOR),
            touch_minor: self.axis_range(mt::ABS_MT_TOUCH_MINOR),
        };
        let surface = SurfaceInfo {
            name: self
                .name
                .clone()
                .unwrap_or_else(|| default_name.to_string()),
            x,
            y,
            max_contacts,
        };
        Ok((axes, surface))
    }
}

/// A readable name for an axis code.
fn abs_name(code: u16) -> String {
    match code {
        mt::ABS_MT_POSITION_X => "ABS_MT_POSITION_X".into(),
        mt::ABS_MT_POSITION_Y => "ABS_MT_POSITION_Y".into(),
        mt::ABS_MT_SLOT => "ABS_MT_SLOT".into(),
        _ => format!("0x{code:02x}"),
    }
}

/// The issues of a recording, capped at [`MAX_WARNINGS`].
#[derive(Debug, Default)]
struct Warnings {
    list: Vec<RecordingIssue>,
    dropped: usize,
}

impl Warnings {
    fn push(&mut self, line: usize, message: String) {
        if self.list.len() < MAX_WARNINGS {
            self.list.push(RecordingIssue { line, message });
        } else {
            self.dropped += 1;
        }
    }

    fn finish(mut self) -> Vec<RecordingIssue> {
        if self.dropped > 0 {
            self.list.push(RecordingIssue {
                line: 0,
                message: format!("{} more issues not listed", self.dropped),
            });
        }
        self.list
    }
}

/// Feeds evdev events into an [`MtDecoder`] and collects the frames.
struct EventStream<'a> {
    path: &'a Path,
    on_bad: OnBadFrame,
    decoder: MtDecoder,
    surface: SurfaceInfo,
    declared: [bool; ABS_MAX as usize + 1],
    frames: Vec<TouchFrame>,
    frame: TouchFrame,
    /// Absolute time of the first event, µs.
    first_us: Option<u64>,
    /// Absolute time of the last accepted event, µs.
    last_us: u64,
    /// Events fed since the last frame closed.
    pending_events: usize,
    warnings: Warnings,
}

impl<'a> EventStream<'a> {
    fn new(
        path: &'a Path,
        on_bad: OnBadFrame,
        axes: MtAxes,
        surface: SurfaceInfo,
        header: &DeviceHeader,
        warnings: Warnings,
    ) -> Self {
        let mut declared = [false; ABS_MAX as usize + 1];
        for (d, a) in declared.iter_mut().zip(header.abs.iter()) {
            *d = a.is_some();
        }
        EventStream {
            path,
            on_bad,
            decoder: MtDecoder::new(axes, 1),
            surface,
            declared,
            frames: Vec::new(),
            frame: TouchFrame::default(),
            first_us: None,
            last_us: 0,
            pending_events: 0,
            warnings,
        }
    }

    /// Reports a bad event: fails, or skips its frame (up to and including the
    /// next `SYN_REPORT`).
    fn bad(&mut self, line: usize, message: String) -> Result<(), RecordingError> {
        self.bad_at(line, message, false)
    }

    /// As [`EventStream::bad`]; `closes_frame` when the bad event is itself the
    /// frame's `SYN_REPORT`, so the next frame is kept.
    fn bad_at(
        &mut self,
        line: usize,
        message: String,
        closes_frame: bool,
    ) -> Result<(), RecordingError> {
        match self.on_bad {
            OnBadFrame::Stop => Err(RecordingError::Parse {
                path: self.path.to_path_buf(),
                line,
                message,
            }),
            OnBadFrame::Skip => {
                self.warnings
                    .push(line, format!("{message}; frame skipped"));
                if closes_frame {
                    self.decoder.discard_staged();
                } else {
                    self.decoder.discard_frame();
                }
                self.pending_events = 0;
                Ok(())
            }
        }
    }

    /// One event at absolute time `time_us`.
    fn event(
        &mut self,
        line: usize,
        time_us: u64,
        ev_type: u16,
        code: u16,
        value: i32,
    ) -> Result<(), RecordingError> {
        if time_us < self.last_us {
            return self.bad_at(
                line,
                format!(
                    "timestamp {} goes back before the previous event's {}",
                    fmt_time(time_us),
                    fmt_time(self.last_us)
                ),
                ev_type == mt::EV_SYN && code == mt::SYN_REPORT,
            );
        }
        if ev_type == mt::EV_ABS {
            if code > ABS_MAX {
                return self.bad(
                    line,
                    format!("unknown axis code 0x{code:x} (the highest is 0x{ABS_MAX:x})"),
                );
            }
            if !self.declared[code as usize] {
                return self.bad(
                    line,
                    format!(
                        "event for axis 0x{code:02x}, which the device header does not declare"
                    ),
                );
            }
        }
        let first = *self.first_us.get_or_insert(time_us);
        self.last_us = time_us;
        let t = Micros(time_us - first);
        self.pending_events += 1;
        if self.decoder.event(t, ev_type, code, value, &mut self.frame) {
            self.frames.push(self.frame);
            self.pending_events = 0;
        }
        Ok(())
    }

    fn finish(mut self) -> Result<Recording, RecordingError> {
        if self.pending_events > 0 {
            self.warnings.push(
                0,
                format!(
                    "{} events after the last SYN_REPORT were ignored",
                    self.pending_events
                ),
            );
        }
        if let Some(last) = self.frames.last().map(|f| f.t) {
            if self
                .decoder
                .cancel_all(last + Micros(END_CANCEL_US), &mut self.frame)
            {
                self.frames.push(self.frame);
            }
        }
        let c = self.decoder.counters();
        let type_b = self.decoder.protocol() == mt::MtProtocol::B;
        let notes = [
            (
                c.slot_out_of_range,
                "ABS_MT_SLOT values out of range (their events ignored)",
            ),
            (c.frame_overflow, "contacts did not fit a frame"),
            (
                c.dropped_sync,
                "SYN_DROPPED events (frames discarded, no resync)",
            ),
            (
                if type_b { c.mt_report } else { 0 },
                "SYN_MT_REPORT events ignored (the device declares slots: protocol B)",
            ),
            (
                c.transient_contacts,
                "contacts began and ended inside one frame (not reported)",
            ),
            (
                c.tracking_id_reused,
                "tracking ids sent again on an active slot (contact continued)",
            ),
            (
                c.contacts_over_capacity,
                "protocol A packets beyond the capacity of a frame (dropped)",
            ),
            (
                c.unterminated_packets,
                "protocol A packets not closed by SYN_MT_REPORT (kept)",
            ),
            (
                c.packets_after_lift,
                "protocol A packets in a frame with BTN_TOUCH 0 (ignored)",
            ),
        ];
        for (n, what) in notes {
            if n > 0 {
                self.warnings.push(0, format!("{n} {what}"));
            }
        }
        if self.frames.is_empty() {
            return Err(RecordingError::Empty {
                path: self.path.to_path_buf(),
            });
        }
        Ok(Recording {
            surface: self.surface,
            frames: self.frames,
            warnings: self.warnings.finish(),
        })
    }
}

fn fmt_time(us: u64) -> String {
    format!("{}.{:06}", us / 1_000_000, us % 1_000_000)
}

fn default_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "unknown device".to_string())
}

// ---------------------------------------------------------------------------
// evemu

/// Parses `sec.usec` into microseconds.
fn parse_evemu_time(s: &str) -> Result<u64, String> {
    let bad = || format!("timestamp `{s}` is not `seconds.microseconds`");
    let (sec, frac) = s.split_once('.').unwrap_or((s, ""));
    if sec.is_empty() || !sec.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    if !frac.bytes().all(|b| b.is_ascii_digit()) || frac.len() > 9 {
        return Err(bad());
    }
    let sec: u64 = sec.parse().map_err(|_| bad())?;
    let mut usec: u64 = 0;
    for (i, b) in frac.bytes().take(6).enumerate() {
        usec += u64::from(b - b'0') * 10u64.pow(5 - i as u32);
    }
    sec.checked_mul(1_000_000)
        .and_then(|v| v.checked_add(usec))
        .ok_or_else(|| format!("timestamp `{s}` is out of range"))
}

/// The fields of an evemu line after its `X:` prefix, up to a `#` comment.
fn evemu_fields(rest: &str) -> impl Iterator<Item = &str> {
    rest.split_whitespace().take_while(|t| !t.starts_with('#'))
}

/// Parses an `E:` line into `(time_us, type, code, value)`.
fn parse_evemu_event(rest: &str) -> Result<(u64, u16, u16, i32), String> {
    let mut f = [""; 4];
    let mut n = 0;
    for tok in evemu_fields(rest) {
        if n < 4 {
            f[n] = tok;
        }
        n += 1;
    }
    if n != 4 {
        return Err(format!(
            "an event line needs 4 fields (`E: sec.usec type code value`), found {n}"
        ));
    }
    let time = parse_evemu_time(f[0])?;
    let ty = u16::from_str_radix(f[1], 16)
        .map_err(|_| format!("event type `{}` is not a 16-bit hex number", f[1]))?;
    let code = u16::from_str_radix(f[2], 16)
        .map_err(|_| format!("event code `{}` is not a 16-bit hex number", f[2]))?;
    let value: i32 = f[3]
        .parse()
        .map_err(|_| format!("event value `{}` is not a 32-bit decimal integer", f[3]))?;
    Ok((time, ty, code, value))
}

/// Applies one header line (`N:`, `I:`, `P:`, `B:`, `A:`) to `hdr`.
fn evemu_header_line(hdr: &mut DeviceHeader, line: usize, l: &str) -> Result<(), String> {
    let rest = l[2..].trim();
    match &l[..2] {
        "N:" => {
            hdr.name = Some(rest.to_string());
            Ok(())
        }
        "A:" => {
            let toks: Vec<&str> = evemu_fields(rest).collect();
            if !(5..=6).contains(&toks.len()) {
                return Err(format!(
                    "an axis line needs `A: code min max fuzz flat [resolution]`, found {} fields",
                    toks.len()
                ));
            }
            let code = u16::from_str_radix(toks[0], 16)
                .map_err(|_| format!("axis code `{}` is not a hex number", toks[0]))?;
            if code > ABS_MAX {
                return Err(format!(
                    "unknown axis code 0x{code:x} (the highest is 0x{ABS_MAX:x})"
                ));
            }
            let mut v = [0i32; 5];
            for (i, tok) in toks[1..].iter().enumerate() {
                let what = ["min", "max", "fuzz", "flat", "resolution"][i];
                v[i] = tok
                    .parse()
                    .map_err(|_| format!("axis 0x{code:02x} {what} `{tok}` is not an integer"))?;
            }
            if hdr.abs[code as usize].is_some() {
                return Err(format!("axis 0x{code:02x} is declared twice"));
            }
            hdr.abs[code as usize] = Some(AbsInfo {
                min: v[0],
                max: v[1],
                resolution: v[4],
                line,
            });
            Ok(())
        }
        // Bus/vendor/product, properties and capability bits are not needed.
        _ => Ok(()),
    }
}

/// Parses evemu text, with the header in `desc` or at the top of `text`.
fn parse_evemu(
    desc: Option<&str>,
    text: &str,
    path: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    let mut hdr = DeviceHeader::default();
    let mut warnings = Warnings::default();
    if let Some(desc) = desc {
        let ctx = HeaderCtx {
            path,
            prefix: "in the device description: ",
        };
        let desc = desc.strip_prefix('\u{feff}').unwrap_or(desc);
        for (i, raw) in desc.lines().enumerate() {
            let l = raw.trim();
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            if l.starts_with("E:") {
                warnings.push(
                    0,
                    "the device description holds events; they are ignored".into(),
                );
                break;
            }
            if !is_evemu_line(l) {
                return Err(ctx.err(i + 1, "unrecognised line (expected N:, I:, P:, B: or A:)"));
            }
            evemu_header_line(&mut hdr, i + 1, l).map_err(|m| ctx.err(i + 1, m))?;
        }
    }
    let ctx = HeaderCtx { path, prefix: "" };
    // Header problems point into the description when there is one.
    let hctx = HeaderCtx {
        path,
        prefix: if desc.is_some() {
            "in the device description: "
        } else {
            ""
        },
    };
    let dflt = default_name(path);
    let mut stream: Option<EventStream<'_>> = None;
    let mut warnings = Some(warnings);
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        if let Some(rest) = l.strip_prefix("E:") {
            if stream.is_none() {
                let mut w = warnings.take().unwrap_or_default();
                let at = if desc.is_some() { 1 } else { line };
                let (axes, surface) = hdr.mt_axes(&hctx, at, &dflt, &mut w)?;
                stream = Some(EventStream::new(path, on_bad, axes, surface, &hdr, w));
            }
            let Some(s) = stream.as_mut() else { continue };
            match parse_evemu_event(rest) {
                Ok((time, ty, code, value)) => s.event(line, time, ty, code, value)?,
                Err(m) => s.bad(line, m)?,
            }
        } else if is_evemu_line(l) {
            match (&mut stream, desc.is_some()) {
                // The description is authoritative; a header repeated in the
                // events file is ignored.
                (_, true) => {}
                (None, false) => {
                    evemu_header_line(&mut hdr, line, l).map_err(|m| ctx.err(line, m))?
                }
                (Some(s), false) => s.bad(line, "header line after the first event".into())?,
            }
        } else {
            let m = "unrecognised line (expected N:, I:, P:, B:, A: or E:)".to_string();
            match &mut stream {
                Some(s) => s.bad(line, m)?,
                None => return Err(ctx.err(line, m)),
            }
        }
    }
    match stream {
        Some(s) => s.finish(),
        None => {
            // A header with no events: say what is wrong with the device first.
            let mut w = warnings.take().unwrap_or_default();
            hdr.mt_axes(&hctx, 1, &dflt, &mut w)?;
            Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
    }
}

/// Reads an evemu file without decoding it: the device's capabilities (`N:`,
/// `I:`, `P:`, `B:`, `A:` lines; `L:`/`S:` state lines are skipped) and every
/// `E:` event, with its time as written (µs).
///
/// `text` may be a whole `.evemu` file, a `.desc`/`.prop` (no events), or a
/// description followed by its `.events`. `name` is used in errors, and as the
/// device name when there is no `N:` line. Bitmask lines add 8 bytes each to
/// their type's bitmask, as evemu reads them; bits beyond what
/// [`EvdevCapabilities`] keeps must be zero.
///
/// # Errors
/// [`RecordingError::Parse`] at the first malformed line (also a header line
/// after the first event).
pub fn read_evemu_raw(
    text: &str,
    name: &Path,
) -> Result<(EvdevCapabilities, Vec<RawEvent>), RecordingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut caps = EvdevCapabilities::new(default_name(name));
    let mut prop_bytes = 0usize;
    let mut mask_bytes = [0usize; EV_CNT];
    let mut events = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let perr = |message: String| RecordingError::Parse {
            path: name.to_path_buf(),
            line,
            message,
        };
        if let Some(rest) = l.strip_prefix("E:") {
            let (time, ev_type, code, value) = parse_evemu_event(rest).map_err(perr)?;
            events.push(RawEvent {
                t: Micros(time),
                ev_type,
                code,
                value,
            });
            continue;
        }
        if !is_evemu_line(l) {
            return Err(perr(
                "unrecognised line (expected N:, I:, P:, B:, A:, L:, S: or E:)".into(),
            ));
        }
        if !events.is_empty() {
            return Err(perr("header line after the first event".into()));
        }
        caps_header_line(&mut caps, &mut prop_bytes, &mut mask_bytes, l).map_err(perr)?;
    }
    Ok((caps, events))
}

/// Parses a hex byte of a bitmask line.
fn hex_byte(tok: &str) -> Result<u8, String> {
    u8::from_str_radix(tok, 16).map_err(|_| format!("`{tok}` is not a hex byte"))
}

/// Applies one evemu header line to a capability snapshot.
fn caps_header_line(
    caps: &mut EvdevCapabilities,
    prop_bytes: &mut usize,
    mask_bytes: &mut [usize; EV_CNT],
    l: &str,
) -> Result<(), String> {
    let rest = l[2..].trim();
    let toks: Vec<&str> = evemu_fields(rest).collect();
    match &l[..2] {
        "N:" => caps.name = rest.to_string(),
        "I:" => {
            if toks.len() != 4 {
                return Err(format!(
                    "an id line needs `I: bus vendor product version`, found {} fields",
                    toks.len()
                ));
            }
            let mut v = [0u16; 4];
            for (k, tok) in toks.iter().enumerate() {
                v[k] = u16::from_str_radix(tok, 16)
                    .map_err(|_| format!("id field `{tok}` is not a 16-bit hex number"))?;
            }
            [caps.bus, caps.vendor, caps.product, caps.version] = v;
        }
        "P:" => {
            for tok in &toks {
                let b = hex_byte(tok)?;
                if *prop_bytes < PROP_BYTES {
                    for bit in 0..8 {
                        if (b >> bit) & 1 == 1 {
                            caps.set_property((*prop_bytes * 8 + bit) as u16);
                        }
                    }
                } else if b != 0 {
                    return Err(format!(
                        "property bits beyond the first {} bytes are not supported",
                        PROP_BYTES
                    ));
                }
                *prop_bytes += 1;
            }
        }
        "B:" => {
            let Some((ty, bytes)) = toks.split_first() else {
                return Err("a bitmask line needs `B: type bytes...`".into());
            };
            let ty = u16::from_str_radix(ty, 16)
                .ok()
                .filter(|&t| usize::from(t) < EV_CNT)
                .ok_or_else(|| format!("event type `{ty}` is not a hex number below 0x20"))?;
            let at = &mut mask_bytes[usize::from(ty)];
            for tok in bytes {
                let b = hex_byte(tok)?;
                if *at < MASK_BYTES {
                    let old = caps.mask(ty)[*at];
                    caps.set_mask_byte(ty, *at, old | b);
                } else if b != 0 {
                    return Err(format!(
                        "type 0x{ty:02x} bits beyond the first {MASK_BYTES} bytes are not supported"
                    ));
                }
                *at += 1;
            }
        }
        "A:" => {
            if !(5..=6).contains(&toks.len()) {
                return Err(format!(
                    "an axis line needs `A: code min max fuzz flat [resolution]`, found {} fields",
                    toks.len()
                ));
            }
            let code = u16::from_str_radix(toks[0], 16)
                .ok()
                .filter(|&c| c <= ABS_MAX)
                .ok_or_else(|| format!("axis code `{}` is not a hex number up to 0x3f", toks[0]))?;
            let mut v = [0i32; 5];
            for (k, tok) in toks[1..].iter().enumerate() {
                let what = ["min", "max", "fuzz", "flat", "resolution"][k];
                v[k] = tok
                    .parse()
                    .map_err(|_| format!("axis 0x{code:02x} {what} `{tok}` is not an integer"))?;
            }
            caps.set_abs(
                code,
                AbsAxisInfo {
                    value: 0,
                    minimum: v[0],
                    maximum: v[1],
                    fuzz: v[2],
                    flat: v[3],
                    resolution: v[4],
                },
            );
        }
        // LED and switch states: not capabilities.
        _ => {}
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// libinput record YAML

/// A YAML node with the line it starts on.
#[derive(Debug)]
enum Node {
    Scalar(String, usize),
    Seq(Vec<Node>, usize),
    /// Keys and values alternate.
    Map(Vec<Node>, usize),
    Alias(usize),
}

impl Node {
    fn line(&self) -> usize {
        match self {
            Node::Scalar(_, l) | Node::Seq(_, l) | Node::Map(_, l) | Node::Alias(l) => *l,
        }
    }

    fn kind(&self) -> &'static str {
        match self {
            Node::Scalar(..) => "a scalar",
            Node::Seq(..) => "a list",
            Node::Map(..) => "a mapping",
            Node::Alias(..) => "an alias",
        }
    }

    /// The value of `key` in a mapping.
    fn get(&self, key: &str) -> Option<&Node> {
        let Node::Map(kv, _) = self else { return None };
        kv.chunks_exact(2).find_map(|p| match &p[0] {
            Node::Scalar(k, _) if k == key => Some(&p[1]),
            _ => None,
        })
    }

    fn is_null(&self) -> bool {
        matches!(self, Node::Scalar(s, _) if s.is_empty() || s == "~" || s == "null")
    }

    fn as_i64(&self) -> Option<i64> {
        match self {
            Node::Scalar(s, _) => s.parse().ok(),
            _ => None,
        }
    }
}

/// Builds a [`Node`] tree from parser events.
#[derive(Default)]
struct TreeBuilder {
    stack: Vec<Node>,
    root: Option<Node>,
}

impl TreeBuilder {
    fn add(&mut self, node: Node) {
        match self.stack.last_mut() {
            Some(Node::Seq(items, _) | Node::Map(items, _)) => items.push(node),
            _ => {
                if self.root.is_none() {
                    self.root = Some(node);
                }
            }
        }
    }
}

impl yaml_rust2::parser::MarkedEventReceiver for TreeBuilder {
    fn on_event(&mut self, ev: yaml_rust2::Event, mark: yaml_rust2::scanner::Marker) {
        use yaml_rust2::Event;
        let line = mark.line();
        match ev {
            Event::Scalar(s, ..) => self.add(Node::Scalar(s, line)),
            Event::Alias(_) => self.add(Node::Alias(line)),
            Event::SequenceStart(..) => self.stack.push(Node::Seq(Vec::new(), line)),
            Event::MappingStart(..) => self.stack.push(Node::Map(Vec::new(), line)),
            Event::SequenceEnd | Event::MappingEnd => {
                if let Some(n) = self.stack.pop() {
                    self.add(n);
                }
            }
            _ => {}
        }
    }
}

/// Refuses YAML nested deeper than the parser can take without deep recursion.
fn check_yaml_depth(text: &str) -> Result<(), (usize, String)> {
    let mut depth = 0usize;
    for (i, l) in text.lines().enumerate() {
        let indent = l
            .bytes()
            .take_while(|b| matches!(b, b' ' | b'\t' | b'-' | b'?' | b':'))
            .count();
        if indent > MAX_YAML_INDENT && !l[indent..].starts_with('#') && indent < l.len() {
            return Err((
                i + 1,
                format!("indentation deeper than {MAX_YAML_INDENT} columns"),
            ));
        }
        let code = l.split(" #").next().unwrap_or(l);
        for b in code.bytes() {
            match b {
                b'[' | b'{' => depth += 1,
                b']' | b'}' => depth = depth.saturating_sub(1),
                _ => {}
            }
            if depth > MAX_YAML_FLOW_DEPTH {
                return Err((
                    i + 1,
                    format!("brackets nested deeper than {MAX_YAML_FLOW_DEPTH}"),
                ));
            }
        }
    }
    Ok(())
}

fn parse_libinput_yaml(
    text: &str,
    path: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    let perr = |line: usize, message: String| RecordingError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    check_yaml_depth(text).map_err(|(l, m)| perr(l, m))?;
    let mut tree = TreeBuilder::default();
    // yaml-rust2 is third-party code: a panic on some odd input must not
    // escape as one from our reader.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut parser = yaml_rust2::parser::Parser::new_from_str(text);
        parser.load(&mut tree, false)
    }));
    match parsed {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            return Err(perr(
                e.marker().line(),
                format!("invalid YAML: {}", e.info()),
            ))
        }
        Err(_) => return Err(perr(1, "invalid YAML (the parser failed)".to_string())),
    }
    let Some(root) = tree.root else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    };
    fn field<'n>(
        parent: &'n Node,
        key: &str,
        what: &str,
        path: &Path,
    ) -> Result<&'n Node, RecordingError> {
        parent.get(key).ok_or_else(|| RecordingError::Parse {
            path: path.to_path_buf(),
            line: parent.line(),
            message: format!("missing field `{what}`"),
        })
    }
    let version = field(&root, "version", "version", path)?;
    match version.as_i64() {
        Some(1) => {}
        Some(v) => {
            return Err(RecordingError::Unsupported {
                path: path.to_path_buf(),
                reason: UnsupportedReason::Version {
                    format: "libinput record",
                    version: v,
                },
            })
        }
        None => {
            return Err(perr(
                version.line(),
                format!(
                    "field `version`: expected an integer, found {}",
                    version.kind()
                ),
            ))
        }
    }
    let devices = field(&root, "devices", "devices", path)?;
    let dev = match devices {
        Node::Seq(items, _) if !items.is_empty() => &items[0],
        other => {
            return Err(perr(
                other.line(),
                format!(
                    "field `devices`: expected a non-empty list, found {}",
                    other.kind()
                ),
            ))
        }
    };
    let mut warnings = Warnings::default();
    if let Node::Seq(items, _) = devices {
        if items.len() > 1 {
            warnings.push(items[1].line(), "only the first device is read".into());
        }
    }
    if !matches!(dev, Node::Map(..)) {
        return Err(perr(
            dev.line(),
            format!(
                "field `devices[0]`: expected a mapping, found {}",
                dev.kind()
            ),
        ));
    }
    let evdev = field(dev, "evdev", "devices[0].evdev", path)?;
    let mut hdr = DeviceHeader::default();
    if let Some(Node::Scalar(s, _)) = evdev.get("name") {
        hdr.name = Some(s.clone());
    }
    let absinfo = field(evdev, "absinfo", "devices[0].evdev.absinfo", path)?;
    let Node::Map(kv, _) = absinfo else {
        return Err(perr(
            absinfo.line(),
            format!(
                "field `devices[0].evdev.absinfo`: expected a mapping, found {}",
                absinfo.kind()
            ),
        ));
    };
    for pair in kv.chunks_exact(2) {
        let (k, v) = (&pair[0], &pair[1]);
        let code = k.as_i64().ok_or_else(|| {
            perr(
                k.line(),
                "field `absinfo`: axis codes must be integers".to_string(),
            )
        })?;
        if !(0..=i64::from(ABS_MAX)).contains(&code) {
            return Err(perr(
                k.line(),
                format!("field `absinfo`: unknown axis code {code} (the highest is {ABS_MAX})"),
            ));
        }
        let f = format!("absinfo.{code}");
        let vals = int_list(v, &f, 4..=5).map_err(|m| perr(v.line(), m))?;
        let get = |i: usize| vals.get(i).copied().unwrap_or(0);
        let to_i32 = |x: i64| {
            i32::try_from(x)
                .map_err(|_| perr(v.line(), format!("field `{f}`: {x} is out of range")))
        };
        if hdr.abs[code as usize].is_some() {
            return Err(perr(
                k.line(),
                format!("field `absinfo`: axis {code} is declared twice"),
            ));
        }
        hdr.abs[code as usize] = Some(AbsInfo {
            min: to_i32(get(0))?,
            max: to_i32(get(1))?,
            resolution: to_i32(get(4))?,
            line: v.line(),
        });
    }
    let ctx = HeaderCtx { path, prefix: "" };
    let (axes, surface) = hdr.mt_axes(&ctx, absinfo.line(), &default_name(path), &mut warnings)?;
    let mut stream = EventStream::new(path, on_bad, axes, surface, &hdr, warnings);
    let events = match dev.get("events") {
        None => {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
        Some(n) if n.is_null() => {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
        Some(Node::Seq(items, _)) => items,
        Some(other) => {
            return Err(perr(
                other.line(),
                format!(
                    "field `devices[0].events`: expected a list, found {}",
                    other.kind()
                ),
            ))
        }
    };
    for (fi, frame) in events.iter().enumerate() {
        let Some(list) = frame.get("evdev") else {
            if !matches!(frame, Node::Map(..)) {
                stream.bad(
                    frame.line(),
                    format!(
                        "field `events[{fi}]`: expected a mapping, found {}",
                        frame.kind()
                    ),
                )?;
            }
            continue; // libinput events and other keys are not needed.
        };
        let Node::Seq(evs, _) = list else {
            stream.bad(
                list.line(),
                format!(
                    "field `events[{fi}].evdev`: expected a list, found {}",
                    list.kind()
                ),
            )?;
            continue;
        };
        for (ei, ev) in evs.iter().enumerate() {
            let f = format!("events[{fi}].evdev[{ei}]");
            match yaml_event(ev, &f) {
                Ok((time, ty, code, value)) => stream.event(ev.line(), time, ty, code, value)?,
                Err(m) => stream.bad(ev.line(), m)?,
            }
        }
    }
    stream.finish()
}

/// A list of integers of a length in `len`.
fn int_list(
    n: &Node,
    field: &str,
    len: std::ops::RangeInclusive<usize>,
) -> Result<Vec<i64>, String> {
    let Node::Seq(items, _) = n else {
        return Err(format!(
            "field `{field}`: expected a list of integers, found {}",
            n.kind()
        ));
    };
    if !len.contains(&items.len()) {
        return Err(format!(
            "field `{field}`: expected {} to {} integers, found {}",
            len.start(),
            len.end(),
            items.len()
        ));
    }
    items
        .iter()
        .enumerate()
        .map(|(i, it)| {
            it.as_i64().ok_or_else(|| match it {
                Node::Scalar(s, _) => format!("field `{field}[{i}]`: `{s}` is not an integer"),
                other => format!(
                    "field `{field}[{i}]`: expected an integer, found {}",
                    other.kind()
                ),
            })
        })
        .collect()
}

/// `[sec, usec, type, code, value]` → `(time_us, type, code, value)`.
fn yaml_event(n: &Node, field: &str) -> Result<(u64, u16, u16, i32), String> {
    let v = int_list(n, field, 5..=5)?;
    let range = |i: usize, what: &str, ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(format!(
                "field `{field}[{i}]` ({what}): {} is out of range",
                v[i]
            ))
        }
    };
    range(0, "seconds", v[0] >= 0)?;
    range(1, "microseconds", v[1] >= 0)?;
    range(2, "type", u16::try_from(v[2]).is_ok())?;
    range(3, "code", u16::try_from(v[3]).is_ok())?;
    range(4, "value", i32::try_from(v[4]).is_ok())?;
    let time = (v[0] as u64)
        .checked_mul(1_000_000)
        .and_then(|s| s.checked_add(v[1] as u64))
        .ok_or_else(|| format!("field `{field}`: timestamp out of range"))?;
    Ok((time, v[2] as u16, v[3] as u16, v[4] as i32))
}

// ---------------------------------------------------------------------------
// crowdtouch JSON Lines

fn want_obj<'v>(v: Option<&'v Value>, field: &str) -> Result<&'v Map<String, Value>, String> {
    match v {
        Some(Value::Object(m)) => Ok(m),
        Some(o) => Err(format!(
            "field `{field}`: expected an object, found {}",
            json_kind(o)
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn want_f64(v: Option<&Value>, field: &str) -> Result<f64, String> {
    match v {
        Some(Value::Number(n)) => n
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("field `{field}`: {n} is not a finite number")),
        Some(o) => Err(format!(
            "field `{field}`: expected a number, found {}",
            json_kind(o)
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn want_u64(v: Option<&Value>, field: &str) -> Result<u64, String> {
    match v {
        Some(Value::Number(n)) => n
            .as_u64()
            .ok_or_else(|| format!("field `{field}`: {n} is not a non-negative integer")),
        Some(o) => Err(format!(
            "field `{field}`: expected a non-negative integer, found {}",
            json_kind(o)
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn want_u32(v: Option<&Value>, field: &str) -> Result<u32, String> {
    let n = want_u64(v, field)?;
    u32::try_from(n).map_err(|_| format!("field `{field}`: {n} does not fit 32 bits"))
}

fn parse_json_line(l: &str) -> Result<Map<String, Value>, String> {
    match serde_json::from_str::<Value>(l) {
        Ok(Value::Object(m)) => Ok(m),
        Ok(o) => Err(format!("expected a JSON object, found {}", json_kind(&o))),
        Err(e) => Err(format!("invalid JSON at column {}: {e}", e.column())),
    }
}

fn json_axis(dev: &Map<String, Value>, key: &str) -> Result<AxisRange, String> {
    let f = format!("device.{key}");
    let a = want_obj(dev.get(key), &f)?;
    let min = want_f64(a.get("min"), &format!("{f}.min"))?;
    let max = want_f64(a.get("max"), &format!("{f}.max"))?;
    if max <= min {
        return Err(format!("field `{f}`: empty range (min {min}, max {max})"));
    }
    let resolution = match a.get("resolution") {
        None | Some(Value::Null) => 0.0,
        r => want_f64(r, &format!("{f}.resolution"))?,
    };
    if resolution < 0.0 {
        return Err(format!("field `{f}.resolution`: {resolution} is negative"));
    }
    Ok(AxisRange {
        min,
        max,
        resolution,
    })
}

fn json_header(l: &str) -> Result<SurfaceInfo, String> {
    let m = parse_json_line(l)?;
    let Some(format) = m.get("format") else {
        return Err(format!(
            "missing header: the first line must be {{\"format\":\"{JSONL_FORMAT}\",\"version\":1,\"device\":{{…}}}}"
        ));
    };
    if format.as_str() != Some(JSONL_FORMAT) {
        return Err(format!(
            "field `format`: expected \"{JSONL_FORMAT}\", found {format}"
        ));
    }
    let dev = want_obj(m.get("device"), "device")?;
    let name = match dev.get("name") {
        Some(Value::String(s)) => s.clone(),
        Some(o) => {
            return Err(format!(
                "field `device.name`: expected a string, found {}",
                json_kind(o)
            ))
        }
        None => return Err("missing field `device.name`".to_string()),
    };
    let x = json_axis(dev, "x")?;
    let y = json_axis(dev, "y")?;
    let max_contacts = want_u32(dev.get("max_contacts"), "device.max_contacts")?;
    if max_contacts == 0 {
        return Err("field `device.max_contacts`: must be at least 1".to_string());
    }
    Ok(SurfaceInfo {
        name,
        x,
        y,
        max_contacts,
    })
}

/// One contact of a JSON Lines frame, still in file terms.
#[derive(Copy, Clone, Debug)]
struct FileContact {
    file_id: u32,
    contact: Contact,
}

/// Parses a frame line into `(t_us, contacts, cancelled ids)`, normalising positions.
fn json_frame(
    l: &str,
    s: &SurfaceInfo,
    contacts: &mut Vec<FileContact>,
    cancelled: &mut Vec<u32>,
    size_dropped: &mut bool,
) -> Result<u64, String> {
    contacts.clear();
    cancelled.clear();
    let m = parse_json_line(l)?;
    if m.contains_key("format") {
        return Err("a second header line".to_string());
    }
    let t_us = want_u64(m.get("t_us"), "t_us")?;
    let list = match m.get("contacts") {
        Some(Value::Array(a)) => a,
        Some(o) => {
            return Err(format!(
                "field `contacts`: expected an array, found {}",
                json_kind(o)
            ))
        }
        None => return Err("missing field `contacts`".to_string()),
    };
    if list.len() > MAX_CONTACTS {
        return Err(format!(
            "field `contacts`: {} contacts, more than the {MAX_CONTACTS} a frame holds",
            list.len()
        ));
    }
    for (i, c) in list.iter().enumerate() {
        let f = |k: &str| format!("contacts[{i}].{k}");
        let o = want_obj(Some(c), &format!("contacts[{i}]"))?;
        let file_id = want_u32(o.get("id"), &f("id"))?;
        if contacts.iter().any(|c| c.file_id == file_id) {
            return Err(format!(
                "field `{}`: id {file_id} appears twice in the frame",
                f("id")
            ));
        }
        let x = want_f64(o.get("x"), &f("x"))?;
        let y = want_f64(o.get("y"), &f("y"))?;
        let opt = |k: &str| -> Result<Option<f64>, String> {
            match o.get(k) {
                None | Some(Value::Null) => Ok(None),
                v => {
                    let x = want_f64(v, &f(k))?;
                    if x < 0.0 {
                        return Err(format!("field `{}`: {x} is negative", f(k)));
                    }
                    Ok(Some(x))
                }
            }
        };
        let pressure = opt("pressure")?;
        if let Some(p) = pressure {
            if p > 1.0 {
                return Err(format!("field `{}`: {p} is outside 0..=1", f("pressure")));
            }
        }
        let to_mm = |v: Option<f64>, dropped: &mut bool| {
            let v = v?;
            if s.x.resolution > 0.0 {
                Some((v / s.x.resolution) as f32)
            } else {
                *dropped = true;
                None
            }
        };
        let major_mm = to_mm(opt("major")?, size_dropped);
        let minor_mm = to_mm(opt("minor")?, size_dropped);
        let palm = match o.get("palm") {
            None | Some(Value::Null) => false,
            Some(Value::Bool(b)) => *b,
            Some(v) => {
                return Err(format!(
                    "field `{}`: expected a boolean, found {}",
                    f("palm"),
                    json_kind(v)
                ))
            }
        };
        let flags = if palm {
            ContactFlags::PALM
        } else {
            ContactFlags::NONE
        };
        contacts.push(FileContact {
            file_id,
            contact: Contact {
                id: ContactId(0),
                x: s.x.normalise(x),
                y: s.y.normalise(y),
                pressure: pressure.map(|p| p as f32),
                major_mm,
                minor_mm,
                flags,
            },
        });
    }
    match m.get("cancelled") {
        None | Some(Value::Null) => {}
        Some(Value::Array(a)) => {
            for (i, v) in a.iter().enumerate() {
                cancelled.push(want_u32(Some(v), &format!("cancelled[{i}]"))?);
            }
        }
        Some(o) => {
            return Err(format!(
                "field `cancelled`: expected an array, found {}",
                json_kind(o)
            ))
        }
    }
    Ok(t_us)
}

fn parse_jsonl(text: &str, path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    let perr = |line: usize, message: String| RecordingError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((hline, header)) = lines.next() else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    };
    let surface = json_header(header).map_err(|m| perr(hline, m))?;
    let mut warnings = Warnings::default();
    let mut frames: Vec<TouchFrame> = Vec::new();
    // Contacts down after the previous frame: (file id, contact).
    let mut down: Vec<FileContact> = Vec::new();
    let mut cur: Vec<FileContact> = Vec::new();
    let mut cancelled: Vec<u32> = Vec::new();
    let mut next_id: u32 = 1;
    let mut last_t: Option<u64> = None;
    let mut size_dropped = false;
    for (line, l) in lines {
        let parsed =
            json_frame(l, &surface, &mut cur, &mut cancelled, &mut size_dropped).and_then(|t| {
                match last_t {
                    Some(prev) if t < prev => Err(format!(
                        "field `t_us`: {t} is earlier than the previous frame's {prev}"
                    )),
                    _ => Ok(t),
                }
            });
        let t = match parsed {
            Ok(t) => t,
            Err(m) => match on_bad {
                OnBadFrame::Stop => return Err(perr(line, m)),
                OnBadFrame::Skip => {
                    warnings.push(line, format!("{m}; frame skipped"));
                    continue;
                }
            },
        };
        last_t = Some(t);
        let mut frame = TouchFrame::new(Micros(t));
        // Ended first, in the previous frame's order, at their last position.
        for d in &down {
            if !cur.iter().any(|c| c.file_id == d.file_id) {
                let mut c = d.contact;
                c.flags = ContactFlags(c.flags.0 & ContactFlags::PALM.0);
                c.flags.insert(if cancelled.contains(&d.file_id) {
                    ContactFlags::CANCELLED
                } else {
                    ContactFlags::UP
                });
                // At most 2 × MAX_CONTACTS; overflow keeps the first that fit.
                let _ = frame.push(c);
            }
        }
        for c in cur.iter_mut() {
            match down.iter().find(|d| d.file_id == c.file_id) {
                Some(d) => c.contact.id = d.contact.id,
                None => {
                    c.contact.id = ContactId(next_id);
                    next_id = next_id.wrapping_add(1);
                    c.contact.flags.insert(ContactFlags::DOWN);
                }
            }
            let _ = frame.push(c.contact);
            c.contact.flags = ContactFlags(c.contact.flags.0 & ContactFlags::PALM.0);
        }
        std::mem::swap(&mut down, &mut cur);
        frames.push(frame);
    }
    if size_dropped {
        warnings.push(
            0,
            "contact sizes (major/minor) ignored: the X axis resolution is unknown".into(),
        );
    }
    let Some(last) = frames.last().map(|f| f.t) else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    };
    if !down.is_empty() {
        let mut frame = TouchFrame::new(last + Micros(END_CANCEL_US));
        for d in &down {
            let mut c = d.contact;
            c.flags.insert(ContactFlags::CANCELLED);
            let _ = frame.push(c);
        }
        frames.push(frame);
    }
    Ok(Recording {
        surface,
        frames,
        warnings: warnings.finish(),
    })
}

#[derive(Serialize)]
struct AxisOut {
    min: f64,
    max: f64,
    #[serde(skip_serializing_if = "is_zero")]
    resolution: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

#[derive(Serialize)]
struct DeviceOut<'a> {
    name: &'a str,
    x: AxisOut,
    y: AxisOut,
    max_contacts: u32,
}

#[derive(Serialize)]
struct HeaderOut<'a> {
    format: &'static str,
    version: u64,
    device: DeviceOut<'a>,
}

#[derive(Debug, Serialize)]
struct ContactOut {
    id: u32,
    x: f64,
    y: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pressure: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    major: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minor: Option<f64>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    palm: bool,
}

#[derive(Serialize)]
struct FrameOut<'a> {
    t_us: u64,
    contacts: &'a [ContactOut],
    #[serde(skip_serializing_if = "<[u32]>::is_empty")]
    cancelled: &'a [u32],
}

fn axis_out(a: &AxisRange) -> AxisOut {
    AxisOut {
        min: a.min,
        max: a.max,
        resolution: a.resolution,
    }
}

/// Device units for a normalised coordinate, rounded to 1e-3 units.
fn to_device(a: &AxisRange, v: f32) -> f64 {
    let d = a.min + f64::from(v) * (a.max - a.min);
    (d * WRITE_SCALE).round() / WRITE_SCALE
}

/// Writes frames as crowdtouch JSON Lines: the inverse of the reader.
///
/// Positions go back to device units of `rec_surface` (rounded to 1e-3 units);
/// `t_us` is relative to the first frame. Each line lists the contacts down after
/// the frame (`UP`/`CANCELLED` contacts are left out; cancelled ids go in
/// `"cancelled"`), with their [`ContactId`] as file id. Reading the output back
/// gives the same contacts and flags, with ids renumbered from 1 in order of
/// appearance, positions within 1e-6 (relative), and an ended contact at its
/// position in the previous frame. Not representable, and so lost: the position
/// a contact had in the frame it ended in, and contacts that began and ended in
/// the same frame (`DOWN | UP`). `major`/`minor` are written only when the X
/// resolution is known.
///
/// # Errors
/// Whatever `w` returns.
pub fn write_jsonl(
    rec_surface: &SurfaceInfo,
    frames: &[TouchFrame],
    w: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let mut out = JsonlWriter::new(rec_surface, w)?;
    for f in frames {
        out.frame(f)?;
    }
    Ok(())
}

/// Writes our JSON Lines recording one frame at a time, as [`write_jsonl`] does
/// for a whole recording (same bytes): the header at creation, then one line per
/// [`JsonlWriter::frame`]. For recording a live device.
#[derive(Debug)]
pub struct JsonlWriter<'s, W: std::io::Write> {
    surface: &'s SurfaceInfo,
    out: W,
    t0: Option<Micros>,
    contacts: Vec<ContactOut>,
    cancelled: Vec<u32>,
    frames: u64,
}

impl<'s, W: std::io::Write> JsonlWriter<'s, W> {
    /// Writes the header line for a device of surface `rec_surface`.
    ///
    /// # Errors
    /// Whatever `out` returns.
    pub fn new(rec_surface: &'s SurfaceInfo, mut out: W) -> std::io::Result<Self> {
        let header = HeaderOut {
            format: JSONL_FORMAT,
            version: JSONL_VERSION,
            device: DeviceOut {
                name: &rec_surface.name,
                x: axis_out(&rec_surface.x),
                y: axis_out(&rec_surface.y),
                max_contacts: rec_surface.max_contacts,
            },
        };
        serde_json::to_writer(&mut out, &header)?;
        out.write_all(b"\n")?;
        Ok(JsonlWriter {
            surface: rec_surface,
            out,
            t0: None,
            contacts: Vec::with_capacity(MAX_CONTACTS),
            cancelled: Vec::with_capacity(MAX_CONTACTS),
            frames: 0,
        })
    }

    /// Writes one frame; times are relative to the first frame written.
    ///
    /// # Errors
    /// Whatever the writer returns.
    pub fn frame(&mut self, f: &TouchFrame) -> std::io::Result<()> {
        let t0 = *self.t0.get_or_insert(f.t);
        let rec_surface = self.surface;
        let res = rec_surface.x.resolution;
        let size = |mm: Option<f32>| {
            mm.filter(|_| res > 0.0)
                .map(|v| (f64::from(v) * res * WRITE_SCALE).round() / WRITE_SCALE)
        };
        self.contacts.clear();
        self.cancelled.clear();
        for c in f.contacts() {
            if c.flags.ended() {
                if c.flags.contains(ContactFlags::CANCELLED)
                    && !c.flags.contains(ContactFlags::DOWN)
                {
                    self.cancelled.push(c.id.0);
                }
                continue;
            }
            self.contacts.push(ContactOut {
                id: c.id.0,
                x: to_device(&rec_surface.x, c.x),
                y: to_device(&rec_surface.y, c.y),
                pressure: c.pressure,
                major: size(c.major_mm),
                minor: size(c.minor_mm),
                palm: c.flags.contains(ContactFlags::PALM),
            });
        }
        let line = FrameOut {
            t_us: f.t.saturating_since(t0).0,
            contacts: &self.contacts,
            cancelled: &self.cancelled,
        };
        serde_json::to_writer(&mut self.out, &line)?;
        self.out.write_all(b"\n")?;
        self.frames += 1;
        Ok(())
    }

    /// Frames written.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Flushes the writer.
    ///
    /// # Errors
    /// The writer's.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("t.jsonl")
    }

    const HEADER: &str = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"d","x":{"min":0,"max":1000,"resolution":10},"y":{"min":0,"max":500},"max_contacts":4}}"#;

    #[test]
    fn jsonl_derives_flags() {
        let text = format!(
            "{HEADER}\n# comment\n\n{}\n{}\n{}\n",
            r#"{"t_us":0,"contacts":[{"id":7,"x":100,"y":250}]}"#,
            r#"{"t_us":8333,"contacts":[{"id":7,"x":200,"y":250},{"id":9,"x":0,"y":0,"pressure":0.5}]}"#,
            r#"{"t_us":16666,"contacts":[{"id":9,"x":0,"y":0}]}"#,
        );
        let rec = parse_recording(&text, p(), OnBadFrame::Stop).unwrap();
        let fl: Vec<Vec<(u32, ContactFlags)>> = rec
            .frames
            .iter()
            .map(|f| f.contacts().iter().map(|c| (c.id.0, c.flags)).collect())
            .collect();
        assert_eq!(
            fl,
            vec![
                vec![(1, ContactFlags::DOWN)],
                vec![(1, ContactFlags::NONE), (2, ContactFlags::DOWN)],
                vec![(1, ContactFlags::UP), (2, ContactFlags::NONE)],
                vec![(2, ContactFlags::CANCELLED)],
            ]
        );
        assert_eq!(rec.frames[3].t, Micros(16_666 + END_CANCEL_US));
        // The lift is reported at the last position.
        assert!((rec.frames[2].contacts()[0].x - 0.2).abs() < 1e-6);
        assert_eq!(rec.frames[1].contacts()[1].pressure, Some(0.5));
        assert!((rec.frames[0].contacts()[0].y - 0.5).abs() < 1e-6);
    }

    #[test]
    fn evemu_time_forms() {
        assert_eq!(parse_evemu_time("0.000001"), Ok(1));
        assert_eq!(
            parse_evemu_time("1357751031.716015"),
            Ok(1_357_751_031_716_015)
        );
        assert_eq!(parse_evemu_time("2.5"), Ok(2_500_000));
        assert_eq!(parse_evemu_time("3"), Ok(3_000_000));
        assert!(parse_evemu_time("-1.0").is_err());
        assert!(parse_evemu_time("1.2.3").is_err());
        assert!(parse_evemu_time("99999999999999999999.0").is_err());
    }

    #[test]
    fn evemu_event_fields() {
        assert_eq!(
            parse_evemu_event(" 0.000001 0003 0039 -001\t# EV_ABS / ABS_MT_TRACKING_ID"),
            Ok((1, 3, 0x39, -1))
        );
        assert!(parse_evemu_event(" 0.1 0003 0035")
            .unwrap_err()
            .contains("4 fields"));
        assert!(parse_evemu_event(" 0.1 0003 zz 1")
            .unwrap_err()
            .contains("code"));
    }

    #[test]
    fn yaml_depth_guard() {
        let deep = "[".repeat(200);
        assert!(check_yaml_depth(&deep).is_err());
        assert!(check_yaml_depth("a:\n  - [1, 2]\n").is_ok());
    }

    #[test]
    fn deep_yaml_is_refused_or_survived() {
        let header = "version: 1\ndevices:\n";
        let dashes = format!("{header}{}x\n", "- ".repeat(100_000));
        assert!(matches!(
            parse_recording(&dashes, p(), OnBadFrame::Stop),
            Err(RecordingError::Parse { line: 3, .. })
        ));
        let flow = format!("{header}{}\n", "[".repeat(100_000));
        assert!(parse_recording(&flow, p(), OnBadFrame::Stop).is_err());
        // The deepest ladder the guard lets through parses on a test thread's stack.
        let mut ladder = String::from(header);
        for i in 0..MAX_YAML_INDENT {
            ladder.push_str(&" ".repeat(i));
            ladder.push_str("k:\n");
        }
        assert!(parse_recording(&ladder, p(), OnBadFrame::Stop).is_err());
    }

    #[test]
    fn yaml_marker_lines_are_one_based() {
        let text = "version: 1\ndevices:\n- evdev:\n    absinfo: 7\n";
        let err = parse_libinput_yaml(text, p(), OnBadFrame::Stop).unwrap_err();
        match err {
            RecordingError::Parse { line, message, .. } => {
                assert_eq!(line, 4, "{message}");
                assert!(message.contains("absinfo"), "{message}");
            }
            e => panic!("{e}"),
        }
    }
}
