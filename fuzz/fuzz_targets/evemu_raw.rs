#![no_main]
//! `read_evemu_raw` on arbitrary text; what it accepts must survive
//! `EvemuWriter` and read back to the same capabilities and events.
use crowdtouch::input::evdev::AbsAxisInfo;
use crowdtouch::input::recording::read_evemu_raw;
use crowdtouch::input::recording::{EvemuTime, EvemuWriter};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok((caps, events)) = read_evemu_raw(&text, Path::new("fuzz.evemu")) else {
        return;
    };
    let mut w = EvemuWriter::with_time(&caps, Vec::new(), EvemuTime::Absolute).unwrap();
    for e in &events {
        w.event(e).unwrap();
    }
    let written = String::from_utf8(w.into_inner()).unwrap();
    let (caps2, events2) = read_evemu_raw(&written, Path::new("w")).expect("own output reads back");
    // The name is written on one line, trimmed (control characters become spaces).
    assert_eq!(
        (caps2.bus, caps2.vendor, caps2.product, caps2.version),
        (caps.bus, caps.vendor, caps.product, caps.version)
    );
    assert_eq!(caps2.property_bytes(), caps.property_bytes());
    for ty in 0..0x20 {
        assert_eq!(caps2.mask(ty), caps.mask(ty), "type {ty}");
    }
    for code in 0..0x40 {
        // An axis declared only in the `B: 03` bitmask is written with a zero absinfo.
        let want = caps
            .abs(code)
            .or_else(|| caps.has_code(3, code).then(AbsAxisInfo::default));
        assert_eq!(caps2.abs(code), want, "axis {code}");
    }
    assert_eq!(events2, events);
});
