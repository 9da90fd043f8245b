//! Protocol B: slot events, committing a frame, and resynchronising the slot table.

use super::decoder::MtDecoder;
use super::slots::{
    MtSlotState, DIRTY_MAJOR, DIRTY_MINOR, DIRTY_PRESSURE, DIRTY_TOOL, DIRTY_TRACKING, DIRTY_X,
    DIRTY_Y,
};
use crate::input::evdev::codes::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE, ABS_MT_SLOT, ABS_MT_TOOL_TYPE,
    ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, ABS_MT_TRACKING_ID, EV_ABS,
};
use crate::vocab::Micros;
use crate::vocab::{ContactFlags, ContactId, TouchFrame};

impl MtDecoder {
    /// A type-B event other than `EV_SYN`.
    pub(super) fn event_b(&mut self, ev_type: u16, code: u16, value: i32) {
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

    /// Type-B part of [`MtDecoder::resync`].
    pub(super) fn resync_b(&mut self, t: Micros, state: &MtSlotState, out: &mut TouchFrame) {
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
    pub(super) fn commit(&mut self, t: Micros, out: &mut TouchFrame) {
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
}

#[cfg(test)]
mod tests {
    use super::super::decoder::tests::{axes, feed, ids_flags, state, xs, EPS, SYN};
    use super::*;
    use crate::input::evdev::codes::*;

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
}
