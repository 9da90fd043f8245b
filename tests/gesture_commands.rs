//! Gesture commands end to end (issue 15, "Done when" 1): a gesture of each of the
//! ten classes, made by the generator of human-like gestures, written as a JSONL
//! recording and replayed through the engine on a virtual clock, is recognised as
//! the class drawn, plays a crowd motion (`gesture_motion` approach → follow → done)
//! that does what the class says (gesture-driven-crowd-motion sections 5–7), keeps
//! the crowd's formation (issue 34: `gestures.apply: keep_formation`, the default;
//! each part's for a split) and leaves a mesh over the formation moved, on which
//! the agents settle. One test plays the paper's way (`as_sampled`): the mesh is
//! then rebuilt around the crowd where it stopped.
//!
//! Every gesture is drawn with 3 fingers (2 per hand for the two-hand classes),
//! 150 mm, on the default config's 1210 × 680 mm glass, left of the crowd: the
//! glass maps onto the 16 × 9 m world, the crowd starts in (6, 3)..(10, 6) m, and
//! the gestures stay within x < 4.5 m, beyond the 0.5 m grab radius.

mod common;

use common::{centroid, Run};
use crowdtouch::config::Config;
use crowdtouch::crowd::motion::measure;
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::MotionClass;
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle};
use crowdtouch::gesture::track::GestureTracks;
use crowdtouch::input::recording::{load_recording, OnBadFrame};
use crowdtouch::vocab::{Event, Micros, MotionPhase};
use std::path::Path;
use std::sync::Arc;

/// Virtual time replayed after the mesh is rebuilt around the stopped crowd (s).
const AFTER_MESH_S: f64 = 1.0;

/// The default config's glass (mm).
const GLASS_MM: (f64, f64) = (1210.0, 680.0);

/// Virtual time after the recording's last frame: the approach (at most the
/// config's 3 s), the motion (a few seconds at 1 m/s) and the remesh.
const SETTLE_S: f64 = 16.0;

/// How far an agent may be from the rebuilt mesh's vertices (its goals) once the
/// crowd has settled on it (m).
const SETTLED_M: f64 = 0.05;

/// `gestures.min_piece_agents` of the default config.
const MIN_PIECE_AGENTS: usize = crowdtouch::config::DEFAULT_MIN_PIECE_AGENTS as usize;

/// Whether the class divides the crowd in two.
fn split_class(c: MotionClass) -> bool {
    matches!(c, MotionClass::Split | MotionClass::SplitThenTranslate)
}

/// Whether `p` lies inside the closed polygon `poly` (even–odd rule).
fn point_in_polygon(p: Vec2, poly: &[Vec2]) -> bool {
    let mut inside = false;
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// The two groups of `pts` (2-means from the ends of the principal axis).
/// Every piece of `mesh` (one outline each) holds at least
/// `MIN_PIECE_AGENTS` of `agents`, with one agent of slack for agents on an
/// outline; `label` names the case in the failure.
fn assert_every_piece_holds_agents(
    mesh: &crowdtouch::vocab::MeshView,
    agents: &[crowdtouch::vocab::AgentView],
    label: impl std::fmt::Display,
) {
    let pieces = mesh.outlines.len();
    for (k, outline) in mesh.outlines.iter().enumerate() {
        let poly: Vec<Vec2> = outline.iter().map(|&v| mesh.vertices[v as usize]).collect();
        let inside = agents
            .iter()
            .filter(|a| point_in_polygon(a.pos, &poly))
            .count();
        assert!(
            inside + 1 >= MIN_PIECE_AGENTS,
            "{label}: mesh piece {k} of {pieces} holds {inside} agents"
        );
    }
}

fn two_parts(pts: &[Vec2]) -> Vec<Vec<usize>> {
    let c = centroid(pts.iter().copied());
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let d = p - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let axis = unit(0.5 * (2.0 * sxy).atan2(sxx - syy));
    let mut label: Vec<bool> = pts.iter().map(|p| (p - c).dot(&axis) > 0.0).collect();
    for _ in 0..50 {
        let mean = |side: bool| {
            centroid(
                pts.iter()
                    .zip(&label)
                    .filter(|(_, &l)| l == side)
                    .map(|(p, _)| *p),
            )
        };
        let (m0, m1) = (mean(false), mean(true));
        let next: Vec<bool> = pts
            .iter()
            .map(|p| (p - m1).norm_squared() < (p - m0).norm_squared())
            .collect();
        if next == label {
            break;
        }
        label = next;
    }
    [false, true]
        .map(|side| (0..pts.len()).filter(|&i| label[i] == side).collect())
        .into_iter()
        .collect()
}

/// The RMS distance between `b` and `a` moved by the least-squares similarity
/// (turn, scale, shift) onto it, over `a`'s RMS radius: 0 when `b` is `a`'s
/// formation moved.
fn procrustes_residual(a: &[Vec2], b: &[Vec2]) -> f64 {
    let (ca, cb) = (centroid(a.iter().copied()), centroid(b.iter().copied()));
    let (mut dot, mut cross, mut var) = (0.0, 0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (p, q) = (p - ca, q - cb);
        dot += p.dot(&q);
        cross += p.x * q.y - p.y * q.x;
        var += p.norm_squared();
    }
    let (theta, s) = (cross.atan2(dot), (dot * dot + cross * cross).sqrt() / var);
    let (sn, cs) = theta.sin_cos();
    let err: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| {
            let d = p - ca;
            let moved = cb + s * Vec2::new(cs * d.x - sn * d.y, sn * d.x + cs * d.y);
            (moved - q).norm_squared()
        })
        .sum::<f64>();
    (err / a.len() as f64).sqrt() / (var / a.len() as f64).sqrt()
}

fn style(class: MotionClass, orientation_rad: f64, clockwise: bool) -> GestureStyle {
    let two_hands = matches!(
        class,
        MotionClass::Join
            | MotionClass::Split
            | MotionClass::SplitThenTranslate
            | MotionClass::TranslateThenJoin
    );
    GestureStyle {
        fingers: if two_hands { vec![2, 2] } else { vec![3] },
        duration_s: 1.0,
        size_mm: 150.0,
        placement: Vec2::new(0.17, 0.5),
        orientation_rad,
        jitter_mm: 0.3,
        device_mm: GLASS_MM,
        rate_hz: 120.0,
        stagger_ms: 30.0,
        early_lifts: 0,
        bow: 0.0,
        spacing_mm: 20.0,
        clockwise,
    }
}

/// Writes `tracks` as a JSONL recording of the default glass (0.1 mm units).
fn write_recording(tracks: &GestureTracks, path: &Path) {
    let frames = to_frames(tracks, GLASS_MM, Micros(500_000));
    common::write_jsonl(&frames, GLASS_MM, "generated gesture", path);
}

/// Replays the recording at `path` through the engine (default config, inline
/// assignment and gesture work), ticking on after its last frame until
/// `AFTER_MESH_S` after the first mesh that follows a finished motion (at most
/// `SETTLE_S`).
fn replay_file(path: &Path) -> Run {
    replay(path, true)
}

/// [`replay_file`]; without `motion`, a gesture that plays none: ticking on until
/// `AFTER_MESH_S` after its end.
fn replay(path: &Path, motion: bool) -> Run {
    replay_with(path, motion, Config::embedded_default())
}

/// [`replay`] with `cfg`.
fn replay_with(path: &Path, motion: bool, mut cfg: Config) -> Run {
    // Timer ticks at 60 Hz (the recording's frames tick at its 120 Hz): half the
    // work of a debug build; motions are timed in seconds, not ticks.
    cfg.pipeline.tick_hz = 60.0;
    let rec = load_recording(path, OnBadFrame::Stop).unwrap();
    assert_eq!(rec.surface.size_mm(), Some(GLASS_MM));
    let mut engine = Engine::new(&cfg, rec.surface.size_mm(), true);
    let mut run = Run {
        snapshots: vec![],
        events: vec![],
        meshes: vec![],
    };
    let clock = VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros::from_secs_f64(SETTLE_S),
        max_gap: Micros(crowdtouch::input::replay::MAX_GAP_US),
    };
    // Set at the first mesh after `done`: stop this long after.
    let mut stop_at: Option<Micros> = None;
    let mut done = false;
    let stopped = replay_virtual(
        &mut engine,
        rec.frames.iter().map(|f| Ok(*f)),
        clock,
        |_| {},
        |o| {
            run.snapshots.push(Arc::clone(&o.snapshot));
            run.events.extend(o.events.iter().cloned());
            done |= o.events.iter().any(|e| {
                matches!(
                    e,
                    Event::GestureMotion {
                        phase: MotionPhase::Done | MotionPhase::Cancelled,
                        ..
                    }
                )
            });
            let ended = o
                .events
                .iter()
                .any(|e| matches!(e, Event::GestureEnd { .. }));
            if !motion && ended && stop_at.is_none() {
                stop_at = Some(o.snapshot.t + Micros::from_secs_f64(AFTER_MESH_S));
            }
            if let Some(m) = &o.mesh {
                run.meshes.push(Arc::clone(m));
                if done && stop_at.is_none() {
                    stop_at = Some(o.snapshot.t + Micros::from_secs_f64(AFTER_MESH_S));
                }
            }
            match stop_at {
                Some(t) if o.snapshot.t >= t => Err(Stop),
                _ => Ok(()),
            }
        },
    );
    assert!(
        !motion || stopped.is_err() || run.meshes.len() > 1,
        "no mesh after the motion within {SETTLE_S} s"
    );
    run
}

/// Ends a replay early.
#[derive(Debug)]
struct Stop;

/// A gesture of `class` generated, recorded, replayed.
struct Played {
    tracks: GestureTracks,
    run: Run,
}

fn play(class: MotionClass, orientation_rad: f64, clockwise: bool, seed: u64) -> Played {
    let tracks = generate(class, &style(class, orientation_rad, clockwise), seed);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{}.jsonl", class.as_str()));
    write_recording(&tracks, &path);
    let t = std::time::Instant::now();
    let run = replay_file(&path);
    eprintln!(
        "{class}: replayed {} ticks in {:?}",
        run.snapshots.len(),
        t.elapsed()
    );
    Played { tracks, run }
}

/// Where the fingers' centroid went, first samples to last (mm of glass; glass
/// and world share their axes).
fn finger_travel(t: &GestureTracks) -> Vec2 {
    let first = centroid(t.fingers.iter().map(|f| f.samples[0].mm));
    let last = centroid(t.fingers.iter().map(|f| f.samples.last().unwrap().mm));
    last - first
}

fn positions(run: &Run, k: usize) -> Vec<Vec2> {
    run.snapshots[k].agents.iter().map(|a| a.pos).collect()
}

/// What the user sees of one played gesture, checked for every class; returns the
/// agents' tracks (every 4th tick) from the first snapshot to the last.
fn check_common(class: MotionClass, p: &Played) -> Vec<Vec<Vec2>> {
    let run = &p.run;
    let ends: Vec<_> = run
        .events
        .iter()
        .filter_map(|e| match e {
            Event::GestureEnd {
                recognition,
                rejected,
                cancelled,
                ..
            } => Some((
                recognition.as_ref().map(|r| (r.class.clone(), r.weight)),
                rejected.clone(),
                *cancelled,
            )),
            _ => None,
        })
        .collect();
    assert_eq!(ends.len(), 1, "{class}: gesture ends {ends:?}");
    let (rec, rejected, cancelled) = &ends[0];
    assert!(!cancelled && rejected.is_none(), "{class}: {ends:?}");
    let (got, weight) = rec.clone().unwrap();
    assert_eq!(
        got,
        class.as_str(),
        "{class} recognised as {got} ({weight:.2})"
    );
    let timeline: Vec<(MotionPhase, f64)> = run
        .events
        .iter()
        .filter_map(|e| match e {
            Event::GestureMotion { phase, t, .. } => Some((*phase, t.as_secs_f64())),
            _ => None,
        })
        .collect();
    eprintln!(
        "{class}: recognised ({weight:.2}); motion {timeline:?}; last tick {:.2} s",
        run.last().t.as_secs_f64()
    );
    let phases: Vec<MotionPhase> = run
        .events
        .iter()
        .filter_map(|e| match e {
            Event::GestureMotion {
                phase, class: c, ..
            } => {
                assert_eq!(c, class.as_str());
                Some(*phase)
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        phases,
        vec![
            MotionPhase::Approach,
            MotionPhase::Follow,
            MotionPhase::Done
        ],
        "{class}"
    );
    // After `done` a mesh arrives, built where the motion planned the crowd (the
    // formation moved, `gestures.apply: keep_formation`), and the agents settle
    // onto its vertices: the scatter the push-apart left is gone.
    let done_t = run
        .events
        .iter()
        .find_map(|e| match e {
            Event::GestureMotion {
                phase: MotionPhase::Done,
                t,
                ..
            } => Some(*t),
            _ => None,
        })
        .unwrap();
    let mesh = run
        .meshes
        .iter()
        .find(|m| run.at(m.seq).t >= done_t)
        .unwrap_or_else(|| panic!("{class}: no mesh after the motion"));
    let at_mesh = run.at(mesh.seq);
    let last = run.last();
    let off_mesh = |agents: &[crowdtouch::vocab::AgentView]| {
        agents
            .iter()
            .map(|a| {
                mesh.vertices
                    .iter()
                    .map(|v| (v - a.pos).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    };
    let (when_built, settled) = (off_mesh(&at_mesh.agents), off_mesh(&last.agents));
    eprintln!(
        "{class}: agents up to {when_built:.3} m off the rebuilt mesh's vertices when it \
         arrives, {settled:.3} m {AFTER_MESH_S} s later"
    );
    assert!(
        settled < SETTLED_M,
        "{class}: an agent is {settled:.3} m from the rebuilt mesh's vertices {AFTER_MESH_S} s after it"
    );
    // A split leaves two parts, each with a mesh of its own; every piece of the
    // mesh holds at least `gestures.min_piece_agents` agents.
    let pieces = mesh.outlines.len().max(1);
    if split_class(class) {
        assert_eq!(
            pieces, 2,
            "{class}: the mesh after a split has {pieces} pieces"
        );
    }
    if pieces > 1 {
        assert_every_piece_holds_agents(mesh, &last.agents, class);
    }
    // The formation is kept: the crowd after is the crowd before moved by one
    // similarity (each part's, for a split), within 15 % of its RMS radius.
    let before = positions(run, 0);
    let after: Vec<Vec2> = last.agents.iter().map(|a| a.pos).collect();
    let parts: Vec<Vec<usize>> = if split_class(class) {
        two_parts(&after)
    } else {
        vec![(0..after.len()).collect()]
    };
    for (k, part) in parts.iter().enumerate() {
        let a: Vec<Vec2> = part.iter().map(|&i| before[i]).collect();
        let b: Vec<Vec2> = part.iter().map(|&i| after[i]).collect();
        let r = procrustes_residual(&a, &b);
        eprintln!(
            "{class}: part {k} of {}: Procrustes residual {:.1} % of its RMS radius",
            parts.len(),
            100.0 * r
        );
        assert!(
            r <= 0.15,
            "{class}: part {k}'s formation is lost: residual {:.1} % of its RMS radius",
            100.0 * r
        );
    }
    let n = run.snapshots[0].agents.len();
    let ticks: Vec<usize> = (0..run.snapshots.len())
        .step_by(4)
        .chain(std::iter::once(run.snapshots.len() - 1))
        .collect();
    (0..n)
        .map(|i| {
            ticks
                .iter()
                .map(|&k| run.snapshots[k].agents[i].pos)
                .collect()
        })
        .collect()
}

/// Labels agents 0/1 by the side of `axis` (through the centroid) they start on.
fn halves(run: &Run, axis: Vec2) -> Vec<u8> {
    let start = positions(run, 0);
    let c = centroid(start.iter().copied());
    start
        .iter()
        .map(|p| u8::from((p - c).dot(&axis) > 0.0))
        .collect()
}

fn unit(a: f64) -> Vec2 {
    Vec2::new(a.cos(), a.sin())
}

fn assert_moved_along(class: MotionClass, shift: Vec2, dir: Vec2) {
    let cos = shift.normalize().dot(&dir.normalize());
    assert!(
        shift.norm() > 1.0 && cos > 0.7,
        "{class}: crowd moved {:.2} m at cos {cos:.2} to the gesture's travel {dir:?} ({shift:?})",
        shift.norm()
    );
}

fn assert_turned(class: MotionClass, rotation_rad: f64, clockwise: bool) {
    let deg = rotation_rad.to_degrees();
    // `clockwise` on the glass turns +x towards +y: a positive rotation in
    // `measure`'s convention (x towards y), the world sharing the glass's axes.
    let sign = if clockwise { 1.0 } else { -1.0 };
    assert!(
        deg * sign > 20.0,
        "{class}: crowd turned {deg:.1}° for a {} gesture",
        if clockwise {
            "clockwise"
        } else {
            "anticlockwise"
        }
    );
}

fn group_ratio(class: MotionClass, tracks: &[Vec<Vec2>], group: &[u8]) -> f64 {
    let m = measure(tracks, group);
    let (d0, d1) = m.group_distance.unwrap();
    eprintln!("{class}: halves {d0:.2} m -> {d1:.2} m apart");
    d1 / d0
}

#[test]
fn translate_moves_the_crowd_the_way_of_the_swipe() {
    let c = MotionClass::Translate;
    let p = play(c, 0.4, true, 1501);
    let tracks = check_common(c, &p);
    let m = measure(&tracks, &vec![0; tracks.len()]);
    eprintln!("{c}: {m:?}");
    assert_moved_along(c, m.centroid_shift, finger_travel(&p.tracks));
}

#[test]
fn twist_turns_the_crowd_the_way_of_the_fingers() {
    let c = MotionClass::Twist;
    for (clockwise, seed) in [(true, 1502), (false, 1512)] {
        let p = play(c, 0.0, clockwise, seed);
        let tracks = check_common(c, &p);
        let m = measure(&tracks, &vec![0; tracks.len()]);
        eprintln!("{c} clockwise {clockwise}: {m:?}");
        assert_turned(c, m.rotation_rad, clockwise);
    }
}

/// The most a crowd can gather with its formation kept: the scale at which its
/// nearest neighbours stand two body radii apart (the default crowd, 100 agents in
/// 4 × 3 m with 0.15 m radii, stands 0.33 m apart: 0.9). A gathering class must
/// reach 0.8 or, on a crowd that dense, within 0.05 of that floor.
fn gather_bound(run: &Run) -> f64 {
    let start = positions(run, 0);
    let mut nn: Vec<f64> = start
        .iter()
        .enumerate()
        .map(|(i, p)| {
            start
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| (q - p).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nn.sort_by(f64::total_cmp);
    let radius = Config::embedded_default().crowd.agent_radius_m;
    let floor = (2.0 * radius / nn[nn.len() / 2]).min(1.0);
    0.8f64.max(floor + 0.05)
}

#[test]
fn contract_gathers_the_crowd() {
    let c = MotionClass::Contract;
    let p = play(c, 0.0, true, 1503);
    let tracks = check_common(c, &p);
    let m = measure(&tracks, &vec![0; tracks.len()]);
    eprintln!("{c}: {m:?}");
    let bound = gather_bound(&p.run);
    assert!(
        m.rms_ratio < bound,
        "{c}: RMS radius ratio {:.2} (at most {bound:.2})",
        m.rms_ratio
    );
}

#[test]
fn expand_spreads_the_crowd() {
    let c = MotionClass::Expand;
    let p = play(c, 0.0, true, 1504);
    let tracks = check_common(c, &p);
    let m = measure(&tracks, &vec![0; tracks.len()]);
    eprintln!("{c}: {m:?}");
    assert!(
        m.rms_ratio > 1.25,
        "{c}: RMS radius ratio {:.2}",
        m.rms_ratio
    );
}

#[test]
fn join_brings_the_halves_together() {
    let c = MotionClass::Join;
    let p = play(c, 0.0, true, 1505);
    let tracks = check_common(c, &p);
    let group = halves(&p.run, unit(0.0));
    let r = group_ratio(c, &tracks, &group);
    let bound = gather_bound(&p.run);
    assert!(
        r < bound,
        "{c}: halves' distance ratio {r:.2} (at most {bound:.2})"
    );
}

#[test]
fn split_moves_the_halves_apart() {
    let c = MotionClass::Split;
    let p = play(c, 0.0, true, 1506);
    let tracks = check_common(c, &p);
    let group = halves(&p.run, unit(0.0));
    let r = group_ratio(c, &tracks, &group);
    assert!(r > 1.25, "{c}: halves' distance ratio {r:.2}");
}

#[test]
fn split_then_translate_splits_and_moves_on() {
    let c = MotionClass::SplitThenTranslate;
    let p = play(c, 0.0, true, 1507);
    let tracks = check_common(c, &p);
    let group = halves(&p.run, unit(0.0));
    let r = group_ratio(c, &tracks, &group);
    let m = measure(&tracks, &group);
    eprintln!("{c}: {m:?}, travel {:?}", finger_travel(&p.tracks));
    assert!(r > 1.25, "{c}: halves' distance ratio {r:.2}");
    assert_moved_along(c, m.centroid_shift, finger_travel(&p.tracks));
}

#[test]
fn translate_then_join_moves_on_and_joins() {
    let c = MotionClass::TranslateThenJoin;
    let p = play(c, 0.0, true, 1508);
    let tracks = check_common(c, &p);
    let group = halves(&p.run, unit(0.0));
    let r = group_ratio(c, &tracks, &group);
    let m = measure(&tracks, &group);
    eprintln!("{c}: {m:?}, travel {:?}", finger_travel(&p.tracks));
    let bound = gather_bound(&p.run);
    assert!(
        r < bound,
        "{c}: halves' distance ratio {r:.2} (at most {bound:.2})"
    );
    assert_moved_along(c, m.centroid_shift, finger_travel(&p.tracks));
}

#[test]
fn twist_while_expanding_turns_and_spreads() {
    let c = MotionClass::TwistWhileExpanding;
    let p = play(c, 0.0, false, 1509);
    let tracks = check_common(c, &p);
    let m = measure(&tracks, &vec![0; tracks.len()]);
    eprintln!("{c}: {m:?}");
    assert_turned(c, m.rotation_rad, false);
    assert!(
        m.rms_ratio > 1.25,
        "{c}: RMS radius ratio {:.2}",
        m.rms_ratio
    );
}

#[test]
fn twist_while_contracting_turns_and_gathers() {
    let c = MotionClass::TwistWhileContracting;
    let p = play(c, 0.0, true, 1510);
    let tracks = check_common(c, &p);
    let m = measure(&tracks, &vec![0; tracks.len()]);
    eprintln!("{c}: {m:?}");
    assert_turned(c, m.rotation_rad, true);
    let bound = gather_bound(&p.run);
    assert!(
        m.rms_ratio < bound,
        "{c}: RMS radius ratio {:.2} (at most {bound:.2})",
        m.rms_ratio
    );
}

/// Played as the paper does (`gestures.apply: as_sampled`), a translate reshapes
/// the crowd into the library crowd's shape on its way (the agents walk to sampled
/// starts first), and the mesh is rebuilt around where the agents stopped, a
/// straggler drawn in to its part: the agents settle on its vertices.
#[test]
fn as_sampled_moves_the_crowd_and_meshes_it_where_it_stopped() {
    let c = MotionClass::Translate;
    let tracks = generate(c, &style(c, 0.4, true), 1501);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("translate.jsonl");
    write_recording(&tracks, &path);
    let mut cfg = Config::embedded_default();
    cfg.gestures.apply = crowdtouch::config::GestureApply::AsSampled;
    let run = replay_with(&path, true, cfg);
    let done_t = run
        .events
        .iter()
        .find_map(|e| match e {
            Event::GestureMotion {
                phase: MotionPhase::Done,
                t,
                ..
            } => Some(*t),
            _ => None,
        })
        .expect("the motion finishes");
    let mesh = run
        .meshes
        .iter()
        .find(|m| run.at(m.seq).t >= done_t)
        .expect("a mesh after the motion");
    // Every agent settles on a vertex of the mesh (a straggler's drawn in to its
    // part), and no piece is smaller than `gestures.min_piece_agents`.
    let settled = run
        .last()
        .agents
        .iter()
        .map(|a| {
            mesh.vertices
                .iter()
                .map(|v| (v - a.pos).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    // (A straggler drawn in 0.7 m is still arriving AFTER_MESH_S later.)
    assert!(
        settled < 2.0 * SETTLED_M,
        "an agent is {settled:.3} m from the rebuilt mesh's vertices"
    );
    assert_every_piece_holds_agents(mesh, &run.last().agents, "straggler");
    let shift = centroid(run.last().agents.iter().map(|a| a.pos))
        - centroid(run.snapshots[0].agents.iter().map(|a| a.pos));
    assert_moved_along(c, shift, finger_travel(&tracks));
    let before = positions(&run, 0);
    let after: Vec<Vec2> = run.last().agents.iter().map(|a| a.pos).collect();
    let r = procrustes_residual(&before, &after);
    eprintln!(
        "as_sampled translate: Procrustes residual {:.1} % of the RMS radius",
        100.0 * r
    );
}

/// Two fingers that creep 11 mm (past the tap's 10 mm, short of the 12 mm a gesture
/// must travel) are not a command: the `gesture` event says `still`, a reason of
/// docs/protocol.md's list, and no motion plays.
#[test]
fn a_creeping_hand_is_rejected_as_still_and_moves_nothing() {
    use crowdtouch::gesture::track::{TouchTrack, TrackSample};
    let finger = |x0: f64| TouchTrack {
        samples: (0..=72)
            .map(|i| TrackSample {
                t: Micros(500_000 + i * 8_333),
                mm: Vec2::new(x0 + 11.0 * i as f64 / 72.0, 300.0),
            })
            .collect(),
    };
    let tracks = GestureTracks {
        fingers: vec![finger(400.0), finger(430.0)],
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("creep.jsonl");
    write_recording(&tracks, &path);
    let run = replay(&path, false);
    let ends: Vec<_> = run
        .events
        .iter()
        .filter_map(|e| match e {
            Event::GestureEnd {
                recognition,
                rejected,
                ..
            } => Some((recognition.is_some(), rejected.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(ends, [(false, Some("still".to_string()))], "{ends:?}");
    assert!(
        !run.events
            .iter()
            .any(|e| matches!(e, Event::GestureMotion { .. })),
        "no motion for a creeping hand"
    );
}

/// The gesture classes, each with the seed its test above uses.
const CLASS_SEEDS: [(MotionClass, u64); 10] = [
    (MotionClass::Translate, 1501),
    (MotionClass::Twist, 1502),
    (MotionClass::Contract, 1503),
    (MotionClass::Expand, 1504),
    (MotionClass::Join, 1505),
    (MotionClass::Split, 1506),
    (MotionClass::SplitThenTranslate, 1507),
    (MotionClass::TranslateThenJoin, 1508),
    (MotionClass::TwistWhileExpanding, 1509),
    (MotionClass::TwistWhileContracting, 1510),
];

/// Every class's gesture played on the crowd standing in `formation` (reached by
/// `set_formation` first): the crowd after is the crowd before moved by the
/// gesture — one similarity, or one per part for a class recognised as a split —
/// within 15 % of its RMS radius (issue 34). Returns each class's residual.
fn classes_keep(formation: &str) -> Vec<(MotionClass, f64)> {
    let mut cfg = Config::embedded_default();
    cfg.pipeline.tick_hz = 60.0;
    let period = (1e6 / cfg.pipeline.tick_hz) as u64;
    let mut out = Vec::new();
    for (class, seed) in CLASS_SEEDS {
        let mut engine = Engine::new(&cfg, Some(GLASS_MM), true);
        let mut now = 0u64;
        if formation != crowdtouch::crowd::formation::START {
            engine.set_formation(formation, Micros(now)).unwrap();
            let mut reached = false;
            while !reached && now < 30_000_000 {
                now += period;
                let o = engine.tick(Micros(now));
                reached = o
                    .events
                    .iter()
                    .any(|e| matches!(e, Event::Formation { name, .. } if name == formation));
                engine.clear_events();
            }
            assert!(reached, "{formation}: the switch did not finish");
            // Touch control settles the crowd on its new mesh.
            for _ in 0..60 {
                now += period;
                engine.tick(Micros(now));
                engine.clear_events();
            }
        }
        let tracks = generate(class, &style(class, 0.0, true), seed);
        let frames = to_frames(&tracks, GLASS_MM, Micros(now + 500_000));
        let mut run = Run {
            snapshots: vec![],
            events: vec![],
            meshes: vec![],
        };
        let clock = VirtualClock {
            period: Micros(period),
            settle: Micros::from_secs_f64(SETTLE_S),
            max_gap: Micros(crowdtouch::input::replay::MAX_GAP_US),
        };
        let (mut done, mut stop_at) = (false, None::<Micros>);
        let _ = replay_virtual(
            &mut engine,
            frames.into_iter().map(Ok),
            clock,
            |_| {},
            |o| {
                run.snapshots.push(Arc::clone(&o.snapshot));
                run.events.extend(o.events.iter().cloned());
                done |= o.events.iter().any(|e| {
                    matches!(
                        e,
                        Event::GestureMotion {
                            phase: MotionPhase::Done | MotionPhase::Cancelled,
                            ..
                        }
                    )
                });
                if o.mesh.is_some() && done && stop_at.is_none() {
                    stop_at = Some(o.snapshot.t + Micros::from_secs_f64(AFTER_MESH_S));
                }
                match stop_at {
                    Some(t) if o.snapshot.t >= t => Err(Stop),
                    _ => Ok(()),
                }
            },
        );
        let recognised = run.events.iter().find_map(|e| match e {
            Event::GestureEnd {
                recognition: Some(r),
                ..
            } => Some(r.class.clone()),
            _ => None,
        });
        let Some(recognised) = recognised else {
            panic!("{formation}/{class}: not recognised");
        };
        assert!(done, "{formation}/{class}: the motion did not finish");
        let before = positions(&run, 0);
        let after: Vec<Vec2> = run.last().agents.iter().map(|a| a.pos).collect();
        let split = matches!(recognised.as_str(), "split" | "split_then_translate");
        let parts = if split {
            two_parts(&after)
        } else {
            vec![(0..after.len()).collect()]
        };
        let worst = parts
            .iter()
            .map(|part| {
                let a: Vec<Vec2> = part.iter().map(|&i| before[i]).collect();
                let b: Vec<Vec2> = part.iter().map(|&i| after[i]).collect();
                procrustes_residual(&a, &b)
            })
            .fold(0.0, f64::max);
        eprintln!(
            "{formation}/{class} (recognised {recognised}): residual {:.1} % of the RMS radius",
            100.0 * worst
        );
        assert!(
            worst <= 0.15,
            "{formation}/{class} (recognised {recognised}): the formation is lost, residual {:.1} %",
            100.0 * worst
        );
        out.push((class, worst));
    }
    out
}

/// One test per shipped formation (they run side by side). A debug build (the
/// README's `cargo test`) plays four of them; the other eight take a minute
/// unoptimised and run in release in `.ci/run`
/// (`cargo test --release --test gesture_commands -- --include-ignored`).
macro_rules! keeps_formation {
    ($($test:ident => $name:literal),* $(,)?) => {$(
        #[test]
        fn $test() {
            assert_eq!(classes_keep($name).len(), 10);
        }
    )*};
}

/// [`keeps_formation`], ignored in debug builds.
macro_rules! keeps_formation_in_release {
    ($($test:ident => $name:literal),* $(,)?) => {$(
        #[test]
        #[cfg_attr(debug_assertions, ignore = "slow unoptimised: .ci/run runs it in release")]
        fn $test() {
            assert_eq!(classes_keep($name).len(), 10);
        }
    )*};
}

keeps_formation! {
    every_class_keeps_the_start_grid => "start",
    every_class_keeps_a_line => "line",
    every_class_keeps_a_ring => "ring",
    every_class_keeps_two_groups => "two_groups",
}

keeps_formation_in_release! {
    every_class_keeps_a_square => "square",
    every_class_keeps_an_arrow => "arrow",
    every_class_keeps_a_column => "column",
    every_class_keeps_a_wedge => "wedge",
    every_class_keeps_a_diamond => "diamond",
    every_class_keeps_a_circle => "circle",
    every_class_keeps_a_letter_a => "letter_a",
    every_class_keeps_a_heart => "heart",
}

/// Every formation the shipped config defines has its test above.
#[test]
fn the_formation_tests_cover_every_shipped_formation() {
    let cfg = Config::embedded_default();
    let mut shipped: Vec<String> = cfg
        .formation_library()
        .names()
        .map(str::to_string)
        .collect();
    shipped.push(crowdtouch::crowd::formation::START.to_string());
    shipped.sort();
    let mut tested = vec![
        "start",
        "square",
        "arrow",
        "column",
        "line",
        "wedge",
        "diamond",
        "circle",
        "ring",
        "two_groups",
        "letter_a",
        "heart",
    ];
    tested.sort_unstable();
    assert_eq!(shipped, tested);
}
