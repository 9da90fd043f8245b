//! The RVO baseline of formation-transform section 5.4 (Table 3): reciprocal
//! velocity obstacles (van den Berg, Lin, Manocha 2008, "Reciprocal Velocity
//! Obstacles for real-time multi-agent navigation"), chosen by sampling as their
//! RVO library did.
//!
//! # What it is
//! Each moving agent `A`, with preferred velocity `v_pref` (towards its target at
//! its desired speed, ramped down near the target as `run.rs` does for every
//! mover), looks at its [`MAX_NEIGHBOURS`] nearest neighbours within
//! [`NEIGHBOUR_RADII`] radii. The velocity obstacle of neighbour `B` (VdBLM08
//! section 3, Definition 1) is the set of velocities `v'` of `A` whose ray from
//! `p_A` relative to `v_B` meets the Minkowski sum `B ⊕ −A` (a disc of radius
//! `r_A + r_B` at `p_B`); the reciprocal velocity obstacle (section 4,
//! Definition 5) is `RVO = {v' | 2 v' − v_A ∈ VO(v_B)}`: the same cone with its
//! apex moved to `(v_A + v_B)/2`, each agent taking half of the avoidance. Among
//! [`SAMPLES`] velocities drawn uniformly in the disc of max speed, plus `v_pref`
//! itself, the agent takes the one of least penalty (section 5.2)
//!
//! `penalty(v') = w / tc(v') + ‖v_pref − v'‖`,
//!
//! `tc(v')` the time at which `A` moving at `2 v' − v_A` relative to a static `B`
//! (the reciprocal relative velocity `2 v' − v_A − v_B`) first touches any
//! neighbour's disc (∞ outside every RVO, so the penalty is then the distance to
//! `v_pref` alone), and `w` the aggressiveness factor [`SAFETY_FACTOR_RADII`] radii. The
//! change of velocity is then limited to `max_accel · h` (the admissible
//! velocities of section 5.1) and the speed to `max_speed`.
//!
//! Two agents already overlapping are at time to collision 0 for every velocity
//! that brings them closer ([`TC_FLOOR_S`] keeps the penalty finite so the
//! distance term still orders those), and out of each other's obstacle for the
//! velocities that part them.
//!
//! The draws come from a [`SplitMix64`] seeded by the run's seed, agent after
//! agent in index order: the same seed gives the same trajectory. The buffers are
//! sized in [`Rvo::new`]; a step allocates nothing.
//!
//! # What it is not
//! The velocity obstacle is the whole cone, with no time horizon (ORCA's is
//! truncated): a collision however far ahead costs `w / tc`. Walking at speed `s`
//! towards a neighbour standing with a gap `g` between the discs, `tc = g / 2s`
//! (reciprocal: the closing speed counts twice), so the penalty is `2 w s / g +
//! ‖v_pref − v'‖`, which grows with `s` while `g < 2 w` (ten radii): an agent with
//! a neighbour standing in line beyond its target stops short of it rather than
//! walk in, and a packed formation fills slowly or not at all (docs/transforms.md,
//! "Baselines", has the numbers). No static obstacles (the scene's circles are handled by `run.rs` projecting
//! agents out of them, as for ORCA), no kinematic model beyond the acceleration
//! and speed limits, no hybrid RVO (HRVO) and no ORCA half-planes: a velocity
//! inside an RVO may be chosen when every sample is (a crowd pressed together),
//! so overlaps can happen; they are measured, not removed (the preset has no
//! contact step).

use super::nearest::NearestLists;
use super::params::MoveParams;
use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// Candidate velocities drawn per agent and step (the RVO library's 250).
pub const SAMPLES: usize = 250;
/// `w` of the penalty (VdBLM08 section 5.2), in agent radii: how much a short
/// time to collision weighs against leaving the preferred velocity (a length, so
/// that `w / tc` is a speed). The RVO library's default safety factor is 7.5 for
/// its example agents of radius 1.5: five radii (0.75 m at 0.15 m). Taken in
/// metres as it stands, 7.5 m would make agents of 0.15 m stop short of any
/// target with a neighbour standing beyond it.
pub const SAFETY_FACTOR_RADII: f64 = 5.0;
/// Most neighbours an agent avoids at once (the library's `maxNeighbors`).
pub const MAX_NEIGHBOURS: usize = 10;
/// Neighbours farther than this many agent radii are not avoided (the library's
/// neighbour distance, 15 for agents of radius 1.5 in its examples).
pub const NEIGHBOUR_RADII: f64 = 10.0;
/// Smallest time to collision of the penalty (s): two agents already in contact
/// and approaching are at `tc = 0`, which would make every such velocity's
/// penalty infinite and equal.
pub const TC_FLOOR_S: f64 = 1e-3;

/// The RVO mover's buffers and random draws.
#[derive(Clone, Debug)]
pub(crate) struct Rvo {
    near: NearestLists,
    rng: SplitMix64,
    out: Vec<Vec2>,
}

/// When a disc at offset `d` from the moving point, of radius `r_sum`, is first
/// touched moving at `w` (s): ∞ if never, 0 if already touching and closing in.
/// The smaller root of `‖t w − d‖² = r_sum²` (VdBLM08 section 5.2's `tc`).
pub(crate) fn time_to_collision(d: Vec2, w: Vec2, r_sum: f64) -> f64 {
    let c = d.norm_squared() - r_sum * r_sum;
    let b = w.dot(&d);
    if c <= 0.0 {
        return if b > 0.0 { 0.0 } else { f64::INFINITY };
    }
    let a = w.norm_squared();
    if b <= 0.0 || a <= 0.0 {
        return f64::INFINITY;
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    (b - disc.sqrt()) / a
}

impl Rvo {
    /// Buffers for `n` agents, draws from `seed`.
    pub(crate) fn new(n: usize, seed: u64) -> Rvo {
        Rvo {
            near: NearestLists::new(n, MAX_NEIGHBOURS),
            // A stream of its own, apart from the run's desired-speed draws.
            rng: SplitMix64::new(seed ^ 0x5256_4f5f_5256_4f00),
            out: vec![Vec2::zeros(); n],
        }
    }

    /// Agent `i`'s penalty for candidate `v` (VdBLM08 section 5.2).
    fn penalty(&self, i: usize, v: Vec2, pos: &[Vec2], vel: &[Vec2], pref: Vec2, r: f64) -> f64 {
        let mut tc = f64::INFINITY;
        for j in self.near.of(i) {
            // Reciprocal: A's velocity relative to B if B takes the mirrored half.
            let w = 2.0 * v - vel[i] - vel[j];
            tc = tc.min(time_to_collision(pos[j] - pos[i], w, 2.0 * r));
        }
        let avoid = if tc.is_finite() {
            SAFETY_FACTOR_RADII * r / tc.max(TC_FLOOR_S)
        } else {
            0.0
        };
        avoid + (pref - v).norm()
    }

    /// Sets `vel[i]` of every agent not `settled` to its RVO velocity for the
    /// preferred `preferred[i]`, over a step of `h` seconds; settled agents get zero.
    pub(crate) fn velocities(
        &mut self,
        pos: &[Vec2],
        vel: &mut [Vec2],
        preferred: &[Vec2],
        settled: &[bool],
        p: &MoveParams,
        h: f64,
    ) {
        let n = pos.len();
        let r = p.radius_m;
        let vmax = p.max_speed_m_s.max(0.0);
        self.near.build(pos, NEIGHBOUR_RADII * r);
        for i in 0..n {
            if settled[i] {
                self.out[i] = Vec2::zeros();
                continue;
            }
            let pref = preferred[i];
            let mut best = pref;
            let mut best_penalty = self.penalty(i, pref, pos, vel, pref, r);
            for _ in 0..SAMPLES {
                // Uniform in the disc of radius max speed.
                let rho = vmax * self.rng.unit().sqrt();
                let phi = std::f64::consts::TAU * self.rng.unit();
                let v = Vec2::new(rho * phi.cos(), rho * phi.sin());
                let pen = self.penalty(i, v, pos, vel, pref, r);
                if pen < best_penalty {
                    best = v;
                    best_penalty = pen;
                }
            }
            // Admissible velocities (section 5.1): within max_accel · h of the
            // current one, and at most max speed.
            let dv = best - vel[i];
            let dv_max = p.max_accel_m_s2.max(0.0) * h;
            let dn = dv.norm();
            let mut v = if dn > dv_max {
                vel[i] + dv * (dv_max / dn)
            } else {
                best
            };
            let vn = v.norm();
            if vn > vmax {
                v *= vmax / vn;
            }
            self.out[i] = v;
        }
        vel.copy_from_slice(&self.out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_to_collision_is_the_first_touch() {
        // Disc of radius 1 at 5 m ahead, closing at 2 m/s: touches at 2 s.
        let t = time_to_collision(Vec2::new(5.0, 0.0), Vec2::new(2.0, 0.0), 1.0);
        assert!((t - 2.0).abs() < 1e-12, "{t}");
        // Moving away or passing wide: never.
        assert!(time_to_collision(Vec2::new(5.0, 0.0), Vec2::new(-1.0, 0.0), 1.0).is_infinite());
        assert!(time_to_collision(Vec2::new(5.0, 0.0), Vec2::new(1.0, 1.0), 1.0).is_infinite());
        // Touching already: 0 when closing in, ∞ when parting.
        assert_eq!(
            time_to_collision(Vec2::new(0.5, 0.0), Vec2::new(1.0, 0.0), 1.0),
            0.0
        );
        assert!(time_to_collision(Vec2::new(0.5, 0.0), Vec2::new(-1.0, 0.0), 1.0).is_infinite());
    }

    #[test]
    fn the_preferred_velocity_wins_when_free_and_is_left_when_it_collides() {
        let p = MoveParams::default();
        let pos = [Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0)];
        let pref = [Vec2::new(1.0, 0.0), Vec2::new(-1.0, 0.0)];
        // Far apart sideways: nothing in range, the preferred velocity is free.
        let far = [Vec2::new(0.0, 0.0), Vec2::new(0.0, 50.0)];
        let mut rvo = Rvo::new(2, 1);
        let mut vel = pref;
        rvo.velocities(&far, &mut vel, &pref, &[false; 2], &p, 1.0);
        assert_eq!(vel, pref);
        // Head-on at 2 m: both swerve, to opposite sides relative to their heading
        // or at least off the line, and each keeps moving forward.
        let mut vel = pref;
        rvo.velocities(&pos, &mut vel, &pref, &[false; 2], &p, 1.0);
        for (v, w) in vel.iter().zip(&pref) {
            assert!(v.y.abs() > 1e-3, "{v:?}");
            assert!(v.dot(w) > 0.0, "{v:?}");
        }
    }
}
