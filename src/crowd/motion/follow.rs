//! The controller that moves the crowd along synthesised trajectories.
//!
//! gesture-driven section 7.3: "the characters move to the starting point of their
//! respective trajectories, and then follow the trajectories", while a low-level
//! spring-mass model keeps them apart. A [`Follower`] holds one trajectory per agent
//! (world metres, [`S_H`] samples over the motion's duration, index = agent, already
//! matched to the agents by optimal assignment) and gives, every tick, each agent's
//! target; the caller steps the agents towards them with
//! [`crate::crowd::agents::Agents::step_towards`], whose push-apart is the
//! spring-mass resolver.
//!
//! ```text
//!   Approach ──90 % within tolerance, or timeout──▶ Follow ──duration + settle,──▶ Done
//!      │                                             │      or all at their ends
//!      └───────────── cancel / crowd resized ────────┴──────▶ Cancelled
//! ```
//!
//! In `Approach` each target is the trajectory's start. In `Follow` it is the
//! trajectory at the motion's time `(t − t_follow) · time_scale`, linear between
//! samples; stragglers that were still walking to their start when the timeout fired
//! chase their moving target. `Done` and `Cancelled` hold the targets still. No call
//! allocates after construction, except [`Follower::targets`] with a crowd of a new
//! size, which cancels.

use crate::geom::Vec2;
use crate::gesture::library::S_H;

/// Share of the agents within the approach tolerance of their starts that ends the
/// approach.
pub const APPROACH_SHARE: f64 = 0.9;

/// Tunables of trajectory following.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FollowParams {
    /// An agent this close to its trajectory's start has arrived there, and one this
    /// close to its end has finished (m).
    pub approach_tolerance_m: f64,
    /// Longest the crowd waits for stragglers before following anyway (s).
    pub approach_timeout_s: f64,
    /// Motion time per second of wall time (1 = the synthesised duration; 2 = twice
    /// as fast).
    pub time_scale: f64,
    /// Longest the agents are given after the motion's end to reach their ends (s).
    pub settle_s: f64,
}

impl Default for FollowParams {
    fn default() -> Self {
        FollowParams {
            approach_tolerance_m: 0.15,
            approach_timeout_s: 4.0,
            time_scale: 1.0,
            settle_s: 2.0,
        }
    }
}

/// Where a [`Follower`] is (see the module's diagram).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum FollowPhase {
    /// Walking to the trajectories' starts.
    Approach,
    /// Following the trajectories.
    Follow,
    /// Finished: every agent at its trajectory's end, or the settle time passed.
    Done,
    /// Stopped early ([`Follower::cancel`], or a crowd of another size).
    Cancelled,
}

/// Why trajectories cannot be followed.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum FollowError {
    /// No trajectories.
    #[error("no trajectories to follow")]
    Empty,
    /// A trajectory sample is NaN or infinite.
    #[error("trajectory {agent} has a non-finite sample")]
    NonFinite {
        /// The offending agent.
        agent: usize,
    },
    /// The duration is not positive and finite.
    #[error("motion duration {0} s is not positive and finite")]
    Duration(f64),
    /// A parameter is out of range (negative, zero time scale, or not finite).
    #[error("follow parameter {0} is out of range")]
    Param(&'static str),
}

/// Walks agents to their trajectories' starts, then along them (gesture-driven
/// section 7.3).
#[derive(Clone, Debug)]
pub struct Follower {
    trajectories: Vec<[Vec2; S_H]>,
    duration_s: f64,
    params: FollowParams,
    phase: FollowPhase,
    approach_from_s: Option<f64>,
    follow_from_s: f64,
    targets: Vec<Vec2>,
}

impl Follower {
    /// A follower for `trajectories` (world m, index = agent) lasting `duration_s`.
    ///
    /// # Errors
    /// [`FollowError`] for no trajectories, non-finite samples, a duration or a
    /// parameter out of range.
    pub fn new(
        trajectories: Vec<[Vec2; S_H]>,
        duration_s: f64,
        params: FollowParams,
    ) -> Result<Follower, FollowError> {
        if trajectories.is_empty() {
            return Err(FollowError::Empty);
        }
        if let Some(agent) = trajectories
            .iter()
            .position(|t| !t.iter().all(|p| p.x.is_finite() && p.y.is_finite()))
        {
            return Err(FollowError::NonFinite { agent });
        }
        if !(duration_s.is_finite() && duration_s > 0.0) {
            return Err(FollowError::Duration(duration_s));
        }
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !ok(params.approach_tolerance_m) {
            return Err(FollowError::Param("approach_tolerance_m"));
        }
        if !ok(params.approach_timeout_s) {
            return Err(FollowError::Param("approach_timeout_s"));
        }
        if !(ok(params.time_scale) && params.time_scale > 0.0) {
            return Err(FollowError::Param("time_scale"));
        }
        if !ok(params.settle_s) {
            return Err(FollowError::Param("settle_s"));
        }
        let targets = trajectories.iter().map(|t| t[0]).collect();
        Ok(Follower {
            trajectories,
            duration_s,
            params,
            phase: FollowPhase::Approach,
            approach_from_s: None,
            follow_from_s: 0.0,
            targets,
        })
    }

    /// The phase.
    pub fn phase(&self) -> FollowPhase {
        self.phase
    }

    /// Whether the follower has finished or was cancelled: the caller hands the crowd
    /// back (and rebuilds the direct-control mesh around it).
    pub fn done(&self) -> bool {
        matches!(self.phase, FollowPhase::Done | FollowPhase::Cancelled)
    }

    /// Stops the motion; [`targets`](Self::targets) then holds agents where they are.
    pub fn cancel(&mut self) {
        self.phase = FollowPhase::Cancelled;
    }

    /// The trajectories (world m, index = agent).
    pub fn trajectories(&self) -> &[[Vec2; S_H]] {
        &self.trajectories
    }

    /// The motion's duration at `time_scale` 1 (s).
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Agent `i`'s trajectory at motion time `s` (s), linear between the [`S_H`]
    /// samples spread evenly over the duration, clamped to the ends.
    pub fn position_at(&self, i: usize, s: f64) -> Vec2 {
        let t = &self.trajectories[i];
        let x = (s / self.duration_s).clamp(0.0, 1.0) * (S_H - 1) as f64;
        let k = (x.floor() as usize).min(S_H - 2);
        let u = x - k as f64;
        t[k] + (t[k + 1] - t[k]) * u
    }

    /// The agents' targets at time `t_s` (s, the caller's monotonic clock) with the
    /// agents at `positions`; advances the phase. The first call starts the approach.
    ///
    /// A crowd of another size than the trajectories cancels the motion (the caller
    /// should have cancelled it on the resize) and the targets become `positions`.
    /// Allocation-free unless the size changed.
    pub fn targets(&mut self, positions: &[Vec2], t_s: f64) -> &[Vec2] {
        if positions.len() != self.trajectories.len() {
            self.phase = FollowPhase::Cancelled;
        }
        let from = *self.approach_from_s.get_or_insert(t_s);
        let tol = self.params.approach_tolerance_m;
        if self.phase == FollowPhase::Approach {
            // Most of the crowd there is enough: agents pressed together by the
            // push-apart may never all reach their exact starts, and the few left
            // chase their moving targets.
            let there = positions
                .iter()
                .zip(&self.trajectories)
                .filter(|(p, tr)| (*p - tr[0]).norm() <= tol)
                .count();
            let enough = there as f64 >= APPROACH_SHARE * self.trajectories.len() as f64;
            if enough || t_s - from >= self.params.approach_timeout_s {
                self.phase = FollowPhase::Follow;
                self.follow_from_s = t_s;
            }
        }
        match self.phase {
            FollowPhase::Approach => {
                for (g, tr) in self.targets.iter_mut().zip(&self.trajectories) {
                    *g = tr[0];
                }
            }
            FollowPhase::Follow => {
                let s = (t_s - self.follow_from_s) * self.params.time_scale;
                for i in 0..self.trajectories.len() {
                    self.targets[i] = self.position_at(i, s);
                }
                if s >= self.duration_s {
                    let at_ends = positions
                        .iter()
                        .zip(&self.trajectories)
                        .all(|(p, tr)| (p - tr[S_H - 1]).norm() <= tol);
                    let wall_since_end = (s - self.duration_s) / self.params.time_scale;
                    if at_ends || wall_since_end >= self.params.settle_s {
                        self.phase = FollowPhase::Done;
                    }
                }
            }
            FollowPhase::Done => {}
            FollowPhase::Cancelled => {
                // Hold the agents where they are.
                self.targets.clear();
                self.targets.extend_from_slice(positions);
            }
        }
        &self.targets
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::agents::{AgentParams, Agents};

    fn agent_params() -> AgentParams {
        AgentParams {
            radius_m: 0.15,
            max_speed_m_s: 1.5,
            max_accel_m_s2: 6.0,
            kp_per_s2: 16.0,
            kd_per_s: 8.0,
            push_stiffness_per_s2: 200.0,
        }
    }

    /// A 5 × 4 grid at 0.6 m spacing, each agent walking `d` in a straight line.
    fn straight(d: Vec2, origin: Vec2) -> Vec<[Vec2; S_H]> {
        (0..20)
            .map(|k| {
                let p0 = origin + Vec2::new((k % 5) as f64 * 0.6, (k / 5) as f64 * 0.6);
                std::array::from_fn(|j| p0 + d * (j as f64 / (S_H - 1) as f64))
            })
            .collect()
    }

    #[test]
    fn a_crowd_walks_to_the_starts_then_ends_where_its_trajectories_end() {
        let trajs = straight(Vec2::new(4.0, 1.0), Vec2::new(2.0, 0.0));
        // The agents start 1.5 m off to the side, in a slightly different order of rows.
        let starts: Vec<Vec2> = trajs.iter().map(|t| t[0] + Vec2::new(-1.5, 0.2)).collect();
        let mut agents = Agents::new(&starts);
        let mut f = Follower::new(trajs.clone(), 5.0, FollowParams::default()).unwrap();
        let dt = 1.0 / 60.0;
        let mut phases = vec![f.phase()];
        let mut t = 0.0;
        while !f.done() && t < 30.0 {
            let targets = f.targets(agents.positions(), t);
            agents.step_towards(targets, |_| 1.0, dt, &agent_params());
            if phases.last() != Some(&f.phase()) {
                phases.push(f.phase());
            }
            t += dt;
        }
        assert_eq!(
            phases,
            [
                FollowPhase::Approach,
                FollowPhase::Follow,
                FollowPhase::Done
            ]
        );
        for (p, tr) in agents.positions().iter().zip(&trajs) {
            assert!(
                (p - tr[S_H - 1]).norm() <= 0.15,
                "{p:?} vs {:?}",
                tr[S_H - 1]
            );
        }
        // The walk took the motion's duration at least, and not much more.
        assert!(t > 5.0 && t < 5.0 + 2.0 + 4.0, "{t}");
    }

    #[test]
    fn mid_motion_targets_lie_on_the_trajectories_at_the_scaled_time() {
        let trajs = straight(Vec2::new(6.3, 0.0), Vec2::zeros());
        let params = FollowParams {
            time_scale: 2.0,
            ..FollowParams::default()
        };
        let mut f = Follower::new(trajs.clone(), 9.0, params).unwrap();
        let at_start: Vec<Vec2> = trajs.iter().map(|t| t[0]).collect();
        // Everyone is at the start: following begins at once, at t = 10 s.
        let _ = f.targets(&at_start, 10.0);
        assert_eq!(f.phase(), FollowPhase::Follow);
        // 1.5 s of wall time is 3 s of motion: a third of the way.
        let g = f.targets(&at_start, 11.5).to_vec();
        for (gi, tr) in g.iter().zip(&trajs) {
            assert!((gi - (tr[0] + Vec2::new(2.1, 0.0))).norm() < 1e-9, "{gi:?}");
        }
    }

    #[test]
    fn one_straggler_in_twenty_does_not_hold_the_crowd_up() {
        let trajs = straight(Vec2::new(2.0, 0.0), Vec2::zeros());
        let mut pos: Vec<Vec2> = trajs.iter().map(|t| t[0]).collect();
        pos[7] += Vec2::new(0.0, 5.0);
        let mut f = Follower::new(trajs, 4.0, FollowParams::default()).unwrap();
        let _ = f.targets(&pos, 1.0);
        assert_eq!(f.phase(), FollowPhase::Follow);
    }

    #[test]
    fn stragglers_are_waited_for_until_the_timeout() {
        let trajs = straight(Vec2::new(2.0, 0.0), Vec2::zeros());
        let mut pos: Vec<Vec2> = trajs.iter().map(|t| t[0]).collect();
        // Three of twenty away: more than a tenth.
        for k in [3, 7, 11] {
            pos[k] += Vec2::new(0.0, 5.0);
        }
        let params = FollowParams {
            approach_timeout_s: 3.0,
            ..FollowParams::default()
        };
        let mut f = Follower::new(trajs, 4.0, params).unwrap();
        let _ = f.targets(&pos, 1.0);
        let _ = f.targets(&pos, 3.9);
        assert_eq!(f.phase(), FollowPhase::Approach);
        let _ = f.targets(&pos, 4.0);
        assert_eq!(f.phase(), FollowPhase::Follow);
        // Nobody reaches the end: the settle time ends it 4 + 2 s later.
        let _ = f.targets(&pos, 9.9);
        assert_eq!(f.phase(), FollowPhase::Follow);
        let _ = f.targets(&pos, 10.0);
        assert_eq!(f.phase(), FollowPhase::Done);
        assert!(f.done());
    }

    #[test]
    fn cancel_and_a_resized_crowd_hold_the_agents_where_they_are() {
        let trajs = straight(Vec2::new(2.0, 0.0), Vec2::zeros());
        let pos: Vec<Vec2> = trajs.iter().map(|t| t[0] + Vec2::new(0.0, 1.0)).collect();
        let mut f = Follower::new(trajs.clone(), 4.0, FollowParams::default()).unwrap();
        let _ = f.targets(&pos, 0.0);
        f.cancel();
        assert!(f.done());
        assert_eq!(f.targets(&pos, 0.1), &pos[..]);
        assert_eq!(f.phase(), FollowPhase::Cancelled);
        let mut g = Follower::new(trajs, 4.0, FollowParams::default()).unwrap();
        let _ = g.targets(&pos, 0.0);
        let fewer = &pos[..12];
        assert_eq!(g.targets(fewer, 0.1), fewer);
        assert_eq!(g.phase(), FollowPhase::Cancelled);
    }

    #[test]
    fn targets_reuse_one_buffer() {
        let trajs = straight(Vec2::new(2.0, 0.0), Vec2::zeros());
        let pos: Vec<Vec2> = trajs.iter().map(|t| t[0]).collect();
        let mut f = Follower::new(trajs, 1.0, FollowParams::default()).unwrap();
        let (ptr, cap) = (f.targets.as_ptr(), f.targets.capacity());
        for k in 0..400 {
            let _ = f.targets(&pos, k as f64 * 0.01);
            assert_eq!((f.targets.as_ptr(), f.targets.capacity()), (ptr, cap));
        }
        assert_eq!(f.phase(), FollowPhase::Done);
    }

    #[test]
    fn bad_input_is_refused() {
        let ok = straight(Vec2::new(1.0, 0.0), Vec2::zeros());
        let p = FollowParams::default();
        assert_eq!(
            Follower::new(vec![], 1.0, p).unwrap_err(),
            FollowError::Empty
        );
        let mut bad = ok.clone();
        bad[3][9].y = f64::INFINITY;
        assert_eq!(
            Follower::new(bad, 1.0, p).unwrap_err(),
            FollowError::NonFinite { agent: 3 }
        );
        assert!(matches!(
            Follower::new(ok.clone(), 0.0, p),
            Err(FollowError::Duration(_))
        ));
        let zero = FollowParams {
            time_scale: 0.0,
            ..p
        };
        assert_eq!(
            Follower::new(ok, 1.0, zero).unwrap_err(),
            FollowError::Param("time_scale")
        );
    }
}
