//! Runs of a few agents under the RVO and steering baselines (`rvo.rs`,
//! `steer.rs`): a lone agent walks straight in, two agents head-on pass each
//! other, the same seed gives the same trajectory.

use super::params::MoveParams;
use super::prepare::TransformPlan;
use super::run::{RunSummary, TransformRun};
use super::{PairCost, Subgroups};
use crate::geom::Vec2;

/// The step of the tests (s).
const DT_S: f64 = 1.0 / 60.0;

/// One run from `sources` to `targets` (one subgroup) with `p` and `seed`, to
/// the end or `max_s`: the summary, every agent's positions after each step.
fn run(
    sources: &[Vec2],
    targets: &[Vec2],
    p: &MoveParams,
    seed: u64,
    max_s: f64,
) -> (RunSummary, Vec<Vec<Vec2>>) {
    let plan = TransformPlan {
        sources_m: sources.to_vec(),
        targets_m: targets.to_vec(),
        subgroups: Subgroups {
            group_of: vec![0; sources.len()],
            exemplars: vec![0],
            iterations: 0,
            converged: true,
        },
        cost: PairCost::Euclidean,
    };
    let mut run = TransformRun::new(&plan, p, seed);
    let mut pos = sources.to_vec();
    let mut vel = vec![Vec2::zeros(); pos.len()];
    let mut track = Vec::new();
    while !run.done() && run.elapsed_s() < max_s {
        let _ = run.step(&mut pos, &mut vel, DT_S, None);
        track.push(pos.clone());
    }
    (run.summary(), track)
}

/// The smallest distance between agents 0 and 1 over a track (m).
fn closest(track: &[Vec<Vec2>]) -> f64 {
    track
        .iter()
        .map(|x| (x[0] - x[1]).norm())
        .fold(f64::INFINITY, f64::min)
}

/// The farthest agent 0 strays from the line `a`–`b` (m).
fn off_line(track: &[Vec<Vec2>], a: Vec2, b: Vec2) -> f64 {
    let u = (b - a).normalize();
    track
        .iter()
        .map(|x| {
            let d = x[0] - a;
            (d - u * d.dot(&u)).norm()
        })
        .fold(0.0, f64::max)
}

/// The presets of the baselines these tests cover.
fn baselines() -> [MoveParams; 2] {
    [
        MoveParams::default().rvo(),
        MoveParams::default().steering(),
    ]
}

/// Slack on the discs' overlap in the runs below (m): a few centimetres.
const OVERLAP_SLACK_M: f64 = 0.03;

#[test]
fn a_lone_agent_walks_straight_to_its_target() {
    for p in baselines() {
        let m = p.mover;
        let (s, t) = (Vec2::new(0.0, 0.0), Vec2::new(6.0, 2.0));
        let (sum, track) = run(&[s], &[t], &p, 1, 60.0);
        assert!(
            !sum.timed_out && sum.arrived_fraction == 1.0,
            "{m:?} {sum:?}"
        );
        let off = off_line(&track, s, t);
        assert!(off < 1e-6, "{m:?} {off}");
        assert!(
            (sum.mean_travel_m - (t - s).norm()).abs() < 0.3,
            "{m:?} {sum:?}"
        );
    }
}

#[test]
fn two_agents_head_on_pass_each_other_and_arrive() {
    for p in baselines() {
        let m = p.mover;
        let (a, b) = (Vec2::new(0.0, 0.0), Vec2::new(5.0, 0.0));
        for seed in 1..4 {
            let (sum, track) = run(&[a, b], &[b, a], &p, seed, 60.0);
            assert!(
                !sum.timed_out && sum.arrived_fraction == 1.0,
                "{m:?} {seed}: {sum:?}"
            );
            let c = closest(&track);
            assert!(
                c > 2.0 * p.radius_m - OVERLAP_SLACK_M,
                "{m:?} {seed}: closest {c}"
            );
        }
    }
}

#[test]
fn the_same_seed_gives_the_same_trajectory() {
    for p in baselines() {
        let m = p.mover;
        // Four agents crossing the square's centre to the opposite corners.
        let s = [
            Vec2::new(0.0, 0.0),
            Vec2::new(3.0, 0.0),
            Vec2::new(3.0, 3.0),
            Vec2::new(0.0, 3.0),
        ];
        let t = [s[2], s[3], s[0], s[1]];
        let (sum_a, a) = run(&s, &t, &p, 7, 30.0);
        let (_, b) = run(&s, &t, &p, 7, 30.0);
        let (_, c) = run(&s, &t, &p, 8, 30.0);
        assert!(sum_a.arrived_fraction == 1.0, "{m:?} {sum_a:?}");
        assert_eq!(a, b, "{m:?}");
        assert_ne!(a, c, "{m:?}");
    }
}
