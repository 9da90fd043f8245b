//! The shipped recordings (`config/recordings/`), compiled into the binary so `demo`
//! and the embedded default config work from any directory and on a machine with no
//! touchscreen.

/// The shipped recordings (`config/recordings/`), by file name.
pub const RECORDINGS: [(&str, &str); 7] = [
    (
        "01-point-drag.jsonl",
        include_str!("../../../config/recordings/01-point-drag.jsonl"),
    ),
    (
        "02-line-drag.jsonl",
        include_str!("../../../config/recordings/02-line-drag.jsonl"),
    ),
    (
        "03-line-pinch.jsonl",
        include_str!("../../../config/recordings/03-line-pinch.jsonl"),
    ),
    (
        "04-area-drag.jsonl",
        include_str!("../../../config/recordings/04-area-drag.jsonl"),
    ),
    (
        "05-area-twist.jsonl",
        include_str!("../../../config/recordings/05-area-twist.jsonl"),
    ),
    (
        "06-two-hands.jsonl",
        include_str!("../../../config/recordings/06-two-hands.jsonl"),
    ),
    (
        "07-open-space-swipe.jsonl",
        include_str!("../../../config/recordings/07-open-space-swipe.jsonl"),
    ),
];
