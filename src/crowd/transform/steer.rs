//! The OpenSteer baseline of formation-transform section 5.4 (Table 3): steering
//! behaviours for autonomous characters (Reynolds 1999, "Steering Behaviors for
//! Autonomous Characters"), combined as OpenSteer's pedestrian plug-in combines
//! them, on OpenSteer's `SimpleVehicle` point mass.
//!
//! # What it is
//! Every moving agent is a vehicle of unit mass with a forward direction (its
//! velocity's, kept while it stands), a max force (the run's `max_accel`) and a
//! max speed. Each step its steering force is
//!
//! - **predictive avoidance** (OpenSteer's `steerToAvoidNeighbors`): first, if a
//!   neighbour's disc touches its own, the component of the direction away from
//!   the nearest such neighbour perpendicular to its forward; otherwise, among the
//!   neighbours whose time of nearest approach (both keeping their velocities;
//!   Reynolds 1999, "unaligned collision avoidance") lies within
//!   [`LEAD_TIME_S`] and whose centres then pass closer than [`DANGER_RADII`]
//!   radii, the one reached soonest is the threat, and the vehicle steers
//!   sideways (along its side vector, to the side away from the threat's
//!   position at nearest approach when head-on, from its position now when
//!   parallel, and for a crossing threat away from its velocity if it is no
//!   faster), with [`AVOID_SHARE`] of max force. The look-ahead ends at the
//!   target (no further than the distance to it at the speed now): a vehicle
//!   stops there, and a neighbour standing beyond its target is no threat;
//! - plus **arrival** (Reynolds' "arrival", OpenSteer's `steerForSeek` towards a
//!   ramped desired velocity): `(v_des − v) / SEEK_TIME_S`, `v_des` the run's
//!   wanted velocity (towards the target at the agent's desired speed, ramped down
//!   to `sqrt(2 · arrival_decel · distance)` near it);
//! - plus **separation** (OpenSteer's `steerForSeparation`, as its boids weigh
//!   it): the sum over neighbours within [`SEPARATION_RADII`] radii of `−offset /
//!   ‖offset‖²`, normalised, times [`SEPARATION_M_S2`].
//!
//! The force is truncated to max force, applied for the step (`v += F h`), the
//! velocity truncated to max speed (`SimpleVehicle::applySteeringForce`), and the
//! forward direction follows the velocity. Neighbours are the
//! [`MAX_NEIGHBOURS`] nearest within the distance two vehicles at max speed close
//! in [`LEAD_TIME_S`], as OpenSteer's proximity database gives them. Nothing is
//! drawn at random; the buffers are sized in [`Steering::new`].
//!
//! # What it is not
//! Not the pedestrian plug-in's priority: there the avoidance (times 10, so at
//! max force after truncation) takes the place of path following; here it is
//! blended with the arrival, which keeps braking (with the priority, the vehicles
//! of a packed formation push each other sideways at max force with nothing to
//! stop them: 5 of 100 agents arrived in 60 s crossing into a lattice of 2.2
//! radii, 100 of 100 in 31 s blended). No path following, no wander (the plug-in's small random heading noise), no
//! obstacle avoidance (the scene's circles are handled by `run.rs` projecting
//! agents out of them), no acceleration smoothing (OpenSteer blends successive
//! accelerations and limits backward steering at low speed; here the force acts as
//! computed), no alignment or cohesion (the boids' other two rules: a formation
//! transform gives every agent a target of its own). Nothing guarantees that
//! discs do not overlap: overlaps are measured, not removed (the preset has no
//! contact step).

use super::nearest::NearestLists;
use super::params::MoveParams;
use crate::geom::Vec2;

/// How far ahead the predictive avoidance looks (s): the pedestrian plug-in's
/// collision-avoidance lead time `caLeadTime`.
pub const LEAD_TIME_S: f64 = 3.0;
/// Two vehicles whose centres pass closer than this many radii are a threat
/// (`collisionDangerThreshold`: two radii, the discs touch).
pub const DANGER_RADII: f64 = 2.0;
/// Cosine of 45°: forward vectors more aligned than this are parallel, more
/// opposed head-on, in between crossing (`steerToAvoidNeighbors`' 0.707).
pub const PARALLEL_COS: f64 = 0.707;
/// Arrival's time to reach the desired velocity (s): OpenSteer's force is the
/// velocity difference itself, applied for the step, i.e. over one second.
pub const SEEK_TIME_S: f64 = 1.0;
/// Neighbours closer than this many radii push the vehicle away (separation).
pub const SEPARATION_RADII: f64 = 2.5;
/// Weight of the normalised separation (m/s²): below the arrival's pull at half
/// an agent radius from the target, so that an agent among neighbours standing at
/// their own targets still comes within its radius of its target.
pub const SEPARATION_M_S2: f64 = 0.3;
/// The lateral avoidance's force as a share of max force, added to the arrival's
/// (blended, not prioritised: with the avoidance in place of the arrival, as the
/// pedestrian plug-in does it, nothing brakes a vehicle pushed sideways in a
/// packed crowd, and the vehicles of a dense formation drift at max speed).
pub const AVOID_SHARE: f64 = 0.5;
/// Most neighbours a vehicle looks at.
pub const MAX_NEIGHBOURS: usize = 10;

/// The steering mover's buffers.
#[derive(Clone, Debug)]
pub(crate) struct Steering {
    near: NearestLists,
    /// Each vehicle's forward direction (unit; zero until it first moves or
    /// wants to).
    forward: Vec<Vec2>,
    out: Vec<Vec2>,
}

/// `v` scaled down to length `max` if longer (OpenSteer's `truncateLength`).
fn truncate(v: Vec2, max: f64) -> Vec2 {
    let n = v.norm();
    if n > max && n > 0.0 {
        v * (max / n)
    } else {
        v
    }
}

/// The side vector of forward `f`: `f` turned a quarter to the left.
fn side(f: Vec2) -> Vec2 {
    Vec2::new(-f.y, f.x)
}

/// When two points at `dp` apart (other minus own) with relative velocity `dv`
/// (other minus own) are nearest (s; 0 when they move together). OpenSteer's
/// `predictNearestApproachTime`.
pub(crate) fn nearest_approach_time(dp: Vec2, dv: Vec2) -> f64 {
    let s2 = dv.norm_squared();
    if s2 <= 0.0 {
        return 0.0;
    }
    -dp.dot(&dv) / s2
}

impl Steering {
    /// Buffers for `n` vehicles, each first facing its wanted direction.
    pub(crate) fn new(n: usize) -> Steering {
        Steering {
            near: NearestLists::new(n, MAX_NEIGHBOURS),
            forward: vec![Vec2::zeros(); n],
            out: vec![Vec2::zeros(); n],
        }
    }

    /// The lateral avoidance of vehicle `i` (unit or zero): touching neighbours
    /// first, then the soonest threat within the lead time.
    fn avoid(&self, i: usize, pos: &[Vec2], vel: &[Vec2], dist_m: f64, r: f64) -> Vec2 {
        let f = self.forward[i];
        // steerToAvoidCloseNeighbors: the nearest neighbour touching now.
        if let Some(j) = self.near.of(i).next() {
            let away = pos[i] - pos[j];
            if away.norm() < 2.0 * r {
                let lateral = away - f * away.dot(&f);
                let n = lateral.norm();
                return if n > 1e-12 { lateral / n } else { side(f) };
            }
        }
        // Look ahead no further than the time to the target at the speed now: a
        // pedestrian's path ends there (its ray beyond is not where it goes).
        let speed = vel[i].norm();
        let mut soonest = if speed > 1e-9 {
            LEAD_TIME_S.min(dist_m / speed)
        } else {
            LEAD_TIME_S
        };
        let mut threat: Option<(usize, Vec2)> = None;
        for j in self.near.of(i) {
            let t = nearest_approach_time(pos[j] - pos[i], vel[j] - vel[i]);
            if !(0.0..soonest).contains(&t) {
                continue;
            }
            let (mine, theirs) = (pos[i] + vel[i] * t, pos[j] + vel[j] * t);
            if (theirs - mine).norm() < DANGER_RADII * r {
                soonest = t;
                threat = Some((j, theirs));
            }
        }
        let Some((j, at_approach)) = threat else {
            return Vec2::zeros();
        };
        let s = side(f);
        let parallelness = f.dot(&self.forward[j]);
        let away_from = |x: Vec2| if x.dot(&s) > 0.0 { -s } else { s };
        if parallelness < -PARALLEL_COS {
            // Head-on: away from where the threat will be.
            away_from(at_approach - pos[i])
        } else if parallelness > PARALLEL_COS {
            // Parallel: away from where it is.
            away_from(pos[j] - pos[i])
        } else if vel[j].norm() <= vel[i].norm() {
            // Crossing, and no faster: away from its velocity.
            away_from(vel[j])
        } else {
            // Crossing and faster: it is its to avoid.
            Vec2::zeros()
        }
    }

    /// Separation of vehicle `i` (unit or zero).
    fn separation(&self, i: usize, pos: &[Vec2], r: f64) -> Vec2 {
        let mut sum = Vec2::zeros();
        for j in self.near.of(i) {
            let offset = pos[j] - pos[i];
            let d2 = offset.norm_squared();
            if d2 > 0.0 && d2 < (SEPARATION_RADII * r).powi(2) {
                sum -= offset / d2;
            }
        }
        let n = sum.norm();
        if n > 1e-12 {
            sum / n
        } else {
            Vec2::zeros()
        }
    }

    /// Sets `vel[i]` of every vehicle not `settled` after a step of `h` seconds
    /// steering towards the wanted velocity `wanted[i]` (`dist[i]` from its target);
    /// settled ones get zero.
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
        let n = pos.len();
        let r = p.radius_m;
        let (fmax, vmax) = (p.max_accel_m_s2.max(0.0), p.max_speed_m_s.max(0.0));
        for i in 0..n {
            let v = vel[i].norm();
            let w = wanted[i].norm();
            if v > 1e-9 {
                self.forward[i] = vel[i] / v;
            } else if w > 1e-9 && self.forward[i] == Vec2::zeros() {
                // Never moved yet: face where it wants to go.
                self.forward[i] = wanted[i] / w;
            }
        }
        self.near.build(pos, 2.0 * r + 2.0 * LEAD_TIME_S * vmax);
        for i in 0..n {
            if settled[i] {
                self.out[i] = Vec2::zeros();
                continue;
            }
            let avoid = self.avoid(i, pos, vel, dist[i], r);
            let force = (wanted[i] - vel[i]) / SEEK_TIME_S
                + avoid * (AVOID_SHARE * fmax)
                + self.separation(i, pos, r) * SEPARATION_M_S2;
            // SimpleVehicle::applySteeringForce: truncate to max force, unit mass,
            // then truncate the new velocity to max speed.
            self.out[i] = truncate(vel[i] + truncate(force, fmax) * h, vmax);
        }
        vel.copy_from_slice(&self.out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_approach_is_when_the_gap_stops_closing() {
        // 4 m ahead, closing at 2 m/s: nearest in 2 s.
        let t = nearest_approach_time(Vec2::new(4.0, 1.0), Vec2::new(-2.0, 0.0));
        assert!((t - 2.0).abs() < 1e-12, "{t}");
        // Parting: in the past.
        assert!(nearest_approach_time(Vec2::new(4.0, 0.0), Vec2::new(1.0, 0.0)) < 0.0);
        assert_eq!(
            nearest_approach_time(Vec2::new(4.0, 0.0), Vec2::zeros()),
            0.0
        );
    }

    #[test]
    fn force_and_speed_are_truncated() {
        let p = MoveParams::default();
        let mut s = Steering::new(1);
        let mut vel = [Vec2::zeros()];
        // Wanting 10 m/s at once: the force is cut to max force, then the speed.
        s.velocities(
            &[Vec2::zeros()],
            &mut vel,
            &[Vec2::new(10.0, 0.0)],
            &[10.0],
            &[false],
            &p,
            0.1,
        );
        assert!((vel[0].x - p.max_accel_m_s2 * 0.1).abs() < 1e-12, "{vel:?}");
        let mut vel = [Vec2::new(p.max_speed_m_s, 0.0)];
        s.velocities(
            &[Vec2::zeros()],
            &mut vel,
            &[Vec2::new(10.0, 0.0)],
            &[10.0],
            &[false],
            &p,
            0.1,
        );
        assert!((vel[0].norm() - p.max_speed_m_s).abs() < 1e-12, "{vel:?}");
    }
}
