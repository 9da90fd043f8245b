//! The minimum-area oriented bounding box of a point set (gesture-driven eq. 10):
//! convex hull by Andrew's monotone chain, then rotating calipers over the hull's
//! edges (Toussaint 1983; the minimum rectangle has a side on a hull edge, Freeman and
//! Shapira 1975).
//!
//! Degenerate sets are answered, not refused: one distinct point gives a 0 × 0 box,
//! collinear points a `length × 0` box.

use crate::geom::Vec2;

/// A rectangle: centre, the unit direction of its first side, and its side lengths.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct OrientedBox {
    /// Centre.
    pub center: Vec2,
    /// Unit direction of the side of length `extent[0]`; the other side is along its
    /// perpendicular `(-axis.y, axis.x)`.
    pub axis: Vec2,
    /// Side lengths along `axis` and along its perpendicular.
    pub extent: [f64; 2],
}

impl OrientedBox {
    /// Area.
    pub fn area(&self) -> f64 {
        self.extent[0] * self.extent[1]
    }

    /// `(width, height)`: the shorter side, then the longer (orientation-free, as the
    /// feature of eq. 10 uses them).
    pub fn sides(&self) -> Vec2 {
        Vec2::new(
            self.extent[0].min(self.extent[1]),
            self.extent[0].max(self.extent[1]),
        )
    }
}

/// The convex hull of `points`, counter-clockwise (x right, y up), without collinear
/// points, into `hull` (cleared first; its capacity is reused).
///
/// # Complexity
///
/// `O(n log n)`; sorts a copy of the points in `scratch`.
pub fn convex_hull(points: &[Vec2], scratch: &mut Vec<Vec2>, hull: &mut Vec<Vec2>) {
    scratch.clear();
    scratch.extend_from_slice(points);
    scratch.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    scratch.dedup();
    hull.clear();
    if scratch.len() <= 2 {
        hull.extend_from_slice(scratch);
        return;
    }
    // Lower hull, then upper hull; a turn that is not strictly left is popped.
    let left = |o: Vec2, a: Vec2, b: Vec2| {
        robust::orient2d(
            robust::Coord { x: o.x, y: o.y },
            robust::Coord { x: a.x, y: a.y },
            robust::Coord { x: b.x, y: b.y },
        ) > 0.0
    };
    for &p in scratch.iter() {
        while hull.len() >= 2 && !left(hull[hull.len() - 2], hull[hull.len() - 1], p) {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in scratch.iter().rev().skip(1) {
        while hull.len() >= lower && !left(hull[hull.len() - 2], hull[hull.len() - 1], p) {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop(); // the first point again
}

/// The minimum-area rectangle enclosing a convex polygon given counter-clockwise
/// without collinear vertices (as [`convex_hull`] returns it).
///
/// # Formula
///
/// For each hull edge `e_i` (unit direction `u`, inward normal `v = (-u.y, u.x)`) the
/// rectangle with a side on that edge spans `[min u·p, max u·p] × [0, max v·(p − p_i)]`;
/// the three extreme vertices only move forward as `i` increases (rotating calipers).
///
/// # Complexity
///
/// `O(h)` in the hull's vertices.
pub fn min_area_rect(hull: &[Vec2]) -> OrientedBox {
    match hull.len() {
        0 => {
            return OrientedBox {
                center: Vec2::zeros(),
                axis: Vec2::x(),
                extent: [0.0, 0.0],
            }
        }
        1 => {
            return OrientedBox {
                center: hull[0],
                axis: Vec2::x(),
                extent: [0.0, 0.0],
            }
        }
        2 => {
            let d = hull[1] - hull[0];
            let len = d.norm();
            let axis = if len > 0.0 { d / len } else { Vec2::x() };
            return OrientedBox {
                center: (hull[0] + hull[1]) * 0.5,
                axis,
                extent: [len, 0.0],
            };
        }
        _ => {}
    }
    let h = hull.len();
    let at = |i: usize| hull[i % h];
    let edge_dir = |i: usize| (at(i + 1) - at(i)).normalize();
    // Extreme vertices for edge 0, by a scan.
    let u0 = edge_dir(0);
    let v0 = Vec2::new(-u0.y, u0.x);
    let arg = |f: &dyn Fn(Vec2) -> f64| {
        (0..h)
            .max_by(|&a, &b| f(hull[a]).total_cmp(&f(hull[b])))
            .unwrap_or(0)
    };
    let (mut right, mut top, mut left) = (
        arg(&|p| p.dot(&u0)),
        arg(&|p| p.dot(&v0)),
        arg(&|p| -p.dot(&u0)),
    );
    let mut best: Option<OrientedBox> = None;
    for i in 0..h {
        let u = edge_dir(i);
        let v = Vec2::new(-u.y, u.x);
        // Advance each caliper while the next vertex is at least as far along its direction.
        for _ in 0..h {
            if at(right + 1).dot(&u) > at(right).dot(&u) {
                right = (right + 1) % h;
            } else {
                break;
            }
        }
        for _ in 0..h {
            if at(top + 1).dot(&v) > at(top).dot(&v) {
                top = (top + 1) % h;
            } else {
                break;
            }
        }
        for _ in 0..h {
            if at(left + 1).dot(&u) < at(left).dot(&u) {
                left = (left + 1) % h;
            } else {
                break;
            }
        }
        let origin = at(i);
        let (lo_u, hi_u) = ((at(left) - origin).dot(&u), (at(right) - origin).dot(&u));
        let hi_v = (at(top) - origin).dot(&v);
        let extent = [hi_u - lo_u, hi_v];
        let center = origin + u * ((lo_u + hi_u) * 0.5) + v * (hi_v * 0.5);
        let candidate = OrientedBox {
            center,
            axis: u,
            extent,
        };
        if best.is_none_or(|b| candidate.area() < b.area()) {
            best = Some(candidate);
        }
    }
    best.unwrap_or(OrientedBox {
        center: hull[0],
        axis: Vec2::x(),
        extent: [0.0, 0.0],
    })
}

/// Workspace for [`Mobb::sides`]: the hull and sort buffers, reused between calls.
#[derive(Clone, Debug, Default)]
pub struct Mobb {
    scratch: Vec<Vec2>,
    hull: Vec<Vec2>,
}

impl Mobb {
    /// A workspace.
    pub fn new() -> Mobb {
        Mobb::default()
    }

    /// The minimum-area oriented box of `points`.
    pub fn of(&mut self, points: &[Vec2]) -> OrientedBox {
        convex_hull(points, &mut self.scratch, &mut self.hull);
        min_area_rect(&self.hull)
    }

    /// `(width, height)` of the minimum-area oriented box of `points`: the shorter
    /// side, then the longer (gesture-driven eq. 10).
    ///
    /// ```
    /// use crowdtouch::geom::Vec2;
    /// use crowdtouch::gesture::mobb::Mobb;
    /// // A 2 × 1 rectangle turned by 30°.
    /// let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    /// let pts: Vec<Vec2> = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0), (1.0, 0.5)]
    ///     .iter().map(|&(x, y)| Vec2::new(c * x - s * y, s * x + c * y)).collect();
    /// let wh = Mobb::new().sides(&pts);
    /// assert!((wh.x - 1.0).abs() < 1e-12 && (wh.y - 2.0).abs() < 1e-12);
    /// ```
    pub fn sides(&mut self, points: &[Vec2]) -> Vec2 {
        self.of(points).sides()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rotate(p: Vec2, a: f64) -> Vec2 {
        Vec2::new(a.cos() * p.x - a.sin() * p.y, a.sin() * p.x + a.cos() * p.y)
    }

    /// The smallest axis-aligned area over `steps` rotations in `[0, π/2)`.
    fn brute_min_area(points: &[Vec2], steps: usize) -> f64 {
        (0..steps)
            .map(|k| {
                let a = std::f64::consts::FRAC_PI_2 * k as f64 / steps as f64;
                let r: Vec<Vec2> = points.iter().map(|&p| rotate(p, -a)).collect();
                let w = r.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max)
                    - r.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
                let h = r.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max)
                    - r.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
                w * h
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn contains(b: &OrientedBox, p: Vec2) -> bool {
        let d = p - b.center;
        let n = Vec2::new(-b.axis.y, b.axis.x);
        d.dot(&b.axis).abs() <= b.extent[0] * 0.5 + 1e-9
            && d.dot(&n).abs() <= b.extent[1] * 0.5 + 1e-9
    }

    #[test]
    fn degenerate_sets() {
        let mut m = Mobb::new();
        assert_eq!(m.sides(&[]), Vec2::new(0.0, 0.0));
        assert_eq!(m.sides(&[Vec2::new(3.0, 4.0); 5]), Vec2::new(0.0, 0.0));
        let line: Vec<Vec2> = (0..6)
            .map(|i| Vec2::new(1.0, 2.0) + Vec2::new(3.0, 4.0) * (i as f64 / 5.0))
            .collect();
        let wh = m.sides(&line);
        assert!(wh.x.abs() < 1e-12 && (wh.y - 5.0).abs() < 1e-12, "{wh}");
    }

    #[test]
    fn rotated_rectangles_are_recovered() {
        let mut m = Mobb::new();
        for k in 0..36 {
            let a = k as f64 * 0.1745;
            let pts: Vec<Vec2> = [
                (0.0, 0.0),
                (3.0, 0.0),
                (3.0, 0.5),
                (0.0, 0.5),
                (1.0, 0.2),
                (2.9, 0.4),
            ]
            .iter()
            .map(|&(x, y)| rotate(Vec2::new(x, y), a) + Vec2::new(7.0, -2.0))
            .collect();
            let b = m.of(&pts);
            let wh = b.sides();
            assert!(
                (wh.x - 0.5).abs() < 1e-9 && (wh.y - 3.0).abs() < 1e-9,
                "angle {a}: {wh}"
            );
            let centre = rotate(Vec2::new(1.5, 0.25), a) + Vec2::new(7.0, -2.0);
            assert!((b.center - centre).norm() < 1e-9);
        }
    }

    #[test]
    fn hull_is_counter_clockwise_and_drops_collinear_points() {
        let pts = [
            (0.0, 0.0),
            (1.0, 0.0),
            (2.0, 0.0),
            (2.0, 2.0),
            (1.0, 1.0),
            (0.0, 2.0),
            (0.0, 1.0),
        ];
        let pts: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
        let (mut s, mut h) = (Vec::new(), Vec::new());
        convex_hull(&pts, &mut s, &mut h);
        let want: Vec<Vec2> = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]
            .iter()
            .map(|&(x, y)| Vec2::new(x, y))
            .collect();
        assert_eq!(h, want);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, rng_seed: proptest::test_runner::RngSeed::Fixed(15), ..ProptestConfig::default() })]
        #[test]
        fn min_area_matches_brute_force_over_angles(pts in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 3..16)) {
            let pts: Vec<Vec2> = pts.into_iter().map(|(x, y)| Vec2::new(x, y)).collect();
            let b = Mobb::new().of(&pts);
            for &p in &pts {
                prop_assert!(contains(&b, p), "{p} outside {b:?}");
            }
            let brute = brute_min_area(&pts, 20_000);
            // The brute force samples angles, so it can only be above the optimum, and by
            // at most diameter² × the angle step.
            prop_assert!(b.area() <= brute + 1e-12, "calipers {} > brute {}", b.area(), brute);
            prop_assert!(brute - b.area() <= 8.0 * std::f64::consts::FRAC_PI_2 / 20_000.0 * 2.0, "calipers {} brute {}", b.area(), brute);
        }
    }
}
