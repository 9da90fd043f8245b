#![no_main]
use crowdtouch::input::recording::{parse_recording, read_evemu_with_desc};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "common.rs"]
mod common;

const DESC: &str = "N: fuzz\nA: 2f 0 9 0 0 0\nA: 30 0 255 0 0 0\nA: 35 0 799 0 0 0\nA: 36 0 479 0 0 0\nA: 39 0 65535 0 0 0\nA: 3a 0 255 0 0 0\n";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    for mode in common::MODES {
        common::check(parse_recording(&text, Path::new("fuzz.evemu"), mode));
        match text.split_once('\0') {
            Some((desc, events)) => common::check(read_evemu_with_desc(
                desc,
                events,
                Path::new("fuzz.events"),
                mode,
            )),
            None => common::check(read_evemu_with_desc(
                DESC,
                &text,
                Path::new("fuzz.events"),
                mode,
            )),
        }
    }
});
