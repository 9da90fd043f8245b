//! Whole-person and whole-group time shifts: the cheap candidates of avoidance.
//!
//! A rigid shift `t ↦ t + dt` of every time of a group of people changes no
//! speed, keeps every track monotone and leaves the pairs inside the group and
//! the pairs among everyone else exactly as they were: only the group's pairs with
//! the others change. Two crowds crossing are separated by delaying one of them
//! (rows of one pass through the gaps of the other, or wait until it has passed),
//! two walkers meeting head-on on one line by one of them waiting; eq. 19's
//! piece retiming (section 4.1.2) needs many rounds for either and each round may
//! push the pair into someone else.
//!
//! The groups tried are the two sides of each connected part of the collision
//! graph (a two-colouring by breadth-first search: for two crossing crowds, the
//! crowds), and each person of a colliding pair alone. The shifts tried run
//! outwards from zero ([`candidates_s`]), delays and advances, within
//! [`AvoidParams::max_shift_s`] of the input and never before time zero for a
//! track that starts at or after it; the first shift that leaves the group with no
//! pair outside itself wins, else the one that leaves the fewest (then the least
//! deep). A shift is kept only if it lowers the group's pairs (in number, or in
//! depth at the same number), brings nobody into collision who was not in one
//! with the group already, and brings nobody closer than the input's closest pair
//! (`floor`): the never-worse rule of the piece retimings, made stricter.
//!
//! Evaluation is exact and cheap: detection runs on the group and the people who
//! could meet it at all — those whose spatial bounding box, widened by the
//! threshold, meets a group member's and whose time span meets the group's
//! widened by the largest shift.

use super::super::collide::{collisions_involving, CollideError, Collisions, DEFAULT_KEEP};
use super::super::tracks::{Track, TrackSet};
use super::{AvoidParams, PairCollision};
use crate::geom::Vec2;

/// The shifts tried, in seconds, by increasing size, each as a delay then an
/// advance: every 0.1 s to 2 s, every 0.25 s to 5 s, every 0.5 s beyond, up to
/// `max_s`.
pub(super) fn candidates_s(max_s: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut push = |m: f64| {
        if m <= max_s + 1e-12 {
            out.push(m);
            out.push(-m);
        }
    };
    for k in 1..=20 {
        push(0.1 * k as f64);
    }
    for k in 1..=12 {
        push(2.0 + 0.25 * k as f64);
    }
    let mut m = 5.5;
    while m <= max_s + 1e-12 {
        push(m);
        m += 0.5;
    }
    out
}

/// Each person's spatial bounding box (min, max corners), metres.
pub(super) fn boxes(set: &TrackSet) -> Vec<(Vec2, Vec2)> {
    set.tracks
        .iter()
        .map(|t| {
            t.points.iter().fold(
                (
                    Vec2::new(f64::INFINITY, f64::INFINITY),
                    Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
                ),
                |(lo, hi), p| (lo.inf(p), hi.sup(p)),
            )
        })
        .collect()
}

/// How a group fares at one shift: its pairs (those involving a member, pairs
/// inside the group included: a shift does not change them), their depth into
/// the threshold in all (m), and the closest of them (m; infinite without).
#[derive(Copy, Clone, Debug, PartialEq)]
struct Fare {
    pairs: usize,
    depth_m: f64,
    closest_m: f64,
}

impl Fare {
    fn of(c: &Collisions, threshold_m: f64) -> Fare {
        Fare {
            pairs: c.pair_count(),
            depth_m: if c.is_complete() {
                c.pairs
                    .iter()
                    .map(|p| (threshold_m - p.closest.distance_m).max(0.0))
                    .sum()
            } else {
                f64::INFINITY
            },
            closest_m: c.closest().map_or(f64::INFINITY, |p| p.closest.distance_m),
        }
    }

    fn better_than(&self, o: &Fare) -> bool {
        self.pairs < o.pairs || (self.pairs == o.pairs && self.depth_m < o.depth_m - 1e-9)
    }
}

/// A shift worth making: the group, by how much (s).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Shift {
    pub group: Vec<usize>,
    pub dt_s: f64,
}

/// The best rigid shift of `group` (indices into `set`), or `None` if no shift
/// tried makes the group's pairs fewer (or as many and shallower) without
/// bringing anyone closer than `floor_m`. `input` holds everyone's times in the
/// input (the shift bound and time zero are measured against it).
///
/// # Errors
/// A [`CollideError`] from detection (a threshold out of range).
pub(super) fn best_shift(
    set: &TrackSet,
    boxes: &[(Vec2, Vec2)],
    group: &[usize],
    p: &AvoidParams,
    input: &[Vec<f64>],
    floor_m: f64,
    shifts_s: &[f64],
) -> Result<Option<Shift>, CollideError> {
    if group.is_empty() {
        return Ok(None);
    }
    let n = set.tracks.len();
    let mut in_group = vec![false; n];
    for &k in group {
        in_group[k] = true;
    }
    // The shift bound and time zero: the room each member leaves.
    let (mut most_delay, mut most_advance) = (p.max_shift_s, p.max_shift_s);
    for &k in group {
        let (t, t0) = (&set.tracks[k].times_s, &input[k]);
        let off = t.iter().zip(t0).map(|(a, b)| a - b);
        let (lo, hi) = off.fold((0.0f64, 0.0f64), |(lo, hi), d| (lo.min(d), hi.max(d)));
        // A delay dt moves the largest offset to hi + dt, an advance a the
        // smallest to lo − a; both must stay within the bound.
        most_delay = most_delay.min(p.max_shift_s - hi);
        most_advance = most_advance.min(p.max_shift_s + lo);
        if t0[0] >= 0.0 {
            most_advance = most_advance.min(t[0]);
        }
    }
    let reach_s = most_delay.max(most_advance).max(0.0);
    // The group and whoever could meet it.
    let (mut t_lo, mut t_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &k in group {
        let (a, b) = set.tracks[k].span_s();
        t_lo = t_lo.min(a);
        t_hi = t_hi.max(b);
    }
    let (t_lo, t_hi) = (t_lo - reach_s, t_hi + reach_s);
    let r = p.threshold_m;
    let meets = |k: usize| {
        let (lo, hi) = boxes[k];
        group.iter().any(|&g| {
            let (glo, ghi) = boxes[g];
            lo.x <= ghi.x + r && glo.x <= hi.x + r && lo.y <= ghi.y + r && glo.y <= hi.y + r
        })
    };
    let mut tracks: Vec<Track> = group.iter().map(|&k| set.tracks[k].clone()).collect();
    for k in 0..n {
        if in_group[k] {
            continue;
        }
        let (a, b) = set.tracks[k].span_s();
        if b >= t_lo && a <= t_hi && meets(k) {
            tracks.push(set.tracks[k].clone());
        }
    }
    let who: Vec<bool> = (0..tracks.len()).map(|i| i < group.len()).collect();
    let mut sub = TrackSet {
        tracks,
        step_s: set.step_s,
    };
    let zero = collisions_involving(&sub, r, &who, DEFAULT_KEEP)?;
    if !zero.is_complete() {
        return Ok(None);
    }
    let at_zero = Fare::of(&zero, r);
    let before: Vec<(usize, usize)> = zero.pairs.iter().map(|q| (q.a, q.b)).collect();
    // Pairs inside the group: no shift changes them.
    let inside = {
        let own = TrackSet {
            tracks: sub.tracks[..group.len()].to_vec(),
            step_s: set.step_s,
        };
        collisions_involving(&own, r, &who[..group.len()], DEFAULT_KEEP)?.pair_count()
    };
    if at_zero.pairs <= inside {
        return Ok(None);
    }
    let mut best: Option<(f64, Fare)> = None;
    let mut applied = 0.0;
    for &dt in shifts_s {
        if (dt > 0.0 && dt > most_delay) || (dt < 0.0 && -dt > most_advance) {
            continue;
        }
        for t in &mut sub.tracks[..group.len()] {
            for x in &mut t.times_s {
                *x += dt - applied;
            }
        }
        applied = dt;
        let c = collisions_involving(&sub, r, &who, DEFAULT_KEEP)?;
        let fare = Fare::of(&c, r);
        // No one the group did not collide with is brought into collision: a
        // shift trades no pair for another (a new pair may be two people walking
        // the same way, whom nothing separates afterwards).
        let fresh = !c.is_complete() || c.pairs.iter().any(|q| !before.contains(&(q.a, q.b)));
        if fresh || fare.closest_m < floor_m || !fare.better_than(&at_zero) {
            continue;
        }
        if best.as_ref().is_none_or(|(_, b)| fare.better_than(b)) {
            best = Some((dt, fare));
        }
        if fare.pairs <= inside {
            break;
        }
    }
    Ok(best.map(|(dt_s, _)| Shift {
        group: group.to_vec(),
        dt_s,
    }))
}

/// The two sides of each connected part of the graph of `pairs` (people as
/// nodes), by breadth-first two-colouring; a side is empty when the part has an
/// odd cycle that leaves nobody on it (then only the other side is tried).
/// Parts are listed largest first.
pub(super) fn sides(n: usize, pairs: &[PairCollision]) -> Vec<[Vec<usize>; 2]> {
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for q in pairs {
        adj[q.a].push(q.b);
        adj[q.b].push(q.a);
    }
    let mut colour: Vec<Option<u8>> = vec![None; n];
    let mut parts = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    for s in 0..n {
        if adj[s].is_empty() || colour[s].is_some() {
            continue;
        }
        let mut part: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
        colour[s] = Some(0);
        queue.push_back(s);
        while let Some(u) = queue.pop_front() {
            let cu = colour[u].unwrap_or(0);
            part[cu as usize].push(u);
            for &w in &adj[u] {
                if colour[w].is_none() {
                    colour[w] = Some(1 - cu);
                    queue.push_back(w);
                }
            }
        }
        part[0].sort_unstable();
        part[1].sort_unstable();
        parts.push(part);
    }
    parts.sort_by_key(|p| std::cmp::Reverse(p[0].len() + p[1].len()));
    parts
}
