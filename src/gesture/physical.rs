//! Features that survive drawing style: what eq. 2's normalisation throws away (the
//! gesture's size on the glass, whether its fingers form one hand or two) and what
//! eqs. 4–10 average away (whether the fingers move together, how much each finger's
//! own path turns), as one short vector per gesture (issue 28, item 1).
//!
//! The paper's four features (section 5.2) are sequences in normalised units: a
//! two-finger pinch and a join drawn with one finger per hand are the same gesture
//! once eq. 2 has scaled both to the unit square, and a one-finger spiral of two
//! turns has a centroid path that warps onto a bowed stroke. The features here are
//! computed on the resampled gesture (eq. 3) *before* the scaling of eq. 2 where they
//! need millimetres (the scale is kept with every library gesture), so a library
//! gesture and a drawn one are measured the same way:
//!
//! | k | feature | what it tells apart |
//! |---|---|---|
//! | 0 | `ln((span₀ + 10 mm) / 60 mm)`, span = largest finger distance, first 10 % | join (hands far) from contract (one hand) |
//! | 1 | the same over the last 10 % | split from expand |
//! | 2 | `ln((gap + 10 mm) / 60 mm)`, gap = longest edge of the fingers' minimum spanning tree when they are most spread | one hand from two |
//! | 3 | `ln((S(T/2) + ε) / (S(0) + ε))`, S the spread (eq. 7), ε = 2 % of the extent | spreading or converging, first half |
//! | 4 | the same from T/2 to the end | … second half (translate then join) |
//! | 5 | coherence of the first half: `Σ_t │mean_i v_i(t)│² / Σ_t mean_i │v_i(t)│²` | translate (1) from pinch, split (≈ 0) |
//! | 6 | coherence of the second half | split then translate |
//! | 7 | `│R(T)│ / 2π`: the fingers' turning about their centroid (eq. 9), turns; 0 for one finger | twist |
//! | 8 | the mean over fingers of `min(│Σ turning of its own path│ / 2π, ½)`, turns | a one-finger circle or spiral from a stroke |
//! | 9 | 1 for one finger, else 0 | one finger from several |
//! | 10 | the smallest over finger pairs down together of `│ln((d_end + 5 mm) / (d_start + 5 mm))│`, d the pair's distance at the start and end of the time both are down; unknown for one finger | expand (every pair spreads) from split (the fingers of a hand keep their distance) |
//! | 11 | the share of finger pairs that keep their distance, `Σ w exp(−(c / 0.15)²) / Σ w` over the pairs of feature 10, c their log change, w the time both are down; unknown for one finger | one rigid hand or two from a hand that opens or closes |
//! | 12 | `max(0, ln(span₀ / 150 mm))`: how far the fingers start beyond one hand's reach | two hands apart (join) from a pinch, also with two fingers |
//! | 13 | the same for the end span | split from expand |
//!
//! Each is dimensionless and of order 1, so one weight per feature sets its share of
//! the distance ([`PhysicalWeights`]). Features 0–2 and 12–13 need the scale;
//! without it (a library file of format version 1) they are NaN and left out of the
//! distance, and features 10–11 fall back to a floor of 2 % of the extent.
//!
//! # Why these generalise across drawing styles (issue 28)
//!
//! Two generators drawing the same classes with different conventions of motion
//! (`gesture::synth`, `gesture::style2`) disagree on sizes, timing and on what the
//! fingers do besides the gesture; what they agree on is what the class *is*. The
//! features are chosen and shaped to measure that and to saturate beyond it:
//!
//! - **Turning saturates at half a turn** (feature 8): the conventions draw a
//!   one-finger twist as 0.5–2 turns, a bowed stroke turns a sixth of a turn or
//!   less; how many turns beyond the first half is the drawer's style. Without the
//!   cap a two-turn spiral is nearer a stroke than a 0.6-turn arc.
//! - **A finger counts only while it is down** (features 10, 11): a finger that
//!   lifts early holds its last position in the resampled gesture, one that lands
//!   late its first, and a finger lifted and landed again is two tracks. Compared
//!   over the whole gesture such a pair looks rigid (neither moves); compared over
//!   the time both are down (a held position is an exactly repeated point), it
//!   shows what the hand did. Pairs down together for less than half the gesture
//!   are left out.
//! - **Rigid pairs, not spans, tell one hand from two** (features 10, 11): a
//!   hand's own fingers keep their distance in a join or a split, every pair
//!   closes in a pinch and opens in an expand — whatever the sizes. With two
//!   fingers (one pair, which closes in a join as in a pinch) only the reach
//!   below can tell.
//! - **Beyond a hand's reach** (features 12, 13): a thumb and finger open at most
//!   about 150 mm; two fingers further apart are two hands. Below that the span
//!   says nothing (0), so sizes that differ between drawers inside one hand do not
//!   count.
//!
//! The distance used for search is `w₁₂ · D₁₂ + Σ_k w_k │a_k − b_k│` (eq. 12 times a
//! weight, plus a weighted L1 over this vector): a sum of non-negative terms, so the
//! pruned search of `knn.rs` stays exact with the L1 part added to every bound.

use super::library::{Resampled, T_H};
use crate::geom::{cross, Vec2};
use std::f64::consts::TAU;

/// Length of the physical feature vector.
pub const PHYSICAL_DIM: usize = 14;

/// The feature names, in vector order (for reports).
pub const PHYSICAL_NAMES: [&str; PHYSICAL_DIM] = [
    "span_start",
    "span_end",
    "hand_gap",
    "spread_first",
    "spread_second",
    "coherence_first",
    "coherence_second",
    "rotation",
    "path_turning",
    "one_finger",
    "pair_change",
    "rigid_pairs",
    "reach_start",
    "reach_end",
];

/// Added to spans and gaps before their logarithm (mm): one finger has span 0.
pub const SPAN_FLOOR_MM: f64 = 10.0;

/// The span and gap a log feature is measured against (mm): `ln(1) = 0` at a wide
/// hand.
pub const SPAN_REFERENCE_MM: f64 = 60.0;

/// Added to the spread (normalised units, a fraction of the gesture's extent) before
/// the ratio of features 3 and 4: a spread from nothing is large but finite.
pub const SPREAD_FLOOR: f64 = 0.02;

/// Largest magnitude of a spread change (features 3, 4; natural log).
pub const SPREAD_CHANGE_CLAMP: f64 = 2.5;

/// A one-finger step shorter than this (normalised units: 3 % of the gesture's
/// extent) is merged into the next (feature 8): a finger at rest has no heading,
/// and the slow steps where a stroke reverses become one cusp.
pub const TURN_MIN_STEP: f64 = 0.03;

/// A one-finger step turning more than this (rad) from the previous one is a cusp
/// (a stroke that reverses, a drag up and down), not a curve: it turns nothing
/// (feature 8). A circle sampled at 64 steps turns a few degrees per step.
pub const CUSP_RAD: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

/// Largest turning counted (feature 7; turns).
pub const TURNS_CLAMP: f64 = 2.5;

/// Largest turning of a finger's own path counted (feature 8; turns): the
/// conventions' one-finger twist is at least half a turn (module doc).
pub const PATH_TURNS_SATURATE: f64 = 0.5;

/// Added to a finger pair's distance before the log change of features 10 and 11
/// (mm): two fingers landing together do not make a change from nothing infinite.
pub const PAIR_FLOOR_MM: f64 = 5.0;

/// A pair's log distance change under which it counts as rigid (feature 11): the
/// share `exp(−(c / PAIR_RIGID)²)`; a pinch closing to 45 % changes by 0.8.
pub const PAIR_RIGID: f64 = 0.15;

/// Pairs down together for less than this share of the gesture are left out of
/// features 10 and 11.
pub const PAIR_MIN_OVERLAP: f64 = 0.5;

/// One hand's reach (mm): features 12 and 13 measure the span beyond it. A thumb
/// and index finger open to about 150 mm comfortably; further apart, more and more
/// likely two hands (a large hand stretched to its limit reaches about 190 mm, and
/// with five fingers 240: `synth::HAND_SPAN_MM`, `synth::REACH_SHARE`). Scaling
/// this reach with the finger count was tried (2–5 fingers: 150–188 mm) and left
/// the cross-style figures within ±0.6 % over seeds 27–33, so it stays one number.
pub const HAND_REACH_MM: f64 = 150.0;

/// A gesture's physical features (module doc); NaN where a feature is unknown.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PhysicalFeatures {
    /// The values, in the order of [`PHYSICAL_NAMES`].
    pub values: [f64; PHYSICAL_DIM],
}

impl Default for PhysicalFeatures {
    /// Every feature unknown: contributes nothing to a distance.
    fn default() -> PhysicalFeatures {
        PhysicalFeatures {
            values: [f64::NAN; PHYSICAL_DIM],
        }
    }
}

/// The weights of the combined distance (module doc).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PhysicalWeights {
    /// The weight of eq. 12's distance.
    pub eq12: f64,
    /// One weight per physical feature.
    pub features: [f64; PHYSICAL_DIM],
}

impl PhysicalWeights {
    /// Eq. 12 alone: the paper's recogniser, the baseline.
    pub const BASELINE: PhysicalWeights = PhysicalWeights {
        eq12: 1.0,
        features: [0.0; PHYSICAL_DIM],
    };

    /// Whether any physical feature has weight.
    pub fn uses_features(&self) -> bool {
        self.features.iter().any(|&w| w > 0.0)
    }

    /// The weighted L1 distance between two feature vectors, unknown features left
    /// out.
    ///
    /// ```
    /// use crowdtouch::gesture::physical::{PhysicalFeatures, PhysicalWeights, PHYSICAL_DIM};
    /// let mut w = PhysicalWeights::BASELINE;
    /// w.features[3] = 2.0;
    /// let mut a = PhysicalFeatures { values: [0.0; PHYSICAL_DIM] };
    /// let b = a;
    /// a.values[3] = 0.5;
    /// a.values[0] = f64::NAN;
    /// assert_eq!(w.distance(&a, &b), 1.0);
    /// ```
    pub fn distance(&self, a: &PhysicalFeatures, b: &PhysicalFeatures) -> f64 {
        let mut d = 0.0;
        for k in 0..PHYSICAL_DIM {
            let w = self.features[k];
            if w == 0.0 {
                continue;
            }
            let x = (a.values[k] - b.values[k]).abs();
            if x.is_finite() {
                d += w * x;
            }
        }
        d
    }
}

impl Default for PhysicalWeights {
    /// The weights fitted across drawing styles: `crowdtouch library eval
    /// --cross-style --fit` (coordinate search maximising the worst of the four
    /// cross-style figures on the six basic classes — leave-one-out on each
    /// generator, each generator's set classified against the other's — plus a tenth
    /// of their mean, on sets of seed 29; never on recordings) finds no change that
    /// raises it; see docs/gestures.md.
    ///
    /// What came out, and why: eq. 12 gets weight 0 — its sequences carry each
    /// generator's timing and proportions, and across styles they pull a gesture
    /// towards the same drawer's gestures of other classes (with any weight on eq.
    /// 12 the worse cross-style accuracy drops); the hand gap and the end span get 0
    /// (the generators disagree on how wide a hand is, and the reach beyond a hand
    /// and the rigid pairs say what they would); the pair features carry the most
    /// weight, as they are what one hand and two hands differ in.
    fn default() -> PhysicalWeights {
        FITTED_WEIGHTS
    }
}

/// The fitted weights of [`PhysicalWeights::default`].
pub const FITTED_WEIGHTS: PhysicalWeights = PhysicalWeights {
    eq12: 0.0,
    features: [
        0.125, 0.0, 0.0, 1.2, 1.2, 0.27, 0.8, 1.0, 0.67, 0.3, 1.8, 1.0, 1.5, 0.75,
    ],
};

impl PhysicalFeatures {
    /// The features of a resampled gesture whose eq. 2 scale was `scale_mm` (the
    /// larger side of its bounding box on the glass; `None` when unknown: features
    /// 0–2 are then NaN).
    ///
    /// # Formula
    ///
    /// See the module doc's table. Positions in millimetres are `p · scale_mm` (eq. 2
    /// undone up to a translation, which no feature sees). Velocities are the
    /// differences of consecutive resampled points (eq. 3's common time axis).
    ///
    /// # Complexity
    ///
    /// `O(T_H · N²)` for `N` fingers (the spanning tree at one step, spans at twelve).
    ///
    /// ```
    /// use crowdtouch::geom::Vec2;
    /// use crowdtouch::gesture::library::{Resampled, T_H};
    /// use crowdtouch::gesture::physical::PhysicalFeatures;
    /// // Two fingers 1.0 apart closing to 0.2, on a gesture 50 mm wide: a pinch.
    /// let s = |k: usize| k as f64 / (T_H - 1) as f64;
    /// let g = Resampled { fingers: vec![
    ///     std::array::from_fn(|k| Vec2::new(0.4 * s(k), 0.5)),
    ///     std::array::from_fn(|k| Vec2::new(1.0 - 0.4 * s(k), 0.5))] };
    /// let f = PhysicalFeatures::of(&g, Some(50.0)).values;
    /// assert!(f[0] < 0.0 && f[1] < f[0]);        // 50 mm, then 10 mm
    /// assert!(f[3] < 0.0 && f[4] < 0.0);          // converging
    /// assert!(f[5] < 1e-9 && f[7] < 1e-9);       // not together, no turning
    /// ```
    pub fn of(g: &Resampled, scale_mm: Option<f64>) -> PhysicalFeatures {
        let mut v = [f64::NAN; PHYSICAL_DIM];
        let n = g.fingers.len();
        if n == 0 {
            return PhysicalFeatures { values: v };
        }
        let centroid = |t: usize| g.fingers.iter().map(|p| p[t]).sum::<Vec2>() / n as f64;
        let spread = |t: usize| {
            let c = centroid(t);
            g.fingers.iter().map(|p| (p[t] - c).norm()).sum::<f64>() / n as f64
        };
        let span = |t: usize| {
            let mut m = 0.0f64;
            for i in 0..n {
                for j in i + 1..n {
                    m = m.max((g.fingers[i][t] - g.fingers[j][t]).norm());
                }
            }
            m
        };
        let scale = scale_mm.filter(|s| s.is_finite() && *s > 0.0);
        if let Some(scale) = scale {
            let edge = T_H / 10;
            let mean_span = |r: std::ops::Range<usize>| {
                let len = r.len() as f64;
                r.map(span).sum::<f64>() / len * scale
            };
            let log = |mm: f64| ((mm + SPAN_FLOOR_MM) / SPAN_REFERENCE_MM).ln();
            let (start_mm, end_mm) = (mean_span(0..edge), mean_span(T_H - edge..T_H));
            v[0] = log(start_mm);
            v[1] = log(end_mm);
            let reach = |mm: f64| (mm / HAND_REACH_MM).ln().max(0.0);
            v[12] = reach(start_mm);
            v[13] = reach(end_mm);
            let widest = (0..T_H)
                .max_by(|&a, &b| span(a).total_cmp(&span(b)))
                .unwrap_or(0);
            v[2] = log(longest_tree_edge(g, widest) * scale);
        }
        let change = |a: f64, b: f64| {
            ((b + SPREAD_FLOOR) / (a + SPREAD_FLOOR))
                .ln()
                .clamp(-SPREAD_CHANGE_CLAMP, SPREAD_CHANGE_CLAMP)
        };
        let (s0, s_mid, s_end) = (spread(0), spread(T_H / 2), spread(T_H - 1));
        v[3] = change(s0, s_mid);
        v[4] = change(s_mid, s_end);
        v[5] = coherence(g, 1..T_H / 2 + 1);
        v[6] = coherence(g, T_H / 2 + 1..T_H);
        v[7] = if n == 1 {
            0.0
        } else {
            (rotation_about_centroid(g) / TAU).abs().min(TURNS_CLAMP)
        };
        v[8] = g
            .fingers
            .iter()
            .map(|p| (path_turning(p) / TAU).abs().min(PATH_TURNS_SATURATE))
            .sum::<f64>()
            / n as f64;
        v[9] = if n == 1 { 1.0 } else { 0.0 };
        // Pair distances in mm (normalised units without a scale).
        let floor = scale.map_or(SPREAD_FLOOR, |s| PAIR_FLOOR_MM / s);
        if let Some((least, rigid)) = pair_changes(g, floor) {
            v[10] = least;
            v[11] = rigid;
        }
        PhysicalFeatures { values: v }
    }
}

/// The steps `[first, last]` over which finger `p` is down: from the step before its
/// first move to its last move. The resampled gesture holds a finger that has not
/// landed yet, or has lifted, on exactly its first or last point (eq. 3 on the
/// common time axis), so those steps repeat a point exactly. A finger that never
/// moves is down throughout.
fn down_steps(p: &[Vec2; T_H]) -> (usize, usize) {
    let moves = |t: &usize| p[*t + 1] != p[*t];
    match ((0..T_H - 1).find(moves), (0..T_H - 1).rev().find(moves)) {
        (Some(a), Some(b)) => (a, b + 1),
        _ => (0, T_H - 1),
    }
}

/// Features 10 and 11 (module doc): over the finger pairs down together for at
/// least [`PAIR_MIN_OVERLAP`] of the gesture, the smallest `│ln((d_end + floor) /
/// (d_start + floor))│` (capped at [`SPREAD_CHANGE_CLAMP`]), and the share of rigid
/// pairs weighted by their time together; `d_start` and `d_end` are the pair's mean
/// distance over the first and last tenth of that time. `None` for one finger or
/// without such a pair.
fn pair_changes(g: &Resampled, floor: f64) -> Option<(f64, f64)> {
    let n = g.fingers.len();
    if n < 2 {
        return None;
    }
    let down: Vec<(usize, usize)> = g.fingers.iter().map(down_steps).collect();
    let (mut least, mut rigid, mut total) = (f64::INFINITY, 0.0, 0.0);
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (down[i].0.max(down[j].0), down[i].1.min(down[j].1));
            if b < a || ((b - a) as f64) < PAIR_MIN_OVERLAP * (T_H - 1) as f64 {
                continue;
            }
            let e = ((b - a) / 10).max(1);
            let d = |r: std::ops::RangeInclusive<usize>| {
                let len = (r.end() - r.start() + 1) as f64;
                r.map(|t| (g.fingers[i][t] - g.fingers[j][t]).norm())
                    .sum::<f64>()
                    / len
            };
            let c = ((d(b + 1 - e..=b) + floor) / (d(a..=a + e - 1) + floor)).ln();
            least = least.min(c.abs());
            let w = (b - a) as f64;
            rigid += w * (-(c / PAIR_RIGID).powi(2)).exp();
            total += w;
        }
    }
    (total > 0.0).then(|| (least.min(SPREAD_CHANGE_CLAMP), rigid / total))
}

/// The longest edge of the minimum spanning tree of the fingers at step `t`
/// (normalised units; Prim's algorithm, `O(N²)`); 0 for one finger.
fn longest_tree_edge(g: &Resampled, t: usize) -> f64 {
    let n = g.fingers.len();
    let mut in_tree = [false; crate::gesture::track::MAX_GESTURE_FINGERS];
    let mut best = [f64::INFINITY; crate::gesture::track::MAX_GESTURE_FINGERS];
    let n = n.min(in_tree.len());
    if n < 2 {
        return 0.0;
    }
    in_tree[0] = true;
    for (j, b) in best.iter_mut().enumerate().take(n).skip(1) {
        *b = (g.fingers[0][t] - g.fingers[j][t]).norm();
    }
    let mut longest = 0.0f64;
    for _ in 1..n {
        let Some(next) = (0..n)
            .filter(|&j| !in_tree[j])
            .min_by(|&a, &b| best[a].total_cmp(&best[b]))
        else {
            break;
        };
        longest = longest.max(best[next]);
        in_tree[next] = true;
        for j in 0..n {
            if !in_tree[j] {
                best[j] = best[j].min((g.fingers[next][t] - g.fingers[j][t]).norm());
            }
        }
    }
    longest
}

/// How much the fingers move together over the steps `range` (each step `t` is the
/// move from `t − 1`): `Σ_t │mean_i v_i│² / Σ_t mean_i │v_i│²`, in `[0, 1]` (1 for
/// one finger, and when nothing moves).
fn coherence(g: &Resampled, range: std::ops::Range<usize>) -> f64 {
    let n = g.fingers.len() as f64;
    let (mut common, mut total) = (0.0, 0.0);
    for t in range {
        let mut mean = Vec2::zeros();
        let mut sq = 0.0;
        for p in &g.fingers {
            let v = p[t] - p[t - 1];
            mean += v;
            sq += v.norm_squared();
        }
        mean /= n;
        common += mean.norm_squared();
        total += sq / n;
    }
    if total <= 1e-18 {
        1.0
    } else {
        (common / total).clamp(0.0, 1.0)
    }
}

/// Eq. 9 summed over the gesture: the mean turning of the fingers about their
/// centroid (rad, signed).
fn rotation_about_centroid(g: &Resampled) -> f64 {
    let n = g.fingers.len() as f64;
    let c = |t: usize| g.fingers.iter().map(|p| p[t]).sum::<Vec2>() / n;
    let mut total = 0.0;
    for t in 1..T_H {
        let (ct, cp) = (c(t), c(t - 1));
        for p in &g.fingers {
            let (u, w) = (p[t] - ct, p[t - 1] - cp);
            if u.norm() > 1e-9 && w.norm() > 1e-9 {
                total += cross(u, w).atan2(u.dot(&w));
            }
        }
    }
    total / n
}

/// The signed turning of one finger's own path (rad): the angles between its
/// consecutive steps, steps shorter than [`TURN_MIN_STEP`] merged into the next,
/// cusps (turns beyond [`CUSP_RAD`]) left out.
fn path_turning(p: &[Vec2; T_H]) -> f64 {
    let mut total = 0.0;
    let mut heading: Option<Vec2> = None;
    let mut from = p[0];
    for &q in &p[1..] {
        let d = q - from;
        if d.norm() < TURN_MIN_STEP {
            continue;
        }
        if let Some(h) = heading {
            let turn = cross(d, h).atan2(d.dot(&h));
            if turn.abs() <= CUSP_RAD {
                total += turn;
            }
        }
        heading = Some(d);
        from = q;
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn finger(f: impl Fn(f64) -> Vec2) -> [Vec2; T_H] {
        std::array::from_fn(|k| f(k as f64 / (T_H - 1) as f64))
    }

    #[test]
    fn a_translate_is_coherent_and_does_not_turn() {
        let g = Resampled {
            fingers: (0..3)
                .map(|i| finger(move |s| Vec2::new(s, 0.1 * i as f64)))
                .collect(),
        };
        let f = PhysicalFeatures::of(&g, Some(200.0)).values;
        assert!((f[5] - 1.0).abs() < 1e-12 && (f[6] - 1.0).abs() < 1e-12);
        assert!(f[3].abs() < 1e-12 && f[4].abs() < 1e-12);
        assert!(f[7].abs() < 1e-9 && f[8].abs() < 1e-9);
        // Three fingers 20 mm apart (0.1 of 200 mm): one hand.
        assert!(
            (f[2] - ((20.0 + 10.0) / 60.0f64).ln()).abs() < 1e-9,
            "{}",
            f[2]
        );
        assert_eq!(f[9], 0.0);
    }

    #[test]
    fn two_hands_have_a_wide_gap_and_one_hand_a_narrow_one() {
        // Two pairs of fingers, 20 mm within a pair, pairs 300 mm apart (split).
        let pair = |x0: f64, dx: f64| {
            vec![
                finger(move |s| Vec2::new(x0 + dx * s, 0.5)),
                finger(move |s| Vec2::new(x0 + dx * s, 0.5 + 0.05)),
            ]
        };
        let mut fingers = pair(0.3, -0.3);
        fingers.extend(pair(0.5, 0.5));
        let g = Resampled { fingers };
        let f = PhysicalFeatures::of(&g, Some(400.0)).values;
        // Most spread at the end: 1.0 · 400 mm between the pairs' closest fingers.
        assert!(
            (f[2] - ((400.0 + 10.0) / 60.0f64).ln()).abs() < 1e-9,
            "{}",
            f[2]
        );
        assert!(f[3] > 0.5 && f[5] < 0.2);
        // Without a scale the physical sizes are unknown.
        let u = PhysicalFeatures::of(&g, None).values;
        assert!(u[0].is_nan() && u[1].is_nan() && u[2].is_nan());
        assert!(u[12].is_nan() && u[13].is_nan());
        assert_eq!(u[3..10], f[3..10]);
        // Two rigid pairs of six.
        assert!((f[11] - 1.0 / 3.0).abs() < 0.01 && f[10] < 1e-9, "{f:?}");
    }

    #[test]
    fn a_spiral_of_one_finger_turns_and_a_line_does_not() {
        let spiral = Resampled {
            fingers: vec![finger(|s| {
                let a = 1.5 * TAU * s;
                let r = 0.1 + 0.4 * s;
                Vec2::new(0.5 + r * a.cos(), 0.5 - r * a.sin())
            })],
        };
        let f = PhysicalFeatures::of(&spiral, Some(100.0)).values;
        // One and a half turns count as half a turn: a circle's arc either way.
        assert_eq!(f[8], PATH_TURNS_SATURATE);
        assert!((path_turning(&spiral.fingers[0]) / TAU - 1.5).abs() < 0.05);
        assert_eq!((f[7], f[9]), (0.0, 1.0));
        assert_eq!((f[5], f[6]), (1.0, 1.0));
        let bowed = Resampled {
            fingers: vec![finger(|s| Vec2::new(s, 0.2 * (PI * s).sin()))],
        };
        let b = PhysicalFeatures::of(&bowed, Some(100.0)).values;
        // A bow turns from +atan(0.2π) to −atan(0.2π): about a sixth of a turn.
        let want = 2.0 * (0.2 * PI).atan() / TAU;
        assert!((b[8] - want).abs() < 0.01, "{} vs {want}", b[8]);
    }

    #[test]
    fn a_drag_up_and_down_is_a_cusp_not_a_turn() {
        let g = Resampled {
            fingers: vec![finger(|s| Vec2::new(0.5, 1.0 - (2.0 * s - 1.0).abs()))],
        };
        let f = PhysicalFeatures::of(&g, Some(100.0)).values;
        assert!(f[8] < 0.01, "{}", f[8]);
    }

    #[test]
    fn turning_fingers_count_their_rotation_in_turns() {
        let turn = |phase: f64| {
            finger(move |s| {
                let a = phase + 0.75 * TAU * s;
                Vec2::new(0.5 + 0.4 * a.cos(), 0.5 - 0.4 * a.sin())
            })
        };
        let g = Resampled {
            fingers: vec![turn(0.0), turn(PI)],
        };
        let f = PhysicalFeatures::of(&g, Some(80.0)).values;
        assert!((f[7] - 0.75).abs() < 1e-9, "{}", f[7]);
        assert!(f[5] < 1e-9, "{}", f[5]);
    }

    #[test]
    fn a_pinch_has_no_rigid_pair_and_a_join_of_two_rigid_hands_has() {
        // A pinch: three fingers closing to a third of their distances.
        let at =
            |x: f64, y: f64, to: f64| finger(move |s| Vec2::new(x, y) * (1.0 - (1.0 - to) * s));
        let pinch = Resampled {
            fingers: vec![at(0.0, 0.5, 0.33), at(0.4, 0.0, 0.33), at(0.5, 0.1, 0.33)],
        };
        let p = PhysicalFeatures::of(&pinch, Some(120.0)).values;
        assert!(p[10] > 0.5 && p[11] < 0.01, "{p:?}");
        // A join: a hand of two fingers 20 mm apart and a hand of one, 300 mm apart
        // closing to 60 mm.
        let hand = |x0: f64, dx: f64, y: f64| finger(move |s| Vec2::new(x0 + dx * s, y));
        let join = Resampled {
            fingers: vec![
                hand(0.0, 0.4, 0.5),
                hand(0.0, 0.4, 0.5 + 20.0 / 300.0),
                hand(1.0, -0.4, 0.5),
            ],
        };
        let j = PhysicalFeatures::of(&join, Some(300.0)).values;
        assert!(j[10] < 1e-9, "{j:?}");
        assert!((j[11] - 1.0 / 3.0).abs() < 0.05, "{j:?}");
        // 300 mm apart at the start: beyond one hand's reach; 60 mm at the end: not.
        // (The start span is the mean over the first tenth, the hands already moving.)
        assert!(
            (j[12] - (300.0f64 / HAND_REACH_MM).ln()).abs() < 0.05,
            "{j:?}"
        );
        assert_eq!(j[13], 0.0);
        assert_eq!(p[12], 0.0);
    }

    #[test]
    fn a_finger_counts_only_while_it_is_down() {
        // Three fingers closing in a pinch; one lifts at 60 % of the gesture and
        // holds its last point, another lands at 40 % and held its first.
        let closing = |x: f64, y: f64| finger(move |s| Vec2::new(x, y) * (1.0 - 0.7 * s));
        let (lift, land) = (T_H * 6 / 10, T_H * 4 / 10);
        let mut early = closing(0.0, 0.5);
        for t in lift..T_H {
            early[t] = early[lift];
        }
        let mut late = closing(0.5, 0.1);
        for t in 0..land {
            late[t] = late[land];
        }
        assert_eq!(down_steps(&early), (0, lift));
        assert_eq!(down_steps(&late), (land, T_H - 1));
        let g = Resampled {
            fingers: vec![early, closing(0.4, 0.0), late],
        };
        // The early and the late finger were down together for a fifth of the
        // gesture (over the whole of it their distance hardly changes: each is
        // held while the other moves): left out; the pairs down together long
        // enough close.
        let f = PhysicalFeatures::of(&g, Some(100.0)).values;
        assert!(f[10] > 0.3 && f[11] < 0.05, "{f:?}");
        // One finger has no pair.
        let one = Resampled {
            fingers: vec![closing(0.3, 0.3)],
        };
        let o = PhysicalFeatures::of(&one, Some(100.0)).values;
        assert!(o[10].is_nan() && o[11].is_nan());
    }

    #[test]
    fn the_distance_skips_unknown_features_and_baseline_has_none() {
        let a = PhysicalFeatures {
            values: [1.0; PHYSICAL_DIM],
        };
        let b = PhysicalFeatures::default();
        assert_eq!(FITTED_WEIGHTS.distance(&a, &b), 0.0);
        assert_eq!(
            PhysicalWeights::BASELINE.distance(
                &a,
                &PhysicalFeatures {
                    values: [0.0; PHYSICAL_DIM]
                }
            ),
            0.0
        );
        assert!(!PhysicalWeights::BASELINE.uses_features());
        assert!(FITTED_WEIGHTS.uses_features());
    }
}
