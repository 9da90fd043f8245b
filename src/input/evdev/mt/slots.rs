//! The slot tables: the device's true state as queried for a resync
//! ([`MtSlotState`]), and the decoder's own per-slot state (committed values and
//! what the current frame staged).

use crate::input::evdev::codes::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE, ABS_MT_TOOL_TYPE, ABS_MT_TOUCH_MAJOR,
    ABS_MT_TOUCH_MINOR, ABS_MT_TRACKING_ID,
};
use crate::vocab::{ContactId, MAX_CONTACTS};

/// Most slots a decoder tracks; slots of larger devices are counted as out of range.
pub const MAX_SLOTS: usize = MAX_CONTACTS;

// One `EVIOCGMTSLOTS` request reads every slot a decoder holds.
const _: () = assert!(MAX_SLOTS <= crate::sys::MAX_SLOTS);

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

/// The device's slot table at one instant, for [`MtDecoder::resync`](super::MtDecoder::resync).
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
pub(super) const DIRTY_X: u8 = 1;
pub(super) const DIRTY_Y: u8 = 2;
pub(super) const DIRTY_PRESSURE: u8 = 4;
pub(super) const DIRTY_MAJOR: u8 = 8;
pub(super) const DIRTY_MINOR: u8 = 16;
pub(super) const DIRTY_TOOL: u8 = 32;
pub(super) const DIRTY_TRACKING: u8 = 64;

/// Per-slot (or per-packet) axis values in device units.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub(super) struct SlotValues {
    pub(super) x: i32,
    pub(super) y: i32,
    pub(super) pressure: i32,
    pub(super) major: i32,
    pub(super) minor: i32,
    pub(super) tool: i32,
}

impl SlotValues {
    pub(super) const ZERO: SlotValues = SlotValues {
        x: 0,
        y: 0,
        pressure: 0,
        major: 0,
        minor: 0,
        tool: 0,
    };

    /// Takes the values a resync reports; optional ones it did not query stay.
    pub(super) fn apply(&mut self, s: &MtSlotValues) {
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
pub(super) struct Slot {
    /// Committed kernel tracking id (`-1` = free).
    pub(super) tracking_id: i32,
    /// Our id for the committed contact (valid when `tracking_id >= 0`).
    pub(super) id: ContactId,
    /// Committed values.
    pub(super) vals: SlotValues,
    /// Values staged in the current frame (valid where `dirty` says so).
    pub(super) staged: SlotValues,
    /// Staged tracking id (valid when `dirty & DIRTY_TRACKING`).
    pub(super) staged_tid: i32,
    /// Which staged values were written in the current frame.
    pub(super) dirty: u8,
}

impl Slot {
    pub(super) const FREE: Slot = Slot {
        tracking_id: -1,
        id: ContactId(0),
        vals: SlotValues::ZERO,
        staged: SlotValues::ZERO,
        staged_tid: -1,
        dirty: 0,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::evdev::codes::*;

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
}
