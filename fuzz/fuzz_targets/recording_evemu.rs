#![no_main]
use crowdtouch::input::recording::{read_evemu_with_desc, RecordingStream};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "common.rs"]
mod common;

const DESC: &str = "N: fuzz\nA: 2f 0 9 0 0 0\nA: 30 0 255 0 0 0\nA: 35 0 799 0 0 0\nA: 36 0 479 0 0 0\nA: 39 0 65535 0 0 0\nA: 3a 0 255 0 0 0\n";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let text: &str = &text;
    common::check_all(text, "fuzz.evemu");
    let (desc, events) = text.split_once('\0').unwrap_or((DESC, text));
    for mode in common::MODES {
        let name = Path::new("fuzz.events");
        let whole = read_evemu_with_desc(desc, events, name, mode);
        common::check_stream(
            || RecordingStream::evemu_with_desc(desc, events.as_bytes().to_vec(), name, mode),
            Some(&whole),
        );
        common::check(whole);
    }
});
