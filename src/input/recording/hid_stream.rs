//! hid-recorder logs read a report at a time: the header up to the first input
//! report, then each `E:` line decoded by the first touch collection's
//! [`HidDecoder`] as it is read.
//!
//! Frames are timed relative to the first report. Contacts still down after the
//! last report get a `CANCELLED` frame [`END_CANCEL_US`] later. Reports the
//! decoder refuses (undeclared report ID, too short, Contact Count above the
//! maximum), and timestamps going back, fail the reading with
//! [`OnBadFrame::Stop`] and are skipped with a warning with [`OnBadFrame::Skip`];
//! reports of other collections are ignored and counted in a warning.

use super::error::{OnBadFrame, RecordingError};
use super::hid_recorder::{no_descriptor, other_devices_note, parse_event, HidHeader, HidLine};
use super::lines::{too_long_message, LineFault, LineReader};
use super::recording_type::END_CANCEL_US;
use super::warnings::Warnings;
use crate::input::hid::{touch_collections, HidCounters, HidDecoder};
use crate::input::SurfaceInfo;
use crate::vocab::{Micros, TouchFrame};
use std::path::Path;

/// Reads a hid-recorder log a frame at a time.
pub(super) struct HidReader {
    lines: LineReader,
    on_bad: OnBadFrame,
    header: HidHeader,
    dec: HidDecoder,
    /// The bytes of the report being decoded.
    bytes: Vec<u8>,
    /// The first report, read while looking for the end of the header.
    first: Option<(usize, Result<u64, String>)>,
    first_us: Option<u64>,
    last_us: u64,
    last_frame_t: Option<Micros>,
    frames: u64,
    other_events: usize,
    ended: bool,
}

impl HidReader {
    /// Reads the header up to the first input report and finds the touch collection.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad header line, an `E:` before the `R:`,
    /// no `R:`, a descriptor without a touch collection; [`RecordingError::Empty`]
    /// when there is no input report.
    pub(super) fn open(
        mut lines: LineReader,
        path: &Path,
        on_bad: OnBadFrame,
    ) -> Result<(HidReader, SurfaceInfo), RecordingError> {
        let perr = |line: usize, message: String| RecordingError::parse(path, line, message);
        let mut header = HidHeader::default();
        let mut bytes = Vec::new();
        let mut other_events = 0usize;
        let first = loop {
            let (line, l) = match lines.next_line() {
                Ok(Some((n, l))) => (n, l.trim()),
                Ok(None) => break None,
                Err(LineFault::TooLong) if header.has_descriptor() => {
                    lines
                        .skip_rest()
                        .map_err(|e| LineFault::Io(e).at(path, lines.line()))?;
                    break Some((lines.line(), Err(too_long_message())));
                }
                Err(f) => return Err(f.at(path, lines.line())),
            };
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            match header.take(line, l).map_err(|m| perr(line, m))? {
                HidLine::Header => {}
                HidLine::OtherEvent => other_events += 1,
                HidLine::Event(rest) => {
                    break Some((line, parse_event(rest, &mut bytes).map(|(t, _)| t)));
                }
            }
        };
        if !header.has_descriptor() {
            return Err(no_descriptor(path, lines.line()));
        }
        let collections = touch_collections(&header.descriptor).map_err(|e| {
            perr(
                header.descriptor_line,
                format!(
                    "the report descriptor has no multi-touch collection crowdtouch can read: {e}"
                ),
            )
        })?;
        let Some(tc) = collections.first() else {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            });
        };
        if first.is_none() {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            });
        }
        let default_name = path.file_stem().map_or_else(
            || "hid-recorder".to_string(),
            |s| s.to_string_lossy().into_owned(),
        );
        let surface = tc.surface(header.name.as_deref().unwrap_or(&default_name));
        let reader = HidReader {
            lines,
            on_bad,
            dec: HidDecoder::new(tc),
            header,
            bytes,
            first,
            first_us: None,
            last_us: 0,
            last_frame_t: None,
            frames: 0,
            other_events,
            ended: false,
        };
        Ok((reader, surface))
    }

    /// The source, for reading again from the start.
    pub(super) fn into_lines(self) -> LineReader {
        self.lines
    }

    /// Bytes read so far.
    pub(super) fn consumed(&self) -> u64 {
        self.lines.consumed()
    }

    /// A bad report: fails, or is skipped with a warning.
    fn bad(
        &self,
        path: &Path,
        line: usize,
        m: String,
        w: &mut Warnings,
    ) -> Result<(), RecordingError> {
        match self.on_bad {
            OnBadFrame::Stop => Err(RecordingError::parse(path, line, m)),
            OnBadFrame::Skip => {
                w.push(line, format!("{m}; report skipped"));
                Ok(())
            }
        }
    }

    /// The next frame into `out`, and the line of the report that completed it;
    /// `None` after the last.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad report with [`OnBadFrame::Stop`] and
    /// for a bad header line anywhere; [`RecordingError::Empty`] at the end when
    /// no frame was decoded.
    pub(super) fn next(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<Option<usize>, RecordingError> {
        loop {
            if self.ended {
                return Ok(None);
            }
            let (line, time) = match self.first.take() {
                Some(first) => first,
                None => {
                    let (line, l) = match self.lines.next_line() {
                        Ok(Some((n, l))) => (n, l.trim()),
                        Ok(None) => return self.end(path, out, w),
                        Err(LineFault::TooLong) => {
                            self.lines
                                .skip_rest()
                                .map_err(|e| LineFault::Io(e).at(path, self.lines.line()))?;
                            let line = self.lines.line();
                            self.bad(path, line, too_long_message(), w)?;
                            continue;
                        }
                        Err(f) => return Err(f.at(path, self.lines.line())),
                    };
                    if l.is_empty() || l.starts_with('#') {
                        continue;
                    }
                    let perr = |m| RecordingError::parse(path, line, m);
                    match self.header.take(line, l).map_err(perr)? {
                        HidLine::Header => continue,
                        HidLine::OtherEvent => {
                            self.other_events += 1;
                            continue;
                        }
                        HidLine::Event(rest) => {
                            self.bytes.clear();
                            (line, parse_event(rest, &mut self.bytes).map(|(t, _)| t))
                        }
                    }
                }
            };
            let time_us = match time {
                Ok(t) if t < self.last_us => {
                    let m = format!(
                        "timestamp {}.{:06} goes back before the previous report's {}.{:06}",
                        t / 1_000_000,
                        t % 1_000_000,
                        self.last_us / 1_000_000,
                        self.last_us % 1_000_000
                    );
                    self.bad(path, line, m, w)?;
                    continue;
                }
                Ok(t) => t,
                Err(m) => {
                    self.bad(path, line, m, w)?;
                    continue;
                }
            };
            let t0 = *self.first_us.get_or_insert(time_us);
            self.last_us = time_us;
            match self.dec.decode(Micros(time_us - t0), &self.bytes, out) {
                Ok(true) => {
                    self.frames += 1;
                    self.last_frame_t = Some(out.t);
                    return Ok(Some(line));
                }
                Ok(false) => {}
                Err(err) => self.bad(path, line, err.to_string(), w)?,
            }
        }
    }

    /// The end of the log: the frame cancelling contacts still down, and the
    /// warnings about the whole log.
    fn end(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<Option<usize>, RecordingError> {
        self.ended = true;
        if self.other_events > 0 {
            w.push(0, other_devices_note(self.other_events));
        }
        if self.dec.frame_pending() {
            w.push(
                0,
                "the last frame was incomplete (its Contact Count announced more contacts \
                 than followed); its changes are not delivered"
                    .into(),
            );
        }
        let cancelled = match self.last_frame_t {
            Some(last) => self.dec.cancel_all(last + Micros(END_CANCEL_US), out),
            None => false,
        };
        for (count, what) in counter_notes(&self.dec.counters()) {
            if count > 0 {
                w.push(0, format!("{count} {what}"));
            }
        }
        if self.frames == 0 {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            });
        }
        Ok(cancelled.then_some(self.lines.line()))
    }
}

/// Counters worth a warning.
fn counter_notes(c: &HidCounters) -> [(u64, &'static str); 5] {
    [
        (
            c.other_reports,
            "reports of other collections (pen, vendor) were ignored",
        ),
        (
            c.incomplete_frames,
            "frames started before the previous one completed (a report is missing)",
        ),
        (
            c.duplicate_contacts,
            "repeated Contact Identifiers within a frame were ignored",
        ),
        (
            c.contacts_over_capacity,
            "contacts above the device's maximum were ignored",
        ),
        (c.frame_overflow, "contacts did not fit a frame"),
    ]
}
