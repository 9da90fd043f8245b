//! Convex parts (polygons and circles) and the queries the crowd needs on them.
//!
//! Every obstacle, patch and checkpoint of a [`Scene`](super::Scene) is built from
//! [`Part`]s. A part is stored in its own frame; a [`Placement`] puts it in the
//! world (identity for static things, the path pose for dynamic ones), so moving a
//! part never copies it: queries map the world point into the part's frame instead.
//!
//! Sign convention of every distance here: negative inside, zero on the boundary,
//! positive outside (metres).
//!
//! ```text
//!   y ^        CCW polygon: the interior is on the left of every edge
//!     |   v2 *-------* v1
//!     |      |  in   |       signed_distance < 0 inside, > 0 outside
//!     |   v3 *-------* v0
//!     +------------------> x
//! ```

use crate::geom::{cross, nearest_on_segment, Rect, Vec2};

/// Two parts whose projections overlap by less than this (m) only touch: their
/// interiors are disjoint.
pub const TOUCH_TOLERANCE_M: f64 = 1e-9;

/// A convex polygon, counter-clockwise, at least three vertices, positive area.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexPolygon {
    vertices: Vec<Vec2>,
    centre: Vec2,
    area_m2: f64,
}

/// A disc.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Circle {
    /// Centre (m).
    pub centre: Vec2,
    /// Radius (m), positive.
    pub radius_m: f64,
}

/// One convex piece of an obstacle, patch or checkpoint.
#[derive(Clone, Debug, PartialEq)]
pub enum Part {
    /// A convex polygon.
    Polygon(ConvexPolygon),
    /// A disc.
    Circle(Circle),
}

/// Where a part is in the world: its frame's origin and rotation.
///
/// # Formula
/// `world = position + R(heading) · local` with `R` the counter-clockwise rotation.
///
/// # Units
/// Metres and radians.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Placement {
    /// World position of the part frame's origin (m).
    pub position: Vec2,
    cos: f64,
    sin: f64,
}

impl Default for Placement {
    fn default() -> Self {
        Placement::IDENTITY
    }
}

impl Placement {
    /// The part frame is the world frame.
    pub const IDENTITY: Placement = Placement {
        position: Vec2::new(0.0, 0.0),
        cos: 1.0,
        sin: 0.0,
    };

    /// A translation by `position` and a counter-clockwise rotation by `heading_rad`.
    /// A non-finite heading is treated as zero.
    pub fn new(position: Vec2, heading_rad: f64) -> Placement {
        let h = if heading_rad.is_finite() {
            heading_rad
        } else {
            0.0
        };
        Placement {
            position,
            cos: h.cos(),
            sin: h.sin(),
        }
    }

    /// The rotation (rad, counter-clockwise, in `(-π, π]`).
    pub fn heading_rad(&self) -> f64 {
        self.sin.atan2(self.cos)
    }

    /// World point → part frame.
    pub fn to_local(&self, p: Vec2) -> Vec2 {
        let d = p - self.position;
        Vec2::new(
            self.cos * d.x + self.sin * d.y,
            -self.sin * d.x + self.cos * d.y,
        )
    }

    /// Part frame point → world.
    pub fn to_world(&self, p: Vec2) -> Vec2 {
        self.position + self.rotate(p)
    }

    /// Part frame direction → world direction.
    pub fn rotate(&self, v: Vec2) -> Vec2 {
        Vec2::new(
            self.cos * v.x - self.sin * v.y,
            self.sin * v.x + self.cos * v.y,
        )
    }
}

/// The point of a part's boundary nearest to a query point, with the outward normal
/// there.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BoundaryPoint {
    /// Nearest boundary point (m).
    pub point: Vec2,
    /// Unit outward normal at that point (the direction that leaves the part).
    pub normal: Vec2,
    /// Signed distance of the query point (m): negative inside.
    pub signed_distance_m: f64,
}

impl ConvexPolygon {
    /// Builds a polygon from vertices already checked by the scene validator:
    /// convex, at least three, positive area, either orientation (stored
    /// counter-clockwise). Returns `None` when they are not.
    pub fn new(mut vertices: Vec<Vec2>) -> Option<ConvexPolygon> {
        if vertices.len() < 3
            || vertices
                .iter()
                .any(|v| !v.x.is_finite() || !v.y.is_finite())
        {
            return None;
        }
        let twice_area = signed_twice_area(&vertices);
        if twice_area < 0.0 {
            vertices.reverse();
        }
        let area_m2 = 0.5 * twice_area.abs();
        if area_m2 <= 0.0 || non_convex_vertex(&vertices).is_some() {
            return None;
        }
        let centre = area_centroid(&vertices, 0.5 * signed_twice_area(&vertices));
        Some(ConvexPolygon {
            vertices,
            centre,
            area_m2,
        })
    }

    /// The vertices, counter-clockwise (m).
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }

    /// Area centroid (m).
    pub fn centre(&self) -> Vec2 {
        self.centre
    }

    /// Area (m²).
    pub fn area_m2(&self) -> f64 {
        self.area_m2
    }

    fn edges(&self) -> impl Iterator<Item = (Vec2, Vec2)> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| (self.vertices[i], self.vertices[(i + 1) % n]))
    }

    /// Nearest boundary point of `p` (part frame).
    pub fn boundary_point(&self, p: Vec2) -> BoundaryPoint {
        let mut inside = true;
        let mut best = (f64::INFINITY, p, Vec2::new(1.0, 0.0));
        for (a, b) in self.edges() {
            let e = b - a;
            if cross(e, p - a) < 0.0 {
                inside = false;
            }
            let (q, _) = nearest_on_segment(a, b, p);
            let d2 = (p - q).norm_squared();
            if d2 < best.0 {
                let len = e.norm();
                let n = if len > 0.0 {
                    Vec2::new(e.y / len, -e.x / len)
                } else {
                    Vec2::new(1.0, 0.0)
                };
                best = (d2, q, n);
            }
        }
        let d = best.0.sqrt();
        let normal = if !inside && d > 0.0 {
            (p - best.1) / d
        } else {
            best.2
        };
        BoundaryPoint {
            point: best.1,
            normal,
            signed_distance_m: if inside { -d } else { d },
        }
    }

    /// Signed distance of `p` (part frame), m: negative inside. The
    /// `signed_distance_m` of [`boundary_point`](Self::boundary_point), bit for
    /// bit, without the point and the normal (the obstacle tests of every agent
    /// in every tick ask only this).
    pub fn signed_distance(&self, p: Vec2) -> f64 {
        let mut inside = true;
        let mut best = f64::INFINITY;
        for (a, b) in self.edges() {
            if cross(b - a, p - a) < 0.0 {
                inside = false;
            }
            let (q, _) = nearest_on_segment(a, b, p);
            best = best.min((p - q).norm_squared());
        }
        let d = best.sqrt();
        if inside {
            -d
        } else {
            d
        }
    }

    /// Whether `p` is inside or on the boundary (part frame).
    pub fn contains(&self, p: Vec2) -> bool {
        self.edges().all(|(a, b)| cross(b - a, p - a) >= 0.0)
    }

    /// Smallest width over all directions (m): the least distance between two
    /// parallel lines enclosing the polygon. For a convex polygon it is attained
    /// with one line through an edge.
    pub fn min_width_m(&self) -> f64 {
        let mut w = f64::INFINITY;
        for (a, b) in self.edges() {
            let e = b - a;
            let len = e.norm();
            if len <= 0.0 {
                continue;
            }
            let far = self
                .vertices
                .iter()
                .map(|&v| cross(e, v - a) / len)
                .fold(0.0, f64::max);
            w = w.min(far);
        }
        w
    }

    /// Entry parameter `s ∈ [0, 1]` of segment `a + s·(b − a)` into the polygon
    /// (Cyrus–Beck clipping); 0 when `a` is inside, `None` when it misses.
    pub fn segment_entry(&self, a: Vec2, b: Vec2) -> Option<f64> {
        let d = b - a;
        let (mut enter, mut leave) = (0.0f64, 1.0f64);
        for (p, q) in self.edges() {
            let e = q - p;
            // Outward normal (e.y, -e.x): inside where n·(x − p) ≤ 0.
            let n = Vec2::new(e.y, -e.x);
            let num = n.dot(&(a - p));
            let den = n.dot(&d);
            if den == 0.0 {
                if num > 0.0 {
                    return None;
                }
            } else {
                let s = -num / den;
                if den < 0.0 {
                    enter = enter.max(s);
                } else {
                    leave = leave.min(s);
                }
            }
            if enter > leave {
                return None;
            }
        }
        Some(enter)
    }
}

/// Twice the signed area (positive counter-clockwise), m².
pub(crate) fn signed_twice_area(v: &[Vec2]) -> f64 {
    let n = v.len();
    (0..n).map(|i| cross(v[i], v[(i + 1) % n])).sum()
}

fn area_centroid(v: &[Vec2], area: f64) -> Vec2 {
    let n = v.len();
    let mut c = Vec2::zeros();
    // Shift to the first vertex for precision far from the origin.
    let o = v[0];
    for i in 0..n {
        let (a, b) = (v[i] - o, v[(i + 1) % n] - o);
        c += (a + b) * cross(a, b);
    }
    if area != 0.0 {
        o + c / (6.0 * area)
    } else {
        o
    }
}

/// First vertex at which a counter-clockwise vertex list is not convex: some
/// vertex lies strictly right of an edge (exact `robust::orient2d`), or a vertex
/// repeats its predecessor. `None` when convex. Catches self-intersecting
/// "stars" whose turns all have the same sign.
pub(crate) fn non_convex_vertex(v: &[Vec2]) -> Option<usize> {
    let n = v.len();
    let c = |p: Vec2| robust::Coord { x: p.x, y: p.y };
    // A reflex (right) turn names the dent itself.
    for i in 0..n {
        let (a, b, d) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
        if robust::orient2d(c(a), c(b), c(d)) < 0.0 {
            return Some(i);
        }
    }
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        if a == b {
            return Some((i + 1) % n);
        }
        for (j, &p) in v.iter().enumerate() {
            if robust::orient2d(c(a), c(b), c(p)) < 0.0 {
                return Some(j);
            }
        }
    }
    None
}

impl Circle {
    /// Nearest boundary point of `p` (part frame).
    pub fn boundary_point(&self, p: Vec2) -> BoundaryPoint {
        let d = p - self.centre;
        let len = d.norm();
        let normal = if len > 0.0 {
            d / len
        } else {
            Vec2::new(1.0, 0.0)
        };
        BoundaryPoint {
            point: self.centre + normal * self.radius_m,
            normal,
            signed_distance_m: len - self.radius_m,
        }
    }

    /// Entry parameter of a segment into the disc, as for polygons.
    pub fn segment_entry(&self, a: Vec2, b: Vec2) -> Option<f64> {
        let d = b - a;
        let f = a - self.centre;
        let c = f.norm_squared() - self.radius_m * self.radius_m;
        if c <= 0.0 {
            return Some(0.0);
        }
        let qa = d.norm_squared();
        if qa == 0.0 {
            return None;
        }
        let qb = f.dot(&d);
        let disc = qb * qb - qa * c;
        if disc < 0.0 || qb > 0.0 {
            return None;
        }
        let s = (-qb - disc.sqrt()) / qa;
        (s <= 1.0).then_some(s.max(0.0))
    }
}

impl Part {
    /// Centre used by the potential field direction (area centroid or disc centre),
    /// part frame.
    pub fn centre(&self) -> Vec2 {
        match self {
            Part::Polygon(p) => p.centre,
            Part::Circle(c) => c.centre,
        }
    }

    /// Nearest boundary point (part frame).
    pub fn boundary_point(&self, p: Vec2) -> BoundaryPoint {
        match self {
            Part::Polygon(poly) => poly.boundary_point(p),
            Part::Circle(c) => c.boundary_point(p),
        }
    }

    /// Signed distance of `p` (part frame), m: negative inside.
    pub fn signed_distance(&self, p: Vec2) -> f64 {
        match self {
            Part::Polygon(poly) => poly.signed_distance(p),
            Part::Circle(c) => (p - c.centre).norm() - c.radius_m,
        }
    }

    /// Whether `p` (part frame) is inside or on the boundary.
    pub fn contains(&self, p: Vec2) -> bool {
        match self {
            Part::Polygon(poly) => poly.contains(p),
            Part::Circle(c) => (p - c.centre).norm_squared() <= c.radius_m * c.radius_m,
        }
    }

    /// Segment entry parameter (part frame).
    pub fn segment_entry(&self, a: Vec2, b: Vec2) -> Option<f64> {
        match self {
            Part::Polygon(poly) => poly.segment_entry(a, b),
            Part::Circle(c) => c.segment_entry(a, b),
        }
    }

    /// Smallest width (m): the diameter of a disc.
    pub fn min_width_m(&self) -> f64 {
        match self {
            Part::Polygon(poly) => poly.min_width_m(),
            Part::Circle(c) => 2.0 * c.radius_m,
        }
    }

    /// Largest distance from the part frame's origin to the part (m).
    pub fn reach_m(&self) -> f64 {
        match self {
            Part::Polygon(poly) => poly.vertices.iter().map(|v| v.norm()).fold(0.0, f64::max),
            Part::Circle(c) => c.centre.norm() + c.radius_m,
        }
    }

    /// Axis-aligned bounding box (part frame).
    pub fn aabb(&self) -> Rect {
        match self {
            Part::Polygon(poly) => {
                let mut r = Rect {
                    min: [f64::INFINITY; 2],
                    max: [f64::NEG_INFINITY; 2],
                };
                for v in &poly.vertices {
                    r.min = [r.min[0].min(v.x), r.min[1].min(v.y)];
                    r.max = [r.max[0].max(v.x), r.max[1].max(v.y)];
                }
                r
            }
            Part::Circle(c) => Rect {
                min: [c.centre.x - c.radius_m, c.centre.y - c.radius_m],
                max: [c.centre.x + c.radius_m, c.centre.y + c.radius_m],
            },
        }
    }

    /// Whether the interiors of two parts (same frame) overlap by more than
    /// [`TOUCH_TOLERANCE_M`].
    pub fn overlaps(&self, other: &Part) -> bool {
        match (self, other) {
            (Part::Circle(a), Part::Circle(b)) => {
                (a.centre - b.centre).norm() < a.radius_m + b.radius_m - TOUCH_TOLERANCE_M
            }
            (Part::Circle(c), Part::Polygon(p)) | (Part::Polygon(p), Part::Circle(c)) => {
                p.boundary_point(c.centre).signed_distance_m < c.radius_m - TOUCH_TOLERANCE_M
            }
            (Part::Polygon(a), Part::Polygon(b)) => !separated(a, b) && !separated(b, a),
        }
    }

    /// Gap between two parts in the same frame (m): 0 when they touch or overlap.
    pub fn gap_m(&self, other: &Part) -> f64 {
        if self.overlaps(other) {
            return 0.0;
        }
        let g = match (self, other) {
            (Part::Circle(a), Part::Circle(b)) => {
                (a.centre - b.centre).norm() - a.radius_m - b.radius_m
            }
            (Part::Circle(c), Part::Polygon(p)) | (Part::Polygon(p), Part::Circle(c)) => {
                p.boundary_point(c.centre).signed_distance_m - c.radius_m
            }
            (Part::Polygon(a), Part::Polygon(b)) => {
                // Separated convex polygons: the nearest pair has a vertex on one side.
                let ab = a
                    .vertices
                    .iter()
                    .map(|&v| b.boundary_point(v).signed_distance_m)
                    .fold(f64::INFINITY, f64::min);
                let ba = b
                    .vertices
                    .iter()
                    .map(|&v| a.boundary_point(v).signed_distance_m)
                    .fold(f64::INFINITY, f64::min);
                ab.min(ba)
            }
        };
        g.max(0.0)
    }
}

/// Whether an edge normal of `a` separates `a` and `b` (touching counts as
/// separated, within [`TOUCH_TOLERANCE_M`]).
fn separated(a: &ConvexPolygon, b: &ConvexPolygon) -> bool {
    a.edges().any(|(p, q)| {
        let e = q - p;
        let len = e.norm();
        if len <= 0.0 {
            return false;
        }
        let n = Vec2::new(e.y / len, -e.x / len);
        // `a` lies at n·(x − p) ≤ 0; `b` separated when all of it is at ≥ −tol.
        b.vertices
            .iter()
            .all(|&v| n.dot(&(v - p)) >= -TOUCH_TOLERANCE_M)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, s: f64) -> Part {
        Part::Polygon(
            ConvexPolygon::new(vec![
                Vec2::new(x0, y0),
                Vec2::new(x0 + s, y0),
                Vec2::new(x0 + s, y0 + s),
                Vec2::new(x0, y0 + s),
            ])
            .unwrap(),
        )
    }

    #[test]
    fn square_signed_distance_and_nearest_point() {
        let sq = square(0.0, 0.0, 2.0);
        // Inside, 0.5 from the left edge.
        let b = sq.boundary_point(Vec2::new(0.5, 1.0));
        assert!((b.signed_distance_m + 0.5).abs() < 1e-12);
        assert!((b.point - Vec2::new(0.0, 1.0)).norm() < 1e-12);
        assert!((b.normal - Vec2::new(-1.0, 0.0)).norm() < 1e-12);
        // Outside past a corner: distance to the corner.
        let b = sq.boundary_point(Vec2::new(3.0, 3.0));
        assert!((b.signed_distance_m - 2f64.sqrt()).abs() < 1e-12);
        assert!((b.point - Vec2::new(2.0, 2.0)).norm() < 1e-12);
        assert!((sq.centre() - Vec2::new(1.0, 1.0)).norm() < 1e-12);
    }

    proptest::proptest! {
        /// The polygon's own signed distance is the one of its nearest boundary
        /// point, bit for bit, inside, outside and on the boundary.
        #[test]
        fn polygon_signed_distance_is_the_boundary_points(
            x in -3.0f64..5.0,
            y in -3.0f64..5.0,
            k in 3usize..9,
            turn in 0.0f64..1.0,
        ) {
            // A regular k-gon of radius 1.5 about (1, 1), turned, and the square.
            let ngon: Vec<Vec2> = (0..k)
                .map(|i| {
                    let a = std::f64::consts::TAU * (i as f64 + turn) / k as f64;
                    Vec2::new(1.0 + 1.5 * a.cos(), 1.0 + 1.5 * a.sin())
                })
                .collect();
            let Part::Polygon(sq) = square(0.0, 0.0, 2.0) else { unreachable!() };
            for poly in [ConvexPolygon::new(ngon).unwrap(), sq] {
                for p in [Vec2::new(x, y), poly.vertices[0], (poly.vertices[0] + poly.vertices[1]) / 2.0] {
                    let want = poly.boundary_point(p).signed_distance_m;
                    proptest::prop_assert_eq!(poly.signed_distance(p).to_bits(), want.to_bits());
                }
            }
        }
    }

    #[test]
    fn clockwise_input_is_stored_counter_clockwise() {
        let p = ConvexPolygon::new(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
        ])
        .unwrap();
        assert!(signed_twice_area(p.vertices()) > 0.0);
        assert!((p.area_m2() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_star_with_same_sign_turns_is_not_convex() {
        // Pentagram: every turn is left, yet it crosses itself.
        let v: Vec<Vec2> = (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        assert!(non_convex_vertex(&v).is_some());
        assert!(ConvexPolygon::new(v).is_none());
    }

    #[test]
    fn segments_enter_polygons_and_circles_where_expected() {
        let sq = square(1.0, -1.0, 2.0);
        let s = sq
            .segment_entry(Vec2::new(0.0, 0.0), Vec2::new(4.0, 0.0))
            .unwrap();
        assert!((s - 0.25).abs() < 1e-12);
        assert!(sq
            .segment_entry(Vec2::new(0.0, 2.0), Vec2::new(4.0, 2.0))
            .is_none());
        let c = Part::Circle(Circle {
            centre: Vec2::new(2.0, 0.0),
            radius_m: 1.0,
        });
        let s = c
            .segment_entry(Vec2::new(0.0, 0.0), Vec2::new(4.0, 0.0))
            .unwrap();
        assert!((s - 0.25).abs() < 1e-12);
        assert!(c
            .segment_entry(Vec2::new(0.0, 0.0), Vec2::new(0.5, 0.0))
            .is_none());
        assert_eq!(
            c.segment_entry(Vec2::new(2.0, 0.0), Vec2::new(9.0, 0.0)),
            Some(0.0)
        );
    }

    #[test]
    fn gaps_and_overlaps_between_parts() {
        let a = square(0.0, 0.0, 1.0);
        let b = square(1.5, 0.0, 1.0);
        assert!(!a.overlaps(&b));
        assert!((a.gap_m(&b) - 0.5).abs() < 1e-12);
        let touching = square(1.0, 0.0, 1.0);
        assert!(!a.overlaps(&touching));
        assert_eq!(a.gap_m(&touching), 0.0);
        let over = square(0.5, 0.5, 1.0);
        assert!(a.overlaps(&over));
        let c = Part::Circle(Circle {
            centre: Vec2::new(3.0, 0.5),
            radius_m: 0.5,
        });
        assert!((a.gap_m(&c) - 1.5).abs() < 1e-12);
        assert!((b.gap_m(&c) - 0.0).abs() < 1e-12);
    }

    #[test]
    fn min_width_of_a_thin_wall_is_its_thickness() {
        let wall = Part::Polygon(
            ConvexPolygon::new(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(4.0, 0.0),
                Vec2::new(4.0, 0.3),
                Vec2::new(0.0, 0.3),
            ])
            .unwrap(),
        );
        assert!((wall.min_width_m() - 0.3).abs() < 1e-12);
    }

    #[test]
    fn placement_round_trips() {
        let pl = Placement::new(Vec2::new(3.0, -2.0), 0.7);
        let p = Vec2::new(1.25, 4.5);
        assert!((pl.to_world(pl.to_local(p)) - p).norm() < 1e-12);
        let q = Placement::new(Vec2::new(1.0, 0.0), std::f64::consts::FRAC_PI_2)
            .to_world(Vec2::new(1.0, 0.0));
        assert!((q - Vec2::new(1.0, 1.0)).norm() < 1e-12);
    }
}
