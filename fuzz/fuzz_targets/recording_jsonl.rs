#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

const HEADER: &str = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"f","x":{"min":0,"max":1000,"resolution":4},"y":{"min":0,"max":1000},"max_contacts":10}}"#;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let text = if text.contains("crowdtouch-touch") {
        text.into_owned()
    } else {
        format!("{HEADER}\n{text}")
    };
    common::check_all(&text, "fuzz.jsonl");
});
