//! Formation transforms in the engine, as a client sees them: `set_formation`
//! with method `transform` (the default) runs the paper's model to the new shape
//! with progress messages, a summary and a `formation` event, then touch control
//! goes on on the new shape; the pairing is the one the transform planned (nothing
//! overwrites it); a touch takes the crowd back; a newer request starts from where
//! the agents are; `mesh` still switches at once; bad requests change nothing;
//! sessions are deterministic.

use crowdtouch::config::{Config, GestureFormation, TransformCost};
use crowdtouch::engine::{Engine, TOUCHED_FORMATION};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::MotionClass;
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle};
use crowdtouch::publish::protocol::{
    encode_snapshot_json, encode_transform_end_json, encode_transform_json, FieldSet,
};
use crowdtouch::vocab::{
    Command, Contact, ContactFlags, ContactId, Event, FormationMethod, Micros, TouchFrame,
    TransformOutcome, TransformSummary, TransformView,
};
use std::sync::Arc;

/// Tick period (µs): 60 Hz.
const TICK_US: u64 = 16_667;
/// Longest a test waits for a transform to end (virtual s).
const MAX_WAIT_S: f64 = 60.0;

fn config(agents: u32) -> Config {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    cfg
}

/// An engine that prepares everything in the tick (as replays do).
fn engine(cfg: &Config) -> (Engine, u64) {
    let mut e = Engine::new(cfg, None, true);
    e.tick(Micros(TICK_US));
    e.clear_events();
    (e, TICK_US)
}

/// What ticks published.
#[derive(Default)]
struct Seen {
    views: Vec<Arc<TransformView>>,
    ends: Vec<Arc<TransformSummary>>,
    events: Vec<Event>,
    /// Per tick: each agent's goal position in the snapshot.
    goals: Vec<Vec<Vec2>>,
}

fn tick(e: &mut Engine, now: &mut u64, seen: &mut Seen) {
    *now += TICK_US;
    let o = e.tick(Micros(*now));
    if let Some(v) = &o.transform {
        seen.views.push(Arc::clone(v));
    }
    if let Some(s) = &o.transform_end {
        seen.ends.push(Arc::clone(s));
    }
    seen.events.extend(o.events.iter().cloned());
    let s = &o.snapshot;
    seen.goals
        .push(s.agents.iter().map(|a| s.goals[a.goal as usize]).collect());
    e.clear_events();
}

/// Ticks until a `formation` event for `name` (or the wait is over).
fn run_until_formation(e: &mut Engine, now: &mut u64, seen: &mut Seen, name: &str) -> bool {
    let end = *now + (MAX_WAIT_S * 1e6) as u64;
    while *now < end {
        tick(e, now, seen);
        if seen
            .events
            .iter()
            .any(|ev| matches!(ev, Event::Formation { name: n, .. } if n == name))
        {
            return true;
        }
    }
    false
}

fn centroid(ps: &[Vec2]) -> Vec2 {
    ps.iter().sum::<Vec2>() / ps.len().max(1) as f64
}

/// A one-finger drag from `from` to `to` (unit-square surface coordinates) over
/// `ticks` ticks, then held there.
fn drag(
    e: &mut Engine,
    now: &mut u64,
    seen: &mut Seen,
    from: (f32, f32),
    to: (f32, f32),
    ticks: u32,
) {
    for k in 0..=ticks {
        let a = k as f32 / ticks as f32;
        let mut f = TouchFrame::new(Micros(*now + 1));
        f.push(Contact {
            id: ContactId(7),
            x: from.0 + a * (to.0 - from.0),
            y: from.1 + a * (to.1 - from.1),
            pressure: None,
            major_mm: None,
            minor_mm: None,
            flags: if k == 0 {
                ContactFlags::DOWN
            } else {
                ContactFlags::NONE
            },
        })
        .unwrap();
        e.push_frame(&f);
        tick(e, now, seen);
    }
}

/// The world point of surface coordinates (the default config's world).
fn surface_of(e: &Engine, p: Vec2) -> (f32, f32) {
    let w = e.world();
    (
        ((p.x - w.min[0]) / w.width()) as f32,
        ((p.y - w.min[1]) / w.height()) as f32,
    )
}

#[test]
fn a_transform_reports_progress_ends_with_a_summary_then_touch_control_goes_on() {
    let cfg = config(60);
    let (mut e, mut now) = engine(&cfg);
    e.command(
        &Command::SetFormation {
            formation: "arrow".into(),
            method: None,
            duration: None,
        },
        Micros(now),
    )
    .unwrap();
    let mut seen = Seen::default();
    assert!(run_until_formation(&mut e, &mut now, &mut seen, "arrow"));
    // Progress every tick of the run, rising to every agent arrived.
    assert!(
        seen.views.len() > 10,
        "{} progress messages",
        seen.views.len()
    );
    assert!(seen.views.iter().all(|v| &*v.formation == "arrow"
        && v.method == "transform"
        && v.cost == "least_effort"
        && (0.0..=1.0).contains(&v.progress)));
    let first = seen.views.first().unwrap();
    let last = seen.views.last().unwrap();
    assert!(first.progress < 0.5, "first progress {}", first.progress);
    assert_eq!(last.progress, 1.0);
    assert!(last.elapsed_s > first.elapsed_s);
    // One summary, before the formation event, saying every agent arrived.
    assert_eq!(seen.ends.len(), 1);
    let s = &seen.ends[0];
    assert_eq!(s.outcome, TransformOutcome::Arrived);
    assert_eq!((s.agents, s.arrived_fraction), (60, 1.0));
    assert!(s.steps > 0 && s.simulated_s > 0.0 && s.mean_travel_m > 0.0);
    assert_eq!(e.formation(), "arrow");
    assert_eq!(e.transforms_started(), 1);
    assert!(!e.transform_running());
    // Touch control on the new shape: a drag from the crowd's middle moves it.
    let c0 = centroid(e.agent_positions());
    let from = surface_of(&e, c0);
    drag(
        &mut e,
        &mut now,
        &mut seen,
        from,
        (from.0 + 0.1, from.1),
        30,
    );
    for _ in 0..120 {
        tick(&mut e, &mut now, &mut seen);
    }
    let c1 = centroid(e.agent_positions());
    let moved = c1 - c0;
    assert!(
        moved.x > 0.3 && moved.y.abs() < 0.5 * moved.x,
        "the drag moved the crowd by {moved:?}"
    );
}

#[test]
fn the_planned_pairing_is_used_and_lambda_changes_it() {
    let run = |lambda: f64| {
        let mut cfg = config(60);
        cfg.formations.lambda = lambda;
        cfg.formations.cost = TransformCost::LeastEffort;
        let (mut e, mut now) = engine(&cfg);
        e.set_formation("wedge", Micros(now)).unwrap();
        let mut seen = Seen::default();
        tick(&mut e, &mut now, &mut seen);
        let targets = e.transform_targets().expect("a transform runs").to_vec();
        // Every tick of the run: each agent's goal is its target in the run, and
        // the engine's pairing is the identity over the targets; the run's targets
        // are the planned ones but for the pairs that exchanged theirs.
        let mut ticks = 0;
        let mut last = targets.clone();
        while let Some(now_targets) = e.transform_targets() {
            last = now_targets.to_vec();
            assert!(e
                .goal_of()
                .iter()
                .enumerate()
                .all(|(i, &g)| g as usize == i));
            assert_eq!(seen.goals.last().unwrap(), &last);
            tick(&mut e, &mut now, &mut seen);
            ticks += 1;
            assert!(ticks < 10_000, "the transform never ended");
        }
        let moved = targets.iter().zip(&last).filter(|(p, q)| p != q).count();
        let swaps = seen.ends[0].swaps as usize;
        assert!(moved <= 2 * swaps, "{moved} targets changed, {swaps} swaps");
        (targets, seen.ends[0].clone())
    };
    let (t0, s0) = run(0.0);
    let (t1, s1) = run(1.0);
    // The same targets (same seed, same start), paired differently.
    let key = |v: &Vec2| ((v.x * 1e6) as i64, (v.y * 1e6) as i64);
    let mut a: Vec<_> = t0.iter().map(key).collect();
    let mut b: Vec<_> = t1.iter().map(key).collect();
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b, "the sampled targets differ");
    let differ = t0
        .iter()
        .zip(&t1)
        .filter(|(p, q)| (*p - *q).norm() > 1e-9)
        .count();
    assert!(differ > 0, "lambda 0 and 1 paired the same");
    // λ = 1 pairs by travel alone: it walks no farther in total than λ = 0.
    assert!(
        s1.mean_travel_m <= s0.mean_travel_m + 1e-9,
        "{} vs {}",
        s1.mean_travel_m,
        s0.mean_travel_m
    );
    assert_ne!(s0.mean, s1.mean);
}

#[test]
fn a_touch_on_the_crowd_during_a_transform_returns_to_direct_control() {
    let cfg = config(60);
    let (mut e, mut now) = engine(&cfg);
    e.set_formation("line", Micros(now)).unwrap();
    let mut seen = Seen::default();
    for _ in 0..20 {
        tick(&mut e, &mut now, &mut seen);
    }
    assert!(e.transform_running());
    let before = e.agent_positions().to_vec();
    let c0 = centroid(&before);
    // On an agent (the crowd's mesh is elsewhere by now).
    let on = e.agent_positions()[0];
    let from = surface_of(&e, on);
    drag(
        &mut e,
        &mut now,
        &mut seen,
        from,
        (from.0, from.1 - 0.08),
        30,
    );
    assert_eq!(seen.ends.len(), 1);
    assert_eq!(seen.ends[0].outcome, TransformOutcome::Touched);
    assert!(seen.ends[0].arrived_fraction < 1.0);
    assert!(!e.transform_running());
    assert_eq!(e.formation(), TOUCHED_FORMATION);
    assert!(!seen
        .events
        .iter()
        .any(|ev| matches!(ev, Event::Formation { .. })));
    for _ in 0..120 {
        tick(&mut e, &mut now, &mut seen);
    }
    // The drag (upwards on the surface is -y in the world) moved the crowd.
    let c1 = centroid(e.agent_positions());
    assert!((c1 - c0).norm() > 0.2, "moved {:?}", c1 - c0);
    let views_after = seen
        .views
        .iter()
        .filter(|v| v.seq > seen.views[0].seq + 1_000)
        .count();
    assert_eq!(views_after, 0);
}

#[test]
fn a_request_during_a_transform_starts_from_where_the_agents_are() {
    let cfg = config(60);
    let (mut e, mut now) = engine(&cfg);
    e.set_formation("column", Micros(now)).unwrap();
    let mut seen = Seen::default();
    for _ in 0..30 {
        tick(&mut e, &mut now, &mut seen);
    }
    let mid = e.agent_positions().to_vec();
    e.set_formation_by(
        "diamond",
        Some(FormationMethod::Transform),
        None,
        Micros(now),
    )
    .unwrap();
    tick(&mut e, &mut now, &mut seen);
    assert_eq!(seen.ends.len(), 1);
    assert_eq!(seen.ends[0].outcome, TransformOutcome::Superseded);
    assert_eq!(seen.ends[0].formation, "column");
    assert_eq!(&*seen.views.last().unwrap().formation, "diamond");
    // Nobody jumped: the new run starts where the agents were (one tick at
    // walking speed from there).
    let jump = e
        .agent_positions()
        .iter()
        .zip(&mid)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(jump < 0.1, "an agent moved {jump} m in one tick");
    assert!(run_until_formation(&mut e, &mut now, &mut seen, "diamond"));
    assert_eq!(e.formation(), "diamond");
    assert_eq!(e.transforms_started(), 2);
    assert!(!seen
        .events
        .iter()
        .any(|ev| matches!(ev, Event::Formation { name, .. } if name == "column")));
}

#[test]
fn method_mesh_switches_at_once_and_bad_requests_change_nothing() {
    let cfg = config(40);
    let (mut e, mut now) = engine(&cfg);
    let mut seen = Seen::default();
    e.set_formation_by("arrow", Some(FormationMethod::Mesh), None, Micros(now))
        .unwrap();
    tick(&mut e, &mut now, &mut seen);
    assert!(seen
        .events
        .iter()
        .any(|ev| matches!(ev, Event::Formation { name, .. } if name == "arrow")));
    assert!(seen.views.is_empty() && !e.transform_running());
    assert_eq!(e.transforms_started(), 0);
    // Unknown formation, bad durations: an error naming what is wrong; the crowd
    // goes on as it was.
    for _ in 0..10 {
        tick(&mut e, &mut now, &mut seen);
    }
    let before = (
        e.agent_positions().to_vec(),
        e.goal_of().to_vec(),
        e.generation(),
    );
    let err = e
        .set_formation_by("blob", None, None, Micros(now))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`blob`") && err.contains("start, square, arrow"),
        "{err}"
    );
    for d in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e9] {
        let err = e
            .set_formation_by("line", None, Some(d), Micros(now))
            .unwrap_err()
            .to_string();
        assert!(err.contains("duration"), "{err}");
    }
    assert_eq!(
        before,
        (
            e.agent_positions().to_vec(),
            e.goal_of().to_vec(),
            e.generation()
        )
    );
    assert!(!e.transform_running() && e.formation() == "arrow");
}

#[test]
fn a_duration_sets_how_long_the_transform_takes() {
    let took = |d: f64| {
        let (mut e, mut now) = engine(&config(40));
        e.set_formation_by("line", None, Some(d), Micros(now))
            .unwrap();
        let mut seen = Seen::default();
        assert!(run_until_formation(&mut e, &mut now, &mut seen, "line"));
        // When a third of the crowd had arrived (s).
        let third = seen
            .views
            .iter()
            .find(|v| v.progress >= 1.0 / 3.0)
            .map(|v| v.elapsed_s)
            .expect("a third arrived");
        (third, seen.ends[0].speed_m_s)
    };
    let (fast_s, fast_v) = took(2.0);
    let (slow_s, slow_v) = took(8.0);
    assert!(fast_v > slow_v, "{fast_v} vs {slow_v} m/s");
    assert!(fast_s < slow_s, "{fast_s} vs {slow_s} s");
}

#[test]
fn a_transform_back_to_start_ends_in_the_start_rectangle() {
    let cfg = config(60);
    let (mut e, mut now) = engine(&cfg);
    let mut seen = Seen::default();
    e.set_formation("arrow", Micros(now)).unwrap();
    assert!(run_until_formation(&mut e, &mut now, &mut seen, "arrow"));
    seen.events.clear();
    e.set_formation("start", Micros(now)).unwrap();
    assert!(run_until_formation(&mut e, &mut now, &mut seen, "start"));
    assert_eq!(seen.ends.len(), 2);
    assert_eq!(seen.ends[1].outcome, TransformOutcome::Arrived);
    assert_eq!(e.formation(), "start");
    // Every agent inside a rectangle of the start's size around the crowd.
    let r = cfg.crowd.formation;
    let ps = e.agent_positions();
    let c = centroid(ps);
    let slack = cfg.crowd.agent_radius_m;
    for p in ps {
        assert!(
            (p.x - c.x).abs() <= 0.5 * r.width() + slack
                && (p.y - c.y).abs() <= 0.5 * r.height() + slack,
            "{p:?} outside the start rectangle around {c:?}"
        );
    }
}

#[test]
fn reset_drops_a_transform() {
    let (mut e, mut now) = engine(&config(40));
    e.set_formation("arrow", Micros(now)).unwrap();
    let mut seen = Seen::default();
    for _ in 0..10 {
        tick(&mut e, &mut now, &mut seen);
    }
    e.reset(false, Micros(now));
    tick(&mut e, &mut now, &mut seen);
    assert!(!e.transform_running());
    assert_eq!(seen.ends.last().unwrap().outcome, TransformOutcome::Dropped);
    assert_eq!(e.formation(), "start");
    let n = seen.views.len();
    for _ in 0..10 {
        tick(&mut e, &mut now, &mut seen);
    }
    assert_eq!(seen.views.len(), n, "progress after the reset");
}

/// Every snapshot, progress and summary line of a session with two transforms
/// and a drag.
fn session_bytes() -> Vec<u8> {
    let (mut e, mut now) = engine(&config(50));
    let mut out = Vec::new();
    let step = |e: &mut Engine, now: &mut u64, out: &mut Vec<u8>| {
        *now += TICK_US;
        let o = e.tick(Micros(*now));
        encode_snapshot_json(&o.snapshot, None, 0, &FieldSet::ALL, out);
        if let Some(v) = &o.transform {
            encode_transform_json(v, out);
        }
        if let Some(s) = &o.transform_end {
            encode_transform_end_json(s, out);
        }
        e.clear_events();
    };
    e.set_formation("arrow", Micros(now)).unwrap();
    for _ in 0..40 {
        step(&mut e, &mut now, &mut out);
    }
    e.set_formation("square", Micros(now)).unwrap();
    for _ in 0..400 {
        step(&mut e, &mut now, &mut out);
    }
    out
}

#[test]
fn a_session_with_transforms_is_deterministic() {
    let a = session_bytes();
    let b = session_bytes();
    assert!(a.len() > 10_000);
    assert!(a == b, "two runs of the same session differ");
}

#[test]
fn a_mapped_gesture_starts_a_transform_instead_of_its_motion() {
    let mut cfg = config(40);
    cfg.formations.gestures = vec![GestureFormation {
        class: "expand".into(),
        formation: "diamond".into(),
    }];
    let glass = (1210.0, 680.0);
    let mut e = Engine::new(&cfg, Some(glass), true);
    let style = GestureStyle {
        fingers: vec![3],
        duration_s: 1.0,
        size_mm: 150.0,
        placement: Vec2::new(0.17, 0.5),
        orientation_rad: 0.0,
        jitter_mm: 0.3,
        device_mm: glass,
        rate_hz: 120.0,
        stagger_ms: 30.0,
        early_lifts: 0,
        bow: 0.0,
        spacing_mm: 20.0,
        clockwise: false,
    };
    let frames = to_frames(
        &generate(MotionClass::Expand, &style, 3),
        glass,
        Micros(500_000),
    );
    let mut seen = Seen::default();
    let mut now = 0;
    for f in &frames {
        e.push_frame(f);
        now = f.t.0;
        let o = e.tick(f.t);
        seen.events.extend(o.events.iter().cloned());
        if let Some(v) = &o.transform {
            seen.views.push(Arc::clone(v));
        }
        e.clear_events();
    }
    assert!(run_until_formation(&mut e, &mut now, &mut seen, "diamond"));
    let recognised = seen.events.iter().find_map(|ev| match ev {
        Event::GestureEnd { recognition, .. } => recognition.as_ref().map(|r| r.class.clone()),
        _ => None,
    });
    assert_eq!(recognised.as_deref(), Some("expand"));
    assert!(!seen
        .events
        .iter()
        .any(|ev| matches!(ev, Event::GestureMotion { .. })));
    assert!(seen.views.iter().all(|v| &*v.formation == "diamond"));
}

/// A crowd shrunk to fit its area (2,000 agents in the default 12 m², radius 3.5
/// cm instead of 15: the model's lengths scale with it) transforms to the arrow and
/// back, each agent to its own target, without overlap. Slow in a debug build.
#[test]
#[ignore = "slow in debug: cargo test --release --test engine_transforms -- --ignored"]
fn a_crowd_shrunk_to_fit_transforms_and_arrives() {
    let cfg = config(2000);
    let (mut e, mut now) = engine(&cfg);
    let mut seen = Seen::default();
    for target in ["arrow", "start"] {
        seen.events.clear();
        e.set_formation(target, Micros(now)).unwrap();
        let arrived = run_until_formation(&mut e, &mut now, &mut seen, target);
        let last = seen.views.last().map(|v| (v.progress, v.elapsed_s));
        assert!(arrived, "{target}: not arrived, last progress {last:?}");
        let end = seen.ends.last().unwrap();
        assert_eq!(end.outcome, TransformOutcome::Arrived, "{target}");
        assert_eq!(end.overlapping_pairs, 0, "{target}: {end:?}");
    }
}
