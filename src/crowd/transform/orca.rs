//! The ORCA baseline of formation-transform section 5.4 (the paper compared with
//! RVO, ORCA and OpenSteer): each moving agent's wanted velocity, towards its
//! target at its desired speed with the same arrival ramp as the social force
//! model, made collision-free for a time horizon by optimal reciprocal collision
//! avoidance (van den Berg et al. 2011; the `dodgy_2d` crate, a port of RVO2).
//!
//! Neighbours come from the grid: the [`MAX_NEIGHBOURS`] nearest within
//! `2 r + horizon · max speed`, as RVO2 limits them. Settled agents are neighbours
//! that do not move (they take almost none of the avoidance). `dodgy_2d` computes
//! in `f32` and builds its constraint lines in a vector of its own per call: the
//! baseline allocates there, the social force model does not.

use super::params::MoveParams;
use crate::crowd::agents::NeighbourGrid;
use crate::geom::Vec2;
use dodgy_2d::{Agent, AvoidanceOptions, Vec2 as V2};
use std::borrow::Cow;

/// Most neighbours an agent avoids at once (RVO2's default `maxNeighbors`).
pub const MAX_NEIGHBOURS: usize = 10;
/// How far ahead collisions with other agents are avoided (s).
pub const TIME_HORIZON_S: f64 = 1.0;

/// ORCA's buffers for `n` agents.
#[derive(Clone, Debug)]
pub(crate) struct Orca {
    grid: NeighbourGrid,
    /// `MAX_NEIGHBOURS` (distance², index) slots per agent.
    near: Vec<(f64, u32)>,
    near_len: Vec<u8>,
    out: Vec<Vec2>,
    agents: Vec<Cow<'static, Agent>>,
}

impl Orca {
    /// Buffers for `n` agents.
    pub(crate) fn new(n: usize) -> Orca {
        Orca {
            grid: NeighbourGrid::with_capacity(n),
            near: vec![(0.0, 0); n * MAX_NEIGHBOURS],
            near_len: vec![0; n],
            out: vec![Vec2::zeros(); n],
            agents: Vec::with_capacity(MAX_NEIGHBOURS),
        }
    }

    fn offer(&mut self, i: usize, j: usize, d2: f64) {
        let slots = &mut self.near[i * MAX_NEIGHBOURS..(i + 1) * MAX_NEIGHBOURS];
        let len = self.near_len[i] as usize;
        if len < MAX_NEIGHBOURS {
            slots[len] = (d2, j as u32);
            self.near_len[i] += 1;
            return;
        }
        let (far, far_d2) =
            slots.iter().enumerate().fold(
                (0, f64::MIN),
                |b, (k, s)| if s.0 > b.1 { (k, s.0) } else { b },
            );
        if d2 < far_d2 {
            slots[far] = (d2, j as u32);
        }
    }

    /// Sets `vel[i]` of every agent not `settled` to ORCA's velocity for the wanted
    /// `preferred[i]`, over a step of `h` seconds; settled agents get zero.
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
        let range = 2.0 * p.radius_m + TIME_HORIZON_S * p.max_speed_m_s;
        self.grid.build(pos, range);
        self.near_len.fill(0);
        // Offer every close pair to both agents' lists.
        let grid = std::mem::take(&mut self.grid);
        grid.for_each_pair(pos, range, |i, j, d, _| {
            self.offer(i, j, d * d);
            self.offer(j, i, d * d);
        });
        self.grid = grid;
        let to = |v: Vec2| V2::new(v.x as f32, v.y as f32);
        let me = |k: usize, vel: &[Vec2]| Agent {
            position: to(pos[k]),
            velocity: to(vel[k]),
            radius: p.radius_m as f32,
            avoidance_responsibility: if settled[k] { 1e-3 } else { 1.0 },
        };
        let options = AvoidanceOptions {
            obstacle_margin: p.radius_m as f32,
            time_horizon: TIME_HORIZON_S as f32,
            obstacle_time_horizon: TIME_HORIZON_S as f32,
        };
        for i in 0..n {
            if settled[i] {
                self.out[i] = Vec2::zeros();
                continue;
            }
            self.agents.clear();
            let len = self.near_len[i] as usize;
            for s in 0..len {
                let j = self.near[i * MAX_NEIGHBOURS + s].1 as usize;
                self.agents.push(Cow::Owned(me(j, vel)));
            }
            let v = me(i, vel).compute_avoiding_velocity(
                &self.agents,
                &[],
                to(preferred[i]),
                p.max_speed_m_s as f32,
                h as f32,
                &options,
            );
            self.out[i] = Vec2::new(v.x as f64, v.y as f64);
        }
        vel.copy_from_slice(&self.out);
    }
}
