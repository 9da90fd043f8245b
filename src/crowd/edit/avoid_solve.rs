//! The solvers of collision avoidance by retiming (crowd-motion-editing section
//! 4.1.2): one pair's colliding pieces retimed (eqs. 18–23, `retime_pair`), a
//! person's whole temporal track re-solved with those nodes fixed (eq. 28,
//! `smooth_track`), and a pair's retiming with its undo (`separate_pair`,
//! `PairState`). The rounds that call them are in `avoid.rs`.

use super::avoid_params::*;
use super::collide::{detect, Approach, CollideError, PairCollision};
use super::tracks::{Track, TrackSet};
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;

/// Tolerance of the constraint and multiplier checks of the active-set solve
/// (seconds, on quantities of a few seconds).
const KKT_TOLERANCE: f64 = 1e-9;

/// Relative slack on the interval bounds `[a_min, 1 / a_min]` (rounding).
const SCALE_TOLERANCE: f64 = 1e-9;

/// The nodes of one person's colliding piece and how the collision time depends on
/// them: `t_collision = Σ w_n t_n` (the piece's linear interpolation).
#[derive(Clone, Debug)]
pub(super) struct PieceNodes {
    pub(super) nodes: Vec<usize>,
    pub(super) weights: Vec<f64>,
    pub(super) times: Vec<f64>,
    /// The piece's duration in the input (seconds; 0 for a sample).
    pub(super) original_len_s: f64,
    /// The person's first time (constraints g3/g4, see `retime_pair`).
    pub(super) first_s: f64,
    pub(super) speed_m_s: f64,
}

pub(super) fn piece_nodes(
    track: &Track,
    original_s: &[f64],
    sample: usize,
    moving: bool,
    t_s: f64,
) -> PieceNodes {
    let first_s = track.times_s[0];
    if moving {
        let (t0, t1) = (track.times_s[sample], track.times_s[sample + 1]);
        let lambda = ((t_s - t0) / (t1 - t0)).clamp(0.0, 1.0);
        PieceNodes {
            nodes: vec![sample, sample + 1],
            weights: vec![1.0 - lambda, lambda],
            times: vec![t0, t1],
            original_len_s: original_s[sample + 1] - original_s[sample],
            first_s,
            speed_m_s: track.segment_speed(sample),
        }
    } else {
        PieceNodes {
            nodes: vec![sample],
            weights: vec![1.0],
            times: vec![track.times_s[sample]],
            original_len_s: 0.0,
            first_s,
            speed_m_s: 0.0,
        }
    }
}

/// New times of the two colliding pieces' nodes, eqs. 18–23.
///
/// # Formula
/// Person `i`'s piece `[t_k, t_{k+1}]` becomes `[a_i t_k + b_i, a_i t_{k+1} + b_i]`
/// (likewise `j`). Two nodes and two unknowns `(a, b)` are one-to-one, so the
/// unknowns here are the node shifts `δ`, and eq. 18 is `E_T = |δ|²`. The time at
/// which a person passes the collision point moves by `wᵀδ` (`w` the linear
/// interpolation weights of the collision time in the piece). Eq. 19 becomes
///
/// ```text
/// min |δ|²  subject to  σ (w_iᵀδ_i − w_jᵀδ_j) ≥ dt          (g5, σ = ±1: who passes first)
///                       Δt + δ_{k+1} − δ_k ≥ a_min Δt₀         (g1, g2: a ≥ a_min)
///                       Δt + δ_{k+1} − δ_k ≤ Δt₀ / a_min       (ours)
///                       δ_k ≥ −t_first                         (g3, g4)
/// ```
///
/// with `Δt` the piece's current duration and `Δt₀` its duration in the input:
/// the scale is measured against the input so that rounds do not compound it.
/// The upper bound is not in the paper: without it a collision near a piece's end
/// stretches that one piece, and slows it, by up to `dt / Δt`.
/// `order` fixes `σ` (a pair keeps the order chosen at its first retiming, so
/// later rounds do not undo it); `None` tries both. Returns `σ` and `δ`.
///
/// a projection onto a polyhedron, solved through its KKT conditions (eq. 23) by
/// enumerating active sets: for each set `S` of active constraints with
/// independent rows, `δ = G_Sᵀ μ` with `(G_S G_Sᵀ) μ = h_S`; the point is kept when
/// `μ ≥ 0` and every constraint holds, and the best of both signs `σ` wins. g3/g4
/// are placed on the person's first time rather than the piece's (the paper's), so
/// carrying the shift to the track's start (the correction of `smooth_track`)
/// never makes a time negative.
///
/// # Units
/// Seconds.
///
/// # Errors
/// `None` when no retiming satisfies the constraints.
pub(super) fn retime_pair(
    pi: &PieceNodes,
    pj: &PieceNodes,
    dt: f64,
    min_scale: f64,
    order: Option<f64>,
) -> Option<(f64, Vec<f64>)> {
    let ni = pi.nodes.len();
    let m = ni + pj.nodes.len();
    let mut best: Option<(f64, f64, Vec<f64>)> = None;
    let signs: &[f64] = match order {
        Some(s) if s > 0.0 => &[1.0],
        Some(_) => &[-1.0],
        None => &[1.0, -1.0],
    };
    for &sigma in signs {
        // Rows of G δ ≥ h.
        let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
        let mut sep = vec![0.0; m];
        for (k, w) in pi.weights.iter().enumerate() {
            sep[k] = sigma * w;
        }
        for (k, w) in pj.weights.iter().enumerate() {
            sep[ni + k] = -sigma * w;
        }
        rows.push((sep, dt));
        for (p, off) in [(pi, 0), (pj, ni)] {
            if p.nodes.len() == 2 {
                let len = p.times[1] - p.times[0];
                let mut g = vec![0.0; m];
                g[off] = -1.0;
                g[off + 1] = 1.0;
                rows.push((g.clone(), min_scale * p.original_len_s - len));
                g[off] = 1.0;
                g[off + 1] = -1.0;
                rows.push((g, len - p.original_len_s / min_scale));
            }
            let mut g = vec![0.0; m];
            g[off] = 1.0;
            // Held with twice the check's slack, so rounding cannot go below 0.
            rows.push((
                g,
                -p.first_s + 2.0 * KKT_TOLERANCE * (1.0 + p.first_s.abs()),
            ));
        }
        let r = rows.len();
        for mask in 1u32..(1 << r) {
            let active: Vec<usize> = (0..r).filter(|k| mask & (1 << k) != 0).collect();
            if active.len() > m {
                continue;
            }
            let g = DMatrix::from_fn(active.len(), m, |a, c| rows[active[a]].0[c]);
            let h = DVector::from_iterator(active.len(), active.iter().map(|&a| rows[a].1));
            let Some(mu) = (&g * g.transpose()).cholesky().map(|c| c.solve(&h)) else {
                continue;
            };
            if mu.iter().any(|&x| x.is_nan() || x < -KKT_TOLERANCE) {
                continue;
            }
            let delta = g.transpose() * mu;
            let feasible = rows.iter().all(|(row, h)| {
                let lhs: f64 = row.iter().zip(delta.iter()).map(|(a, b)| a * b).sum();
                lhs >= h - KKT_TOLERANCE * (1.0 + h.abs())
            });
            let e = delta.norm_squared();
            if feasible && e.is_finite() && best.as_ref().is_none_or(|(b, _, _)| e < *b) {
                best = Some((e, sigma, delta.iter().copied().collect()));
            }
        }
    }
    best.map(|(_, sigma, d)| (sigma, d))
}

/// Re-solves one person's temporal track with some nodes fixed, eq. 28.
///
/// # Formula
/// `min α² E_DT + β² E_T + γ² E_TP` subject to the fixed nodes, with
/// `E_DT = Σ (Δt̄_{i+1}/l_{i+1} − Δt̄_i/l_i)²` over consecutive linked segments both
/// at least [`MIN_PACE_LENGTH_M`] long (eq. 24), `E_T = Σ (Δt̄_i − Δt_i)²` over all
/// intervals, gaps included (eq. 26), and `E_TP = Σ (t̄_i − t_i)²` (eq. 27), `t`
/// the times of the input (`original_s`): measured against the input, not the
/// times of the previous round, so rounds do not drift a person's times away
/// (the fixed nodes are every node a retiming of this person has fixed so far).
/// The
/// normal equations are pentadiagonal; the fixed nodes are eliminated and the
/// system solved by a banded Cholesky factorisation, O(n).
///
/// If the solution is not strictly increasing, or makes the first time negative
/// (when it was not), or takes an interval outside
/// `[a_min, 1 / a_min]` times its length in the input (`original_s`), or the
/// factorisation fails, the correction is used instead: nodes before the first
/// fixed node move by its shift, nodes after the last by its shift, and nodes
/// between two fixed nodes are mapped linearly in the current times between them.
/// The correction keeps every other interval as it is, so by induction over the
/// rounds every interval stays within those bounds and the speed of every segment
/// within `[a_min, 1 / a_min]` times its input speed. Returns whether the
/// correction was used; `None`, with the track unchanged, when the correction is
/// not strictly increasing either (the fixed nodes disagree).
///
/// # Units
/// Seconds; lengths in metres.
pub(super) fn smooth_track(
    track: &mut Track,
    original_s: &[f64],
    fixed: &[(usize, f64)],
    p: &AvoidParams,
) -> Option<bool> {
    let n = track.len();
    let t = original_s.to_vec();
    let mut is_fixed = vec![None; n];
    for &(k, v) in fixed {
        is_fixed[k] = Some(v);
    }
    // Normal matrix as lower bands: band[i][d] = N[i][i - d].
    let mut band = vec![[0.0f64; 3]; n];
    let mut rhs = vec![0.0f64; n];
    let mut add = |terms: &[(usize, f64)], target: f64, w2: f64| {
        for &(a, ca) in terms {
            rhs[a] += w2 * ca * target;
            for &(b, cb) in terms {
                if b <= a {
                    band[a][a - b] += w2 * ca * cb;
                }
            }
        }
    };
    let (a2, b2, g2) = (p.alpha * p.alpha, p.beta * p.beta, p.gamma * p.gamma);
    for (i, &ti) in t.iter().enumerate() {
        add(&[(i, 1.0)], ti, g2);
    }
    for i in 0..n.saturating_sub(1) {
        add(&[(i, -1.0), (i + 1, 1.0)], t[i + 1] - t[i], b2);
    }
    if a2 > 0.0 {
        let len = |i: usize| (track.points[i + 1] - track.points[i]).norm();
        for i in 0..n.saturating_sub(2) {
            if !(track.linked[i] && track.linked[i + 1]) {
                continue;
            }
            let (l0, l1) = (len(i), len(i + 1));
            if l0 < MIN_PACE_LENGTH_M || l1 < MIN_PACE_LENGTH_M {
                continue;
            }
            add(
                &[
                    (i, 1.0 / l0),
                    (i + 1, -1.0 / l0 - 1.0 / l1),
                    (i + 2, 1.0 / l1),
                ],
                0.0,
                a2,
            );
        }
    }
    // Eliminate the fixed nodes: move their columns to the right-hand side.
    #[allow(clippy::needless_range_loop)]
    for i in 0..n {
        for d in 1..3 {
            if i < d {
                continue;
            }
            let j = i - d;
            let c = band[i][d];
            match (is_fixed[i], is_fixed[j]) {
                (None, Some(v)) => rhs[i] -= c * v,
                (Some(v), None) => rhs[j] -= c * v,
                _ => {}
            }
            if is_fixed[i].is_some() || is_fixed[j].is_some() {
                band[i][d] = 0.0;
            }
        }
    }
    for i in 0..n {
        if let Some(v) = is_fixed[i] {
            band[i] = [1.0, 0.0, 0.0];
            rhs[i] = v;
        }
    }
    let solved = banded_cholesky_solve(&mut band, &mut rhs);
    let lo = p.min_scale * (1.0 - SCALE_TOLERANCE);
    let hi = (1.0 + SCALE_TOLERANCE) / p.min_scale;
    let increasing = solved
        && rhs.iter().all(|x| x.is_finite())
        && rhs.first().is_none_or(|&x| x >= t[0].min(0.0))
        && (1..n).all(|i| {
            let (new, old) = (rhs[i] - rhs[i - 1], original_s[i] - original_s[i - 1]);
            new > 0.0 && new >= lo * old && new <= hi * old
        });
    if increasing {
        track.times_s = rhs;
        Some(false)
    } else {
        let a = anchored(&t, fixed);
        // Pins of several retimings may disagree (a later one earlier than an
        // earlier one's node, or squeezing the intervals between them past the
        // speed bound): then nothing is changed.
        let within = (1..n).all(|i| {
            let (new, old) = (a[i] - a[i - 1], original_s[i] - original_s[i - 1]);
            new > 0.0 && new >= lo * old && new <= hi * old
        });
        if !within || a.iter().any(|x| !x.is_finite()) {
            return None;
        }
        track.times_s = a;
        Some(true)
    }
}

/// The correction of `smooth_track`: shifts of the fixed nodes carried to the
/// ends, linear in the original times between fixed nodes.
pub(super) fn anchored(t: &[f64], fixed: &[(usize, f64)]) -> Vec<f64> {
    let mut f = fixed.to_vec();
    f.sort_by_key(|x| x.0);
    let mut out = t.to_vec();
    let Some(&(first, v_first)) = f.first() else {
        return out;
    };
    let &(last, v_last) = f.last().expect("non-empty");
    for i in 0..first {
        out[i] = t[i] + (v_first - t[first]);
    }
    for i in last + 1..t.len() {
        out[i] = t[i] + (v_last - t[last]);
    }
    for w in f.windows(2) {
        let ((a, va), (b, vb)) = (w[0], w[1]);
        for i in a..=b {
            let s = if b > a {
                (t[i] - t[a]) / (t[b] - t[a])
            } else {
                0.0
            };
            out[i] = va + (vb - va) * s;
        }
    }
    out
}

/// Solves `N x = rhs` in place for a symmetric positive definite matrix given by
/// its lower bands (`band[i][d] = N[i][i − d]`, `d ≤ 2`); false if not definite.
pub(super) fn banded_cholesky_solve(band: &mut [[f64; 3]], rhs: &mut [f64]) -> bool {
    let n = band.len();
    // band becomes L's bands: L[i][i - d].
    for i in 0..n {
        for d in (0..3).rev() {
            if i < d {
                continue;
            }
            let j = i - d;
            let mut s = band[i][d];
            // Σ_k L[i][k] L[j][k] for k < j, k ≥ i - 2.
            for k in i.saturating_sub(2)..j {
                s -= band[i][i - k] * band[j][j - k];
            }
            if d == 0 {
                if s.is_nan() || s <= 0.0 {
                    return false;
                }
                band[i][0] = s.sqrt();
            } else {
                band[i][d] = s / band[j][0];
            }
        }
    }
    for i in 0..n {
        let mut s = rhs[i];
        for d in 1..3 {
            if i >= d {
                s -= band[i][d] * rhs[i - d];
            }
        }
        rhs[i] = s / band[i][0];
    }
    for i in (0..n).rev() {
        let mut s = rhs[i];
        for d in 1..3 {
            if i + d < n {
                s -= band[i + d][d] * rhs[i + d];
            }
        }
        rhs[i] = s / band[i][0];
    }
    true
}

/// One pair's retiming (Algorithm 3 steps 2–4) on the two tracks; `None` if
/// infeasible. Returns whether a correction replaced a re-solve.
pub(super) fn separate(
    set: &mut TrackSet,
    pair: &PairCollision,
    p: &AvoidParams,
    original: &[Vec<f64>],
    orders: &mut HashMap<(usize, usize), f64>,
    pins: &mut [Vec<(usize, f64)>],
) -> Option<usize> {
    let a: &Approach = &pair.closest;
    let velocity = |t: &Track, a: &Approach| {
        let (k, moving) = if std::ptr::eq(t, &set.tracks[pair.a]) {
            (a.sample_a, a.moving_a)
        } else {
            (a.sample_b, a.moving_b)
        };
        if moving {
            (t.points[k + 1] - t.points[k]) / (t.times_s[k + 1] - t.times_s[k])
        } else {
            crate::geom::Vec2::zeros()
        }
    };
    let pi = piece_nodes(
        &set.tracks[pair.a],
        &original[pair.a],
        a.sample_a,
        a.moving_a,
        a.t_s,
    );
    let pj = piece_nodes(
        &set.tracks[pair.b],
        &original[pair.b],
        a.sample_b,
        a.moving_b,
        a.t_s,
    );
    // Eqs. 20–22.
    let distance = p.threshold_m + p.margin_m - a.distance_m;
    let slow = pi.speed_m_s.min(pj.speed_m_s);
    let v = if slow > STILL_SPEED_M_S {
        slow
    } else {
        pi.speed_m_s.max(pj.speed_m_s)
    };
    if v.is_nan() || v <= STILL_SPEED_M_S {
        return None;
    }
    // The speed at which a time offset moves the two apart across their relative
    // path: |v_i × v_j| / |v_i − v_j| (no more than eq. 20's v); at most
    // MAX_DT_FACTOR times eq. 22's dt.
    let (vi, vj) = (
        velocity(&set.tracks[pair.a], a),
        velocity(&set.tracks[pair.b], a),
    );
    let w = (vi - vj).norm();
    let across = if w > STILL_SPEED_M_S {
        crate::geom::cross(vi, vj).abs() / w
    } else {
        v
    };
    let dt = distance / across.clamp(v / MAX_DT_FACTOR, v);
    let key = (pair.a, pair.b);
    let (sigma, delta) = retime_pair(&pi, &pj, dt, p.min_scale, orders.get(&key).copied())?;
    orders.insert(key, sigma);
    let ni = pi.nodes.len();
    let fixed_i: Vec<(usize, f64)> = (0..ni)
        .map(|k| (pi.nodes[k], pi.times[k] + delta[k]))
        .collect();
    let fixed_j: Vec<(usize, f64)> = (0..pj.nodes.len())
        .map(|k| (pj.nodes[k], pj.times[k] + delta[ni + k]))
        .collect();
    let mut corrections = 0;
    for (k, fixed) in [(pair.a, fixed_i), (pair.b, fixed_j)] {
        // Every node fixed for this person so far stays fixed: earlier
        // separations hold while the track is re-solved against its input times.
        for (node, t) in fixed {
            match pins[k].iter_mut().find(|x| x.0 == node) {
                Some(x) => x.1 = t,
                None => pins[k].push((node, t)),
            }
        }
        if smooth_track(&mut set.tracks[k], &original[k], &pins[k], p)? {
            corrections += 1;
        }
    }
    Some(corrections)
}

/// A pair's two people as they were (times and pins) and the pair's passing
/// order, to undo a retiming that did not help.
pub(super) struct PairState {
    key: (usize, usize),
    people: [Saved; 2],
    order: Option<f64>,
}

/// One person's index, times and pins.
type Saved = (usize, Vec<f64>, Vec<(usize, f64)>);

impl PairState {
    pub(super) fn save(
        set: &TrackSet,
        pins: &[Vec<(usize, f64)>],
        orders: &HashMap<(usize, usize), f64>,
        q: &PairCollision,
    ) -> PairState {
        let one = |k: usize| (k, set.tracks[k].times_s.clone(), pins[k].clone());
        PairState {
            key: (q.a, q.b),
            people: [one(q.a), one(q.b)],
            order: orders.get(&(q.a, q.b)).copied(),
        }
    }

    pub(super) fn restore(
        &self,
        set: &mut TrackSet,
        pins: &mut [Vec<(usize, f64)>],
        orders: &mut HashMap<(usize, usize), f64>,
    ) {
        for (k, t, p) in &self.people {
            set.tracks[*k].times_s.clone_from(t);
            pins[*k].clone_from(p);
        }
        match self.order {
            Some(o) => orders.insert(self.key, o),
            None => orders.remove(&self.key),
        };
    }
}

/// The most retimings of one pair in a row (each from where the previous left
/// it) before the result is judged: a pair walking head-on along one line needs
/// several, as the paper's rounds give it.
pub(super) const PAIR_STEPS: usize = 8;

/// Why one pair's retimings were not kept.
pub(super) enum PairFailure {
    Stuck(Stuck),
    Collide(CollideError),
}

/// Retimes one pair until it no longer collides (at most [`PAIR_STEPS`] times,
/// each step undone if it fails), within the shift bound. Returns the
/// corrections used, or why nothing was done (the tracks and pins are then as
/// before).
pub(super) fn separate_pair(
    set: &mut TrackSet,
    q: &PairCollision,
    p: &AvoidParams,
    original: &[Vec<f64>],
    input: &[Vec<f64>],
    orders: &mut HashMap<(usize, usize), f64>,
    pins: &mut [Vec<(usize, f64)>],
) -> Result<usize, PairFailure> {
    let mut pq = *q;
    let mut corrections = 0;
    let mut steps = 0;
    for _ in 0..PAIR_STEPS {
        let saved = PairState::save(set, pins, orders, q);
        let why = match separate(set, &pq, p, original, orders, pins) {
            None => Stuck::Infeasible,
            Some(_)
                if largest_shift(&set.tracks[q.a].times_s, &input[q.a]) > p.max_shift_s
                    || largest_shift(&set.tracks[q.b].times_s, &input[q.b]) > p.max_shift_s =>
            {
                Stuck::Bound
            }
            Some(c) => {
                corrections += c;
                steps += 1;
                // Does the pair still collide? The two alone.
                let two = TrackSet {
                    tracks: vec![set.tracks[q.a].clone(), set.tracks[q.b].clone()],
                    step_s: set.step_s,
                };
                let c2 = detect(&two, p.threshold_m).map_err(PairFailure::Collide)?;
                match c2.pairs.first() {
                    None => return Ok(corrections),
                    Some(x) => {
                        pq = PairCollision {
                            a: q.a,
                            b: q.b,
                            id_a: q.id_a,
                            id_b: q.id_b,
                            ..*x
                        };
                        continue;
                    }
                }
            }
        };
        saved.restore(set, pins, orders);
        if steps == 0 {
            return Err(PairFailure::Stuck(why));
        }
        break;
    }
    Ok(corrections)
}

/// Whether the pair walks together where it is closest: both moving, velocities
/// differing by at most `rel` of the faster one's speed.
pub(super) fn companions(set: &TrackSet, pair: &PairCollision, rel: f64) -> bool {
    let a = &pair.closest;
    let velocity = |t: &Track, k: usize, moving: bool| {
        if moving && k + 1 < t.len() {
            Some((t.points[k + 1] - t.points[k]) / (t.times_s[k + 1] - t.times_s[k]))
        } else {
            None
        }
    };
    match (
        velocity(&set.tracks[pair.a], a.sample_a, a.moving_a),
        velocity(&set.tracks[pair.b], a.sample_b, a.moving_b),
    ) {
        (Some(vi), Some(vj)) => {
            let fast = vi.norm().max(vj.norm());
            fast > STILL_SPEED_M_S && (vi - vj).norm() <= rel * fast
        }
        _ => false,
    }
}

/// The largest `|t − t₀|` of one person (s).
pub(super) fn largest_shift(t: &[f64], t0: &[f64]) -> f64 {
    t.iter()
        .zip(t0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}
