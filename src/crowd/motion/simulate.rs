//! The crowd simulator that generates the library's crowd motions from start/goal
//! specifications.
//!
//! gesture-driven section 4 builds its motion set (ten classes, figure 2) with a crowd
//! simulator, and section 8.1 notes that "basic crowd simulation systems that control
//! characters by setting the starting and goal positions can effectively generate the
//! database". This is such a system, built on the project's own agents
//! ([`Agents`]: PD following with the spring-mass push-apart of section 7.3):
//!
//! 1. A [`MotionSpec`] holds a start layout of M agents (world metres) and, per agent,
//!    a goal path: positions at shared waypoint times. [`library_specs`] writes them
//!    for every class as a sequence of *phases*; in each phase every agent's goal is
//!    moved by one similarity about the crowd's centroid (rotation, uniform scale)
//!    plus a shift of its group (0 or 1), eased in and out (smoothstep), sampled at
//!    [`WAYPOINTS_PER_PHASE`] waypoints. Twist agents so walk along arcs; composite
//!    classes are two phases (split, then both halves translate) or one combined
//!    similarity (twist while expanding).
//! 2. [`simulate`] steps the agents towards their time-varying goals with
//!    [`Agents::step_towards`] until the last waypoint's time has passed and every
//!    agent has arrived (or the crowd has come to rest, pressed together), at most
//!    [`SETTLE_CAP_S`] after it, and returns the raw world tracks with their
//!    duration. Resampling and normalisation to a crowd motion are done elsewhere.
//! 3. [`measure`] reads back what a set of tracks did (centroid shift, RMS radius
//!    ratio, signed rotation, the two groups' distance), for tests of the library and
//!    of the daemon's gesture motions.
//!
//! Variation by seed: crowd size 20–80, shape (disc, grid, ellipse, jittered grid),
//! spacing, orientation, place, goal speed, and the class's direction and magnitude.

use crate::crowd::agents::{AgentParams, Agents};
use crate::geom::{cross, Vec2};
use crate::gesture::library::MotionClass;
use crate::rng::SplitMix64;

/// Waypoints per phase of a goal path (a half turn is sampled every 7.5°).
pub const WAYPOINTS_PER_PHASE: usize = 24;

/// Longest the simulation runs past the last waypoint for the agents to arrive (s).
pub const SETTLE_CAP_S: f64 = 10.0;

/// An agent within this distance of its final goal has arrived (m).
pub const ARRIVE_TOLERANCE_M: f64 = 0.1;

/// A crowd whose agents all move slower than this has come to rest (m/s).
pub const REST_SPEED_M_S: f64 = 0.03;

/// Fewest and most agents of a library crowd.
pub const LIBRARY_AGENTS: (usize, usize) = (20, 80);

/// What a crowd motion is made from: where the agents start and where their goals
/// are over time.
///
/// Invariants (checked by [`MotionSpec::validate`]): `start`, `group` and `paths`
/// have one entry per agent (at least one agent); `times_s` starts at 0, increases
/// strictly and is as long as every path; every coordinate is finite; path `i`
/// starts at `start[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionSpec {
    /// The class the motion illustrates.
    pub class: MotionClass,
    /// Start positions (m), one per agent.
    pub start: Vec<Vec2>,
    /// The agent's group: 0 or 1 for the two halves of a join or split, 0 otherwise.
    pub group: Vec<u8>,
    /// Waypoint times (s), shared by all paths.
    pub times_s: Vec<f64>,
    /// Per agent, its goal (m) at each waypoint time; between waypoints the goal
    /// moves linearly, after the last it stays.
    pub paths: Vec<Vec<Vec2>>,
}

/// Why a spec or a time step cannot be simulated.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimulateError {
    /// No agents.
    #[error("motion spec has no agents")]
    NoAgents,
    /// Per-agent lists of different lengths.
    #[error("motion spec: {what} has {got} entries, expected {expected}")]
    Length {
        /// Which list.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length it should have.
        expected: usize,
    },
    /// Waypoint times do not start at 0 and increase strictly, or are not finite.
    #[error("motion spec: waypoint time {index} ({t_s} s) does not follow the previous one")]
    Times {
        /// The offending waypoint.
        index: usize,
        /// Its time.
        t_s: f64,
    },
    /// A position is NaN or infinite.
    #[error("motion spec: agent {agent} has a non-finite position")]
    NonFinite {
        /// The offending agent.
        agent: usize,
    },
    /// A path does not start where its agent does.
    #[error("motion spec: the path of agent {agent} does not start at its start position")]
    PathStart {
        /// The offending agent.
        agent: usize,
    },
    /// The time step is not a positive finite number.
    #[error("time step {0} s is not positive and finite")]
    TimeStep(f64),
}

impl MotionSpec {
    /// Number of agents.
    pub fn agents(&self) -> usize {
        self.start.len()
    }

    /// Time of the last waypoint (s).
    pub fn end_s(&self) -> f64 {
        self.times_s.last().copied().unwrap_or(0.0)
    }

    /// Agent `i`'s goal at `t_s` (m): linear between waypoints, held after the last.
    pub fn goal_at(&self, i: usize, t_s: f64) -> Vec2 {
        let path = &self.paths[i];
        let times = &self.times_s;
        if t_s <= 0.0 || times.len() < 2 {
            return path[0];
        }
        let k = times.partition_point(|&t| t <= t_s);
        if k >= times.len() {
            return path[times.len() - 1];
        }
        let (t0, t1) = (times[k - 1], times[k]);
        let u = (t_s - t0) / (t1 - t0);
        path[k - 1] + (path[k] - path[k - 1]) * u
    }

    /// Agent `i`'s final goal (m).
    pub fn goal_end(&self, i: usize) -> Vec2 {
        self.paths[i][self.paths[i].len() - 1]
    }

    /// Checks the invariants listed on [`MotionSpec`].
    ///
    /// # Errors
    /// The first violation found.
    pub fn validate(&self) -> Result<(), SimulateError> {
        let m = self.start.len();
        if m == 0 {
            return Err(SimulateError::NoAgents);
        }
        for (what, got) in [("group", self.group.len()), ("paths", self.paths.len())] {
            if got != m {
                return Err(SimulateError::Length {
                    what,
                    got,
                    expected: m,
                });
            }
        }
        let mut prev = f64::NEG_INFINITY;
        for (index, &t_s) in self.times_s.iter().enumerate() {
            let first_ok = index > 0 || t_s == 0.0;
            if !t_s.is_finite() || t_s <= prev || !first_ok {
                return Err(SimulateError::Times { index, t_s });
            }
            prev = t_s;
        }
        if self.times_s.is_empty() {
            return Err(SimulateError::Times {
                index: 0,
                t_s: f64::NAN,
            });
        }
        for (agent, (p0, path)) in self.start.iter().zip(&self.paths).enumerate() {
            if path.len() != self.times_s.len() {
                return Err(SimulateError::Length {
                    what: "a path",
                    got: path.len(),
                    expected: self.times_s.len(),
                });
            }
            let finite = |p: &Vec2| p.x.is_finite() && p.y.is_finite();
            if !finite(p0) || !path.iter().all(finite) {
                return Err(SimulateError::NonFinite { agent });
            }
            if path[0] != *p0 {
                return Err(SimulateError::PathStart { agent });
            }
        }
        Ok(())
    }
}

/// Raw output of [`simulate`]: world tracks sampled every `dt_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatedMotion {
    /// Per agent, its positions (m) at `0, dt_s, 2 dt_s, …`; all tracks have the same
    /// length, the last sample at `duration_s`.
    pub tracks: Vec<Vec<Vec2>>,
    /// Time of the last sample (s).
    pub duration_s: f64,
    /// Sampling interval (s).
    pub dt_s: f64,
    /// Whether every agent reached its final goal (within [`ARRIVE_TOLERANCE_M`])
    /// rather than the crowd coming to rest short of it or the cap being hit.
    pub arrived: bool,
}

/// Runs the agents of `spec` along their goal paths (gesture-driven section 4 and
/// 8.1: a crowd simulator driven by start and goal positions).
///
/// Every `dt_s` each agent's target is its goal at that time; the agents move with
/// [`Agents::step_towards`] (PD following, spring-mass push-apart, section 7.3).
/// The run ends once the last waypoint time has passed and every agent is within
/// [`ARRIVE_TOLERANCE_M`] of its final goal or all move slower than
/// [`REST_SPEED_M_S`], or [`SETTLE_CAP_S`] after the last waypoint.
///
/// # Errors
/// An invalid spec ([`MotionSpec::validate`]) or time step.
pub fn simulate(
    spec: &MotionSpec,
    params: &AgentParams,
    dt_s: f64,
) -> Result<SimulatedMotion, SimulateError> {
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(SimulateError::TimeStep(dt_s));
    }
    spec.validate()?;
    let m = spec.agents();
    let end = spec.end_s();
    let max_steps = ((end + SETTLE_CAP_S) / dt_s).ceil() as usize;
    let mut agents = Agents::new(&spec.start);
    let mut targets = spec.start.clone();
    let mut tracks: Vec<Vec<Vec2>> = spec
        .start
        .iter()
        .map(|&p| {
            let mut v = Vec::with_capacity(max_steps + 1);
            v.push(p);
            v
        })
        .collect();
    let mut steps = 0;
    let mut arrived = false;
    while steps < max_steps {
        steps += 1;
        let t = steps as f64 * dt_s;
        for (i, g) in targets.iter_mut().enumerate() {
            *g = spec.goal_at(i, t);
        }
        agents.step_towards(&targets, |_| 1.0, dt_s, params);
        for (track, &p) in tracks.iter_mut().zip(agents.positions()) {
            track.push(p);
        }
        if t >= end {
            arrived = (0..m)
                .all(|i| (agents.positions()[i] - spec.goal_end(i)).norm() <= ARRIVE_TOLERANCE_M);
            let at_rest = agents
                .velocities()
                .iter()
                .all(|v| v.norm() < REST_SPEED_M_S);
            if arrived || at_rest {
                break;
            }
        }
    }
    Ok(SimulatedMotion {
        tracks,
        duration_s: steps as f64 * dt_s,
        dt_s,
        arrived,
    })
}

/// One phase of a goal path: a similarity about the crowd's centroid at the phase's
/// start, plus a shift per group, reached at the phase's end.
#[derive(Copy, Clone, Debug)]
struct Phase {
    /// Signed turn (rad, counter-clockwise positive).
    rotate_rad: f64,
    /// Uniform scale at the end (1 = none).
    scale: f64,
    /// Shift of group 0 and of group 1 (m).
    shift: [Vec2; 2],
}

/// `3u² − 2u³`: starts and ends at rest.
fn smoothstep(u: f64) -> f64 {
    u * u * (3.0 - 2.0 * u)
}

fn rot(v: Vec2, a: f64) -> Vec2 {
    let (s, c) = a.sin_cos();
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

fn centroid(p: &[Vec2]) -> Vec2 {
    p.iter().fold(Vec2::zeros(), |a, q| a + q) / p.len().max(1) as f64
}

/// Goal paths from `start` through `phases`, each agent's goal moving at most
/// `speed_m_s` on average over a phase.
fn build(
    class: MotionClass,
    start: Vec<Vec2>,
    group: Vec<u8>,
    phases: &[Phase],
    speed_m_s: f64,
) -> MotionSpec {
    let m = start.len();
    let mut paths: Vec<Vec<Vec2>> = start.iter().map(|&p| vec![p]).collect();
    let mut times_s = vec![0.0];
    let mut at = start.clone();
    let mut pos = vec![Vec2::zeros(); m];
    for ph in phases {
        let c = centroid(&at);
        let place = |p0: Vec2, g: u8, u: f64| {
            let s = ph.scale.powf(u);
            c + ph.shift[g as usize] * u + rot(p0 - c, ph.rotate_rad * u) * s
        };
        // The phase lasts as long as its longest path takes at the goal speed.
        let mut longest: f64 = 0.0;
        for i in 0..m {
            let mut len = 0.0;
            let mut prev = at[i];
            for k in 1..=WAYPOINTS_PER_PHASE {
                let q = place(at[i], group[i], k as f64 / WAYPOINTS_PER_PHASE as f64);
                len += (q - prev).norm();
                prev = q;
            }
            longest = longest.max(len);
        }
        let t0 = times_s[times_s.len() - 1];
        let dur = (longest / speed_m_s).max(1.0);
        for k in 1..=WAYPOINTS_PER_PHASE {
            let tau = k as f64 / WAYPOINTS_PER_PHASE as f64;
            let u = smoothstep(tau);
            times_s.push(t0 + dur * tau);
            for i in 0..m {
                pos[i] = place(at[i], group[i], u);
                paths[i].push(pos[i]);
            }
        }
        at.clone_from(&pos);
    }
    MotionSpec {
        class,
        start,
        group,
        times_s,
        paths,
    }
}

/// A start layout of `m` agents centred on the origin with spacing about
/// `spacing_m`: 0 disc (sunflower), 1 grid, 2 ellipse, 3 jittered grid.
fn layout(shape: u64, m: usize, spacing_m: f64, rng: &mut SplitMix64) -> Vec<Vec2> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let sunflower = |aspect: f64| -> Vec<Vec2> {
        let r = spacing_m * (m as f64 / std::f64::consts::PI).sqrt();
        (0..m)
            .map(|k| {
                let rk = r * ((k as f64 + 0.5) / m as f64).sqrt();
                let a = k as f64 * golden;
                Vec2::new(rk * a.cos() * aspect, rk * a.sin() / aspect)
            })
            .collect()
    };
    let grid = |jitter: f64, rng: &mut SplitMix64| -> Vec<Vec2> {
        let cols = (m as f64).sqrt().ceil() as usize;
        let rows = m.div_ceil(cols);
        (0..m)
            .map(|k| {
                let (c, r) = ((k % cols) as f64, (k / cols) as f64);
                let j = Vec2::new(rng.uniform(-jitter, jitter), rng.uniform(-jitter, jitter));
                Vec2::new(
                    (c - (cols - 1) as f64 / 2.0) * spacing_m,
                    (r - (rows - 1) as f64 / 2.0) * spacing_m,
                ) + j * spacing_m
            })
            .collect()
    };
    let pts = match shape % 4 {
        0 => sunflower(1.0),
        1 => grid(0.0, rng),
        2 => sunflower(rng.uniform(1.3, 1.8)),
        _ => grid(0.2, rng),
    };
    let c = centroid(&pts);
    let turn = rng.uniform(0.0, std::f64::consts::TAU);
    pts.into_iter().map(|p| rot(p - c, turn)).collect()
}

fn rms_radius(p: &[Vec2]) -> f64 {
    let c = centroid(p);
    (p.iter().map(|q| (q - c).norm_squared()).sum::<f64>() / p.len().max(1) as f64).sqrt()
}

/// One library spec of `class` drawn from `rng`.
fn one_spec(class: MotionClass, rng: &mut SplitMix64) -> MotionSpec {
    use std::f64::consts::{PI, TAU};
    let (lo, hi) = LIBRARY_AGENTS;
    let m = lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize;
    let shape = rng.next_u64();
    let spacing = rng.uniform(0.5, 0.75);
    let place = Vec2::new(rng.uniform(-5.0, 5.0), rng.uniform(-3.0, 3.0));
    let speed = rng.uniform(0.5, 1.0);
    let dir = rng.uniform(0.0, TAU);
    let axis = Vec2::new(dir.cos(), dir.sin());
    let sign = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
    let none = Phase {
        rotate_rad: 0.0,
        scale: 1.0,
        shift: [Vec2::zeros(); 2],
    };
    let translate = |rng: &mut SplitMix64| {
        let d = axis * rng.uniform(3.0, 7.0);
        Phase {
            shift: [d, d],
            ..none
        }
    };
    let twist = rng.uniform(PI / 3.0, PI) * sign;
    let two_groups = matches!(class, MotionClass::Join | MotionClass::TranslateThenJoin);
    let (start, group) = if two_groups {
        // Two groups apart along a direction across the axis, with a gap between them.
        let half = m / 2;
        let a = layout(shape, half, spacing, rng);
        let b = layout(shape.wrapping_add(1), m - half, spacing, rng);
        let across = rot(axis, PI / 2.0);
        let gap = rms_radius(&a) + rms_radius(&b) + rng.uniform(3.0, 6.0);
        let mut start: Vec<Vec2> = a.iter().map(|p| p - across * (gap / 2.0)).collect();
        start.extend(b.iter().map(|p| p + across * (gap / 2.0)));
        let mut group = vec![0u8; half];
        group.resize(m, 1);
        (start, group)
    } else {
        let start = layout(shape, m, spacing, rng);
        // Halves by the side of the line through the centroid across the axis.
        let group = start.iter().map(|p| u8::from(p.dot(&axis) > 0.0)).collect();
        (start, group)
    };
    let start: Vec<Vec2> = start.into_iter().map(|p| p + place).collect();
    let join = |start: &[Vec2], group: &[u8]| {
        // Each group moves towards the other until the gap between them closes.
        let (mut c, mut n) = ([Vec2::zeros(); 2], [0.0; 2]);
        for (p, &g) in start.iter().zip(group) {
            c[g as usize] += p;
            n[g as usize] += 1.0;
        }
        let (c0, c1) = (c[0] / n[0], c[1] / n[1]);
        let d = c1 - c0;
        let dist = d.norm();
        let r0 = rms_radius(&pick(start, group, 0));
        let r1 = rms_radius(&pick(start, group, 1));
        let close = ((dist - (r0 + r1) * 1.1) / 2.0).max(0.0);
        let u = d / dist.max(1e-9);
        Phase {
            shift: [u * close, -u * close],
            ..none
        }
    };
    let split = |rng: &mut SplitMix64| {
        let d = axis * (rng.uniform(2.5, 5.0) / 2.0);
        Phase {
            shift: [-d, d],
            ..none
        }
    };
    let phases: Vec<Phase> = match class {
        MotionClass::Translate => vec![translate(rng)],
        MotionClass::Twist => vec![Phase {
            rotate_rad: twist,
            ..none
        }],
        MotionClass::Contract => vec![Phase {
            scale: rng.uniform(0.4, 0.7),
            ..none
        }],
        MotionClass::Expand => vec![Phase {
            scale: rng.uniform(1.5, 2.2),
            ..none
        }],
        MotionClass::Join => vec![join(&start, &group)],
        MotionClass::Split => vec![split(rng)],
        MotionClass::SplitThenTranslate => {
            let s = split(rng);
            // The halves move on together, across the split axis or along it.
            let across = rot(axis, PI / 2.0 * sign) * rng.uniform(3.0, 6.0);
            vec![
                s,
                Phase {
                    shift: [across, across],
                    ..none
                },
            ]
        }
        MotionClass::TranslateThenJoin => {
            let t = translate(rng);
            let moved: Vec<Vec2> = start.iter().map(|p| p + t.shift[0]).collect();
            vec![t, join(&moved, &group)]
        }
        MotionClass::TwistWhileExpanding => vec![Phase {
            rotate_rad: twist,
            scale: rng.uniform(1.5, 2.2),
            ..none
        }],
        MotionClass::TwistWhileContracting => vec![Phase {
            rotate_rad: twist,
            scale: rng.uniform(0.4, 0.7),
            ..none
        }],
    };
    build(class, start, group, &phases, speed)
}

fn pick(p: &[Vec2], group: &[u8], g: u8) -> Vec<Vec2> {
    p.iter()
        .zip(group)
        .filter(|(_, &h)| h == g)
        .map(|(q, _)| *q)
        .collect()
}

/// `count` specs of `class`, varied by `seed` (crowd size, shape, spacing, place,
/// orientation, speed, and the class's direction and magnitude: translation 3–7 m,
/// twist 60–180° either way, contraction to 0.4–0.7 or expansion to 1.5–2.2 of the
/// size, split 2.5–5 m apart, join until the groups' gap closes).
/// The same `(class, count, seed)` always gives the same specs.
pub fn library_specs(class: MotionClass, count: usize, seed: u64) -> Vec<MotionSpec> {
    let mut rng = SplitMix64::new(seed ^ (class.index() as u64).wrapping_mul(0x9e37_79b9));
    (0..count).map(|_| one_spec(class, &mut rng)).collect()
}

/// What a set of tracks did (see [`measure`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MotionMeasure {
    /// Centroid at the end minus centroid at the start (m).
    pub centroid_shift: Vec2,
    /// RMS distance from the centroid at the end over that at the start.
    pub rms_ratio: f64,
    /// Signed rotation about the moving centroid (rad, counter-clockwise positive),
    /// summed sample to sample, so turns beyond a half turn count fully.
    pub rotation_rad: f64,
    /// Distance between the centroids of groups 0 and 1 at the start and at the
    /// end (m); `None` when a group is empty.
    pub group_distance: Option<(f64, f64)>,
}

/// Measures `tracks` (per agent, equally long, at least one sample) with `group`
/// labels (0 or 1 per agent).
///
/// # Formula
/// Rotation: per pair of samples `k, k+1`, the angle of `(Σ a·b, Σ a×b)` with `a`,
/// `b` the agents' offsets from the centroid at `k` and `k+1` (the least-squares
/// rotation, closed-form Procrustes), summed over `k`.
pub fn measure(tracks: &[Vec<Vec2>], group: &[u8]) -> MotionMeasure {
    let n = tracks.iter().map(Vec::len).min().unwrap_or(0);
    if n == 0 {
        return MotionMeasure {
            centroid_shift: Vec2::zeros(),
            rms_ratio: 1.0,
            rotation_rad: 0.0,
            group_distance: None,
        };
    }
    let at = |k: usize| -> Vec<Vec2> { tracks.iter().map(|t| t[k]).collect() };
    let (first, last) = (at(0), at(n - 1));
    let mut rotation = 0.0;
    let mut prev = first.clone();
    for k in 1..n {
        let cur = at(k);
        let (c0, c1) = (centroid(&prev), centroid(&cur));
        let (mut d, mut x) = (0.0, 0.0);
        for (p, q) in prev.iter().zip(&cur) {
            let (a, b) = (p - c0, q - c1);
            d += a.dot(&b);
            x += cross(a, b);
        }
        rotation += x.atan2(d);
        prev = cur;
    }
    let gd = |p: &[Vec2]| {
        let (a, b) = (pick(p, group, 0), pick(p, group, 1));
        (!a.is_empty() && !b.is_empty()).then(|| (centroid(&a) - centroid(&b)).norm())
    };
    MotionMeasure {
        centroid_shift: centroid(&last) - centroid(&first),
        rms_ratio: rms_radius(&last) / rms_radius(&first).max(1e-12),
        rotation_rad: rotation,
        group_distance: gd(&first).zip(gd(&last)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn params() -> AgentParams {
        AgentParams {
            radius_m: 0.15,
            max_speed_m_s: 1.5,
            max_accel_m_s2: 6.0,
            kp_per_s2: 16.0,
            kd_per_s: 8.0,
            push_stiffness_per_s2: 200.0,
        }
    }

    /// What the spec's own goals do, measured on the start and final goals.
    fn intended(spec: &MotionSpec) -> MotionMeasure {
        let tracks: Vec<Vec<Vec2>> = spec.paths.clone();
        measure(&tracks, &spec.group)
    }

    fn check(class: MotionClass, got: &MotionMeasure, want: &MotionMeasure) {
        use MotionClass as C;
        let shift = got.centroid_shift.norm();
        let want_shift = want.centroid_shift.norm();
        let (gd0, gd1) = got.group_distance.expect("both groups present");
        let (_, wd1) = want.group_distance.expect("both groups present");
        let ctx = format!("{class}: got {got:?}, wanted {want:?}");
        // Everyone ends near its goal: the measures agree with the spec's.
        assert!(
            (got.centroid_shift - want.centroid_shift).norm() < 0.1 + 0.05 * want_shift,
            "{ctx}"
        );
        match class {
            C::Translate => {
                assert!(shift > 3.0 * 0.95, "{ctx}");
                assert!((got.rms_ratio - 1.0).abs() < 0.1, "{ctx}");
                assert!(got.rotation_rad.abs() < 0.1, "{ctx}");
            }
            C::Twist => {
                assert!(
                    got.rotation_rad.signum() == want.rotation_rad.signum(),
                    "{ctx}"
                );
                assert!(
                    got.rotation_rad.abs() > 0.9 * (std::f64::consts::PI / 3.0),
                    "{ctx}"
                );
                assert!((got.rotation_rad - want.rotation_rad).abs() < 0.15, "{ctx}");
                assert!(shift < 0.2, "{ctx}");
            }
            C::Contract | C::Expand | C::TwistWhileContracting | C::TwistWhileExpanding => {
                let contract = matches!(class, C::Contract | C::TwistWhileContracting);
                if contract {
                    assert!(got.rms_ratio < 0.85, "{ctx}");
                } else {
                    assert!(got.rms_ratio > 1.4, "{ctx}");
                }
                // Pressed together agents cannot reach a tight goal: within 15 %.
                assert!((got.rms_ratio / want.rms_ratio - 1.0).abs() < 0.15, "{ctx}");
                if matches!(class, C::Contract | C::Expand) {
                    assert!(got.rotation_rad.abs() < 0.1, "{ctx}");
                } else {
                    assert!(
                        got.rotation_rad.signum() == want.rotation_rad.signum(),
                        "{ctx}"
                    );
                    assert!(got.rotation_rad.abs() > 0.8, "{ctx}");
                }
            }
            C::Join | C::TranslateThenJoin => {
                assert!(gd1 < gd0 - 2.5, "{ctx}");
                assert!((gd1 - wd1).abs() < 0.3, "{ctx}");
                if class == C::TranslateThenJoin {
                    assert!(shift > 3.0 * 0.95, "{ctx}");
                }
            }
            C::Split | C::SplitThenTranslate => {
                assert!(gd1 > gd0 + 2.0, "{ctx}");
                assert!((gd1 - wd1).abs() < 0.3, "{ctx}");
                if class == C::SplitThenTranslate {
                    assert!(shift > 3.0 * 0.95, "{ctx}");
                } else {
                    assert!(shift < 0.3, "{ctx}");
                }
            }
        }
    }

    #[test]
    fn every_class_does_what_it_says() {
        for class in MotionClass::ALL {
            for spec in library_specs(class, 3, 11) {
                spec.validate().unwrap();
                let m = spec.agents();
                assert!((LIBRARY_AGENTS.0..=LIBRARY_AGENTS.1).contains(&m));
                let sim = simulate(&spec, &params(), 1.0 / 30.0).unwrap();
                assert_eq!(sim.tracks.len(), m);
                let want = intended(&spec);
                let got = measure(&sim.tracks, &spec.group);
                check(class, &got, &want);
                assert!(
                    sim.duration_s >= spec.end_s()
                        && sim.duration_s <= spec.end_s() + SETTLE_CAP_S + 1e-9
                );
            }
        }
    }

    #[test]
    fn specs_and_simulations_are_deterministic_by_seed_and_vary_with_it() {
        for class in [MotionClass::Twist, MotionClass::Join] {
            let a = library_specs(class, 2, 5);
            let b = library_specs(class, 2, 5);
            let c = library_specs(class, 2, 6);
            assert_eq!(a, b);
            assert_ne!(a, c);
            assert_ne!(a[0], a[1]);
            let sa = simulate(&a[0], &params(), 0.05).unwrap();
            let sb = simulate(&b[0], &params(), 0.05).unwrap();
            assert_eq!(sa, sb);
        }
    }

    #[test]
    fn the_library_varies_size_shape_direction_and_sign() {
        let specs = library_specs(MotionClass::Twist, 15, 1);
        let sizes: std::collections::BTreeSet<usize> = specs.iter().map(|s| s.agents()).collect();
        assert!(sizes.len() > 5, "{sizes:?}");
        let signs: Vec<f64> = specs
            .iter()
            .map(|s| intended(s).rotation_rad.signum())
            .collect();
        assert!(signs.contains(&1.0) && signs.contains(&-1.0));
        let dirs: Vec<f64> = library_specs(MotionClass::Translate, 15, 1)
            .iter()
            .map(|s| {
                let d = intended(s).centroid_shift;
                d.y.atan2(d.x)
            })
            .collect();
        let spread = dirs.iter().cloned().fold(f64::MIN, f64::max)
            - dirs.iter().cloned().fold(f64::MAX, f64::min);
        assert!(spread > 3.0, "{dirs:?}");
    }

    #[test]
    fn bad_specs_and_steps_are_refused() {
        let good = library_specs(MotionClass::Translate, 1, 3).remove(0);
        assert!(matches!(
            simulate(&good, &params(), 0.0),
            Err(SimulateError::TimeStep(_))
        ));
        assert!(simulate(&good, &params(), f64::NAN).is_err());
        let mut s = good.clone();
        s.paths[2][5].x = f64::NAN;
        assert_eq!(s.validate(), Err(SimulateError::NonFinite { agent: 2 }));
        let mut s = good.clone();
        s.times_s[3] = s.times_s[2];
        assert!(matches!(
            s.validate(),
            Err(SimulateError::Times { index: 3, .. })
        ));
        let mut s = good.clone();
        s.group.pop();
        assert!(matches!(
            s.validate(),
            Err(SimulateError::Length { what: "group", .. })
        ));
        let mut s = good.clone();
        s.paths[0][0].x += 1.0;
        assert_eq!(s.validate(), Err(SimulateError::PathStart { agent: 0 }));
        let mut s = good;
        s.start.clear();
        assert_eq!(s.validate(), Err(SimulateError::NoAgents));
    }

    #[test]
    fn goals_interpolate_between_waypoints_and_hold_after_the_last() {
        let spec = MotionSpec {
            class: MotionClass::Translate,
            start: vec![Vec2::zeros()],
            group: vec![0],
            times_s: vec![0.0, 2.0, 3.0],
            paths: vec![vec![
                Vec2::zeros(),
                Vec2::new(2.0, 0.0),
                Vec2::new(2.0, 4.0),
            ]],
        };
        assert_eq!(spec.goal_at(0, -1.0), Vec2::zeros());
        assert!((spec.goal_at(0, 1.0) - Vec2::new(1.0, 0.0)).norm() < 1e-12);
        assert!((spec.goal_at(0, 2.5) - Vec2::new(2.0, 2.0)).norm() < 1e-12);
        assert_eq!(spec.goal_at(0, 9.0), Vec2::new(2.0, 4.0));
        let sim = simulate(&spec, &params(), 0.02).unwrap();
        assert!(sim.arrived);
        let end = sim.tracks[0].last().unwrap();
        assert!((end - Vec2::new(2.0, 4.0)).norm() <= ARRIVE_TOLERANCE_M);
    }

    #[test]
    fn measure_reads_a_known_rotation_beyond_a_half_turn() {
        let start: Vec<Vec2> = (0..6).map(|k| rot(Vec2::new(1.0, 0.0), k as f64)).collect();
        let tracks: Vec<Vec<Vec2>> = start
            .iter()
            .map(|&p| {
                (0..=40)
                    .map(|k| {
                        rot(p, -4.0 * k as f64 / 40.0) * (1.0 + k as f64 / 40.0)
                            + Vec2::new(3.0, 1.0)
                    })
                    .collect()
            })
            .collect();
        let m = measure(&tracks, &[0, 0, 0, 1, 1, 1]);
        assert!((m.rotation_rad + 4.0).abs() < 1e-9, "{m:?}");
        assert!((m.rms_ratio - 2.0).abs() < 1e-9);
    }
}
