//! The parameters, errors and report of collision avoidance by retiming
//! (crowd-motion-editing section 4.1.2; the method is in `avoid.rs`).

use super::collide::{CollideError, PairCollision};
use thiserror::Error;

/// Speeds below this (m/s) count as standing still in eq. 20.
pub const STILL_SPEED_M_S: f64 = 1e-6;

/// Segments shorter than this (metres) have no pace in eq. 24 (it divides by the
/// length) and no speed in [`AvoidReport::max_speed_change_pct`].
pub const MIN_PACE_LENGTH_M: f64 = 1e-6;

/// The most the separation time may exceed eq. 22's estimate (see [`avoid`](super::avoid())).
pub const MAX_DT_FACTOR: f64 = 10.0;

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

/// Bad input to [`avoid`](super::avoid()).
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

/// Why a pair still collides after [`avoid`](super::avoid()).
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

/// What [`avoid`](super::avoid()) did.
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

pub(super) fn check_params(p: &AvoidParams) -> Result<(), AvoidError> {
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
