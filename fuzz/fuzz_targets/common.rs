// Shared checks for the recording targets: the whole-recording readers, and the
// stream they are built on, read through, rewound and read again.
use crowdtouch::input::recording::{
    OnBadFrame, Recording, RecordingError, RecordingStream, MAX_TIME_JUMP_US,
};
use crowdtouch::vocab::TouchFrame;
use std::path::Path;

pub fn check(result: Result<Recording, RecordingError>) {
    if let Ok(rec) = result {
        for f in &rec.frames {
            check_frame(f);
        }
        assert!(rec.frames.windows(2).all(|w| w[0].t <= w[1].t));
    }
}

fn check_frame(f: &TouchFrame) {
    assert!(f.len() <= crowdtouch::vocab::MAX_CONTACTS);
    for c in f.contacts() {
        assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
    }
}

/// Reads a stream to its end, checking every frame as it comes: the frames and
/// how the reading ended.
fn read_through(s: &mut RecordingStream) -> (Vec<TouchFrame>, Option<String>) {
    let mut frames: Vec<TouchFrame> = Vec::new();
    loop {
        match s.next_frame() {
            Ok(Some(f)) => {
                check_frame(f);
                if let Some(prev) = frames.last() {
                    assert!(prev.t <= f.t && f.t.0 - prev.t.0 <= MAX_TIME_JUMP_US);
                }
                frames.push(*f);
            }
            Ok(None) => return (frames, None),
            Err(e) => return (frames, Some(e.to_string())),
        }
    }
}

/// `open` as a stream: the same frames and end as the whole reading `whole`
/// (when given), and again after going back to the start.
pub fn check_stream(
    open: impl Fn() -> Result<RecordingStream, RecordingError>,
    whole: Option<&Result<Recording, RecordingError>>,
) {
    let Ok(mut s) = open() else {
        if let Some(w) = whole {
            assert!(
                w.is_err(),
                "the stream failed to open, the whole reading did not"
            );
        }
        return;
    };
    let (frames, end) = read_through(&mut s);
    if let Some(w) = whole {
        match w {
            Ok(rec) => assert!(end.is_none() && rec.frames == frames),
            Err(e) => assert_eq!(end.as_deref(), Some(e.to_string().as_str())),
        }
    }
    if s.rewind().is_ok() {
        assert_eq!(read_through(&mut s), (frames, end));
    }
}

/// Every check of both readings of `text` named `name`, in both modes.
pub fn check_all(text: &str, name: &str) {
    for mode in MODES {
        let whole = crowdtouch::input::recording::parse_recording(text, Path::new(name), mode);
        check_stream(
            || RecordingStream::from_bytes(text.as_bytes().to_vec(), Path::new(name), mode),
            Some(&whole),
        );
        check(whole);
    }
}

pub const MODES: [OnBadFrame; 2] = [OnBadFrame::Stop, OnBadFrame::Skip];
