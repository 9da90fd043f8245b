#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let text = if text.contains("devices:") {
        text.into_owned()
    } else {
        format!("version: 1\ndevices:\n{text}")
    };
    common::check_all(&text, "fuzz.yml");
});
