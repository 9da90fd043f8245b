#![no_main]
//! Arbitrary report descriptors: `touch_collections` and `describe` never panic
//! nor allocate without bound; every layout found decodes arbitrary reports (taken
//! from the same bytes) with the frame invariants intact.
use crowdtouch::input::hid::{describe, touch_collections, HidDecoder};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{ContactFlags, TouchFrame};
use libfuzzer_sys::fuzz_target;
use std::collections::HashSet;

fuzz_target!(|data: &[u8]| {
    let _ = describe(data);
    let Ok(collections) = touch_collections(data) else {
        return;
    };
    for c in &collections {
        assert!(!c.reports.is_empty() && c.first_finger().is_some());
        let mut dec = HidDecoder::new(c);
        let len = dec.max_report_bytes().clamp(1, 256);
        let mut f = TouchFrame::default();
        let mut down = HashSet::new();
        let mut check = |f: &TouchFrame| {
            for c in f.contacts() {
                assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
                if c.flags.contains(ContactFlags::DOWN) {
                    assert!(down.insert(c.id.0), "DOWN twice");
                } else {
                    assert!(down.contains(&c.id.0), "contact without DOWN");
                }
                if c.flags.ended() {
                    down.remove(&c.id.0);
                }
            }
        };
        for (i, chunk) in data.chunks(len).enumerate() {
            if dec.report(Micros(i as u64), chunk, &mut f) {
                check(&f);
            }
        }
        if dec.cancel_all(Micros(u64::MAX), &mut f) {
            check(&f);
        }
        assert!(down.is_empty(), "contacts left down after cancel_all");
    }
});
