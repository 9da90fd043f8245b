//! A pure decoder for the Linux multi-touch protocol, type B (slots).
//!
//! [`MtDecoder`] is a state machine over evdev input events `(time, type, code,
//! value)`. It keeps a fixed table of slots (no allocation after construction,
//! none per event), stages every change made between two `SYN_REPORT`s, and at
//! `SYN_REPORT` commits them and fills a [`TouchFrame`]. It never opens a device:
//! the evdev thread, the recording readers and the fuzz targets all feed it the
//! same way.
//!
//! # Protocol B, as decoded here
//!
//! * `ABS_MT_SLOT n` selects the slot later `ABS_MT_*` events apply to. The
//!   selection persists across frames; until the first `ABS_MT_SLOT`, slot 0 is
//!   implied (one-finger recordings often never send one).
//! * `ABS_MT_TRACKING_ID v` with `v >= 0` starts a contact in the slot; `-1` ends
//!   it. A slot going straight from id `A` to id `B` ends `A` (reported `UP` at
//!   its last position) and begins `B` (`DOWN`) in the same frame.
//! * Values are incremental: a slot keeps its last position, so a new contact
//!   whose position equals the slot's previous one (which the kernel does not
//!   resend) starts there.
//! * `ABS_MT_TOOL_TYPE = MT_TOOL_PALM` marks the contact [`ContactFlags::PALM`].
//! * `BTN_TOUCH`, `BTN_TOOL_*`, the single-touch `ABS_X/ABS_Y`, `EV_MSC` and
//!   every other event are counted and ignored: segmentation is driven by the
//!   slots only.
//!
//! ```text
//!                 TRACKING_ID >= 0                  TRACKING_ID -1
//!   free slot ─────────────────────► active ─────────────────────────► free slot
//!      ▲          (DOWN at SYN)        │  ▲   (UP at SYN, last position)
//!      │                               │  │ TRACKING_ID B != A
//!      │                               └──┘ (A: UP, B: DOWN, same frame)
//!      └──────────── cancel_all (CANCELLED) ◄───────── active
//! ```
//!
//! # Frame contents
//!
//! At every `SYN_REPORT` the frame (cleared first, `t` set) lists, transitions
//! first: the contacts that ended in this frame (`UP`, at their last committed
//! position), the contacts that began (`DOWN`), then the contacts that continue.
//! Frames with no contact at all are returned too (a device reports them, e.g.
//! for `MSC_TIMESTAMP` only), so a recording keeps one frame per `SYN_REPORT`.
//!
//! Positions are normalised to the unit square with [`AxisRange::normalise`];
//! pressure is normalised over its axis; `ABS_MT_TOUCH_MAJOR/MINOR` are
//! converted to millimetres with the axis' resolution, or, when that is unknown,
//! with the X position resolution (the kernel documents touch sizes in surface
//! units); with neither known they are left out.
//!
//! # Not supported (yet)
//!
//! * **`SYN_DROPPED`** is handled by discarding the staged changes and every
//!   event up to and including the next `SYN_REPORT` (counted in
//!   [`MtCounters::dropped_sync`]). The full resynchronisation — querying the
//!   device with `EVIOCGMTSLOTS` and diffing it against the slot table, ending
//!   vanished contacts as `CANCELLED` — needs the device and comes with the evdev
//!   source in a later issue. Until then the slot table keeps its pre-drop state,
//!   so a lift lost in the dropped block leaves a contact down until its slot is
//!   reused or [`MtDecoder::cancel_all`] runs.
//! * **Protocol A** (anonymous contacts closed by `SYN_MT_REPORT`) is not
//!   decoded: its events are counted in [`MtCounters::mt_report`] and ignored.
//!   The recording readers refuse type-A devices at import with
//!   `RecordingError::Unsupported`.
//! * `ABS_MT_DISTANCE` (hover) is not interpreted: a hovering contact is reported
//!   like a touching one.
//! * Contacts that begin and end inside a single frame (two tracking-id changes
//!   in one slot before a `SYN_REPORT`) are not reported; they are counted in
//!   [`MtCounters::transient_contacts`].

use super::{AxisRange, Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};
use crate::time::Micros;

/// Event type: synchronisation.
pub const EV_SYN: u16 = 0;
/// Event type: keys and buttons.
pub const EV_KEY: u16 = 1;
/// Event type: relative axes.
pub const EV_REL: u16 = 2;
/// Event type: absolute axes.
pub const EV_ABS: u16 = 3;
/// Event type: miscellaneous (e.g. `MSC_TIMESTAMP`).
pub const EV_MSC: u16 = 4;

/// `EV_SYN` code closing a frame.
pub const SYN_REPORT: u16 = 0;
/// `EV_SYN` code (unused by touch devices).
pub const SYN_CONFIG: u16 = 1;
/// `EV_SYN` code closing one contact packet in protocol A.
pub const SYN_MT_REPORT: u16 = 2;
/// `EV_SYN` code: the client's event buffer overflowed, events were lost.
pub const SYN_DROPPED: u16 = 3;

/// `EV_KEY` code: at least one tool touches the surface.
pub const BTN_TOUCH: u16 = 0x14a;
/// `EV_KEY` code: one finger (mostly touchpads).
pub const BTN_TOOL_FINGER: u16 = 0x145;
/// `EV_KEY` code: two fingers.
pub const BTN_TOOL_DOUBLETAP: u16 = 0x14d;
/// `EV_KEY` code: three fingers.
pub const BTN_TOOL_TRIPLETAP: u16 = 0x14e;
/// `EV_KEY` code: four fingers.
pub const BTN_TOOL_QUADTAP: u16 = 0x14f;
/// `EV_KEY` code: five fingers.
pub const BTN_TOOL_QUINTTAP: u16 = 0x148;

/// `EV_ABS` code: single-touch X.
pub const ABS_X: u16 = 0x00;
/// `EV_ABS` code: single-touch Y.
pub const ABS_Y: u16 = 0x01;
/// `EV_ABS` code: single-touch pressure.
pub const ABS_PRESSURE: u16 = 0x18;
/// `EV_ABS` code: selects the slot later `ABS_MT_*` events apply to.
pub const ABS_MT_SLOT: u16 = 0x2f;
/// `EV_ABS` code: major axis of the contact ellipse (surface units).
pub const ABS_MT_TOUCH_MAJOR: u16 = 0x30;
/// `EV_ABS` code: minor axis of the contact ellipse (surface units).
pub const ABS_MT_TOUCH_MINOR: u16 = 0x31;
/// `EV_ABS` code: major axis of the approaching tool.
pub const ABS_MT_WIDTH_MAJOR: u16 = 0x32;
/// `EV_ABS` code: minor axis of the approaching tool.
pub const ABS_MT_WIDTH_MINOR: u16 = 0x33;
/// `EV_ABS` code: ellipse orientation.
pub const ABS_MT_ORIENTATION: u16 = 0x34;
/// `EV_ABS` code: contact centre X.
pub const ABS_MT_POSITION_X: u16 = 0x35;
/// `EV_ABS` code: contact centre Y.
pub const ABS_MT_POSITION_Y: u16 = 0x36;
/// `EV_ABS` code: tool type (`MT_TOOL_*`).
pub const ABS_MT_TOOL_TYPE: u16 = 0x37;
/// `EV_ABS` code: blob id (protocol A grouping).
pub const ABS_MT_BLOB_ID: u16 = 0x38;
/// `EV_ABS` code: contact identity; `-1` ends the contact of the slot.
pub const ABS_MT_TRACKING_ID: u16 = 0x39;
/// `EV_ABS` code: contact pressure.
pub const ABS_MT_PRESSURE: u16 = 0x3a;
/// `EV_ABS` code: hover distance.
pub const ABS_MT_DISTANCE: u16 = 0x3b;
/// `EV_ABS` code: tool centre X.
pub const ABS_MT_TOOL_X: u16 = 0x3c;
/// `EV_ABS` code: tool centre Y.
pub const ABS_MT_TOOL_Y: u16 = 0x3d;
/// Highest `EV_ABS` code the kernel defines.
pub const ABS_MAX: u16 = 0x3f;

/// `ABS_MT_TOOL_TYPE` value: a finger.
pub const MT_TOOL_FINGER: i32 = 0;
/// `ABS_MT_TOOL_TYPE` value: a pen.
pub const MT_TOOL_PEN: i32 = 1;
/// `ABS_MT_TOOL_TYPE` value: a palm.
pub const MT_TOOL_PALM: i32 = 2;

/// Most slots a decoder tracks; slots of larger devices are counted as out of range.
pub const MAX_SLOTS: usize = MAX_CONTACTS;

/// The axes of a type-B multi-touch device that the decoder needs.
#[derive(Clone, Debug, PartialEq)]
pub struct MtAxes {
    /// `ABS_MT_POSITION_X` range.
    pub x: AxisRange,
    /// `ABS_MT_POSITION_Y` range.
    pub y: AxisRange,
    /// Number of slots (`ABS_MT_SLOT` max + 1); clamped to `1..=MAX_SLOTS`.
    pub slots: usize,
    /// `ABS_MT_PRESSURE` range, when the device reports pressure.
    pub pressure: Option<AxisRange>,
    /// `ABS_MT_TOUCH_MAJOR` range, when reported.
    pub touch_major: Option<AxisRange>,
    /// `ABS_MT_TOUCH_MINOR` range, when reported.
    pub touch_minor: Option<AxisRange>,
}

/// What a decoder has seen, for stats and import warnings.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct MtCounters {
    /// Events fed.
    pub events: u64,
    /// Frames returned (one per `SYN_REPORT` outside a dropped block).
    pub frames: u64,
    /// Contacts begun.
    pub contacts_begun: u64,
    /// Contacts ended by a tracking id change (`UP`).
    pub contacts_ended: u64,
    /// Contacts ended by [`MtDecoder::cancel_all`].
    pub contacts_cancelled: u64,
    /// `ABS_MT_SLOT` values outside `0..slots`; the `ABS_MT_*` events after one
    /// are ignored until a valid slot is selected.
    pub slot_out_of_range: u64,
    /// `ABS_MT_*` events ignored because the selected slot was out of range.
    pub ignored_slot_events: u64,
    /// Contacts that did not fit a frame of [`MAX_CONTACTS`].
    pub frame_overflow: u64,
    /// `SYN_DROPPED` events seen.
    pub dropped_sync: u64,
    /// Events discarded after a `SYN_DROPPED` (up to the next `SYN_REPORT`).
    pub discarded_events: u64,
    /// `SYN_MT_REPORT` events (protocol A; not decoded).
    pub mt_report: u64,
    /// Contacts that began and ended within one frame (not reported).
    pub transient_contacts: u64,
}

/// Dirty bits of the staged values of one slot.
const DIRTY_X: u8 = 1;
const DIRTY_Y: u8 = 2;
const DIRTY_PRESSURE: u8 = 4;
const DIRTY_MAJOR: u8 = 8;
const DIRTY_MINOR: u8 = 16;
const DIRTY_TOOL: u8 = 32;
const DIRTY_TRACKING: u8 = 64;

/// Per-slot axis values in device units.
#[derive(Copy, Clone, Debug, Default)]
struct SlotValues {
    x: i32,
    y: i32,
    pressure: i32,
    major: i32,
    minor: i32,
    tool: i32,
}

/// One slot: the committed state, and what the current frame staged.
#[derive(Copy, Clone, Debug)]
struct Slot {
    /// Committed kernel tracking id (`-1` = free).
    tracking_id: i32,
    /// Our id for the committed contact (valid when `tracking_id >= 0`).
    id: ContactId,
    /// Committed values.
    vals: SlotValues,
    /// Values staged in the current frame (valid where `dirty` says so).
    staged: SlotValues,
    /// Staged tracking id (valid when `dirty & DIRTY_TRACKING`).
    staged_tid: i32,
    /// Which staged values were written in the current frame.
    dirty: u8,
}

impl Slot {
    const FREE: Slot = Slot {
        tracking_id: -1,
        id: ContactId(0),
        vals: SlotValues {
            x: 0,
            y: 0,
            pressure: 0,
            major: 0,
            minor: 0,
            tool: 0,
        },
        staged: SlotValues {
            x: 0,
            y: 0,
            pressure: 0,
            major: 0,
            minor: 0,
            tool: 0,
        },
        staged_tid: -1,
        dirty: 0,
    };
}

/// Decodes type-B multi-touch events into [`TouchFrame`]s.
///
/// # Complexity
/// `event` is O(1) except at `SYN_REPORT`, which is O(slots). No allocation
/// after [`MtDecoder::new`].
///
/// # Example
/// ```
/// use crowdtouch::input::mt::*;
/// use crowdtouch::input::{AxisRange, ContactFlags, TouchFrame};
/// use crowdtouch::time::Micros;
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
    axes: MtAxes,
    slots: [Slot; MAX_SLOTS],
    /// Number of slots in use (`1..=MAX_SLOTS`).
    nslots: usize,
    /// Selected slot, `None` after an out-of-range `ABS_MT_SLOT`.
    current: Option<usize>,
    /// Bit `i` set when slot `i` has staged changes.
    dirty_slots: u64,
    /// Discarding events until the next `SYN_REPORT` (after `SYN_DROPPED`).
    dropping: bool,
    next_id: u32,
    counters: MtCounters,
}

impl MtDecoder {
    /// A decoder with every slot free and slot 0 selected.
    ///
    /// Contact ids are handed out from `first_id` upward and never reused.
    pub fn new(axes: MtAxes, first_id: u32) -> MtDecoder {
        let nslots = axes.slots.clamp(1, MAX_SLOTS);
        MtDecoder {
            axes,
            slots: [Slot::FREE; MAX_SLOTS],
            nslots,
            current: Some(0),
            dirty_slots: 0,
            dropping: false,
            next_id: first_id,
            counters: MtCounters::default(),
        }
    }

    /// The axes the decoder was built with.
    pub fn axes(&self) -> &MtAxes {
        &self.axes
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
        self.slots[..self.nslots]
            .iter()
            .filter(|s| s.tracking_id >= 0)
            .count()
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
            }
            return false;
        }
        match (ev_type, code) {
            (EV_SYN, SYN_REPORT) => {
                self.commit(t, out);
                true
            }
            (EV_SYN, SYN_DROPPED) => {
                self.counters.dropped_sync += 1;
                self.discard_frame();
                false
            }
            (EV_SYN, SYN_MT_REPORT) => {
                self.counters.mt_report += 1;
                false
            }
            (EV_ABS, ABS_MT_SLOT) => {
                if value >= 0 && (value as usize) < self.nslots {
                    self.current = Some(value as usize);
                } else {
                    self.counters.slot_out_of_range += 1;
                    self.current = None;
                }
                false
            }
            (
                EV_ABS,
                ABS_MT_TRACKING_ID | ABS_MT_POSITION_X | ABS_MT_POSITION_Y | ABS_MT_PRESSURE
                | ABS_MT_TOUCH_MAJOR | ABS_MT_TOUCH_MINOR | ABS_MT_TOOL_TYPE,
            ) => {
                let Some(i) = self.current else {
                    self.counters.ignored_slot_events += 1;
                    return false;
                };
                self.dirty_slots |= 1u64 << i;
                let s = &mut self.slots[i];
                match code {
                    ABS_MT_TRACKING_ID => {
                        let value = value.max(-1);
                        let before = if s.dirty & DIRTY_TRACKING != 0 {
                            s.staged_tid
                        } else {
                            s.tracking_id
                        };
                        if value != before {
                            if s.dirty & DIRTY_TRACKING != 0 && before >= 0 {
                                // A contact begun in this frame ends in it too.
                                self.counters.transient_contacts += 1;
                            }
                            s.staged_tid = value;
                            s.dirty |= DIRTY_TRACKING;
                        }
                    }
                    ABS_MT_POSITION_X => {
                        s.staged.x = value;
                        s.dirty |= DIRTY_X;
                    }
                    ABS_MT_POSITION_Y => {
                        s.staged.y = value;
                        s.dirty |= DIRTY_Y;
                    }
                    ABS_MT_PRESSURE => {
                        s.staged.pressure = value;
                        s.dirty |= DIRTY_PRESSURE;
                    }
                    ABS_MT_TOUCH_MAJOR => {
                        s.staged.major = value;
                        s.dirty |= DIRTY_MAJOR;
                    }
                    ABS_MT_TOUCH_MINOR => {
                        s.staged.minor = value;
                        s.dirty |= DIRTY_MINOR;
                    }
                    _ => {
                        s.staged.tool = value;
                        s.dirty |= DIRTY_TOOL;
                    }
                }
                false
            }
            _ => false,
        }
    }

    /// Throws away the changes staged since the last `SYN_REPORT` and every
    /// event up to and including the next `SYN_REPORT`.
    ///
    /// This is what `SYN_DROPPED` does; readers call it to skip a bad frame.
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
            let s = &mut self.slots[i];
            s.dirty = 0;
        }
        self.dirty_slots = 0;
    }

    /// Ends every contact still down, as a frame of `CANCELLED` contacts at
    /// their last committed position, and frees all slots.
    ///
    /// Staged changes of an unfinished frame are dropped. Returns `false` (and
    /// leaves `out` cleared) when no contact was down.
    pub fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool {
        out.clear();
        out.t = t;
        self.dirty_slots = 0;
        self.dropping = false;
        let mut any = false;
        for i in 0..self.nslots {
            let s = self.slots[i];
            self.slots[i].dirty = 0;
            if s.tracking_id >= 0 {
                any = true;
                self.counters.contacts_cancelled += 1;
                let c = self.contact(s.id, &s.vals, ContactFlags::CANCELLED);
                if out.push(c).is_err() {
                    self.counters.frame_overflow += 1;
                }
                self.slots[i].tracking_id = -1;
            }
        }
        any
    }

    /// Builds a normalised contact from device values.
    fn contact(&self, id: ContactId, v: &SlotValues, flags: ContactFlags) -> Contact {
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
    fn emit(&mut self, out: &mut TouchFrame, c: Contact) {
        if out.push(c).is_err() {
            self.counters.frame_overflow += 1;
        }
    }

    /// Applies the staged changes and fills `out`: ended, begun, then continuing.
    fn commit(&mut self, t: Micros, out: &mut TouchFrame) {
        out.clear();
        out.t = t;
        self.counters.frames += 1;
        // Bit i: slot i began a contact in this frame.
        let mut began: u64 = 0;
        let mut bits = self.dirty_slots;
        self.dirty_slots = 0;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let s = self.slots[i];
            let mut vals = s.vals;
            let d = s.dirty;
            if d & DIRTY_TRACKING != 0 && s.staged_tid != s.tracking_id {
                if s.tracking_id >= 0 {
                    // Ended at its last committed position.
                    self.counters.contacts_ended += 1;
                    let c = self.contact(s.id, &s.vals, ContactFlags::UP);
                    self.emit(out, c);
                }
                if s.staged_tid >= 0 {
                    began |= 1u64 << i;
                    self.slots[i].id = ContactId(self.next_id);
                    self.next_id = self.next_id.wrapping_add(1);
                    self.counters.contacts_begun += 1;
                }
                self.slots[i].tracking_id = s.staged_tid;
            }
            if d & DIRTY_X != 0 {
                vals.x = s.staged.x;
            }
            if d & DIRTY_Y != 0 {
                vals.y = s.staged.y;
            }
            if d & DIRTY_PRESSURE != 0 {
                vals.pressure = s.staged.pressure;
            }
            if d & DIRTY_MAJOR != 0 {
                vals.major = s.staged.major;
            }
            if d & DIRTY_MINOR != 0 {
                vals.minor = s.staged.minor;
            }
            if d & DIRTY_TOOL != 0 {
                vals.tool = s.staged.tool;
            }
            let slot = &mut self.slots[i];
            slot.vals = vals;
            slot.dirty = 0;
        }
        // Begun contacts, then continuing ones, in slot order.
        for pass_began in [true, false] {
            for i in 0..self.nslots {
                let s = self.slots[i];
                if s.tracking_id < 0 || ((began >> i) & 1 == 1) != pass_began {
                    continue;
                }
                let flags = if pass_began {
                    ContactFlags::DOWN
                } else {
                    ContactFlags::NONE
                };
                let c = self.contact(s.id, &s.vals, flags);
                self.emit(out, c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f32 = 1e-6;

    fn axes(slots: usize) -> MtAxes {
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
    fn feed(d: &mut MtDecoder, t: u64, evs: &[(u16, u16, i32)]) -> Option<TouchFrame> {
        let mut f = TouchFrame::default();
        let mut got = None;
        for &(ty, code, v) in evs {
            if d.event(Micros(t), ty, code, v, &mut f) {
                got = Some(f);
            }
        }
        got
    }

    fn ids_flags(f: &TouchFrame) -> Vec<(u32, ContactFlags)> {
        f.contacts().iter().map(|c| (c.id.0, c.flags)).collect()
    }

    const SYN: (u16, u16, i32) = (EV_SYN, SYN_REPORT, 0);

    #[test]
    fn implicit_slot_zero_down_move_up() {
        let mut d = MtDecoder::new(axes(10), 5);
        let f = feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 3),
                (EV_ABS, ABS_MT_POSITION_X, 100),
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(ids_flags(&f), vec![(5, ContactFlags::DOWN)]);
        assert!((f.contacts()[0].x - 0.1).abs() < EPS);
        assert_eq!(f.contacts()[0].y, 0.0);
        let f = feed(&mut d, 2, &[(EV_ABS, ABS_MT_POSITION_Y, 500), SYN]).unwrap();
        assert_eq!(ids_flags(&f), vec![(5, ContactFlags::NONE)]);
        assert!((f.contacts()[0].y - 0.5).abs() < EPS);
        // Lift: reported at the last position, even if a position came with it.
        let f = feed(
            &mut d,
            3,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, -1),
                (EV_ABS, ABS_MT_POSITION_Y, 900),
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(ids_flags(&f), vec![(5, ContactFlags::UP)]);
        assert!((f.contacts()[0].y - 0.5).abs() < EPS);
        assert_eq!(f.t, Micros(3));
        let f = feed(&mut d, 4, &[SYN]).unwrap();
        assert!(f.is_empty());
        assert_eq!(d.next_id(), 6);
        let c = d.counters();
        assert_eq!((c.frames, c.contacts_begun, c.contacts_ended), (4, 1, 1));
    }

    #[test]
    fn id_change_in_one_slot_ends_and_begins() {
        let mut d = MtDecoder::new(axes(2), 1);
        feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 10),
                (EV_ABS, ABS_MT_POSITION_X, 100),
                SYN,
            ],
        );
        let f = feed(
            &mut d,
            2,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 11),
                (EV_ABS, ABS_MT_POSITION_X, 700),
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(
            ids_flags(&f),
            vec![(1, ContactFlags::UP), (2, ContactFlags::DOWN)]
        );
        assert!((f.contacts()[0].x - 0.1).abs() < EPS);
        assert!((f.contacts()[1].x - 0.7).abs() < EPS);
    }

    #[test]
    fn new_contact_keeps_slot_values_not_resent() {
        let mut d = MtDecoder::new(axes(2), 1);
        feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 1),
                (EV_ABS, ABS_MT_POSITION_X, 300),
                SYN,
            ],
        );
        feed(&mut d, 2, &[(EV_ABS, ABS_MT_TRACKING_ID, -1), SYN]);
        let f = feed(&mut d, 3, &[(EV_ABS, ABS_MT_TRACKING_ID, 2), SYN]).unwrap();
        assert_eq!(ids_flags(&f), vec![(2, ContactFlags::DOWN)]);
        assert!((f.contacts()[0].x - 0.3).abs() < EPS);
    }

    #[test]
    fn two_slots_transitions_first() {
        let mut d = MtDecoder::new(axes(4), 1);
        feed(&mut d, 1, &[(EV_ABS, ABS_MT_TRACKING_ID, 1), SYN]);
        let f = feed(
            &mut d,
            2,
            &[
                (EV_ABS, ABS_MT_SLOT, 1),
                (EV_ABS, ABS_MT_TRACKING_ID, 2),
                (EV_ABS, ABS_MT_POSITION_X, 500),
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(
            ids_flags(&f),
            vec![(2, ContactFlags::DOWN), (1, ContactFlags::NONE)]
        );
        // The slot selection persists across frames.
        let f = feed(&mut d, 3, &[(EV_ABS, ABS_MT_POSITION_X, 600), SYN]).unwrap();
        assert!((f.contacts()[1].x - 0.6).abs() < EPS);
        assert!((f.contacts()[0].x - 0.0).abs() < EPS);
    }

    #[test]
    fn slot_out_of_range_is_counted_and_ignored() {
        let mut d = MtDecoder::new(axes(2), 1);
        let f = feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_SLOT, 2),
                (EV_ABS, ABS_MT_TRACKING_ID, 7),
                (EV_ABS, ABS_MT_SLOT, -1),
                (EV_ABS, ABS_MT_POSITION_X, 7),
                SYN,
            ],
        )
        .unwrap();
        assert!(f.is_empty());
        let c = d.counters();
        assert_eq!((c.slot_out_of_range, c.ignored_slot_events), (2, 2));
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
    fn transient_contact_is_counted() {
        let mut d = MtDecoder::new(axes(1), 1);
        let f = feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 1),
                (EV_ABS, ABS_MT_TRACKING_ID, -1),
                SYN,
            ],
        )
        .unwrap();
        assert!(f.is_empty());
        assert_eq!(d.counters().transient_contacts, 1);
        assert_eq!(d.next_id(), 1);
    }

    #[test]
    fn protocol_a_report_is_counted() {
        let mut d = MtDecoder::new(axes(1), 1);
        feed(&mut d, 1, &[(EV_SYN, SYN_MT_REPORT, 0), SYN]);
        assert_eq!(d.counters().mt_report, 1);
    }
}
