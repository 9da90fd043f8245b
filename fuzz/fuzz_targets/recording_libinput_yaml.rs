#![no_main]
use crowdtouch::input::recording::parse_recording;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let text = if text.contains("devices:") {
        text.into_owned()
    } else {
        format!("version: 1\ndevices:\n{text}")
    };
    for mode in common::MODES {
        common::check(parse_recording(&text, Path::new("fuzz.yml"), mode));
    }
});
