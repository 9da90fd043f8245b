//! The shipped recordings replayed through the engine (virtual clock): where the crowd
//! goes, how controls shape the mesh, whether agents arrive, whether the assignment is
//! optimal.

mod common;

use common::*;
use crowdtouch::config::Config;
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::{ControlKind, Event};

fn cfg() -> Config {
    Config::embedded_default()
}

/// Tolerance for "stays rigid" and "on the line" (m): a few percent of the 0.43 m
/// mesh spacing.
const SHAPE_TOL_M: f64 = 0.04;
/// An agent has reached its goal when this close (m).
const ARRIVED_M: f64 = 0.05;

fn control_events(run: &Run) -> Vec<(u32, ControlKind, Vec<u32>)> {
    let mut out: Vec<(u32, ControlKind, Vec<u32>)> = vec![];
    for e in &run.events {
        match e {
            Event::ControlBegin {
                id, kind, vertices, ..
            }
            | Event::ControlUpdate {
                id, kind, vertices, ..
            } => match out.iter_mut().find(|c| c.0 == *id) {
                Some(c) => {
                    c.1 = *kind;
                    c.2 = vertices.clone();
                }
                None => out.push((*id, *kind, vertices.clone())),
            },
            _ => {}
        }
    }
    out
}

fn assert_all_arrived(run: &Run) {
    let s = run.last();
    let worst = s
        .agents
        .iter()
        .map(|a| (a.pos - s.goals[a.goal as usize]).norm())
        .fold(0.0, f64::max);
    assert!(
        worst < ARRIVED_M,
        "an agent is {worst:.3} m from its goal after settling"
    );
    let mut used = vec![false; s.goals.len()];
    for a in &s.agents {
        assert!(!used[a.goal as usize], "goal {} assigned twice", a.goal);
        used[a.goal as usize] = true;
    }
}

#[test]
fn point_drag_moves_the_crowd_with_the_finger() {
    let run = replay("01-point-drag.jsonl", &cfg(), 6.0);
    let kinds: Vec<_> = control_events(&run).iter().map(|c| c.1).collect();
    assert_eq!(kinds, vec![ControlKind::Point]);
    let before = centroid(run.snapshots[0].agents.iter().map(|a| a.pos));
    let after = centroid(run.last().agents.iter().map(|a| a.pos));
    let moved = after - before;
    // The finger drags 2.5 m to the right; one finger translates the whole mesh.
    assert!((moved.x - 2.5).abs() < 0.25, "crowd moved {moved}");
    assert!(moved.y.abs() < 0.25, "crowd moved {moved}");
    assert_all_arrived(&run);
    assert!(run.events.iter().any(|e| matches!(
        e,
        Event::ControlEnd {
            kind: ControlKind::Point,
            cancelled: false,
            ..
        }
    )));
}

/// Line control (section 4.2): the vertices between the two fingers follow the
/// straight segment between them.
#[test]
fn line_drag_keeps_the_segment_straight() {
    let run = replay("02-line-drag.jsonl", &cfg(), 6.0);
    let ctl = control_events(&run);
    assert_eq!(ctl.len(), 1, "{ctl:?}");
    assert_eq!(ctl[0].1, ControlKind::Line);
    let (h0, h1) = (ctl[0].2[0] as usize, ctl[0].2[1] as usize);
    let rest = &run.first_mesh().vertices;
    let fin = &run.last_mesh().vertices;
    let (a0, b0) = (rest[h0], rest[h1]);
    let (a1, b1) = (fin[h0], fin[h1]);
    let between: Vec<usize> = (0..rest.len())
        .filter(|&v| v != h0 && v != h1)
        .filter(|&v| {
            let t = (rest[v] - a0).dot(&(b0 - a0)) / (b0 - a0).norm_squared();
            let off = (rest[v] - (a0 + (b0 - a0) * t)).norm();
            (0.0..=1.0).contains(&t) && off < 0.05
        })
        .collect();
    assert!(!between.is_empty());
    for &v in &between {
        let t = (rest[v] - a0).dot(&(b0 - a0)) / (b0 - a0).norm_squared();
        let want = a1 + (b1 - a1) * t;
        assert!(
            (fin[v] - want).norm() < SHAPE_TOL_M,
            "vertex {v} at {} not on the segment ({want})",
            fin[v]
        );
    }
    // The edge moved about 2 m to the left.
    assert!((a1.x - a0.x + 2.0).abs() < 0.2, "{a0} -> {a1}");
    assert_all_arrived(&run);
}

#[test]
fn line_pinch_keeps_the_segment_straight_and_shortens_it() {
    let run = replay("03-line-pinch.jsonl", &cfg(), 6.0);
    let ctl = control_events(&run);
    assert_eq!(ctl.len(), 1);
    assert_eq!(ctl[0].1, ControlKind::Line);
    let (h0, h1) = (ctl[0].2[0] as usize, ctl[0].2[1] as usize);
    let (rest, fin) = (&run.first_mesh().vertices, &run.last_mesh().vertices);
    let l0 = (rest[h0] - rest[h1]).norm();
    let l1 = (fin[h0] - fin[h1]).norm();
    assert!(l1 < 0.6 * l0, "pinched from {l0:.2} to {l1:.2} m");
    for v in 0..rest.len() {
        let t = (rest[v] - rest[h0]).dot(&(rest[h1] - rest[h0])) / l0.powi(2);
        let off = (rest[v] - (rest[h0] + (rest[h1] - rest[h0]) * t)).norm();
        if v != h0 && v != h1 && (0.0..=1.0).contains(&t) && off < 0.05 {
            let want = fin[h0] + (fin[h1] - fin[h0]) * t;
            assert!(
                (fin[v] - want).norm() < SHAPE_TOL_M,
                "vertex {v} off the pinched segment"
            );
        }
    }
}

fn inside_hull_of(rest: &[Vec2], handles: &[usize]) -> Vec<usize> {
    let pts: Vec<Vec2> = handles.iter().map(|&h| rest[h]).collect();
    let hull = crowdtouch::crowd::mesh::convex_hull(&pts);
    let poly: Vec<Vec2> = hull.iter().map(|&i| pts[i]).collect();
    (0..rest.len())
        .filter(|&v| {
            crowdtouch::crowd::mesh::point_in_convex_polygon(&poly, rest[v]) || handles.contains(&v)
        })
        .collect()
}

/// Area control (section 4.2): the region inside the fingers' hull moves rigidly.
#[test]
fn area_drag_moves_its_region_rigidly() {
    let run = replay("04-area-drag.jsonl", &cfg(), 6.0);
    let ctl = control_events(&run);
    assert_eq!(ctl.len(), 1);
    assert_eq!(ctl[0].1, ControlKind::Area);
    let handles: Vec<usize> = ctl[0].2.iter().map(|&v| v as usize).collect();
    let (rest, fin) = (&run.first_mesh().vertices, &run.last_mesh().vertices);
    let region = inside_hull_of(rest, &handles);
    assert!(region.len() >= 4, "region {region:?}");
    let a: Vec<Vec2> = region.iter().map(|&v| rest[v]).collect();
    let b: Vec<Vec2> = region.iter().map(|&v| fin[v]).collect();
    let (angle, residual) = rigid_fit(&a, &b);
    assert!(residual < SHAPE_TOL_M, "region deformed by {residual:.3} m");
    assert!(angle.abs() < 0.05, "a drag should not rotate: {angle}");
    let shift = centroid(b.iter().copied()) - centroid(a.iter().copied());
    assert!(
        (shift - Vec2::new(1.0, 1.5)).norm() < 0.2,
        "region moved {shift}"
    );
    assert_all_arrived(&run);
}

#[test]
fn area_twist_rotates_its_region_rigidly() {
    let run = replay("05-area-twist.jsonl", &cfg(), 6.0);
    let ctl = control_events(&run);
    assert_eq!(ctl.len(), 1);
    assert_eq!(ctl[0].1, ControlKind::Area);
    let handles: Vec<usize> = ctl[0].2.iter().map(|&v| v as usize).collect();
    let (rest, fin) = (&run.first_mesh().vertices, &run.last_mesh().vertices);
    let region = inside_hull_of(rest, &handles);
    let a: Vec<Vec2> = region.iter().map(|&v| rest[v]).collect();
    let b: Vec<Vec2> = region.iter().map(|&v| fin[v]).collect();
    let (angle, residual) = rigid_fit(&a, &b);
    assert!(residual < SHAPE_TOL_M, "region deformed by {residual:.3} m");
    assert!(
        (angle.to_degrees() - 60.0).abs() < 5.0,
        "rotated {:.1}°",
        angle.to_degrees()
    );
    assert_all_arrived(&run);
}

/// Two hands far apart make two controls that deform the mesh together.
#[test]
fn two_hands_make_two_simultaneous_controls() {
    let run = replay("06-two-hands.jsonl", &cfg(), 6.0);
    let ctl = control_events(&run);
    let kinds: Vec<_> = ctl.iter().map(|c| c.1).collect();
    assert_eq!(kinds, vec![ControlKind::Line, ControlKind::Area]);
    // Both were live at once: the second began before the first ended.
    let begin2 = run
        .events
        .iter()
        .position(|e| matches!(e, Event::ControlBegin { id, .. } if *id == ctl[1].0));
    let end1 = run
        .events
        .iter()
        .position(|e| matches!(e, Event::ControlEnd { id, .. } if *id == ctl[0].0));
    assert!(begin2.unwrap() < end1.unwrap());
    let (rest, fin) = (&run.first_mesh().vertices, &run.last_mesh().vertices);
    let (minx0, maxx0) = rest
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
    let (minx1, maxx1) = fin
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
    assert!(
        minx1 < minx0 - 0.7 && maxx1 > maxx0 + 0.7,
        "stretched [{minx0},{maxx0}] -> [{minx1},{maxx1}]"
    );
}

/// Fingers in open space are a gesture, not a control: a two-finger swipe is
/// recognised as a translate and the crowd walks the way it went
/// (gesture-driven-crowd-motion sections 5–7).
#[test]
fn open_space_swipe_is_a_gesture() {
    let run = replay("07-open-space-swipe.jsonl", &cfg(), 8.0);
    assert!(control_events(&run).is_empty());
    let begins = run
        .events
        .iter()
        .filter(|e| matches!(e, Event::GestureBegin { .. }))
        .count();
    let ends: Vec<_> = run
        .events
        .iter()
        .filter_map(|e| match e {
            Event::GestureEnd {
                fingers,
                cancelled,
                recognition,
                ..
            } => Some((
                *fingers,
                *cancelled,
                recognition.as_ref().map(|r| r.class.clone()),
            )),
            _ => None,
        })
        .collect();
    assert_eq!(begins, 1);
    assert_eq!(ends, vec![(2, false, Some("translate".to_string()))]);
    // The swipe's direction: where its fingers went.
    let with_touches: Vec<_> = run
        .snapshots
        .iter()
        .filter(|s| !s.touches.is_empty())
        .collect();
    let swipe = centroid(with_touches.last().unwrap().touches.iter().map(|t| t.pos))
        - centroid(with_touches[0].touches.iter().map(|t| t.pos));
    let before = centroid(run.snapshots[0].agents.iter().map(|a| a.pos));
    let after = centroid(run.last().agents.iter().map(|a| a.pos));
    let moved = after - before;
    assert!(
        moved.norm() > 0.5 && moved.normalize().dot(&swipe.normalize()) > 0.7,
        "crowd moved {moved:?} for a swipe {swipe:?}"
    );
}

/// The assignment in use is optimal for the state it was solved on (an independent
/// Kuhn–Munkres gives the same total cost), checked all along a recording.
#[test]
fn assignment_is_optimal_along_a_recording() {
    let mut c = cfg();
    c.crowd.agents = 60;
    let run = replay("05-area-twist.jsonl", &c, 1.0);
    let mut checked = 0;
    for s in run.snapshots.iter().skip(1).step_by(25) {
        let solved_on = run.at(s.assignment_seq);
        let agents: Vec<Vec2> = solved_on.agents.iter().map(|a| a.pos).collect();
        let ours = assignment_cost(&agents, &solved_on.goals, s.agents.iter().map(|a| a.goal));
        let best = reference_optimal_cost(&agents, &solved_on.goals);
        assert!(
            ours <= best + 1e-4,
            "tick {}: cost {ours} vs optimum {best}",
            s.seq
        );
        checked += 1;
    }
    assert!(checked > 10);
}

#[test]
fn replay_is_deterministic() {
    let a = replay("06-two-hands.jsonl", &cfg(), 1.0);
    let b = replay("06-two-hands.jsonl", &cfg(), 1.0);
    assert_eq!(a.snapshots.len(), b.snapshots.len());
    assert!(a.snapshots.iter().zip(&b.snapshots).all(|(x, y)| x == y));
    assert_eq!(a.events, b.events);
}
