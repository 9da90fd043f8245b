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
//! the shift bound (`AvoidParams::max_shift_s`) of the input and never before time zero for a
//! track that starts at or after it; the first shift that leaves the group with no
//! pair outside itself wins, else the one that leaves the fewest (then the least
//! deep). A shift is kept only if it lowers the group's pairs (in number, or in
//! depth at the same number), brings nobody into collision who was not in one
//! with the group already, and brings nobody closer than the input's closest pair
//! (`floor`): the never-worse rule of the piece retimings, made stricter.
//!
//! Evaluation is exact and cheap: each member's closest approach to each person
//! who could meet them at all — whose spatial bounding box, widened by the
//! threshold, meets the member's and whose time span meets the member's widened
//! by the largest shift — computed on the shifted pieces as detection computes
//! it, without building detection's grid for every shift tried.

use super::collide::PairCollision;
use super::collide::{
    collisions_involving, CollideError, Collisions, NearPieces, PersonPieces, DEFAULT_KEEP,
};
use super::tracks::TrackSet;
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

/// How a group fares at one shift against everyone else: its pairs with people
/// outside it (pairs inside the group do not change), their depth into the
/// threshold in all (m), and the closest of them (m; infinite without).
#[derive(Copy, Clone, Debug, PartialEq)]
struct Fare {
    pairs: usize,
    depth_m: f64,
    closest_m: f64,
}

impl Fare {
    fn better_than(&self, o: &Fare) -> bool {
        self.pairs < o.pairs || (self.pairs == o.pairs && self.depth_m < o.depth_m - 1e-9)
    }
}

/// A shift worth making: the group, by how much (s).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Shift {
    pub group: Vec<usize>,
    pub dt_s: f64,
    /// The group's pairs with people outside it after the shift.
    pub pairs_left: usize,
}

/// What a shift must respect.
#[derive(Copy, Clone, Debug)]
pub(super) struct Limits<'a> {
    /// Two people closer than this collide (m).
    pub threshold_m: f64,
    /// The most anyone's times may move from `input` (s).
    pub max_shift_s: f64,
    /// No pair may come closer than this (m): the input's closest.
    pub floor_m: f64,
    /// Everyone's times in the input (the bound and time zero are measured
    /// against them).
    pub input: &'a [Vec<f64>],
}

/// The best rigid shift of `group` (indices into `set`, sorted) among
/// `shifts_s`, or `None` if none makes the group's pairs fewer (or as many and
/// shallower) without bringing anyone new into collision with it or anyone
/// closer than the floor.
///
/// # Complexity
/// For each member and person whose bounding box comes within the threshold of
/// the member's, one pass over their piece pairs to keep those close in space
/// ([`NearPieces`]); then one closest approach per kept piece pair and shift tried.
pub(super) fn best_shift(
    set: &TrackSet,
    boxes: &[(Vec2, Vec2)],
    group: &[usize],
    limits: &Limits<'_>,
    shifts_s: &[f64],
) -> Option<Shift> {
    if group.is_empty() {
        return None;
    }
    let Limits {
        threshold_m,
        max_shift_s,
        floor_m,
        input,
    } = *limits;
    // The shift bound and time zero: the room each member leaves.
    let (mut most_delay, mut most_advance) = (max_shift_s, max_shift_s);
    for &k in group {
        let (t, t0) = (&set.tracks[k].times_s, &input[k]);
        let off = t.iter().zip(t0).map(|(a, b)| a - b);
        let (lo, hi) = off.fold((0.0f64, 0.0f64), |(lo, hi), d| (lo.min(d), hi.max(d)));
        // A delay dt moves the largest offset to hi + dt, an advance a the
        // smallest to lo − a; both must stay within the bound.
        most_delay = most_delay.min(max_shift_s - hi);
        most_advance = most_advance.min(max_shift_s + lo);
        if t0[0] >= 0.0 {
            most_advance = most_advance.min(t[0]);
        }
    }
    let reach_s = most_delay.max(most_advance).max(0.0);
    // Each member's pieces against the pieces of everyone outside the group who
    // could meet it: bounding boxes within the threshold, times within reach.
    let r = threshold_m;
    let near = |a: usize, b: usize| could_meet(set, boxes, a, b, r, reach_s);
    let mut others: Vec<(usize, PersonPieces)> = Vec::new();
    // Per member and person near them: the pieces that come within the
    // threshold of each other in space, where alone a shift can make them meet.
    let mut checks: Vec<NearPieces> = Vec::new();
    for &a in group {
        let mine = PersonPieces::of(&set.tracks[a].as_ref());
        for b in 0..set.tracks.len() {
            if group.binary_search(&b).is_ok() || !near(a, b) {
                continue;
            }
            let oi = match others.iter().position(|(k, _)| *k == b) {
                Some(i) => i,
                None => {
                    others.push((b, PersonPieces::of(&set.tracks[b].as_ref())));
                    others.len() - 1
                }
            };
            let close = NearPieces::of(&mine, &others[oi].1, r, reach_s);
            if !close.is_empty() {
                checks.push(close);
            }
        }
    }
    let fare = |dt: f64, colliding: &mut Vec<usize>| {
        colliding.clear();
        let mut f = Fare {
            pairs: 0,
            depth_m: 0.0,
            closest_m: f64::INFINITY,
        };
        for (c, close) in checks.iter().enumerate() {
            if let Some(d) = close.closest_shifted(dt, r) {
                f.pairs += 1;
                f.depth_m += r - d;
                f.closest_m = f.closest_m.min(d);
                colliding.push(c);
            }
        }
        f
    };
    let mut before = Vec::new();
    let at_zero = fare(0.0, &mut before);
    if at_zero.pairs == 0 {
        return None;
    }
    let mut now = Vec::new();
    let mut best: Option<(f64, Fare)> = None;
    for &dt in shifts_s {
        if (dt > 0.0 && dt > most_delay) || (dt < 0.0 && -dt > most_advance) {
            continue;
        }
        let f = fare(dt, &mut now);
        // No one the group did not collide with is brought into collision: a
        // shift trades no pair for another (a new pair may be two people walking
        // the same way, whom nothing separates afterwards).
        let fresh = now.iter().any(|c| before.binary_search(c).is_err());
        if fresh || f.closest_m < floor_m || !f.better_than(&at_zero) {
            continue;
        }
        if best.as_ref().is_none_or(|(_, b)| f.better_than(b)) {
            best = Some((dt, f));
        }
        if f.pairs == 0 {
            break;
        }
    }
    best.map(|(dt_s, f)| Shift {
        group: group.to_vec(),
        dt_s,
        pairs_left: f.pairs,
    })
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

/// The pairs involving `group` (sorted indices into `set`), as
/// [`collisions_involving`] finds them on the whole set, but detected among the
/// group and the people who could meet it (bounding boxes within the threshold,
/// time spans meeting) only; indices are the set's.
///
/// # Errors
/// A [`CollideError`] from detection.
pub(super) fn involving_near(
    set: &TrackSet,
    boxes: &[(Vec2, Vec2)],
    group: &[usize],
    threshold_m: f64,
) -> Result<Collisions, CollideError> {
    let near = |a: usize, b: usize| could_meet(set, boxes, a, b, threshold_m, 0.0);
    // In the set's order, so a < b holds after mapping back.
    let people: Vec<usize> = (0..set.tracks.len())
        .filter(|&k| group.binary_search(&k).is_ok() || group.iter().any(|&g| near(g, k)))
        .collect();
    let sub = TrackSet {
        tracks: people.iter().map(|&k| set.tracks[k].clone()).collect(),
        step_s: set.step_s,
    };
    let who: Vec<bool> = people
        .iter()
        .map(|k| group.binary_search(k).is_ok())
        .collect();
    let mut c = collisions_involving(&sub, threshold_m, &who, DEFAULT_KEEP)?;
    for q in c.pairs.iter_mut().chain(c.closest.iter_mut()) {
        q.a = people[q.a];
        q.b = people[q.b];
    }
    for e in &mut c.events {
        e.a = people[e.a];
        e.b = people[e.b];
    }
    Ok(c)
}

/// Whether people `a` and `b` could come within `r` metres of each other with
/// `a`'s times moved by at most `reach_s` either way: their bounding boxes
/// within `r` on both axes and their time spans meeting, widened by `reach_s`.
fn could_meet(
    set: &TrackSet,
    boxes: &[(Vec2, Vec2)],
    a: usize,
    b: usize,
    r: f64,
    reach_s: f64,
) -> bool {
    let ((alo, ahi), (blo, bhi)) = (boxes[a], boxes[b]);
    let (sa, sb) = (set.tracks[a].span_s(), set.tracks[b].span_s());
    blo.x <= ahi.x + r
        && alo.x <= bhi.x + r
        && blo.y <= ahi.y + r
        && alo.y <= bhi.y + r
        && sb.1 >= sa.0 - reach_s
        && sb.0 <= sa.1 + reach_s
}
