//! Single touch: one contact at `ABS_X/ABS_Y` while `BTN_TOUCH` is 1.

use super::decoder::MtDecoder;
use super::packets::Packet;
use super::slots::MtSlotState;
use crate::input::evdev::codes::{
    ABS_MT_SLOT, ABS_MT_TOOL_Y, ABS_PRESSURE, ABS_X, ABS_Y, BTN_TOUCH, EV_ABS, EV_KEY,
};
use crate::vocab::Micros;
use crate::vocab::{ContactFlags, TouchFrame};

impl MtDecoder {
    /// A single-touch event other than `EV_SYN`.
    pub(super) fn event_st(&mut self, ev_type: u16, code: u16, value: i32) {
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
    /// Single-touch part of [`MtDecoder::resync`].
    pub(super) fn resync_st(&mut self, t: Micros, state: &MtSlotState, out: &mut TouchFrame) {
        if let Some(s) = state.slots().first() {
            let p = &mut self.packets;
            p.pkt.vals.apply(s);
            p.st_vals = p.pkt.vals;
            p.touch_staged = s.tracking_id >= 0;
        }
        self.stage_single_touch();
        self.commit_packets(t, out, ContactFlags::CANCELLED);
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
    pub(super) fn commit_st(&mut self, t: Micros, out: &mut TouchFrame) {
        self.stage_single_touch();
        self.commit_packets(t, out, ContactFlags::UP);
    }
}

#[cfg(test)]
mod tests {
    use super::super::axes::MtProtocol;
    use super::super::decoder::tests::{axes, feed, state, xs, SYN};
    use super::*;
    use crate::input::evdev::codes::*;
    use crate::input::AxisRange;

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
}
