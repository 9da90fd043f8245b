//! The evdev event stream shared by the evemu and libinput record readers: events
//! checked against the device header and fed to [`MtDecoder`], one frame handed
//! out at a time.
//!
//! A bad event fails the reading with [`OnBadFrame::Stop`]; with
//! [`OnBadFrame::Skip`] every event up to and including the next `SYN_REPORT` is
//! skipped and a warning recorded.

use super::error::{OnBadFrame, RecordingError};
use super::evdev_header::DeviceHeader;
use super::recording_type::END_CANCEL_US;
use super::warnings::Warnings;
use crate::input::evdev::{self as mt, MtAxes, MtDecoder, ABS_MAX};
use crate::vocab::{Micros, TouchFrame};
use std::path::Path;

/// Feeds evdev events into an [`MtDecoder`], a frame at a time.
pub(super) struct EventStream {
    on_bad: OnBadFrame,
    decoder: MtDecoder,
    declared: [bool; ABS_MAX as usize + 1],
    frame: TouchFrame,
    /// Frames handed out.
    frames: u64,
    /// Absolute time of the first event, µs.
    first_us: Option<u64>,
    /// Absolute time of the last accepted event, µs.
    last_us: u64,
    /// Relative time of the last frame.
    last_frame_t: Option<Micros>,
    /// Events fed since the last frame closed.
    pending_events: usize,
    /// The end was reached.
    ended: bool,
}

impl EventStream {
    pub(super) fn new(on_bad: OnBadFrame, axes: MtAxes, header: &DeviceHeader) -> Self {
        let mut declared = [false; ABS_MAX as usize + 1];
        for (d, a) in declared.iter_mut().zip(header.abs.iter()) {
            *d = a.is_some();
        }
        EventStream {
            on_bad,
            decoder: MtDecoder::new(axes, 1),
            declared,
            frame: TouchFrame::default(),
            frames: 0,
            first_us: None,
            last_us: 0,
            last_frame_t: None,
            pending_events: 0,
            ended: false,
        }
    }

    /// Reports a bad event: fails, or skips its frame (up to and including the
    /// next `SYN_REPORT`).
    pub(super) fn bad(
        &mut self,
        path: &Path,
        line: usize,
        message: String,
        w: &mut Warnings,
    ) -> Result<(), RecordingError> {
        self.bad_at(path, line, message, false, w)
    }

    /// As [`EventStream::bad`]; `closes_frame` when the bad event is itself the
    /// frame's `SYN_REPORT`, so the next frame is kept.
    fn bad_at(
        &mut self,
        path: &Path,
        line: usize,
        message: String,
        closes_frame: bool,
        w: &mut Warnings,
    ) -> Result<(), RecordingError> {
        match self.on_bad {
            OnBadFrame::Stop => Err(RecordingError::parse(path, line, message)),
            OnBadFrame::Skip => {
                w.push(line, format!("{message}; frame skipped"));
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

    /// One event at absolute time `time_us`; `true` when it closed a frame, which
    /// is then in `out`.
    pub(super) fn event(
        &mut self,
        path: &Path,
        line: usize,
        (time_us, ev_type, code, value): (u64, u16, u16, i32),
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<bool, RecordingError> {
        if time_us < self.last_us {
            let m = format!(
                "timestamp {} goes back before the previous event's {}",
                fmt_time(time_us),
                fmt_time(self.last_us)
            );
            let closes = ev_type == mt::EV_SYN && code == mt::SYN_REPORT;
            return self.bad_at(path, line, m, closes, w).map(|()| false);
        }
        if ev_type == mt::EV_ABS {
            if code > ABS_MAX {
                let m = format!("unknown axis code 0x{code:x} (the highest is 0x{ABS_MAX:x})");
                return self.bad(path, line, m, w).map(|()| false);
            }
            if !self.declared[code as usize] {
                let m = format!(
                    "event for axis 0x{code:02x}, which the device header does not declare"
                );
                return self.bad(path, line, m, w).map(|()| false);
            }
        }
        let first = *self.first_us.get_or_insert(time_us);
        self.last_us = time_us;
        let t = Micros(time_us - first);
        self.pending_events += 1;
        if self.decoder.event(t, ev_type, code, value, &mut self.frame) {
            *out = self.frame;
            self.frames += 1;
            self.last_frame_t = Some(self.frame.t);
            self.pending_events = 0;
            return Ok(true);
        }
        Ok(false)
    }

    /// The end of the events: the frame cancelling contacts still down (into
    /// `out`, `true`), and the decoder's counters as warnings. Later calls
    /// return `false`.
    ///
    /// # Errors
    /// [`RecordingError::Empty`] when no frame was decoded.
    pub(super) fn finish(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<bool, RecordingError> {
        if self.ended {
            return Ok(false);
        }
        self.ended = true;
        if self.pending_events > 0 {
            w.push(
                0,
                format!(
                    "{} events after the last SYN_REPORT were ignored",
                    self.pending_events
                ),
            );
        }
        let cancelled = match self.last_frame_t {
            Some(last) => self
                .decoder
                .cancel_all(last + Micros(END_CANCEL_US), &mut self.frame),
            None => false,
        };
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
                w.push(0, format!("{n} {what}"));
            }
        }
        if self.frames == 0 {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            });
        }
        if cancelled {
            *out = self.frame;
        }
        Ok(cancelled)
    }
}

fn fmt_time(us: u64) -> String {
    format!("{}.{:06}", us / 1_000_000, us % 1_000_000)
}
