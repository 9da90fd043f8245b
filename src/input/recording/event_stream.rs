//! The evdev event stream shared by the evemu and libinput record readers: events
//! checked against the device header, fed to [`MtDecoder`], frames collected.
//!
//! A bad event fails the reading with [`OnBadFrame::Stop`]; with
//! [`OnBadFrame::Skip`] every event up to and including the next `SYN_REPORT` is
//! skipped and a warning recorded.

use super::error::{OnBadFrame, RecordingError};
use super::evdev_header::DeviceHeader;
use super::recording_type::{Recording, END_CANCEL_US};
use super::warnings::Warnings;
use crate::input::evdev::{self as mt, MtAxes, MtDecoder, ABS_MAX};
use crate::input::SurfaceInfo;
use crate::vocab::{Micros, TouchFrame};
use std::path::Path;

/// Feeds evdev events into an [`MtDecoder`] and collects the frames.
pub(super) struct EventStream<'a> {
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
    pub(super) fn new(
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
    pub(super) fn bad(&mut self, line: usize, message: String) -> Result<(), RecordingError> {
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
            OnBadFrame::Stop => Err(RecordingError::parse(self.path, line, message)),
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
    pub(super) fn event(
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

    pub(super) fn finish(mut self) -> Result<Recording, RecordingError> {
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
