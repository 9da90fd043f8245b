//! The objective measures of formation-transform section 5.1: `I_d` (eq. 17, with
//! `I_v` beside it; computed in `feedback.rs`), the spread of the agents' nearest
//! neighbour distances `σ_min_dis` (eq. 24) and the spread of their current efforts
//! `σ_curr_eft` (eqs. 25–26); and the crowd's heading-change rate, the
//! "fluctuation" of moving directions section 5.3 (Fig. 12) says the feedback
//! removes.

use crate::crowd::agents::NeighbourGrid;
use crate::geom::Vec2;

/// The three measures of section 5.1 (and `I_v`), for one instant or averaged.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Measures {
    /// `I_d`, eq. 17 (bits).
    pub i_d: f64,
    /// `I_v`: as `I_d`, with speed bins for directions (bits).
    pub i_v: f64,
    /// `σ_min_dis`, eq. 24 (m).
    pub sigma_min_dis_m: f64,
    /// `σ_curr_eft`, eq. 26 (m).
    pub sigma_curr_eft_m: f64,
    /// The mean absolute heading-change rate of the moving agents (rad/s),
    /// [`HeadingChange`]: section 5.3's fluctuation.
    pub heading_change_rad_s: f64,
}

/// An agent moves, for the heading-change rate, when faster than this at both
/// ends of a step (m/s): slower, its direction is mostly the fluctuation `ξ` and
/// the contacts' pushes, not where it walks.
pub const MOVING_SPEED_M_S: f64 = 0.1;

/// The crowd's mean absolute heading-change rate (section 5.3, Fig. 12: the
/// "fluctuation" of the moving directions): over the agents faster than
/// [`MOVING_SPEED_M_S`] at both the previous and the current step, the mean of
/// `|Δθ_a| / Δt`, `Δθ_a ∈ (−π, π]` the signed angle from the previous velocity's
/// direction to the current one (`atan2(v_prev × v, v_prev · v)`, so the wrap is
/// exact). An agent walking a circle of radius `r` at speed `v` gives `v / r`; one
/// walking straight 0. Zero when no agent qualifies. Keeps the previous step's
/// velocities in a buffer sized once: no allocation per step.
#[derive(Clone, Debug)]
pub struct HeadingChange {
    previous: Vec<Vec2>,
}

impl HeadingChange {
    /// For `n` agents, all at rest before the first step.
    pub fn new(n: usize) -> HeadingChange {
        HeadingChange {
            previous: vec![Vec2::zeros(); n],
        }
    }

    /// The rate (rad/s) between the velocities of the last call and `velocities`,
    /// `dt_s` apart; `velocities` kept for the next call. Zero for a `dt_s` that is
    /// not positive and finite, or another number of agents (nothing kept then).
    pub fn rate(&mut self, velocities: &[Vec2], dt_s: f64) -> f64 {
        if velocities.len() != self.previous.len() || !(dt_s.is_finite() && dt_s > 0.0) {
            return 0.0;
        }
        let moving2 = MOVING_SPEED_M_S * MOVING_SPEED_M_S;
        let (mut sum_rad, mut k) = (0.0, 0usize);
        for (p, v) in self.previous.iter_mut().zip(velocities) {
            if p.norm_squared() > moving2 && v.norm_squared() > moving2 {
                sum_rad += crate::geom::cross(*p, *v).atan2(p.dot(v)).abs();
                k += 1;
            }
            *p = *v;
        }
        if k == 0 {
            0.0
        } else {
            sum_rad / k as f64 / dt_s
        }
    }
}

/// Population standard deviation `sqrt(Σ (x − μ)² / N)` of the values `f(i)`,
/// `i < n` (eqs. 24, 26), in two passes; zero for `n = 0`.
pub(crate) fn std_dev(n: usize, f: impl Fn(usize) -> f64) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mean = (0..n).map(&f).sum::<f64>() / n as f64;
    ((0..n).map(|i| (f(i) - mean).powi(2)).sum::<f64>() / n as f64).sqrt()
}

/// `σ_min_dis` (eq. 24): the deviation of each agent's distance to its nearest
/// neighbour `min_dis(i)`, found with `grid` (built on `pos`) by
/// [`nearest_distances`] and left in `nearest`; with the smallest of them. `(0, ∞)`
/// for fewer than two agents.
#[cfg(test)]
pub(crate) fn sigma_min_dis(grid: &NeighbourGrid, pos: &[Vec2], nearest: &mut [f64]) -> (f64, f64) {
    nearest_distances(grid, pos, nearest, |_, _, _| {});
    spread_and_min(&nearest[..pos.len()])
}

/// The deviation (eq. 24) and the smallest of the nearest-neighbour distances
/// `nearest`; `(0, ∞)` for fewer than two.
pub(crate) fn spread_and_min(nearest: &[f64]) -> (f64, f64) {
    let min = nearest.iter().cloned().fold(f64::INFINITY, f64::min);
    if nearest.len() < 2 {
        return (0.0, min);
    }
    (std_dev(nearest.len(), |i| nearest[i]), min)
}

/// Each agent's distance to its nearest other agent into `nearest` (m, `∞` when
/// alone), `grid` built on `pos`. One pass over the pairs closer than the grid's
/// cell side finds it for every agent with a neighbour that near (each such pair
/// is also handed to `visit(i, j, squared distance)`); the others, in sparse
/// places, by the grid's ring search. The same values as a ring search for every
/// agent, without one.
pub(crate) fn nearest_distances(
    grid: &NeighbourGrid,
    pos: &[Vec2],
    nearest: &mut [f64],
    mut visit: impl FnMut(usize, usize, f64),
) {
    let n = pos.len();
    let best2 = &mut nearest[..n];
    best2.fill(f64::INFINITY);
    grid.for_each_pair_d2(pos, grid.cell_m(), |i, j, _, d2| {
        best2[i] = best2[i].min(d2);
        best2[j] = best2[j].min(d2);
        visit(i, j, d2);
    });
    for (i, m) in best2.iter_mut().enumerate() {
        *m = if m.is_finite() {
            m.sqrt()
        } else {
            grid.nearest_distance(pos, i)
        };
    }
}

/// `σ_curr_eft` (eq. 26) of `curr_eft(i) = |s_i − pos(a_i)|` (eq. 25).
pub(crate) fn sigma_curr_eft(sources: &[Vec2], pos: &[Vec2]) -> f64 {
    std_dev(pos.len(), |i| (sources[i] - pos[i]).norm())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_min_dis_matches_the_direct_formula() {
        // Three agents on a line at 0, 1, 3: nearest distances 1, 1, 2.
        let pos = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(3.0, 0.0),
        ];
        let mut g = NeighbourGrid::with_capacity(3);
        g.build(&pos, 0.5);
        let mean = 4.0 / 3.0;
        let want = ((2.0 * (1.0f64 - mean).powi(2) + (2.0f64 - mean).powi(2)) / 3.0).sqrt();
        let mut nearest = [0.0; 3];
        let (sigma, min) = sigma_min_dis(&g, &pos, &mut nearest);
        assert!((sigma - want).abs() < 1e-12);
        assert_eq!((min, nearest), (1.0, [1.0, 1.0, 2.0]));
        // A square lattice: every nearest distance equal.
        let lattice: Vec<Vec2> = (0..100)
            .map(|i| Vec2::new((i % 10) as f64 * 0.8, (i / 10) as f64 * 0.8))
            .collect();
        let mut g = NeighbourGrid::with_capacity(100);
        g.build(&lattice, 1.0);
        let mut nearest = [0.0; 100];
        let (sigma, min) = sigma_min_dis(&g, &lattice, &mut nearest);
        assert!(sigma < 1e-12 && (min - 0.8).abs() < 1e-12);
    }

    #[test]
    fn nearest_distances_match_brute_force_dense_and_sparse() {
        // A dense cluster (neighbours within a cell) and scattered stragglers (found
        // by the ring search), with the pairs handed over checked too.
        let mut r = crate::rng::SplitMix64::new(7);
        let mut pos: Vec<Vec2> = (0..200)
            .map(|_| Vec2::new(r.uniform(0.0, 5.0), r.uniform(0.0, 5.0)))
            .collect();
        pos.extend((0..20).map(|_| Vec2::new(r.uniform(10.0, 60.0), r.uniform(-40.0, 0.0))));
        pos.push(pos[3]);
        let mut g = NeighbourGrid::with_capacity(pos.len());
        g.build(&pos, 0.6);
        let mut nearest = vec![0.0; pos.len()];
        let mut seen = vec![];
        nearest_distances(&g, &pos, &mut nearest, |i, j, d2| {
            assert_eq!(d2, (pos[i] - pos[j]).norm_squared());
            seen.push((i.min(j), i.max(j)));
        });
        for i in 0..pos.len() {
            let brute = (0..pos.len())
                .filter(|&j| j != i)
                .map(|j| (pos[i] - pos[j]).norm())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(nearest[i], brute, "agent {i}");
        }
        seen.sort();
        let c = g.cell_m();
        let want: Vec<(usize, usize)> = (0..pos.len())
            .flat_map(|i| (i + 1..pos.len()).map(move |j| (i, j)))
            .filter(|&(i, j)| (pos[i] - pos[j]).norm_squared() < c * c)
            .collect();
        assert_eq!(seen, want);
        assert!(nearest[200..220].iter().any(|&d| d > c));
    }

    #[test]
    fn heading_change_of_circle_walkers_is_speed_over_radius() {
        // Agents on circles of radius 2 m at 1.2 m/s, starting at different
        // angles and turning either way: v / r = 0.6 rad/s; a straight walker 0.
        let (r_m, v_m_s, dt_s) = (2.0, 1.2, 1.0 / 60.0);
        let omega = v_m_s / r_m;
        let vel_at = |t: f64, k: usize| {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            let a = k as f64 * 0.7 + sign * omega * t;
            Vec2::new(-a.sin(), a.cos()) * (sign * v_m_s)
        };
        let mut h = HeadingChange::new(8);
        let mut vel = vec![Vec2::zeros(); 8];
        // From rest: no agent moved before, nothing to measure.
        vel.iter_mut()
            .enumerate()
            .for_each(|(k, v)| *v = vel_at(0.0, k));
        assert_eq!(h.rate(&vel, dt_s), 0.0);
        for step in 1..=100 {
            let t = step as f64 * dt_s;
            vel.iter_mut()
                .enumerate()
                .for_each(|(k, v)| *v = vel_at(t, k));
            let rate = h.rate(&vel, dt_s);
            assert!((rate - omega).abs() < 1e-9, "step {step}: {rate}");
        }
        let mut straight = HeadingChange::new(2);
        let walk = [Vec2::new(1.3, 0.4), Vec2::new(-0.2, 0.9)];
        for _ in 0..10 {
            assert_eq!(straight.rate(&walk, dt_s), 0.0);
        }
    }

    #[test]
    fn heading_change_wraps_and_skips_slow_agents() {
        let dt_s = 0.5;
        let mut h = HeadingChange::new(3);
        let before = [
            Vec2::new(1.0, 0.0),
            Vec2::new(-1.0, 1e-9),
            Vec2::new(0.05, 0.0),
        ];
        let _ = h.rate(&before, dt_s);
        // Agent 0 turns a quarter left, agent 1 crosses the ±π seam by a small
        // angle (not 2π), agent 2 is too slow to count.
        let after = [
            Vec2::new(0.0, 2.0),
            Vec2::new(-1.0, -1e-9),
            Vec2::new(0.0, 0.05),
        ];
        let want = (std::f64::consts::FRAC_PI_2 + 2e-9) / 2.0 / dt_s;
        assert!((h.rate(&after, dt_s) - want).abs() < 1e-9);
        // A reversal is π, and a wrong length or step measures nothing.
        let back = [-after[0], -after[1], after[2]];
        let pi_rate = std::f64::consts::PI / dt_s;
        assert!((h.rate(&back, dt_s) - pi_rate).abs() < 1e-9);
        assert_eq!(h.rate(&back[..2], dt_s), 0.0);
        assert_eq!(h.rate(&back, 0.0), 0.0);
    }

    #[test]
    fn sigma_curr_eft_matches_the_direct_formula() {
        let s = [Vec2::zeros(); 4];
        let p = [
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 2.0),
            Vec2::new(-3.0, 0.0),
            Vec2::new(0.0, -4.0),
        ];
        // Efforts 1, 2, 3, 4: mean 2.5, variance 1.25.
        assert!((sigma_curr_eft(&s, &p) - 1.25f64.sqrt()).abs() < 1e-12);
    }
}
