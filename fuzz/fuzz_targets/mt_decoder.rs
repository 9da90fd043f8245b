#![no_main]
//! Raw events: 8 bytes each, `type: u16le, code: u16le, value: i32le`; the first
//! byte picks the slot count.
use crowdtouch::input::mt::{MtAxes, MtDecoder};
use crowdtouch::input::{AxisRange, ContactFlags, TouchFrame};
use crowdtouch::time::Micros;
use libfuzzer_sys::fuzz_target;
use std::collections::HashMap;

fuzz_target!(|data: &[u8]| {
    let Some((&slots, rest)) = data.split_first() else {
        return;
    };
    let r = AxisRange {
        min: -50.0,
        max: 1000.0,
        resolution: 10.0,
    };
    let axes = MtAxes {
        x: r,
        y: r,
        slots: slots as usize % 80,
        pressure: Some(r),
        touch_major: Some(r),
        touch_minor: None,
    };
    let mut dec = MtDecoder::new(axes, 1);
    let mut f = TouchFrame::default();
    let mut down: HashMap<u32, ()> = HashMap::new();
    let check = |f: &TouchFrame, down: &mut HashMap<u32, ()>| {
        for c in f.contacts() {
            assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
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
        let ty = u16::from_le_bytes([ev[0], ev[1]]) % 5;
        let code = u16::from_le_bytes([ev[2], ev[3]]) % 0x40;
        let value = i32::from_le_bytes([ev[4], ev[5], ev[6], ev[7]]);
        if dec.event(Micros(i as u64), ty, code, value, &mut f) {
            check(&f, &mut down);
        }
    }
    if dec.cancel_all(Micros(u64::MAX), &mut f) {
        check(&f, &mut down);
    }
    assert!(down.is_empty(), "contacts left down after cancel_all");
});
