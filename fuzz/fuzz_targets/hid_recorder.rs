#![no_main]
//! hid-recorder text through `parse_recording` and the stream it is built on (an
//! `R:` line with the ActionStar descriptor is prepended when the input has
//! none), and `parse_hid_recorder`.
use crowdtouch::input::recording::parse_hid_recorder;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "common.rs"]
mod common;

const R_LINE: &str = "R: 177 05 0d 09 04 a1 01 85 01 09 22 a1 02 09 42 15 00 25 01 75 01 95 01 81 02 09 32 81 02 09 47 81 02 95 05 81 03 09 51 75 08 95 01 81 02 05 01 35 00 55 0e 65 33 75 10 95 01 09 30 26 ff 4d 46 70 03 81 02 09 31 26 ff 2b 46 f1 01 81 02 46 00 00 c0 a1 02 05 0d 09 42 15 00 25 01 75 01 95 01 81 02 09 32 81 02 09 47 81 02 95 05 81 03 09 51 75 08 95 01 81 02 05 01 35 00 55 0e 65 33 75 10 95 01 09 30 26 ff 4d 46 70 03 81 02 09 31 26 ff 2b 46 f1 01 81 02 46 00 00 c0 05 0d 09 54 75 08 95 01 81 02 05 0d 85 02 09 55 25 02 75 08 95 01 b1 02 c0\n";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let text = if text.contains("R:") {
        text.into_owned()
    } else {
        format!("{R_LINE}{text}")
    };
    common::check_all(&text, "fuzz.hid");
    for mode in common::MODES {
        let _ = parse_hid_recorder(&text, Path::new("fuzz.hid"), mode);
    }
});
