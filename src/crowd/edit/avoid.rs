//! Collision avoidance by retiming, crowd-motion-editing section 4.1.2 (eqs. 18–28,
//! Algorithm 3): the spatial tracks stay as they are; the times at which people
//! reach their positions move so that no two come closer than the threshold.
//!
//! Each round (Algorithm 3) detects collisions ([`detect`]), then, worst pair first
//! and each person at most once per round:
//!
//! 1. the time separation needed at the collision point is estimated (eqs. 20–22):
//!    `dt = (D_threshold + margin − d_min) / v`, with `v` the slower of the two
//!    people's speeds on their colliding pieces (the faster one's if the slower
//!    stands still). Ours: `v` is replaced by the speed at which a time offset
//!    moves the two apart across their relative path, `|v_i × v_j| / |v_i − v_j|`
//!    (never more than eq. 20's `v`; equal to `v / √2` for equal speeds crossing
//!    at right angles, far less for nearly head-on walkers, for whom eq. 22 alone
//!    needs many rounds), bounded so `dt` is at most [`MAX_DT_FACTOR`] times
//!    eq. 22's;
//! 2. the two colliding pieces are retimed (eqs. 18, 19, 23) — see `retime_pair`;
//! 3. each of the two people's whole temporal tracks is re-solved with the retimed
//!    nodes fixed (eq. 28) — see `smooth_track`.
//!
//! Rounds repeat until nothing collides or [`AvoidParams::max_iterations`] is
//! reached. A pair that retiming cannot separate (both standing still, no feasible
//! retiming) is reported in [`AvoidReport::remaining`]; nothing panics.
//!
//! The work is bounded whatever the input: each round looks at no more than the
//! [`DEFAULT_KEEP`](super::DEFAULT_KEEP) closest pairs detection keeps (when more collide, the next
//! round detects again and takes the next closest), and the people of a
//! [`Cluster`](super::Cluster) of detection (on one identical track, for instance
//! standing at one point, or standing together within the threshold) are left as
//! they are: their pairs, and their pairs with anyone else, are
//! not retimed, and each cluster is one [`Remaining`] ([`Stuck::Cluster`]) for its
//! first two members.

use super::avoid_shift as shift;
use super::collide::{detect, Approach, CollideError, Collisions, PairCollision};
use super::tracks::{Track, TrackSet};
use nalgebra::{DMatrix, DVector};
use std::collections::{HashMap, HashSet};
use thiserror::Error;

/// Speeds below this (m/s) count as standing still in eq. 20.
pub const STILL_SPEED_M_S: f64 = 1e-6;

/// Segments shorter than this (metres) have no pace in eq. 24 (it divides by the
/// length) and no speed in [`AvoidReport::max_speed_change_pct`].
pub const MIN_PACE_LENGTH_M: f64 = 1e-6;

/// Tolerance of the constraint and multiplier checks of the active-set solve
/// (seconds, on quantities of a few seconds).
const KKT_TOLERANCE: f64 = 1e-9;

/// The most the separation time may exceed eq. 22's estimate (see [`avoid`]).
pub const MAX_DT_FACTOR: f64 = 10.0;

/// Relative slack on the interval bounds `[a_min, 1 / a_min]` (rounding).
const SCALE_TOLERANCE: f64 = 1e-9;

/// Parameters of the avoidance. The paper states the terms but gives no values;
/// the defaults are ours (see each field).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct AvoidParams {
    /// `D_threshold` (eq. 21): people closer than this collide (metres).
    pub threshold_m: f64,
    /// Added to `distance_{i,j}` (eq. 21) so a retimed pair ends clear of the
    /// threshold rather than on it (metres). Default 0.02.
    pub margin_m: f64,
    /// The least scaling `a` of a colliding piece's duration (constraints `g1`,
    /// `g2` of eq. 19), in (0, 1]; `1 / min_scale` is the most (ours, see
    /// `retime_pair`). Default 0.8: a retimed piece's speed changes by at most 25 %.
    pub min_scale: f64,
    /// `α` (eq. 28), weight of the pace smoothness `E_DT` (eq. 24). Default 0.1.
    pub alpha: f64,
    /// `β` (eq. 28), weight of the interval change `E_T` (eq. 26). Default 1.
    pub beta: f64,
    /// `γ` (eq. 28), weight of the time change `E_TP` (eq. 27); it must be
    /// positive (it keeps eq. 28 definite). Smaller values spread a retiming over
    /// more of the track (about `β / γ` samples). Default 0.1.
    pub gamma: f64,
    /// The most detection-and-retiming rounds (Algorithm 3). Default 200.
    pub max_iterations: usize,
    /// The most any person's time may move from the input (seconds): a retiming
    /// that would move someone further is not made (the pair is reported as
    /// [`Stuck::Bound`]). Default 10 s (ours: the paper states no bound).
    pub max_shift_s: f64,
    /// Two people whose velocities at their closest approach differ by at most
    /// this fraction of the faster one's speed walk together (*companions*): no
    /// retiming separates people who walk side by side, so they are left as they
    /// are and reported ([`Stuck::Companions`]). Default 0.25 (ours).
    pub companion_rel_speed: f64,
}

impl Default for AvoidParams {
    fn default() -> Self {
        AvoidParams {
            threshold_m: 0.3,
            margin_m: 0.02,
            min_scale: 0.8,
            alpha: 0.1,
            beta: 1.0,
            gamma: 0.1,
            max_iterations: 200,
            max_shift_s: 10.0,
            companion_rel_speed: 0.25,
        }
    }
}

/// Bad input to [`avoid`].
#[derive(Debug, Error, PartialEq)]
pub enum AvoidError {
    /// A parameter is out of range.
    #[error("avoidance parameter {name} must be {want}, not {value}")]
    Param {
        /// The field.
        name: &'static str,
        /// What it must be.
        want: &'static str,
        /// The value given.
        value: f64,
    },
    /// The tracks or threshold are unusable for detection.
    #[error(transparent)]
    Collide(#[from] CollideError),
}

/// Why a pair still collides after [`avoid`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Stuck {
    /// Retiming cannot separate them: both stand still at the collision, or eq. 19
    /// has no feasible solution.
    Infeasible,
    /// They still collided when the rounds ran out.
    IterationLimit,
    /// They are (or one is) in a cluster of people on one identical track, which
    /// avoidance leaves as it is.
    Cluster,
    /// They walk together (similar velocities where they are closest,
    /// [`AvoidParams::companion_rel_speed`]): retiming cannot separate them.
    Companions,
    /// Separating them would move someone's times by more than
    /// [`AvoidParams::max_shift_s`].
    Bound,
    /// Every retiming tried made things worse (more collisions, or a closer
    /// approach than the input's closest), and was undone.
    NoImprovement,
}

impl Stuck {
    /// A short name for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Stuck::Infeasible => "infeasible",
            Stuck::IterationLimit => "iteration-limit",
            Stuck::Cluster => "cluster",
            Stuck::Companions => "companions",
            Stuck::Bound => "bound",
            Stuck::NoImprovement => "no-improvement",
        }
    }
}

/// A pair that still collides.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Remaining {
    /// The pair and its closest approach after avoidance.
    pub pair: PairCollision,
    /// Why.
    pub why: Stuck,
}

/// What [`avoid`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct AvoidReport {
    /// Detection-and-retiming rounds run.
    pub iterations: usize,
    /// Colliding pairs before (all of them, clusters' pairs included).
    pub pairs_before: usize,
    /// Colliding pairs after (likewise).
    pub pairs_after: usize,
    /// Pair retimings applied (eq. 19 solves whose result was kept).
    pub retimings: usize,
    /// The pairs that still collide: at most [`DEFAULT_KEEP`](super::DEFAULT_KEEP) of them (the closest)
    /// and one per cluster; `pairs_after` counts them all.
    pub remaining: Vec<Remaining>,
    /// Sum over all samples of `|t̄ − t|` (seconds).
    pub total_abs_dt_s: f64,
    /// The largest change of a segment's speed, `|v̄ / v − 1|` in percent, over
    /// segments at least [`MIN_PACE_LENGTH_M`] long.
    pub max_speed_change_pct: f64,
    /// Track re-solves (eq. 28) that broke strictly increasing times and were
    /// replaced by the correction of `smooth_track`.
    pub corrections: usize,
    /// People in a colliding pair before (clusters' people included).
    pub people_in_collision: usize,
    /// People whose times changed.
    pub retimed_people: usize,
    /// The median, over the retimed people, of their largest time shift (s).
    pub median_shift_s: f64,
    /// The largest time shift of anyone (s); at most
    /// [`AvoidParams::max_shift_s`].
    pub max_shift_s: f64,
    /// The bound it was held to, [`AvoidParams::max_shift_s`] (s).
    pub max_shift_bound_s: f64,
    /// Pairs left as they are because they walk together.
    pub companions: usize,
    /// Retimings undone because they did not reduce the collisions or brought
    /// two people closer than the input's closest approach.
    pub undone: usize,
    /// The closest approach of any colliding pair before and after (m; `None`
    /// without collisions). Never smaller after than before.
    pub closest_before_m: Option<f64>,
    /// See `closest_before_m`.
    pub closest_after_m: Option<f64>,
    /// Whether the result would have been worse than the input on either count
    /// and the input was kept instead (a safety net: each retiming kept already
    /// makes things better).
    pub reverted: bool,
    /// Rigid shifts kept: a group, or one person, whose every time moved by
    /// the same amount (`avoid_shift`).
    pub shifts: usize,
}

/// The nodes of one person's colliding piece and how the collision time depends on
/// them: `t_collision = Σ w_n t_n` (the piece's linear interpolation).
#[derive(Clone, Debug)]
struct PieceNodes {
    nodes: Vec<usize>,
    weights: Vec<f64>,
    times: Vec<f64>,
    /// The piece's duration in the input (seconds; 0 for a sample).
    original_len_s: f64,
    /// The person's first time (constraints g3/g4, see `retime_pair`).
    first_s: f64,
    speed_m_s: f64,
}

fn piece_nodes(
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
fn retime_pair(
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
fn smooth_track(
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
fn anchored(t: &[f64], fixed: &[(usize, f64)]) -> Vec<f64> {
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
fn banded_cholesky_solve(band: &mut [[f64; 3]], rhs: &mut [f64]) -> bool {
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

fn check_params(p: &AvoidParams) -> Result<(), AvoidError> {
    let bad = |name, want, value: f64| Err(AvoidError::Param { name, want, value });
    if !(p.margin_m.is_finite() && p.margin_m >= 0.0) {
        return bad("margin_m", "a non-negative distance", p.margin_m);
    }
    if !(p.min_scale > 0.0 && p.min_scale <= 1.0) {
        return bad("min_scale", "in (0, 1]", p.min_scale);
    }
    if !(p.alpha.is_finite() && p.alpha >= 0.0) {
        return bad("alpha", "finite and non-negative", p.alpha);
    }
    if !(p.beta.is_finite() && p.beta >= 0.0) {
        return bad("beta", "finite and non-negative", p.beta);
    }
    if !(p.gamma.is_finite() && p.gamma > 0.0) {
        return bad("gamma", "finite and positive", p.gamma);
    }
    if !(p.max_shift_s.is_finite() && p.max_shift_s > 0.0) {
        return bad("max_shift_s", "finite and positive", p.max_shift_s);
    }
    if !(p.companion_rel_speed.is_finite() && p.companion_rel_speed >= 0.0) {
        return bad(
            "companion_rel_speed",
            "finite and non-negative",
            p.companion_rel_speed,
        );
    }
    Ok(())
}

/// One pair's retiming (Algorithm 3 steps 2–4) on the two tracks; `None` if
/// infeasible. Returns whether a correction replaced a re-solve.
fn separate(
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
struct PairState {
    key: (usize, usize),
    people: [Saved; 2],
    order: Option<f64>,
}

/// One person's index, times and pins.
type Saved = (usize, Vec<f64>, Vec<(usize, f64)>);

impl PairState {
    fn save(
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

    fn restore(
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
const PAIR_STEPS: usize = 8;

/// Why one pair's retimings were not kept.
enum PairFailure {
    Stuck(Stuck),
    Collide(CollideError),
}

/// Retimes one pair until it no longer collides (at most [`PAIR_STEPS`] times,
/// each step undone if it fails), within the shift bound. Returns the
/// corrections used, or why nothing was done (the tracks and pins are then as
/// before).
fn separate_pair(
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
fn companions(set: &TrackSet, pair: &PairCollision, rel: f64) -> bool {
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
fn largest_shift(t: &[f64], t0: &[f64]) -> f64 {
    t.iter()
        .zip(t0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// Retimes the tracks so no two people come closer than `params.threshold_m`
/// (section 4.1.2, Algorithm 3). Positions are never changed; times stay strictly
/// increasing and non-negative when they start so.
///
/// # Formula
/// Eqs. 20–22 for the separation, eqs. 18, 19 and 23 for the colliding pieces
/// (`retime_pair`), eq. 28 for the whole tracks (`smooth_track`).
///
/// # Complexity
/// Per round one [`detect`] and O(n) per retimed person of n samples.
///
/// # Errors
/// [`AvoidError`]: parameters out of range, a bad threshold or a track set breaking
/// [`TrackSet::validate`]. Pairs that cannot be separated are not errors: they are
/// in [`AvoidReport::remaining`].
pub fn avoid(set: &mut TrackSet, params: &AvoidParams) -> Result<AvoidReport, AvoidError> {
    avoid_around(set, params, &[])
}

/// As [`avoid`], but only the pairs with one of `people` (indices into `set`) are
/// worked on; everyone else's collisions are left as they are (and counted in
/// the report). An empty `people` means everyone. The daemon's edit mode uses it
/// after a drag: the people dragged and whoever they now meet are retimed, not
/// strangers who happened to collide already.
///
/// # Errors
/// As [`avoid`].
pub fn avoid_around(
    set: &mut TrackSet,
    params: &AvoidParams,
    people: &[usize],
) -> Result<AvoidReport, AvoidError> {
    avoid_around_leaving(set, params, people, &HashSet::new())
}

/// As [`avoid_around`], but the pairs in `leave` (track indices, the smaller
/// first) are left as they are, like strangers' pairs: the daemon's edit mode
/// leaves the pairs a drag did not bring (two people who walked together before
/// the edit and still do), so that only the people the edit brought into
/// collision are retimed.
///
/// # Errors
/// As [`avoid`].
pub fn avoid_around_leaving(
    set: &mut TrackSet,
    params: &AvoidParams,
    people: &[usize],
    leave: &HashSet<(usize, usize)>,
) -> Result<AvoidReport, AvoidError> {
    check_params(params)?;
    let n = set.tracks.len();
    let original: Vec<Vec<f64>> = set.tracks.iter().map(|t| t.times_s.clone()).collect();
    // Each person's schedule the piece retimings smooth towards (eq. 28's `t`):
    // the input's times moved by the rigid shifts made so far (`shift`), so a
    // later retiming does not pull a shifted person back.
    let mut base = original.clone();
    let boxes = shift::boxes(set);
    let shifts_s = shift::candidates_s(params.max_shift_s);
    // Groups whose every shift was tried (each group is tried once: a rigid
    // shift that failed is rarely the answer after others moved, and the piece
    // retimings still get their pairs), and how many shifts were kept.
    let mut shift_tried: HashSet<Vec<usize>> = HashSet::new();
    let mut shifts_kept = 0;
    let collisions = detect(set, params.threshold_m)?;
    let pairs_before = collisions.pair_count();
    let closest_before_m = collisions.closest().map(|q| q.closest.distance_m);
    // No retiming may bring two people closer than the input's closest pair.
    let floor = closest_before_m.unwrap_or(f64::INFINITY);
    let limits = shift::Limits {
        threshold_m: params.threshold_m,
        max_shift_s: params.max_shift_s,
        floor_m: floor,
        input: &original,
    };
    // People in clusters are left as they are (their tracks are never retimed, so
    // the clusters stay what they were).
    let mut in_cluster = vec![false; n];
    let mut in_collision = vec![false; n];
    for c in &collisions.clusters {
        for &k in &c.members {
            in_cluster[k] = true;
            in_collision[k] = true;
        }
    }
    for q in &collisions.pairs {
        in_collision[q.a] = true;
        in_collision[q.b] = true;
    }
    let people_in_collision = in_collision.iter().filter(|&&x| x).count();
    let mut in_scope = vec![people.is_empty(); n];
    for &k in people {
        if let Some(x) = in_scope.get_mut(k) {
            *x = true;
        }
    }
    let workable = |q: &PairCollision| {
        !in_cluster[q.a]
            && !in_cluster[q.b]
            && (in_scope[q.a] || in_scope[q.b])
            && !leave.contains(&(q.a.min(q.b), q.a.max(q.b)))
    };
    // The colliding pairs as retimings change them: a retiming changes two people,
    // so only their pairs are detected again, as long as every pair is known
    // (`complete`); else each round detects everything again.
    let mut complete = collisions.is_complete();
    let mut current: Vec<PairCollision> = collisions.pairs.clone();
    let mut stuck: HashMap<(usize, usize), Stuck> = HashMap::new();
    let mut pins: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let (mut iterations, mut retimings, mut corrections, mut undone) = (0, 0, 0, 0);
    let mut orders = HashMap::new();
    let mut kept_last_round = false;
    // The round in which each person last changed, and in which each pair's
    // retiming last failed to help.
    let mut changed_at = vec![0usize; n];
    let mut failed_at: HashMap<(usize, usize), usize> = HashMap::new();
    while iterations < params.max_iterations {
        if !complete {
            let again = detect(set, params.threshold_m)?;
            complete = again.is_complete();
            current = again.pairs.clone();
        }
        // A retiming that did not help may help once one of the two has moved
        // (retrying every such pair after every change anywhere costs a
        // detection per pair per round on a dense file, for little).
        if kept_last_round {
            stuck.retain(|k, w| {
                *w != Stuck::NoImprovement || {
                    let at = failed_at.get(k).copied().unwrap_or(0);
                    changed_at[k.0] <= at && changed_at[k.1] <= at
                }
            });
        }
        let mut pairs: Vec<PairCollision> = current
            .iter()
            .filter(|q| workable(q) && !stuck.contains_key(&(q.a, q.b)))
            .copied()
            .collect();
        if pairs.is_empty() {
            break;
        }
        iterations += 1;
        kept_last_round = false;
        pairs.sort_by(|x, y| x.closest.distance_m.total_cmp(&y.closest.distance_m));
        pairs.retain(|q| {
            let together = companions(set, q, params.companion_rel_speed);
            if together {
                stuck.insert((q.a, q.b), Stuck::Companions);
            }
            !together
        });
        let mut touched = vec![false; n];
        // Rigid shifts first: one side of each connected part of the pairs (for
        // two crossing crowds, one crowd), then (below) each person of a pair alone.
        for part in shift::sides(n, &pairs) {
            for side in part
                .iter()
                .filter(|s| s.len() > 1 || part[0].len() + part[1].len() > 2)
            {
                if side.is_empty() || side.iter().any(|&k| touched[k]) || shift_tried.contains(side)
                {
                    continue;
                }
                match shift::best_shift(set, &boxes, side, &limits, &shifts_s) {
                    Some(sh) => {
                        apply_shift(set, &mut base, &mut pins, &sh);
                        for &k in &sh.group {
                            changed_at[k] = iterations;
                        }
                        refresh_after_shift(set, &boxes, params, &sh, &mut current, &mut complete)?;
                        for &k in &sh.group {
                            touched[k] = true;
                        }
                        shifts_kept += 1;
                        kept_last_round = true;
                        break;
                    }
                    None => {
                        shift_tried.insert(side.clone());
                    }
                }
            }
        }
        for q in &pairs {
            if touched[q.a] || touched[q.b] {
                continue;
            }
            let key = (q.a, q.b);
            // One of the two shifted whole, the smaller shift of the two.
            let mut alone: Option<shift::Shift> = None;
            for k in [q.a, q.b] {
                let g = vec![k];
                if shift_tried.contains(&g) {
                    continue;
                }
                match shift::best_shift(set, &boxes, &g, &limits, &shifts_s) {
                    Some(sh) if alone.as_ref().is_none_or(|a| sh.dt_s.abs() < a.dt_s.abs()) => {
                        alone = Some(sh);
                    }
                    Some(_) => {}
                    None => {
                        shift_tried.insert(g);
                    }
                }
            }
            if let Some(sh) = alone {
                apply_shift(set, &mut base, &mut pins, &sh);
                for &k in &sh.group {
                    changed_at[k] = iterations;
                }
                refresh_after_shift(set, &boxes, params, &sh, &mut current, &mut complete)?;
                touched[q.a] = true;
                touched[q.b] = true;
                shifts_kept += 1;
                kept_last_round = true;
                continue;
            }
            // The pairs of these two now (from the list when it is whole): how
            // many, and how deep into the threshold they reach in all.
            let depth = |ps: &mut dyn Iterator<Item = &PairCollision>| -> (usize, f64) {
                ps.fold((0, 0.0), |(n, d), p| {
                    (
                        n + 1,
                        d + (params.threshold_m - p.closest.distance_m).max(0.0),
                    )
                })
            };
            let before = if complete {
                depth(
                    &mut current
                        .iter()
                        .filter(|p| p.a == q.a || p.b == q.a || p.a == q.b || p.b == q.b),
                )
            } else {
                let c = shift::involving_near(set, &boxes, &pair_of(q), params.threshold_m)?;
                if c.is_complete() {
                    depth(&mut c.pairs.iter())
                } else {
                    (c.pair_count(), f64::INFINITY)
                }
            };
            let saved = PairState::save(set, &pins, &orders, q);
            let verdict =
                match separate_pair(set, q, params, &base, &original, &mut orders, &mut pins) {
                    Err(PairFailure::Collide(e)) => return Err(e.into()),
                    Err(PairFailure::Stuck(why)) => Err(why),
                    Ok(c) => {
                        let after =
                            shift::involving_near(set, &boxes, &pair_of(q), params.threshold_m)?;
                        let closest = after
                            .closest()
                            .map_or(f64::INFINITY, |p| p.closest.distance_m);
                        let now = if after.is_complete() {
                            depth(&mut after.pairs.iter())
                        } else {
                            (after.pair_count(), f64::INFINITY)
                        };
                        // Kept only when it makes things better (the others' pairs
                        // are as they were): fewer colliding pairs, or as many
                        // reaching less deep into the threshold; and nobody closer
                        // than the input's closest pair. So the number of colliding
                        // pairs never grows and the closest approach never shrinks.
                        let better =
                            now.0 < before.0 || (now.0 == before.0 && now.1 < before.1 - 1e-9);
                        if better && closest >= floor {
                            Ok((c, after))
                        } else {
                            undone += 1;
                            Err(Stuck::NoImprovement)
                        }
                    }
                };
            match verdict {
                Ok((c, after)) => {
                    corrections += c;
                    retimings += 1;
                    touched[q.a] = true;
                    touched[q.b] = true;
                    changed_at[q.a] = iterations;
                    changed_at[q.b] = iterations;
                    kept_last_round = true;
                    if complete {
                        current.retain(|p| !(p.a == q.a || p.b == q.a || p.a == q.b || p.b == q.b));
                        current.extend(after.pairs.iter().copied());
                        complete = after.is_complete();
                    }
                }
                Err(why) => {
                    saved.restore(set, &mut pins, &mut orders);
                    stuck.insert(key, why);
                    failed_at.insert(key, iterations);
                }
            }
        }
    }
    // The report's pairs from a full detection; the input back if the result is
    // worse on either count (each kept retiming made things better, so this is a
    // safety net).
    let mut after = detect(set, params.threshold_m)?;
    let closest = |c: &Collisions| c.closest().map(|q| q.closest.distance_m);
    let worse = after.pair_count() > pairs_before
        || match (closest(&after), closest_before_m) {
            (Some(a), Some(b)) => a < b,
            (Some(_), None) => true,
            _ => false,
        };
    if worse {
        for (t, t0) in set.tracks.iter_mut().zip(&original) {
            t.times_s.clone_from(t0);
        }
        after = detect(set, params.threshold_m)?;
    }
    let remaining = remaining_of(set, &after, &in_cluster, &stuck);
    let mut total_abs_dt_s = 0.0;
    let mut max_speed_change_pct: f64 = 0.0;
    let mut shifts: Vec<f64> = Vec::new();
    for (tr, t0) in set.tracks.iter().zip(&original) {
        total_abs_dt_s += tr
            .times_s
            .iter()
            .zip(t0)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>();
        let shift = largest_shift(&tr.times_s, t0);
        if shift > 0.0 {
            shifts.push(shift);
        }
        for j in tr.segments() {
            if (tr.points[j + 1] - tr.points[j]).norm() < MIN_PACE_LENGTH_M {
                continue;
            }
            let ratio = (t0[j + 1] - t0[j]) / (tr.times_s[j + 1] - tr.times_s[j]);
            max_speed_change_pct = max_speed_change_pct.max((ratio - 1.0).abs() * 100.0);
        }
    }
    shifts.sort_by(f64::total_cmp);
    let median_shift_s = match shifts.len() {
        0 => 0.0,
        k if k % 2 == 1 => shifts[k / 2],
        k => 0.5 * (shifts[k / 2 - 1] + shifts[k / 2]),
    };
    let companions = remaining
        .iter()
        .filter(|r| r.why == Stuck::Companions)
        .count();
    Ok(AvoidReport {
        iterations,
        pairs_before,
        pairs_after: after.pair_count(),
        retimings,
        remaining,
        total_abs_dt_s,
        max_speed_change_pct,
        corrections,
        people_in_collision,
        retimed_people: shifts.len(),
        median_shift_s,
        max_shift_s: shifts.last().copied().unwrap_or(0.0),
        max_shift_bound_s: params.max_shift_s,
        companions,
        undone,
        closest_before_m,
        closest_after_m: closest(&after),
        reverted: worse,
        shifts: shifts_kept,
    })
}

/// Makes a rigid shift: every time of the group, its pins and its schedule move
/// by `dt_s`.
fn apply_shift(
    set: &mut TrackSet,
    base: &mut [Vec<f64>],
    pins: &mut [Vec<(usize, f64)>],
    sh: &shift::Shift,
) {
    for &k in &sh.group {
        for t in &mut set.tracks[k].times_s {
            *t += sh.dt_s;
        }
        for t in &mut base[k] {
            *t += sh.dt_s;
        }
        for pin in &mut pins[k] {
            pin.1 += sh.dt_s;
        }
    }
}

/// After `group` changed: their pairs in `current` replaced by a detection of
/// theirs (when the list is whole; otherwise the next round detects everything).
fn refresh(
    set: &TrackSet,
    boxes: &[(crate::geom::Vec2, crate::geom::Vec2)],
    p: &AvoidParams,
    group: &[usize],
    current: &mut Vec<PairCollision>,
    complete: &mut bool,
) -> Result<(), AvoidError> {
    if !*complete {
        return Ok(());
    }
    let found = shift::involving_near(set, boxes, group, p.threshold_m)?;
    current.retain(|q| !(who_has(group, q.a) || who_has(group, q.b)));
    current.extend(found.pairs.iter().copied());
    *complete = found.is_complete();
    Ok(())
}

/// After a rigid shift: when it left the group no pair with anyone outside (its
/// evaluation is exact), those pairs are dropped from `current` without a
/// detection (pairs inside the group do not change); else as [`refresh`].
fn refresh_after_shift(
    set: &TrackSet,
    boxes: &[(crate::geom::Vec2, crate::geom::Vec2)],
    p: &AvoidParams,
    sh: &shift::Shift,
    current: &mut Vec<PairCollision>,
    complete: &mut bool,
) -> Result<(), AvoidError> {
    if sh.pairs_left == 0 {
        current.retain(|q| who_has(&sh.group, q.a) == who_has(&sh.group, q.b));
        // Pairs inside the group meet dt later (or earlier), at the same places.
        for q in current.iter_mut() {
            if who_has(&sh.group, q.a) {
                q.closest.t_s += sh.dt_s;
            }
        }
        return Ok(());
    }
    refresh(set, boxes, p, &sh.group, current, complete)
}

/// The two people of a pair as a sorted group.
fn pair_of(q: &PairCollision) -> [usize; 2] {
    [q.a.min(q.b), q.a.max(q.b)]
}

fn who_has(group: &[usize], k: usize) -> bool {
    group.binary_search(&k).is_ok()
}

/// The pairs that still collide, and why: each cluster once (its first two
/// members), then the kept pairs.
fn remaining_of(
    set: &TrackSet,
    after: &Collisions,
    in_cluster: &[bool],
    stuck: &HashMap<(usize, usize), Stuck>,
) -> Vec<Remaining> {
    let mut out: Vec<Remaining> = after
        .clusters
        .iter()
        .map(|c| Remaining {
            pair: PairCollision {
                a: c.members[0],
                b: c.members[1],
                id_a: c.first_id,
                id_b: set.tracks[c.members[1]].id,
                closest: Approach {
                    t_s: c.start_s,
                    distance_m: 0.0,
                    at_a: c.place,
                    at_b: c.place,
                    sample_a: 0,
                    sample_b: 0,
                    moving_a: false,
                    moving_b: false,
                },
                events: 1,
            },
            why: Stuck::Cluster,
        })
        .collect();
    out.extend(after.pairs.iter().map(|q| Remaining {
        pair: *q,
        why: if in_cluster[q.a] || in_cluster[q.b] {
            Stuck::Cluster
        } else {
            stuck
                .get(&(q.a, q.b))
                .copied()
                .unwrap_or(Stuck::IterationLimit)
        },
    }));
    out
}

#[cfg(test)]
#[path = "avoid_tests.rs"]
mod tests;
