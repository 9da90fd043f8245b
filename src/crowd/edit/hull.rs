//! The cage around a selection: a concave hull of the selected positions
//! (crowd-motion-editing section 3.2), simple, counter-clockwise, with a margin so
//! that every selected position lies strictly inside.
//!
//! The positions are first thinned on a square grid (one representative per occupied
//! cell, [`grid_subsample`]); geo's concave hull (concaveman) runs on the corners of
//! the occupied cells, so every position lies in a cell whose corners the hull
//! encloses, and the cage keeps a margin of up to one cell around the crowd. The
//! polygon is cleaned (duplicates and collinear vertices removed, made
//! counter-clockwise), its long edges are subdivided (at most
//! [`HullParams::max_edge_cells`] cells long, so that a drag can act locally) and it is
//! checked: simple, positive area, every position inside or on
//! the boundary. When a check fails the cage falls back to the convex hull of the same
//! corners ([`Hull::convex_fallback`]), which is always simple and contains every
//! position.

use super::error::EditError;
use super::select::point_in_polygon;
use crate::crowd::mesh::convex_hull;
use crate::geom::{cross, nearest_on_segment, twice_signed_area, Vec2};
use geo::{ConcaveHull, MultiPoint, Point};
use std::collections::HashMap;

/// geo's concavity for crowds (dimensionless). geo (concaveman) splits a hull edge of
/// length `L` at an interior point whose distance to the nearer end of the edge is
/// `d` when `L / d > concavity`. On representatives one grid cell apart, interior
/// candidates are at least about one cell from an edge's ends, so 2 leaves edges of up
/// to about two cells (twice the typical spacing) unsplit and digs into larger gaps.
pub const DEFAULT_CONCAVITY: f64 = 2.0;

/// Smallest grid cell for the thinning (m): about half the spacing of people walking
/// side by side.
pub const DEFAULT_MIN_CELL_M: f64 = 0.25;

/// Most occupied cells the thinning aims for: bounds the hull's vertex count (the
/// cage's unknowns) and the deformation mesh.
pub const DEFAULT_MAX_POINTS: usize = 1000;

/// Longest hull edge, in grid cells: longer edges are subdivided evenly, so that the
/// cage has vertices all along the crowd's boundary for a drag to act locally.
pub const DEFAULT_MAX_EDGE_CELLS: f64 = 4.0;

/// Most cells per point for [`grid_subsample`]'s dense grid (one byte each).
pub const DENSE_GRID_FACTOR: usize = 16;

/// Two consecutive hull vertices closer than this fraction of the cell are merged;
/// a vertex whose turn (|sin|) is below it is dropped as collinear.
const MERGE_FRACTION: f64 = 1e-3;

/// Parameters of [`concave_hull`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct HullParams {
    /// geo's concavity ratio (see [`DEFAULT_CONCAVITY`]); larger is more convex.
    pub concavity: f64,
    /// Smallest grid cell (m).
    pub min_cell_m: f64,
    /// Representatives aimed for; the cell grows so that the selection's bounding box
    /// holds about this many cells.
    pub max_points: usize,
    /// Longest hull edge in grid cells (see [`DEFAULT_MAX_EDGE_CELLS`]).
    pub max_edge_cells: f64,
}

impl Default for HullParams {
    fn default() -> Self {
        HullParams {
            concavity: DEFAULT_CONCAVITY,
            min_cell_m: DEFAULT_MIN_CELL_M,
            max_points: DEFAULT_MAX_POINTS,
            max_edge_cells: DEFAULT_MAX_EDGE_CELLS,
        }
    }
}

/// A cage polygon.
#[derive(Clone, Debug, PartialEq)]
pub struct Hull {
    /// Vertices, counter-clockwise, simple, no duplicates (m).
    pub vertices: Vec<Vec2>,
    /// The grid cell used for thinning (m).
    pub cell_m: f64,
    /// Indices of the representatives (into the input positions).
    pub representatives: Vec<usize>,
    /// Whether geo's concave hull was degenerate and the convex fallback was used.
    pub convex_fallback: bool,
}

/// The grid cell for `points` under `params` (m).
pub fn grid_cell(points: &[Vec2], params: &HullParams) -> f64 {
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let ext = hi - lo;
    let area = ext.x.max(params.min_cell_m) * ext.y.max(params.min_cell_m);
    params
        .min_cell_m
        .max((area / params.max_points.max(1) as f64).sqrt())
}

/// One representative per occupied grid cell of side `cell_m`: the first position in
/// input order that falls in the cell. Every position is within one cell in x and y of
/// its representative.
///
/// # Complexity
/// O(N) on a dense grid over the cells' bounding box when it has at most
/// [`DENSE_GRID_FACTOR`] cells per point, else through a hash map.
pub fn grid_subsample(points: &[Vec2], cell_m: f64) -> Vec<usize> {
    let key = |p: &Vec2| ((p.x / cell_m).floor() as i64, (p.y / cell_m).floor() as i64);
    let mut reps = Vec::new();
    let Some(first) = points.first() else {
        return reps;
    };
    let (mut lo, mut hi) = (key(first), key(first));
    for p in points {
        let (i, j) = key(p);
        lo = (lo.0.min(i), lo.1.min(j));
        hi = (hi.0.max(i), hi.1.max(j));
    }
    let (w, h) = ((hi.0 - lo.0 + 1) as u128, (hi.1 - lo.1 + 1) as u128);
    if w * h <= (DENSE_GRID_FACTOR * points.len() + 1024) as u128 {
        let mut seen = vec![false; (w * h) as usize];
        for (i, p) in points.iter().enumerate() {
            let (a, b) = key(p);
            let c = (b - lo.1) as usize * w as usize + (a - lo.0) as usize;
            if !seen[c] {
                seen[c] = true;
                reps.push(i);
            }
        }
        return reps;
    }
    let mut seen: HashMap<(i64, i64), ()> = HashMap::with_capacity(points.len() / 4 + 1);
    for (i, p) in points.iter().enumerate() {
        if seen.insert(key(p), ()).is_none() {
            reps.push(i);
        }
    }
    reps
}

/// Whether the closed polygon `poly` is simple: no two non-adjacent edges meet and no
/// two adjacent edges overlap.
///
/// # Complexity
/// O(n²).
pub fn is_simple(poly: &[Vec2]) -> bool {
    let n = poly.len();
    if n < 3 {
        return false;
    }
    let orient = |a: Vec2, b: Vec2, c: Vec2| {
        robust::orient2d(
            robust::Coord { x: a.x, y: a.y },
            robust::Coord { x: b.x, y: b.y },
            robust::Coord { x: c.x, y: c.y },
        )
    };
    let on = |a: Vec2, b: Vec2, p: Vec2| {
        p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
    };
    let meet = |a: Vec2, b: Vec2, c: Vec2, d: Vec2| {
        let (o1, o2) = (orient(a, b, c), orient(a, b, d));
        let (o3, o4) = (orient(c, d, a), orient(c, d, b));
        if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
            return true;
        }
        (o1 == 0.0 && on(a, b, c))
            || (o2 == 0.0 && on(a, b, d))
            || (o3 == 0.0 && on(c, d, a))
            || (o4 == 0.0 && on(c, d, b))
    };
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if a == b {
            return false;
        }
        for j in i + 1..n {
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if adjacent {
                // Sharing one end: only a fold back along the edge is a problem.
                let (shared, other_ab, other_cd) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
                if orient(other_ab, shared, other_cd) == 0.0
                    && (other_ab - shared).dot(&(other_cd - shared)) > 0.0
                {
                    return false;
                }
                continue;
            }
            if meet(a, b, c, d) {
                return false;
            }
        }
    }
    true
}

/// Removes repeated and collinear vertices and makes the polygon counter-clockwise.
fn clean(poly: &mut Vec<Vec2>, tol_m: f64) {
    if poly.len() > 1 && poly[0] == poly[poly.len() - 1] {
        poly.pop();
    }
    let mut changed = true;
    while changed && poly.len() >= 3 {
        changed = false;
        let n = poly.len();
        for i in 0..n {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (u, v) = (b - a, c - b);
            let (lu, lv) = (u.norm(), v.norm());
            let collinear = lu > 0.0 && lv > 0.0 && cross(u, v).abs() <= MERGE_FRACTION * lu * lv;
            if lu <= tol_m || (collinear && u.dot(&v) > 0.0) {
                poly.remove(i);
                changed = true;
                break;
            }
        }
    }
    if twice_signed_area(poly) < 0.0 {
        poly.reverse();
    }
}

/// Splits every edge longer than `max_m` into equal pieces no longer than `max_m`.
fn subdivide(poly: &[Vec2], max_m: f64) -> Vec<Vec2> {
    let n = poly.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let pieces = ((b - a).norm() / max_m).ceil().max(1.0) as usize;
        for k in 0..pieces {
            out.push(a + (b - a) * (k as f64 / pieces as f64));
        }
    }
    out
}

/// Whether every point is inside `poly` or on its boundary.
fn contains_all(poly: &[Vec2], points: &[Vec2]) -> bool {
    let n = poly.len();
    points.iter().all(|&p| {
        point_in_polygon(poly, p)
            || (0..n).any(|i| {
                let (q, _) = nearest_on_segment(poly[i], poly[(i + 1) % n], p);
                q == p
            })
    })
}

/// The cage polygon around `points` (see the module documentation).
///
/// # Units
/// Metres.
///
/// # Complexity
/// Thinning O(N); geo's hull O(r log r) on r representatives; the checks O(N·n) and
/// O(n²) for n hull vertices.
///
/// # Errors
/// [`EditError::NoHull`] for fewer than 3 distinct points, [`EditError::DegenerateHull`]
/// for non-finite points or when even the fallback has no area.
pub fn concave_hull(points: &[Vec2], params: &HullParams) -> Result<Hull, EditError> {
    if !points.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        return Err(EditError::DegenerateHull {
            reason: "a selected point is not finite",
        });
    }
    // Three distinct points are enough; fewer are counted exactly.
    let mut distinct: Vec<[u64; 2]> = Vec::with_capacity(3);
    for p in points {
        let k = [(p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()];
        if !distinct.contains(&k) {
            distinct.push(k);
            if distinct.len() == 3 {
                break;
            }
        }
    }
    if distinct.len() < 3 {
        return Err(EditError::NoHull {
            distinct: distinct.len(),
        });
    }
    let cell = grid_cell(points, params);
    let reps = grid_subsample(points, cell);
    let rp: Vec<Vec2> = reps.iter().map(|&i| points[i]).collect();
    // The occupied cells' corners, in grid units: every position lies in a cell whose
    // four corners are hull input.
    let mut corners: Vec<(i64, i64)> = rp
        .iter()
        .flat_map(|p| {
            let (i, j) = ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
            [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
        })
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let mp: MultiPoint<f64> = corners
        .iter()
        .map(|&(i, j)| Point::new(i as f64 * cell, j as f64 * cell))
        .collect();
    let hull = mp.concave_hull(params.concavity);
    let mut poly: Vec<Vec2> = hull
        .exterior()
        .0
        .iter()
        .map(|c| Vec2::new(c.x, c.y))
        .collect();
    clean(&mut poly, MERGE_FRACTION * cell);
    if poly.len() >= 3
        && twice_signed_area(&poly) > 0.0
        && is_simple(&poly)
        && contains_all(&poly, points)
    {
        return Ok(Hull {
            vertices: subdivide(&poly, params.max_edge_cells * cell),
            cell_m: cell,
            representatives: reps,
            convex_fallback: false,
        });
    }
    // Convex fallback: the convex hull of the same cell corners.
    let corners: Vec<Vec2> = corners
        .iter()
        .map(|&(i, j)| Vec2::new(i as f64 * cell, j as f64 * cell))
        .collect();
    let mut poly: Vec<Vec2> = convex_hull(&corners).iter().map(|&i| corners[i]).collect();
    clean(&mut poly, MERGE_FRACTION * cell);
    if poly.len() < 3 || twice_signed_area(&poly) <= 0.0 {
        return Err(EditError::DegenerateHull {
            reason: "the convex fallback has no area",
        });
    }
    Ok(Hull {
        vertices: subdivide(&poly, params.max_edge_cells * cell),
        cell_m: cell,
        representatives: reps,
        convex_fallback: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// An L-shaped crowd: a concave selection.
    fn l_shape() -> Vec<Vec2> {
        let mut rng = SplitMix64::new(7);
        let mut v = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                if i < 12 || j < 12 {
                    let jitter = Vec2::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
                    v.push(Vec2::new(i as f64 * 0.5, j as f64 * 0.5) + jitter);
                }
            }
        }
        v
    }

    #[test]
    fn hull_contains_every_point_and_is_simple_ccw() {
        let pts = l_shape();
        let h = concave_hull(&pts, &HullParams::default()).unwrap();
        assert!(!h.convex_fallback, "geo's hull was usable");
        assert!(is_simple(&h.vertices));
        assert!(twice_signed_area(&h.vertices) > 0.0);
        for p in &pts {
            assert!(point_in_polygon(&h.vertices, *p), "{p:?} outside");
        }
        // Concave: much smaller than the convex hull (20 m × 20 m minus the notch).
        let area = 0.5 * twice_signed_area(&h.vertices);
        assert!(area < 0.8 * 21.0 * 21.0, "area {area}");
    }

    #[test]
    fn collinear_points_get_a_cage_of_cells() {
        let pts: Vec<Vec2> = (0..10)
            .map(|i| Vec2::new(i as f64, 2.0 * i as f64))
            .collect();
        let h = concave_hull(&pts, &HullParams::default()).unwrap();
        assert!(twice_signed_area(&h.vertices) > 0.0);
        assert!(pts.iter().all(|p| point_in_polygon(&h.vertices, *p)));
        assert!(is_simple(&h.vertices));
    }

    #[test]
    fn too_few_points() {
        let pts = [Vec2::zeros(), Vec2::zeros(), Vec2::x()];
        assert_eq!(
            concave_hull(&pts, &HullParams::default()),
            Err(EditError::NoHull { distinct: 2 })
        );
    }

    #[test]
    fn simplicity_check() {
        let bow = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ];
        assert!(!is_simple(&bow));
        let sq = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        assert!(is_simple(&sq));
    }
}
