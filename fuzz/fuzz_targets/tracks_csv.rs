#![no_main]
//! CSV track files (`t,id,x,y`) into `read_csv`, with the frame step taken as the
//! median and, when the first byte is odd, given as 0.4 s: a track set or an error
//! naming a line of the input, never a panic; an accepted set passes `validate` and
//! its written form, read at the set's step, gives back the same people and links.
use crowdtouch::crowd::edit::io::{read_csv, write_csv};
use crowdtouch::crowd::edit::TrackSet;
use libfuzzer_sys::fuzz_target;

fn by_id(mut set: TrackSet) -> TrackSet {
    set.tracks.sort_by_key(|t| t.id);
    set
}

fuzz_target!(|data: &[u8]| {
    let step = match data.first() {
        Some(b) if b % 2 == 1 => Some(0.4),
        _ => None,
    };
    let text = String::from_utf8_lossy(data.get(1..).unwrap_or_default());
    match read_csv(&text, step) {
        Err(e) => assert!(e.line <= text.lines().count(), "{e}"),
        Ok(set) => {
            set.validate().expect("an accepted set is valid");
            let again = read_csv(&write_csv(&set), Some(set.step_s)).expect("own output reads back");
            assert_eq!(by_id(again), by_id(set));
        }
    }
});
