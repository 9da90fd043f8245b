use super::*;

const MS: u64 = 1000;

fn params() -> SegmentParams {
    SegmentParams {
        group_window: Micros(150 * MS),
        hand_span_mm: 200.0,
        gesture_span_mm: 200.0,
        gesture_grace: Micros(250 * MS),
    }
}

/// A tiny timeline: `(t_ms, id, x_mm, y_mm, flags)`; world = glass / 100.
fn run(
    seg: &mut Segmenter,
    steps: &[(u64, u32, f64, f64, ContactFlags)],
    crowd: impl Fn(Vec2) -> bool,
) -> Vec<Segment> {
    let mut out = Vec::new();
    for &(t, id, x, y, flags) in steps {
        let now = Micros(t * MS);
        seg.tick(now, &mut out);
        let glass = Vec2::new(x, y);
        let p = TouchPoint {
            id: ContactId(id),
            world: glass / 100.0,
            glass_mm: glass,
            flags,
        };
        let on = crowd(p.world);
        seg.touch(now, &p, on, &mut out);
    }
    out
}

const D: ContactFlags = ContactFlags::DOWN;
const M: ContactFlags = ContactFlags::NONE;
const U: ContactFlags = ContactFlags::UP;

#[test]
fn one_two_three_fingers_make_point_line_area() {
    for n in 1..=4u32 {
        let mut seg = Segmenter::new(params());
        let mut steps = vec![];
        for i in 0..n {
            steps.push((i as u64 * 30, i + 1, 100.0 + 40.0 * i as f64, 100.0, D));
        }
        run(&mut seg, &steps, |_| true);
        assert_eq!(seg.controls().len(), 1);
        assert_eq!(seg.controls()[0].kind(), control_kind(n as usize));
    }
}

#[test]
fn late_finger_starts_a_new_control() {
    let mut seg = Segmenter::new(params());
    let out = run(
        &mut seg,
        &[(0, 1, 100.0, 100.0, D), (200, 2, 150.0, 100.0, D)],
        |_| true,
    );
    assert_eq!(seg.controls().len(), 2);
    assert_eq!(
        out,
        vec![Segment::ControlBegin(1), Segment::ControlBegin(2)]
    );
    assert!(seg
        .controls()
        .iter()
        .all(|c| c.kind() == ControlKind::Point));
}

#[test]
fn two_hands_far_apart_make_two_controls() {
    let mut seg = Segmenter::new(params());
    run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (10, 2, 100.0, 180.0, D),
            (20, 3, 600.0, 100.0, D),
            (30, 4, 640.0, 120.0, D),
            (40, 5, 620.0, 160.0, D),
        ],
        |_| true,
    );
    let kinds: Vec<_> = seg.controls().iter().map(|c| c.kind()).collect();
    assert_eq!(kinds, vec![ControlKind::Line, ControlKind::Area]);
}

#[test]
fn control_ends_when_last_finger_lifts_and_pins_the_first() {
    let mut seg = Segmenter::new(params());
    let out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (20, 2, 150.0, 100.0, D),
            (300, 1, 90.0, 100.0, U),
            (310, 2, 160.0, 100.0, M),
        ],
        |_| true,
    );
    assert_eq!(seg.controls().len(), 1);
    let c = &seg.controls()[0];
    assert_eq!(c.state, ControlState::Held);
    assert!(!c.fingers[0].down);
    assert_eq!(c.fingers[0].world, Vec2::new(0.9, 1.0));
    assert_eq!(out.len(), 2);
    let out = run(&mut seg, &[(400, 2, 170.0, 100.0, U)], |_| true);
    assert_eq!(
        out,
        vec![Segment::ControlEnd {
            id: 1,
            kind: ControlKind::Line,
            cancelled: false
        }]
    );
    assert!(seg.controls().is_empty());
}

#[test]
fn gesture_ends_after_grace_and_a_quick_refinger_continues_it() {
    let mut seg = Segmenter::new(params());
    let off = |_: Vec2| false;
    let mut out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (100, 1, 120.0, 100.0, U),
            (200, 2, 130.0, 100.0, D),
        ],
        off,
    );
    assert_eq!(out, vec![Segment::GestureBegin(1)]);
    out = run(&mut seg, &[(300, 2, 140.0, 100.0, U)], off);
    assert!(out.is_empty());
    seg.tick(Micros(500 * MS), &mut out);
    assert!(out.is_empty(), "grace not over yet: {out:?}");
    seg.tick(Micros(551 * MS), &mut out);
    assert_eq!(
        out,
        vec![Segment::GestureEnd {
            id: 1,
            fingers: 1,
            // Back 100 ms after its lift and 10 mm on: the same finger again.
            contacts: 1,
            duration: Micros(300 * MS),
            cancelled: false
        }]
    );
    assert!(seg.gestures().is_empty());
}

#[test]
fn cancelled_contact_is_reported_as_cancelled() {
    let mut seg = Segmenter::new(params());
    let out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (50, 1, 100.0, 100.0, ContactFlags::CANCELLED),
        ],
        |_| true,
    );
    assert_eq!(
        out[1],
        Segment::ControlEnd {
            id: 1,
            kind: ControlKind::Point,
            cancelled: true
        }
    );
}

#[test]
fn down_and_up_in_one_coalesced_frame_begins_and_ends() {
    let mut seg = Segmenter::new(params());
    let out = run(&mut seg, &[(0, 1, 100.0, 100.0, D | U)], |_| true);
    assert_eq!(out.len(), 2);
    assert!(matches!(out[1], Segment::ControlEnd { .. }));
    assert!(seg.controls().is_empty());
}

#[test]
fn palms_are_ignored() {
    let mut seg = Segmenter::new(params());
    let out = run(
        &mut seg,
        &[(0, 1, 100.0, 100.0, D | ContactFlags::PALM)],
        |_| true,
    );
    assert!(out.is_empty());
    assert!(seg.controls().is_empty());
    assert_eq!(seg.bad_transitions, 0);
}

#[test]
fn a_finger_landing_after_the_grace_starts_a_new_gesture() {
    let mut seg = Segmenter::new(params());
    let off = |_: Vec2| false;
    let mut out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (100, 1, 120.0, 100.0, U),
            (400, 2, 125.0, 100.0, D),
        ],
        off,
    );
    assert_eq!(out[0], Segment::GestureBegin(1));
    assert!(matches!(out[1], Segment::GestureEnd { id: 1, .. }));
    assert_eq!(out[2], Segment::GestureBegin(2));
    out.clear();
    // A finger joining mid-gesture, far from the first but within a hand span.
    out = run(&mut seg, &[(450, 3, 250.0, 180.0, D)], off);
    assert!(out.is_empty(), "{out:?}");
    assert_eq!(seg.gestures()[0].fingers.len(), 2);
}

#[test]
fn every_touch_is_a_gesture_when_switched_on() {
    let mut seg = Segmenter::new(params());
    seg.set_all_touches_are_gestures(true);
    assert!(seg.all_touches_are_gestures());
    let out = run(
        &mut seg,
        &[(0, 1, 100.0, 100.0, D), (20, 2, 140.0, 100.0, D)],
        |_| true,
    );
    assert_eq!(out, vec![Segment::GestureBegin(1)]);
    assert!(seg.controls().is_empty());
    assert_eq!(seg.gestures()[0].fingers.len(), 2);
    // Switched off again, the next touch on the crowd is a control.
    seg.set_all_touches_are_gestures(false);
    let out = run(&mut seg, &[(40, 3, 600.0, 600.0, D)], |_| true);
    assert_eq!(out, vec![Segment::ControlBegin(1)]);
}

#[test]
fn an_eleventh_finger_down_starts_a_new_gesture() {
    let mut seg = Segmenter::new(params());
    let steps: Vec<_> = (0..11u32)
        .map(|i| (i as u64 * 5, i + 1, 100.0 + 10.0 * i as f64, 100.0, D))
        .collect();
    let out = run(&mut seg, &steps, |_| false);
    assert_eq!(
        out,
        vec![Segment::GestureBegin(1), Segment::GestureBegin(2)]
    );
    assert_eq!(seg.gestures()[0].fingers.len(), MAX_FINGERS);
    assert_eq!(seg.gestures()[0].max_down, MAX_FINGERS as u32);
    assert_eq!(seg.gestures()[1].fingers.len(), 1);
}

#[test]
fn a_finger_tapping_on_one_spot_beside_a_resting_one_is_two_fingers() {
    let mut seg = Segmenter::new(params());
    let mut steps = vec![(0, 100, 300.0, 100.0, D)];
    // Taps of 50 ms, 10 ms apart.
    for k in 0..2 * MAX_GESTURE_CONTACTS as u64 {
        steps.push((10 + 60 * k, 1 + k as u32, 320.0, 100.0, D));
        steps.push((60 + 60 * k, 1 + k as u32, 320.0, 100.0, U));
    }
    let out = run(&mut seg, &steps, |_| false);
    assert_eq!(out, vec![Segment::GestureBegin(1)]);
    let g = &seg.gestures()[0];
    assert_eq!(g.fingers.len(), 2);
    assert_eq!(g.reattached, 2 * MAX_GESTURE_CONTACTS as u32 - 1);
    assert_eq!(g.max_down, 2);
}

#[test]
fn landings_past_a_full_gesture_reattach_instead_of_starting_one_each() {
    let mut seg = Segmenter::new(params());
    let mut steps = vec![(0, 100, 300.0, 100.0, D)];
    // Beside a resting finger, taps 40 mm apart (never re-attached by
    // distance): the twenty-first and later continue the nearest lifted finger.
    for k in 0..MAX_GESTURE_CONTACTS as u64 + 5 {
        let x = 200.0 + 40.0 * (k % 5) as f64;
        let y = 150.0 + 40.0 * (k / 5) as f64;
        steps.push((10 + 60 * k, 1 + k as u32, x, y, D));
        steps.push((60 + 60 * k, 1 + k as u32, x, y, U));
    }
    let out = run(&mut seg, &steps, |_| false);
    assert_eq!(out, vec![Segment::GestureBegin(1)], "one gesture");
    let g = &seg.gestures()[0];
    assert_eq!(g.fingers.len(), MAX_GESTURE_CONTACTS);
    assert_eq!(g.reattached, 6);
    assert_eq!(g.max_down, 2);
}

#[test]
fn a_new_tracking_id_in_the_same_frame_is_the_same_finger() {
    let mut seg = Segmenter::new(params());
    let off = |_: Vec2| false;
    let out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (0, 2, 130.0, 100.0, D),
            (10, 1, 105.0, 100.0, M),
            (10, 2, 135.0, 100.0, M),
            // The device re-identifies finger 1: id 1 ends, id 7 begins.
            (20, 1, 110.0, 100.0, U),
            (20, 7, 110.0, 100.0, D),
            (20, 2, 140.0, 100.0, M),
            (30, 7, 115.0, 100.0, M),
            (30, 2, 145.0, 100.0, M),
        ],
        off,
    );
    assert_eq!(out, vec![Segment::GestureBegin(1)]);
    let g = &seg.gestures()[0];
    assert_eq!(g.fingers.len(), 2);
    assert_eq!(g.fingers[0].id, ContactId(7));
    assert!(g.fingers.iter().all(|f| f.down));
    assert_eq!(g.fingers[0].glass_mm, Vec2::new(115.0, 100.0));
    assert_eq!(g.spans[0].t_down, Micros(0));
    assert_eq!((g.max_down, g.reattached), (2, 1));
}

#[test]
fn a_finger_back_too_late_or_too_far_is_a_new_finger() {
    for (t_ms, x) in [(150, 110.0), (40, 160.0)] {
        let mut seg = Segmenter::new(params());
        run(
            &mut seg,
            &[
                (0, 1, 100.0, 100.0, D),
                (0, 2, 300.0, 100.0, D),
                (20, 1, 100.0, 100.0, U),
                (20 + t_ms, 3, x, 100.0, D),
            ],
            |_| false,
        );
        let g = &seg.gestures()[0];
        assert_eq!(g.fingers.len(), 3, "{t_ms} ms, {x} mm");
        assert_eq!(g.reattached, 0);
    }
}

#[test]
fn ghosts_are_not_counted_but_a_two_finger_tap_is() {
    let off = |_: Vec2| false;
    // A third contact for 20 ms between two fingers down: a ghost.
    let mut seg = Segmenter::new(params());
    let mut out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (5, 2, 160.0, 100.0, D),
            (100, 3, 130.0, 100.0, D),
            (120, 3, 130.0, 100.0, U),
            (400, 1, 100.0, 100.0, U),
            (400, 2, 160.0, 100.0, U),
        ],
        off,
    );
    seg.tick(Micros(700 * MS), &mut out);
    assert!(
        matches!(
            out.last(),
            Some(Segment::GestureEnd {
                fingers: 2,
                contacts: 3,
                ..
            })
        ),
        "{out:?}"
    );
    // Two fingers landing and lifting together after 30 ms: two fingers.
    let mut seg = Segmenter::new(params());
    let mut out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (0, 2, 140.0, 100.0, D),
            (30, 1, 100.0, 100.0, U),
            (30, 2, 140.0, 100.0, U),
        ],
        off,
    );
    seg.tick(Micros(400 * MS), &mut out);
    assert!(
        matches!(out.last(), Some(Segment::GestureEnd { fingers: 2, .. })),
        "{out:?}"
    );
    assert!(seg.gestures().is_empty());
}

#[test]
fn a_finger_of_the_hand_landing_late_joins_the_nearest_gesture() {
    let off = |_: Vec2| false;
    let mut seg = Segmenter::new(params());
    // Two people 400 mm apart; a finger lands 140 ms later beside the second
    // (within both gestures' span): it joins the nearer.
    let out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (10, 2, 300.0, 100.0, D),
            (150, 3, 290.0, 150.0, D),
        ],
        off,
    );
    assert_eq!(
        out,
        vec![Segment::GestureBegin(1)],
        "span 200 mm: one gesture"
    );
    let mut seg = Segmenter::new(SegmentParams {
        gesture_span_mm: 150.0,
        ..params()
    });
    let out = run(
        &mut seg,
        &[
            (0, 1, 100.0, 100.0, D),
            (10, 2, 300.0, 100.0, D),
            (150, 3, 290.0, 150.0, D),
        ],
        off,
    );
    assert_eq!(
        out,
        vec![Segment::GestureBegin(1), Segment::GestureBegin(2)]
    );
    assert_eq!(seg.gestures()[1].fingers.len(), 2);
    assert_eq!(seg.gestures()[1].max_down, 2);
}

#[test]
fn a_hand_straddling_the_crowd_edge_stays_one_control_or_one_gesture() {
    let crowd = |p: Vec2| p.x < 2.0; // the crowd is left of x = 200 mm
                                     // First finger on the crowd, two more just off it within 150 ms: an area
                                     // control of three.
    let mut seg = Segmenter::new(params());
    let out = run(
        &mut seg,
        &[
            (0, 1, 180.0, 100.0, D),
            (60, 2, 205.0, 110.0, D),
            (140, 3, 230.0, 120.0, D),
        ],
        crowd,
    );
    assert_eq!(
        out,
        vec![
            Segment::ControlBegin(1),
            Segment::ControlUpdate(1),
            Segment::ControlUpdate(1)
        ]
    );
    assert_eq!(seg.controls()[0].kind(), ControlKind::Area);
    assert!(seg.gestures().is_empty());
    // First finger off the crowd, the next on its edge 80 ms later: one gesture.
    let mut seg = Segmenter::new(params());
    let out = run(
        &mut seg,
        &[(0, 1, 230.0, 100.0, D), (80, 2, 190.0, 110.0, D)],
        crowd,
    );
    assert_eq!(out, vec![Segment::GestureBegin(1)]);
    assert!(seg.controls().is_empty());
    assert_eq!(seg.gestures()[0].max_down, 2);
    // After the grouping window a finger on the crowd is a control of its own.
    let out = run(&mut seg, &[(300, 3, 150.0, 100.0, D)], crowd);
    assert_eq!(out, vec![Segment::ControlBegin(1)]);
}
