//! Collision detection between people in space-time, crowd-motion-editing
//! section 4.1.1 (eqs. 13–17, Algorithm 2).
//!
//! A person's track is cut into *pieces*: each linked segment `j → j + 1`, along
//! which the person moves linearly over `[t_j, t_{j+1}]`, and each isolated sample
//! (one touching no linked segment), at which the person is present for an instant.
//! A gap breaks the track: between unlinked samples the person is away.
//!
//! Two people collide at threshold `d` when, at some time both are present, their
//! distance is below `d` (strictly). For two pieces whose closed time intervals
//! overlap in `[l1, l2]`, the closest approach of the two linearly moving points is
//! eqs. 13–16 with the time clamped to the overlap (eq. 17); when the overlap is a
//! single instant (a segment ending where the other's interval starts or ends, an
//! isolated sample inside the other's interval) it is the distance at that instant.
//!
//! [`detect`] finds them with a sweep over time slabs and a uniform grid per slab;
//! [`collisions_all_pairs`] is the reference (every pair of people, every pair of
//! pieces that overlap in time) the tests and benches compare it with. Both evaluate
//! the same piece pairs with the same arithmetic, so they agree exactly.
//!
//! # Bounded results
//! Detection *streams*: it counts every colliding pair and event, keeps the closest
//! approach, and keeps only the [`DEFAULT_KEEP`] closest pairs and earliest events
//! (or as many as [`detect_keeping`] is told), so its memory is O(people + pieces +
//! kept), whatever the number of colliding pairs. Two kinds of crowd are a
//! [`Cluster`], one report with its size, its pairs counted in closed form and never
//! enumerated: people on one identical track (same positions, times and links:
//! for instance standing at one point for the same span), and at least
//! [`MIN_STANDING_CLUSTER`](super::MIN_STANDING_CLUSTER) people standing still at the same times within half the
//! threshold of one of them (so every two are closer than the threshold whenever
//! present; their closest two are found by a sweep over their places). An
//! identical track's pairs with anyone else are evaluated once, for its first
//! person, and counted for every one. People close together who move, or stand at
//! different times, are still evaluated pair by pair: O(k²) time for k of them in
//! one grid cell, O(k) memory.
//!
//! On the two UCY fixtures (`tests/fixtures/crowd/`, 25 fps, step 10) the counts of
//! pairs below 0.2/0.3/0.5/1.0 m equal the README's *continuous* counts with this
//! reading, in which single shared instants count (zara01 0/3/27/160, students001
//! 48/168/606/1840; minima 0.236 and 0.078 m). Leaving single instants out gives
//! zara01 0/3/27/159 and students001 48/166/600/1828, which disagrees; distances at
//! shared annotated frames alone give the README's *sampled* counts.

use super::clusters::{
    classes, closest_standing, spatial_order, standing_groups, Cluster, NO_GROUP,
};
use super::flat::{TrackError, TrackRef, Tracks};
use super::slab_grid::{cell_range, overlap, SlabGrid};
use crate::geom::Vec2;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use thiserror::Error;

/// Margin added to the bounding boxes the grid compares (metres), so rounding in
/// the box corners never drops a pair the exact test would keep.
const BOX_MARGIN_M: f64 = 1e-9;

/// The most time slabs a sweep uses; longer spans get wider slabs.
const MAX_SLABS: usize = 1 << 20;

/// The pairs and events a detection keeps by default ([`Collisions::pairs`],
/// [`Collisions::events`], [`Collisions::clusters`]); every one is counted.
pub const DEFAULT_KEEP: usize = 1_000;

/// Bad input to collision detection.
#[derive(Debug, Error, PartialEq)]
pub enum CollideError {
    /// The threshold is not a positive finite distance.
    #[error("the collision threshold must be a positive number of metres, not {threshold_m}")]
    Threshold {
        /// The threshold given.
        threshold_m: f64,
    },
    /// The track set breaks its invariants.
    #[error(transparent)]
    Tracks(#[from] TrackError),
}

/// Where and when two people come closest (eq. 17 and the positions after it).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Approach {
    /// Time of the closest approach (seconds).
    pub t_s: f64,
    /// The distance then (metres).
    pub distance_m: f64,
    /// First person's position then (metres).
    pub at_a: Vec2,
    /// Second person's position then (metres).
    pub at_b: Vec2,
    /// First person's sample at the start of the piece they were on (the segment
    /// `sample_a → sample_a + 1`, or the isolated sample).
    pub sample_a: usize,
    /// Second person's sample, likewise.
    pub sample_b: usize,
    /// Whether the first person was on a linked segment (else an isolated sample).
    pub moving_a: bool,
    /// Whether the second person was on a linked segment.
    pub moving_b: bool,
}

impl Approach {
    /// The midpoint of the two positions: the place of the collision.
    pub fn place(&self) -> Vec2 {
        (self.at_a + self.at_b) * 0.5
    }
}

/// One collision: a maximal run of consecutive time overlaps of two people's pieces
/// in each of which they come closer than the threshold (a run continues while the
/// next such overlap starts no later than the run's end).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CollisionEvent {
    /// First person's index in the track set (`a < b`).
    pub a: usize,
    /// Second person's index.
    pub b: usize,
    /// First person's id.
    pub id_a: u64,
    /// Second person's id.
    pub id_b: u64,
    /// Start of the run's first overlap (seconds).
    pub start_s: f64,
    /// End of the run's last overlap (seconds).
    pub end_s: f64,
    /// The closest approach in the run.
    pub closest: Approach,
}

/// Two people who collide, with their closest approach overall.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PairCollision {
    /// First person's index in the track set (`a < b`).
    pub a: usize,
    /// Second person's index.
    pub b: usize,
    /// First person's id.
    pub id_a: u64,
    /// Second person's id.
    pub id_b: u64,
    /// Their closest approach (below the threshold).
    pub closest: Approach,
    /// Number of [`CollisionEvent`]s of the pair.
    pub events: usize,
}

/// The collisions of a track set at one threshold: every one counted, a bounded
/// number kept.
#[derive(Clone, Debug, PartialEq)]
pub struct Collisions {
    /// The threshold (metres): pairs closer than this collide.
    pub threshold_m: f64,
    /// How many pairs, events and clusters were kept at most.
    pub keep: usize,
    /// Every colliding pair of people, clusters' pairs included (a pair with a
    /// cluster's first member counts once per member).
    pub pair_total: u64,
    /// Every [`CollisionEvent`] (counted per member, as `pair_total`; two members of
    /// a cluster have one per stretch of their track between gaps).
    pub event_total: u64,
    /// Every cluster.
    pub cluster_total: usize,
    /// The pair that comes closest of all (a cluster's first two members when there
    /// is a cluster), if any: least `(distance, a, b)`.
    pub closest: Option<PairCollision>,
    /// The `keep` closest pairs (least `(distance, a, b)`), ordered by `(a, b)`.
    /// Pairs inside a cluster are not listed; a pair with a cluster member is
    /// listed for the cluster's first member.
    pub pairs: Vec<PairCollision>,
    /// The `keep` earliest events (least `(closest.t_s, a, b, start_s)`), ordered by
    /// pair, then time.
    pub events: Vec<CollisionEvent>,
    /// The `keep` clusters of most people (ties: by first member), ordered by first member.
    pub clusters: Vec<Cluster>,
}

impl Collisions {
    /// The number of distinct colliding pairs: the primary measure.
    pub fn pair_count(&self) -> usize {
        usize::try_from(self.pair_total).unwrap_or(usize::MAX)
    }

    /// The colliding pair that comes closest, if any.
    pub fn closest(&self) -> Option<&PairCollision> {
        self.closest.as_ref()
    }

    /// The closest approach of any colliding pair (metres), if any.
    pub fn min_distance_m(&self) -> Option<f64> {
        self.closest().map(|p| p.closest.distance_m)
    }

    /// Whether every pair and event is listed (nothing left out, no cluster).
    pub fn is_complete(&self) -> bool {
        self.pairs.len() as u64 == self.pair_total
            && self.events.len() as u64 == self.event_total
            && self.cluster_total == 0
    }

    /// The kept events in time order (of their closest approach).
    pub fn events_by_time(&self) -> Vec<CollisionEvent> {
        let mut e = self.events.clone();
        e.sort_by(|x, y| {
            x.closest
                .t_s
                .total_cmp(&y.closest.t_s)
                .then((x.a, x.b).cmp(&(y.a, y.b)))
        });
        e
    }
}

/// A value ordered by a key of a float and two indices and a float, compared with
/// `total_cmp` (for the bounded heaps of [`Tally`]).
#[derive(Copy, Clone, Debug)]
struct Keyed<T> {
    key: (f64, usize, usize, f64),
    item: T,
}

impl<T> Keyed<T> {
    fn order(&self, other: &Self) -> Ordering {
        let (a, b) = (&self.key, &other.key);
        a.0.total_cmp(&b.0)
            .then(a.1.cmp(&b.1))
            .then(a.2.cmp(&b.2))
            .then(a.3.total_cmp(&b.3))
    }
}

impl<T> PartialEq for Keyed<T> {
    fn eq(&self, other: &Self) -> bool {
        self.order(other) == Ordering::Equal
    }
}
impl<T> Eq for Keyed<T> {}
impl<T> PartialOrd for Keyed<T> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl<T> Ord for Keyed<T> {
    fn cmp(&self, other: &Self) -> Ordering {
        self.order(other)
    }
}

/// Pushes into a max-heap holding the `keep` least items.
fn push_bounded<T>(heap: &mut BinaryHeap<Keyed<T>>, keep: usize, x: Keyed<T>) {
    if heap.len() < keep {
        heap.push(x);
    } else if let Some(mut top) = heap.peek_mut() {
        if x < *top {
            *top = x;
        }
    }
}

/// Counts every pair and event and keeps the closest pairs and earliest events:
/// O(keep) memory however many collide.
struct Tally {
    keep: usize,
    pair_total: u64,
    event_total: u64,
    closest: Option<PairCollision>,
    pairs: BinaryHeap<Keyed<PairCollision>>,
    events: BinaryHeap<Keyed<CollisionEvent>>,
    clusters: BinaryHeap<Keyed<Cluster>>,
    cluster_total: usize,
}

impl Tally {
    fn new(keep: usize) -> Tally {
        Tally {
            keep,
            pair_total: 0,
            event_total: 0,
            closest: None,
            pairs: BinaryHeap::new(),
            events: BinaryHeap::new(),
            clusters: BinaryHeap::new(),
            cluster_total: 0,
        }
    }

    fn consider_closest(&mut self, p: &PairCollision) {
        let key = |q: &PairCollision| (q.closest.distance_m, q.a, q.b);
        let better = self.closest.as_ref().is_none_or(|c| {
            let (x, y) = (key(p), key(c));
            x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))) == Ordering::Less
        });
        if better {
            self.closest = Some(*p);
        }
    }

    /// A colliding pair with its events, standing for `multiplicity` pairs.
    fn pair(&mut self, pair: PairCollision, events: &[CollisionEvent], multiplicity: u64) {
        self.pair_total += multiplicity;
        self.event_total += events.len() as u64 * multiplicity;
        self.consider_closest(&pair);
        let keep = self.keep;
        push_bounded(
            &mut self.pairs,
            keep,
            Keyed {
                key: (pair.closest.distance_m, pair.a, pair.b, 0.0),
                item: pair,
            },
        );
        for e in events {
            push_bounded(
                &mut self.events,
                keep,
                Keyed {
                    key: (e.closest.t_s, e.a, e.b, e.start_s),
                    item: *e,
                },
            );
        }
    }

    /// A cluster; `closest` its closest pair (`a < b`) and their distance, the
    /// distance 0 of its first two members for an identical track.
    fn cluster<S: Tracks + ?Sized>(
        &mut self,
        set: &S,
        c: Cluster,
        closest: Option<(usize, usize, f64)>,
    ) {
        let tr = set.track(c.members[0]);
        // Every two members collide in each stretch of the track between gaps.
        let events = 1 + tr.linked.iter().filter(|l| !**l).count();
        self.pair_total += c.pairs();
        self.event_total += c.pairs() * events as u64;
        self.cluster_total += 1;
        let (a, b, distance_m) = closest.unwrap_or((c.members[0], c.members[1], 0.0));
        let (ta, tb) = (set.track(a), set.track(b));
        self.consider_closest(&PairCollision {
            a,
            b,
            id_a: ta.id,
            id_b: tb.id,
            closest: Approach {
                t_s: ta.times_s[0],
                distance_m,
                at_a: ta.points[0],
                at_b: tb.points[0],
                sample_a: 0,
                sample_b: 0,
                moving_a: ta.linked.first().copied().unwrap_or(false),
                moving_b: tb.linked.first().copied().unwrap_or(false),
            },
            events,
        });
        let keep = self.keep;
        let first = c.members[0];
        push_bounded(
            &mut self.clusters,
            keep,
            Keyed {
                // Largest first, then by first member.
                key: (-(c.members.len() as f64), first, 0, 0.0),
                item: c,
            },
        );
    }

    fn finish(self, threshold_m: f64) -> Collisions {
        let mut pairs: Vec<PairCollision> = self.pairs.into_iter().map(|k| k.item).collect();
        pairs.sort_by_key(|p| (p.a, p.b));
        let mut events: Vec<CollisionEvent> = self.events.into_iter().map(|k| k.item).collect();
        events.sort_by(|x, y| {
            (x.a, x.b)
                .cmp(&(y.a, y.b))
                .then(x.start_s.total_cmp(&y.start_s))
        });
        let mut clusters: Vec<Cluster> = self.clusters.into_iter().map(|k| k.item).collect();
        clusters.sort_by_key(|c| c.members[0]);
        Collisions {
            threshold_m,
            keep: self.keep,
            pair_total: self.pair_total,
            event_total: self.event_total,
            cluster_total: self.cluster_total,
            closest: self.closest,
            pairs,
            events,
            clusters,
        }
    }
}

/// A piece of a track: a linked segment (`t0 < t1`, the times of a valid set
/// strictly increase) or an isolated sample (`t0 == t1`). 56 bytes: detection
/// holds one per segment or lone sample of every person.
#[derive(Copy, Clone, Debug)]
struct Piece {
    track: u32,
    sample: u32,
    t0: f64,
    t1: f64,
    p0: Vec2,
    p1: Vec2,
}

impl Piece {
    /// Position at `t` in `[t0, t1]`: the endpoints exactly, linear between.
    fn at(&self, t: f64) -> Vec2 {
        if t <= self.t0 {
            self.p0
        } else if t >= self.t1 {
            self.p1
        } else {
            self.p0 + (self.p1 - self.p0) * ((t - self.t0) / (self.t1 - self.t0))
        }
    }

    /// Whether the piece is a segment (else a lone sample, standing).
    fn moving(&self) -> bool {
        self.t1 > self.t0
    }

    fn velocity(&self) -> Vec2 {
        if self.moving() {
            (self.p1 - self.p0) / (self.t1 - self.t0)
        } else {
            Vec2::zeros()
        }
    }
}

/// The pieces of the tracks `include` keeps (every track when `None`), grouped by
/// track, the tracks in `order` (by index when `None`), each track's in time order;
/// `starts[r]..starts[r+1]` are the pieces of the `r`-th track of `order` (empty
/// for a track left out).
fn pieces<S: Tracks + ?Sized>(
    set: &S,
    include: Option<&[u32]>,
    order: Option<&[u32]>,
) -> (Vec<Piece>, Vec<usize>) {
    let mut out = Vec::with_capacity(set.samples());
    let mut starts = Vec::with_capacity(set.people() + 1);
    for pos in 0..set.people() {
        let k = order.map_or(pos, |o| o[pos] as usize);
        let tr = set.track(k);
        starts.push(out.len());
        if include.is_some_and(|m| m[k] == 0) {
            continue;
        }
        push_pieces(&tr, k, &mut out);
    }
    starts.push(out.len());
    out.shrink_to_fit();
    (out, starts)
}

/// Appends person `k`'s pieces (track `tr`) to `out`: a linked segment per
/// linked pair of samples, a lone sample where neither neighbour is linked.
fn push_pieces(tr: &TrackRef<'_>, k: usize, out: &mut Vec<Piece>) {
    let n = tr.len();
    for j in 0..n {
        let next = j + 1 < n && tr.linked[j];
        let prev = j > 0 && tr.linked[j - 1];
        if next {
            out.push(Piece {
                track: k as u32,
                sample: j as u32,
                t0: tr.times_s[j],
                t1: tr.times_s[j + 1],
                p0: tr.points[j],
                p1: tr.points[j + 1],
            });
        } else if !prev {
            out.push(Piece {
                track: k as u32,
                sample: j as u32,
                t0: tr.times_s[j],
                t1: tr.times_s[j],
                p0: tr.points[j],
                p1: tr.points[j],
            });
        }
    }
}

/// One person's pieces as detection sees them, for [`closest_shifted`].
#[derive(Clone, Debug, Default)]
pub(super) struct PersonPieces(Vec<Piece>);

impl PersonPieces {
    /// The pieces of `tr`.
    pub(super) fn of(tr: &TrackRef<'_>) -> PersonPieces {
        let mut out = Vec::with_capacity(tr.len());
        push_pieces(tr, 0, &mut out);
        PersonPieces(out)
    }
}

/// The reference for [`NearPieces::closest_shifted`] (tests): the closest approach of two people (metres) if it is under `below_m`, `a`'s
/// times all moved by `shift_s`, exactly as [`detect`] would find it on the
/// shifted tracks (the same pieces and eqs. 13–17); `None` when their times
/// never meet or they never come that close. The pieces of a track are in time
/// order, so each of `a`'s pieces is compared only with the pieces of `b` whose
/// times meet it, and two pieces whose bounding boxes are `below_m` apart are
/// not compared: O(n_a + n_b) comparisons plus the overlaps.
#[cfg(test)]
pub(super) fn closest_shifted(
    a: &PersonPieces,
    shift_s: f64,
    b: &PersonPieces,
    below_m: f64,
) -> Option<f64> {
    let pb = &b.0;
    let (Some(b_first), Some(b_last)) = (pb.first(), pb.last()) else {
        return None;
    };
    let (b_t0, b_t1) = (b_first.t0, b_last.t1);
    let mut best: Option<f64> = None;
    let mut first = 0;
    // `a`'s pieces before `b` begins cannot meet it (ends are non-decreasing).
    let start = a.0.partition_point(|p| p.t1 + shift_s < b_t0);
    for pa in &a.0[start..] {
        if pa.t0 + shift_s > b_t1 {
            break;
        }
        let pa = Piece {
            t0: pa.t0 + shift_s,
            t1: pa.t1 + shift_s,
            ..*pa
        };
        while first < pb.len() && pb[first].t1 < pa.t0 {
            first += 1;
        }
        for q in &pb[first..] {
            if q.t0 > pa.t1 {
                break;
            }
            if boxes_apart(&pa, q, below_m) {
                continue;
            }
            if let Some((_, _, x)) = closest(&pa, q) {
                if x.distance_m < below_m && best.is_none_or(|d| x.distance_m < d) {
                    best = Some(x.distance_m);
                }
            }
        }
    }
    best
}

/// The pairs of pieces of two people that come within some distance of each
/// other in space, whenever they are (their bounding boxes that close): the only
/// places where the two can come that close at any relative shift of their
/// times. [`NearPieces::closest_shifted`] then costs one comparison per pair.
#[derive(Clone, Debug, Default)]
pub(super) struct NearPieces(Vec<(Piece, Piece)>);

impl NearPieces {
    /// The piece pairs of `a` and `b` whose bounding boxes are closer than
    /// `within_m` on both axes and whose times can meet when `a`'s move by at
    /// most `reach_s` either way.
    pub(super) fn of(
        a: &PersonPieces,
        b: &PersonPieces,
        within_m: f64,
        reach_s: f64,
    ) -> NearPieces {
        // Each side's pieces near the other's whole box first: a path crossing
        // another meets it in a few pieces.
        let bound = |ps: &[Piece]| {
            ps.iter().fold(
                Piece {
                    track: 0,
                    sample: 0,
                    t0: 0.0,
                    t1: 0.0,
                    p0: Vec2::new(f64::INFINITY, f64::INFINITY),
                    p1: Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
                },
                |acc, p| Piece {
                    p0: acc.p0.inf(&p.p0.inf(&p.p1)),
                    p1: acc.p1.sup(&p.p0.sup(&p.p1)),
                    ..acc
                },
            )
        };
        let (box_a, box_b) = (bound(&a.0), bound(&b.0));
        let near_b: Vec<&Piece> =
            b.0.iter()
                .filter(|p| !boxes_apart(p, &box_a, within_m))
                .collect();
        let mut out = Vec::new();
        if near_b.is_empty() {
            return NearPieces(out);
        }
        for pa in a.0.iter().filter(|p| !boxes_apart(p, &box_b, within_m)) {
            for pb in &near_b {
                let meet = pa.t1 + reach_s >= pb.t0 && pa.t0 - reach_s <= pb.t1;
                if meet && !boxes_apart(pa, pb, within_m) {
                    out.push((*pa, **pb));
                }
            }
        }
        NearPieces(out)
    }

    /// Whether no two pieces come that close.
    pub(super) fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// As [`closest_shifted`] with the `within_m` given to [`NearPieces::of`]
    /// as `below_m` (no larger): the same distance, found among the near pairs.
    pub(super) fn closest_shifted(&self, shift_s: f64, below_m: f64) -> Option<f64> {
        let mut best: Option<f64> = None;
        for (pa, pb) in &self.0 {
            if pa.t1 + shift_s < pb.t0 || pa.t0 + shift_s > pb.t1 {
                continue;
            }
            let pa = Piece {
                t0: pa.t0 + shift_s,
                t1: pa.t1 + shift_s,
                ..*pa
            };
            if let Some((_, _, x)) = closest(&pa, pb) {
                if x.distance_m < below_m && best.is_none_or(|d| x.distance_m < d) {
                    best = Some(x.distance_m);
                }
            }
        }
        best
    }
}

/// Whether two pieces' bounding boxes are at least `d` apart on an axis.
fn boxes_apart(a: &Piece, b: &Piece, d: f64) -> bool {
    let apart = |u0: f64, u1: f64, v0: f64, v1: f64| {
        u0.min(u1) - v0.max(v1) >= d || v0.min(v1) - u0.max(u1) >= d
    };
    apart(a.p0.x, a.p1.x, b.p0.x, b.p1.x) || apart(a.p0.y, a.p1.y, b.p0.y, b.p1.y)
}

/// A piece pair closer than the threshold.
#[derive(Copy, Clone, Debug)]
struct Hit {
    pa: u32,
    pb: u32,
    lo: f64,
    hi: f64,
    approach: Approach,
}

/// Closest approach of two pieces over the overlap of their time intervals,
/// eqs. 13–17; `None` when the intervals do not meet.
///
/// With `r` the relative position at the overlap's start `l1` and `w = v_a - v_b`
/// the relative velocity, the distance `|r + w t'|` is least at
/// `t' = -(r·w)/|w|²` (eq. 15, written for vectors), `t' = 0` when `w = 0` (eq. 16),
/// clamped to `[0, l2 - l1]` (eq. 17).
fn closest(a: &Piece, b: &Piece) -> Option<(f64, f64, Approach)> {
    let lo = a.t0.max(b.t0);
    let hi = a.t1.min(b.t1);
    if lo > hi {
        return None;
    }
    let r = a.at(lo) - b.at(lo);
    let w = a.velocity() - b.velocity();
    let ww = w.norm_squared();
    let s = if ww > 0.0 {
        (-r.dot(&w) / ww).clamp(0.0, hi - lo)
    } else {
        0.0
    };
    let t = if s > 0.0 { (lo + s).min(hi) } else { lo };
    let at_a = a.at(t);
    let at_b = b.at(t);
    Some((
        lo,
        hi,
        Approach {
            t_s: t,
            distance_m: (at_a - at_b).norm(),
            at_a,
            at_b,
            sample_a: a.sample as usize,
            sample_b: b.sample as usize,
            moving_a: a.moving(),
            moving_b: b.moving(),
        },
    ))
}

fn check_threshold(threshold_m: f64) -> Result<(), CollideError> {
    if threshold_m.is_finite() && threshold_m > 0.0 {
        Ok(())
    } else {
        Err(CollideError::Threshold { threshold_m })
    }
}

fn try_pair(pieces: &[Piece], i: usize, j: usize, d: f64, hits: &mut Vec<Hit>) {
    let (i, j) = if pieces[i].track < pieces[j].track {
        (i, j)
    } else {
        (j, i)
    };
    if let Some((lo, hi, approach)) = closest(&pieces[i], &pieces[j]) {
        if approach.distance_m < d {
            hits.push(Hit {
                pa: i as u32,
                pb: j as u32,
                lo,
                hi,
                approach,
            });
        }
    }
}

/// The pair and its events from the hits of one pair of people (`a < b`), in
/// `events` (cleared first); `None` without hits.
fn assemble_pair<S: Tracks + ?Sized>(
    set: &S,
    a: usize,
    b: usize,
    hits: &mut [Hit],
    events: &mut Vec<CollisionEvent>,
) -> Option<PairCollision> {
    events.clear();
    hits.sort_by(|x, y| {
        x.lo.total_cmp(&y.lo)
            .then(x.hi.total_cmp(&y.hi))
            .then((x.pa, x.pb).cmp(&(y.pa, y.pb)))
    });
    let first = hits.first()?;
    let mut pair = PairCollision {
        a,
        b,
        id_a: set.track(a).id,
        id_b: set.track(b).id,
        closest: first.approach,
        events: 0,
    };
    for h in hits.iter() {
        if h.approach.distance_m < pair.closest.distance_m {
            pair.closest = h.approach;
        }
        match events.last_mut() {
            Some(e) if h.lo <= e.end_s => {
                e.end_s = e.end_s.max(h.hi);
                if h.approach.distance_m < e.closest.distance_m {
                    e.closest = h.approach;
                }
            }
            _ => {
                pair.events += 1;
                events.push(CollisionEvent {
                    a,
                    b,
                    id_a: pair.id_a,
                    id_b: pair.id_b,
                    start_s: h.lo,
                    end_s: h.hi,
                    closest: h.approach,
                });
            }
        }
    }
    Some(pair)
}

/// The collisions of the people marked in `who` with anyone (pairs in which at
/// least one is marked), as [`detect`] finds them: the same sweep, only the marked
/// people's pieces looked up; no clusters (every pair of identical tracks with a
/// marked person is a pair). For the avoidance loop, which changes a few people per
/// round: the pairs of the others are as they were.
pub(super) fn collisions_involving<S: Tracks + ?Sized>(
    set: &S,
    threshold_m: f64,
    who: &[bool],
    keep: usize,
) -> Result<Collisions, CollideError> {
    detect_among(set, threshold_m, Some(who), keep)
}

/// Every collision, by comparing every pair of people: for each piece of one, the
/// pieces of the other whose time intervals meet it (found by binary search).
/// The reference for [`detect`]: the same counts, the same kept pairs and events,
/// but no clusters (identical tracks are pairs like any other).
///
/// # Complexity
/// O(n² + P log P) time for n people and P pieces; O(P + [`DEFAULT_KEEP`]) memory.
///
/// # Errors
/// [`CollideError`]: a threshold that is not positive and finite, or a track set
/// breaking [`Tracks::validate`].
pub fn collisions_all_pairs<S: Tracks + ?Sized>(
    set: &S,
    threshold_m: f64,
) -> Result<Collisions, CollideError> {
    check_threshold(threshold_m)?;
    set.validate()?;
    let (pieces, starts) = pieces(set, None, None);
    let mut tally = Tally::new(DEFAULT_KEEP);
    let mut hits = Vec::new();
    let mut events = Vec::new();
    let n = set.people();
    for ka in 0..n {
        let pa = &pieces[starts[ka]..starts[ka + 1]];
        for kb in ka + 1..n {
            let pb = &pieces[starts[kb]..starts[kb + 1]];
            hits.clear();
            for (ia, a) in pa.iter().enumerate() {
                // Pieces of a track are in time order with non-decreasing ends.
                let first = pb.partition_point(|b| b.t1 < a.t0);
                for (ib, b) in pb[first..].iter().enumerate() {
                    if b.t0 > a.t1 {
                        break;
                    }
                    try_pair(
                        &pieces,
                        starts[ka] + ia,
                        starts[kb] + first + ib,
                        threshold_m,
                        &mut hits,
                    );
                }
            }
            if let Some(p) = assemble_pair(set, ka, kb, &mut hits, &mut events) {
                tally.pair(p, &events, 1);
            }
        }
    }
    Ok(tally.finish(threshold_m))
}

/// Every collision of a track set at `threshold_m` (section 4.1.1, Algorithm 2),
/// found without comparing all pairs, keeping [`DEFAULT_KEEP`] pairs, events and
/// clusters (see [`detect_keeping`]).
///
/// Time is cut into slabs of the set's frame step. In each slab every piece present
/// is boxed (its positions over the slab, grown by half the threshold) and entered
/// in the cells of a uniform grid the box covers; cells are `max(threshold, mean box
/// size)` wide, gathered into buckets by a counting sort (row by row, or hashed when
/// the cells' bounding box is sparse). Two pieces closer than the threshold at a
/// common time have overlapping boxes in the slab of that time, so they share a
/// cell. Then person by person, in Z order of their first places, each piece looks
/// up the cells its boxes cover and compares itself (eqs. 13–17) with the later
/// people's pieces there whose boxes overlap its own (once per slab: in the cell of
/// the overlap's low corner); the person's pairs are assembled, counted and dropped
/// before the next person's.
///
/// # Formula
/// Eqs. 13–17 per piece pair, as [`collisions_all_pairs`].
///
/// # Units
/// Metres and seconds.
///
/// # Complexity
/// O(P log P) time for P pieces when people are spread; a [`Cluster`] costs
/// O(k log k) for its k people; k other people crowded into one cell cost O(k²)
/// time. Memory O(n + E + keep) for n people and E grid entries
/// (O(P) when pieces are short against the cells), however many pairs collide.
///
/// # Errors
/// As [`collisions_all_pairs`].
///
/// ```
/// use crowdtouch::crowd::edit::{detect, Track, TrackSet};
/// use crowdtouch::geom::Vec2;
/// // Two people crossing: one along x, one along y, both through (1, 0) at t = 1 s.
/// let set = TrackSet {
///     tracks: vec![
///         Track::linked(1, vec![Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0)], vec![0.0, 2.0]),
///         Track::linked(2, vec![Vec2::new(1.0, -1.0), Vec2::new(1.0, 1.0)], vec![0.0, 2.0]),
///     ],
///     step_s: 2.0,
/// };
/// let c = detect(&set, 0.3).unwrap();
/// assert_eq!(c.pair_count(), 1);
/// assert!((c.events[0].closest.t_s - 1.0).abs() < 1e-12);
/// assert!(c.events[0].closest.distance_m < 1e-12);
/// ```
pub fn detect<S: Tracks + ?Sized>(set: &S, threshold_m: f64) -> Result<Collisions, CollideError> {
    detect_among(set, threshold_m, None, DEFAULT_KEEP)
}

/// [`detect`], keeping the `keep` closest pairs, `keep` earliest events and `keep`
/// largest clusters (everything is counted whatever `keep` is).
///
/// # Errors
/// As [`detect`].
pub fn detect_keeping<S: Tracks + ?Sized>(
    set: &S,
    threshold_m: f64,
    keep: usize,
) -> Result<Collisions, CollideError> {
    detect_among(set, threshold_m, None, keep)
}

/// A piece's box over a slab `[s0, s1]` (its positions then, widened in time by
/// `slack` against rounding), grown by `half` on every side.
fn slab_box(p: &Piece, s0: f64, s1: f64, slack: f64, half: f64) -> (Vec2, Vec2) {
    let ta = p.t0.max(s0 - slack);
    let tb = p.t1.min(s1 + slack);
    let (qa, qb) = if ta <= tb {
        (p.at(ta), p.at(tb))
    } else {
        (p.p0, p.p1)
    };
    (
        qa.inf(&qb) - Vec2::repeat(half),
        qa.sup(&qb) + Vec2::repeat(half),
    )
}

/// [`detect`], for pairs with at least one person marked in `who` (every pair,
/// and clusters, when `None`), keeping `keep`.
fn detect_among<S: Tracks + ?Sized>(
    set: &S,
    threshold_m: f64,
    who: Option<&[bool]>,
    keep: usize,
) -> Result<Collisions, CollideError> {
    check_threshold(threshold_m)?;
    set.validate()?;
    let d = threshold_m;
    let mut tally = Tally::new(keep);
    let n = set.people();
    // Identical tracks: only each class's first member takes part below.
    // Standing clusters: their pairs are counted, never looked up.
    let mut group = vec![NO_GROUP; n];
    let mult: Vec<u32> = match who {
        Some(_) => vec![1; n],
        None => {
            let (mult, clusters) = classes(set);
            let standing = standing_groups(set, &mult, d);
            for g in &standing {
                let m: Vec<u64> = g.iter().map(|&k| u64::from(mult[k])).collect();
                let total: u64 = m.iter().sum();
                let same: u64 = m.iter().map(|x| x * x).sum();
                let t = set.track(g[0]);
                let (start_s, end_s) = t.span_s();
                let c = Cluster {
                    members: g.clone(),
                    identical: false,
                    pair_count: (total * total - same) / 2,
                    first_id: t.id,
                    start_s,
                    end_s,
                    place: t.points[0],
                };
                tally.cluster(set, c, Some(closest_standing(set, g)));
            }
            for c in clusters {
                tally.cluster(set, c, None);
            }
            for (k, g) in standing.iter().enumerate() {
                for &m in g {
                    group[m] = k as u32;
                }
            }
            mult
        }
    };
    // People in Z order of their first place, so that people near each other look
    // up the same cells and their pieces lie together in memory; a standing
    // cluster's people one after the other.
    let order = spatial_order(set, &group);
    let mut rank_of = vec![0u32; n];
    // For each standing cluster, the rank after its last person.
    let mut group_end: Vec<usize> = Vec::new();
    for (r, &k) in order.iter().enumerate() {
        rank_of[k as usize] = r as u32;
        let g = group[k as usize];
        if g != NO_GROUP {
            if group_end.len() <= g as usize {
                group_end.resize(g as usize + 1, 0);
            }
            group_end[g as usize] = r + 1;
        }
    }
    let (pieces, starts) = pieces(set, Some(&mult), Some(&order));
    if pieces.is_empty() {
        return Ok(tally.finish(d));
    }
    let marked = |k: usize| who.is_none_or(|w| w.get(k).copied().unwrap_or(false));
    let (t_lo, t_hi) = set.span_s();
    let mut width = set.step_s();
    if ((t_hi - t_lo) / width) as usize >= MAX_SLABS {
        width = (t_hi - t_lo) / (MAX_SLABS - 1) as f64;
    }
    // Slabs cover [t_lo, t_lo + n_slabs * width], the last one closed: the last
    // sample time is in it, not alone in a slab of its own (a file sampled on whole
    // steps would otherwise enter every piece ending there twice).
    let n_slabs = (((t_hi - t_lo) / width).ceil() as usize).clamp(1, MAX_SLABS);
    let slab_of = |t: f64| (((t - t_lo) / width) as usize).min(n_slabs - 1);

    // Pieces per slab (counting sort): a piece is in every slab its interval meets.
    let mut count = vec![0usize; n_slabs + 1];
    for p in &pieces {
        for s in slab_of(p.t0)..=slab_of(p.t1) {
            count[s + 1] += 1;
        }
    }
    for s in 0..n_slabs {
        count[s + 1] += count[s];
    }
    let mut fill = count.clone();
    let mut in_slab = vec![0u32; count[n_slabs]];
    for (i, p) in pieces.iter().enumerate() {
        for s in slab_of(p.t0)..=slab_of(p.t1) {
            in_slab[fill[s]] = i as u32;
            fill[s] += 1;
        }
    }
    drop(fill);

    // Each slab's grid: cell size, entries gathered by a counting sort into
    // buckets hashed from their cell (a bucket may hold several cells: the box
    // test drops the extra pieces), oversized pieces apart.
    let half = 0.5 * d + BOX_MARGIN_M;
    let slack = 1e-6 * width + 1e-12 * (t_lo.abs() + t_hi.abs());
    let slab_t = |s: usize| {
        let s0 = t_lo + s as f64 * width;
        (s0, s0 + width)
    };
    let mut grids = vec![SlabGrid::default(); n_slabs];
    // Slab s: its pieces from grid_base[s], its buckets' starts (relative to that)
    // at bucket_base[s]..=bucket_base[s] + grids[s].buckets.
    let mut grid_base = vec![0usize; n_slabs];
    let mut bucket_base = vec![0usize; n_slabs];
    let mut over_start = vec![0usize; n_slabs + 1];
    let mut bucket_start: Vec<u32> = Vec::new();
    let mut grid_pieces: Vec<u32> = Vec::new();
    let mut over: Vec<u32> = Vec::new();
    for s in 0..n_slabs {
        let members = &in_slab[count[s]..count[s + 1]];
        over_start[s] = over.len();
        grid_base[s] = grid_pieces.len();
        bucket_base[s] = bucket_start.len();
        if members.len() < 2 {
            continue;
        }
        let (s0, s1) = slab_t(s);
        let boxed = |i: u32| slab_box(&pieces[i as usize], s0, s1, slack, half);
        let extent: f64 = members
            .iter()
            .map(|&i| {
                let b = boxed(i);
                (b.1 - b.0).max()
            })
            .sum();
        let cell = (extent / members.len() as f64).max(d);
        // The cells' bounds and number of entries, then the layout of the buckets.
        let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        let mut n_entries = 0usize;
        for &i in members {
            if let Some((x0, x1, y0, y1)) = cell_range(&boxed(i), cell) {
                (x_lo, x_hi, y_lo, y_hi) = (x_lo.min(x0), x_hi.max(x1), y_lo.min(y0), y_hi.max(y1));
                n_entries += ((x1 - x0 + 1) * (y1 - y0 + 1)) as usize;
            }
        }
        let grid = SlabGrid::new(cell, (x_lo, x_hi, y_lo, y_hi), n_entries);
        grids[s] = grid;
        // Every (bucket, piece) entry of the slab, in piece order; walked twice
        // (count, then place) rather than stored: a million people's entries
        // would be 32 MB more.
        let each_entry = |f: &mut dyn FnMut(usize, u32)| {
            for &i in members {
                if let Some((x0, x1, y0, y1)) = cell_range(&boxed(i), cell) {
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            if let Some(b) = grid.bucket(x, y) {
                                f(b, i);
                            }
                        }
                    }
                }
            }
        };
        over.extend(
            members
                .iter()
                .filter(|&&i| cell_range(&boxed(i), cell).is_none()),
        );
        let nb = grid.buckets;
        let first = bucket_start.len();
        bucket_start.resize(first + nb + 1, 0);
        let starts_of = &mut bucket_start[first..];
        each_entry(&mut |b, _| starts_of[b + 1] += 1);
        for b in 0..nb {
            starts_of[b + 1] += starts_of[b];
        }
        let base = grid_pieces.len();
        grid_pieces.resize(base + starts_of[nb] as usize, 0);
        // Members come in piece order, so each bucket's pieces ascend.
        each_entry(&mut |b, i| {
            let at = starts_of[b] as usize;
            grid_pieces[base + at] = i;
            starts_of[b] += 1;
        });
        // The fill moved every start to its bucket's end: shift back.
        for b in (1..=nb).rev() {
            starts_of[b] = starts_of[b - 1];
        }
        starts_of[0] = 0;
    }
    over_start[n_slabs] = over.len();

    // Person by person: the later (or unmarked) people's pieces near each piece.
    // A pair (q, r) is looked up from q when q is a querying person and r is not, or
    // both are and q comes first in the Z order. In a slab, a pair of pieces entered in cells is taken only
    // in the cell holding the low corner of their boxes' overlap, so once.
    let queries = |k: usize| mult[k] > 0 && marked(k);
    let mut candidates: Vec<(u32, u32, u32)> = Vec::new();
    let mut hits: Vec<Hit> = Vec::new();
    let mut events: Vec<CollisionEvent> = Vec::new();
    for (rank, &q) in order.iter().enumerate() {
        let q = q as usize;
        if !queries(q) {
            continue;
        }
        candidates.clear();
        let gq = group[q];
        let accept = |r: usize| {
            r != q
                && (gq == NO_GROUP || group[r] != gq)
                && (!queries(r) || rank_of[r] as usize > rank)
        };
        // Without marks only later people are partners: their pieces come after q's
        // (and after q's standing cluster's).
        let first_partner = if who.is_some() {
            0
        } else if gq != NO_GROUP {
            starts[group_end[gq as usize]] as u32
        } else {
            starts[rank + 1] as u32
        };
        for i in starts[rank]..starts[rank + 1] {
            let p = &pieces[i];
            for s in slab_of(p.t0)..=slab_of(p.t1) {
                let members = &in_slab[count[s]..count[s + 1]];
                if members.len() < 2 {
                    continue;
                }
                let (s0, s1) = slab_t(s);
                let bi = slab_box(p, s0, s1, slack, half);
                let grid = grids[s];
                let cell = grid.cell;
                let consider =
                    |j: u32, in_cell: Option<(i64, i64)>, out: &mut Vec<(u32, u32, u32)>| {
                        let pj = &pieces[j as usize];
                        if !accept(pj.track as usize) {
                            return;
                        }
                        let bj = slab_box(pj, s0, s1, slack, half);
                        if !overlap(&bi, &bj) {
                            return;
                        }
                        if let Some((x, y)) = in_cell {
                            let cx = (bi.0.x.max(bj.0.x) / cell).floor() as i64;
                            let cy = (bi.0.y.max(bj.0.y) / cell).floor() as i64;
                            if (cx, cy) != (x, y) {
                                return;
                            }
                        }
                        out.push((pj.track, i as u32, j));
                    };
                match cell_range(&bi, cell) {
                    None => {
                        for &j in members {
                            consider(j, None, &mut candidates);
                        }
                    }
                    Some((x0, x1, y0, y1)) => {
                        let bs = &bucket_start[bucket_base[s]..=bucket_base[s] + grid.buckets];
                        let ids = &grid_pieces[grid_base[s]..];
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                let Some(b) = grid.bucket(x, y) else {
                                    continue;
                                };
                                let bucket = &ids[bs[b] as usize..bs[b + 1] as usize];
                                let from = bucket.partition_point(|&j| j < first_partner);
                                for &j in &bucket[from..] {
                                    consider(j, Some((x, y)), &mut candidates);
                                }
                            }
                        }
                        for &j in &over[over_start[s]..over_start[s + 1]] {
                            consider(j, None, &mut candidates);
                        }
                    }
                }
            }
        }
        candidates.sort_unstable();
        candidates.dedup();
        let mut g = 0;
        while g < candidates.len() {
            let r = candidates[g].0;
            hits.clear();
            while g < candidates.len() && candidates[g].0 == r {
                let (_, i, j) = candidates[g];
                try_pair(&pieces, i as usize, j as usize, d, &mut hits);
                g += 1;
            }
            let r = r as usize;
            let (a, b) = (q.min(r), q.max(r));
            if let Some(p) = assemble_pair(set, a, b, &mut hits, &mut events) {
                tally.pair(p, &events, u64::from(mult[a]) * u64::from(mult[b]));
            }
        }
    }
    Ok(tally.finish(d))
}

#[cfg(test)]
#[path = "collide_tests.rs"]
pub(super) mod tests;
