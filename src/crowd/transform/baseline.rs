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
