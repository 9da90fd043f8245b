//! Mean value coordinates and convex-polygon helpers for area controls.
//!
//! An area control (mesh-formation-control section 4.2) takes the convex hull of three
//! or more touch points ([`convex_hull`]), samples supplementary control points on and
//! inside it ([`point_in_convex_polygon`]), and stores each supplementary point's mean
//! value coordinates ([`mean_value_coordinates`], Floater 2003) with respect to the hull.
//! When the fingers move, the supplementary targets are `Σ λ_i c_i` of the moved touch
//! points `c_i`.

use crate::geom::{cross, twice_signed_area, Vec2};

/// A point closer to a polygon vertex than `MVC_VERTEX_EPS` × (polygon bounding-box
/// diagonal) gets the one-hot coordinates of that vertex (dimensionless).
pub const MVC_VERTEX_EPS: f64 = 1e-12;

/// A point whose angle to an edge's endpoints is within `MVC_EDGE_EPS` (radians, as
/// `|sin α|`) of a straight angle lies on that edge and gets linear coordinates.
pub const MVC_EDGE_EPS: f64 = 1e-12;

/// Errors of [`mean_value_coordinates`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MvcError {
    /// The polygon has fewer than 3 vertices.
    #[error("polygon has {got} vertices, at least 3 are needed")]
    TooFewVertices {
        /// Number of vertices given.
        got: usize,
    },
    /// `out` does not have one entry per polygon vertex.
    #[error("output has {got} entries, the polygon has {expected} vertices")]
    LengthMismatch {
        /// Polygon vertex count.
        expected: usize,
        /// Output length.
        got: usize,
    },
    /// A polygon vertex or the query point is NaN or infinite.
    #[error("polygon vertex or query point is not finite")]
    NonFinite,
    /// The weights do not normalise (zero-size polygon, or a point where the
    /// coordinates are undefined).
    #[error("mean value coordinates are undefined here (degenerate polygon)")]
    Degenerate,
}

/// Exact orientation sign of `(a, b, c)`: positive when CCW.
fn orient(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let co = |v: Vec2| robust::Coord { x: v.x, y: v.y };
    robust::orient2d(co(a), co(b), co(c))
}

/// Mean value coordinates of `p` with respect to the closed polygon `poly`.
///
/// Writes `poly.len()` weights `λ_i` with `Σ λ_i = 1` and `Σ λ_i v_i = p`. Exact at the
/// vertices (one-hot) and on the edges (linear in the two endpoints); positive inside a
/// convex polygon; defined, finite and still reproducing `p` outside (signed angles,
/// Hormann & Floater 2006). Works for CCW and CW polygons.
///
/// # Formula
/// Floater 2003, eq. (3.1): `w_i = (tan(α_{i-1}/2) + tan(α_i/2)) / ‖v_i - p‖`,
/// `λ_i = w_i / Σ_j w_j`, with `α_i` the signed angle at `p` from `v_i - p` to
/// `v_{i+1} - p`. `tan(α/2)` is evaluated as `A / (r r' + D)` when `D ≥ 0`, else as
/// `(r r' - D) / A` (`A` = cross, `D` = dot product of the two vectors, `r, r'` their
/// lengths), which is stable for both small and nearly straight angles.
/// mesh-formation-control section 4.2 (reference \[29\]).
///
/// # Units
/// Positions in metres; coordinates dimensionless.
///
/// # Complexity
/// O(n), no allocation.
///
/// # Errors
/// [`MvcError::TooFewVertices`], [`MvcError::LengthMismatch`], [`MvcError::NonFinite`],
/// [`MvcError::Degenerate`]; on error `out` (when of the right length) is zeroed.
///
/// ```
/// use crowdtouch::crowd::mesh::mean_value_coordinates;
/// use crowdtouch::geom::Vec2;
/// let square = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
/// let p = Vec2::new(0.25, 0.5);
/// let mut l = [0.0; 4];
/// mean_value_coordinates(&square, p, &mut l).unwrap();
/// let q: Vec2 = square.iter().zip(&l).map(|(v, w)| v * *w).sum();
/// assert!((q - p).norm() < 1e-12);
/// assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-12);
/// ```
pub fn mean_value_coordinates(poly: &[Vec2], p: Vec2, out: &mut [f64]) -> Result<(), MvcError> {
    let n = poly.len();
    if out.len() != n {
        return Err(MvcError::LengthMismatch {
            expected: n,
            got: out.len(),
        });
    }
    out.fill(0.0);
    if n < 3 {
        return Err(MvcError::TooFewVertices { got: n });
    }
    let finite = |v: &Vec2| v.x.is_finite() && v.y.is_finite();
    if !finite(&p) || !poly.iter().all(finite) {
        return Err(MvcError::NonFinite);
    }
    let (mut lo, mut hi) = (poly[0], poly[0]);
    for v in poly {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let scale = (hi - lo).norm();
    if scale.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(MvcError::Degenerate);
    }
    // At a vertex: one-hot.
    for (i, v) in poly.iter().enumerate() {
        if (v - p).norm() <= MVC_VERTEX_EPS * scale {
            out[i] = 1.0;
            return Ok(());
        }
    }
    // tan(α_i / 2) for each edge (i, i+1); on an edge: linear.
    let mut tan_prev = 0.0;
    for i in 0..n {
        let j = (i + 1) % n;
        let (di, dj) = (poly[i] - p, poly[j] - p);
        let (ri, rj) = (di.norm(), dj.norm());
        let a = cross(di, dj);
        let d = di.dot(&dj);
        let rr = ri * rj;
        if a.abs() <= MVC_EDGE_EPS * rr && d < 0.0 {
            out.fill(0.0);
            out[i] = rj / (ri + rj);
            out[j] = ri / (ri + rj);
            return Ok(());
        }
        let t = if d >= 0.0 { a / (rr + d) } else { (rr - d) / a };
        // Store w_i partially: out[i] gets tan_i / r_i now, tan_{i-1} / r_i below.
        out[i] = t / ri;
        if i > 0 {
            out[i] += tan_prev / ri;
        }
        tan_prev = t;
    }
    out[0] += tan_prev / (poly[0] - p).norm();
    let sum: f64 = out.iter().sum();
    if !(sum.is_finite() && sum != 0.0) {
        out.fill(0.0);
        return Err(MvcError::Degenerate);
    }
    for w in out.iter_mut() {
        *w /= sum;
    }
    if !out.iter().all(|w| w.is_finite()) {
        out.fill(0.0);
        return Err(MvcError::Degenerate);
    }
    Ok(())
}

/// Indices of the convex hull of `points`, CCW, without collinear or repeated points
/// (Andrew's monotone chain with exact orientation tests).
///
/// Non-finite points are ignored; of several equal points the lowest index is used. With
/// fewer than 3 distinct non-collinear points, returns what exists: no index, the one
/// point, or the two extreme points of a collinear set.
///
/// # Formula
/// Andrew 1979, monotone chain: sort by (x, y), build the lower and upper chains keeping
/// only strict left turns.
///
/// # Complexity
/// O(n log n); allocates the result and a sort buffer.
///
/// # Errors
/// None.
///
/// ```
/// use crowdtouch::crowd::mesh::convex_hull;
/// use crowdtouch::geom::Vec2;
/// let pts = [Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0), Vec2::new(1.0, 0.5),
///            Vec2::new(2.0, 2.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 2.0)];
/// assert_eq!(convex_hull(&pts), vec![0, 1, 3, 5]);
/// ```
pub fn convex_hull(points: &[Vec2]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].x.is_finite() && points[i].y.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        // `+ 0.0` maps -0.0 to 0.0 so that equal points sort next to each other.
        let (p, q) = (points[a].add_scalar(0.0), points[b].add_scalar(0.0));
        p.x.total_cmp(&q.x)
            .then(p.y.total_cmp(&q.y))
            .then(a.cmp(&b))
    });
    // Keep the first (lowest index) of equal points.
    idx.dedup_by(|b, a| points[*a] == points[*b]);
    if idx.len() < 3 {
        return idx;
    }
    let mut hull: Vec<usize> = Vec::with_capacity(2 * idx.len());
    for &i in &idx {
        while hull.len() >= 2
            && orient(
                points[hull[hull.len() - 2]],
                points[hull[hull.len() - 1]],
                points[i],
            ) <= 0.0
        {
            hull.pop();
        }
        hull.push(i);
    }
    let lower_len = hull.len() + 1;
    for &i in idx.iter().rev().skip(1) {
        while hull.len() >= lower_len
            && orient(
                points[hull[hull.len() - 2]],
                points[hull[hull.len() - 1]],
                points[i],
            ) <= 0.0
        {
            hull.pop();
        }
        hull.push(i);
    }
    hull.pop(); // the first point again
    hull
}

/// Whether `p` lies inside or on the boundary of the convex polygon `poly` (CCW or CW).
///
/// # Formula
/// `p` is inside iff the exact orientations of `(v_i, v_{i+1}, p)` never take both
/// signs.
///
/// # Complexity
/// O(n), no allocation.
///
/// # Errors
/// None: fewer than 3 vertices, non-finite input or a polygon of zero area give `false`.
pub fn point_in_convex_polygon(poly: &[Vec2], p: Vec2) -> bool {
    let n = poly.len();
    if n < 3 || !(p.x.is_finite() && p.y.is_finite()) {
        return false;
    }
    if !poly.iter().all(|v| v.x.is_finite() && v.y.is_finite()) {
        return false;
    }
    let area2 = twice_signed_area(poly);
    if area2 == 0.0 {
        return false;
    }
    let (mut pos, mut neg) = (false, false);
    for i in 0..n {
        let o = orient(poly[i], poly[(i + 1) % n], p);
        pos |= o > 0.0;
        neg |= o < 0.0;
        if pos && neg {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config as ProptestConfig, RngSeed};

    fn square() -> Vec<Vec2> {
        vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]
    }

    fn reproduce(poly: &[Vec2], l: &[f64]) -> Vec2 {
        poly.iter().zip(l).map(|(v, w)| v * *w).sum()
    }

    #[test]
    fn one_hot_at_vertices() {
        let poly = square();
        let mut l = [0.0; 4];
        for (i, v) in poly.iter().enumerate() {
            mean_value_coordinates(&poly, *v, &mut l).expect("vertex");
            for (k, w) in l.iter().enumerate() {
                assert_eq!(*w, if k == i { 1.0 } else { 0.0 });
            }
        }
    }

    #[test]
    fn linear_on_edges() {
        let poly = square();
        let mut l = [0.0; 4];
        for i in 0..4 {
            let j = (i + 1) % 4;
            for t in [0.1, 0.5, 0.93] {
                let p = poly[i] * (1.0 - t) + poly[j] * t;
                mean_value_coordinates(&poly, p, &mut l).expect("edge");
                assert!((l[i] - (1.0 - t)).abs() < 1e-12, "{l:?}");
                assert!((l[j] - t).abs() < 1e-12);
                assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn outside_points_are_finite_and_reproduce() {
        let poly = square();
        let mut l = [0.0; 4];
        for p in [
            Vec2::new(5.0, 0.5),
            Vec2::new(-1.0, -1.0),
            Vec2::new(3.0, 0.0), // on the extension of an edge
            Vec2::new(1.0, 40.0),
        ] {
            mean_value_coordinates(&poly, p, &mut l).expect("defined outside");
            assert!(l.iter().all(|w| w.is_finite()));
            assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-9);
            assert!((reproduce(&poly, &l) - p).norm() < 1e-9 * p.norm().max(1.0));
        }
    }

    #[test]
    fn errors() {
        let poly = square();
        let mut l3 = [0.0; 3];
        assert_eq!(
            mean_value_coordinates(&poly, Vec2::zeros(), &mut l3),
            Err(MvcError::LengthMismatch {
                expected: 4,
                got: 3
            })
        );
        let mut l2 = [0.0; 2];
        assert_eq!(
            mean_value_coordinates(&poly[..2], Vec2::zeros(), &mut l2),
            Err(MvcError::TooFewVertices { got: 2 })
        );
        let mut l = [0.0; 4];
        assert_eq!(
            mean_value_coordinates(&poly, Vec2::new(f64::NAN, 0.0), &mut l),
            Err(MvcError::NonFinite)
        );
        let same = [Vec2::new(1.0, 1.0); 4];
        assert_eq!(
            mean_value_coordinates(&same, Vec2::zeros(), &mut l),
            Err(MvcError::Degenerate)
        );
        assert!(l.iter().all(|&w| w == 0.0));
    }

    #[test]
    fn point_in_convex_polygon_cases() {
        let poly = square();
        assert!(point_in_convex_polygon(&poly, Vec2::new(1.0, 0.5)));
        assert!(
            point_in_convex_polygon(&poly, Vec2::new(2.0, 0.5)),
            "on an edge"
        );
        assert!(
            point_in_convex_polygon(&poly, Vec2::new(0.0, 0.0)),
            "at a vertex"
        );
        assert!(!point_in_convex_polygon(&poly, Vec2::new(2.0 + 1e-12, 0.5)));
        assert!(!point_in_convex_polygon(&poly, Vec2::new(-1.0, 3.0)));
        let cw: Vec<Vec2> = poly.iter().rev().copied().collect();
        assert!(point_in_convex_polygon(&cw, Vec2::new(1.0, 0.5)));
        assert!(!point_in_convex_polygon(&cw, Vec2::new(3.0, 0.5)));
        let flat = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(2.0, 0.0),
        ];
        assert!(!point_in_convex_polygon(&flat, Vec2::new(1.0, 0.0)));
        assert!(!point_in_convex_polygon(&poly[..2], Vec2::new(1.0, 0.0)));
        assert!(!point_in_convex_polygon(&poly, Vec2::new(f64::NAN, 0.5)));
    }

    #[test]
    fn convex_hull_small_cases() {
        assert!(convex_hull(&[]).is_empty());
        assert_eq!(convex_hull(&[Vec2::new(1.0, 1.0)]), vec![0]);
        assert_eq!(
            convex_hull(&[Vec2::new(1.0, 1.0), Vec2::new(1.0, 1.0)]),
            vec![0]
        );
        let line = [
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(0.5, 0.5),
        ];
        assert_eq!(convex_hull(&line), vec![1, 2]);
        let with_nan = [
            Vec2::new(0.0, 0.0),
            Vec2::new(f64::NAN, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ];
        assert_eq!(convex_hull(&with_nan), vec![0, 2, 3]);
        // -0.0 and 0.0 are the same coordinate.
        let signed_zero = [
            Vec2::new(-0.0, 0.0),
            Vec2::new(-0.0, 1.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
        ];
        assert_eq!(convex_hull(&signed_zero), vec![0, 3, 1]);
    }

    /// Extreme points by brute force: a point is on the hull iff it is not in a
    /// (closed) triangle or segment of other, distinct points.
    fn brute_force_hull_points(points: &[Vec2]) -> Vec<(i64, i64)> {
        let mut uniq: Vec<Vec2> = Vec::new();
        for p in points {
            if !uniq.contains(p) {
                uniq.push(*p);
            }
        }
        let n = uniq.len();
        let in_segment =
            |a: Vec2, b: Vec2, q: Vec2| orient(a, b, q) == 0.0 && (q - a).dot(&(q - b)) <= 0.0;
        let mut out = Vec::new();
        'points: for q in 0..n {
            for a in 0..n {
                for b in 0..n {
                    if a == q || b == q || a == b {
                        continue;
                    }
                    if in_segment(uniq[a], uniq[b], uniq[q]) {
                        continue 'points;
                    }
                    for c in 0..n {
                        if c == q || c == a || c == b {
                            continue;
                        }
                        if point_in_convex_polygon(&[uniq[a], uniq[b], uniq[c]], uniq[q]) {
                            continue 'points;
                        }
                    }
                }
            }
            out.push((uniq[q].x as i64, uniq[q].y as i64));
        }
        out.sort_unstable();
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 64,
            rng_seed: RngSeed::Fixed(0x6d76_6331),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn prop_linear_precision_and_partition_of_unity(
            angles in proptest::collection::vec(0.0f64..std::f64::consts::TAU, 3..12),
            rx in 0.5f64..20.0, ry in 0.5f64..20.0, cx in -50.0f64..50.0, cy in -50.0f64..50.0,
            mix in proptest::collection::vec(0.01f64..1.0, 12),
            reverse in proptest::bool::ANY,
        ) {
            // A strictly convex polygon: points on an ellipse at sorted, distinct angles.
            let mut angles = angles;
            angles.sort_by(f64::total_cmp);
            angles.dedup_by(|a, b| (*a - *b).abs() < 1e-3);
            prop_assume!(angles.len() >= 3);
            let mut poly: Vec<Vec2> = angles
                .iter()
                .map(|t| Vec2::new(cx + rx * t.cos(), cy + ry * t.sin()))
                .collect();
            if reverse {
                poly.reverse();
            }
            let area2: f64 = (0..poly.len()).map(|i| cross(poly[i], poly[(i + 1) % poly.len()])).sum();
            prop_assume!(area2.abs() > 1e-3);
            // An interior point as a strictly positive convex combination.
            let wsum: f64 = mix[..poly.len()].iter().sum();
            let p: Vec2 = poly.iter().zip(&mix).map(|(v, w)| v * (*w / wsum)).sum();
            let mut l = vec![0.0; poly.len()];
            mean_value_coordinates(&poly, p, &mut l).expect("inside");
            let scale = rx.max(ry) + cx.abs().max(cy.abs());
            prop_assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            prop_assert!((reproduce(&poly, &l) - p).norm() < 1e-9 * scale);
            prop_assert!(l.iter().all(|&w| w > 0.0), "positive inside: {:?}", l);
            prop_assert!(point_in_convex_polygon(&poly, p));
        }

        #[test]
        fn prop_convex_hull_matches_brute_force(
            pts in proptest::collection::vec((-4i64..5, -4i64..5), 0..14),
        ) {
            let points: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x as f64, y as f64)).collect();
            let hull = convex_hull(&points);
            let expect = brute_force_hull_points(&points);
            let mut got: Vec<(i64, i64)> = hull.iter().map(|&i| (points[i].x as i64, points[i].y as i64)).collect();
            got.sort_unstable();
            if expect.len() >= 3 {
                prop_assert_eq!(&got, &expect);
                // CCW with strict left turns, everything inside.
                let h: Vec<Vec2> = hull.iter().map(|&i| points[i]).collect();
                for i in 0..h.len() {
                    prop_assert!(orient(h[i], h[(i + 1) % h.len()], h[(i + 2) % h.len()]) > 0.0);
                }
                for p in &points {
                    prop_assert!(point_in_convex_polygon(&h, *p));
                }
            } else {
                // Collinear or fewer than 3 distinct points: the extreme points only.
                let mut uniq = expect.clone();
                uniq.dedup();
                prop_assert!(got.len() <= 2);
                prop_assert_eq!(got, uniq);
            }
        }
    }
}
