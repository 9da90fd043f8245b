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
//! On the two UCY fixtures (`tests/fixtures/crowd/`, 25 fps, step 10) the counts of
//! pairs below 0.2/0.3/0.5/1.0 m equal the README's *continuous* counts with this
//! reading, in which single shared instants count (zara01 0/3/27/160, students001
//! 48/168/606/1840; minima 0.236 and 0.078 m). Leaving single instants out gives
//! zara01 0/3/27/159 and students001 48/166/600/1828, which disagrees; distances at
//! shared annotated frames alone give the README's *sampled* counts.

use super::tracks::{TrackError, TrackSet};
use crate::geom::Vec2;
use thiserror::Error;

/// Margin added to the bounding boxes the grid compares (metres), so rounding in
/// the box corners never drops a pair the exact test would keep.
const BOX_MARGIN_M: f64 = 1e-9;

/// The most grid cells one piece is entered into; a piece covering more is compared
/// with every piece of its slab instead.
const MAX_CELLS_PER_PIECE: i64 = 64;

/// The most time slabs a sweep uses; longer spans get wider slabs.
const MAX_SLABS: usize = 1 << 20;

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

/// Every collision of a track set at one threshold.
#[derive(Clone, Debug, PartialEq)]
pub struct Collisions {
    /// The threshold (metres): pairs closer than this collide.
    pub threshold_m: f64,
    /// The distinct colliding pairs, ordered by `(a, b)`.
    pub pairs: Vec<PairCollision>,
    /// The collisions, ordered by pair, then time.
    pub events: Vec<CollisionEvent>,
}

impl Collisions {
    /// The number of distinct colliding pairs: the primary measure.
    pub fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// The colliding pair that comes closest, if any.
    pub fn closest(&self) -> Option<&PairCollision> {
        self.pairs
            .iter()
            .min_by(|x, y| x.closest.distance_m.total_cmp(&y.closest.distance_m))
    }

    /// The closest approach of any colliding pair (metres), if any.
    pub fn min_distance_m(&self) -> Option<f64> {
        self.closest().map(|p| p.closest.distance_m)
    }

    /// Events in time order (of their closest approach).
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

/// A piece of a track: a linked segment or an isolated sample.
#[derive(Copy, Clone, Debug)]
struct Piece {
    track: u32,
    sample: u32,
    moving: bool,
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

    fn velocity(&self) -> Vec2 {
        if self.moving {
            (self.p1 - self.p0) / (self.t1 - self.t0)
        } else {
            Vec2::zeros()
        }
    }
}

/// The pieces of every track, grouped by track and in time order; `starts[k]..starts[k+1]`
/// are track `k`'s.
fn pieces(set: &TrackSet) -> (Vec<Piece>, Vec<usize>) {
    let mut out = Vec::with_capacity(set.samples());
    let mut starts = Vec::with_capacity(set.tracks.len() + 1);
    for (k, tr) in set.tracks.iter().enumerate() {
        starts.push(out.len());
        let n = tr.len();
        for j in 0..n {
            let next = j + 1 < n && tr.linked[j];
            let prev = j > 0 && tr.linked[j - 1];
            if next {
                out.push(Piece {
                    track: k as u32,
                    sample: j as u32,
                    moving: true,
                    t0: tr.times_s[j],
                    t1: tr.times_s[j + 1],
                    p0: tr.points[j],
                    p1: tr.points[j + 1],
                });
            } else if !prev {
                out.push(Piece {
                    track: k as u32,
                    sample: j as u32,
                    moving: false,
                    t0: tr.times_s[j],
                    t1: tr.times_s[j],
                    p0: tr.points[j],
                    p1: tr.points[j],
                });
            }
        }
    }
    starts.push(out.len());
    (out, starts)
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
            moving_a: a.moving,
            moving_b: b.moving,
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

/// The collisions of the people marked in `who` with anyone (pairs in which at
/// least one is marked), as [`detect`] finds them: the same sweep, candidate
/// pairs of two unmarked people dropped before their closest approach is
/// computed. For the avoidance loop, which changes a few people per round: the
/// pairs of the others are as they were.
pub(super) fn collisions_involving(
    set: &TrackSet,
    threshold_m: f64,
    who: &[bool],
) -> Result<Collisions, CollideError> {
    detect_among(set, threshold_m, Some(who))
}

/// Every collision, by comparing every pair of people: for each piece of one, the
/// pieces of the other whose time intervals meet it (found by binary search).
/// The reference for [`detect`].
///
/// # Complexity
/// O(n² + P log P) for n people and P pieces.
///
/// # Errors
/// [`CollideError`]: a threshold that is not positive and finite, or a track set
/// breaking [`TrackSet::validate`].
pub fn collisions_all_pairs(set: &TrackSet, threshold_m: f64) -> Result<Collisions, CollideError> {
    check_threshold(threshold_m)?;
    set.validate()?;
    let (pieces, starts) = pieces(set);
    let mut hits = Vec::new();
    let n = set.tracks.len();
    for ka in 0..n {
        let pa = &pieces[starts[ka]..starts[ka + 1]];
        for kb in ka + 1..n {
            let pb = &pieces[starts[kb]..starts[kb + 1]];
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
        }
    }
    Ok(assemble(set, &pieces, hits, threshold_m))
}

/// Every collision of a track set at `threshold_m` (section 4.1.1, Algorithm 2),
/// found without comparing all pairs.
///
/// Time is cut into slabs of the set's frame step. In each slab every piece present
/// is boxed (its positions over the slab, grown by half the threshold) and entered
/// in the cells of a uniform grid the box covers; cells are `threshold + mean box
/// size` wide, and cells are gathered by a counting sort on a hash of their key. Two pieces closer than the threshold at a common time have
/// overlapping boxes in the slab of that time, so they share a cell; only pieces
/// sharing a cell with overlapping boxes are compared (eqs. 13–17).
///
/// # Formula
/// Eqs. 13–17 per piece pair, as [`collisions_all_pairs`].
///
/// # Units
/// Metres and seconds.
///
/// # Complexity
/// O(P log P) for P pieces when people are spread (each slab's grid is sorted);
/// all people crowded into one cell degrade it towards comparing all pairs present.
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
pub fn detect(set: &TrackSet, threshold_m: f64) -> Result<Collisions, CollideError> {
    detect_among(set, threshold_m, None)
}

/// [`detect`], for pairs with at least one person marked in `who` (every pair
/// when `None`).
fn detect_among(
    set: &TrackSet,
    threshold_m: f64,
    who: Option<&[bool]>,
) -> Result<Collisions, CollideError> {
    check_threshold(threshold_m)?;
    set.validate()?;
    let (pieces, _) = pieces(set);
    let d = threshold_m;
    let mut hits = Vec::new();
    if pieces.is_empty() {
        return Ok(assemble(set, &pieces, hits, d));
    }
    let (t_lo, t_hi) = set.span_s();
    let mut width = set.step_s;
    if ((t_hi - t_lo) / width) as usize >= MAX_SLABS {
        width = (t_hi - t_lo) / (MAX_SLABS - 1) as f64;
    }
    let n_slabs = (((t_hi - t_lo) / width) as usize + 1).min(MAX_SLABS);
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

    let half = 0.5 * d + BOX_MARGIN_M;
    let slack = 1e-6 * width + 1e-12 * (t_lo.abs() + t_hi.abs());
    let mut boxes: Vec<(Vec2, Vec2)> = Vec::new();
    let mut entries: Vec<(u64, u32)> = Vec::new();
    let mut bucket_start: Vec<usize> = Vec::new();
    let mut bucket_fill: Vec<usize> = Vec::new();
    let mut sorted: Vec<u32> = Vec::new();
    let mut oversized: Vec<u32> = Vec::new();
    let mut candidates: Vec<u64> = Vec::new();
    for s in 0..n_slabs {
        let members = &in_slab[count[s]..count[s + 1]];
        if members.len() < 2 {
            continue;
        }
        let s0 = t_lo + s as f64 * width;
        let s1 = s0 + width;
        boxes.clear();
        let mut extent = 0.0;
        for &i in members {
            let p = &pieces[i as usize];
            // Positions over the slab (widened in time against rounding).
            let ta = p.t0.max(s0 - slack);
            let tb = p.t1.min(s1 + slack);
            let (qa, qb) = if ta <= tb {
                (p.at(ta), p.at(tb))
            } else {
                (p.p0, p.p1)
            };
            let lo = qa.inf(&qb) - Vec2::repeat(half);
            let hi = qa.sup(&qb) + Vec2::repeat(half);
            extent += (hi - lo).max();
            boxes.push((lo, hi));
        }
        let cell = (extent / members.len() as f64).max(d);
        entries.clear();
        oversized.clear();
        for (m, (lo, hi)) in boxes.iter().enumerate() {
            let x0 = (lo.x / cell).floor() as i64;
            let x1 = (hi.x / cell).floor() as i64;
            let y0 = (lo.y / cell).floor() as i64;
            let y1 = (hi.y / cell).floor() as i64;
            if (x1 - x0 + 1) * (y1 - y0 + 1) > MAX_CELLS_PER_PIECE {
                oversized.push(m as u32);
                continue;
            }
            for x in x0..=x1 {
                for y in y0..=y1 {
                    let key = ((x as u32 as u64) << 32) | (y as u32 as u64);
                    entries.push((key, m as u32));
                }
            }
        }
        // Counting sort of the entries into hashed buckets (a bucket may hold
        // several cells: the box test below drops the extra pairs).
        let buckets = (2 * entries.len()).next_power_of_two().max(2);
        let bucket_of =
            |key: u64| (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & (buckets - 1);
        bucket_start.clear();
        bucket_start.resize(buckets + 1, 0);
        for &(key, _) in &entries {
            bucket_start[bucket_of(key) + 1] += 1;
        }
        for b in 0..buckets {
            bucket_start[b + 1] += bucket_start[b];
        }
        bucket_fill.clear();
        bucket_fill.extend_from_slice(&bucket_start[..buckets]);
        sorted.clear();
        sorted.resize(entries.len(), 0);
        for &(key, m) in &entries {
            let b = bucket_of(key);
            sorted[bucket_fill[b]] = m;
            bucket_fill[b] += 1;
        }
        let overlap = |u: usize, v: usize| {
            let (a0, a1) = boxes[u];
            let (b0, b1) = boxes[v];
            a0.x <= b1.x && b0.x <= a1.x && a0.y <= b1.y && b0.y <= a1.y
        };
        let marked = |k: u32| who.is_none_or(|w| w.get(k as usize).copied().unwrap_or(false));
        let push = |u: usize, v: usize, candidates: &mut Vec<u64>| {
            let (i, j) = (members[u], members[v]);
            let (ta, tb) = (pieces[i as usize].track, pieces[j as usize].track);
            if ta != tb && (marked(ta) || marked(tb)) && overlap(u, v) {
                let (i, j) = (i.min(j), i.max(j));
                candidates.push(((i as u64) << 32) | j as u64);
            }
        };
        for b in 0..buckets {
            let bucket = &sorted[bucket_start[b]..bucket_start[b + 1]];
            for (k, &u) in bucket.iter().enumerate() {
                for &v in &bucket[k + 1..] {
                    if u != v {
                        push(u as usize, v as usize, &mut candidates);
                    }
                }
            }
        }
        for (k, &u) in oversized.iter().enumerate() {
            for v in 0..members.len() {
                // Pairs of two oversized pieces once.
                if oversized[..k].contains(&(v as u32)) || v == u as usize {
                    continue;
                }
                push(u as usize, v, &mut candidates);
            }
        }
    }
    candidates.sort_unstable();
    candidates.dedup();
    for c in candidates {
        try_pair(
            &pieces,
            (c >> 32) as usize,
            (c & 0xffff_ffff) as usize,
            d,
            &mut hits,
        );
    }
    Ok(assemble(set, &pieces, hits, d))
}

/// Groups piece hits into pairs and events.
fn assemble(set: &TrackSet, pieces: &[Piece], mut hits: Vec<Hit>, d: f64) -> Collisions {
    let key = |h: &Hit| (pieces[h.pa as usize].track, pieces[h.pb as usize].track);
    hits.sort_by(|x, y| {
        key(x)
            .cmp(&key(y))
            .then(x.lo.total_cmp(&y.lo))
            .then(x.hi.total_cmp(&y.hi))
            .then((x.pa, x.pb).cmp(&(y.pa, y.pb)))
    });
    let mut pairs: Vec<PairCollision> = Vec::new();
    let mut events: Vec<CollisionEvent> = Vec::new();
    for h in &hits {
        let (a, b) = key(h);
        let (a, b) = (a as usize, b as usize);
        let same_pair = pairs.last().is_some_and(|p| (p.a, p.b) == (a, b));
        if !same_pair {
            pairs.push(PairCollision {
                a,
                b,
                id_a: set.tracks[a].id,
                id_b: set.tracks[b].id,
                closest: h.approach,
                events: 0,
            });
        }
        let pair = pairs.last_mut().expect("pushed above");
        if h.approach.distance_m < pair.closest.distance_m {
            pair.closest = h.approach;
        }
        match events.last_mut() {
            Some(e) if same_pair && h.lo <= e.end_s => {
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
    Collisions {
        threshold_m: d,
        pairs,
        events,
    }
}

#[cfg(test)]
#[path = "collide_tests.rs"]
mod tests;
