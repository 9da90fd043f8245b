//! Dynamic time warping between feature sequences, its lower bounds, and the weighted
//! gesture distance of gesture-driven eq. 12.
//!
//! The DTW is defined exactly as the `dtaidistance` package defines it (checked by
//! `benches/dtw_crosscheck.py`): the square root of the smallest sum of squared
//! Euclidean point differences over the warping paths from `(0, 0)` to
//! `(n − 1, m − 1)` with steps `(1, 0)`, `(0, 1)`, `(1, 1)`. A Sakoe–Chiba band of
//! radius `r` allows cell `(i, j)` when `|i − j| ≤ r` for sequences of equal length
//! (`dtaidistance`'s `window = r + 1`; for unequal lengths the band is widened by the
//! difference on the longer side, as there).
//!
//! The lower bounds, each `≤` that DTW for the same band:
//! - LB_Kim (first and last points): every path holds `(0, 0)` and `(n − 1, m − 1)`.
//! - LB_Keogh: every path visits each row `i`, at a column inside the band, so
//!   `a_i`'s distance to the band's envelope of `b` (per coordinate) is a floor for
//!   that row's term. Unbanded, the envelope is `b`'s global minimum and maximum.

use super::features::GestureFeatures;

/// A point of a DTW sequence: a scalar or a 2-D vector.
pub trait DtwPoint: Copy {
    /// Coordinates of the point.
    const DIM: usize;
    /// Coordinate `k` (`k < DIM`).
    fn coord(&self, k: usize) -> f64;
    /// Squared Euclidean distance.
    fn sq_dist(&self, other: &Self) -> f64;
}

impl DtwPoint for f64 {
    const DIM: usize = 1;
    #[inline]
    fn coord(&self, _: usize) -> f64 {
        *self
    }
    #[inline]
    fn sq_dist(&self, o: &f64) -> f64 {
        (self - o) * (self - o)
    }
}

impl DtwPoint for crate::geom::Vec2 {
    const DIM: usize = 2;
    #[inline]
    fn coord(&self, k: usize) -> f64 {
        self[k]
    }
    #[inline]
    fn sq_dist(&self, o: &Self) -> f64 {
        let (dx, dy) = (self.x - o.x, self.y - o.y);
        dx * dx + dy * dy
    }
}

/// The columns `[lo, hi)` of row `i` inside a band of radius `band` (or all columns),
/// with `dtaidistance`'s widening for unequal lengths `n` (rows) and `m` (columns).
#[inline]
fn columns(i: usize, n: usize, m: usize, band: Option<usize>) -> (usize, usize) {
    match band {
        None => (0, m),
        Some(r) => {
            let lo = i.saturating_sub(r + n.saturating_sub(m));
            let hi = (i + r + m.saturating_sub(n) + 1).min(m);
            (lo, hi)
        }
    }
}

/// The smaller of two numbers that are never NaN (one instruction, unlike
/// `f64::min`, which must also handle NaN).
#[inline(always)]
fn fmin(a: f64, b: f64) -> f64 {
    if b < a {
        b
    } else {
        a
    }
}

/// A DTW workspace: two reused rows, so a call allocates only when a longer
/// sequence than any before arrives.
#[derive(Clone, Debug, Default)]
pub struct Dtw {
    prev: Vec<f64>,
    cur: Vec<f64>,
}

impl Dtw {
    /// A workspace.
    pub fn new() -> Dtw {
        Dtw::default()
    }

    /// DTW distance between `a` and `b` (see the module doc), or `f64::INFINITY` when
    /// it exceeds `max_dist` (early abandoning: the computation stops at the first row
    /// whose every cell already exceeds `max_dist²`, since every path crosses every
    /// row). Two empty sequences are 0 apart; an empty and a non-empty one, infinitely.
    ///
    /// # Complexity
    ///
    /// `O(n · m)`, or `O(n · (2r + 1))` in a band of radius `r`.
    ///
    /// ```
    /// use crowdtouch::gesture::dtw::Dtw;
    /// let mut dtw = Dtw::new();
    /// // [0, 1, 2] against [0, 0, 1, 2]: the repeated 0 warps away.
    /// assert_eq!(dtw.distance(&[0.0, 1.0, 2.0], &[0.0, 0.0, 1.0, 2.0], None, None), 0.0);
    /// assert_eq!(dtw.distance(&[0.0, 1.0], &[3.0, 1.0], None, None), 3.0);
    /// assert_eq!(dtw.distance(&[0.0, 1.0], &[3.0, 1.0], None, Some(2.5)), f64::INFINITY);
    /// ```
    pub fn distance<P: DtwPoint>(
        &mut self,
        a: &[P],
        b: &[P],
        band: Option<usize>,
        max_dist: Option<f64>,
    ) -> f64 {
        let (n, m) = (a.len(), b.len());
        if n == 0 || m == 0 {
            return if n == m { 0.0 } else { f64::INFINITY };
        }
        let max_sq = max_dist.map_or(f64::INFINITY, |d| d * d);
        if self.prev.len() < m + 1 {
            self.prev.resize(m + 1, f64::INFINITY);
            self.cur.resize(m + 1, f64::INFINITY);
        }
        // Index j + 1 holds column j; index 0 is the column before the first.
        let (mut prev, mut cur) = (&mut self.prev, &mut self.cur);
        prev[..=m].fill(f64::INFINITY);
        cur[..=m].fill(f64::INFINITY);
        prev[0] = 0.0;
        for (i, ai) in a.iter().enumerate() {
            let (lo, hi) = columns(i, n, m, band);
            cur[lo] = f64::INFINITY;
            let mut left = f64::INFINITY;
            let mut row_min = f64::INFINITY;
            // Slices of equal length, so the loop runs without bounds checks.
            let (diag_up, out, cols) = (&prev[lo..=hi], &mut cur[lo + 1..=hi], &b[lo..hi]);
            for ((du, o), bj) in diag_up.windows(2).zip(out.iter_mut()).zip(cols) {
                let c = ai.sq_dist(bj) + fmin(fmin(du[0], du[1]), left);
                *o = c;
                left = c;
                row_min = fmin(row_min, c);
            }
            if hi < m {
                cur[hi + 1] = f64::INFINITY;
            }
            if row_min > max_sq {
                return f64::INFINITY;
            }
            std::mem::swap(&mut prev, &mut cur);
        }
        let d = prev[m].sqrt();
        if d * d > max_sq {
            f64::INFINITY
        } else {
            d
        }
    }
}

/// LB_Kim (first and last points): `sqrt(|a_0 − b_0|² + |a_n − b_m|²)`, or
/// `|a_0 − b_0|` when both sequences have one point; `≤` the DTW for any band.
pub fn lb_kim<P: DtwPoint>(a: &[P], b: &[P]) -> f64 {
    match (a.len(), b.len()) {
        (0, _) | (_, 0) => 0.0,
        (1, 1) => a[0].sq_dist(&b[0]).sqrt(),
        _ => (a[0].sq_dist(&b[0]) + a[a.len() - 1].sq_dist(&b[b.len() - 1])).sqrt(),
    }
}

/// The envelope of a sequence for LB_Keogh: per point and coordinate, the minimum
/// and maximum over the band (all points when unbanded).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Envelope {
    /// `lower[i * DIM + k]`: the minimum of coordinate `k` over row `i`'s band.
    pub lower: Vec<f64>,
    /// The maximum, laid out like `lower`.
    pub upper: Vec<f64>,
    /// The band it was built for.
    pub band: Option<usize>,
    /// Length of the sequence the rows come from (`n`, the other sequence).
    pub rows: usize,
}

impl Envelope {
    /// The envelope of `b` as seen from a sequence of `rows` points, in the band.
    ///
    /// # Complexity
    ///
    /// `O(rows · DIM · window)` in a band; unbanded, every row has the same window
    /// and it is scanned once: `O((rows + len) · DIM)`.
    pub fn of<P: DtwPoint>(b: &[P], rows: usize, band: Option<usize>) -> Envelope {
        let mut e = Envelope::default();
        e.fill(b, rows, band);
        e
    }

    /// [`Envelope::of`] into `self`, reusing its buffers.
    pub fn fill<P: DtwPoint>(&mut self, b: &[P], rows: usize, band: Option<usize>) {
        self.lower.clear();
        self.upper.clear();
        self.band = band;
        self.rows = rows;
        if b.is_empty() {
            return;
        }
        let mut prev = None;
        for i in 0..rows {
            let (lo, hi) = columns(i, rows, b.len(), band);
            if prev == Some((lo, hi)) {
                // The row before had the same window (every row does when unbanded):
                // the same minima and maxima.
                let at = self.lower.len() - P::DIM;
                for k in at..at + P::DIM {
                    let (l, u) = (self.lower[k], self.upper[k]);
                    self.lower.push(l);
                    self.upper.push(u);
                }
                continue;
            }
            prev = Some((lo, hi));
            for k in 0..P::DIM {
                let (mut l, mut u) = (f64::INFINITY, f64::NEG_INFINITY);
                for p in &b[lo..hi] {
                    l = l.min(p.coord(k));
                    u = u.max(p.coord(k));
                }
                self.lower.push(l);
                self.upper.push(u);
            }
        }
    }
}

/// LB_Keogh of `a` against the envelope of the other sequence:
/// `sqrt(Σ_i Σ_k excess(a_i,k, [lower, upper])²)`, `≤` the DTW in the envelope's
/// band. Stops early (returning the partial, still a lower bound) once the sum
/// exceeds `max_dist²`.
pub fn lb_keogh<P: DtwPoint>(a: &[P], env: &Envelope, max_dist: f64) -> f64 {
    if a.len() != env.rows || env.lower.len() != a.len() * P::DIM {
        return 0.0;
    }
    let max_sq = max_dist * max_dist;
    let mut sum = 0.0;
    for (i, p) in a.iter().enumerate() {
        for k in 0..P::DIM {
            let (c, l, u) = (
                p.coord(k),
                env.lower[i * P::DIM + k],
                env.upper[i * P::DIM + k],
            );
            let e = if c > u {
                c - u
            } else if c < l {
                l - c
            } else {
                0.0
            };
            sum += e * e;
        }
        if sum > max_sq {
            break;
        }
    }
    sum.sqrt()
}

/// The weights of the four features in the gesture distance (gesture-driven eq. 12).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Weights {
    /// Of the centroid `C(G)`.
    pub alpha: f64,
    /// Of the spread `S(G)`.
    pub beta: f64,
    /// Of the rotation `R(G)`.
    pub gamma: f64,
    /// Of the bounding box `B(G)`.
    pub delta: f64,
}

impl Default for Weights {
    /// The paper's: α = 0.04, β = 0.36, γ = 0.36, δ = 0.24 (section 5.3).
    fn default() -> Weights {
        Weights {
            alpha: 0.04,
            beta: 0.36,
            gamma: 0.36,
            delta: 0.24,
        }
    }
}

impl Weights {
    /// The weights in feature order: centroid, spread, rotation, box.
    pub fn as_array(&self) -> [f64; 4] {
        [self.alpha, self.beta, self.gamma, self.delta]
    }

    /// From weights in feature order.
    pub fn from_array(w: [f64; 4]) -> Weights {
        Weights {
            alpha: w[0],
            beta: w[1],
            gamma: w[2],
            delta: w[3],
        }
    }
}

/// The DTW of feature `f` (0 centroid, 1 spread, 2 rotation, 3 box) between two
/// gestures, abandoned (infinite) above `max_dist`.
pub fn feature_dtw(
    dtw: &mut Dtw,
    a: &GestureFeatures,
    b: &GestureFeatures,
    f: usize,
    band: Option<usize>,
    max_dist: Option<f64>,
) -> f64 {
    match f {
        0 => dtw.distance(&a.centroid, &b.centroid, band, max_dist),
        1 => dtw.distance(&a.spread, &b.spread, band, max_dist),
        2 => dtw.distance(&a.rotation, &b.rotation, band, max_dist),
        _ => dtw.distance(&a.mobb, &b.mobb, band, max_dist),
    }
}

/// Sums weighted per-feature DTWs in feature order, leaving out features of weight
/// 0 (so an ablated feature never contributes, even as `0 × ∞`).
pub fn weighted_sum(weights: &Weights, dtws: &[f64; 4]) -> f64 {
    let w = weights.as_array();
    (0..4)
        .filter(|&f| w[f] != 0.0)
        .map(|f| w[f] * dtws[f])
        .sum()
}

/// The distance between two gestures (gesture-driven eq. 12):
/// `α DTW(C) + β DTW(S) + γ DTW(R) + δ DTW(B)`.
///
/// # Complexity
///
/// Four DTWs of [`super::library::T_H`] points.
pub fn gesture_distance(
    dtw: &mut Dtw,
    a: &GestureFeatures,
    b: &GestureFeatures,
    weights: &Weights,
    band: Option<usize>,
) -> f64 {
    let w = weights.as_array();
    let mut d = [0.0; 4];
    for f in 0..4 {
        if w[f] != 0.0 {
            d[f] = feature_dtw(dtw, a, b, f, band, None);
        }
    }
    weighted_sum(weights, &d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use proptest::prelude::*;

    /// DTW by the full matrix and recursion over all cells, for the property tests.
    fn reference<P: DtwPoint>(a: &[P], b: &[P], band: Option<usize>) -> f64 {
        let (n, m) = (a.len(), b.len());
        let mut d = vec![vec![f64::INFINITY; m]; n];
        for i in 0..n {
            let (lo, hi) = columns(i, n, m, band);
            for j in lo..hi {
                let best = if i == 0 && j == 0 {
                    0.0
                } else {
                    let mut b_ = f64::INFINITY;
                    if i > 0 {
                        b_ = b_.min(d[i - 1][j]);
                    }
                    if j > 0 {
                        b_ = b_.min(d[i][j - 1]);
                    }
                    if i > 0 && j > 0 {
                        b_ = b_.min(d[i - 1][j - 1]);
                    }
                    b_
                };
                d[i][j] = a[i].sq_dist(&b[j]) + best;
            }
        }
        d[n - 1][m - 1].sqrt()
    }

    #[test]
    fn known_values() {
        let mut dtw = Dtw::new();
        // Identical sequences, and a shifted copy that warping absorbs.
        let a = [0.0, 1.0, 2.0, 1.0, 0.0];
        assert_eq!(dtw.distance(&a, &a, None, None), 0.0);
        assert_eq!(
            dtw.distance(&a, &[0.0, 0.0, 1.0, 2.0, 1.0, 0.0], None, None),
            0.0
        );
        // Diagonal band only: the Euclidean distance.
        let b = [1.0, 1.0, 1.0, 1.0, 1.0];
        assert!((dtw.distance(&a, &b, Some(0), None) - 3f64.sqrt()).abs() < 1e-15);
        // 2-D: two points apart by (3, 4) at one end.
        let p = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)];
        let q = [Vec2::new(0.0, 0.0), Vec2::new(4.0, 5.0)];
        assert_eq!(dtw.distance(&p, &q, None, None), 5.0);
        assert_eq!(dtw.distance::<f64>(&[], &[], None, None), 0.0);
        assert_eq!(dtw.distance(&[], &[1.0], None, None), f64::INFINITY);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, rng_seed: proptest::test_runner::RngSeed::Fixed(15), ..ProptestConfig::default() })]
        #[test]
        fn rows_match_the_full_matrix_and_bounds_hold(
            a in proptest::collection::vec(-3.0f64..3.0, 1..20),
            b in proptest::collection::vec(-3.0f64..3.0, 1..20),
            r in proptest::option::of(0usize..6),
            cut in 0.0f64..3.0,
        ) {
            let mut dtw = Dtw::new();
            let d = dtw.distance(&a, &b, r, None);
            let want = reference(&a, &b, r);
            prop_assert!((d - want).abs() <= 1e-12 * (1.0 + want), "{d} vs {want}");
            // Early abandoning answers infinity exactly when the distance is above the cut.
            let e = dtw.distance(&a, &b, r, Some(cut));
            let expected = if d > cut { f64::INFINITY } else { d };
            prop_assert_eq!(e, expected);
            prop_assert!(lb_kim(&a, &b) <= d + 1e-12);
            if a.len() == b.len() {
                let env = Envelope::of(&b, a.len(), r);
                prop_assert!(lb_keogh(&a, &env, f64::INFINITY) <= d + 1e-12);
            }
        }

        #[test]
        fn envelope_is_the_min_and_max_over_each_rows_window(
            b in proptest::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 1..20),
            rows in 1usize..20,
            r in proptest::option::of(0usize..6),
        ) {
            let b: Vec<Vec2> = b.into_iter().map(|(x, y)| Vec2::new(x, y)).collect();
            let env = Envelope::of(&b, rows, r);
            prop_assert_eq!(env.lower.len(), rows * 2);
            for i in 0..rows {
                let (lo, hi) = columns(i, rows, b.len(), r);
                for k in 0..2 {
                    let w = b[lo..hi].iter().map(|p| p[k]);
                    prop_assert_eq!(env.lower[i * 2 + k], w.clone().fold(f64::INFINITY, f64::min));
                    prop_assert_eq!(env.upper[i * 2 + k], w.fold(f64::NEG_INFINITY, f64::max));
                }
            }
        }

        #[test]
        fn two_d_bounds_hold(
            a in proptest::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 12),
            b in proptest::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 12),
            r in proptest::option::of(0usize..6),
        ) {
            let a: Vec<Vec2> = a.into_iter().map(|(x, y)| Vec2::new(x, y)).collect();
            let b: Vec<Vec2> = b.into_iter().map(|(x, y)| Vec2::new(x, y)).collect();
            let mut dtw = Dtw::new();
            let d = dtw.distance(&a, &b, r, None);
            prop_assert!((d - reference(&a, &b, r)).abs() < 1e-12);
            prop_assert!(lb_kim(&a, &b) <= d + 1e-12);
            prop_assert!(lb_keogh(&a, &Envelope::of(&b, a.len(), r), f64::INFINITY) <= d + 1e-12);
            prop_assert!(lb_keogh(&b, &Envelope::of(&a, b.len(), r), f64::INFINITY) <= d + 1e-12);
        }
    }
}
