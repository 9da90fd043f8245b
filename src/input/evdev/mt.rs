//! A pure decoder for the Linux multi-touch protocol: type B (slots), type A
//! (anonymous contacts) and single-touch screens.
//!
//! [`MtDecoder`] is a state machine over evdev input events `(time, type, code,
//! value)`. It keeps fixed tables (no allocation after construction, none per
//! event), stages every change made between two `SYN_REPORT`s, and at
//! `SYN_REPORT` commits them and fills a [`TouchFrame`]. It never opens a device:
//! the evdev thread, the recording readers and the fuzz targets all feed it the
//! same way. The protocol comes from the axes: [`MtAxes::slots`] `>= 1` is type B,
//! `0` type A (the device declares no `ABS_MT_SLOT`); single-touch screens are
//! chosen explicitly with [`MtDecoder::with_protocol`].
//!
//! # Protocol B, as decoded here
//!
//! * `ABS_MT_SLOT n` selects the slot later `ABS_MT_*` events apply to. The
//!   selection persists across frames; until the first `ABS_MT_SLOT`, slot 0 is
//!   implied (one-finger recordings often never send one).
//! * `ABS_MT_TRACKING_ID v` with `v >= 0` starts a contact in the slot; `-1` ends
//!   it. A slot going straight from id `A` to id `B` ends `A` (reported `UP` at
//!   its last position) and begins `B` (`DOWN`) in the same frame (counted in
//!   [`MtCounters::tracking_id_switched`]). The same id again on an active slot
//!   (a begin without a release) continues the contact
//!   ([`MtCounters::tracking_id_reused`]).
//! * Values are incremental: a slot keeps its last position, so a new contact
//!   whose position equals the slot's previous one (which the kernel does not
//!   resend) starts there.
//! * `ABS_MT_TOOL_TYPE = MT_TOOL_PALM` marks the contact [`ContactFlags::PALM`].
//! * `BTN_TOUCH`, `BTN_TOOL_*`, the single-touch `ABS_X/ABS_Y`, `EV_MSC` and
//!   every other event are counted and ignored: segmentation is driven by the
//!   slots only. A device that declares slots is type B by the kernel's
//!   contract, so a stray `SYN_MT_REPORT` does not switch it to type A (it is
//!   counted in [`MtCounters::mt_report`]).
//!
//! ```text
//!                 TRACKING_ID >= 0                  TRACKING_ID -1
//!   free slot ─────────────────────► active ─────────────────────────► free slot
//!      ▲          (DOWN at SYN)        │  ▲   (UP at SYN, last position)
//!      │                               │  │ TRACKING_ID B != A
//!      │                               └──┘ (A: UP, B: DOWN, same frame)
//!      └──── cancel_all / resync: id gone or changed (CANCELLED) ◄──── active
//! ```
//!
//! # Protocol A, as decoded here
//!
//! * Each `SYN_MT_REPORT` closes one contact packet (its `ABS_MT_*` values);
//!   `SYN_REPORT` closes the frame, which lists every contact that is down. A
//!   packet that sets no value (the lone `SYN_MT_REPORT` of an empty frame) is no
//!   contact. Values carry over from the previous packet when a packet leaves an
//!   axis out (as the input core keeps the last value of an axis).
//! * Packets are matched to the previous frame's contacts by
//!   `ABS_MT_TRACKING_ID` when they carry one; anonymous packets by a minimum-cost
//!   assignment of squared distances ([`assign_min_cost`]), where a pair farther
//!   apart than [`TYPE_A_MAX_JUMP_MM`] (or [`TYPE_A_MAX_JUMP_UNIT`] of the unit
//!   square when the resolution is unknown) is never matched: the old contact
//!   ends (`UP`) and a new one begins (`DOWN`).
//! * A frame with no packet, or with `BTN_TOUCH 0`, lifts every contact (the
//!   input core drops an empty `SYN_REPORT`, so drivers that report `BTN_TOUCH`
//!   signal "all lifted" with it alone).
//! * After a `SYN_DROPPED` the next complete frame is the truth again; contacts
//!   missing from it ended without a clean lift (`CANCELLED`).
//!
//! # Single touch
//!
//! [`MtProtocol::SingleTouch`] decodes a touchscreen with no `ABS_MT_*` axes:
//! one contact at `ABS_X/ABS_Y` (pressure from `ABS_PRESSURE` when the axes
//! declare it) while `BTN_TOUCH` is 1.
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
//! # SYN_DROPPED and resynchronisation
//!
//! `SYN_DROPPED` throws away the staged changes and every event up to and
//! including the next `SYN_REPORT` (counted in [`MtCounters::dropped_sync`] and
//! [`MtCounters::discarded_events`]). For type B and single touch the decoder
//! then [wants a resync](MtDecoder::wants_resync): the device shell queries the
//! true state (`EVIOCGMTSLOTS`, `EVIOCGABS(ABS_MT_SLOT)`, `EVIOCGKEY`) into an
//! [`MtSlotState`] and calls [`MtDecoder::resync`], which diffs it against the
//! slot table and emits one frame: contacts that vanished or whose tracking id
//! changed end `CANCELLED` (not a deliberate lift), new ones begin `DOWN`, the
//! others move. The shell does the same once at open (fingers may already be
//! down). Type A needs no query: its next frame is complete.
//!
//! # Bad input
//!
//! Counted in [`MtCounters`] and skipped, never a panic: slots out of range,
//! tracking ids reused without a release, more packets than a frame holds,
//! events for axes the device does not declare (pressure, touch size, slots on a
//! type-A device, `ABS_MT_*` on a single-touch one).
//!
//! # Not supported
//!
//! * `ABS_MT_DISTANCE` (hover) is not interpreted: a hovering contact is reported
//!   like a touching one.
//! * Contacts that begin and end inside a single frame (two tracking-id changes
//!   in one slot before a `SYN_REPORT`) are not reported; they are counted in
//!   [`MtCounters::transient_contacts`].

use crate::input::AxisRange;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};

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
pub use crate::sys::ABS_MAX;

/// `ABS_MT_TOOL_TYPE` value: a finger.
pub const MT_TOOL_FINGER: i32 = 0;
/// `ABS_MT_TOOL_TYPE` value: a pen.
pub const MT_TOOL_PEN: i32 = 1;
/// `ABS_MT_TOOL_TYPE` value: a palm.
pub const MT_TOOL_PALM: i32 = 2;

/// Most slots a decoder tracks; slots of larger devices are counted as out of range.
pub const MAX_SLOTS: usize = MAX_CONTACTS;

// One `EVIOCGMTSLOTS` request reads every slot a decoder holds.
const _: () = assert!(MAX_SLOTS <= crate::sys::MAX_SLOTS);

/// Protocol A: farthest a contact moves between two frames and is still the
/// same contact, in millimetres (used when both position resolutions are known).
///
/// 40 mm per frame is 2.4 m/s at 60 Hz, faster than a finger drags on glass;
/// the N-Trig drag fixture moves at most 0.045 of its width (≈ 12 mm) per frame.
pub const TYPE_A_MAX_JUMP_MM: f64 = 40.0;
/// Protocol A: as [`TYPE_A_MAX_JUMP_MM`], in unit-square coordinates, for
/// devices whose resolution is unknown.
pub const TYPE_A_MAX_JUMP_UNIT: f64 = 0.15;

/// How many rows [`assign_min_cost`] solves at most: every anonymous packet
/// and every anonymous previous contact of a type-A frame.
pub const ASSIGN_MAX: usize = 2 * MAX_CONTACTS;

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

/// Which protocol a decoder speaks.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum MtProtocol {
    /// Type B: slots selected with `ABS_MT_SLOT`, contacts named by
    /// `ABS_MT_TRACKING_ID`, incremental values.
    B,
    /// Type A: anonymous contact packets closed by `SYN_MT_REPORT`, every frame
    /// complete.
    A,
    /// No `ABS_MT_*` axes: one contact at `ABS_X/ABS_Y` while `BTN_TOUCH` is 1.
    SingleTouch,
}

/// The axes of a multi-touch device that the decoder needs.
#[derive(Clone, Debug, PartialEq)]
pub struct MtAxes {
    /// `ABS_MT_POSITION_X` range (`ABS_X` for single touch).
    pub x: AxisRange,
    /// `ABS_MT_POSITION_Y` range (`ABS_Y` for single touch).
    pub y: AxisRange,
    /// Number of slots (`ABS_MT_SLOT` max + 1), clamped to `1..=MAX_SLOTS`;
    /// `0` for a type-A device (no `ABS_MT_SLOT`).
    pub slots: usize,
    /// `ABS_MT_PRESSURE` range (`ABS_PRESSURE` for single touch), when the
    /// device reports pressure.
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
    /// Contacts ended by a lift (`UP`).
    pub contacts_ended: u64,
    /// Contacts ended without a clean lift (`CANCELLED`): by
    /// [`MtDecoder::cancel_all`], a [`MtDecoder::resync`], or missing from the
    /// first type-A frame after a `SYN_DROPPED`.
    pub contacts_cancelled: u64,
    /// `ABS_MT_SLOT` values outside `0..slots`; the `ABS_MT_*` events after one
    /// are ignored until a valid slot is selected.
    pub slot_out_of_range: u64,
    /// `ABS_MT_*` events ignored because the selected slot was out of range.
    pub ignored_slot_events: u64,
    /// Contacts that did not fit a frame of [`MAX_CONTACTS`].
    pub frame_overflow: u64,
    /// Type-A packets beyond [`MAX_CONTACTS`] in one frame (dropped).
    pub contacts_over_capacity: u64,
    /// `SYN_DROPPED` events seen.
    pub dropped_sync: u64,
    /// Events discarded after a `SYN_DROPPED` (up to the next `SYN_REPORT`).
    pub discarded_events: u64,
    /// Resynchronisations applied ([`MtDecoder::resync`]).
    pub resyncs: u64,
    /// `SYN_MT_REPORT` events (type-A packets; ignored by type B).
    pub mt_report: u64,
    /// Type-A packets not closed by `SYN_MT_REPORT` before `SYN_REPORT` (kept).
    pub unterminated_packets: u64,
    /// Type-A packets ignored because `BTN_TOUCH 0` came in the same frame.
    pub packets_after_lift: u64,
    /// Contacts that began and ended within one frame (not reported).
    pub transient_contacts: u64,
    /// A slot's active tracking id sent again without a release (continues).
    pub tracking_id_reused: u64,
    /// An active slot given a different tracking id without a release (the old
    /// contact ends, the new one begins).
    pub tracking_id_switched: u64,
    /// Events for an axis the device does not declare (ignored).
    pub undeclared_axis: u64,
}

/// The true state of one slot, as the device reports it on request.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct MtSlotValues {
    /// Tracking id; `-1` when the slot is free.
    pub tracking_id: i32,
    /// `ABS_MT_POSITION_X`.
    pub x: i32,
    /// `ABS_MT_POSITION_Y`.
    pub y: i32,
    /// `ABS_MT_PRESSURE`, when queried.
    pub pressure: Option<i32>,
    /// `ABS_MT_TOUCH_MAJOR`, when queried.
    pub major: Option<i32>,
    /// `ABS_MT_TOUCH_MINOR`, when queried.
    pub minor: Option<i32>,
    /// `ABS_MT_TOOL_TYPE`, when queried.
    pub tool: Option<i32>,
}

impl MtSlotValues {
    /// A free slot with no value known.
    pub const FREE: MtSlotValues = MtSlotValues {
        tracking_id: -1,
        x: 0,
        y: 0,
        pressure: None,
        major: None,
        minor: None,
        tool: None,
    };
}

/// The device's slot table at one instant, for [`MtDecoder::resync`].
///
/// Filled by the device shell from `EVIOCGMTSLOTS` (one call per `ABS_MT_*`
/// code, see [`MtSlotState::set_column`]) and `EVIOCGABS(ABS_MT_SLOT)`, or by
/// tests. For single touch, slot 0 holds the contact (`tracking_id >= 0` while
/// `BTN_TOUCH` is 1, position from `ABS_X/ABS_Y`, pressure from `ABS_PRESSURE`).
/// Fixed capacity, no heap.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MtSlotState {
    slots: [MtSlotValues; MAX_SLOTS],
    len: usize,
    /// The slot later events apply to (`EVIOCGABS(ABS_MT_SLOT).value`), when known.
    pub selected: Option<i32>,
}

impl MtSlotState {
    /// `len` free slots (clamped to [`MAX_SLOTS`]), no selection known.
    pub fn new(len: usize) -> MtSlotState {
        MtSlotState {
            slots: [MtSlotValues::FREE; MAX_SLOTS],
            len: len.min(MAX_SLOTS),
            selected: None,
        }
    }

    /// Number of slots described.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no slot is described.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The slots.
    pub fn slots(&self) -> &[MtSlotValues] {
        &self.slots[..self.len]
    }

    /// The slots, mutable.
    pub fn slots_mut(&mut self) -> &mut [MtSlotValues] {
        &mut self.slots[..self.len]
    }

    /// Stores one `ABS_MT_*` code's value per slot, as `EVIOCGMTSLOTS` returns it.
    ///
    /// Values beyond [`MtSlotState::len`] are ignored. Returns `false` (and
    /// changes nothing) for a code the state does not keep.
    pub fn set_column(&mut self, code: u16, values: &[i32]) -> bool {
        let n = self.len.min(values.len());
        let slots = &mut self.slots[..n];
        match code {
            ABS_MT_TRACKING_ID => slots
                .iter_mut()
                .zip(values)
                .for_each(|(s, &v)| s.tracking_id = v),
            ABS_MT_POSITION_X => slots.iter_mut().zip(values).for_each(|(s, &v)| s.x = v),
            ABS_MT_POSITION_Y => slots.iter_mut().zip(values).for_each(|(s, &v)| s.y = v),
            ABS_MT_PRESSURE => slots
                .iter_mut()
                .zip(values)
                .for_each(|(s, &v)| s.pressure = Some(v)),
            ABS_MT_TOUCH_MAJOR => slots
                .iter_mut()
                .zip(values)
                .for_each(|(s, &v)| s.major = Some(v)),
            ABS_MT_TOUCH_MINOR => slots
                .iter_mut()
                .zip(values)
                .for_each(|(s, &v)| s.minor = Some(v)),
            ABS_MT_TOOL_TYPE => slots
                .iter_mut()
                .zip(values)
                .for_each(|(s, &v)| s.tool = Some(v)),
            _ => return false,
        }
        true
    }
}

/// Dirty bits of the staged values of one slot.
const DIRTY_X: u8 = 1;
const DIRTY_Y: u8 = 2;
const DIRTY_PRESSURE: u8 = 4;
const DIRTY_MAJOR: u8 = 8;
const DIRTY_MINOR: u8 = 16;
const DIRTY_TOOL: u8 = 32;
const DIRTY_TRACKING: u8 = 64;

/// Per-slot (or per-packet) axis values in device units.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
struct SlotValues {
    x: i32,
    y: i32,
    pressure: i32,
    major: i32,
    minor: i32,
    tool: i32,
}

impl SlotValues {
    const ZERO: SlotValues = SlotValues {
        x: 0,
        y: 0,
        pressure: 0,
        major: 0,
        minor: 0,
        tool: 0,
    };

    /// Takes the values a resync reports; optional ones it did not query stay.
    fn apply(&mut self, s: &MtSlotValues) {
        self.x = s.x;
        self.y = s.y;
        self.pressure = s.pressure.unwrap_or(self.pressure);
        self.major = s.major.unwrap_or(self.major);
        self.minor = s.minor.unwrap_or(self.minor);
        self.tool = s.tool.unwrap_or(self.tool);
    }
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
        vals: SlotValues::ZERO,
        staged: SlotValues::ZERO,
        staged_tid: -1,
        dirty: 0,
    };
}

/// A type-A packet (or the single-touch contact) of the current frame.
#[derive(Copy, Clone, Debug)]
struct Packet {
    /// `ABS_MT_TRACKING_ID`, `-1` when the packet carries none.
    tid: i32,
    vals: SlotValues,
}

impl Packet {
    const EMPTY: Packet = Packet {
        tid: -1,
        vals: SlotValues::ZERO,
    };
}

/// A contact of the previous type-A (or single-touch) frame.
#[derive(Copy, Clone, Debug)]
struct Tracked {
    id: ContactId,
    tid: i32,
    vals: SlotValues,
}

impl Tracked {
    const EMPTY: Tracked = Tracked {
        id: ContactId(0),
        tid: -1,
        vals: SlotValues::ZERO,
    };
}

/// State of the type-A and single-touch decoders.
#[derive(Clone, Debug)]
struct PacketState {
    /// Contacts down after the previous frame.
    prev: [Tracked; MAX_CONTACTS],
    prev_len: usize,
    /// Packets closed in the current frame.
    cur: [Packet; MAX_CONTACTS],
    cur_len: usize,
    /// The packet being filled; its values persist from packet to packet.
    pkt: Packet,
    /// Whether the packet being filled received a value.
    pkt_seen: bool,
    /// `BTN_TOUCH 0` came in the current frame.
    lift_all: bool,
    /// A `SYN_DROPPED` came since the last committed frame.
    after_drop: bool,
    /// Single touch: committed and staged `BTN_TOUCH`.
    touch: bool,
    touch_staged: bool,
    /// Single touch: tracking id of the current touch (one per touch-down).
    st_tid: i32,
    /// Single touch: values committed at the last `SYN_REPORT`.
    st_vals: SlotValues,
    /// Distance metric: device units to millimetres (or unit square) per axis.
    scale_x: f64,
    scale_y: f64,
    /// Squared maximum jump in the metric's units.
    max_jump2: f64,
}

impl PacketState {
    fn new(axes: &MtAxes) -> PacketState {
        let mm = axes.x.resolution > 0.0 && axes.y.resolution > 0.0;
        let per_unit = |a: &AxisRange| {
            let span = a.max - a.min;
            if span > 0.0 {
                1.0 / span
            } else {
                1.0
            }
        };
        let (scale_x, scale_y, jump) = if mm {
            (
                1.0 / axes.x.resolution,
                1.0 / axes.y.resolution,
                TYPE_A_MAX_JUMP_MM,
            )
        } else {
            (per_unit(&axes.x), per_unit(&axes.y), TYPE_A_MAX_JUMP_UNIT)
        };
        PacketState {
            prev: [Tracked::EMPTY; MAX_CONTACTS],
            prev_len: 0,
            cur: [Packet::EMPTY; MAX_CONTACTS],
            cur_len: 0,
            pkt: Packet::EMPTY,
            pkt_seen: false,
            lift_all: false,
            after_drop: false,
            touch: false,
            touch_staged: false,
            st_tid: 0,
            st_vals: SlotValues::ZERO,
            scale_x,
            scale_y,
            max_jump2: jump * jump,
        }
    }

    /// Closes the packet being filled, if it received a value.
    fn close_packet(&mut self, counters: &mut MtCounters) {
        if self.pkt_seen {
            if self.cur_len < MAX_CONTACTS {
                self.cur[self.cur_len] = self.pkt;
                self.cur_len += 1;
            } else {
                counters.contacts_over_capacity += 1;
            }
        }
        self.pkt_seen = false;
        self.pkt.tid = -1;
    }
}

/// Cost of a forbidden pair in [`MtDecoder`]'s type-A matching, as a multiple
/// of the squared maximum jump (anything above 1 keeps such pairs unmatched).
const FORBIDDEN_COST_FACTOR: f64 = 4.0;

/// Minimum-cost perfect assignment of an `n × n` cost matrix given as a function.
///
/// Writes `col_of_row[r]` = the column assigned to row `r`, for `r < n`, such that
/// `Σ cost(r, col_of_row[r])` is minimal.
///
/// # Formula
/// The Hungarian method (Kuhn 1955; Munkres 1957) in its shortest augmenting
/// path form with row and column potentials `u`, `v`: each row is added by a
/// Dijkstra-like search over reduced costs `cost(r, c) − u[r] − v[c] ≥ 0`,
/// then the potentials are updated by the smallest slack. The kernel's
/// multi-touch documentation states type-A tracking as this Euclidean bipartite
/// matching problem.
///
/// # Units
/// Whatever `cost` returns; it must be finite (non-finite costs give an
/// arbitrary assignment, never a panic or an endless loop).
///
/// # Complexity
/// O(n³) time, O(`ASSIGN_MAX`) stack, no heap. `n` above [`ASSIGN_MAX`] is
/// clamped to it.
///
/// # Errors
/// None.
///
/// ```
/// use crowdtouch::input::evdev::{assign_min_cost, ASSIGN_MAX};
/// let c = [[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]];
/// let mut col = [0usize; ASSIGN_MAX];
/// assign_min_cost(3, |r, k| c[r][k], &mut col);
/// let total: f64 = (0..3).map(|r| c[r][col[r]]).sum();
/// assert!((total - 5.0).abs() < 1e-12);
/// ```
pub fn assign_min_cost(
    n: usize,
    cost: impl Fn(usize, usize) -> f64,
    col_of_row: &mut [usize; ASSIGN_MAX],
) {
    let n = n.min(ASSIGN_MAX);
    // 1-based arrays; index 0 is the virtual root column.
    let mut u = [0.0f64; ASSIGN_MAX + 1];
    let mut v = [0.0f64; ASSIGN_MAX + 1];
    let mut row_of_col = [0usize; ASSIGN_MAX + 1];
    let mut way = [0usize; ASSIGN_MAX + 1];
    for row in 1..=n {
        row_of_col[0] = row;
        let mut j0 = 0usize;
        let mut minv = [f64::INFINITY; ASSIGN_MAX + 1];
        let mut used = [false; ASSIGN_MAX + 1];
        loop {
            used[j0] = true;
            let i0 = row_of_col[j0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0usize;
            for j in 1..=n {
                if used[j] {
                    continue;
                }
                let cur = cost(i0 - 1, j - 1) - u[i0] - v[j];
                if cur < minv[j] {
                    minv[j] = cur;
                    way[j] = j0;
                }
                // `j1 == 0` takes the first free column even if every slack is
                // NaN or infinite, so the search always advances.
                if j1 == 0 || minv[j] < delta {
                    delta = minv[j];
                    j1 = j;
                }
            }
            if !delta.is_finite() {
                delta = 0.0;
            }
            for j in 0..=n {
                if used[j] {
                    u[row_of_col[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if j0 == 0 || row_of_col[j0] == 0 {
                break;
            }
        }
        // Augment along the alternating path back to the root.
        while j0 != 0 {
            let j1 = way[j0];
            row_of_col[j0] = row_of_col[j1];
            j0 = j1;
        }
    }
    for j in 1..=n {
        if row_of_col[j] > 0 {
            col_of_row[row_of_col[j] - 1] = j - 1;
        }
    }
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
    axes: MtAxes,
    protocol: MtProtocol,
    slots: [Slot; MAX_SLOTS],
    /// Number of slots in use (`1..=MAX_SLOTS` for type B, 0 otherwise).
    nslots: usize,
    /// Selected slot, `None` after an out-of-range `ABS_MT_SLOT`.
    current: Option<usize>,
    /// Bit `i` set when slot `i` has staged changes.
    dirty_slots: u64,
    /// Discarding events until the next `SYN_REPORT`.
    dropping: bool,
    /// The block being discarded began with `SYN_DROPPED` (not `discard_frame`).
    dropped_sync: bool,
    /// A dropped block ended: the shell should query the device and resync.
    resync_wanted: bool,
    packets: PacketState,
    next_id: u32,
    counters: MtCounters,
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
    fn declared(&mut self, code: u16) -> bool {
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

    /// A type-B event other than `EV_SYN`.
    fn event_b(&mut self, ev_type: u16, code: u16, value: i32) {
        match (ev_type, code) {
            (EV_ABS, ABS_MT_SLOT) => {
                if value >= 0 && (value as usize) < self.nslots {
                    self.current = Some(value as usize);
                } else {
                    self.counters.slot_out_of_range += 1;
                    self.current = None;
                }
            }
            (
                EV_ABS,
                ABS_MT_TRACKING_ID | ABS_MT_POSITION_X | ABS_MT_POSITION_Y | ABS_MT_PRESSURE
                | ABS_MT_TOUCH_MAJOR | ABS_MT_TOUCH_MINOR | ABS_MT_TOOL_TYPE,
            ) => {
                if !self.declared(code) {
                    return;
                }
                let Some(i) = self.current else {
                    self.counters.ignored_slot_events += 1;
                    return;
                };
                self.dirty_slots |= 1u64 << i;
                let s = &mut self.slots[i];
                match code {
                    ABS_MT_TRACKING_ID => {
                        let value = value.max(-1);
                        let staged = s.dirty & DIRTY_TRACKING != 0;
                        let before = if staged { s.staged_tid } else { s.tracking_id };
                        if value == before {
                            if value >= 0 {
                                // A begin without a release: the contact continues.
                                self.counters.tracking_id_reused += 1;
                            }
                        } else {
                            if staged && before >= 0 && before != s.tracking_id {
                                // A contact begun in this frame ends in it too.
                                self.counters.transient_contacts += 1;
                            } else if before >= 0 && value >= 0 {
                                self.counters.tracking_id_switched += 1;
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
            }
            _ => {}
        }
    }

    /// A type-A event other than `EV_SYN`.
    fn event_a(&mut self, ev_type: u16, code: u16, value: i32) {
        match (ev_type, code) {
            (EV_KEY, BTN_TOUCH) if value == 0 => self.packets.lift_all = true,
            (EV_ABS, ABS_MT_SLOT) => self.counters.undeclared_axis += 1,
            (
                EV_ABS,
                ABS_MT_TRACKING_ID | ABS_MT_POSITION_X | ABS_MT_POSITION_Y | ABS_MT_PRESSURE
                | ABS_MT_TOUCH_MAJOR | ABS_MT_TOUCH_MINOR | ABS_MT_TOOL_TYPE,
            ) => {
                if !self.declared(code) {
                    return;
                }
                let p = &mut self.packets;
                p.pkt_seen = true;
                match code {
                    ABS_MT_TRACKING_ID => p.pkt.tid = value.max(-1),
                    ABS_MT_POSITION_X => p.pkt.vals.x = value,
                    ABS_MT_POSITION_Y => p.pkt.vals.y = value,
                    ABS_MT_PRESSURE => p.pkt.vals.pressure = value,
                    ABS_MT_TOUCH_MAJOR => p.pkt.vals.major = value,
                    ABS_MT_TOUCH_MINOR => p.pkt.vals.minor = value,
                    _ => p.pkt.vals.tool = value,
                }
            }
            _ => {}
        }
    }

    /// A single-touch event other than `EV_SYN`.
    fn event_st(&mut self, ev_type: u16, code: u16, value: i32) {
        match (ev_type, code) {
            (EV_KEY, BTN_TOUCH) => self.packets.touch_staged = value != 0,
            (EV_ABS, ABS_X) => self.packets.pkt.vals.x = value,
            (EV_ABS, ABS_Y) => self.packets.pkt.vals.y = value,
            (EV_ABS, ABS_PRESSURE) => {
                if self.axes.pressure.is_some() {
                    self.packets.pkt.vals.pressure = value;
                } else {
                    self.counters.undeclared_axis += 1;
                }
            }
            (EV_ABS, ABS_MT_SLOT..=ABS_MT_TOOL_Y) => self.counters.undeclared_axis += 1,
            _ => {}
        }
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
            MtProtocol::A => {
                let p = &mut self.packets;
                for s in state.slots().iter().filter(|s| s.tracking_id >= 0) {
                    if p.cur_len < MAX_CONTACTS {
                        let mut vals = SlotValues::ZERO;
                        vals.apply(s);
                        p.cur[p.cur_len] = Packet {
                            tid: s.tracking_id,
                            vals,
                        };
                        p.cur_len += 1;
                    } else {
                        self.counters.contacts_over_capacity += 1;
                    }
                }
                self.packets.after_drop = false;
                self.commit_packets(t, out, ContactFlags::CANCELLED);
            }
            MtProtocol::SingleTouch => {
                if let Some(s) = state.slots().first() {
                    let p = &mut self.packets;
                    p.pkt.vals.apply(s);
                    p.st_vals = p.pkt.vals;
                    p.touch_staged = s.tracking_id >= 0;
                }
                self.stage_single_touch();
                self.commit_packets(t, out, ContactFlags::CANCELLED);
            }
        }
        !out.is_empty()
    }

    /// Type-B part of [`MtDecoder::resync`].
    fn resync_b(&mut self, t: Micros, state: &MtSlotState, out: &mut TouchFrame) {
        out.clear();
        out.t = t;
        let n = state.len().min(self.nslots);
        let mut began: u64 = 0;
        for (i, s) in state.slots()[..n].iter().enumerate() {
            let new_tid = s.tracking_id.max(-1);
            let old = self.slots[i];
            if old.tracking_id >= 0 && new_tid != old.tracking_id {
                self.counters.contacts_cancelled += 1;
                let c = self.contact(old.id, &old.vals, ContactFlags::CANCELLED);
                self.emit(out, c);
            }
            if new_tid >= 0 && new_tid != old.tracking_id {
                began |= 1u64 << i;
                self.slots[i].id = ContactId(self.next_id);
                self.next_id = self.next_id.wrapping_add(1);
                self.counters.contacts_begun += 1;
            }
            let slot = &mut self.slots[i];
            slot.tracking_id = new_tid;
            slot.vals.apply(s);
        }
        if let Some(sel) = state.selected {
            self.current = (sel >= 0 && (sel as usize) < self.nslots).then_some(sel as usize);
        }
        self.emit_slots(out, began);
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

    /// Pushes the active slots: begun ones (`began` bit set) `DOWN`, then the
    /// continuing ones, in slot order.
    fn emit_slots(&mut self, out: &mut TouchFrame, began: u64) {
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

    /// Applies the staged changes and fills `out`: ended, begun, then continuing.
    fn commit(&mut self, t: Micros, out: &mut TouchFrame) {
        out.clear();
        out.t = t;
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
        self.emit_slots(out, began);
    }

    /// Closes a type-A frame.
    fn commit_a(&mut self, t: Micros, out: &mut TouchFrame) {
        let p = &mut self.packets;
        if p.pkt_seen {
            self.counters.unterminated_packets += 1;
            p.close_packet(&mut self.counters);
        }
        if p.lift_all {
            self.counters.packets_after_lift += p.cur_len as u64;
            p.cur_len = 0;
        }
        let end = if p.after_drop {
            ContactFlags::CANCELLED
        } else {
            ContactFlags::UP
        };
        p.after_drop = false;
        p.lift_all = false;
        self.commit_packets(t, out, end);
    }

    /// Turns the staged single-touch state into the frame's packet.
    fn stage_single_touch(&mut self) {
        let p = &mut self.packets;
        p.st_vals = p.pkt.vals;
        p.cur_len = 0;
        if p.touch_staged {
            if !p.touch {
                p.st_tid = p.st_tid.wrapping_add(1) & i32::MAX;
            }
            p.cur[0] = Packet {
                tid: p.st_tid,
                vals: p.pkt.vals,
            };
            p.cur_len = 1;
        }
        p.touch = p.touch_staged;
    }

    /// Closes a single-touch frame.
    fn commit_st(&mut self, t: Micros, out: &mut TouchFrame) {
        self.stage_single_touch();
        self.commit_packets(t, out, ContactFlags::UP);
    }

    /// Matches the current packets to the previous frame's contacts and fills
    /// `out`: ended (with `end`), begun, then continuing. The packets become
    /// the previous frame's contacts.
    fn commit_packets(&mut self, t: Micros, out: &mut TouchFrame, end: ContactFlags) {
        const NONE: usize = usize::MAX;
        out.clear();
        out.t = t;
        let n = self.packets.cur_len;
        let m = self.packets.prev_len;
        // Previous contact matched by each packet, and which are taken.
        let mut match_of = [NONE; MAX_CONTACTS];
        let mut taken = [false; MAX_CONTACTS];
        {
            let p = &self.packets;
            for (i, pkt) in p.cur[..n].iter().enumerate() {
                if pkt.tid < 0 {
                    continue;
                }
                if let Some(j) = (0..m).find(|&j| !taken[j] && p.prev[j].tid == pkt.tid) {
                    match_of[i] = j;
                    taken[j] = true;
                }
            }
            // Anonymous packets against anonymous previous contacts.
            let mut rows = [0usize; MAX_CONTACTS];
            let mut na = 0;
            for (i, pkt) in p.cur[..n].iter().enumerate() {
                if pkt.tid < 0 {
                    rows[na] = i;
                    na += 1;
                }
            }
            let mut cols = [0usize; MAX_CONTACTS];
            let mut nb = 0;
            for (j, prev) in p.prev[..m].iter().enumerate() {
                if !taken[j] && prev.tid < 0 {
                    cols[nb] = j;
                    nb += 1;
                }
            }
            if na > 0 && nb > 0 {
                let (sx, sy, lim2) = (p.scale_x, p.scale_y, p.max_jump2);
                // Rows: packets then one "previous contact ends" row per column;
                // columns: previous contacts then one "packet begins" column per
                // row. A real pair costs its squared distance (forbidden beyond
                // the jump limit); leaving both unmatched costs `lim2`.
                let cost = |r: usize, c: usize| -> f64 {
                    match (r < na, c < nb) {
                        (true, true) => {
                            let a = &p.cur[rows[r]].vals;
                            let b = &p.prev[cols[c]].vals;
                            let dx = (f64::from(a.x) - f64::from(b.x)) * sx;
                            let dy = (f64::from(a.y) - f64::from(b.y)) * sy;
                            let d2 = dx * dx + dy * dy;
                            if d2 <= lim2 {
                                d2
                            } else {
                                FORBIDDEN_COST_FACTOR * lim2
                            }
                        }
                        (false, false) => 0.0,
                        _ => 0.5 * lim2,
                    }
                };
                let mut col_of_row = [0usize; ASSIGN_MAX];
                assign_min_cost(na + nb, cost, &mut col_of_row);
                for r in 0..na {
                    let c = col_of_row[r];
                    if c < nb {
                        let j = cols[c];
                        // Only pairs within the limit count (a forbidden pair
                        // can only be chosen through non-finite input).
                        let a = &p.cur[rows[r]].vals;
                        let b = &p.prev[j].vals;
                        let dx = (f64::from(a.x) - f64::from(b.x)) * sx;
                        let dy = (f64::from(a.y) - f64::from(b.y)) * sy;
                        if dx * dx + dy * dy <= lim2 {
                            match_of[rows[r]] = j;
                            taken[j] = true;
                        }
                    }
                }
            }
        }
        for j in (0..m).filter(|&j| !taken[j]) {
            let prev = self.packets.prev[j];
            if end == ContactFlags::CANCELLED {
                self.counters.contacts_cancelled += 1;
            } else {
                self.counters.contacts_ended += 1;
            }
            let c = self.contact(prev.id, &prev.vals, end);
            self.emit(out, c);
        }
        let mut next = [Tracked::EMPTY; MAX_CONTACTS];
        for i in 0..n {
            let pkt = self.packets.cur[i];
            let id = if match_of[i] == NONE {
                let id = ContactId(self.next_id);
                self.next_id = self.next_id.wrapping_add(1);
                self.counters.contacts_begun += 1;
                let c = self.contact(id, &pkt.vals, ContactFlags::DOWN);
                self.emit(out, c);
                id
            } else {
                self.packets.prev[match_of[i]].id
            };
            next[i] = Tracked {
                id,
                tid: pkt.tid,
                vals: pkt.vals,
            };
        }
        for i in 0..n {
            if match_of[i] != NONE {
                let c = self.contact(next[i].id, &next[i].vals, ContactFlags::NONE);
                self.emit(out, c);
            }
        }
        self.packets.prev = next;
        self.packets.prev_len = n;
        self.packets.cur_len = 0;
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
    fn axes_a() -> MtAxes {
        MtAxes {
            slots: 0,
            ..axes(1)
        }
    }

    const MT: (u16, u16, i32) = (EV_SYN, SYN_MT_REPORT, 0);

    fn pkt(x: i32, y: i32) -> [(u16, u16, i32); 3] {
        [
            (EV_ABS, ABS_MT_POSITION_X, x),
            (EV_ABS, ABS_MT_POSITION_Y, y),
            MT,
        ]
    }

    /// Feeds one type-A frame of packets at `(x, y)`.
    fn frame_a(d: &mut MtDecoder, t: u64, pts: &[(i32, i32)]) -> TouchFrame {
        let mut evs: Vec<(u16, u16, i32)> = pts.iter().flat_map(|&(x, y)| pkt(x, y)).collect();
        evs.push(SYN);
        feed(d, t, &evs).unwrap()
    }

    fn xs(f: &TouchFrame) -> Vec<(u32, i32, ContactFlags)> {
        f.contacts()
            .iter()
            .map(|c| (c.id.0, (c.x * 1000.0).round() as i32, c.flags))
            .collect()
    }

    #[test]
    fn protocol_a_tracks_by_nearest_neighbour() {
        let mut d = MtDecoder::new(axes_a(), 1);
        assert_eq!(d.protocol(), MtProtocol::A);
        let f = frame_a(&mut d, 1, &[(100, 100), (800, 800)]);
        assert_eq!(
            xs(&f),
            vec![(1, 100, ContactFlags::DOWN), (2, 800, ContactFlags::DOWN)]
        );
        // Packet order swaps; identity follows the positions.
        let f = frame_a(&mut d, 2, &[(790, 800), (110, 100)]);
        assert_eq!(
            xs(&f),
            vec![(2, 790, ContactFlags::NONE), (1, 110, ContactFlags::NONE)]
        );
        // Contact 1 lifts: it ends at its last position, 2 continues.
        let f = frame_a(&mut d, 3, &[(780, 800)]);
        assert_eq!(
            xs(&f),
            vec![(1, 110, ContactFlags::UP), (2, 780, ContactFlags::NONE)]
        );
        // A jump beyond the limit (40 mm; 10 units/mm here) is a new contact.
        let f = frame_a(&mut d, 4, &[(370, 800)]);
        assert_eq!(
            xs(&f),
            vec![(2, 780, ContactFlags::UP), (3, 370, ContactFlags::DOWN)]
        );
        // Just within the limit it moves.
        let f = frame_a(&mut d, 5, &[(760, 800)]);
        assert_eq!(xs(&f), vec![(3, 760, ContactFlags::NONE)]);
        // The empty frame (a lone SYN_MT_REPORT) lifts everything.
        let f = feed(&mut d, 6, &[MT, SYN]).unwrap();
        assert_eq!(xs(&f), vec![(3, 760, ContactFlags::UP)]);
        assert_eq!(d.active_contacts(), 0);
        let c = d.counters();
        assert_eq!((c.contacts_begun, c.contacts_ended, c.mt_report), (3, 3, 8));
    }

    #[test]
    fn protocol_a_optimal_not_greedy() {
        // Greedy nearest-first would pair the new (500) with old 450 and leave
        // (380) to jump to 600; the optimal assignment keeps both close.
        let mut d = MtDecoder::new(axes_a(), 1);
        frame_a(&mut d, 1, &[(380, 500), (600, 500)]);
        let f = frame_a(&mut d, 2, &[(450, 500), (560, 500)]);
        assert_eq!(
            xs(&f),
            vec![(1, 450, ContactFlags::NONE), (2, 560, ContactFlags::NONE)]
        );
    }

    #[test]
    fn protocol_a_btn_touch_zero_lifts_all() {
        let mut d = MtDecoder::new(axes_a(), 1);
        frame_a(&mut d, 1, &[(100, 100), (800, 800)]);
        // No SYN_MT_REPORT at all, only BTN_TOUCH 0.
        let f = feed(&mut d, 2, &[(EV_KEY, BTN_TOUCH, 0), SYN]).unwrap();
        assert_eq!(
            ids_flags(&f),
            vec![(1, ContactFlags::UP), (2, ContactFlags::UP)]
        );
        // Packets in a BTN_TOUCH 0 frame are ignored and counted.
        frame_a(&mut d, 3, &[(100, 100)]);
        let mut evs = pkt(100, 100).to_vec();
        evs.extend([(EV_KEY, BTN_TOUCH, 0), SYN]);
        let f = feed(&mut d, 4, &evs).unwrap();
        assert_eq!(ids_flags(&f), vec![(3, ContactFlags::UP)]);
        assert_eq!(d.counters().packets_after_lift, 1);
    }

    #[test]
    fn protocol_a_tracking_id_wins_over_distance() {
        let mut d = MtDecoder::new(axes_a(), 1);
        let f = feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 40),
                (EV_ABS, ABS_MT_POSITION_X, 100),
                MT,
                (EV_ABS, ABS_MT_TRACKING_ID, 41),
                (EV_ABS, ABS_MT_POSITION_X, 120),
                MT,
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(xs(&f).len(), 2);
        // Positions swap, ids do not: identity follows the tracking id, even a
        // far jump.
        let f = feed(
            &mut d,
            2,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 41),
                (EV_ABS, ABS_MT_POSITION_X, 100),
                MT,
                (EV_ABS, ABS_MT_TRACKING_ID, 40),
                (EV_ABS, ABS_MT_POSITION_X, 900),
                MT,
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(
            xs(&f),
            vec![(2, 100, ContactFlags::NONE), (1, 900, ContactFlags::NONE)]
        );
    }

    #[test]
    fn protocol_a_bad_input_is_counted() {
        let mut d = MtDecoder::new(axes_a(), 1);
        let mut evs = Vec::new();
        for i in 0..(MAX_CONTACTS as i32 + 3) {
            evs.extend(pkt(i * 10, 0));
        }
        evs.push((EV_ABS, ABS_MT_SLOT, 1));
        evs.push((EV_ABS, ABS_MT_PRESSURE, 1));
        // An unterminated packet is kept.
        evs.push((EV_ABS, ABS_MT_POSITION_X, 5));
        evs.push(SYN);
        let f = feed(&mut d, 1, &evs).unwrap();
        assert_eq!(f.len(), MAX_CONTACTS);
        let c = d.counters();
        assert_eq!(c.contacts_over_capacity, 4);
        assert_eq!(c.unterminated_packets, 1);
        assert_eq!(c.undeclared_axis, 2);
    }

    #[test]
    fn protocol_a_after_drop_cancels_vanished() {
        let mut d = MtDecoder::new(axes_a(), 1);
        frame_a(&mut d, 1, &[(100, 100), (800, 800)]);
        let mut f = TouchFrame::default();
        d.event(Micros(2), EV_ABS, ABS_MT_POSITION_X, 3, &mut f);
        d.event(Micros(2), EV_SYN, SYN_DROPPED, 0, &mut f);
        d.event(Micros(2), EV_SYN, SYN_REPORT, 0, &mut f);
        assert!(!d.wants_resync(), "type A resyncs from its next frame");
        let f = frame_a(&mut d, 3, &[(805, 800)]);
        assert_eq!(
            ids_flags(&f),
            vec![(1, ContactFlags::CANCELLED), (2, ContactFlags::NONE)]
        );
        // Only the first frame after the drop cancels.
        let f = frame_a(&mut d, 4, &[]);
        assert_eq!(ids_flags(&f), vec![(2, ContactFlags::UP)]);
    }

    fn state(tids: &[(i32, i32, i32)]) -> MtSlotState {
        let mut s = MtSlotState::new(tids.len());
        for (slot, &(tid, x, y)) in s.slots_mut().iter_mut().zip(tids) {
            slot.tracking_id = tid;
            slot.x = x;
            slot.y = y;
        }
        s
    }

    #[test]
    fn resync_cancels_begins_and_moves() {
        let mut d = MtDecoder::new(axes(4), 1);
        feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_MT_TRACKING_ID, 10),
                (EV_ABS, ABS_MT_POSITION_X, 100),
                (EV_ABS, ABS_MT_SLOT, 1),
                (EV_ABS, ABS_MT_TRACKING_ID, 11),
                (EV_ABS, ABS_MT_POSITION_X, 200),
                (EV_ABS, ABS_MT_SLOT, 2),
                (EV_ABS, ABS_MT_TRACKING_ID, 12),
                (EV_ABS, ABS_MT_POSITION_X, 300),
                SYN,
            ],
        );
        let mut f = TouchFrame::default();
        d.event(Micros(2), EV_SYN, SYN_DROPPED, 0, &mut f);
        assert!(!d.wants_resync(), "not before the block's SYN_REPORT");
        d.event(Micros(2), EV_ABS, ABS_MT_TRACKING_ID, -1, &mut f);
        d.event(Micros(3), EV_SYN, SYN_REPORT, 0, &mut f);
        assert!(d.wants_resync() && !d.is_discarding());
        // Slot 0 moved, slot 1 lifted, slot 2 re-identified, slot 3 new.
        let mut s = state(&[(10, 150, 0), (-1, 200, 0), (13, 350, 0), (14, 900, 0)]);
        s.selected = Some(3);
        assert!(d.resync(Micros(3), &s, &mut f));
        assert!(!d.wants_resync());
        assert_eq!(
            xs(&f),
            vec![
                (2, 200, ContactFlags::CANCELLED),
                (3, 300, ContactFlags::CANCELLED),
                (4, 350, ContactFlags::DOWN),
                (5, 900, ContactFlags::DOWN),
                (1, 150, ContactFlags::NONE),
            ]
        );
        assert_eq!(f.t, Micros(3));
        // The selected slot now is 3: a lift without ABS_MT_SLOT ends contact 5.
        let f = feed(&mut d, 4, &[(EV_ABS, ABS_MT_TRACKING_ID, -1), SYN]).unwrap();
        assert_eq!(ids_flags(&f)[0], (5, ContactFlags::UP));
        assert_eq!(d.counters().contacts_cancelled, 2);
        assert_eq!(d.counters().resyncs, 1);
        // Nothing down and nothing reported: no frame content.
        let mut d = MtDecoder::new(axes(2), 1);
        let mut f = TouchFrame::default();
        assert!(!d.resync(Micros(5), &MtSlotState::new(2), &mut f));
        assert!(f.is_empty());
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

    #[test]
    fn tracking_id_reuse_and_switch_are_counted() {
        let mut d = MtDecoder::new(axes(2), 1);
        feed(&mut d, 1, &[(EV_ABS, ABS_MT_TRACKING_ID, 7), SYN]);
        let f = feed(&mut d, 2, &[(EV_ABS, ABS_MT_TRACKING_ID, 7), SYN]).unwrap();
        assert_eq!(ids_flags(&f), vec![(1, ContactFlags::NONE)]);
        let f = feed(&mut d, 3, &[(EV_ABS, ABS_MT_TRACKING_ID, 8), SYN]).unwrap();
        assert_eq!(
            ids_flags(&f),
            vec![(1, ContactFlags::UP), (2, ContactFlags::DOWN)]
        );
        let c = d.counters();
        assert_eq!((c.tracking_id_reused, c.tracking_id_switched), (1, 1));
        // Axes the device lacks.
        feed(&mut d, 4, &[(EV_ABS, ABS_MT_PRESSURE, 3), SYN]);
        assert_eq!(d.counters().undeclared_axis, 1);
    }

    #[test]
    fn single_touch_down_move_up_and_resync() {
        let mut a = axes(1);
        a.pressure = Some(AxisRange {
            min: 0.0,
            max: 100.0,
            resolution: 0.0,
        });
        let mut d = MtDecoder::with_protocol(a, MtProtocol::SingleTouch, 1);
        let f = feed(
            &mut d,
            1,
            &[
                (EV_ABS, ABS_X, 100),
                (EV_ABS, ABS_Y, 200),
                (EV_ABS, ABS_PRESSURE, 50),
                (EV_KEY, BTN_TOUCH, 1),
                SYN,
            ],
        )
        .unwrap();
        assert_eq!(xs(&f), vec![(1, 100, ContactFlags::DOWN)]);
        assert_eq!(f.contacts()[0].pressure, Some(0.5));
        let f = feed(&mut d, 2, &[(EV_ABS, ABS_X, 300), SYN]).unwrap();
        assert_eq!(xs(&f), vec![(1, 300, ContactFlags::NONE)]);
        let f = feed(&mut d, 3, &[(EV_KEY, BTN_TOUCH, 0), SYN]).unwrap();
        assert_eq!(xs(&f), vec![(1, 300, ContactFlags::UP)]);
        feed(&mut d, 4, &[(EV_KEY, BTN_TOUCH, 1), SYN]);
        // A drop hides the lift and a new touch elsewhere: the resync says
        // "touching" (same contact moved, as single touch has no identity).
        let mut f = TouchFrame::default();
        d.event(Micros(5), EV_SYN, SYN_DROPPED, 0, &mut f);
        d.event(Micros(5), EV_SYN, SYN_REPORT, 0, &mut f);
        assert!(d.wants_resync());
        assert!(d.resync(Micros(5), &state(&[(0, 700, 0)]), &mut f));
        assert_eq!(xs(&f), vec![(2, 700, ContactFlags::NONE)]);
        assert!(d.resync(Micros(6), &state(&[(-1, 700, 0)]), &mut f));
        assert_eq!(xs(&f), vec![(2, 700, ContactFlags::CANCELLED)]);
        assert_eq!(d.active_contacts(), 0);
        // MT events on a single-touch device are counted.
        feed(&mut d, 7, &[(EV_ABS, ABS_MT_POSITION_X, 1), SYN]);
        assert_eq!(d.counters().undeclared_axis, 1);
    }

    #[test]
    fn slot_state_columns() {
        let mut s = MtSlotState::new(3);
        assert!(s.set_column(ABS_MT_TRACKING_ID, &[4, -1, 6, 99]));
        assert!(s.set_column(ABS_MT_POSITION_X, &[1, 2]));
        assert!(s.set_column(ABS_MT_PRESSURE, &[9, 9, 9]));
        assert!(!s.set_column(ABS_MT_ORIENTATION, &[1, 1, 1]));
        let v: Vec<(i32, i32, Option<i32>)> = s
            .slots()
            .iter()
            .map(|v| (v.tracking_id, v.x, v.pressure))
            .collect();
        assert_eq!(v, vec![(4, 1, Some(9)), (-1, 2, Some(9)), (6, 0, Some(9))]);
        assert_eq!(MtSlotState::new(1000).len(), MAX_SLOTS);
    }

    /// Smallest total cost over all permutations.
    fn brute_force(n: usize, c: &[f64]) -> f64 {
        fn go(n: usize, row: usize, used: &mut Vec<bool>, c: &[f64]) -> f64 {
            if row == n {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for col in 0..n {
                if !used[col] {
                    used[col] = true;
                    best = best.min(c[row * n + col] + go(n, row + 1, used, c));
                    used[col] = false;
                }
            }
            best
        }
        go(n, 0, &mut vec![false; n], c)
    }

    #[test]
    fn assignment_is_optimal_against_brute_force() {
        // Seeded LCG: integer costs make ties common.
        let mut seed: u64 = 0x5eed;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 33) % 20
        };
        for n in 1..=7 {
            for _ in 0..30 {
                let c: Vec<f64> = (0..n * n).map(|_| rnd() as f64).collect();
                let mut col = [usize::MAX; ASSIGN_MAX];
                assign_min_cost(n, |r, k| c[r * n + k], &mut col);
                let mut seen = vec![false; n];
                for &k in &col[..n] {
                    assert!(k < n && !seen[k], "not a permutation: {:?}", &col[..n]);
                    seen[k] = true;
                }
                let got: f64 = (0..n).map(|r| c[r * n + col[r]]).sum();
                assert!((got - brute_force(n, &c)).abs() < 1e-9, "n={n}");
            }
        }
        // Non-finite costs still give a permutation.
        let mut col = [usize::MAX; ASSIGN_MAX];
        assign_min_cost(3, |_, _| f64::NAN, &mut col);
        let mut cols = col[..3].to_vec();
        cols.sort_unstable();
        assert_eq!(cols, vec![0, 1, 2]);
    }
}
