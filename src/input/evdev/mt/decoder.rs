//! The decoder: one state machine over evdev events that stages changes between
//! two `SYN_REPORT`s, dispatches to the protocol decoders, handles `SYN_DROPPED`,
//! resynchronisation and cancelling, and turns device values into contacts. The
//! per-protocol methods of [`MtDecoder`] are in `protocol_b.rs`, `protocol_a.rs` and
//! `single_touch.rs`.

use super::axes::{MtAxes, MtProtocol};
use super::counters::MtCounters;
use super::packets::PacketState;
use super::slots::{MtSlotState, Slot, SlotValues, MAX_SLOTS};
use crate::input::evdev::codes::{
    ABS_MT_PRESSURE, ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, EV_SYN, MT_TOOL_PALM, SYN_DROPPED,
    SYN_MT_REPORT, SYN_REPORT,
};
use crate::input::AxisRange;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame};

/// One evdev input event: what a device node returns, what an evemu `E:` line
/// holds.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct RawEvent {
    /// Event time (kernel timestamp; for a recording, as written in the file).
    pub t: Micros,
    /// Event type (`EV_*`).
    pub ev_type: u16,
    /// Event code.
    pub code: u16,
    /// Event value.
    pub value: i32,
}

/// Decodes multi-touch events (type B, type A or single touch) into [`TouchFrame`]s.
///
/// # Complexity
/// `event` is O(1) except at `SYN_REPORT`: O(slots) for type B, O(n³) in the
/// number of anonymous contacts for type A (matching). No allocation after
/// [`MtDecoder::new`].
///
/// # Example
/// ```
/// use crowdtouch::input::evdev::*;
/// use crowdtouch::input::AxisRange;
/// use crowdtouch::vocab::{ContactFlags, TouchFrame};
/// use crowdtouch::vocab::Micros;
///
/// let r = AxisRange { min: 0.0, max: 1000.0, resolution: 10.0 };
/// let axes = MtAxes { x: r, y: r, slots: 2, pressure: None, touch_major: None, touch_minor: None };
/// let mut dec = MtDecoder::new(axes, 1);
/// let mut f = TouchFrame::default();
/// let t = Micros(8_000);
/// assert!(!dec.event(t, EV_ABS, ABS_MT_TRACKING_ID, 17, &mut f));
/// dec.event(t, EV_ABS, ABS_MT_POSITION_X, 250, &mut f);
/// dec.event(t, EV_ABS, ABS_MT_POSITION_Y, 500, &mut f);
/// assert!(dec.event(t, EV_SYN, SYN_REPORT, 0, &mut f));
/// let c = f.contacts()[0];
/// assert_eq!((c.id.0, c.x, c.y, c.flags), (1, 0.25, 0.5, ContactFlags::DOWN));
/// ```
#[derive(Clone, Debug)]
pub struct MtDecoder {
    pub(super) axes: MtAxes,
    pub(super) protocol: MtProtocol,
    pub(super) slots: [Slot; MAX_SLOTS],
    /// Number of slots in use (`1..=MAX_SLOTS` for type B, 0 otherwise).
    pub(super) nslots: usize,
    /// Selected slot, `None` after an out-of-range `ABS_MT_SLOT`.
    pub(super) current: Option<usize>,
    /// Bit `i` set when slot `i` has staged changes.
    pub(super) dirty_slots: u64,
    /// Discarding events until the next `SYN_REPORT`.
    pub(super) dropping: bool,
    /// The block being discarded began with `SYN_DROPPED` (not `discard_frame`).
    pub(super) dropped_sync: bool,
    /// A dropped block ended: the shell should query the device and resync.
    pub(super) resync_wanted: bool,
    pub(super) packets: PacketState,
    pub(super) next_id: u32,
    pub(super) counters: MtCounters,
}

impl MtDecoder {
    /// A decoder with every slot free and slot 0 selected: type B when
    /// `axes.slots >= 1`, type A when it is 0.
    ///
    /// Contact ids are handed out from `first_id` upward and never reused.
    pub fn new(axes: MtAxes, first_id: u32) -> MtDecoder {
        let protocol = if axes.slots == 0 {
            MtProtocol::A
        } else {
            MtProtocol::B
        };
        MtDecoder::with_protocol(axes, protocol, first_id)
    }

    /// A decoder for an explicit protocol. For [`MtProtocol::B`] the slot count
    /// is `axes.slots` clamped to `1..=MAX_SLOTS`; the others ignore it.
    pub fn with_protocol(axes: MtAxes, protocol: MtProtocol, first_id: u32) -> MtDecoder {
        let nslots = match protocol {
            MtProtocol::B => axes.slots.clamp(1, MAX_SLOTS),
            MtProtocol::A | MtProtocol::SingleTouch => 0,
        };
        let packets = PacketState::new(&axes);
        MtDecoder {
            axes,
            protocol,
            slots: [Slot::FREE; MAX_SLOTS],
            nslots,
            current: Some(0),
            dirty_slots: 0,
            dropping: false,
            dropped_sync: false,
            resync_wanted: false,
            packets,
            next_id: first_id,
            counters: MtCounters::default(),
        }
    }

    /// The axes the decoder was built with.
    pub fn axes(&self) -> &MtAxes {
        &self.axes
    }

    /// The protocol decoded.
    pub fn protocol(&self) -> MtProtocol {
        self.protocol
    }

    /// Number of slots of a type-B decoder (0 for the others).
    pub fn slot_count(&self) -> usize {
        self.nslots
    }

    /// The id the next new contact will get.
    pub fn next_id(&self) -> u32 {
        self.next_id
    }

    /// What the decoder has seen so far.
    pub fn counters(&self) -> MtCounters {
        self.counters
    }

    /// Number of contacts currently down (committed state).
    pub fn active_contacts(&self) -> usize {
        match self.protocol {
            MtProtocol::B => self.slots[..self.nslots]
                .iter()
                .filter(|s| s.tracking_id >= 0)
                .count(),
            MtProtocol::A | MtProtocol::SingleTouch => self.packets.prev_len,
        }
    }

    /// Whether a dropped block (`SYN_DROPPED` … `SYN_REPORT`) has ended and the
    /// device state should be queried and passed to [`MtDecoder::resync`].
    ///
    /// Type A never asks: its next frame is complete.
    pub fn wants_resync(&self) -> bool {
        self.resync_wanted
    }

    /// Whether events are being discarded up to the next `SYN_REPORT`.
    pub fn is_discarding(&self) -> bool {
        self.dropping
    }

    /// Feeds one event; see [`MtDecoder::event`].
    pub fn feed(&mut self, ev: &RawEvent, out: &mut TouchFrame) -> bool {
        self.event(ev.t, ev.ev_type, ev.code, ev.value, out)
    }

    /// Feeds one event.
    ///
    /// When the event is a `SYN_REPORT` that closes a frame, `out` is cleared,
    /// `out.t` set to `t`, filled with the frame's contacts, and `true` is
    /// returned; otherwise `out` is untouched and `false` is returned.
    pub fn event(
        &mut self,
        t: Micros,
        ev_type: u16,
        code: u16,
        value: i32,
        out: &mut TouchFrame,
    ) -> bool {
        self.counters.events += 1;
        if self.dropping {
            self.counters.discarded_events += 1;
            if ev_type == EV_SYN && code == SYN_REPORT {
                self.dropping = false;
                if self.dropped_sync && self.protocol != MtProtocol::A {
                    self.resync_wanted = true;
                }
                self.dropped_sync = false;
            }
            return false;
        }
        match (ev_type, code) {
            (EV_SYN, SYN_REPORT) => {
                self.counters.frames += 1;
                match self.protocol {
                    MtProtocol::B => self.commit(t, out),
                    MtProtocol::A => self.commit_a(t, out),
                    MtProtocol::SingleTouch => self.commit_st(t, out),
                }
                true
            }
            (EV_SYN, SYN_DROPPED) => {
                self.counters.dropped_sync += 1;
                self.discard_frame();
                self.dropped_sync = true;
                self.packets.after_drop = true;
                false
            }
            (EV_SYN, SYN_MT_REPORT) => {
                self.counters.mt_report += 1;
                if self.protocol == MtProtocol::A {
                    self.packets.close_packet(&mut self.counters);
                }
                false
            }
            _ => {
                match self.protocol {
                    MtProtocol::B => self.event_b(ev_type, code, value),
                    MtProtocol::A => self.event_a(ev_type, code, value),
                    MtProtocol::SingleTouch => self.event_st(ev_type, code, value),
                }
                false
            }
        }
    }

    /// Whether an optional per-contact axis is declared; counts it when not.
    pub(super) fn declared(&mut self, code: u16) -> bool {
        let ok = match code {
            ABS_MT_PRESSURE => self.axes.pressure.is_some(),
            ABS_MT_TOUCH_MAJOR => self.axes.touch_major.is_some(),
            ABS_MT_TOUCH_MINOR => self.axes.touch_minor.is_some(),
            _ => true,
        };
        if !ok {
            self.counters.undeclared_axis += 1;
        }
        ok
    }

    /// Throws away the changes staged since the last `SYN_REPORT` and every
    /// event up to and including the next `SYN_REPORT`.
    ///
    /// This is what `SYN_DROPPED` does (which also asks for a resync); readers
    /// call it to skip a bad frame.
    pub fn discard_frame(&mut self) {
        self.discard_staged();
        self.dropping = true;
    }

    /// Throws away the changes staged since the last `SYN_REPORT`; later events
    /// are decoded normally.
    ///
    /// For a reader that drops a frame whose closing `SYN_REPORT` it rejected.
    pub fn discard_staged(&mut self) {
        let mut bits = self.dirty_slots;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            self.slots[i].dirty = 0;
        }
        self.dirty_slots = 0;
        let p = &mut self.packets;
        p.cur_len = 0;
        p.pkt_seen = false;
        p.pkt.tid = -1;
        p.lift_all = false;
        if self.protocol == MtProtocol::SingleTouch {
            p.touch_staged = p.touch;
            p.pkt.vals = p.st_vals;
        }
    }

    /// Ends every contact still down, as a frame of `CANCELLED` contacts at
    /// their last committed position, and frees all slots.
    ///
    /// Staged changes of an unfinished frame, a discarding state and a pending
    /// resync are dropped. Returns `false` (and leaves `out` cleared) when no
    /// contact was down.
    pub fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool {
        self.discard_staged();
        out.clear();
        out.t = t;
        self.dropping = false;
        self.dropped_sync = false;
        self.resync_wanted = false;
        let mut any = false;
        for i in 0..self.nslots {
            let s = self.slots[i];
            if s.tracking_id >= 0 {
                any = true;
                self.counters.contacts_cancelled += 1;
                let c = self.contact(s.id, &s.vals, ContactFlags::CANCELLED);
                self.emit(out, c);
                self.slots[i].tracking_id = -1;
            }
        }
        for j in 0..self.packets.prev_len {
            let p = self.packets.prev[j];
            any = true;
            self.counters.contacts_cancelled += 1;
            let c = self.contact(p.id, &p.vals, ContactFlags::CANCELLED);
            self.emit(out, c);
        }
        self.packets.prev_len = 0;
        self.packets.after_drop = false;
        self.packets.touch = false;
        self.packets.touch_staged = false;
        any
    }

    /// Brings the decoder to the device's true state after a `SYN_DROPPED` (or
    /// at open), emitting the difference as one frame at `t`.
    ///
    /// Type B: for each slot below both `state.len()` and the decoder's slot
    /// count, a contact whose tracking id vanished or changed ends `CANCELLED`
    /// at its last committed position; a new tracking id begins `DOWN`; the same
    /// id moves to the reported values. Slots beyond `state.len()` keep their
    /// state. The selected slot becomes `state.selected` when it is known.
    /// Single touch reads slot 0 (`tracking_id >= 0` = touching). Type A takes
    /// the state's active slots as the complete current frame (contacts matched
    /// by tracking id; the others end `CANCELLED`).
    ///
    /// Staged changes are dropped and the pending resync is cleared. When called
    /// in the middle of a dropped block (before its `SYN_REPORT`), the rest of
    /// the block is still discarded and a new resync is wanted at its end,
    /// because the events up to it are partial.
    ///
    /// Returns whether `out` holds a contact (ended, begun or continuing);
    /// `out` is cleared and timed `t` either way.
    ///
    /// # Complexity
    /// O(slots) for type B; no allocation.
    pub fn resync(&mut self, t: Micros, state: &MtSlotState, out: &mut TouchFrame) -> bool {
        self.counters.resyncs += 1;
        self.resync_wanted = false;
        self.discard_staged();
        match self.protocol {
            MtProtocol::B => self.resync_b(t, state, out),
            MtProtocol::A => self.resync_a(t, state, out),
            MtProtocol::SingleTouch => self.resync_st(t, state, out),
        }
        !out.is_empty()
    }

    /// Builds a normalised contact from device values.
    pub(super) fn contact(&self, id: ContactId, v: &SlotValues, flags: ContactFlags) -> Contact {
        let size_mm = |axis: &Option<AxisRange>, raw: i32| {
            let a = axis.as_ref()?;
            let res = if a.resolution > 0.0 {
                a.resolution
            } else {
                self.axes.x.resolution
            };
            (res > 0.0).then(|| (f64::from(raw) / res) as f32)
        };
        let mut flags = flags;
        if v.tool == MT_TOOL_PALM {
            flags.insert(ContactFlags::PALM);
        }
        Contact {
            id,
            x: self.axes.x.normalise(f64::from(v.x)),
            y: self.axes.y.normalise(f64::from(v.y)),
            pressure: self
                .axes
                .pressure
                .as_ref()
                .map(|p| p.normalise(f64::from(v.pressure))),
            major_mm: size_mm(&self.axes.touch_major, v.major),
            minor_mm: size_mm(&self.axes.touch_minor, v.minor),
            flags,
        }
    }

    /// Pushes `c` into `out`, counting an overflow.
    pub(super) fn emit(&mut self, out: &mut TouchFrame, c: Contact) {
        if out.push(c).is_err() {
            self.counters.frame_overflow += 1;
        }
    }
}

/// Helpers the decoder's tests share, and the tests of what every protocol does.
#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::input::evdev::codes::*;

    pub(crate) const EPS: f32 = 1e-6;

    pub(crate) fn axes(slots: usize) -> MtAxes {
        let r = AxisRange {
            min: 0.0,
            max: 1000.0,
            resolution: 10.0,
        };
        MtAxes {
            x: r,
            y: r,
            slots,
            pressure: None,
            touch_major: None,
            touch_minor: None,
        }
    }

    /// Feeds `(type, code, value)` events at time `t`; returns the frame if one closed.
    pub(crate) fn feed(d: &mut MtDecoder, t: u64, evs: &[(u16, u16, i32)]) -> Option<TouchFrame> {
        let mut f = TouchFrame::default();
        let mut got = None;
        for &(ty, code, v) in evs {
            if d.event(Micros(t), ty, code, v, &mut f) {
                got = Some(f);
            }
        }
        got
    }

    pub(crate) fn ids_flags(f: &TouchFrame) -> Vec<(u32, ContactFlags)> {
        f.contacts().iter().map(|c| (c.id.0, c.flags)).collect()
    }

    pub(crate) const SYN: (u16, u16, i32) = (EV_SYN, SYN_REPORT, 0);

    pub(crate) fn xs(f: &TouchFrame) -> Vec<(u32, i32, ContactFlags)> {
        f.contacts()
            .iter()
            .map(|c| (c.id.0, (c.x * 1000.0).round() as i32, c.flags))
            .collect()
    }

    pub(crate) fn state(tids: &[(i32, i32, i32)]) -> MtSlotState {
        let mut s = MtSlotState::new(tids.len());
        for (slot, &(tid, x, y)) in s.slots_mut().iter_mut().zip(tids) {
            slot.tracking_id = tid;
            slot.x = x;
            slot.y = y;
        }
        s
    }

    #[test]
    fn syn_dropped_discards_until_report() {
        let mut d = MtDecoder::new(axes(2), 1);
        feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 1),
                (EV_ABS, ABS_MT_POSITION_X, 100),
                SYN,
            ],
        );
        let mut f = TouchFrame::default();
        assert!(!d.event(Micros(2), EV_ABS, ABS_MT_POSITION_X, 200, &mut f));
        assert!(!d.event(Micros(2), EV_SYN, SYN_DROPPED, 0, &mut f));
        assert!(!d.event(Micros(2), EV_ABS, ABS_MT_TRACKING_ID, -1, &mut f));
        assert!(!d.event(Micros(2), EV_SYN, SYN_REPORT, 0, &mut f));
        let f = feed(&mut d, 3, &[SYN]).unwrap();
        // State from before the drop: still down at x = 0.1.
        assert_eq!(ids_flags(&f), vec![(1, ContactFlags::NONE)]);
        assert!((f.contacts()[0].x - 0.1).abs() < EPS);
        let c = d.counters();
        assert_eq!((c.dropped_sync, c.discarded_events), (1, 2));
    }

    #[test]
    fn cancel_all_ends_active() {
        let mut d = MtDecoder::new(axes(3), 1);
        feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 1),
                (EV_ABS, ABS_MT_SLOT, 2),
                (EV_ABS, ABS_MT_TRACKING_ID, 2),
                SYN,
            ],
        );
        let mut f = TouchFrame::default();
        assert!(d.cancel_all(Micros(9), &mut f));
        assert_eq!(
            ids_flags(&f),
            vec![(1, ContactFlags::CANCELLED), (2, ContactFlags::CANCELLED)]
        );
        assert_eq!(f.t, Micros(9));
        assert!(!d.cancel_all(Micros(10), &mut f));
        assert_eq!(d.active_contacts(), 0);
    }

    #[test]
    fn pressure_size_and_palm() {
        let mut a = axes(1);
        a.pressure = Some(AxisRange {
            min: 0.0,
            max: 255.0,
            resolution: 0.0,
        });
        a.touch_major = Some(AxisRange {
            min: 0.0,
            max: 255.0,
            resolution: 0.0,
        });
        a.touch_minor = Some(AxisRange {
            min: 0.0,
            max: 255.0,
            resolution: 5.0,
        });
        let mut d = MtDecoder::new(a, 1);
        let f = feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 1),
                (EV_ABS, ABS_MT_PRESSURE, 51),
                (EV_ABS, ABS_MT_TOUCH_MAJOR, 100),
                (EV_ABS, ABS_MT_TOUCH_MINOR, 40),
                (EV_ABS, ABS_MT_TOOL_TYPE, MT_TOOL_PALM),
                SYN,
            ],
        )
        .unwrap();
        let c = f.contacts()[0];
        assert!((c.pressure.unwrap() - 0.2).abs() < EPS);
        // Major falls back to the X resolution (10 units/mm), minor has its own.
        assert!((c.major_mm.unwrap() - 10.0).abs() < EPS);
        assert!((c.minor_mm.unwrap() - 8.0).abs() < EPS);
        assert!(c.flags.contains(ContactFlags::PALM | ContactFlags::DOWN));
    }

    #[test]
    fn protocol_a_report_is_counted() {
        let mut d = MtDecoder::new(axes(1), 1);
        feed(&mut d, 1, &[(EV_SYN, SYN_MT_REPORT, 0), SYN]);
        assert_eq!(d.counters().mt_report, 1);
    }

    #[test]
    fn resync_mid_block_keeps_discarding() {
        let mut d = MtDecoder::new(axes(2), 1);
        let mut f = TouchFrame::default();
        d.event(Micros(1), EV_SYN, SYN_DROPPED, 0, &mut f);
        assert!(!d.resync(Micros(1), &state(&[(5, 10, 10)]), &mut f) || f.len() == 1);
        assert!(d.is_discarding());
        d.event(Micros(2), EV_ABS, ABS_MT_POSITION_X, 999, &mut f);
        assert!(!d.event(Micros(2), EV_SYN, SYN_REPORT, 0, &mut f));
        assert!(d.wants_resync());
        assert!(d.resync(Micros(2), &state(&[(5, 20, 10)]), &mut f));
        assert_eq!(
            xs(&f),
            vec![(1, 20, ContactFlags::NONE)],
            "the contact begun at the first resync continues"
        );
    }
}
