//! The velocity-based movers of the paper's Table 3 baselines behind one call:
//! ORCA (`orca.rs`), RVO (`rvo.rs`) and OpenSteer-style steering (`steer.rs`).
//! Each turns the agents' wanted velocities into new velocities for a substep;
//! `run.rs` then moves the agents by them.

use super::orca::Orca;
use super::params::{MoveParams, Mover};
use super::rvo::Rvo;
use super::steer::Steering;
use crate::geom::Vec2;

/// A baseline mover's state.
#[derive(Clone, Debug)]
pub(crate) enum Baseline {
    /// ORCA as RVO2 runs it.
    Orca(Orca),
    /// RVO by sampling, as the RVO library ran it.
    Rvo(Rvo),
    /// OpenSteer-style steering behaviours.
    Steering(Steering),
}

impl Baseline {
    /// The baseline `mover` names, for `n` agents and the run's `seed`; `None` for
    /// the social force model.
    pub(crate) fn new(mover: Mover, n: usize, seed: u64) -> Option<Baseline> {
        match mover {
            Mover::SocialForce => None,
            Mover::Orca => Some(Baseline::Orca(Orca::new(n))),
            Mover::Rvo => Some(Baseline::Rvo(Rvo::new(n, seed))),
            Mover::Steering => Some(Baseline::Steering(Steering::new(n))),
        }
    }

    /// Sets `vel[i]` of every agent not `settled` to the mover's velocity for the
    /// wanted `wanted[i]` (`dist[i]` from its target) over a substep of `h`
    /// seconds; settled agents get zero.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn velocities(
        &mut self,
        pos: &[Vec2],
        vel: &mut [Vec2],
        wanted: &[Vec2],
        dist: &[f64],
        settled: &[bool],
        p: &MoveParams,
        h: f64,
    ) {
        match self {
            Baseline::Orca(m) => m.velocities(pos, vel, wanted, settled, p, h),
            Baseline::Rvo(m) => m.velocities(pos, vel, wanted, settled, p, h),
            Baseline::Steering(m) => m.velocities(pos, vel, wanted, dist, settled, p, h),
        }
    }
}

/// Runs of a few agents under a baseline, for the movers' tests.
#[cfg(test)]
pub(crate) mod testing {
    use super::super::prepare::TransformPlan;
    use super::super::run::{MoveParams, RunSummary, TransformRun};
    use super::super::{PairCost, Subgroups};
    use crate::geom::Vec2;

    /// The step of the tests (s).
    pub(crate) const DT_S: f64 = 1.0 / 60.0;

    /// One run from `sources` to `targets` (one subgroup) with `p` and `seed`, to
    /// the end or `max_s`: the summary, every agent's positions after each step.
    pub(crate) fn run(
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
    pub(crate) fn closest(track: &[Vec<Vec2>]) -> f64 {
        track
            .iter()
            .map(|x| (x[0] - x[1]).norm())
            .fold(f64::INFINITY, f64::min)
    }

    /// The farthest agent 0 strays from the line `a`–`b` (m).
    pub(crate) fn off_line(track: &[Vec<Vec2>], a: Vec2, b: Vec2) -> f64 {
        let u = (b - a).normalize();
        track
            .iter()
            .map(|x| {
                let d = x[0] - a;
                (d - u * d.dot(&u)).norm()
            })
            .fold(0.0, f64::max)
    }
}
