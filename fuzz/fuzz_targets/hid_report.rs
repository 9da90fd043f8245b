#![no_main]
//! Arbitrary input reports through real device layouts. Byte 0 picks the layout;
//! the rest is a sequence of `len: u8, bytes[len]` reports (a report ID byte is
//! forced when byte 1's low bit is set, so most reports reach the decoder).
use crowdtouch::input::hid::{touch_collections, HidDecoder};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{ContactFlags, TouchFrame, MAX_CONTACTS};
use libfuzzer_sys::fuzz_target;
use std::collections::HashSet;

const LAYOUTS: [&[u8]; 6] = [
    include_bytes!("../../tests/fixtures/hid/descriptors/actionstar_2101_1011.rdesc"),
    include_bytes!("../../tests/fixtures/hid/descriptors/3m_0596_0500.rdesc"),
    include_bytes!("../../tests/fixtures/hid/descriptors/egalax_capacitive_0eef_7224.rdesc"),
    include_bytes!("../../tests/fixtures/hid/descriptors/ite_06cb_2968.rdesc"),
    include_bytes!("../../tests/fixtures/hid/descriptors/pqlabs_1ef1_0001.rdesc"),
    include_bytes!("../../tests/fixtures/hid/descriptors/elan_04f3_010c.rdesc"),
];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let Some((&mode, mut rest)) = rest.split_first() else {
        return;
    };
    let c = touch_collections(LAYOUTS[pick as usize % LAYOUTS.len()])
        .expect("fixture layouts parse")
        .remove(0);
    let id = c.reports[0].report_id;
    let mut dec = HidDecoder::new(&c);
    dec.set_max_contacts(u32::from(pick >> 3).max(1));
    let mut f = TouchFrame::default();
    let mut down = HashSet::new();
    let mut check = |f: &TouchFrame| {
        assert!(f.len() <= MAX_CONTACTS);
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
    let mut buf = Vec::with_capacity(256);
    let mut t = 0u64;
    while let Some((&len, tail)) = rest.split_first() {
        let n = (len as usize).min(tail.len());
        buf.clear();
        buf.extend_from_slice(&tail[..n]);
        rest = &tail[n..];
        if let (true, Some(id), Some(b)) = (mode & 1 == 1, id, buf.first_mut()) {
            *b = id;
        }
        t += 1;
        if dec.report(Micros(t), &buf, &mut f) {
            check(&f);
        }
    }
    if dec.cancel_all(Micros(t + 1), &mut f) {
        check(&f);
    }
    assert!(down.is_empty(), "contacts left down after cancel_all");
    assert_eq!(dec.active_contacts(), 0);
});
