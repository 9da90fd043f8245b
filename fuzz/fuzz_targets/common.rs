// Shared checks for the recording targets.
use crowdtouch::input::recording::{OnBadFrame, Recording, RecordingError};

pub fn check(result: Result<Recording, RecordingError>) {
    if let Ok(rec) = result {
        for f in &rec.frames {
            assert!(f.len() <= crowdtouch::vocab::MAX_CONTACTS);
            for c in f.contacts() {
                assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
            }
        }
        assert!(rec.frames.windows(2).all(|w| w[0].t <= w[1].t));
    }
}

pub const MODES: [OnBadFrame; 2] = [OnBadFrame::Stop, OnBadFrame::Skip];
