//! Formation shapes the crowd switches between (mesh-formation-control section 7.3).
//!
//! "A set of mesh shapes is registered to define formations that the crowd can switch
//! between", and "the formation is switched when the crowd pass over pre-defined
//! checkpoints embedded in the environment". A [`Formation`] is such a shape: a simple
//! polygon (convex or not) in its own frame, with `+x` the direction the crowd heads.
//! Only the shape matters: when the crowd switches, the outline is scaled to the
//! crowd's current area (so the density of agents stays), turned to its heading and
//! centred on it ([`Placement`]), then meshed ([`Formation::mesh`]): points on the
//! outline and on a square lattice inside it, triangulated by a constrained Delaunay
//! triangulation (spade) that keeps the outline's edges, so a concave notch (the
//! arrow's tail) stays open.
//!
//! The [`FormationLibrary`] holds the shipped shapes ([`SHIPPED`]: `square`,
//! `arrow`, `column`, `line`, `wedge`, `diamond`) and the config's own
//! (`formations.shapes`), which add to them or replace one of the same name.
//! Definitions are validated ([`Formation::new`]): a name, 3 to
//! [`MAX_OUTLINE_VERTICES`] finite vertices, no repeated vertex, no two edges
//! crossing or touching except neighbours at their shared vertex, a non-zero area.
//!
//! ```text
//!   arrow (+x: heading)        column              line
//!        ╲                    ┌────────────┐        ┌──┐
//!     ╲   ╲──▶ tip            └────────────┘        │  │
//!     ╱   ╱                                         │  │
//!        ╱                                          └──┘
//! ```

use crate::crowd::mesh::{MeshError, TriMesh};
use crate::geom::{cross, segment_distance_squared, twice_signed_area, Vec2};
use serde::{Deserialize, Serialize};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// Most vertices in one outline.
pub const MAX_OUTLINE_VERTICES: usize = 256;
/// Most shapes in the config's `formations.shapes`.
pub const MAX_FORMATIONS: usize = 64;
/// Most mesh vertices [`Formation::mesh`] is asked for.
pub const MAX_MESH_VERTICES: usize = 40_000;
/// Default `λ` of the least-effort pairing when the formation switches
/// (formation-transform eq. 3: equal weight on travel and on local structure).
pub const DEFAULT_LAMBDA: f64 = 0.5;
/// Name of the formation the crowd starts in (the config's `crowd.formation`
/// rectangle with its `mesh.cols × mesh.rows` grid).
pub const START: &str = "start";
/// Lattice points closer than this fraction of the spacing to the outline are left
/// out, so no triangle is a sliver against the boundary (dimensionless).
const CLEARANCE: f64 = 0.45;

/// One formation shape as written in the config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FormationDef {
    /// Name a scene checkpoint uses.
    pub name: String,
    /// The outline, a simple polygon in either winding, `+x` the heading. Units are
    /// free: the shape is scaled to the crowd's area.
    pub outline: Vec<(f64, f64)>,
}

/// The shipped shapes: `(name, outline)`, `+x` the heading.
pub const SHIPPED: &[(&str, &[(f64, f64)])] = &[
    // The start's usual shape.
    (
        "square",
        &[(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)],
    ),
    // A chevron with its tip ahead and a notch at the tail (Fig. 9a: "effective for
    // passing through a narrow corridor").
    (
        "arrow",
        &[(1.0, 0.0), (-1.0, 0.55), (-0.55, 0.0), (-1.0, -0.55)],
    ),
    // Four times as long as wide, along the heading: single file through a gap.
    (
        "column",
        &[(-2.0, -0.5), (2.0, -0.5), (2.0, 0.5), (-2.0, 0.5)],
    ),
    // Four times as wide as long, across the heading: a rank.
    (
        "line",
        &[(-0.5, -2.0), (0.5, -2.0), (0.5, 2.0), (-0.5, 2.0)],
    ),
    // A solid triangle pointing ahead.
    ("wedge", &[(1.0, 0.0), (-1.0, 1.0), (-1.0, -1.0)]),
    // A square turned by 45°, corner ahead.
    (
        "diamond",
        &[(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)],
    ),
];

/// What is wrong with a formation definition.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FormationError {
    /// The name is empty.
    #[error("a formation needs a name")]
    EmptyName,
    /// The name is the reserved start name.
    #[error("`{START}` is the formation the crowd starts in (crowd.formation); pick another name")]
    ReservedName,
    /// Too few or too many vertices.
    #[error("an outline needs 3 to {max} vertices, got {got}", max = MAX_OUTLINE_VERTICES)]
    VertexCount {
        /// Vertices given.
        got: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} is not finite")]
    NonFinite {
        /// Index in the outline.
        vertex: usize,
    },
    /// Two vertices are at the same place.
    #[error("vertices {a} and {b} are at the same place")]
    Repeated {
        /// First index.
        a: usize,
        /// Second index.
        b: usize,
    },
    /// Two edges cross or touch.
    #[error("edges {a} and {b} cross or touch: the outline must be a simple polygon (edge k runs from vertex k to k+1)")]
    SelfIntersecting {
        /// First edge.
        a: usize,
        /// Second edge.
        b: usize,
    },
    /// The outline encloses (almost) no area.
    #[error("the outline encloses no area")]
    NoArea,
}

impl FormationError {
    /// The field of [`FormationDef`] the problem is in (`name` or `outline`).
    pub fn field(&self) -> &'static str {
        match self {
            FormationError::EmptyName | FormationError::ReservedName => "name",
            _ => "outline",
        }
    }
}

/// A validated formation shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Formation {
    name: String,
    /// Counter-clockwise, centroid at the origin, area 1.
    outline: Vec<Vec2>,
}

/// Where and how large a formation is laid out.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Placement {
    /// Where the formation's centroid goes (m).
    pub centre_m: Vec2,
    /// The direction its `+x` axis points (any length > 0; zero or non-finite: `+x`).
    pub heading: Vec2,
    /// Its area (m²).
    pub area_m2: f64,
}

/// Whether closed segments `ab` and `cd` share a point.
fn segments_touch(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let o = |p: Vec2, q: Vec2, r: Vec2| cross(q - p, r - p);
    let on = |p: Vec2, q: Vec2, r: Vec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on(c, d, a))
        || (d2 == 0.0 && on(c, d, b))
        || (d3 == 0.0 && on(a, b, c))
        || (d4 == 0.0 && on(a, b, d))
}

/// Whether `p` is strictly inside the polygon (even-odd rule).
fn inside(poly: &[Vec2], p: Vec2) -> bool {
    let mut c = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                c = !c;
            }
        }
    }
    c
}

fn segment_distance(a: Vec2, b: Vec2, p: Vec2) -> f64 {
    segment_distance_squared(p, a, b).sqrt()
}

impl Formation {
    /// Validates a definition and normalises its outline (counter-clockwise,
    /// centroid at the origin, area 1).
    ///
    /// # Errors
    /// The first [`FormationError`] found.
    pub fn new(def: &FormationDef) -> Result<Formation, FormationError> {
        if def.name.trim().is_empty() {
            return Err(FormationError::EmptyName);
        }
        if def.name == START {
            return Err(FormationError::ReservedName);
        }
        let n = def.outline.len();
        if !(3..=MAX_OUTLINE_VERTICES).contains(&n) {
            return Err(FormationError::VertexCount { got: n });
        }
        if let Some(vertex) = def
            .outline
            .iter()
            .position(|&(x, y)| !(x.is_finite() && y.is_finite()))
        {
            return Err(FormationError::NonFinite { vertex });
        }
        let mut p: Vec<Vec2> = def.outline.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
        // Work relative to the first vertex and in units of the extent, so the
        // tests below do not depend on where or how large the outline was drawn.
        let o = p[0];
        let extent = p.iter().map(|q| (q - o).amax()).fold(0.0f64, f64::max);
        if !(extent > 0.0 && extent.is_finite()) {
            return Err(FormationError::NoArea);
        }
        for q in &mut p {
            *q = (*q - o) / extent;
        }
        for a in 0..n {
            for b in a + 1..n {
                if p[a] == p[b] {
                    return Err(FormationError::Repeated { a, b });
                }
            }
        }
        for a in 0..n {
            for b in a + 1..n {
                // Neighbouring edges share a vertex; they may only meet there, which
                // for distinct vertices means they are not collinear and overlapping.
                let adjacent = b == a + 1 || (a == 0 && b == n - 1);
                let (p0, p1) = (p[a], p[(a + 1) % n]);
                let (q0, q1) = (p[b], p[(b + 1) % n]);
                let hit = if adjacent {
                    // The far end of one edge lies on the other.
                    let (shared, far_a, far_b) = if b == a + 1 {
                        (p1, p0, q1)
                    } else {
                        (p0, p1, q0)
                    };
                    let on = |s: Vec2, e: Vec2, r: Vec2| {
                        cross(e - s, r - s) == 0.0 && (r - s).dot(&(e - s)) > 0.0
                    };
                    on(shared, far_a, far_b) || on(shared, far_b, far_a)
                } else {
                    segments_touch(p0, p1, q0, q1)
                };
                if hit {
                    return Err(FormationError::SelfIntersecting { a, b });
                }
            }
        }
        let a2 = twice_signed_area(&p);
        if a2.is_nan() || a2.abs() <= 1e-9 {
            return Err(FormationError::NoArea);
        }
        if a2 < 0.0 {
            p.reverse();
        }
        // Area centroid.
        let mut c = Vec2::zeros();
        for i in 0..n {
            let (u, v) = (p[i], p[(i + 1) % n]);
            c += (u + v) * cross(u, v);
        }
        c /= 3.0 * a2.abs();
        let s = (0.5 * a2.abs()).sqrt();
        for q in &mut p {
            *q = (*q - c) / s;
        }
        Ok(Formation {
            name: def.name.clone(),
            outline: p,
        })
    }

    /// Name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The normalised outline: counter-clockwise, centroid at the origin, area 1.
    pub fn outline(&self) -> &[Vec2] {
        &self.outline
    }

    /// The outline laid out at `place` (world frame, m, counter-clockwise).
    pub fn placed_outline(&self, place: &Placement) -> Vec<Vec2> {
        let h = place.heading;
        let n = h.norm();
        let (c, s) = if n > 0.0 && n.is_finite() {
            (h.x / n, h.y / n)
        } else {
            (1.0, 0.0)
        };
        let k = if place.area_m2.is_finite() && place.area_m2 > 0.0 {
            place.area_m2.sqrt()
        } else {
            1.0
        };
        self.outline
            .iter()
            .map(|q| place.centre_m + Vec2::new(c * q.x - s * q.y, s * q.x + c * q.y) * k)
            .collect()
    }

    /// A triangle mesh of the formation laid out at `place`, with about `vertices`
    /// vertices (at least the outline's; at most [`MAX_MESH_VERTICES`]).
    ///
    /// # Method
    /// With `A` the area and `P` the perimeter, the spacing `h` solves
    /// `A / h² + P / h = vertices` (lattice points inside plus points along the
    /// outline). Every outline edge gets `max(1, round(length / h))` equal pieces;
    /// lattice points of spacing `h` inside the outline, at least `0.45 h` from it,
    /// are added; the constrained Delaunay triangulation of all of them keeps the
    /// outline's edges, and its triangles inside the outline are the mesh.
    ///
    /// # Complexity
    /// `O(V · E)` for the clearance test (`E` outline pieces), then `O(V log V)`
    /// expected for the triangulation. Allocates: meant for a formation switch.
    ///
    /// # Errors
    /// A [`MeshError`] when the triangulation does not give a valid mesh (a shape
    /// too thin for the spacing, or a placement that is not finite).
    pub fn mesh(&self, place: &Placement, vertices: usize) -> Result<TriMesh, MeshError> {
        let poly = self.placed_outline(place);
        if let Some(vertex) = poly
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(MeshError::NonFinite { vertex });
        }
        let n = poly.len();
        let area = 0.5 * twice_signed_area(&poly);
        let perimeter: f64 = (0..n).map(|i| (poly[(i + 1) % n] - poly[i]).norm()).sum();
        let target = vertices.clamp(n, MAX_MESH_VERTICES) as f64;
        let h = (perimeter + (perimeter * perimeter + 4.0 * target * area).sqrt()) / (2.0 * target);
        let mut boundary = Vec::new();
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let pieces = ((b - a).norm() / h).round().max(1.0) as usize;
            boundary.extend((0..pieces).map(|j| a + (b - a) * (j as f64 / pieces as f64)));
        }
        let mut interior = Vec::new();
        let (mut lo, mut hi) = (poly[0], poly[0]);
        for p in &poly {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        // The lattice is centred on the placement so a symmetric shape gets a
        // symmetric mesh.
        let c = place.centre_m;
        let i0 = ((lo.x - c.x) / h).floor() as i64;
        let i1 = ((hi.x - c.x) / h).ceil() as i64;
        let j0 = ((lo.y - c.y) / h).floor() as i64;
        let j1 = ((hi.y - c.y) / h).ceil() as i64;
        let m = boundary.len();
        for j in j0..=j1 {
            for i in i0..=i1 {
                let p = c + Vec2::new(i as f64 * h, j as f64 * h);
                if inside(&poly, p)
                    && (0..m).all(|k| {
                        segment_distance(boundary[k], boundary[(k + 1) % m], p) >= CLEARANCE * h
                    })
                {
                    interior.push(p);
                }
            }
        }
        let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
            ConstrainedDelaunayTriangulation::new();
        let mut handles = Vec::with_capacity(m);
        for p in &boundary {
            match cdt.insert(Point2::new(p.x, p.y)) {
                Ok(v) => handles.push(v),
                Err(_) => {
                    return Err(MeshError::NonFinite {
                        vertex: handles.len(),
                    })
                }
            }
        }
        for k in 0..m {
            // A simple outline has no crossing pieces; should rounding make two
            // touch, the edge is left to the plain triangulation.
            let _ = cdt.try_add_constraint(handles[k], handles[(k + 1) % m]);
        }
        for p in &interior {
            if cdt.insert(Point2::new(p.x, p.y)).is_err() {
                return Err(MeshError::NonFinite { vertex: m });
            }
        }
        let rest: Vec<Vec2> = cdt
            .vertices()
            .map(|v| {
                let p = v.position();
                Vec2::new(p.x, p.y)
            })
            .collect();
        let triangles = inside_faces(&cdt);
        TriMesh::from_triangles(rest, triangles)
    }
}

/// The triangles of `cdt` inside its constraint loop: a face's side flips each
/// time a path from the outer face crosses a constraint edge, found by a flood fill
/// from the faces on the convex hull. (A centroid test would misjudge the thin
/// faces between collinear outline points that lie outside.)
fn inside_faces(cdt: &ConstrainedDelaunayTriangulation<Point2<f64>>) -> Vec<[u32; 3]> {
    let mut side: Vec<Option<bool>> = vec![None; cdt.num_all_faces()];
    let mut stack = Vec::new();
    for f in cdt.inner_faces() {
        for e in f.adjacent_edges() {
            if e.rev().face().is_outer() {
                let crossing = cdt.is_constraint_edge(e.fix().as_undirected());
                side[f.fix().index()] = Some(crossing);
                stack.push(f.fix());
                break;
            }
        }
    }
    while let Some(fx) = stack.pop() {
        let f = cdt.face(fx);
        let here = side[fx.index()].unwrap_or(false);
        for e in f.adjacent_edges() {
            if let Some(nb) = e.rev().face().as_inner() {
                let k = nb.fix().index();
                if side[k].is_none() {
                    side[k] = Some(here != cdt.is_constraint_edge(e.fix().as_undirected()));
                    stack.push(nb.fix());
                }
            }
        }
    }
    cdt.inner_faces()
        .filter(|f| side[f.fix().index()] == Some(true))
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect()
}

/// The shapes a crowd can switch to: the shipped ones and the config's.
#[derive(Clone, Debug, PartialEq)]
pub struct FormationLibrary {
    formations: Vec<Formation>,
}

impl Default for FormationLibrary {
    fn default() -> Self {
        FormationLibrary::shipped()
    }
}

impl FormationLibrary {
    /// The shipped shapes ([`SHIPPED`]).
    pub fn shipped() -> FormationLibrary {
        let formations = SHIPPED
            .iter()
            .filter_map(|(name, outline)| {
                Formation::new(&FormationDef {
                    name: (*name).to_string(),
                    outline: outline.to_vec(),
                })
                .ok()
            })
            .collect();
        FormationLibrary { formations }
    }

    /// The shipped shapes plus `defs`; a definition replaces a shipped shape of the
    /// same name.
    ///
    /// # Errors
    /// Every `(field, problem)` with `field` relative to the list (`[2].outline`):
    /// an invalid shape, a name given twice, more than [`MAX_FORMATIONS`]
    /// definitions (reported at the list itself, field `""`).
    pub fn with(defs: &[FormationDef]) -> Result<FormationLibrary, Vec<(String, String)>> {
        let mut lib = FormationLibrary::shipped();
        let mut problems = Vec::new();
        if defs.len() > MAX_FORMATIONS {
            problems.push((
                String::new(),
                format!(
                    "at most {MAX_FORMATIONS} formation shapes, got {}",
                    defs.len()
                ),
            ));
            return Err(problems);
        }
        for (i, d) in defs.iter().enumerate() {
            if defs[..i].iter().any(|e| e.name == d.name) {
                problems.push((
                    format!("[{i}].name"),
                    format!("formation `{}` is defined twice", d.name),
                ));
                continue;
            }
            match Formation::new(d) {
                Ok(f) => match lib.formations.iter_mut().find(|g| g.name == f.name) {
                    Some(g) => *g = f,
                    None => lib.formations.push(f),
                },
                Err(e) => problems.push((format!("[{i}].{}", e.field()), e.to_string())),
            }
        }
        if problems.is_empty() {
            Ok(lib)
        } else {
            Err(problems)
        }
    }

    /// The formation named `name`.
    pub fn get(&self, name: &str) -> Option<&Formation> {
        self.formations.iter().find(|f| f.name == name)
    }

    /// Names, shipped first, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> + '_ {
        self.formations.iter().map(|f| f.name.as_str())
    }

    /// Whether `name` is a known formation (a library name or [`START`]).
    pub fn knows(&self, name: &str) -> bool {
        name == START || self.get(name).is_some()
    }

    /// Every name a checkpoint or command may give: [`START`], then the library's.
    pub fn known_names(&self) -> Vec<&str> {
        std::iter::once(START).chain(self.names()).collect()
    }

    /// `start, square, arrow, …` for messages.
    pub fn names_list(&self) -> String {
        self.known_names().join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn def(name: &str, outline: &[(f64, f64)]) -> FormationDef {
        FormationDef {
            name: name.into(),
            outline: outline.to_vec(),
        }
    }

    fn place(x: f64, y: f64, hx: f64, hy: f64, area: f64) -> Placement {
        Placement {
            centre_m: Vec2::new(x, y),
            heading: Vec2::new(hx, hy),
            area_m2: area,
        }
    }

    /// Every mesh vertex on or inside the placed outline, area as asked, vertex count
    /// near the request, the mesh's own invariants.
    fn check_mesh(f: &Formation, p: &Placement, vertices: usize) -> TriMesh {
        let m = f
            .mesh(p, vertices)
            .unwrap_or_else(|e| panic!("{}: {e}", f.name()));
        m.sanity_check().unwrap();
        let poly = f.placed_outline(p);
        let n = poly.len();
        for (i, v) in m.rest().iter().enumerate() {
            let d = (0..n)
                .map(|k| segment_distance(poly[k], poly[(k + 1) % n], *v))
                .fold(f64::INFINITY, f64::min);
            assert!(
                inside(&poly, *v) || d < 1e-9 * p.area_m2.sqrt(),
                "{}: vertex {i} {v:?} outside",
                f.name()
            );
        }
        let rel = (m.area() - p.area_m2).abs() / p.area_m2;
        assert!(
            rel < 1e-9,
            "{}: area {} vs {}",
            f.name(),
            m.area(),
            p.area_m2
        );
        m
    }

    #[test]
    fn shipped_shapes_are_valid_and_mesh_at_the_asked_size_and_place() {
        let lib = FormationLibrary::shipped();
        assert_eq!(lib.names().count(), SHIPPED.len());
        for f in &lib.formations {
            assert!((0.5 * twice_signed_area(f.outline()) - 1.0).abs() < 1e-12);
            let p = place(8.0, 4.5, 1.0, 0.0, 12.0);
            let m = check_mesh(f, &p, 100);
            let v = m.vertex_count();
            assert!(
                (60..=140).contains(&v),
                "{}: {v} vertices for 100",
                f.name()
            );
            let c = m.rest().iter().sum::<Vec2>() / v as f64;
            assert!((c - p.centre_m).norm() < 0.6, "{}: centre {c:?}", f.name());
        }
    }

    #[test]
    fn the_heading_turns_the_shape() {
        let lib = FormationLibrary::shipped();
        let arrow = lib.get("arrow").unwrap();
        // Heading +y: the tip (the farthest point ahead) is straight above the centre.
        let p = place(0.0, 0.0, 0.0, 2.0, 4.0);
        let poly = arrow.placed_outline(&p);
        let tip = poly
            .iter()
            .copied()
            .max_by(|a, b| a.y.total_cmp(&b.y))
            .unwrap();
        assert!(tip.x.abs() < 1e-12 && tip.y > 1.0, "tip {tip:?}");
        // A column headed along x is four times longer in x than in y.
        let col = lib.get("column").unwrap();
        let m = check_mesh(col, &place(0.0, 0.0, 1.0, 0.0, 4.0), 80);
        let (lo, hi) = m.rest().iter().fold(
            (Vec2::repeat(f64::MAX), Vec2::repeat(f64::MIN)),
            |(l, h), p| (l.inf(p), h.sup(p)),
        );
        let ext = hi - lo;
        assert!((ext.x / ext.y - 4.0).abs() < 1e-9, "{ext:?}");
        // Zero heading: +x.
        let z = arrow.placed_outline(&place(0.0, 0.0, 0.0, 0.0, 1.0));
        let tip = z
            .iter()
            .copied()
            .max_by(|a, b| a.x.total_cmp(&b.x))
            .unwrap();
        assert!(tip.y.abs() < 1e-12);
    }

    #[test]
    fn the_arrows_notch_stays_open() {
        let arrow = FormationLibrary::shipped().get("arrow").cloned().unwrap();
        let p = place(0.0, 0.0, 1.0, 0.0, 10.0);
        let m = check_mesh(&arrow, &p, 200);
        // The notch vertex (outline vertex 2 of the definition, at the tail) is on
        // the outline and no triangle covers the notch between it and the tail tips.
        let poly = arrow.placed_outline(&p);
        let notch = poly
            .iter()
            .copied()
            .filter(|q| q.y.abs() < 1e-9)
            .min_by(|a, b| a.x.total_cmp(&b.x))
            .unwrap();
        let probe = notch - Vec2::new(0.1, 0.0);
        for t in m.triangles() {
            let [a, b, c] = t.map(|v| m.rest()[v as usize]);
            let o = |p: Vec2, q: Vec2| cross(q - p, probe - p) >= 0.0;
            assert!(
                !(o(a, b) && o(b, c) && o(c, a)),
                "a triangle covers the notch"
            );
        }
    }

    #[test]
    fn bad_definitions_are_named() {
        let cases: &[(FormationDef, FormationError)] = &[
            (
                def("", &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]),
                FormationError::EmptyName,
            ),
            (
                def("start", &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]),
                FormationError::ReservedName,
            ),
            (
                def("a", &[(0.0, 0.0), (1.0, 0.0)]),
                FormationError::VertexCount { got: 2 },
            ),
            (
                def("a", &[(0.0, 0.0), (f64::NAN, 0.0), (0.0, 1.0)]),
                FormationError::NonFinite { vertex: 1 },
            ),
            (
                def("a", &[(0.0, 0.0), (1.0, 0.0), (0.0, 0.0), (0.0, 1.0)]),
                FormationError::Repeated { a: 0, b: 2 },
            ),
            // A bow tie.
            (
                def("a", &[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]),
                FormationError::SelfIntersecting { a: 0, b: 2 },
            ),
            // Collinear.
            (
                def("a", &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]),
                FormationError::SelfIntersecting { a: 0, b: 2 },
            ),
            // A spike folding back on its own edge.
            (
                def("a", &[(0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (1.0, 1.0)]),
                FormationError::SelfIntersecting { a: 0, b: 1 },
            ),
            // Scale is free (a tiny triangle is fine), but a sliver has no area.
            (
                def("a", &[(0.0, 0.0), (1.0, 0.0), (0.5, 1e-12)]),
                FormationError::NoArea,
            ),
        ];
        for (d, want) in cases {
            assert_eq!(Formation::new(d).as_ref().err(), Some(want), "{d:?}");
        }
        // Either winding is fine and gives the same shape.
        let cw = Formation::new(&def("t", &[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)])).unwrap();
        let ccw = Formation::new(&def("t", &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])).unwrap();
        assert!(twice_signed_area(cw.outline()) > 0.0);
        let mut a: Vec<_> = cw.outline().iter().map(|p| (p.x, p.y)).collect();
        let mut b: Vec<_> = ccw.outline().iter().map(|p| (p.x, p.y)).collect();
        a.sort_by(|p, q| p.partial_cmp(q).unwrap());
        b.sort_by(|p, q| p.partial_cmp(q).unwrap());
        for (p, q) in a.iter().zip(&b) {
            assert!((p.0 - q.0).abs() < 1e-12 && (p.1 - q.1).abs() < 1e-12);
        }
    }

    #[test]
    fn the_library_adds_replaces_and_reports() {
        let star = def(
            "star",
            &[
                (1.0, 0.0),
                (0.2, 0.2),
                (0.0, 1.0),
                (-0.2, 0.2),
                (-1.0, 0.0),
                (-0.2, -0.2),
                (0.0, -1.0),
                (0.2, -0.2),
            ],
        );
        let sq = def("square", &[(0.0, 0.0), (3.0, 0.0), (3.0, 1.0), (0.0, 1.0)]);
        let lib = FormationLibrary::with(&[star.clone(), sq]).unwrap();
        assert!(lib.knows("star") && lib.knows("start") && !lib.knows("nope"));
        assert_eq!(lib.names().count(), SHIPPED.len() + 1);
        // The replaced square is 3:1 now.
        let o = lib.get("square").unwrap().outline();
        let w = o.iter().map(|p| p.x).fold(f64::MIN, f64::max)
            - o.iter().map(|p| p.x).fold(f64::MAX, f64::min);
        assert!((w - 3.0f64.sqrt()).abs() < 1e-12, "{w}");
        check_mesh(
            lib.get("star").unwrap(),
            &place(3.0, 3.0, 1.0, 1.0, 5.0),
            150,
        );
        let e = FormationLibrary::with(&[star.clone(), def("x", &[(0.0, 0.0)]), star]).unwrap_err();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].0, "[1].outline");
        assert_eq!(e[1].0, "[2].name");
        assert!(e[1].1.contains("defined twice"), "{e:?}");
        assert!(lib.names_list().starts_with("start, square, arrow"));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Random star-shaped polygons (simple, often concave), any placement and
        /// size: the mesh is valid, inside the outline and of the right area.
        #[test]
        fn star_shaped_outlines_mesh(
            radii in prop::collection::vec(0.3f64..1.0, 3..24),
            cx in -50.0f64..50.0, cy in -50.0f64..50.0,
            angle in 0.0f64..std::f64::consts::TAU,
            area in 0.05f64..400.0,
            vertices in 3usize..400,
        ) {
            let n = radii.len();
            let outline: Vec<(f64, f64)> = radii.iter().enumerate().map(|(i, r)| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                (r * a.cos(), r * a.sin())
            }).collect();
            let f = Formation::new(&def("s", &outline)).unwrap();
            let p = place(cx, cy, angle.cos(), angle.sin(), area);
            check_mesh(&f, &p, vertices);
        }

        /// Arbitrary outlines never panic: either an error or a usable shape.
        #[test]
        fn arbitrary_outlines_never_panic(pts in prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 0..12)) {
            if let Ok(f) = Formation::new(&def("r", &pts)) {
                let _ = f.mesh(&place(0.0, 0.0, 1.0, 0.0, 2.0), 60);
            }
        }
    }
}
