#![no_main]
//! ETH/UCY raw files (`frame id x y`) into `read_eth` at the datasets' 25 fps and
//! 10-frame step: a track set or an error naming a line of the input, never a
//! panic; an accepted set passes `validate`, and (frames below 2^44, which
//! survive the trip through seconds exactly) its written form reads back to the
//! same people with the same samples.
use crowdtouch::crowd::edit::io::{read_eth, write_eth, EthOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let opts = EthOptions::default();
    match read_eth(&text, opts) {
        Err(e) => assert!(e.line <= text.lines().count(), "{e}"),
        Ok(set) => {
            set.validate().expect("an accepted set is valid");
            if set.span_s().1 * opts.frame_rate_hz >= 2f64.powi(44) {
                return;
            }
            let again = read_eth(&write_eth(&set, opts), opts).expect("own output reads back");
            assert_eq!(again.tracks.len(), set.tracks.len());
            assert_eq!(again.samples(), set.samples());
        }
    }
});
