use super::*;

/// Position of a track at time `t`: its latest sample at or before `t`.
fn at(track: &TouchTrack, t: u64) -> Option<Vec2> {
    let s = &track.samples;
    if s.first()?.t.0 > t || s.last()?.t.0 < t {
        return None;
    }
    s.iter().rev().find(|x| x.t.0 <= t).map(|x| x.mm)
}

fn points(g: &Generated, t: u64, hand: Option<usize>) -> Vec<Vec2> {
    g.tracks
        .fingers
        .iter()
        .zip(&g.hand)
        .filter(|(_, &h)| hand.is_none_or(|w| w == h))
        .map(|(f, _)| at(f, t).expect("every finger is down during the motion"))
        .collect()
}

fn centroid(p: &[Vec2]) -> Vec2 {
    p.iter().sum::<Vec2>() / p.len() as f64
}

/// RMS distance to the centroid, mm.
fn spread(p: &[Vec2]) -> f64 {
    let c = centroid(p);
    (p.iter().map(|q| (q - c).norm_squared()).sum::<f64>() / p.len() as f64).sqrt()
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// Cumulative turn of the fingers about their centroid from `t0` to `t1`, rad
/// (positive turns +x towards +y), in 64 steps.
fn rotation(g: &Generated, t0: u64, t1: u64) -> f64 {
    let mut total = 0.0;
    let mut prev = points(g, t0, None);
    for k in 1..=64 {
        let t = t0 + (t1 - t0) * k / 64;
        let cur = points(g, t, None);
        let (c0, c1) = (centroid(&prev), centroid(&cur));
        let turns: Vec<f64> = prev
            .iter()
            .zip(&cur)
            .map(|(a, b)| {
                let (u, v) = (a - c0, b - c1);
                wrap(v.y.atan2(v.x) - u.y.atan2(u.x))
            })
            .collect();
        total += turns.iter().sum::<f64>() / turns.len() as f64;
        prev = cur;
    }
    total
}

/// Turn of a single finger's heading from `t0` to `t1`, rad, in 48 steps.
fn heading_turn(track: &TouchTrack, t0: u64, t1: u64) -> f64 {
    let p: Vec<Vec2> = (0..=48)
        .map(|k| at(track, t0 + (t1 - t0) * k / 48).expect("down"))
        .collect();
    p.windows(3)
        .map(|w| {
            let (u, v) = (w[1] - w[0], w[2] - w[1]);
            wrap(v.y.atan2(v.x) - u.y.atan2(u.x))
        })
        .sum()
}

fn style(class: MotionClass, seed: u64) -> GestureStyle {
    let mut s = GestureStyle::random(class, seed, &StyleRanges::default());
    s.early_lifts = 0;
    s
}

fn check_sane(class: MotionClass, s: &GestureStyle, g: &Generated) {
    let (hands, (lo, hi)) = class_hands(class);
    assert_eq!(s.fingers.len(), hands);
    assert!(
        s.fingers.iter().all(|n| (lo..=hi).contains(n)),
        "{:?}",
        s.fingers
    );
    assert_eq!(g.tracks.fingers.len(), s.fingers.iter().sum::<usize>());
    let (w, h) = s.device_mm;
    let mut lands = Vec::new();
    for f in &g.tracks.fingers {
        assert!(f.samples.len() >= 2);
        assert!(f.samples.windows(2).all(|p| p[0].t < p[1].t));
        assert!(f
            .samples
            .iter()
            .all(|p| (0.0..=w).contains(&p.mm.x) && (0.0..=h).contains(&p.mm.y)));
        lands.push(f.samples[0].t);
    }
    assert!(
        lands.windows(2).all(|p| p[0] <= p[1]),
        "tracks in landing order"
    );
    assert_eq!(lands[0], Micros(0));
}

#[test]
fn every_class_has_its_geometry() {
    for class in MotionClass::ALL {
        for seed in 0..24 {
            let s = style(class, seed);
            let g = generate_detailed(class, &s, seed);
            check_sane(class, &s, &g);
            let (t0, t1) = g.motion_us;
            let tm = (t0 + t1) / 2;
            let (p0, pm, p1) = (
                points(&g, t0, None),
                points(&g, tm, None),
                points(&g, t1, None),
            );
            let moved = (centroid(&p1) - centroid(&p0)).norm();
            let (s0, s1) = (spread(&p0), spread(&p1));
            let sign = if s.clockwise { 1.0 } else { -1.0 };
            let hands =
                |t| (centroid(&points(&g, t, Some(0))) - centroid(&points(&g, t, Some(1)))).norm();
            let why =
                format!("{class} seed {seed}: {s:?} moved {moved:.1} spread {s0:.1} -> {s1:.1}");
            match class {
                MotionClass::Translate => {
                    assert!(moved > 15.0, "{why}");
                    assert!((s1 - s0).abs() < 3.0, "{why}");
                }
                MotionClass::Twist if s.fingers[0] == 1 => {
                    let turn = heading_turn(&g.tracks.fingers[0], t0, t1);
                    assert!(turn * sign > 150f64.to_radians(), "{why}: turn {turn:.2}");
                }
                MotionClass::Twist => {
                    let turn = rotation(&g, t0, t1);
                    assert!(turn * sign > 50f64.to_radians(), "{why}: turn {turn:.2}");
                    assert!((s1 - s0).abs() < 0.1 * s0 + 3.0, "{why}");
                }
                MotionClass::Contract => assert!(s1 < 0.55 * s0, "{why}"),
                MotionClass::Expand => assert!(s1 > 1.8 * s0, "{why}"),
                MotionClass::TwistWhileExpanding | MotionClass::TwistWhileContracting => {
                    let turn = rotation(&g, t0, t1);
                    assert!(turn * sign > 80f64.to_radians(), "{why}: turn {turn:.2}");
                    if class == MotionClass::TwistWhileExpanding {
                        assert!(s1 > 1.8 * s0, "{why}");
                    } else {
                        assert!(s1 < 0.55 * s0, "{why}");
                    }
                }
                MotionClass::Join => assert!(hands(t1) < 0.7 * hands(t0), "{why}"),
                MotionClass::Split => assert!(hands(t1) > 1.4 * hands(t0), "{why}"),
                MotionClass::SplitThenTranslate => {
                    assert!(hands(tm) > 1.4 * hands(t0), "{why}");
                    assert!((hands(t1) / hands(tm) - 1.0).abs() < 0.2, "{why}");
                    assert!((centroid(&p1) - centroid(&pm)).norm() > 10.0, "{why}");
                }
                MotionClass::TranslateThenJoin => {
                    assert!((centroid(&pm) - centroid(&p0)).norm() > 10.0, "{why}");
                    assert!((hands(tm) / hands(t0) - 1.0).abs() < 0.2, "{why}");
                    assert!(hands(t1) < 0.7 * hands(tm), "{why}");
                }
            }
        }
    }
}

#[test]
fn one_seed_one_gesture() {
    for class in MotionClass::ALL {
        let s = GestureStyle::random(class, 5, &StyleRanges::default());
        assert_eq!(s, GestureStyle::random(class, 5, &StyleRanges::default()));
        assert_ne!(s, GestureStyle::random(class, 6, &StyleRanges::default()));
        assert_eq!(generate(class, &s, 9), generate(class, &s, 9));
        assert_ne!(generate(class, &s, 9), generate(class, &s, 10));
    }
}

#[test]
fn styles_stay_in_their_ranges() {
    let ranges = StyleRanges {
        fingers: (2, 3),
        duration_s: (1.0, 1.5),
        size_mm: (40.0, 60.0),
        rate_hz: (90.0, 90.0),
        devices_mm: vec![(300.0, 200.0)],
        ..StyleRanges::default()
    };
    for class in MotionClass::ALL {
        for seed in 0..10 {
            let s = GestureStyle::random(class, seed, &ranges);
            assert!((1.0..1.5).contains(&s.duration_s) && (40.0..60.0).contains(&s.size_mm));
            assert_eq!((s.rate_hz, s.device_mm), (90.0, (300.0, 200.0)));
            assert!(
                s.fingers.iter().all(|&n| (2..=3).contains(&n)),
                "{class}: {s:?}"
            );
            let g = generate_detailed(class, &s, seed);
            check_sane(class, &s, &g);
            // Samples a frame period apart (±3 % jitter, µs rounding).
            let f = &g.tracks.fingers[0].samples;
            assert!(f
                .windows(2)
                .all(|p| (p[1].t.0 - p[0].t.0).abs_diff(11_111) < 700));
        }
    }
}

#[test]
fn early_lifts_end_a_finger_during_the_motion() {
    let mut s = style(MotionClass::Translate, 3);
    s.fingers = vec![4];
    s.early_lifts = 2;
    let g = generate_detailed(MotionClass::Translate, &s, 3);
    let (t0, t1) = g.motion_us;
    let ends: Vec<u64> = g
        .tracks
        .fingers
        .iter()
        .map(|f| f.samples.last().unwrap().t.0)
        .collect();
    let early = ends.iter().filter(|&&e| e > t0 && e < t1).count();
    assert_eq!(early, 2, "{ends:?} motion {t0}..{t1}");
    assert!(ends.iter().any(|&e| e > t1));
}

#[test]
fn a_big_gesture_on_a_small_glass_is_shrunk_to_fit() {
    let mut s = style(MotionClass::Split, 1);
    s.size_mm = 250.0;
    s.device_mm = (150.0, 100.0);
    s.placement = Vec2::new(1.0, 0.0);
    let g = generate_detailed(MotionClass::Split, &s, 1);
    check_sane(MotionClass::Split, &s, &g);
    let (t0, t1) = g.motion_us;
    let d = |t| (centroid(&points(&g, t, Some(0))) - centroid(&points(&g, t, Some(1)))).norm();
    assert!(d(t1) > 1.4 * d(t0));
}

/// Rebuilds tracks from frames as a capture would: one track per contact id, in
/// order of first appearance.
fn tracks_of(
    frames: &[TouchFrame],
    device_mm: (f64, f64),
    t0: Micros,
) -> (GestureTracks, Vec<Vec<ContactFlags>>) {
    let mut ids: Vec<ContactId> = Vec::new();
    let mut tracks: Vec<TouchTrack> = Vec::new();
    let mut flags: Vec<Vec<ContactFlags>> = Vec::new();
    for f in frames {
        for c in f.contacts() {
            let j = match ids.iter().position(|&i| i == c.id) {
                Some(j) => j,
                None => {
                    ids.push(c.id);
                    tracks.push(TouchTrack::default());
                    flags.push(Vec::new());
                    ids.len() - 1
                }
            };
            tracks[j].samples.push(TrackSample {
                t: f.t - t0,
                mm: Vec2::new(f64::from(c.x) * device_mm.0, f64::from(c.y) * device_mm.1),
            });
            flags[j].push(c.flags);
        }
    }
    (GestureTracks { fingers: tracks }, flags)
}

#[test]
fn frames_round_trip_to_tracks() {
    let t0 = Micros(5_000_000);
    for (k, class) in MotionClass::ALL.into_iter().enumerate() {
        let s = GestureStyle::random(class, 40 + k as u64, &StyleRanges::default());
        let tracks = generate(class, &s, 40 + k as u64);
        let frames = to_frames(&tracks, s.device_mm, t0);
        assert!(frames.windows(2).all(|w| w[0].t < w[1].t));
        assert!(frames.iter().all(|f| f
            .contacts()
            .iter()
            .all(|c| (0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y))));
        let (back, flags) = tracks_of(&frames, s.device_mm, t0);
        assert_eq!(back.fingers.len(), tracks.fingers.len());
        for (a, b) in tracks.fingers.iter().zip(&back.fingers) {
            assert_eq!(a.samples.len(), b.samples.len());
            for (p, q) in a.samples.iter().zip(&b.samples) {
                assert_eq!(p.t, q.t);
                assert!((p.mm - q.mm).norm() < 1e-3, "{p:?} {q:?}");
            }
        }
        for f in &flags {
            assert_eq!(f[0], ContactFlags::DOWN);
            assert_eq!(*f.last().unwrap(), ContactFlags::UP);
            assert!(f[1..f.len() - 1].iter().all(|&x| x == ContactFlags::NONE));
        }
    }
}

#[test]
fn a_one_sample_track_is_down_and_up_in_one_frame() {
    let tracks = GestureTracks {
        fingers: vec![
            TouchTrack {
                samples: vec![TrackSample {
                    t: Micros(100),
                    mm: Vec2::new(50.0, 25.0),
                }],
            },
            TouchTrack {
                samples: vec![
                    TrackSample {
                        t: Micros(0),
                        mm: Vec2::new(10.0, 10.0),
                    },
                    TrackSample {
                        t: Micros(200),
                        mm: Vec2::new(20.0, 10.0),
                    },
                ],
            },
        ],
    };
    let frames = to_frames(&tracks, (100.0, 50.0), Micros(0));
    assert_eq!(frames.len(), 3);
    assert_eq!(frames[0].contacts().len(), 1);
    // At 100 µs the second finger is reported at its latest position.
    let c = frames[1].contacts();
    assert_eq!(c.len(), 2);
    assert_eq!(
        (c[0].id, c[0].flags, c[0].x, c[0].y),
        (
            ContactId(1),
            ContactFlags::DOWN | ContactFlags::UP,
            0.5,
            0.5
        )
    );
    assert_eq!(
        (c[1].id, c[1].flags, c[1].x),
        (ContactId(2), ContactFlags::NONE, 0.1)
    );
    assert_eq!(frames[2].contacts()[0].flags, ContactFlags::UP);
}

/// Widest distance between two of `p`, mm.
fn widest(p: &[Vec2]) -> f64 {
    let mut m = 0.0f64;
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            m = m.max((a - b).norm());
        }
    }
    m
}

#[test]
fn one_hand_never_opens_wider_than_a_hand_reaches() {
    // Sensor noise and tremor: at most a millimetre or two on top of the hand.
    let noise_mm = 4.0;
    for class in [
        MotionClass::Twist,
        MotionClass::Contract,
        MotionClass::Expand,
        MotionClass::TwistWhileExpanding,
        MotionClass::TwistWhileContracting,
    ] {
        for seed in 0..40 {
            let mut s = style(class, seed);
            // The largest size asked for: the hand, not the size, limits it.
            s.size_mm = 250.0;
            s.fingers = vec![2 + (seed as usize % 4)];
            let g = generate_detailed(class, &s, seed);
            let n = s.fingers[0];
            let most = HAND_SPAN_MM.1 * REACH_SHARE[n - 1] * COMFORTABLE_STRETCH;
            let (t0, t1) = g.motion_us;
            for k in 0..=16 {
                let t = t0 + (t1 - t0) * k / 16;
                let w = widest(&points(&g, t, None));
                assert!(
                    w <= most + noise_mm,
                    "{class} seed {seed}, {n} fingers: {w:.1} mm apart, a hand reaches {most:.1}"
                );
            }
        }
    }
}

#[test]
fn a_pinch_closes_the_thumb_on_the_fingers_which_close_only_until_they_touch() {
    for seed in 0..20 {
        for n in 3..=5 {
            let mut s = style(MotionClass::Contract, seed);
            s.fingers = vec![n];
            s.size_mm = 200.0;
            let mut rng = SplitMix64::new(seed);
            let h = &hands(MotionClass::Contract, &s, &mut rng)[0];
            let at = |u: f64| (0..n).map(|i| h.at(i, u)).collect::<Vec<_>>();
            let (open, closed) = (at(0.0), at(1.0));
            // The thumb (finger 0) comes towards the fingers by the pinch's scale.
            let towards = |p: &[Vec2]| (p[0] - centroid(&p[1..])).norm();
            assert!(
                towards(&closed) < 0.45 * towards(&open),
                "seed {seed}, {n} fingers: thumb {:.1} -> {:.1} mm from the fingers",
                towards(&open),
                towards(&closed)
            );
            // The fingers side by side stay at least a fingertip apart (less the
            // row's ±2 mm irregularity on each finger).
            for i in 1..n {
                for j in i + 1..n {
                    let d = (closed[i] - closed[j]).norm();
                    assert!(
                        d > FINGERTIP_PITCH_MM - 4.0,
                        "seed {seed}, {n} fingers: fingers {i} and {j} {d:.1} mm apart"
                    );
                }
            }
            // Open, the fingers are splayed wider than at rest.
            let pitch = (open[1] - open[2]).norm();
            assert!(pitch > s.spacing_mm, "{pitch:.1} vs {}", s.spacing_mm);
        }
    }
}

#[test]
fn two_hands_are_at_least_a_palm_apart() {
    for class in [
        MotionClass::Join,
        MotionClass::Split,
        MotionClass::SplitThenTranslate,
        MotionClass::TranslateThenJoin,
    ] {
        for seed in 0..40 {
            let s = style(class, seed);
            let g = generate_detailed(class, &s, seed);
            let (t0, t1) = g.motion_us;
            for k in 0..=16 {
                let t = t0 + (t1 - t0) * k / 16;
                let d =
                    (centroid(&points(&g, t, Some(0))) - centroid(&points(&g, t, Some(1)))).norm();
                assert!(
                    d > HAND_BREADTH_MM.0 - 3.0,
                    "{class} seed {seed} {:?}: hands {d:.1} mm apart",
                    s.fingers
                );
            }
        }
    }
}

#[test]
fn two_hand_gestures_are_often_one_finger_per_hand() {
    let mut both_one = 0;
    let mut counts = [0usize; 4];
    let trials = 600;
    for seed in 0..trials {
        let s = GestureStyle::random(MotionClass::Join, seed, &StyleRanges::default());
        both_one += usize::from(s.fingers == [1, 1]);
        for &n in &s.fingers {
            counts[n] += 1;
        }
    }
    // One finger 6/11, two 3/11, three 2/11 per hand: both one about 30 %.
    let share = both_one as f64 / trials as f64;
    assert!((0.22..0.38).contains(&share), "{share} {counts:?}");
    assert!(counts[1] > counts[2] && counts[2] > counts[3], "{counts:?}");
    // One-hand classes keep drawing 1–5 fingers evenly.
    let fives = (0..trials)
        .filter(|&seed| {
            GestureStyle::random(MotionClass::Translate, seed, &StyleRanges::default()).fingers
                == [5]
        })
        .count();
    assert!((80..160).contains(&fives), "{fives}");
}
