//! Tests of the continuous recogniser: the state machine fed synthetic votes, the
//! window cut against brute force, and end to end with a tiny labelled index.

use super::*;
use crate::geom::Vec2;
use crate::gesture::library::MotionClass;
use crate::gesture::resample::prepare;
use crate::rng::SplitMix64;

// The classes of a library of the ten built-in classes, by their usual names.
#[allow(non_upper_case_globals)]
const Expand: ClassId = MotionClass::Expand.id();
#[allow(non_upper_case_globals)]
const Translate: ClassId = MotionClass::Translate.id();
#[allow(non_upper_case_globals)]
const Twist: ClassId = MotionClass::Twist.id();

const MS: u64 = 1000;

fn params(window_ms: u64, hold_ms: u64) -> ContinuousParams {
    ContinuousParams {
        slots: 2,
        ..ContinuousParams::from_ms(window_ms, hold_ms)
    }
}

/// Drives gesture 1 from 0 to `until_ms` with ticks every 10 ms; at each due
/// window asks `vote_at(t_ms)`. Returns every fire with its time (ms).
fn drive(
    r: &mut ContinuousRecogniser,
    until_ms: u64,
    vote_at: impl Fn(u64) -> Option<(ClassId, f64)>,
) -> Vec<(u64, Fire)> {
    assert!(r.begin(1, Micros::ZERO));
    let mut fires = Vec::new();
    for t in (0..=until_ms).step_by(10) {
        let now = Micros(t * MS);
        if r.due(1, now) {
            if let Some(f) = r.observe(1, now, vote_at(t)) {
                fires.push((t, f));
            }
        }
    }
    fires
}

#[test]
fn a_class_held_fires_once_at_window_plus_hold() {
    let mut r = ContinuousRecogniser::new(params(1000, 500));
    let fires = drive(&mut r, 4000, |_| Some((Translate, 0.8)));
    assert_eq!(fires.len(), 1, "{fires:?}");
    let (t, f) = fires[0];
    assert_eq!(t, 1500);
    assert_eq!(f.class, Translate);
    assert_eq!(f.since, Micros(1000 * MS));
    assert_eq!(f.window, (Micros(500 * MS), Micros(1500 * MS)));
    assert_eq!((f.id, f.count, f.weight), (1, 1, 0.8));
    assert_eq!(r.state(1), ContinuousState::Fired { class: Translate });
    assert_eq!(
        r.end(1),
        Some(Ended {
            fired: 1,
            last: Some(Translate)
        })
    );
    assert_eq!(r.stats().fired, 1);
}

#[test]
fn windows_are_due_every_period_from_window_on() {
    let mut r = ContinuousRecogniser::new(params(300, 0));
    r.begin(7, Micros(50 * MS));
    let due: Vec<u64> = (0..=800)
        .step_by(10)
        .filter(|&t| r.due(7, Micros(t * MS)))
        .collect();
    assert_eq!(due, vec![350, 450, 550, 650, 750]);
    // A late tick is due once; the next is a period after it.
    let mut r = ContinuousRecogniser::new(params(300, 0));
    r.begin(7, Micros::ZERO);
    let due: Vec<u64> = [290, 420, 430, 510, 530, 700]
        .into_iter()
        .filter(|&t| r.due(7, Micros(t * MS)))
        .collect();
    assert_eq!(due, vec![420, 530, 700]);
    assert!(
        !r.due(8, Micros(900 * MS)),
        "an unknown gesture is never due"
    );
}

#[test]
fn flicker_between_classes_never_fires() {
    let mut r = ContinuousRecogniser::new(params(1000, 300));
    let fires = drive(&mut r, 5000, |t| {
        let c = if (t / 100) % 3 == 2 { Twist } else { Translate };
        Some((c, 0.9))
    });
    assert!(fires.is_empty(), "{fires:?}");
    assert_eq!(r.end(1).map(|e| e.fired), Some(0));
}

#[test]
fn a_weight_below_the_floor_or_no_vote_breaks_the_lead() {
    let mut r = ContinuousRecogniser::new(params(1000, 300));
    // Translate ahead but weak every 3rd window (and nothing at all at 2.5 s)
    // until 3 s: no run lasts 300 ms until the last weak window, at 2.7 s.
    let fires = drive(&mut r, 4000, |t| match t {
        2500 => None,
        t if t < 3000 && (t / 100) % 3 == 0 => Some((Translate, 0.49)),
        _ => Some((Translate, 0.5)),
    });
    // From 2.8 s on every window votes 0.5: the lead starts at 2.8, fires at 3.1.
    assert_eq!(fires.iter().map(|f| f.0).collect::<Vec<_>>(), vec![3100]);
    assert_eq!(fires[0].1.since, Micros(2800 * MS));
    // A NaN weight is not ahead.
    let mut r = ContinuousRecogniser::new(params(1000, 0));
    assert!(drive(&mut r, 2000, |_| Some((Twist, f64::NAN))).is_empty());
}

#[test]
fn fires_again_only_for_a_change_of_class() {
    let mut r = ContinuousRecogniser::new(params(1000, 200));
    let fires = drive(&mut r, 6000, |t| match t {
        ..=1900 => Some((Translate, 0.7)),
        // A moment of nothing, then translate again: no second translate.
        2000..=2200 => None,
        2300..=2900 => Some((Translate, 0.7)),
        // Twist holds: fires.
        3000..=3900 => Some((Twist, 0.6)),
        // Translate too briefly, then twist again: nothing.
        4000..=4100 => Some((Translate, 0.7)),
        4200..=4900 => Some((Twist, 0.6)),
        // Translate holds again: fires (the last fire was twist).
        _ => Some((Translate, 0.9)),
    });
    let got: Vec<(u64, ClassId, u32)> = fires.iter().map(|(t, f)| (*t, f.class, f.count)).collect();
    assert_eq!(
        got,
        vec![(1200, Translate, 1), (3200, Twist, 2), (5200, Translate, 3)]
    );
    assert_eq!(
        r.end(1),
        Some(Ended {
            fired: 3,
            last: Some(Translate)
        })
    );
}

#[test]
fn zero_hold_fires_on_the_first_winning_window() {
    let mut r = ContinuousRecogniser::new(params(500, 0));
    let fires = drive(&mut r, 1500, |t| (t >= 800).then_some((Expand, 1.0)));
    assert_eq!(fires.len(), 1);
    assert_eq!((fires[0].0, fires[0].1.since), (800, Micros(800 * MS)));
}

#[test]
fn a_gesture_shorter_than_the_window_never_fires() {
    let mut r = ContinuousRecogniser::new(params(1000, 0));
    assert!(r.begin(3, Micros(100 * MS)));
    for t in (100..1100).step_by(10) {
        assert!(!r.due(3, Micros(t * MS)));
        assert_eq!(r.state(3), ContinuousState::Filling);
    }
    // A vote that no due asked for is early, ignored.
    assert_eq!(r.observe(3, Micros(1000 * MS), Some((Twist, 1.0))), None);
    assert_eq!(r.stats().early, 1);
    assert_eq!(
        r.end(3),
        Some(Ended {
            fired: 0,
            last: None
        })
    );
    assert_eq!(r.state(3), ContinuousState::Free);
    assert_eq!(r.end(3), None, "ended twice");
}

#[test]
fn stale_and_unknown_votes_are_ignored_and_counted() {
    let mut r = ContinuousRecogniser::new(params(100, 100));
    r.begin(1, Micros::ZERO);
    assert!(r.due(1, Micros(100 * MS)));
    assert!(r.due(1, Micros(200 * MS)));
    assert_eq!(r.observe(1, Micros(200 * MS), Some((Twist, 1.0))), None);
    // The older window's vote comes back late: stale, even though it would have
    // made twist ahead for the hold.
    assert_eq!(r.observe(1, Micros(100 * MS), Some((Twist, 1.0))), None);
    assert_eq!(r.observe(1, Micros(200 * MS), Some((Twist, 1.0))), None);
    assert_eq!(r.stats().stale, 2);
    assert!(r.observe(1, Micros(300 * MS), Some((Twist, 1.0))).is_some());
    r.end(1);
    assert_eq!(r.observe(1, Micros(400 * MS), Some((Twist, 1.0))), None);
    assert_eq!(r.stats().unknown, 1);
}

#[test]
fn slots_are_reused_and_overflow_is_counted() {
    let mut r = ContinuousRecogniser::new(params(100, 0));
    assert!(r.begin(1, Micros::ZERO));
    assert!(r.begin(2, Micros::ZERO));
    assert!(r.begin(2, Micros::ZERO), "begin twice keeps the gesture");
    assert!(!r.begin(3, Micros::ZERO));
    assert_eq!(r.stats().overflowed, 1);
    // The overflowed gesture is ignored throughout.
    assert!(!r.due(3, Micros(200 * MS)));
    assert_eq!(r.observe(3, Micros(200 * MS), Some((Twist, 1.0))), None);
    assert_eq!(r.end(3), None);
    // Gesture 2 fired; its slot is freed and the next gesture starts afresh.
    assert!(r.due(2, Micros(100 * MS)));
    assert!(r.observe(2, Micros(100 * MS), Some((Twist, 1.0))).is_some());
    assert_eq!(r.end(2).map(|e| e.fired), Some(1));
    assert!(r.begin(4, Micros(150 * MS)));
    assert_eq!(r.state(4), ContinuousState::Filling);
    assert_eq!(r.fired(4), 0);
    assert!(!r.due(4, Micros(200 * MS)));
    assert!(r.due(4, Micros(250 * MS)));
    let f = r.observe(4, Micros(250 * MS), Some((Twist, 1.0)));
    assert_eq!(f.map(|f| (f.id, f.count)), Some((4, 1)), "twist fires anew");
    assert_eq!(r.stats().overflowed, 1);
    r.clear();
    assert_eq!(r.state(1), ContinuousState::Free);
    assert!(r.begin(5, Micros::ZERO) && r.begin(6, Micros::ZERO));
}

#[test]
fn parameters_out_of_range_are_brought_in_range() {
    let r = ContinuousRecogniser::new(ContinuousParams {
        period: Micros::ZERO,
        min_weight: f64::NAN,
        slots: 0,
        ..ContinuousParams::from_ms(1000, 500)
    });
    let p = r.params();
    assert_eq!(
        (p.period, p.min_weight, p.slots),
        (MIN_PERIOD, DEFAULT_MIN_WEIGHT, 1)
    );
    assert_eq!((p.window, p.hold), (Micros(1_000_000), Micros(500_000)));
}

fn sample(t_ms: u64, x: f64, y: f64) -> TrackSample {
    TrackSample {
        t: Micros(t_ms * MS),
        mm: Vec2::new(x, y),
    }
}

fn track(samples: Vec<TrackSample>) -> TouchTrack {
    TouchTrack { samples }
}

#[test]
fn window_cuts_and_interpolates_the_ends() {
    let g = GestureTracks {
        fingers: vec![
            // Down all along: cut at 250 (between 200 and 300) and at 650.
            track(
                (0..=10)
                    .map(|i| sample(i * 100, i as f64 * 10.0, 0.0))
                    .collect(),
            ),
            // Lifted before the window: dropped.
            track(vec![sample(0, 0.0, 5.0), sample(240, 9.0, 5.0)]),
            // Lands inside the window, lifts after it.
            track(vec![
                sample(400, 0.0, 1.0),
                sample(500, 0.0, 2.0),
                sample(900, 0.0, 6.0),
            ]),
            // Spans the window with no sample inside.
            track(vec![sample(200, 0.0, 0.0), sample(1000, 80.0, 0.0)]),
            // Starts exactly at the window's start: no duplicate point.
            track(vec![sample(250, 1.0, 1.0), sample(260, 2.0, 1.0)]),
            track(vec![]),
        ],
    };
    let mut out = GestureTracks::default();
    assert_eq!(window(&g, Micros(650 * MS), Micros(400 * MS), &mut out), 4);
    let pts = |f: usize| -> Vec<(u64, f64, f64)> {
        out.fingers[f]
            .samples
            .iter()
            .map(|s| (s.t.0 / MS, s.mm.x, s.mm.y))
            .collect()
    };
    assert_eq!(
        pts(0),
        vec![
            (250, 25.0, 0.0),
            (300, 30.0, 0.0),
            (400, 40.0, 0.0),
            (500, 50.0, 0.0),
            (600, 60.0, 0.0),
            (650, 65.0, 0.0)
        ]
    );
    assert_eq!(
        pts(1),
        vec![(400, 0.0, 1.0), (500, 0.0, 2.0), (650, 0.0, 3.5)]
    );
    assert_eq!(pts(2), vec![(250, 5.0, 0.0), (650, 45.0, 0.0)]);
    assert_eq!(pts(3), vec![(250, 1.0, 1.0), (260, 2.0, 1.0)]);
    // A window longer than the gesture is the whole gesture (minus the lifted
    // fingers' absence: none here).
    assert_eq!(
        window(&g, Micros(1000 * MS), Micros(5000 * MS), &mut out),
        5
    );
    assert_eq!(out.fingers[0], g.fingers[0]);
    assert_eq!(out.fingers[1], g.fingers[1]);
}

#[test]
fn window_matches_interpolating_the_track_and_reuses_its_buffers() {
    let mut rng = SplitMix64::new(15);
    let mut out = GestureTracks::default();
    for _ in 0..200 {
        let mut t = rng.uniform(0.0, 500.0) as u64;
        let n = 2 + (rng.unit() * 30.0) as usize;
        let samples: Vec<TrackSample> = (0..n)
            .map(|_| {
                t += 1 + (rng.unit() * 60.0) as u64;
                sample(t, rng.uniform(-100.0, 100.0), rng.uniform(-100.0, 100.0))
            })
            .collect();
        let g = GestureTracks {
            fingers: vec![track(samples.clone())],
        };
        let now = Micros(rng.uniform(0.0, 2500.0) as u64 * MS);
        let len = Micros(rng.uniform(1.0, 1000.0) as u64 * MS);
        let lo = now - len;
        // Brute force: the piecewise-linear path at time t.
        let at = |t: Micros| -> Vec2 {
            let k = samples.iter().rposition(|s| s.t <= t).unwrap();
            if k + 1 == samples.len() || samples[k].t == t {
                return samples[k].mm;
            }
            let (a, b) = (samples[k], samples[k + 1]);
            let u = (t.0 - a.t.0) as f64 / (b.t.0 - a.t.0) as f64;
            a.mm + (b.mm - a.mm) * u
        };
        let kept = window(&g, now, len, &mut out);
        let (first, last) = (samples[0].t, samples[n - 1].t);
        if last < lo || first > now {
            assert_eq!(kept, 0);
            continue;
        }
        assert_eq!(kept, 1);
        let o = &out.fingers[0].samples;
        assert_eq!(o[0].t, first.max(lo));
        assert_eq!(o.last().unwrap().t, last.min(now));
        assert!(o.windows(2).all(|w| w[0].t < w[1].t));
        for s in o {
            assert!((s.mm - at(s.t)).norm() < 1e-9, "{s:?} vs {:?}", at(s.t));
        }
        let inside = samples.iter().filter(|s| s.t >= lo && s.t <= now).count();
        assert!(o.len() >= inside && o.len() <= inside + 2);
    }
    // Same window again: the buffers are reused, not reallocated.
    let g = GestureTracks {
        fingers: vec![track(
            (0..50).map(|i| sample(i * 10, i as f64, 0.0)).collect(),
        )],
    };
    window(&g, Micros(400 * MS), Micros(300 * MS), &mut out);
    let ptr = out.fingers[0].samples.as_ptr();
    window(&g, Micros(450 * MS), Micros(300 * MS), &mut out);
    assert_eq!(out.fingers[0].samples.as_ptr(), ptr);
}

/// Samples every 8 ms (125 Hz) from `t0` for `dur_ms`, of `fingers` fingers
/// whose positions at time `s` (seconds since `t0`) are `pos(finger, s)`, with
/// ±0.3 mm of sensor noise.
fn draw(
    rng: &mut SplitMix64,
    fingers: usize,
    dur_ms: u64,
    pos: impl Fn(usize, f64) -> Vec2,
) -> GestureTracks {
    GestureTracks {
        fingers: (0..fingers)
            .map(|f| {
                track(
                    (0..=dur_ms / 8)
                        .map(|i| {
                            let s = (i * 8) as f64 / 1000.0;
                            let noise = Vec2::new(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3));
                            TrackSample {
                                t: Micros(i * 8 * MS),
                                mm: pos(f, s) + noise,
                            }
                        })
                        .collect(),
                )
            })
            .collect(),
    }
}

/// One hand of three fingers translating rightwards (±15°) at `speed` mm/s.
fn translating(rng: &mut SplitMix64, dur_ms: u64, speed: f64) -> GestureTracks {
    let a = rng.uniform(-0.26, 0.26);
    let dir = Vec2::new(a.cos(), a.sin());
    let start = Vec2::new(rng.uniform(100.0, 300.0), rng.uniform(100.0, 300.0));
    let hand = [
        Vec2::new(0.0, 0.0),
        Vec2::new(20.0, -15.0),
        Vec2::new(40.0, -5.0),
    ];
    draw(rng, 3, dur_ms, move |f, s| {
        start + hand[f] + dir * (speed * s)
    })
}

/// Two fingers opposite each other turning about their midpoint at `rate` rad/s
/// (either way).
fn twisting(rng: &mut SplitMix64, dur_ms: u64, rate: f64) -> GestureTracks {
    let r = rng.uniform(25.0, 45.0);
    let phase = rng.uniform(0.0, std::f64::consts::TAU);
    let sign = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
    let c = Vec2::new(rng.uniform(150.0, 300.0), rng.uniform(150.0, 300.0));
    draw(rng, 2, dur_ms, move |f, s| {
        let a = phase + std::f64::consts::PI * f as f64 + sign * rate * s;
        c + Vec2::new(a.cos(), a.sin()) * r
    })
}

/// A labelled index of eight translates and eight twists of 0.8–1.5 s.
fn tiny_index(rng: &mut SplitMix64) -> (GestureIndex, Vec<ClassId>) {
    let mut features = Vec::new();
    let mut classes = Vec::new();
    for i in 0..16 {
        let dur = rng.uniform(800.0, 1500.0) as u64;
        let (g, c) = if i % 2 == 0 {
            {
                let speed = rng.uniform(80.0, 200.0);
                (translating(rng, dur, speed), Translate)
            }
        } else {
            {
                let rate = rng.uniform(1.5, 3.0);
                (twisting(rng, dur, rate), Twist)
            }
        };
        features.push(GestureFeatures::of(&prepare(&g).unwrap()));
        classes.push(c);
    }
    (GestureIndex::new(features), classes)
}

/// Plays `g` live from its first sample: ticks every 10 ms, the tracks so far as
/// the capture's snapshot would give them, each due window recognised. Returns
/// the fires (ms) and the last window's vote.
fn play(
    g: &GestureTracks,
    index: &GestureIndex,
    classes: &[ClassId],
    r: &mut ContinuousRecogniser,
) -> (Vec<(u64, Fire)>, WindowVote) {
    let wp = WindowParams {
        window: r.params().window,
        min_travel_mm: DEFAULT_WINDOW_MIN_TRAVEL_MM,
        search: SearchParams {
            k: 5,
            ..SearchParams::default()
        },
    };
    let mut buf = WindowBuffers::new();
    let mut so_far = GestureTracks::default();
    let (start, end) = g.span().unwrap();
    assert!(r.begin(9, start));
    let mut fires = Vec::new();
    let mut last = WindowVote::NoNeighbours;
    for t in (start.0 / MS..=end.0 / MS).step_by(10) {
        let now = Micros(t * MS);
        if !r.due(9, now) {
            continue;
        }
        so_far.fingers = g
            .fingers
            .iter()
            .map(|f| track(f.samples.iter().copied().filter(|s| s.t <= now).collect()))
            .collect();
        last = recognise_window(&so_far, now, &wp, index, |e| classes[e], &mut buf);
        if let Some(f) = r.observe(9, now, last.vote()) {
            fires.push((t, f));
        }
    }
    r.end(9);
    (fires, last)
}

#[test]
fn a_long_translate_fires_translate_after_window_plus_hold() {
    let mut rng = SplitMix64::new(2015);
    let (index, classes) = tiny_index(&mut rng);
    let mut r = ContinuousRecogniser::new(params(1000, 500));
    let g = translating(&mut rng, 3000, 120.0);
    let (fires, last) = play(&g, &index, &classes, &mut r);
    let got: Vec<(u64, ClassId)> = fires.iter().map(|(t, f)| (*t, f.class)).collect();
    assert_eq!(got, vec![(1500, Translate)], "last window: {last:?}");
    assert!(fires[0].1.weight >= 0.5);
    assert_eq!(last.vote().map(|v| v.0), Some(Translate));

    // A long twist fires twist.
    let g = twisting(&mut rng, 3000, 2.0);
    let (fires, _) = play(&g, &index, &classes, &mut r);
    let got: Vec<(u64, ClassId)> = fires.iter().map(|(t, f)| (*t, f.class)).collect();
    assert_eq!(got, vec![(1500, Twist)]);

    // A gesture shorter than the window never fires.
    let g = translating(&mut rng, 900, 120.0);
    assert!(play(&g, &index, &classes, &mut r).0.is_empty());
}

#[test]
fn a_translate_then_twist_fires_both_in_turn() {
    let mut rng = SplitMix64::new(77);
    let (index, classes) = tiny_index(&mut rng);
    let mut r = ContinuousRecogniser::new(params(800, 300));
    let a = translating(&mut rng, 2500, 150.0);
    let b = twisting(&mut rng, 2500, 2.5);
    // The same hand: the translating hand's first two fingers, then a twist of
    // two fingers from 2.5 s to 5 s (the third finger lifts at 2.5 s).
    let mut g = a.clone();
    g.fingers.truncate(2);
    for (f, t) in g.fingers.iter_mut().zip(&b.fingers) {
        f.samples
            .extend(t.samples.iter().skip(1).map(|s| TrackSample {
                t: s.t + Micros(2500 * MS),
                mm: s.mm,
            }));
    }
    g.fingers.push(a.fingers[2].clone());
    let (fires, _) = play(&g, &index, &classes, &mut r);
    let got: Vec<ClassId> = fires.iter().map(|(_, f)| f.class).collect();
    assert_eq!(got, vec![Translate, Twist], "{fires:?}");
    assert_eq!(fires[0].0, 1100);
    assert!(fires[1].0 > 2500 && fires[1].0 <= 2500 + 800 + 300 + 100);
}

#[test]
fn a_resting_hand_is_still_and_an_empty_index_has_no_neighbours() {
    let mut rng = SplitMix64::new(3);
    let g = draw(&mut rng, 3, 2000, |f, _| {
        Vec2::new(100.0 + 20.0 * f as f64, 100.0)
    });
    let wp = WindowParams {
        window: Micros(1000 * MS),
        min_travel_mm: DEFAULT_WINDOW_MIN_TRAVEL_MM,
        search: SearchParams::default(),
    };
    let mut buf = WindowBuffers::new();
    let empty = GestureIndex::new(Vec::new());
    let v = recognise_window(&g, Micros(2000 * MS), &wp, &empty, |_| Twist, &mut buf);
    assert!(
        matches!(v, WindowVote::Still { travel_mm } if travel_mm < 1.0),
        "{v:?}"
    );
    assert_eq!(v.vote(), None);
    let g = translating(&mut rng, 2000, 100.0);
    let v = recognise_window(&g, Micros(2000 * MS), &wp, &empty, |_| Twist, &mut buf);
    assert_eq!(v, WindowVote::NoNeighbours);
    // After the last finger lifted the window is empty: no travel (still), and
    // refused when no travel is required.
    let v = recognise_window(&g, Micros(9000 * MS), &wp, &empty, |_| Twist, &mut buf);
    assert!(matches!(v, WindowVote::Still { .. }), "{v:?}");
    let wp0 = WindowParams {
        min_travel_mm: 0.0,
        ..wp
    };
    let v = recognise_window(&g, Micros(9000 * MS), &wp0, &empty, |_| Twist, &mut buf);
    assert_eq!(v, WindowVote::Refused(GestureError::NoFingers));
}
