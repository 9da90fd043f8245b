//! A pure decoder for the Linux multi-touch protocol: type B (slots), type A
//! (anonymous contacts) and single-touch screens.
//!
//! [`MtDecoder`] is a state machine over evdev input events `(time, type, code,
//! value)`. It keeps fixed tables (no allocation after construction, none per
//! event), stages every change made between two `SYN_REPORT`s, and at
//! `SYN_REPORT` commits them and fills a [`TouchFrame`](crate::vocab::TouchFrame). It never opens a device:
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
//! * `ABS_MT_TOOL_TYPE = MT_TOOL_PALM` marks the contact [`ContactFlags::PALM`](crate::vocab::ContactFlags::PALM).
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
//! Positions are normalised to the unit square with [`AxisRange::normalise`](crate::input::AxisRange::normalise);
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

mod assign;
mod axes;
mod counters;
mod decoder;
mod packets;
mod protocol_a;
mod protocol_b;
mod single_touch;
mod slots;

pub use assign::{assign_min_cost, ASSIGN_MAX};
pub use axes::{MtAxes, MtProtocol};
pub use counters::MtCounters;
pub use decoder::{MtDecoder, RawEvent};
pub use packets::{TYPE_A_MAX_JUMP_MM, TYPE_A_MAX_JUMP_UNIT};
pub use slots::{MtSlotState, MtSlotValues, MAX_SLOTS};
