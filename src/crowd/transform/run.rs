//! A transform running: each agent walks to its target by the social force model
//! with subgroup terms and mutual-information feedback (formation-transform
//! sections 3.3, 3.5; forces in `social.rs`, feedback in `feedback.rs`), or by one
//! of the baselines of section 5.4 (`baseline.rs`: ORCA, RVO, steering); the
//! measures of section 5.1 every step.
//!
//! # One step
//! In substeps of at most [`MoveParams::max_substep_s`]:
//! 1. each moving agent's heading `e_a` towards its target and desired speed, its
//!    own `v⁰_a` ramped down to `sqrt(2 · arrival_decel · distance)` near the
//!    target (braking evenly);
//! 2. the feedback (eqs. 17–19): `I_d`, `I_v` of the crowd now, headings and
//!    desired speeds pulled towards their bin's;
//! 3. `F` of eq. 23: driving force `(v_des e − v)/τ` (eq. 8), inter-agent and
//!    cross-subgroup repulsion, subgroup attraction, obstacles, fluctuation `ξ`;
//!    the repulsion between two agents scaled by both their fades, so agents at
//!    or near their targets neither hold off nor are held off by the others
//!    (without this the settled outer rows of a dense formation stop the agents
//!    whose targets lie behind them: 35 of 110 shipped pairs at 100 agents);
//! 4. semi-implicit Euler with `|a| ≤ max_accel`, `|v| ≤ max_speed`;
//! 5. overlaps resolved positionally: every pair closer than `2r` is moved apart
//!    along its centre line, a few rounds, the agent with farther to go moving
//!    less (it has right of way: settled agents step aside for one walking
//!    through and walk back after); agents out of obstacles;
//! 6. head-on blocks undone: two walking agents in contact (and every
//!    `WIDE_SWAP_PERIOD_S` any two up to `WIDE_SWAP_RADII` radii apart), each
//!    heading for a target beyond the other, exchange targets when that shortens the sum of
//!    their remaining distances by at least [`SWAP_GAIN_RADII`] radii. Agents are
//!    interchangeable; the exchange lowers the sum of *linear* remaining
//!    distances, which is the Euclidean pairing's cost but not ΔE's (eq. 3) nor
//!    Manhattan's, so it rewrites those pairings a little. Without it, two such
//!    agents hemmed in by settled neighbours push against each other until the
//!    timeout (line → ring at 1,000 agents). Not rare with the baselines'
//!    pairings (tens to hundreds per run at 300 agents): the summary counts them
//!    (`swaps`);
//! 7. arrival: an agent within `arrive_m` of its target and slower than
//!    `settle_speed` settles (the ramp brings it in below that speed, so it stops
//!    as it enters, without overshoot): velocity zero, no forces act on it; it
//!    moves again only when a contact pushes it more than `arrive_m` off its
//!    target.
//!
//! The fades (step 3), the positional contacts (5), the exchanges (6) and the
//! settling (7) are ours, not the paper's; each has a switch in [`MoveParams`]
//! (`fades`, `contacts`, `exchanges`, `settling`), and [`MoveParams::paper`]
//! turns them all off. Without settling, arrived agents keep being driven to
//! their targets and keep interacting, and a run ends when every agent is within
//! `arrive_m` of its target at once.
//!
//! Nothing allocates in a step once [`TransformRun::new`] has sized the buffers
//! (the set of distinct overlapping pairs grows only past `4 n` such pairs, the
//! list of candidate contacts only past `4 n` pairs closer than `2 r` plus skin).
//!
//! # Work shared within a step
//! One grid (cells of the interaction range) serves the forces; the overlap rounds
//! take their pairs from a contact list made once per substep; the report finds
//! the contacts and every agent's nearest neighbour in one pass over the pairs of
//! a grid of a few radii (far fewer pairs than the interaction range holds), and
//! the next step reuses the report's `I_d`, `I_v` while it starts from exactly the
//! reported positions and velocities.

use super::baseline::Baseline;
use super::feedback::{Feedback, Information};
use super::measures::{nearest_distances, sigma_curr_eft, spread_and_min, HeadingChange, Measures};
pub use super::params::{MoveParams, Mover, SubgroupAttraction};
use super::prepare::TransformPlan;
use super::social;
use super::social_groups::Groups;
use crate::crowd::agents::{unit_or_fixed, NeighbourGrid};
use crate::crowd::environment::Scene;
use crate::geom::Vec2;
use crate::rng::SplitMix64;
use std::collections::HashSet;

/// Added to both distances to target when sharing an overlap, in agent radii (5 cm
/// at 0.15 m), so that two agents at their targets share it half each.
const YIELD_EPS_RADII: f64 = 1.0 / 3.0;

/// Two agents closer than `2 r − OVERLAP_TOLERANCE_M` overlap (m): what the
/// positional resolution may leave (it moves pairs to exactly `2 r`, and moving
/// one pair may press another).
pub const OVERLAP_TOLERANCE_M: f64 = 0.005;

/// Two blocked agents exchange targets when that shortens the sum of their
/// distances to target by at least this much, in agent radii (5 cm at 0.15 m).
pub const SWAP_GAIN_RADII: f64 = 1.0 / 3.0;

/// Two agents are in contact for an exchange of targets when closer than two
/// radii plus this much, in agent radii (1 cm at 0.15 m).
const SWAP_TOUCH_RADII: f64 = 1.0 / 15.0;

/// How often the exchange of step 6 also looks at agents a few radii apart (s).
const WIDE_SWAP_PERIOD_S: f64 = 0.25;

/// How far apart two agents may be for that wider exchange, in agent radii.
const WIDE_SWAP_RADII: f64 = 4.0;

/// Without settling, the crowd is at rest when no agent is faster than this
/// (m/s): the fluctuation `ξ` alone keeps a standing agent below `ξ τ` (0.04 m/s
/// at the defaults), an agent still walking is far above.
pub const REST_SPEED_M_S: f64 = 0.1;

/// Without settling, a run ends once the crowd has stayed at rest this long (s);
/// it came to rest when this began.
pub const REST_HOLD_S: f64 = 1.0;

/// Cell side of the grid the report finds nearest neighbours with, in agent radii.
const NEAREST_CELL_RADII: f64 = 3.0;

/// How far an agent may move during the overlap rounds before the list of
/// candidate contact pairs is made again, in agent radii (5 cm at 0.15 m).
const CONTACT_SKIN_RADII: f64 = 1.0 / 3.0;

/// One step's report.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Agents at their targets.
    pub arrived: usize,
    /// `arrived / agents`.
    pub arrived_fraction: f64,
    /// The measures now.
    pub measures: Measures,
    /// The smallest distance between two agents now (m).
    pub min_distance_m: f64,
    /// Pairs closer than two radii now.
    pub overlapping_pairs: usize,
}

/// A whole run, summarised.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSummary {
    /// Agents.
    pub agents: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub simulated_s: f64,
    /// Agents at their targets at the end, as a fraction.
    pub arrived_fraction: f64,
    /// The smallest distance between two agents at any step (m).
    pub min_distance_m: f64,
    /// Distinct pairs that were closer than two radii at some step.
    pub overlapping_pairs: usize,
    /// Mean distance walked (m).
    pub mean_travel_m: f64,
    /// Largest distance walked (m).
    pub max_travel_m: f64,
    /// The measures averaged over the steps.
    pub mean: Measures,
    /// Whether it ended by the timeout.
    pub timed_out: bool,
    /// Pairs of agents that exchanged targets to undo a head-on block (step 6).
    pub swaps: u64,
    /// Without settling: when the crowd came to rest (no agent faster than
    /// [`REST_SPEED_M_S`] from then on, for [`REST_HOLD_S`] at least), whether or
    /// not every agent is at its target then (s). `None` with settling, or when it
    /// never rested that long.
    pub rest_s: Option<f64>,
    /// Mean distance of the agents from their targets at the end (m).
    pub mean_offset_m: f64,
    /// How spread out the subgroups were at the end: the members' distance from
    /// their group's centroid over that of the layout the group should have at
    /// its progress (1: the layout's size, below 1 contracted; `social_groups.rs`).
    /// `None` without a group of two or more.
    pub subgroup_spread: Option<f64>,
    /// The same averaged over the steps.
    pub subgroup_spread_mean: Option<f64>,
}

/// A transform in progress; the agents' positions and velocities stay the caller's.
#[derive(Clone, Debug)]
pub struct TransformRun {
    targets: Vec<Vec2>,
    sources: Vec<Vec2>,
    p: MoveParams,
    rng: SplitMix64,
    groups: Groups,
    feedback: Feedback,
    /// ORCA, RVO or steering; `None`: social forces.
    baseline: Option<Baseline>,
    grid: NeighbourGrid,
    /// Grid for the candidate contact pairs of the overlap rounds.
    contact_grid: NeighbourGrid,
    /// Pairs closer than `2 r` plus twice the contact skin at `listed_at`.
    contacts: Vec<(u32, u32)>,
    /// Entries of `contacts` in use.
    contacts_len: usize,
    listed_at: Vec<Vec2>,
    /// Agent `a`'s own desired speed `v⁰_a` (m/s), evened out by eq. 19.
    v0: Vec<f64>,
    /// Heading `e_a` this substep (unit).
    e: Vec<Vec2>,
    /// Distance to the target this substep (m).
    dist: Vec<f64>,
    /// Weight of the forces other than the driving one (0 when settled).
    fade: Vec<f64>,
    acc: Vec<Vec2>,
    settled: Vec<bool>,
    /// No heading: settled or at rest (left out of `I_d`, `I_v`).
    still: Vec<bool>,
    before: Vec<Vec2>,
    scratch: Vec<Vec2>,
    travel: Vec<f64>,
    nearest: Vec<f64>,
    overlapped: HashSet<(u32, u32)>,
    /// The previous step's velocities, for the heading-change rate.
    heading: HeadingChange,
    /// Positions and velocities the last report measured, with what it found:
    /// while the next step starts from them bit for bit, its first substep takes
    /// `I_d`, `I_v` (and the bins they left in `feedback`) from the report
    /// instead of computing them again.
    reported_pos: Vec<Vec2>,
    reported_vel: Vec<Vec2>,
    reported: Option<Information>,
    elapsed_s: f64,
    /// When the next wider exchange pass is due (s of the run).
    next_wide_swap_s: f64,
    steps: u64,
    swaps: u64,
    /// Without settling: since when no agent has been faster than
    /// [`REST_SPEED_M_S`] (s of the run).
    rest_since_s: Option<f64>,
    /// Mean distance to target at the last report (m).
    mean_offset_m: f64,
    /// The subgroups' spread at the last report, and its sum and count over
    /// the reports that had one.
    spread: Option<f64>,
    spread_sum: f64,
    spread_steps: u64,
    sum: Measures,
    min_distance_m: f64,
    last: StepReport,
}

impl TransformRun {
    /// A run of `plan` with `params`, fluctuation and desired speeds drawn from
    /// `seed`. Allocates its buffers once. Agents are those of `plan.sources_m`;
    /// `plan.targets_m` and `plan.subgroups.group_of` give one entry per agent
    /// (missing ones: the source as target, group 0).
    pub fn new(plan: &TransformPlan, params: &MoveParams, seed: u64) -> TransformRun {
        let n = plan.sources_m.len();
        let sources = plan.sources_m.clone();
        let targets: Vec<Vec2> = (0..n)
            .map(|i| plan.targets_m.get(i).copied().unwrap_or(sources[i]))
            .collect();
        let mut rng = SplitMix64::new(seed);
        let spread = params.desired_speed_spread_m_s.abs();
        let v0 = (0..n)
            .map(|_| {
                (params.desired_speed_m_s + rng.uniform(-spread, spread))
                    .clamp(0.0, params.max_speed_m_s)
            })
            .collect();
        let baseline = Baseline::new(params.mover, n, seed);
        TransformRun {
            groups: Groups::new(
                &plan.subgroups.group_of,
                &sources,
                &targets,
                params.subgroup_attraction,
            ),
            feedback: Feedback::new(n, params.bin_m, params.sectors),
            baseline,
            grid: NeighbourGrid::with_capacity(n),
            contact_grid: NeighbourGrid::with_capacity(n),
            contacts: vec![(0, 0); 4 * n],
            contacts_len: 0,
            listed_at: vec![Vec2::zeros(); n],
            v0,
            e: vec![Vec2::zeros(); n],
            dist: vec![0.0; n],
            fade: vec![0.0; n],
            acc: vec![Vec2::zeros(); n],
            settled: vec![false; n],
            still: vec![false; n],
            before: vec![Vec2::zeros(); n],
            scratch: vec![Vec2::zeros(); n],
            travel: vec![0.0; n],
            nearest: vec![0.0; n],
            overlapped: HashSet::with_capacity(4 * n),
            heading: HeadingChange::new(n),
            reported_pos: vec![Vec2::zeros(); n],
            reported_vel: vec![Vec2::zeros(); n],
            reported: None,
            elapsed_s: 0.0,
            next_wide_swap_s: WIDE_SWAP_PERIOD_S,
            steps: 0,
            swaps: 0,
            rest_since_s: None,
            mean_offset_m: 0.0,
            spread: None,
            spread_sum: 0.0,
            spread_steps: 0,
            sum: Measures::default(),
            min_distance_m: f64::INFINITY,
            last: StepReport::default(),
            targets,
            sources,
            p: params.clone(),
            rng,
        }
    }

    /// One step of `dt_s` seconds: forces, feedback, integration, arrival; the scene's
    /// obstacles at scene time `t_s` when given. No allocation in steady state.
    /// A `dt_s` that is not positive and finite, or slices of another length than
    /// the plan's, leave everything as it is and report the state now.
    pub fn step(
        &mut self,
        positions: &mut [Vec2],
        velocities: &mut [Vec2],
        dt_s: f64,
        scene: Option<(&Scene, f64)>,
    ) -> StepReport {
        let n = self.targets.len();
        if positions.len() != n || velocities.len() != n || !(dt_s.is_finite() && dt_s > 0.0) {
            return self.last;
        }
        let max_sub = if self.p.max_substep_s > 0.0 {
            self.p.max_substep_s
        } else {
            dt_s
        };
        let substeps = (dt_s / max_sub).ceil().clamp(1.0, 64.0) as usize;
        let h = dt_s / substeps as f64;
        self.before.copy_from_slice(positions);
        if self.p.exchanges {
            self.undo_blocks_nearby(positions);
        }
        for k in 0..substeps {
            let t = scene.map(|(s, t0)| (s, t0 + k as f64 * h));
            self.substep(positions, velocities, h, t);
        }
        for ((t, x), b) in self.travel.iter_mut().zip(&*positions).zip(&self.before) {
            *t += (x - b).norm();
        }
        self.elapsed_s += dt_s;
        self.steps += 1;
        let report = self.report(positions, velocities, dt_s);
        self.last = report;
        self.spread = self.groups.spread(positions, &self.sources, &self.targets);
        if let Some(r) = self.spread {
            self.spread_sum += r;
            self.spread_steps += 1;
        }
        if !self.p.settling {
            let fastest2 = velocities
                .iter()
                .map(|v| v.norm_squared())
                .fold(0.0, f64::max);
            self.rest_since_s = if fastest2 < REST_SPEED_M_S * REST_SPEED_M_S {
                self.rest_since_s.or(Some(self.elapsed_s))
            } else {
                None
            };
        }
        report
    }

    /// Headings, desired speeds and fades of the moving agents (steps 1–2).
    fn desire(&mut self, pos: &[Vec2], vel: &[Vec2]) -> Information {
        let p = &self.p;
        for i in 0..pos.len() {
            let d = self.targets[i] - pos[i];
            let dn = d.norm();
            self.dist[i] = dn;
            self.e[i] = if dn > 1e-12 { d / dn } else { Vec2::zeros() };
            self.fade[i] = if self.settled[i] {
                0.0
            } else if !p.fades {
                1.0
            } else {
                ((dn - p.arrive_m) / p.fade_m.max(1e-9)).clamp(0.0, 1.0)
            };
            self.still[i] = self.settled[i] || vel[i].norm_squared() < 1e-12;
        }
        if !p.feedback {
            return Information::default();
        }
        // `still` is that of the report when the state is: `settled` changes
        // only in `settle`, before the report.
        let info = match self.reported.take() {
            Some(info) if self.at_report(pos, vel) => info,
            _ => self
                .feedback
                .measure(pos, vel, p.max_speed_m_s, &self.still),
        };
        self.feedback
            .adjust(&mut self.e, &mut self.v0, &self.settled, &self.fade, info);
        let vmax = p.max_speed_m_s;
        for v in &mut self.v0 {
            *v = v.clamp(0.0, vmax);
        }
        info
    }

    /// Whether `pos` and `vel` are bit for bit those of the last report.
    fn at_report(&self, pos: &[Vec2], vel: &[Vec2]) -> bool {
        let same = |a: &[Vec2], b: &[Vec2]| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| x.x.to_bits() == y.x.to_bits() && x.y.to_bits() == y.y.to_bits())
        };
        same(pos, &self.reported_pos) && same(vel, &self.reported_vel)
    }

    /// The velocity agent `i` wants now: its heading at its desired speed, ramped
    /// down near the target.
    fn wanted(&self, i: usize) -> Vec2 {
        let ramp = (2.0 * self.p.arrival_decel_m_s2.max(0.0) * self.dist[i]).sqrt();
        self.e[i] * self.v0[i].min(ramp)
    }

    fn substep(
        &mut self,
        pos: &mut [Vec2],
        vel: &mut [Vec2],
        h: f64,
        scene: Option<(&Scene, f64)>,
    ) {
        let n = pos.len();
        self.desire(pos, vel);
        if self.baseline.is_some() {
            // ORCA, RVO or steering: the wanted velocity made (or steered) clear.
            for i in 0..n {
                self.acc[i] = if self.settled[i] {
                    Vec2::zeros()
                } else {
                    self.wanted(i)
                };
            }
            let Some(baseline) = &mut self.baseline else {
                return;
            };
            baseline.velocities(pos, vel, &self.acc, &self.dist, &self.settled, &self.p, h);
            for i in 0..n {
                if !self.settled[i] {
                    pos[i] += vel[i] * h;
                }
            }
        } else {
            self.forces(pos, vel, scene);
            let (amax, vmax) = (self.p.max_accel_m_s2, self.p.max_speed_m_s);
            for i in 0..n {
                if self.settled[i] {
                    vel[i] = Vec2::zeros();
                    continue;
                }
                let mut a = self.acc[i];
                let an = a.norm();
                if an > amax {
                    a *= amax / an;
                }
                let mut v = vel[i] + a * h;
                let vn = v.norm();
                if vn > vmax {
                    v *= vmax / vn;
                }
                vel[i] = v;
                pos[i] += v * h;
            }
        }
        if self.p.contacts {
            self.resolve_overlaps(pos, vel);
        }
        if self.p.exchanges {
            if !self.p.contacts {
                // The exchange reads the contact list the overlap rounds make.
                self.scratch.copy_from_slice(pos);
                let touch = (2.0 + SWAP_TOUCH_RADII) * self.p.radius_m;
                self.list_contacts(touch);
            }
            self.undo_head_on_blocks(pos);
        }
        if let Some((s, t)) = scene {
            for x in pos.iter_mut() {
                if s.closer_than(*x, self.p.radius_m, t) {
                    *x = s.project_out(*x, self.p.radius_m, t);
                }
            }
        }
        self.settle(pos, vel);
    }

    /// `F` of eq. 23 for every moving agent into `acc` (step 3).
    fn forces(&mut self, pos: &[Vec2], vel: &[Vec2], scene: Option<(&Scene, f64)>) {
        let n = pos.len();
        let inv_tau = 1.0 / self.p.tau_s.max(1e-6);
        for (i, v) in vel.iter().enumerate().take(n) {
            // Eq. 8, with eq. 7's ξ uniform in a disc.
            let mut a = (self.wanted(i) - v) * inv_tau;
            let xi = self.fluctuation();
            a += xi * self.fade[i];
            self.acc[i] = a;
        }
        let p = &self.p;
        let cell_m = p.interaction_range_m.max(2.0 * p.radius_m);
        self.grid.build(pos, cell_m);
        let groups = p.subgroup_forces.then_some(&self.groups.group_of[..]);
        social::repulse(
            &self.grid,
            pos,
            groups,
            &self.fade,
            &self.settled,
            p,
            &mut self.acc,
        );
        if p.subgroup_forces {
            self.groups.attract(
                pos,
                vel,
                &self.sources,
                &self.targets,
                &self.fade,
                p,
                &mut self.acc,
            );
        }
        if let Some((s, t)) = scene {
            social::obstacles(s, t, pos, &self.fade, p, &mut self.acc);
        }
    }

    /// A draw of `ξ`: uniform in the disc of radius `fluctuation_m_s2`.
    fn fluctuation(&mut self) -> Vec2 {
        let r = self.p.fluctuation_m_s2;
        if r <= 0.0 {
            return Vec2::zeros();
        }
        let a = self.rng.uniform(0.0, std::f64::consts::TAU);
        let m = r * self.rng.unit().sqrt();
        Vec2::new(a.cos(), a.sin()) * m
    }

    /// Step 5: pairs closer than `2 r` moved apart to `2 r` along their centre
    /// line (Gauss–Seidel, a few rounds), shared by right of way, the velocity
    /// into the contact removed. Each round takes the pairs closer than `2 r` at
    /// the round's start; they are drawn from a list of the pairs closer than
    /// `2 r` plus twice the contact skin made once (a grid over the positions then), made
    /// again only when an agent has since moved more than the skin, so the pairs
    /// are exactly those a grid built every round would give.
    fn resolve_overlaps(&mut self, pos: &mut [Vec2], vel: &mut [Vec2]) {
        let two_r = 2.0 * self.p.radius_m;
        if two_r <= 0.0 {
            return;
        }
        let skin = CONTACT_SKIN_RADII * self.p.radius_m;
        let skin2 = skin * skin;
        let eps = YIELD_EPS_RADII * self.p.radius_m;
        let r2 = two_r * two_r;
        let mut listed = false;
        for _ in 0..self.p.overlap_rounds {
            // Pairs are found on a copy; each push reads the positions as they are.
            self.scratch.copy_from_slice(pos);
            let stale = !listed
                || self
                    .scratch
                    .iter()
                    .zip(&self.listed_at)
                    .any(|(x, a)| (x - a).norm_squared() > skin2);
            if stale {
                self.list_contacts(two_r + 2.0 * skin);
                listed = true;
            }
            let mut pushed = 0usize;
            let (targets, scratch) = (&self.targets, &self.scratch);
            for &(i, j) in &self.contacts[..self.contacts_len] {
                let (i, j) = (i as usize, j as usize);
                let ds = scratch[i] - scratch[j];
                let ds2 = ds.norm_squared();
                if ds2 >= r2 {
                    continue;
                }
                let d = pos[i] - pos[j];
                let dn = d.norm();
                if dn >= two_r {
                    continue;
                }
                let n = if dn > 1e-12 {
                    d / dn
                } else {
                    unit_or_fixed(ds, ds2.sqrt(), i, j)
                };
                // Right of way to the agent with farther to go: each moves by a
                // share of the overlap proportional to the other's distance to its
                // target (half each when both are there).
                let (di, dj) = (
                    (pos[i] - targets[i]).norm() + eps,
                    (pos[j] - targets[j]).norm() + eps,
                );
                let depth = two_r - dn;
                pos[i] += n * (depth * dj / (di + dj));
                pos[j] -= n * (depth * di / (di + dj));
                for (k, s, share) in [(i, 1.0, dj / (di + dj)), (j, -1.0, di / (di + dj))] {
                    // Velocity into the other agent (against s·n) removed by the
                    // agent's share: the one with right of way keeps walking.
                    let into = vel[k].dot(&n) * s;
                    if into < 0.0 {
                        vel[k] -= n * (into * s * share);
                    }
                }
                pushed += 1;
            }
            if pushed == 0 {
                break;
            }
        }
    }

    /// Step 6: walking agents in contact that head for targets beyond each other
    /// exchange targets when the sum of their distances to target falls by at
    /// least [`SWAP_GAIN_RADII`] radii. Reads the contact list of the overlap rounds (every
    /// pair closer than `2 r` is in it).
    fn undo_head_on_blocks(&mut self, pos: &[Vec2]) {
        let touch = (2.0 + SWAP_TOUCH_RADII) * self.p.radius_m;
        let gain = SWAP_GAIN_RADII * self.p.radius_m;
        let touch2 = touch * touch;
        for k in 0..self.contacts_len {
            let (i, j) = self.contacts[k];
            let (i, j) = (i as usize, j as usize);
            if (pos[i] - pos[j]).norm_squared() <= touch2 {
                self.swaps += u64::from(exchange_if_blocked(
                    i,
                    j,
                    pos,
                    &mut self.targets,
                    &self.settled,
                    &mut self.groups,
                    gain,
                ));
            }
        }
    }

    /// Every [`WIDE_SWAP_PERIOD_S`]: the exchange of step 6 for pairs up to
    /// [`WIDE_SWAP_RADII`] radii apart, not only in contact. Two agents heading
    /// for each other's places with a third between them block each other as
    /// surely as two in contact (square → arrow at 2,000 agents shrunk to fit).
    fn undo_blocks_nearby(&mut self, pos: &[Vec2]) {
        if self.elapsed_s < self.next_wide_swap_s {
            return;
        }
        self.next_wide_swap_s = self.elapsed_s + WIDE_SWAP_PERIOD_S;
        let reach = WIDE_SWAP_RADII * self.p.radius_m;
        if reach.is_nan() || reach <= 0.0 {
            return;
        }
        let gain = SWAP_GAIN_RADII * self.p.radius_m;
        self.contact_grid.build(pos, reach);
        let (targets, settled, groups) = (&mut self.targets, &self.settled, &mut self.groups);
        let mut swaps = 0u64;
        self.contact_grid
            .for_each_pair_d2(pos, reach, |i, j, _, _| {
                swaps += u64::from(exchange_if_blocked(
                    i, j, pos, targets, settled, groups, gain,
                ));
            });
        self.swaps += swaps;
    }

    /// The pairs closer than `reach_m` at `scratch` into `contacts`, and `scratch`
    /// into `listed_at`.
    fn list_contacts(&mut self, reach_m: f64) {
        self.contact_grid.build(&self.scratch, reach_m);
        // Written in place over the whole length (kept by a clone of the run, which
        // keeps lengths, not capacities); grown only past it.
        let (contacts, mut k) = (&mut self.contacts, 0usize);
        self.contact_grid
            .for_each_pair_d2(&self.scratch, reach_m, |i, j, _, _| {
                let pair = (i as u32, j as u32);
                match contacts.get_mut(k) {
                    Some(slot) => *slot = pair,
                    None => contacts.push(pair),
                }
                k += 1;
            });
        self.contacts_len = k;
        self.listed_at.copy_from_slice(&self.scratch);
    }

    /// Step 6: agents near enough and slow enough settle; settled agents pushed
    /// within `arrive_m` of their target stay settled.
    fn settle(&mut self, pos: &[Vec2], vel: &mut [Vec2]) {
        if !self.p.settling {
            return;
        }
        let (arrive, slow) = (self.p.arrive_m, self.p.settle_speed_m_s);
        for i in 0..pos.len() {
            let near = (pos[i] - self.targets[i]).norm() <= arrive;
            if near && (self.settled[i] || vel[i].norm() <= slow) {
                self.settled[i] = true;
                vel[i] = Vec2::zeros();
            } else {
                self.settled[i] = false;
            }
        }
    }

    /// The measures and contacts now.
    fn report(&mut self, pos: &[Vec2], vel: &[Vec2], dt_s: f64) -> StepReport {
        let n = pos.len();
        let two_r = 2.0 * self.p.radius_m;
        let mut arrived = 0usize;
        let mut offset_sum_m = 0.0;
        for (p, t) in pos.iter().zip(&self.targets) {
            let d = (p - t).norm();
            offset_sum_m += d;
            arrived += usize::from(d <= self.p.arrive_m);
        }
        self.mean_offset_m = if n == 0 { 0.0 } else { offset_sum_m / n as f64 };
        // The nearest neighbour of an agent in a crowd is almost always within a
        // few radii: a grid of that cell side visits far fewer pairs than one of
        // the interaction range (a tenth in a packed crowd), and the ring search
        // finds the nearest of the few agents with none that near.
        self.contact_grid
            .build(pos, (NEAREST_CELL_RADII * self.p.radius_m).max(two_r));
        let mut overlapping = 0usize;
        let overlapped = &mut self.overlapped;
        let limit = two_r - OVERLAP_TOLERANCE_M;
        let limit2 = limit * limit;
        // One pass over the pairs for the contacts and the nearest neighbours.
        nearest_distances(&self.contact_grid, pos, &mut self.nearest, |i, j, d2| {
            if d2 < limit2 {
                overlapping += 1;
                let _ = overlapped.insert((i.min(j) as u32, i.max(j) as u32));
            }
        });
        let (sigma_min_dis_m, min_d) = spread_and_min(&self.nearest[..n]);
        for ((still, &settled), v) in self.still.iter_mut().zip(&self.settled).zip(vel) {
            *still = settled || v.norm_squared() < 1e-12;
        }
        let info = self
            .feedback
            .measure(pos, vel, self.p.max_speed_m_s, &self.still);
        self.reported_pos.copy_from_slice(pos);
        self.reported_vel.copy_from_slice(vel);
        self.reported = Some(info);
        let measures = Measures {
            i_d: info.i_d,
            i_v: info.i_v,
            sigma_min_dis_m,
            sigma_curr_eft_m: sigma_curr_eft(&self.sources, pos),
            heading_change_rad_s: self.heading.rate(vel, dt_s),
        };
        self.sum.i_d += measures.i_d;
        self.sum.i_v += measures.i_v;
        self.sum.sigma_min_dis_m += measures.sigma_min_dis_m;
        self.sum.sigma_curr_eft_m += measures.sigma_curr_eft_m;
        self.sum.heading_change_rad_s += measures.heading_change_rad_s;
        self.min_distance_m = self.min_distance_m.min(min_d);
        StepReport {
            arrived,
            arrived_fraction: if n == 0 {
                1.0
            } else {
                arrived as f64 / n as f64
            },
            measures,
            min_distance_m: min_d,
            overlapping_pairs: overlapping,
        }
    }

    /// Every agent arrived and settled (without settling: every agent within
    /// `arrive_m` of its target at the last step, or the crowd at rest for
    /// [`REST_HOLD_S`]), or the timeout passed.
    pub fn done(&self) -> bool {
        self.all_arrived() || self.rested().is_some() || self.elapsed_s >= self.p.timeout_s
    }

    /// Without settling: when the crowd came to rest, once it has stayed so for
    /// [`REST_HOLD_S`] (s of the run).
    fn rested(&self) -> Option<f64> {
        self.rest_since_s
            .filter(|&t| self.elapsed_s - t >= REST_HOLD_S - 1e-9)
    }

    fn all_arrived(&self) -> bool {
        if self.p.settling {
            self.settled.iter().all(|&s| s)
        } else {
            self.steps > 0 && self.last.arrived == self.targets.len()
        }
    }

    /// Simulated time since the start (s).
    pub fn elapsed_s(&self) -> f64 {
        self.elapsed_s
    }

    /// Agent `i`'s target is `targets()[i]` (m).
    pub fn targets(&self) -> &[Vec2] {
        &self.targets
    }

    /// Moves every target by `by_m` (a formation whose anchor travels, the
    /// transforms along a path of section 4, Figs. 6–7); the subgroups' target
    /// layouts move with them. Settled agents whose target left them walk again.
    pub fn shift_targets(&mut self, by_m: Vec2) {
        for t in &mut self.targets {
            *t += by_m;
        }
        self.groups.shift_targets(by_m);
    }

    /// Whether agent `i` has arrived and settled.
    pub fn settled(&self, i: usize) -> bool {
        self.settled[i]
    }

    /// The run so far, summarised.
    pub fn summary(&self) -> RunSummary {
        let n = self.targets.len();
        let steps = self.steps.max(1) as f64;
        RunSummary {
            agents: n,
            steps: self.steps,
            simulated_s: self.elapsed_s,
            arrived_fraction: self.last.arrived_fraction,
            min_distance_m: self.min_distance_m,
            overlapping_pairs: self.overlapped.len(),
            mean_travel_m: if n == 0 {
                0.0
            } else {
                self.travel.iter().sum::<f64>() / n as f64
            },
            max_travel_m: self.travel.iter().cloned().fold(0.0, f64::max),
            mean: Measures {
                i_d: self.sum.i_d / steps,
                i_v: self.sum.i_v / steps,
                sigma_min_dis_m: self.sum.sigma_min_dis_m / steps,
                sigma_curr_eft_m: self.sum.sigma_curr_eft_m / steps,
                heading_change_rad_s: self.sum.heading_change_rad_s / steps,
            },
            timed_out: self.elapsed_s >= self.p.timeout_s
                && !self.all_arrived()
                && self.rested().is_none(),
            swaps: self.swaps,
            rest_s: self.rested(),
            mean_offset_m: self.mean_offset_m,
            subgroup_spread: self.spread,
            subgroup_spread_mean: (self.spread_steps > 0)
                .then(|| self.spread_sum / self.spread_steps as f64),
        }
    }
}

/// Agents `i` and `j`, both walking, each heading for a target beyond the other
/// (headings opposed), exchange targets when that shortens the sum of their
/// distances to target by at least `gain_m`. Whether they did.
fn exchange_if_blocked(
    i: usize,
    j: usize,
    pos: &[Vec2],
    targets: &mut [Vec2],
    settled: &[bool],
    groups: &mut Groups,
    gain_m: f64,
) -> bool {
    if settled[i] || settled[j] {
        return false;
    }
    let (ti, tj) = (targets[i], targets[j]);
    let (ei, ej) = (ti - pos[i], tj - pos[j]);
    let d = pos[j] - pos[i];
    if ei.dot(&ej) >= 0.0 || ei.dot(&d) <= 0.0 || ej.dot(&d) >= 0.0 {
        return false;
    }
    let now = ei.norm() + ej.norm();
    let swapped = (tj - pos[i]).norm() + (ti - pos[j]).norm();
    if swapped <= now - gain_m {
        targets.swap(i, j);
        groups.swapped(i, j, ti, tj);
        true
    } else {
        false
    }
}

#[cfg(test)]
#[path = "run_tests.rs"]
mod tests;
