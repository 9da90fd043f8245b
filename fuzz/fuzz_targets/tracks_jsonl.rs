#![no_main]
//! JSON Lines track files (a header is prepended when the input has none) into
//! `read_jsonl`: a track set or an error naming a line of the input, never a panic;
//! an accepted set passes `validate` and its written form reads back to the same
//! people.
use crowdtouch::crowd::edit::io::{read_jsonl, write_jsonl, JSONL_FORMAT};
use crowdtouch::crowd::edit::TrackSet;
use libfuzzer_sys::fuzz_target;

const HEADER: &str = r#"{"format":"crowdtouch-tracks","version":1,"step_s":0.4}"#;

fn by_id(mut set: TrackSet) -> TrackSet {
    set.tracks.sort_by_key(|t| t.id);
    set
}

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let text = if text.contains(JSONL_FORMAT) {
        text.into_owned()
    } else {
        format!("{HEADER}\n{text}")
    };
    match read_jsonl(&text) {
        Err(e) => assert!(e.line <= text.lines().count(), "{e}"),
        Ok(set) => {
            set.validate().expect("an accepted set is valid");
            let again = read_jsonl(&write_jsonl(&set, Some("fuzz"))).expect("own output reads back");
            assert_eq!(by_id(again), by_id(set));
        }
    }
});
