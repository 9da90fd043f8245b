//! The packet table of the type-A and single-touch decoders: the contacts of the
//! previous frame, the packets of the current one, and the distance metric that
//! matches them.

use super::axes::MtAxes;
use super::counters::MtCounters;
use super::slots::SlotValues;
use crate::input::AxisRange;
use crate::vocab::{ContactId, MAX_CONTACTS};

/// Protocol A: farthest a contact moves between two frames and is still the
/// same contact, in millimetres (used when both position resolutions are known).
///
/// 40 mm per frame is 2.4 m/s at 60 Hz, faster than a finger drags on glass;
/// the N-Trig drag fixture moves at most 0.045 of its width (≈ 12 mm) per frame.
pub const TYPE_A_MAX_JUMP_MM: f64 = 40.0;
/// Protocol A: as [`TYPE_A_MAX_JUMP_MM`], in unit-square coordinates, for
/// devices whose resolution is unknown.
pub const TYPE_A_MAX_JUMP_UNIT: f64 = 0.15;

/// A type-A packet (or the single-touch contact) of the current frame.
#[derive(Copy, Clone, Debug)]
pub(super) struct Packet {
    /// `ABS_MT_TRACKING_ID`, `-1` when the packet carries none.
    pub(super) tid: i32,
    pub(super) vals: SlotValues,
}

impl Packet {
    pub(super) const EMPTY: Packet = Packet {
        tid: -1,
        vals: SlotValues::ZERO,
    };
}

/// A contact of the previous type-A (or single-touch) frame.
#[derive(Copy, Clone, Debug)]
pub(super) struct Tracked {
    pub(super) id: ContactId,
    pub(super) tid: i32,
    pub(super) vals: SlotValues,
}

impl Tracked {
    pub(super) const EMPTY: Tracked = Tracked {
        id: ContactId(0),
        tid: -1,
        vals: SlotValues::ZERO,
    };
}

/// State of the type-A and single-touch decoders.
#[derive(Clone, Debug)]
pub(super) struct PacketState {
    /// Contacts down after the previous frame.
    pub(super) prev: [Tracked; MAX_CONTACTS],
    pub(super) prev_len: usize,
    /// Packets closed in the current frame.
    pub(super) cur: [Packet; MAX_CONTACTS],
    pub(super) cur_len: usize,
    /// The packet being filled; its values persist from packet to packet.
    pub(super) pkt: Packet,
    /// Whether the packet being filled received a value.
    pub(super) pkt_seen: bool,
    /// `BTN_TOUCH 0` came in the current frame.
    pub(super) lift_all: bool,
    /// A `SYN_DROPPED` came since the last committed frame.
    pub(super) after_drop: bool,
    /// Single touch: committed and staged `BTN_TOUCH`.
    pub(super) touch: bool,
    pub(super) touch_staged: bool,
    /// Single touch: tracking id of the current touch (one per touch-down).
    pub(super) st_tid: i32,
    /// Single touch: values committed at the last `SYN_REPORT`.
    pub(super) st_vals: SlotValues,
    /// Distance metric: device units to millimetres (or unit square) per axis.
    pub(super) scale_x: f64,
    pub(super) scale_y: f64,
    /// Squared maximum jump in the metric's units.
    pub(super) max_jump2: f64,
}

impl PacketState {
    pub(super) fn new(axes: &MtAxes) -> PacketState {
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
    pub(super) fn close_packet(&mut self, counters: &mut MtCounters) {
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
