use super::*;
use crate::gesture::segment::{Segment, SegmentParams, TouchPoint, MAX_FINGERS};
use crate::vocab::ContactId;

const MS: u64 = 1000;
const D: ContactFlags = ContactFlags::DOWN;
const M: ContactFlags = ContactFlags::NONE;
const U: ContactFlags = ContactFlags::UP;

/// A segmenter and a capture fed the same touches, as the engine does.
struct Table {
    seg: Segmenter,
    cap: GestureCapture,
    out: Vec<Segment>,
}

impl Table {
    fn new(params: CaptureParams) -> Table {
        Table {
            seg: Segmenter::new(SegmentParams {
                group_window: Micros(150 * MS),
                hand_span_mm: 200.0,
                gesture_span_mm: 200.0,
                gesture_grace: Micros(250 * MS),
            }),
            cap: GestureCapture::new(params, TapThresholds::default()),
            out: Vec::new(),
        }
    }

    /// One touch at `t_us`; `on_crowd` as the engine would say.
    fn touch_us(&mut self, t_us: u64, id: u32, x: f64, y: f64, flags: ContactFlags, on: bool) {
        let now = Micros(t_us);
        self.seg.tick(now, &mut self.out);
        let p = TouchPoint {
            id: ContactId(id),
            world: Vec2::new(x, y) / 100.0,
            glass_mm: Vec2::new(x, y),
            flags,
        };
        self.seg.touch(now, &p, on, &mut self.out);
        self.cap.observe(now, &self.seg, &p);
    }

    fn touch(&mut self, t_ms: u64, id: u32, x: f64, y: f64, flags: ContactFlags) {
        self.touch_us(t_ms * MS, id, x, y, flags, false);
    }

    fn tick(&mut self, t_ms: u64) {
        self.seg.tick(Micros(t_ms * MS), &mut self.out);
    }

    fn ended(&self) -> Vec<u32> {
        self.out
            .iter()
            .filter_map(|s| match s {
                Segment::GestureEnd { id, .. } => Some(*id),
                _ => None,
            })
            .collect()
    }
}

fn times(t: &TouchTrack) -> Vec<u64> {
    t.samples.iter().map(|s| s.t.0).collect()
}

#[test]
fn a_short_track_keeps_every_sample() {
    let mut tr = Track::new(15);
    tr.reset();
    for i in 0..10u64 {
        tr.push(TrackSample {
            t: Micros(i),
            mm: Vec2::new(i as f64, 0.0),
        });
    }
    let mut out = TouchTrack::default();
    tr.copy_into(&mut out);
    assert_eq!(times(&out), (0..10).collect::<Vec<_>>());
    assert_eq!(tr.stride, 1);
}

#[test]
fn decimation_keeps_the_first_the_last_and_evenly_spaced_samples() {
    for cap in [3usize, 4, 15, 16, 255] {
        for n in [cap as u64 + 1, 2 * cap as u64, 1000, 4097] {
            let mut tr = Track::new(cap);
            tr.reset();
            for i in 0..n {
                tr.push(TrackSample {
                    t: Micros(i),
                    mm: Vec2::new(0.0, i as f64),
                });
            }
            let s = tr.stride;
            assert!(s.is_power_of_two());
            // Exactly every s-th incoming sample is stored, from the first on.
            let stored: Vec<u64> = tr.stored.iter().map(|x| x.t.0).collect();
            let expect: Vec<u64> = (0..n).step_by(s as usize).collect();
            assert_eq!(stored, expect, "cap {cap}, n {n}");
            assert!(stored.len() <= cap);
            // The stride is the smallest that fits: half of it would not.
            assert!((n - 1) / (s / 2).max(1) + 1 > cap as u64 || s == 1);
            let mut out = TouchTrack::default();
            tr.copy_into(&mut out);
            let t = times(&out);
            assert_eq!(t[0], 0);
            assert_eq!(*t.last().unwrap(), n - 1, "latest kept, cap {cap}, n {n}");
            assert!(t.len() <= cap + 1);
            assert!(t.windows(2).all(|w| w[0] < w[1]));
        }
    }
}

#[test]
fn ten_minutes_of_ten_fingers_never_grow_a_buffer() {
    let mut table = Table::new(CaptureParams::default());
    let mut buf = table.cap.tracks_buffer();
    let caps = |c: &GestureCapture| -> Vec<(usize, *const TrackSample)> {
        c.slots
            .iter()
            .flat_map(|s| s.tracks.iter())
            .map(|t| (t.stored.capacity(), t.stored.as_ptr()))
            .collect()
    };
    let before = caps(&table.cap);
    let buf_before: Vec<_> = buf
        .fingers
        .iter()
        .map(|f| (f.samples.capacity(), f.samples.as_ptr()))
        .collect();
    let period_us = 8_333; // 120 Hz
    let frames = 600 * 120u64;
    for f in 0..frames {
        let t = f * period_us;
        for k in 0..MAX_FINGERS as u32 {
            let a = f as f64 * 0.01 + k as f64;
            let (x, y) = (300.0 + 50.0 * a.cos(), 300.0 + 50.0 * a.sin());
            let flags = match f {
                0 => D,
                _ if f == frames - 1 => U,
                _ => M,
            };
            table.touch_us(t, k + 1, x, y, flags, false);
        }
    }
    table.tick(frames * period_us / MS + 300);
    assert_eq!(table.ended(), vec![1]);
    assert_eq!(caps(&table.cap), before, "no capture buffer grew or moved");
    let r = table.cap.finish(1, &mut buf);
    assert!(
        matches!(r, Err(Rejected::TooLong { duration_us }) if duration_us == (frames - 1) * period_us),
        "{r:?}"
    );
    let buf_after: Vec<_> = buf
        .fingers
        .iter()
        .map(|f| (f.samples.capacity(), f.samples.as_ptr()))
        .collect();
    assert_eq!(buf_after[..MAX_FINGERS], buf_before[..MAX_FINGERS]);
    assert_eq!(buf.fingers.len(), MAX_FINGERS);
    for f in &buf.fingers {
        assert!(f.samples.len() <= DEFAULT_SAMPLES_PER_TRACK);
        assert!(f.samples.len() > DEFAULT_SAMPLES_PER_TRACK / 2);
        assert_eq!(f.samples[0].t, Micros(0));
        assert_eq!(
            f.samples.last().unwrap().t,
            Micros((frames - 1) * period_us)
        );
    }
    assert!(!table.cap.is_capturing(1), "finish frees the slot");
}

#[test]
fn a_long_gesture_within_the_limit_is_accepted_decimated() {
    let mut table = Table::new(CaptureParams::default());
    table.cap.set_thresholds(TapThresholds {
        max_duration: Micros(700_000_000),
        ..TapThresholds::default()
    });
    for f in 0..20_000u64 {
        let flags = if f == 0 { D } else { M };
        table.touch(f * 10, 1, 100.0 + f as f64 * 0.01, 100.0, flags);
    }
    table.touch(200_000, 1, 300.0, 100.0, U);
    table.tick(200_300);
    let mut buf = table.cap.tracks_buffer();
    let c = table.cap.finish(1, &mut buf).expect("accepted");
    assert_eq!(c.tracks, 1);
    assert_eq!(c.duration, Micros(200_000 * MS));
    assert!(c.stride >= 64, "stride {}", c.stride);
    assert!((c.travel_mm - 200.0).abs() < 1e-9);
    assert_eq!(
        buf.fingers[0].samples.last().unwrap().mm,
        Vec2::new(300.0, 100.0)
    );
}

#[test]
fn a_bounce_within_the_grace_is_one_gesture_with_a_track_per_landing() {
    let mut table = Table::new(CaptureParams::default());
    for i in 0..10u64 {
        let flags = if i == 0 { D } else { M };
        table.touch(i * 10, 1, 100.0 + 5.0 * i as f64, 100.0, flags);
    }
    table.touch(100, 1, 150.0, 100.0, U);
    // Lands again 120 ms later (grace 250 ms, past the re-attach window), a few mm on.
    for i in 0..10u64 {
        let flags = if i == 0 { D } else { M };
        table.touch(220 + i * 10, 2, 155.0 + 5.0 * i as f64, 100.0, flags);
    }
    table.touch(320, 2, 205.0, 100.0, U);
    table.tick(400);
    assert!(table.ended().is_empty(), "grace not over");
    table.tick(580);
    assert_eq!(table.ended(), vec![1]);
    let mut buf = GestureTracks::default();
    let c = table.cap.finish(1, &mut buf).expect("a gesture");
    assert_eq!(c.tracks, 2);
    assert_eq!(c.duration, Micros(320 * MS));
    assert_eq!(buf.fingers[0].samples.len(), 11);
    assert_eq!(buf.fingers[1].samples.len(), 11);
    assert_eq!(buf.fingers[1].samples[0].t, Micros(220 * MS));
}

#[test]
fn a_finger_lost_for_a_few_frames_goes_on_as_one_track() {
    let mut table = Table::new(CaptureParams::default());
    for i in 0..10u64 {
        let flags = if i == 0 { D } else { M };
        table.touch(i * 10, 1, 100.0 + 5.0 * i as f64, 100.0, flags);
    }
    table.touch(100, 1, 150.0, 100.0, U);
    // Back 60 ms later as a new contact, 12 mm on (the hand kept moving).
    for i in 0..10u64 {
        let flags = if i == 0 { D } else { M };
        table.touch(160 + i * 10, 2, 162.0 + 5.0 * i as f64, 100.0, flags);
    }
    table.touch(260, 2, 212.0, 100.0, U);
    table.tick(600);
    assert_eq!(table.ended(), vec![1]);
    let mut buf = GestureTracks::default();
    let c = table.cap.finish(1, &mut buf).expect("a gesture");
    assert_eq!(c.tracks, 1, "one finger: {buf:?}");
    let t = &buf.fingers[0];
    assert_eq!(t.samples.len(), 22);
    assert_eq!(t.samples[10].t, Micros(100 * MS));
    assert_eq!(t.samples[11].t, Micros(160 * MS));
    assert_eq!(t.samples[11].mm, Vec2::new(162.0, 100.0));
    assert!((c.travel_mm - 112.0).abs() < 1e-9, "{c:?}");
}

#[test]
fn ten_fingers_whose_ids_change_mid_run_are_ten_tracks() {
    let mut table = Table::new(CaptureParams::default());
    // Ten fingers move right for 1 s at 100 Hz; every 100 ms three of them get a new
    // tracking id (the old contact ends, the new begins, in the same frame).
    let mut ids: Vec<u32> = (1..=10).collect();
    let mut next = 11;
    for f in 0..=100u64 {
        let t = f * 10;
        for (k, id) in ids.iter_mut().enumerate() {
            let (x, y) = (100.0 + 30.0 * k as f64 + f as f64, 200.0 + 5.0 * k as f64);
            if f > 0 && f < 100 && f % 10 == 0 && k % 3 == (f / 10) as usize % 3 {
                table.touch(t, *id, x, y, U);
                *id = next;
                next += 1;
                table.touch(t, *id, x, y, D);
                continue;
            }
            let flags = match f {
                0 => D,
                100 => U,
                _ => M,
            };
            table.touch(t, *id, x, y, flags);
        }
    }
    assert!(next > 30, "more ids than a gesture has records: {next}");
    table.tick(1500);
    assert_eq!(table.ended(), vec![1], "one gesture");
    assert!(
        matches!(
            table.out.last(),
            Some(Segment::GestureEnd {
                fingers: 10,
                contacts: 10,
                ..
            })
        ),
        "{:?}",
        table.out.last()
    );
    let mut buf = table.cap.tracks_buffer();
    let c = table.cap.finish(1, &mut buf).expect("a gesture");
    assert_eq!(c.tracks, 10);
    for (k, tr) in buf.fingers.iter().enumerate() {
        assert_eq!(tr.samples.len(), 101, "finger {k}: every frame once");
        assert_eq!(tr.samples[0].mm.x, 100.0 + 30.0 * k as f64);
        assert_eq!(tr.samples[100].mm.x, 200.0 + 30.0 * k as f64);
    }
}

#[test]
fn a_ghost_contact_is_not_a_finger() {
    let mut table = Table::new(CaptureParams::default());
    // Two fingers drag; an infrared frame reports a third contact for two frames
    // between them.
    for f in 0..=50u64 {
        let t = f * 10;
        let flags = match f {
            0 => D,
            50 => U,
            _ => M,
        };
        table.touch(t, 1, 100.0 + 2.0 * f as f64, 100.0, flags);
        table.touch(t, 2, 100.0 + 2.0 * f as f64, 160.0, flags);
        if f == 20 {
            table.touch(t, 3, 140.0, 130.0, D);
        } else if f == 22 {
            table.touch(t, 3, 140.0, 130.0, U);
        }
    }
    table.tick(900);
    assert!(
        matches!(
            table.out.last(),
            Some(Segment::GestureEnd {
                fingers: 2,
                contacts: 3,
                ..
            })
        ),
        "{:?}",
        table.out.last()
    );
    let mut buf = table.cap.tracks_buffer();
    let c = table.cap.finish(1, &mut buf).expect("a gesture");
    assert_eq!(c.tracks, 2);
    assert!(buf.fingers.iter().all(|f| f.samples.len() == 51));
}

#[test]
fn taps_are_rejected() {
    // Short.
    let mut table = Table::new(CaptureParams::default());
    table.touch(0, 1, 100.0, 100.0, D);
    table.touch(80, 1, 160.0, 100.0, U);
    table.tick(400);
    let mut buf = GestureTracks::default();
    let r = table.cap.finish(1, &mut buf);
    assert!(
        matches!(
            r,
            Err(Rejected::Tap {
                duration_us: 80_000,
                ..
            })
        ),
        "{r:?}"
    );
    assert_eq!(r.unwrap_err().as_str(), "tap");
    assert_eq!(buf.fingers.len(), 1, "the tracks are still handed out");
    // Long but still: a press with a little jitter.
    let mut table = Table::new(CaptureParams::default());
    for i in 0..100u64 {
        let flags = if i == 0 { D } else { M };
        let j = if i % 2 == 0 { 0.5 } else { -0.5 };
        table.touch(i * 10, 1, 100.0 + j, 100.0, flags);
    }
    table.touch(1000, 1, 100.0, 100.0, U);
    table.tick(1300);
    let r = table.cap.finish(1, &mut buf);
    match r {
        Err(Rejected::Tap { travel_mm, .. }) => assert!(travel_mm < 1.01),
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_eleventh_finger_is_captured_in_a_gesture_of_its_own() {
    let mut table = Table::new(CaptureParams::default());
    for i in 0..11u32 {
        table.touch(i as u64, i + 1, 100.0 + 10.0 * i as f64, 100.0, D);
    }
    for step in 1..30u64 {
        for i in 0..11u32 {
            let flags = if step == 29 { U } else { M };
            let x = 100.0 + 10.0 * i as f64;
            table.touch(20 + step * 10, i + 1, x, 100.0 + 2.0 * step as f64, flags);
        }
    }
    table.tick(700);
    assert_eq!(table.ended(), vec![1, 2]);
    let mut buf = GestureTracks::default();
    let a = table.cap.finish(1, &mut buf).expect("ten fingers");
    assert_eq!(a.tracks, MAX_FINGERS);
    let b = table.cap.finish(2, &mut buf).expect("the eleventh");
    assert_eq!(b.tracks, 1);
    assert_eq!(buf.fingers[0].samples[0].mm, Vec2::new(200.0, 100.0));
}

#[test]
fn more_gestures_than_slots_are_counted_not_captured() {
    let mut table = Table::new(CaptureParams {
        max_gestures: 2,
        samples_per_track: 16,
    });
    for g in 0..3u32 {
        table.touch(0, g + 1, 100.0 + 500.0 * g as f64, 100.0, D);
    }
    assert_eq!(table.seg.gestures().len(), 3);
    assert_eq!(table.cap.overflowed, 1);
    let mut buf = GestureTracks::default();
    assert_eq!(table.cap.finish(3, &mut buf), Err(Rejected::NotCaptured));
    assert!(buf.fingers.is_empty());
    assert!(table.cap.is_capturing(1) && table.cap.is_capturing(2));
}

#[test]
fn a_slot_left_by_a_gesture_the_segmenter_dropped_is_reused() {
    let mut table = Table::new(CaptureParams {
        max_gestures: 1,
        samples_per_track: 16,
    });
    table.touch(0, 1, 100.0, 100.0, D);
    table.touch(100, 1, 150.0, 100.0, U);
    table.tick(500); // gesture 1 ended; the engine never called finish
    table.touch(600, 2, 100.0, 100.0, D);
    table.touch(700, 2, 100.0, 160.0, M);
    assert_eq!(table.cap.overflowed, 0);
    assert!(table.cap.is_capturing(2) && !table.cap.is_capturing(1));
    let mut buf = GestureTracks::default();
    assert!(table.cap.snapshot(2, &mut buf));
    assert_eq!(buf.fingers.len(), 1);
    assert_eq!(times(&buf.fingers[0]), vec![600 * MS, 700 * MS]);
}

#[test]
fn touches_of_controls_are_not_captured_even_with_a_reused_contact_id() {
    let mut table = Table::new(CaptureParams::default());
    table.touch(0, 1, 100.0, 100.0, D);
    table.touch(100, 1, 150.0, 100.0, U);
    // Contact id 1 is reused at once for a touch on the crowd, within the gesture's
    // grace: it is a control, and its samples stay out of the gesture.
    table.touch_us(150 * MS, 1, 120.0, 100.0, D, true);
    table.touch_us(200 * MS, 1, 130.0, 100.0, M, true);
    table.touch_us(220 * MS, 1, 130.0, 100.0, U, true);
    assert_eq!(table.seg.gestures().len(), 1);
    let mut buf = GestureTracks::default();
    assert!(table.cap.snapshot(1, &mut buf));
    assert_eq!(times(&buf.fingers[0]), vec![0, 100 * MS]);
}

#[test]
fn palms_and_unknown_gestures_are_ignored() {
    let mut table = Table::new(CaptureParams::default());
    table.touch(0, 1, 100.0, 100.0, D | ContactFlags::PALM);
    assert!(table.seg.gestures().is_empty());
    let mut buf = GestureTracks::default();
    assert!(!table.cap.snapshot(1, &mut buf));
    assert_eq!(table.cap.finish(7, &mut buf), Err(Rejected::NotCaptured));
    table.touch(10, 2, 100.0, 100.0, D);
    table.cap.discard(1);
    assert!(!table.cap.is_capturing(1));
}
