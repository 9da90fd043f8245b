//! Protocol A: contact packets, and matching them to the previous frame's contacts
//! (by tracking id, else by a minimum-cost assignment of squared distances).

use super::assign::{assign_min_cost, ASSIGN_MAX};
use super::decoder::MtDecoder;
use super::packets::{Packet, Tracked};
use super::slots::{MtSlotState, SlotValues};
use crate::input::evdev::codes::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE, ABS_MT_SLOT, ABS_MT_TOOL_TYPE,
    ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, ABS_MT_TRACKING_ID, BTN_TOUCH, EV_ABS, EV_KEY,
};
use crate::vocab::Micros;
use crate::vocab::{ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};

/// Cost of a forbidden pair in [`MtDecoder`]'s type-A matching, as a multiple
/// of the squared maximum jump (anything above 1 keeps such pairs unmatched).
const FORBIDDEN_COST_FACTOR: f64 = 4.0;

impl MtDecoder {
    /// A type-A event other than `EV_SYN`.
    pub(super) fn event_a(&mut self, ev_type: u16, code: u16, value: i32) {
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

    /// Type-A part of [`MtDecoder::resync`].
    pub(super) fn resync_a(&mut self, t: Micros, state: &MtSlotState, out: &mut TouchFrame) {
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

    /// Closes a type-A frame.
    pub(super) fn commit_a(&mut self, t: Micros, out: &mut TouchFrame) {
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

    /// Matches the current packets to the previous frame's contacts and fills
    /// `out`: ended (with `end`), begun, then continuing. The packets become
    /// the previous frame's contacts.
    pub(super) fn commit_packets(&mut self, t: Micros, out: &mut TouchFrame, end: ContactFlags) {
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
    use super::super::axes::{MtAxes, MtProtocol};
    use super::super::decoder::tests::{axes, feed, ids_flags, xs, SYN};
    use super::*;
    use crate::input::evdev::codes::*;

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
}
