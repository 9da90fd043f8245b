//! Snapshots and comparisons shared by the encoder tests.

use crate::geom::Vec2;
use crate::vocab::Micros;
use crate::vocab::{AgentView, Snapshot, TouchView};
use proptest::prelude::*;
use serde_json::Value;

/// Worst-case error of a 3-decimal coordinate (m): half the last digit plus float slack.
pub(super) const FIXED3_TOLERANCE: f64 = 0.0005 + 1e-9;

pub(super) fn snap(n: usize) -> Snapshot {
    Snapshot {
        seq: 42,
        t: Micros(1_000_123),
        input_t: Some(Micros(999_000)),
        agents: (0..n)
            .map(|i| AgentView {
                pos: Vec2::new(i as f64 * 0.123_456 - 3.0, -(i as f64) * 0.01),
                vel: Vec2::new(0.5, -0.000_4),
                goal: (n - 1 - i) as u32,
            })
            .collect(),
        goals: (0..n).map(|i| Vec2::new(i as f64, 1.0005)).collect(),
        assignment_seq: 40,
        touches: vec![
            TouchView {
                id: 7,
                pos: Vec2::new(0.25, 0.75),
                control: Some(3),
            },
            TouchView {
                id: 8,
                pos: Vec2::new(-1.0, 2.0),
                control: None,
            },
        ],
        paused: false,
        motions: Vec::new(),
    }
}

pub(super) fn flat(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

pub(super) fn arb_snapshot() -> impl Strategy<Value = Snapshot> {
    let coord = -1.0e4..1.0e4f64;
    let agent = (
        coord.clone(),
        coord.clone(),
        coord.clone(),
        coord.clone(),
        0..1000u32,
    )
        .prop_map(|(x, y, vx, vy, goal)| AgentView {
            pos: Vec2::new(x, y),
            vel: Vec2::new(vx, vy),
            goal,
        });
    let touch = (
        any::<u32>(),
        coord.clone(),
        coord.clone(),
        proptest::option::of(0..u32::MAX),
    )
        .prop_map(|(id, x, y, control)| TouchView {
            id,
            pos: Vec2::new(x, y),
            control,
        });
    (
        any::<u64>(),
        any::<u64>(),
        proptest::collection::vec(agent, 0..40),
        proptest::collection::vec(
            (coord.clone(), coord).prop_map(|(x, y)| Vec2::new(x, y)),
            0..40,
        ),
        proptest::collection::vec(touch, 0..5),
        any::<bool>(),
        any::<u64>(),
        // A scene (one motion per agent) or none.
        proptest::option::of(proptest::collection::vec(
            0..crate::vocab::MotionType::ALL.len(),
            40,
        )),
    )
        .prop_map(
            |(seq, t, agents, goals, touches, paused, aseq, scene)| Snapshot {
                seq,
                t: Micros(t),
                input_t: None,
                motions: scene
                    .map(|m| {
                        m.iter()
                            .take(agents.len())
                            .map(|&i| crate::vocab::MotionType::ALL[i])
                            .collect()
                    })
                    .unwrap_or_default(),
                agents,
                goals,
                assignment_seq: aseq,
                touches,
                paused,
            },
        )
}

pub(super) fn close(a: &[f64], b: impl Iterator<Item = f64>) -> bool {
    let b: Vec<f64> = b.collect();
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| (x - y).abs() <= FIXED3_TOLERANCE)
}

/// One motion per agent, cycling through every type.
pub(super) fn with_motions(mut s: Snapshot) -> Snapshot {
    use crate::vocab::MotionType;
    s.motions = (0..s.agents.len())
        .map(|i| MotionType::ALL[i % MotionType::ALL.len()])
        .collect();
    s
}
