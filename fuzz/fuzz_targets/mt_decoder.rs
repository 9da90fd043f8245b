#![no_main]
//! Raw events: 8 bytes each, `type: u16le, code: u16le, value: i32le`; the first
//! byte picks the protocol (`% 3`: B, A, single touch) and the slot count
//! (`/ 3 % 80`). A chunk whose type is `0xffff` is a resync instead: `code % 9`
//! slots, each with tracking id `(value >> 4i) & 0xf) - 1` and a position
//! derived from `code` and `value`.
use crowdtouch::input::evdev::{MtAxes, MtDecoder, MtProtocol, MtSlotState};
use crowdtouch::input::AxisRange;
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{ContactFlags, TouchFrame, MAX_CONTACTS};
use libfuzzer_sys::fuzz_target;
use std::collections::HashMap;

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let r = AxisRange {
        min: -50.0,
        max: 1000.0,
        resolution: if first & 0x80 != 0 { 10.0 } else { 0.0 },
    };
    let protocol = [MtProtocol::B, MtProtocol::A, MtProtocol::SingleTouch][usize::from(first % 3)];
    let axes = MtAxes {
        x: r,
        y: r,
        slots: usize::from(first / 3) % 80,
        pressure: Some(r),
        touch_major: Some(r),
        touch_minor: None,
    };
    let mut dec = MtDecoder::with_protocol(axes, protocol, 1);
    let mut f = TouchFrame::default();
    let mut down: HashMap<u32, ()> = HashMap::new();
    let mut overflow = false;
    let check = |f: &TouchFrame, down: &mut HashMap<u32, ()>, overflow: bool| {
        assert!(f.len() <= MAX_CONTACTS);
        for c in f.contacts() {
            assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
            if overflow {
                continue;
            }
            if c.flags.contains(ContactFlags::DOWN) {
                assert!(down.insert(c.id.0, ()).is_none(), "DOWN twice");
            } else {
                assert!(down.contains_key(&c.id.0), "contact without DOWN");
            }
            if c.flags.ended() {
                down.remove(&c.id.0);
            }
        }
    };
    for (i, ev) in rest.chunks_exact(8).enumerate() {
        let ty = u16::from_le_bytes([ev[0], ev[1]]);
        let code = u16::from_le_bytes([ev[2], ev[3]]);
        let value = i32::from_le_bytes([ev[4], ev[5], ev[6], ev[7]]);
        let t = Micros(i as u64);
        let produced = if ty == 0xffff {
            let mut st = MtSlotState::new(usize::from(code % 9));
            for (k, s) in st.slots_mut().iter_mut().enumerate() {
                s.tracking_id = ((value >> (4 * k)) & 0xf) - 1;
                s.x = i32::from(code) ^ (k as i32 * 97);
                s.y = value.wrapping_mul(k as i32 + 1);
            }
            st.selected = Some(i32::from(code >> 8) - 2);
            dec.resync(t, &st, &mut f)
        } else {
            dec.event(t, ty % 5, code % 0x150, value, &mut f)
        };
        overflow |= dec.counters().frame_overflow > 0;
        if produced {
            check(&f, &mut down, overflow);
        }
    }
    if dec.cancel_all(Micros(u64::MAX), &mut f) {
        overflow |= dec.counters().frame_overflow > 0;
        check(&f, &mut down, overflow);
    }
    assert_eq!(dec.active_contacts(), 0);
    assert!(
        overflow || down.is_empty(),
        "contacts left down after cancel_all"
    );
});
