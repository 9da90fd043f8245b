//! Crowds reported as one [`Cluster`] by collision detection (`collide.rs`,
//! crowd-motion-editing section 4.1.1): people on one identical track, and people
//! standing still at the same times within half the threshold of one of them; their
//! pairs are counted in closed form, never enumerated. Also the order detection
//! visits people in (Z order of their first place, a standing cluster together).

use super::flat::{TrackRef, Tracks};
use crate::geom::Vec2;
use std::hash::{Hash, Hasher};

/// People every two of whom collide, reported once instead of pair by pair: either
/// on one identical track (the same positions, times and links, ids aside; at
/// distance 0 whenever present), or standing still at the same times within half
/// the threshold of one of them (so within the threshold of each other throughout).
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// The members' indices in the track set, ascending. A standing cluster lists
    /// one person of each identical track among it (that track is a cluster of its
    /// own).
    pub members: Vec<usize>,
    /// Whether the members are on one identical track (else standing within the
    /// threshold).
    pub identical: bool,
    /// The colliding pairs this cluster stands for (`size (size − 1) / 2` for an
    /// identical track; for a standing cluster, the pairs of its people not on one
    /// identical track).
    pub pair_count: u64,
    /// The first member's id.
    pub first_id: u64,
    /// The track's first and last time (seconds).
    pub start_s: f64,
    /// See `start_s`.
    pub end_s: f64,
    /// Where they are at `start_s` (metres).
    pub place: Vec2,
}

impl Cluster {
    /// The number of people.
    pub fn size(&self) -> usize {
        self.members.len()
    }

    /// The colliding pairs this cluster stands for.
    pub fn pairs(&self) -> u64 {
        self.pair_count
    }
}

/// The classes of identical tracks (positions, times and links equal bit for bit,
/// ids aside): `mult[k]` is the size of the class whose first member is `k`, 0 for
/// its other members; and the classes of two or more, as clusters.
pub(super) fn classes<S: Tracks + ?Sized>(set: &S) -> (Vec<u32>, Vec<Cluster>) {
    let n = set.people();
    let mut hashed: Vec<(u64, u32)> = (0..n)
        .map(|k| {
            let t = set.track(k);
            let mut h = std::collections::hash_map::DefaultHasher::new();
            for (p, ts) in t.points.iter().zip(t.times_s) {
                (p.x.to_bits(), p.y.to_bits(), ts.to_bits()).hash(&mut h);
            }
            t.linked.hash(&mut h);
            (h.finish(), k as u32)
        })
        .collect();
    hashed.sort_unstable();
    let same = |a: usize, b: usize| {
        let (x, y) = (set.track(a), set.track(b));
        same_times(x, y)
            && x.points
                .iter()
                .zip(y.points)
                .all(|(u, v)| u.x.to_bits() == v.x.to_bits() && u.y.to_bits() == v.y.to_bits())
    };
    let mut mult = vec![0u32; n];
    let mut clusters = Vec::new();
    let mut local: Vec<Vec<usize>> = Vec::new();
    let mut i = 0;
    while i < hashed.len() {
        let mut j = i;
        while j < hashed.len() && hashed[j].0 == hashed[i].0 {
            j += 1;
        }
        if j == i + 1 {
            // A hash of its own: a class of one, no list kept (a million people
            // of distinct tracks would otherwise hold a million small vectors).
            mult[hashed[i].1 as usize] = 1;
            i = j;
            continue;
        }
        // One hash: usually one class; split by comparing with each class's first.
        local.clear();
        for &(_, k) in &hashed[i..j] {
            let k = k as usize;
            match local.iter_mut().find(|c| same(c[0], k)) {
                Some(c) => c.push(k),
                None => local.push(vec![k]),
            }
        }
        for mut g in local.drain(..) {
            g.sort_unstable();
            mult[g[0]] = g.len() as u32;
            if g.len() >= 2 {
                let t = set.track(g[0]);
                let (start_s, end_s) = t.span_s();
                let n = g.len() as u64;
                clusters.push(Cluster {
                    first_id: t.id,
                    start_s,
                    end_s,
                    place: t.points[0],
                    members: g,
                    identical: true,
                    pair_count: n * (n - 1) / 2,
                });
            }
        }
        i = j;
    }
    // In order of first member, as the classes were before.
    clusters.sort_unstable_by_key(|c| c.members[0]);
    (mult, clusters)
}

/// No standing cluster.
pub(super) const NO_GROUP: u32 = u32::MAX;

/// The fewest people a standing cluster holds; fewer are looked up pair by pair
/// (and listed) as before.
pub const MIN_STANDING_CLUSTER: usize = 32;

/// The most leaders of standing clusters a person is compared with.
const MAX_LEADERS_CHECKED: usize = 16;

/// Standing clusters among the people `mult` keeps: people standing still (every
/// position equal) at the same times with the same links, each within half the
/// threshold (less 1e-9 of it, against rounding) of the cluster's first person, its
/// leader, so every two are closer than the threshold whenever present. Greedy:
/// each person joins the first of at most [`MAX_LEADERS_CHECKED`] leaders near
/// it that fits, else leads a new one; clusters of fewer than
/// [`MIN_STANDING_CLUSTER`] are dropped. O(n log n).
pub(super) fn standing_groups<S: Tracks + ?Sized>(
    set: &S,
    mult: &[u32],
    d: f64,
) -> Vec<Vec<usize>> {
    let r = 0.5 * d * (1.0 - 1e-9);
    let stands = |t: TrackRef| {
        let p = t.points[0];
        t.points
            .iter()
            .all(|q| q.x.to_bits() == p.x.to_bits() && q.y.to_bits() == p.y.to_bits())
    };
    let mut cand: Vec<(u64, u32)> = (0..set.people())
        .map(|k| (k, set.track(k)))
        .filter(|(k, t)| mult[*k] > 0 && stands(*t))
        .map(|(k, t)| {
            let mut h = std::collections::hash_map::DefaultHasher::new();
            for ts in t.times_s {
                ts.to_bits().hash(&mut h);
            }
            t.linked.hash(&mut h);
            (h.finish(), k as u32)
        })
        .collect();
    cand.sort_unstable();
    let cell_of = |p: Vec2| ((p.x / r).floor() as i64, (p.y / r).floor() as i64);
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut leaders: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    let mut i = 0;
    while i < cand.len() {
        let mut j = i;
        while j < cand.len() && cand[j].0 == cand[i].0 {
            j += 1;
        }
        leaders.clear();
        for &(_, k) in &cand[i..j] {
            let k = k as usize;
            let p = set.track(k).points[0];
            let (cx, cy) = cell_of(p);
            let mut joined = None;
            let mut checked = 0;
            'search: for dx in -1..=1 {
                for dy in -1..=1 {
                    for &g in leaders.get(&(cx + dx, cy + dy)).into_iter().flatten() {
                        checked += 1;
                        if checked > MAX_LEADERS_CHECKED {
                            break 'search;
                        }
                        let l = groups[g][0];
                        if (set.track(l).points[0] - p).norm() < r
                            && same_times(set.track(l), set.track(k))
                        {
                            joined = Some(g);
                            break 'search;
                        }
                    }
                }
            }
            match joined {
                Some(g) => groups[g].push(k),
                None => {
                    leaders.entry((cx, cy)).or_default().push(groups.len());
                    groups.push(vec![k]);
                }
            }
        }
        i = j;
    }
    groups.retain(|g| g.len() >= MIN_STANDING_CLUSTER);
    for g in &mut groups {
        g.sort_unstable();
    }
    groups
}

/// The closest two of a standing cluster `(a, b, distance)` with `a < b`, least
/// `(distance, a, b)`: a sweep over the places sorted by x, a pair skipped only
/// when its x distance alone exceeds the best.
pub(super) fn closest_standing<S: Tracks + ?Sized>(
    set: &S,
    members: &[usize],
) -> (usize, usize, f64) {
    let mut pts: Vec<(f64, usize)> = members
        .iter()
        .map(|&k| (set.track(k).points[0].x, k))
        .collect();
    pts.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut best = (f64::INFINITY, usize::MAX, usize::MAX);
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            if pts[j].0 - pts[i].0 > best.0 {
                break;
            }
            let (a, b) = (pts[i].1.min(pts[j].1), pts[i].1.max(pts[j].1));
            // As the pair's closest approach computes it: first minus second.
            let dist = (set.track(a).points[0] - set.track(b).points[0]).norm();
            let better = dist
                .total_cmp(&best.0)
                .then((a, b).cmp(&(best.1, best.2)))
                .is_lt();
            if better {
                best = (dist, a, b);
            }
        }
    }
    (best.1, best.2, best.0)
}

/// The people in Z (Morton) order of their first place, quantised to 2^16 steps
/// each way across the box of all first places; a standing cluster's people
/// together at its leader's place (ties by cluster, then index).
pub(super) fn spatial_order<S: Tracks + ?Sized>(set: &S, group: &[u32]) -> Vec<u32> {
    let mut lo = Vec2::repeat(f64::INFINITY);
    let mut hi = Vec2::repeat(f64::NEG_INFINITY);
    for k in 0..set.people() {
        let t = set.track(k);
        lo = lo.inf(&t.points[0]);
        hi = hi.sup(&t.points[0]);
    }
    let span = (hi - lo).max().max(f64::MIN_POSITIVE);
    let spread = |v: u32| {
        let mut v = v as u64 & 0xffff;
        v = (v | (v << 8)) & 0x00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    // Each standing cluster's leader (its first person in index order).
    let mut leader: std::collections::HashMap<u32, usize> = Default::default();
    for (k, &g) in group.iter().enumerate() {
        if g != NO_GROUP {
            leader.entry(g).or_insert(k);
        }
    }
    let mut keyed: Vec<(u64, u32, u32)> = (0..set.people())
        .map(|k| {
            let g = group[k];
            let at = if g == NO_GROUP {
                set.track(k).points[0]
            } else {
                set.track(leader[&g]).points[0]
            };
            let q = (at - lo) / span * 65535.0;
            let (x, y) = (
                q.x.clamp(0.0, 65535.0) as u32,
                q.y.clamp(0.0, 65535.0) as u32,
            );
            (spread(x) | (spread(y) << 1), g, k as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, _, k)| k).collect()
}

/// Whether two tracks have the same times and links, bit for bit.
fn same_times(x: TrackRef, y: TrackRef) -> bool {
    x.linked == y.linked
        && x.times_s.len() == y.times_s.len()
        && x.times_s
            .iter()
            .zip(y.times_s)
            .all(|(u, v)| u.to_bits() == v.to_bits())
}
