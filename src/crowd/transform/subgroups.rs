//! Subgroups of a formation transform by affinity propagation (formation-transform
//! section 3.4; Frey & Dueck 2007, Science 315): agents whose mutual distances change
//! alike between the source and the target formation move as one subgroup.
//!
//! The messages run on a list of candidate pairs per agent (rows of a compressed
//! sparse layout): every pair for a crowd of at most [`ApParams::dense_up_to`] agents
//! (dense affinity propagation), otherwise the pairs within `ring` hops of each other
//! in the Delaunay triangulation of the sources (sparse affinity propagation: a pair
//! left out has similarity `−∞`). Dense and sparse run the same code, so a ring that
//! covers the whole crowd gives the dense answer bit for bit.
//!
//! Two similarities ([`Similarity`]): the paper's eq. 20 as written (`Paper`), and
//! the project's `Local` one, which adds a spatial term so that neighbours are
//! preferred over far agents whose distance happens not to change, always runs on
//! the Delaunay ring, and merges subgroups smaller than [`min_group_size`] into a
//! neighbouring one (`subgroup_merge.rs`). Eq. 20 alone has no notion of distance:
//! at 300 agents its subgroups are spread over the whole formation.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate; the message
// loops index several per-pair arrays by the same compressed-row range.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

use super::subgroup_merge::{merge_small, min_group_size};
use crate::crowd::assign::Cancel;
use crate::geom::Vec2;
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// The preference `s(k, k)` of affinity propagation.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Preference {
    /// The median of the similarities (Frey & Dueck's default) for
    /// [`Similarity::Paper`]; the smallest candidate similarity (Frey & Dueck's
    /// choice for few clusters) for [`Similarity::Local`].
    Median,
    /// This value.
    Value(f64),
}

/// The similarity affinity propagation clusters by.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Similarity {
    /// Eq. 20 as written, `−Δdis(s_i, s_j)`: every pair up to
    /// [`ApParams::dense_up_to`] agents, the Delaunay ring above; no merge. It
    /// groups a rigid far pair as readily as two neighbours.
    Paper,
    /// `−Δdis(s_i, s_j) − μ·w(s_i, s_j)²` ([`SPATIAL_WEIGHT`] `μ`) on the Delaunay
    /// ring at every crowd size, then subgroups smaller than [`min_group_size`]
    /// merged into the neighbouring subgroup whose shared Delaunay edges change
    /// least (eq. 20 on those edges).
    Local,
}

/// `μ` of [`Similarity::Local`], dimensionless: a metre between two agents costs
/// as much similarity as a metre of change of their distance (eq. 20's Manhattan
/// weights). With it a far pair (`w` the formation's size) is never more similar
/// than two neighbours (`w` about one spacing), whatever the distance changes.
pub const SPATIAL_WEIGHT: f64 = 1.0;

/// Affinity propagation's parameters.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ApParams {
    /// Damping `λ` of the messages, in `[0.5, 1)`.
    pub damping: f64,
    /// Most iterations.
    pub max_iterations: u32,
    /// Iterations with unchanged exemplars that count as converged.
    pub convergence_iterations: u32,
    /// `s(k, k)`.
    pub preference: Preference,
    /// Candidate pairs of a large crowd: the Delaunay `ring`-ring of each source point.
    pub ring: u32,
    /// Crowds up to this size use every pair (dense; [`Similarity::Paper`] only).
    pub dense_up_to: usize,
    /// Which similarity.
    pub similarity: Similarity,
}

impl Default for ApParams {
    /// The local similarity, damping 0.7, at most 500 iterations (on the three
    /// shipped pairs over ten seeds the default converged within 406 at 2,000
    /// agents, and 5 of 30 crowds did not within 200), converged after 15
    /// with the same exemplars, the default preference ([`Preference::Median`]), the
    /// 2-ring of the triangulation (above 300 agents with the paper's similarity).
    /// Bench `transform_subgroups` (2,000 agents, a jittered grid turning into a
    /// ring, release build, with a report running on the other core): local
    /// 72 ms, 12 subgroups, converged in 203 iterations; paper 162 ms, 377
    /// subgroups, not converged in 500; `transform_plan` (pairing and subgroups)
    /// 130 ms.
    fn default() -> ApParams {
        ApParams {
            damping: 0.7,
            max_iterations: 500,
            convergence_iterations: 15,
            preference: Preference::Median,
            ring: 2,
            dense_up_to: 300,
            similarity: Similarity::Local,
        }
    }
}

/// A partition of the agents into subgroups.
#[derive(Clone, Debug, PartialEq)]
pub struct Subgroups {
    /// `group_of[i]`: agent `i`'s subgroup, `0..count()`.
    pub group_of: Vec<u32>,
    /// The exemplar (agent index) of each subgroup.
    pub exemplars: Vec<u32>,
    /// Iterations run.
    pub iterations: u32,
    /// Whether the exemplars settled before `max_iterations`.
    pub converged: bool,
}

impl Subgroups {
    /// Every agent in one subgroup (subgroups off); no subgroup for no agent.
    pub fn single(n: usize) -> Subgroups {
        Subgroups {
            group_of: vec![0; n],
            exemplars: if n > 0 { vec![0] } else { Vec::new() },
            iterations: 0,
            converged: true,
        }
    }

    /// Number of subgroups.
    pub fn count(&self) -> usize {
        self.exemplars.len()
    }
}

/// The similarity of eq. 20 between two agents: `−Δdis(s_i, s_j)`.
///
/// # Formula
/// formation-transform eq. 20 with Manhattan edge weights `w`:
/// `s(i, j) = −|w(s_i, s_j) − w(Ψ(s_i), Ψ(s_j))|²`, `w(p, q) = |p_x − q_x| + |p_y − q_y|`.
///
/// # Units
/// Positions in metres, similarity in −m².
#[inline]
fn delta_dis(s: &[Vec2], t: &[Vec2], i: usize, j: usize) -> f64 {
    let w = |p: Vec2, q: Vec2| (p.x - q.x).abs() + (p.y - q.y).abs();
    let d = w(s[i], s[j]) - w(t[i], t[j]);
    -(d * d)
}

/// A deterministic value in `[−1, 1)` for the pair `(i, j)` (SplitMix64 finaliser).
#[inline]
fn pair_noise(i: usize, j: usize) -> f64 {
    let mut z = ((i as u64) << 32 ^ j as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// The similarity of two distinct agents: [`delta_dis`] (eq. 20), minus
/// `μ·w(s_i, s_j)²` when `local` ([`Similarity::Local`]). −m².
#[inline]
fn base_similarity(s: &[Vec2], t: &[Vec2], local: bool, i: usize, j: usize) -> f64 {
    let d = delta_dis(s, t, i, j);
    if local {
        let w = (s[i].x - s[j].x).abs() + (s[i].y - s[j].y).abs();
        d - SPATIAL_WEIGHT * w * w
    } else {
        d
    }
}

/// The similarity the messages use: [`base_similarity`] (the preference on the
/// diagonal) plus a perturbation at rounding level that breaks the ties of
/// symmetric crowds (as scikit-learn's `AffinityPropagation` does with its random
/// state; here a hash of the pair, so every run and both layouts see the same
/// values).
#[inline]
fn similarity(s: &[Vec2], t: &[Vec2], local: bool, pref: f64, i: usize, j: usize) -> f64 {
    let v = if i == j {
        pref
    } else {
        base_similarity(s, t, local, i, j)
    };
    v + (f64::EPSILON * v.abs() + 100.0 * f64::MIN_POSITIVE) * pair_noise(i, j)
}

/// Candidate pairs, row by row (CSR): row `i` lists `col[start[i]..start[i + 1]]`,
/// ascending, always including `i` itself at `diag[i]`.
struct Pairs {
    start: Vec<usize>,
    col: Vec<u32>,
    diag: Vec<usize>,
}

impl Pairs {
    /// Every pair of `n` points.
    fn dense(n: usize) -> Pairs {
        Pairs {
            start: (0..=n).map(|i| i * n).collect(),
            col: (0..n * n).map(|e| (e % n) as u32).collect(),
            diag: (0..n).map(|i| i * n + i).collect(),
        }
    }

    /// The pairs within `ring` hops in the Delaunay triangulation of `points` (points
    /// at one position share a vertex, so they are each other's candidates).
    /// `points` must be finite.
    fn delaunay_rings(points: &[Vec2], ring: u32) -> Pairs {
        let n = points.len();
        let mut dt: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
        let handles: Vec<_> = points
            .iter()
            .map(|p| dt.insert(Point2::new(p.x, p.y)).ok())
            .collect();
        let nv = dt.num_vertices();
        // Agents at each vertex.
        let mut at: Vec<Vec<u32>> = vec![Vec::new(); nv];
        for (i, h) in handles.iter().enumerate() {
            if let Some(h) = h {
                at[h.index()].push(i as u32);
            }
        }
        let vh: Vec<_> = dt.fixed_vertices().collect();
        let mut seen = vec![u32::MAX; nv];
        let (mut frontier, mut next, mut reached) = (Vec::new(), Vec::new(), Vec::new());
        let mut start = Vec::with_capacity(n + 1);
        let mut col = Vec::new();
        let mut diag = Vec::with_capacity(n);
        start.push(0);
        for (i, h) in handles.iter().enumerate() {
            reached.clear();
            match h {
                Some(h) => {
                    let v0 = h.index();
                    seen[v0] = i as u32;
                    frontier.clear();
                    frontier.push(v0);
                    reached.extend_from_slice(&at[v0]);
                    for _ in 0..ring {
                        next.clear();
                        for &v in &frontier {
                            for e in dt.vertex(vh[v]).out_edges() {
                                let w = e.to().fix().index();
                                if seen[w] != i as u32 {
                                    seen[w] = i as u32;
                                    next.push(w);
                                    reached.extend_from_slice(&at[w]);
                                }
                            }
                        }
                        std::mem::swap(&mut frontier, &mut next);
                    }
                }
                None => reached.push(i as u32),
            }
            reached.sort_unstable();
            let base = col.len();
            let d = reached.binary_search(&(i as u32)).unwrap_or(0);
            diag.push(base + d);
            col.extend_from_slice(&reached);
            start.push(col.len());
        }
        Pairs { start, col, diag }
    }
}

/// Median of `v` (the mean of the two middle values for an even count); NaN when
/// empty. Reorders `v`.
fn median(v: &mut [f64]) -> f64 {
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    let (_, &mut hi, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        let lo = v[..n / 2].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lo + hi)
    }
}

/// Clusters the source points by affinity propagation on the similarity
/// `−Δdis(s_i, s_j)` of eq. 20 (Manhattan edge weights), `paired_targets[i]` being
/// agent `i`'s target `Ψ(s_i)`. `None` when `cancel` said so.
///
/// # Algorithm
/// Frey & Dueck (2007), with damping `λ` on both messages:
///
/// ```text
///   r(i,k) ← s(i,k) − max_{k'≠k} (a(i,k') + s(i,k'))
///   a(i,k) ← min(0, r(k,k) + Σ_{i'∉{i,k}} max(0, r(i',k)))      (i ≠ k)
///   a(k,k) ← Σ_{i'≠k} max(0, r(i',k))
/// ```
///
/// over the candidate pairs (module documentation); the exemplars are the `k` with
/// `a(k,k) + r(k,k) > 0`, converged when they stay the same for
/// `convergence_iterations` iterations. As scikit-learn does, each agent then joins
/// its most similar exemplar, each subgroup's exemplar becomes the member most
/// similar to the others, and the agents join their most similar exemplar again;
/// except that an agent whose candidate exemplars are all less similar than the
/// preference joins the subgroup of its most similar candidate instead (`assign`).
/// Exemplars are listed by agent index.
///
/// # Degenerate input
/// No agent: no subgroup. An agent whose source or target is not finite is a
/// subgroup of its own, the others are clustered without it. Equal similarities
/// everywhere (a rigid motion): one subgroup, or one per agent if the preference is
/// above them (scikit-learn makes the median case one per agent; a crowd that moves
/// rigidly is one group).
/// No exemplar at the end: one subgroup, `converged == false`.
///
/// # Complexity
/// `O(iterations · pairs)`; pairs `n²` dense, about `(3 ring² + 3 ring + 1) · n`
/// sparse, plus one triangulation. Allocates.
pub fn subgroups(
    sources: &[Vec2],
    paired_targets: &[Vec2],
    p: &ApParams,
    cancel: Cancel<'_>,
) -> Option<Subgroups> {
    let n = sources.len();
    let fin = |q: &Vec2| q.x.is_finite() && q.y.is_finite();
    let ok: Vec<usize> = (0..n)
        .filter(|&i| fin(&sources[i]) && paired_targets.get(i).is_some_and(fin))
        .collect();
    if ok.len() == n {
        return cluster(sources, paired_targets, p, cancel);
    }
    // The finite agents clustered alone, then one subgroup each for the others.
    let s: Vec<Vec2> = ok.iter().map(|&i| sources[i]).collect();
    let t: Vec<Vec2> = ok.iter().map(|&i| paired_targets[i]).collect();
    let inner = cluster(&s, &t, p, cancel)?;
    let mut group_of = vec![0u32; n];
    let mut exemplars: Vec<u32> = inner
        .exemplars
        .iter()
        .map(|&e| ok[e as usize] as u32)
        .collect();
    for (&i, &g) in ok.iter().zip(&inner.group_of) {
        group_of[i] = g;
    }
    let mut lone = vec![true; n];
    for &i in &ok {
        lone[i] = false;
    }
    for i in (0..n).filter(|&i| lone[i]) {
        group_of[i] = exemplars.len() as u32;
        exemplars.push(i as u32);
    }
    Some(Subgroups {
        group_of,
        exemplars,
        iterations: inner.iterations,
        converged: inner.converged,
    })
}

/// [`subgroups`] on finite positions.
fn cluster(s: &[Vec2], t: &[Vec2], p: &ApParams, cancel: Cancel<'_>) -> Option<Subgroups> {
    let n = s.len();
    if n <= 1 {
        return Some(Subgroups::single(n));
    }
    let local = p.similarity == Similarity::Local;
    let pairs = if n <= p.dense_up_to && !local {
        Pairs::dense(n)
    } else {
        Pairs::delaunay_rings(s, p.ring.max(1))
    };
    if cancel.cancelled() {
        return None;
    }
    let row = |i: usize| pairs.start[i]..pairs.start[i + 1];
    // Off-diagonal similarities (without the perturbation): preference and the
    // all-equal test (on eq. 20 alone: a rigid motion is one subgroup).
    let mut off = Vec::with_capacity(pairs.col.len().saturating_sub(n));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..n {
        for e in row(i) {
            let k = pairs.col[e] as usize;
            if k != i {
                let d = delta_dis(s, t, i, k);
                (lo, hi) = (lo.min(d), hi.max(d));
                off.push(base_similarity(s, t, local, i, k));
            }
        }
    }
    let top = off.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let pref = match p.preference {
        Preference::Value(v) if v.is_finite() => v,
        // The smallest candidate similarity (Frey & Dueck's choice for few
        // clusters): the median of a ring's similarities makes an exemplar of about
        // every fifth agent, and the many small subgroups keep the messages from
        // settling at 1,000 agents and more.
        _ if local => off.iter().copied().fold(f64::INFINITY, f64::min),
        _ => median(&mut off),
    };
    // Similarities equal up to rounding: distance changes below 1e-9 of the extent.
    let extent = s
        .iter()
        .chain(t)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q.x).min(q.y), b.max(q.x).max(q.y))
        });
    let flat = (1e-9 * (extent.1 - extent.0)).powi(2);
    if off.is_empty() || hi - lo <= flat {
        // Nothing tells the agents apart (a rigid motion keeps every distance): one
        // subgroup, unless the preference is above every similarity.
        if off.is_empty() || !(pref > top + flat) {
            return Some(Subgroups::single(n));
        }
        return Some(Subgroups {
            group_of: (0..n as u32).collect(),
            exemplars: (0..n as u32).collect(),
            iterations: 0,
            converged: true,
        });
    }
    drop(off);
    let damping = if p.damping.is_nan() {
        0.7
    } else {
        p.damping.clamp(0.5, 0.99)
    };
    let sim: Vec<f64> = (0..n)
        .flat_map(|i| row(i).map(move |e| (i, e)))
        .map(|(i, e)| similarity(s, t, local, pref, i, pairs.col[e] as usize))
        .collect();
    let m = sim.len();
    let (mut r, mut a) = (vec![0.0f64; m], vec![0.0f64; m]);
    let mut colsum = vec![0.0f64; n];
    let mut rdiag = vec![0.0f64; n];
    let (mut ex, mut ex_prev) = (vec![false; n], vec![false; n]);
    let (mut stable, mut iterations, mut converged) = (0u32, 0u32, false);
    let conv = p.convergence_iterations.max(1);
    for it in 0..p.max_iterations {
        if cancel.cancelled() {
            return None;
        }
        iterations = it + 1;
        // Responsibilities, row by row.
        colsum.fill(0.0);
        for i in 0..n {
            let (mut m1, mut m2, mut arg) = (f64::NEG_INFINITY, f64::NEG_INFINITY, usize::MAX);
            for e in row(i) {
                let v = a[e] + sim[e];
                if v > m1 {
                    m2 = m1;
                    m1 = v;
                    arg = e;
                } else if v > m2 {
                    m2 = v;
                }
            }
            for e in row(i) {
                let rn = sim[e] - if e == arg { m2 } else { m1 };
                r[e] = damping * r[e] + (1.0 - damping) * rn;
                let k = pairs.col[e] as usize;
                if k != i {
                    colsum[k] += r[e].max(0.0);
                }
            }
            rdiag[i] = r[pairs.diag[i]];
        }
        // Availabilities.
        for i in 0..n {
            for e in row(i) {
                let k = pairs.col[e] as usize;
                let an = if k == i {
                    colsum[k]
                } else {
                    (rdiag[k] + colsum[k] - r[e].max(0.0)).min(0.0)
                };
                a[e] = damping * a[e] + (1.0 - damping) * an;
            }
        }
        let mut count = 0usize;
        for (k, x) in ex.iter_mut().enumerate() {
            let d = pairs.diag[k];
            *x = a[d] + r[d] > 0.0;
            count += usize::from(*x);
        }
        if ex == ex_prev {
            stable += 1;
        } else {
            stable = 1;
            ex_prev.copy_from_slice(&ex);
        }
        if count > 0 && stable >= conv {
            converged = true;
            break;
        }
    }
    let mut exemplars: Vec<u32> = (0..n as u32).filter(|&k| ex_prev[k as usize]).collect();
    if exemplars.is_empty() {
        return Some(Subgroups {
            iterations,
            converged: false,
            ..Subgroups::single(n)
        });
    }
    let sij = |i: usize, k: usize| similarity(s, t, local, pref, i, k);
    // Join the most similar exemplar; refine each subgroup's exemplar; join again.
    let mut is_ex = vec![u32::MAX; n];
    let mut group_of = vec![0u32; n];
    for pass in 0..2 {
        is_ex.fill(u32::MAX);
        for (g, &k) in exemplars.iter().enumerate() {
            is_ex[k as usize] = g as u32;
        }
        assign(&pairs, &sim, pref, &is_ex, &mut group_of);
        if pass == 1 {
            break;
        }
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); exemplars.len()];
        for (i, &g) in group_of.iter().enumerate() {
            members[g as usize].push(i);
        }
        for (e, ms) in exemplars.iter_mut().zip(&members) {
            let (mut best, mut arg) = (f64::NEG_INFINITY, *e as usize);
            for &j in ms {
                let tot: f64 = ms.iter().map(|&i| sij(i, j)).sum();
                if tot > best {
                    best = tot;
                    arg = j;
                }
            }
            *e = arg as u32;
        }
        exemplars.sort_unstable();
        exemplars.dedup();
    }
    // Subgroups left without a member (an exemplar that joined another) go away.
    let mut used = vec![false; exemplars.len()];
    for &g in &group_of {
        used[g as usize] = true;
    }
    let mut renum = vec![0u32; exemplars.len()];
    let mut kept = Vec::with_capacity(exemplars.len());
    for (g, &k) in exemplars.iter().enumerate() {
        if used[g] {
            renum[g] = kept.len() as u32;
            kept.push(k);
        }
    }
    for g in &mut group_of {
        *g = renum[*g as usize];
    }
    if local {
        // The Delaunay edges (i < k) with eq. 20's similarity, for the merge.
        let ring = Pairs::delaunay_rings(s, 1);
        let mut edges: Vec<(u32, u32, f64)> = Vec::new();
        for i in 0..n {
            for e in ring.start[i]..ring.start[i + 1] {
                let k = ring.col[e] as usize;
                if k > i {
                    edges.push((i as u32, k as u32, delta_dis(s, t, i, k)));
                }
            }
        }
        merge_small(&edges, &mut group_of, &mut kept, min_group_size(n));
    }
    Some(Subgroups {
        group_of,
        exemplars: kept,
        iterations,
        converged,
    })
}

/// Every agent joins the exemplar among its candidates with the largest similarity
/// if that is at least the preference `pref` (an exemplar joins itself); an agent
/// for which none is (it would rather be an exemplar than join one — in a sparse
/// crowd, the exemplar of its own subgroup may be out of its candidates' reach)
/// joins, repeatedly, the subgroup of its most similar candidate that has one with
/// similarity at least `pref`; the agents still left join their most similar
/// exemplar among their candidates, or the subgroup of their most similar candidate
/// (the candidate graph is connected, so every agent ends in a subgroup; one that
/// could not would join the first). `is_ex[k]`: the subgroup of exemplar `k`,
/// `u32::MAX` for the others.
fn assign(pairs: &Pairs, sim: &[f64], pref: f64, is_ex: &[u32], group_of: &mut [u32]) {
    const NONE: u32 = u32::MAX;
    let n = group_of.len();
    // The most similar candidate `k` of `i` with `ok(k)`, and its similarity.
    let best = |i: usize, ok: &dyn Fn(usize) -> bool| {
        let (mut b, mut arg) = (f64::NEG_INFINITY, usize::MAX);
        for e in pairs.start[i]..pairs.start[i + 1] {
            let k = pairs.col[e] as usize;
            if k != i && ok(k) && sim[e] > b {
                b = sim[e];
                arg = k;
            }
        }
        (b, arg)
    };
    for i in 0..n {
        group_of[i] = is_ex[i];
        if is_ex[i] == NONE {
            let (b, k) = best(i, &|k| is_ex[k] != NONE);
            if k != usize::MAX && b >= pref {
                group_of[i] = is_ex[k];
            }
        }
    }
    for strict in [true, false] {
        loop {
            let (mut changed, mut left) = (false, false);
            for i in 0..n {
                if group_of[i] != NONE {
                    continue;
                }
                let g = &*group_of;
                let (b, k) = best(i, &|k| g[k] != NONE);
                if k != usize::MAX && (!strict || b >= pref) {
                    group_of[i] = group_of[k];
                    changed = true;
                } else {
                    left = true;
                }
            }
            if !left {
                return;
            }
            if !changed {
                break;
            }
        }
        if strict {
            for i in 0..n {
                if group_of[i] == NONE {
                    let (_, k) = best(i, &|k| is_ex[k] != NONE);
                    if k != usize::MAX {
                        group_of[i] = is_ex[k];
                    }
                }
            }
        }
    }
    for g in group_of.iter_mut().filter(|g| **g == NONE) {
        *g = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn points(rng: &mut SplitMix64, n: usize, side: f64) -> Vec<Vec2> {
        (0..n)
            .map(|_| Vec2::new(side * rng.unit(), side * rng.unit()))
            .collect()
    }

    /// Targets: the sources turned, the right half stretched, jittered (subgroups
    /// with distinct distance changes).
    fn deform(rng: &mut SplitMix64, s: &[Vec2]) -> Vec<Vec2> {
        s.iter()
            .map(|p| {
                let q = Vec2::new(0.8 * p.x - 0.6 * p.y, 0.6 * p.x + 0.8 * p.y);
                let stretch = if p.x > 0.5 { 1.8 } else { 1.0 };
                Vec2::new(stretch * q.x + 0.05 * rng.unit(), q.y + 0.05 * rng.unit())
            })
            .collect()
    }

    /// Affinity propagation on full matrices, written from the formulas of
    /// [`subgroups`] (the reference of the CSR code): the exemplar flags at the end,
    /// and the iterations run.
    fn reference(s: &[Vec2], t: &[Vec2], p: &ApParams) -> (Vec<bool>, u32) {
        let n = s.len();
        let mut off = Vec::new();
        for i in 0..n {
            for k in 0..n {
                if i != k {
                    off.push(delta_dis(s, t, i, k));
                }
            }
        }
        let pref = median(&mut off);
        let sm: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|k| similarity(s, t, false, pref, i, k))
                    .collect()
            })
            .collect();
        let (mut r, mut a) = (vec![vec![0.0; n]; n], vec![vec![0.0; n]; n]);
        let l = p.damping;
        let (mut prev, mut stable) = (vec![false; n], 0);
        for it in 0..p.max_iterations {
            for i in 0..n {
                for k in 0..n {
                    let m = (0..n)
                        .filter(|&kk| kk != k)
                        .map(|kk| a[i][kk] + sm[i][kk])
                        .fold(f64::NEG_INFINITY, f64::max);
                    r[i][k] = l * r[i][k] + (1.0 - l) * (sm[i][k] - m);
                }
            }
            for i in 0..n {
                for k in 0..n {
                    let sum: f64 = (0..n)
                        .filter(|&ii| ii != i && ii != k)
                        .map(|ii| r[ii][k].max(0.0))
                        .sum();
                    let an = if i == k {
                        sum
                    } else {
                        (r[k][k] + sum).min(0.0)
                    };
                    a[i][k] = l * a[i][k] + (1.0 - l) * an;
                }
            }
            let ex: Vec<bool> = (0..n).map(|k| a[k][k] + r[k][k] > 0.0).collect();
            if ex == prev {
                stable += 1;
            } else {
                stable = 1;
                prev = ex;
            }
            if prev.iter().any(|&e| e) && stable >= p.convergence_iterations {
                return (prev, it + 1);
            }
        }
        (prev, p.max_iterations)
    }

    #[test]
    fn defaults_and_single() {
        let p = ApParams::default();
        assert!(p.damping >= 0.5 && p.damping < 1.0);
        assert_eq!((p.max_iterations, p.convergence_iterations), (500, 15));
        assert_eq!(p.preference, Preference::Median);
        let g = Subgroups::single(4);
        assert_eq!(
            (g.group_of, g.exemplars, g.converged),
            (vec![0; 4], vec![0], true)
        );
        assert_eq!(Subgroups::single(0).count(), 0);
    }

    /// The message passing agrees with the matrix formulas (same exemplars before
    /// the refinement; same iteration count), on crowds of 30 and 60.
    #[test]
    fn dense_matches_the_matrix_formulas() {
        let mut rng = SplitMix64::new(0xa9);
        for n in [30usize, 60] {
            let s = points(&mut rng, n, 1.0);
            let t = deform(&mut rng, &s);
            let p = ApParams {
                similarity: Similarity::Paper,
                ..ApParams::default()
            };
            let (ex, iters) = reference(&s, &t, &p);
            let g = subgroups(&s, &t, &p, Cancel::NEVER).unwrap();
            assert_eq!(g.iterations, iters, "n={n}");
            assert!(g.converged);
            // Each refined exemplar lies in the subgroup of a message-passing exemplar,
            // and there are as many.
            assert_eq!(g.count(), ex.iter().filter(|&&e| e).count(), "n={n}");
            for (i, &gi) in g.group_of.iter().enumerate() {
                assert_eq!(
                    g.group_of[g.exemplars[gi as usize] as usize], gi,
                    "agent {i}"
                );
            }
        }
    }

    /// A ring covering the whole crowd gives the dense answer exactly; the default
    /// smaller ring is checked on two crowds in `subgroups_follow_the_distance_changes`.
    #[test]
    fn sparse_matches_dense_when_the_ring_covers_the_crowd() {
        let mut rng = SplitMix64::new(0x5ba);
        for n in [50usize, 150] {
            let s = points(&mut rng, n, 1.0);
            let t = deform(&mut rng, &s);
            let dense = ApParams {
                dense_up_to: n,
                similarity: Similarity::Paper,
                ..ApParams::default()
            };
            let sparse = ApParams {
                dense_up_to: 0,
                ring: n as u32,
                ..dense
            };
            let a = subgroups(&s, &t, &dense, Cancel::NEVER).unwrap();
            let b = subgroups(&s, &t, &sparse, Cancel::NEVER).unwrap();
            assert_eq!(a, b, "n={n}");
            assert!(
                a.count() > 1 && a.count() < n / 2,
                "n={n}: {} subgroups",
                a.count()
            );
        }
    }

    /// Two crowds: one translated, the other spread to twice its size and moved
    /// 10 m away (every distance between the crowds changes by metres, within
    /// them by at most 2 m). No subgroup takes agents of both.
    #[test]
    fn subgroups_follow_the_distance_changes() {
        let mut rng = SplitMix64::new(0x2c);
        let n = 80;
        let mut s = points(&mut rng, n, 1.0);
        for p in &mut s[n / 2..] {
            p.x += 3.0;
        }
        let t: Vec<Vec2> = s
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if i < n / 2 {
                    *p + Vec2::new(0.0, 2.0)
                } else {
                    Vec2::new(13.0 + 2.0 * (p.x - 3.0), 2.0 * p.y)
                }
            })
            .collect();
        for (dense_up_to, similarity) in [
            (n, Similarity::Paper),
            (0, Similarity::Paper),
            (n, Similarity::Local),
        ] {
            let p = ApParams {
                dense_up_to,
                similarity,
                ..ApParams::default()
            };
            let g = subgroups(&s, &t, &p, Cancel::NEVER).unwrap();
            for k in 0..g.count() {
                let sides: Vec<bool> = (0..n)
                    .filter(|&i| g.group_of[i] as usize == k)
                    .map(|i| i < n / 2)
                    .collect();
                assert!(
                    sides.iter().all(|&x| x == sides[0]),
                    "dense_up_to {dense_up_to}: subgroup {k} spans both crowds: {g:?}"
                );
            }
        }
    }

    #[test]
    fn degenerate_input() {
        let p = ApParams::default();
        let none = subgroups(&[], &[], &p, Cancel::NEVER).unwrap();
        assert_eq!(none.count(), 0);
        let one = subgroups(
            &[Vec2::new(1.0, 1.0)],
            &[Vec2::new(2.0, 2.0)],
            &p,
            Cancel::NEVER,
        );
        assert_eq!(one.unwrap().group_of, [0]);
        // A rigid translation: every similarity is 0, one subgroup.
        let mut rng = SplitMix64::new(9);
        let s = points(&mut rng, 40, 1.0);
        let t: Vec<Vec2> = s.iter().map(|p| *p + Vec2::new(5.0, 1.0)).collect();
        assert_eq!(subgroups(&s, &t, &p, Cancel::NEVER).unwrap().count(), 1);
        let above = ApParams {
            preference: Preference::Value(1.0),
            ..p
        };
        assert_eq!(
            subgroups(&s, &t, &above, Cancel::NEVER).unwrap().count(),
            40
        );
        // NaN positions: their agents are subgroups of their own.
        let mut bad = s.clone();
        bad[3].x = f64::NAN;
        let mut tb = deform(&mut rng, &s);
        tb[7].y = f64::INFINITY;
        for dense_up_to in [100, 0] {
            let q = ApParams { dense_up_to, ..p };
            let g = subgroups(&bad, &tb, &q, Cancel::NEVER).unwrap();
            assert_eq!(g.group_of.len(), 40);
            for i in [3usize, 7] {
                let gi = g.group_of[i];
                assert_eq!(g.exemplars[gi as usize], i as u32);
                assert_eq!(g.group_of.iter().filter(|&&x| x == gi).count(), 1);
            }
        }
        // Fewer targets than agents: the unpaired ones are alone too.
        let g = subgroups(&s, &t[..30], &p, Cancel::NEVER).unwrap();
        assert!(g.count() >= 11);
        // Duplicated sources and no iterations.
        let dup = vec![Vec2::new(0.5, 0.5); 12];
        let td = deform(&mut rng, &dup);
        for dense_up_to in [100, 0] {
            let q = ApParams { dense_up_to, ..p };
            let g = subgroups(&dup, &td, &q, Cancel::NEVER).unwrap();
            assert!(g.group_of.iter().all(|&x| (x as usize) < g.count()));
            let q0 = ApParams {
                max_iterations: 0,
                ..q
            };
            let g = subgroups(&dup, &td, &q0, Cancel::NEVER).unwrap();
            assert!(!g.converged);
            assert_eq!(g.count(), 1);
        }
    }

    #[test]
    fn cancelled() {
        let mut rng = SplitMix64::new(4);
        let s = points(&mut rng, 50, 1.0);
        let t = deform(&mut rng, &s);
        let stop = || true;
        assert_eq!(
            subgroups(&s, &t, &ApParams::default(), Cancel::new(&stop)),
            None
        );
    }

    /// Writes the instances `benches/ap_crosscheck.py` gives scikit-learn:
    /// `target/ap_crosscheck/cases.json`, with each instance's similarity matrix
    /// (eq. 20, off the diagonal), the preference, the parameters and our labels.
    #[test]
    #[ignore = "writes the data of benches/ap_crosscheck.py"]
    fn ap_crosscheck_dataset() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/ap_crosscheck");
        std::fs::create_dir_all(&dir).unwrap();
        let mut rng = SplitMix64::new(0xc4055);
        let mut cases = Vec::new();
        for (n, damping) in [(40usize, 0.7), (80, 0.5), (150, 0.7), (300, 0.9)] {
            let s = points(&mut rng, n, 1.0);
            let t = deform(&mut rng, &s);
            let p = ApParams {
                damping,
                max_iterations: 1000,
                ..ApParams::default()
            };
            let g = subgroups(&s, &t, &p, Cancel::NEVER).unwrap();
            let mut off = Vec::new();
            let sm: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|k| if i == k { 0.0 } else { delta_dis(&s, &t, i, k) })
                        .collect()
                })
                .collect();
            for (i, row) in sm.iter().enumerate() {
                off.extend(
                    row.iter()
                        .enumerate()
                        .filter(|&(k, _)| k != i)
                        .map(|(_, &v)| v),
                );
            }
            let pref = median(&mut off);
            cases.push(serde_json::json!({
                "n": n,
                "damping": damping,
                "max_iter": p.max_iterations,
                "convergence_iter": p.convergence_iterations,
                "preference": pref,
                "S": sm,
                "labels": g.group_of,
                "exemplars": g.exemplars,
                "converged": g.converged,
                "iterations": g.iterations,
            }));
        }
        std::fs::write(
            dir.join("cases.json"),
            serde_json::to_string(&cases).unwrap(),
        )
        .unwrap();
    }
}
