//! Continuous recognition (`gestures.continuous`): a long gesture commands the crowd
//! while it is still being drawn, once its class has stayed ahead for the hold time.

use crowdtouch::config::{Config, ContinuousConfig};
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::MotionClass;
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle, StyleRanges};
use crowdtouch::vocab::{Event, Micros, MotionPhase};
use std::convert::Infallible;

/// A slow three-finger translate to the right, drawn for `seconds`, in the glass's
/// lower left (away from the default crowd in the middle).
fn long_translate(seconds: f64) -> (Vec<crowdtouch::vocab::TouchFrame>, (f64, f64)) {
    let mut style = GestureStyle::random(MotionClass::Translate, 3, &StyleRanges::default());
    style.fingers = vec![3];
    style.duration_s = seconds;
    style.size_mm = 400.0;
    style.device_mm = (1210.0, 680.0);
    style.placement = Vec2::new(0.5, 0.85);
    style.orientation_rad = 0.0;
    style.early_lifts = 0;
    style.rate_hz = 100.0;
    let tracks = generate(MotionClass::Translate, &style, 11);
    (
        to_frames(&tracks, style.device_mm, Micros(1_000_000)),
        style.device_mm,
    )
}

fn run(cfg: &Config, seconds: f64) -> Vec<(Micros, Event)> {
    let (frames, glass) = long_translate(seconds);
    let mut engine = Engine::new(cfg, Some(glass), true);
    let clock = VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros::from_secs_f64(1.0),
        max_gap: Micros(2_000_000),
    };
    let mut events = Vec::new();
    replay_virtual(
        &mut engine,
        frames.iter().map(|f| Ok(*f)),
        clock,
        |_| {},
        |o| {
            events.extend(o.events.iter().map(|e| (o.snapshot.t, e.clone())));
            Ok::<(), Infallible>(())
        },
    )
    .unwrap();
    events
}

#[test]
fn a_long_gesture_fires_while_it_is_drawn_and_ends_with_that_recognition() {
    let mut cfg = Config::embedded_default();
    cfg.gestures.continuous = Some(ContinuousConfig {
        window_ms: 1000,
        hold_ms: 500,
    });
    let events = run(&cfg, 4.0);
    let start = events
        .iter()
        .find(|(_, e)| matches!(e, Event::GestureBegin { .. }))
        .map(|(t, _)| *t)
        .expect("a gesture began");
    let motion = events
        .iter()
        .find(|(_, e)| {
            matches!(e, Event::GestureMotion { phase: MotionPhase::Approach, class, .. } if class == "translate")
        })
        .map(|(t, _)| *t)
        .expect("a translate motion started");
    let end = events
        .iter()
        .find_map(|(t, e)| match e {
            Event::GestureEnd { recognition, .. } => Some((*t, recognition.clone())),
            _ => None,
        })
        .expect("the gesture ended");
    // Fired after the window and the hold (1.5 s), well before the 4 s gesture ended.
    let fired_after = motion.saturating_since(start).as_secs_f64();
    assert!(
        (1.4..3.0).contains(&fired_after),
        "fired {fired_after} s in"
    );
    assert!(motion < end.0);
    assert_eq!(end.1.map(|r| r.class), Some("translate".to_string()));
}

#[test]
fn without_continuous_recognition_the_motion_waits_for_the_end() {
    let cfg = Config::embedded_default();
    assert!(cfg.gestures.continuous.is_none());
    let events = run(&cfg, 4.0);
    let end = events
        .iter()
        .position(|(_, e)| matches!(e, Event::GestureEnd { .. }))
        .expect("the gesture ended");
    let motion = events
        .iter()
        .position(|(_, e)| matches!(e, Event::GestureMotion { .. }))
        .expect("a motion started");
    assert!(motion > end);
}
