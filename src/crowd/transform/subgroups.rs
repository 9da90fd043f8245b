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

use crate::crowd::assign::Cancel;
use crate::geom::Vec2;
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// The preference `s(k, k)` of affinity propagation.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Preference {
    /// The median of the similarities (Frey & Dueck's default).
    Median,
    /// This value.
    Value(f64),
}

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
    /// Crowds up to this size use every pair (dense).
    pub dense_up_to: usize,
}

impl Default for ApParams {
    /// Damping 0.7, at most 200 iterations, converged after 15 with the same
    /// exemplars, the median preference, the 3-ring of the triangulation above 300
    /// agents.
    fn default() -> ApParams {
        ApParams {
            damping: 0.7,
            max_iterations: 200,
            convergence_iterations: 15,
            preference: Preference::Median,
            ring: 3,
            dense_up_to: 300,
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

/// The similarity the messages use: [`delta_dis`] (the preference on the diagonal)
/// plus a perturbation at rounding level that breaks the ties of symmetric crowds
/// (as scikit-learn's `AffinityPropagation` does with its random state; here a
/// hash of the pair, so every run and both layouts see the same values).
#[inline]
fn similarity(s: &[Vec2], t: &[Vec2], pref: f64, i: usize, j: usize) -> f64 {
    let v = if i == j { pref } else { delta_dis(s, t, i, j) };
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
/// similar to the others, and the agents join their most similar exemplar again; an
/// agent with no exemplar among its candidates joins the subgroup of its most similar
/// candidate. Exemplars are listed by agent index.
///
/// # Degenerate input
/// No agent: no subgroup. An agent whose source or target is not finite is a
/// subgroup of its own, the others are clustered without it. Equal similarities
/// everywhere: one subgroup if the preference is below them, else one per agent.
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
    let mut exemplars: Vec<u32> = inner.exemplars.iter().map(|&e| ok[e as usize] as u32).collect();
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
    let pairs = if n <= p.dense_up_to {
        Pairs::dense(n)
    } else {
        Pairs::delaunay_rings(s, p.ring.max(1))
    };
    if cancel.cancelled() {
        return None;
    }
    let row = |i: usize| pairs.start[i]..pairs.start[i + 1];
    // Off-diagonal similarities (without the perturbation): preference and the
    // all-equal test.
    let mut off = Vec::with_capacity(pairs.col.len().saturating_sub(n));
    for i in 0..n {
        for e in row(i) {
            let k = pairs.col[e] as usize;
            if k != i {
                off.push(delta_dis(s, t, i, k));
            }
        }
    }
    let pref = match p.preference {
        Preference::Value(v) if v.is_finite() => v,
        _ => median(&mut off),
    };
    let (lo, hi) = off
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    if off.is_empty() || lo == hi {
        // Nothing tells the agents apart (scikit-learn's special case).
        if off.is_empty() || pref < lo {
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
        .map(|(i, e)| similarity(s, t, pref, i, pairs.col[e] as usize))
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
    let sij = |i: usize, k: usize| similarity(s, t, pref, i, k);
    // Join the most similar exemplar; refine each subgroup's exemplar; join again.
    let mut is_ex = vec![u32::MAX; n];
    let mut group_of = vec![0u32; n];
    for pass in 0..2 {
        is_ex.fill(u32::MAX);
        for (g, &k) in exemplars.iter().enumerate() {
            is_ex[k as usize] = g as u32;
        }
        assign(&pairs, &sim, &is_ex, &mut group_of);
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
    Some(Subgroups {
        group_of,
        exemplars: kept,
        iterations,
        converged,
    })
}

/// Every agent joins the exemplar among its candidates with the largest similarity
/// (an exemplar joins itself); agents without one join the subgroup of their most
/// similar candidate that has one, repeatedly (the candidate graph is connected, so
/// every agent ends in a subgroup; an agent that could not would join the first).
/// `is_ex[k]`: the subgroup of exemplar `k`, `u32::MAX` for the others.
fn assign(pairs: &Pairs, sim: &[f64], is_ex: &[u32], group_of: &mut [u32]) {
    let n = group_of.len();
    const NONE: u32 = u32::MAX;
    for i in 0..n {
        group_of[i] = if is_ex[i] != NONE {
            is_ex[i]
        } else {
            let (mut best, mut g) = (f64::NEG_INFINITY, NONE);
            for e in pairs.start[i]..pairs.start[i + 1] {
                let k = pairs.col[e] as usize;
                if k != i && is_ex[k] != NONE && sim[e] > best {
                    best = sim[e];
                    g = is_ex[k];
                }
            }
            g
        };
    }
    loop {
        let mut changed = false;
        let mut left = false;
        for i in 0..n {
            if group_of[i] != NONE {
                continue;
            }
            let (mut best, mut g) = (f64::NEG_INFINITY, NONE);
            for e in pairs.start[i]..pairs.start[i + 1] {
                let k = pairs.col[e] as usize;
                if k != i && group_of[k] != NONE && sim[e] > best {
                    best = sim[e];
                    g = group_of[k];
                }
            }
            if g != NONE {
                group_of[i] = g;
                changed = true;
            } else {
                left = true;
            }
        }
        if !left {
            return;
        }
        if !changed {
            // A component without an exemplar (not reached through candidates).
            for g in group_of.iter_mut().filter(|g| **g == NONE) {
                *g = 0;
            }
            return;
        }
    }
}
