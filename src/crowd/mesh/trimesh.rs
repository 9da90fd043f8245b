//! The crowd's triangle mesh: rest pose, topology, nearest vertex and distance.
//!
//! The crowd is represented by a deformable triangle mesh (mesh-formation-control section
//! 4.1): a uniform grid over the formation rectangle ([`TriMesh::grid`]) or an arbitrary
//! triangulation of a formation shape ([`TriMesh::from_triangles`]). Fingers grab its
//! vertices ([`nearest_vertex`]); the deformation (`arap.rs`) and the goal points on
//! the mesh (`goals.rs`) are beside it in [`crate::crowd::mesh`].
//!
//! Orientation convention: a triangle `[a, b, c]` is counter-clockwise (CCW) when
//! `(b - a) × (c - a) > 0` with `u × v = u.x v.y - u.y v.x`, i.e. in a frame with x to the
//! right and y up. The outline is the boundary loop traversed in the same sense as the
//! triangles' own edges.
//!
//! Pieces: a mesh may consist of several *pieces* (connected components: triangles
//! joined through shared vertices), each a disc with one boundary loop — a crowd
//! split into groups far apart (`mesh_around`) is one piece per group, so
//! deforming one group leaves the others where they are. Pieces are numbered in the
//! order their first triangle appears; [`TriMesh::outlines`] has one loop per piece
//! and [`TriMesh::outline`] is the loop of the largest piece (by rest area), so a
//! one-piece mesh has exactly the outline it always had. Pieces are not checked for
//! overlapping each other in the plane (the triangulations that build them do not
//! produce overlaps).
//!
//! ```text
//!   row 1   3 ─── 4 ─── 5        grid(rect, 3, 2): vertex = row * cols + col,
//!           │   ╱ │ ╲   │        row 0 at rect.min[1]; the diagonal alternates
//!   row 0   0 ─── 1 ─── 2        per cell so the mesh has no preferred shear.
//! ```

use std::cmp::Ordering;
use std::collections::{HashMap, HashSet};

use crate::geom::{cross, segment_distance_squared, Rect, Vec2};

/// A triangle mesh with a rest pose.
///
/// Invariants (checked by [`TriMesh::sanity_check`], guaranteed by
/// [`TriMesh::from_triangles`] and by [`TriMesh::grid`] for a finite rectangle of
/// positive size): every rest position is finite, every vertex is used by a triangle,
/// every triangle is CCW with positive rest area, every directed edge occurs at most once
/// (a consistently oriented manifold), and every piece (vertex-connected component)
/// has a boundary that is a single closed CCW loop, stored in `outlines` (one per
/// piece, in piece order).
#[derive(Clone, Debug, PartialEq)]
pub struct TriMesh {
    rest: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
    /// One boundary loop per piece.
    outlines: Vec<Vec<u32>>,
    /// Piece index of every vertex.
    piece_of: Vec<u32>,
    /// Vertex ids of every piece, ascending.
    components: Vec<Vec<u32>>,
    /// Index of the piece with the largest rest area (lowest index on ties).
    largest: usize,
}

/// Why a triangle list is not a usable crowd mesh.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MeshError {
    /// No triangles were given.
    #[error("mesh has no triangles")]
    Empty,
    /// A rest position is NaN or infinite.
    #[error("rest position of vertex {vertex} is not finite")]
    NonFinite {
        /// The offending vertex.
        vertex: usize,
    },
    /// A triangle references a vertex that does not exist.
    #[error(
        "triangle {triangle} references vertex {vertex}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// The offending triangle.
        triangle: usize,
        /// The out-of-range vertex index.
        vertex: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A triangle has zero area (collinear or repeated corners).
    #[error("triangle {triangle} has zero area")]
    DegenerateTriangle {
        /// The offending triangle.
        triangle: usize,
    },
    /// A vertex is used by no triangle.
    #[error("vertex {vertex} is not used by any triangle")]
    UnusedVertex {
        /// The unused vertex.
        vertex: usize,
    },
    /// An edge is shared by more than two triangles, or by two with the same direction.
    #[error("edge {from} -> {to} is non-manifold or inconsistently oriented")]
    NonManifoldEdge {
        /// Edge start vertex.
        from: u32,
        /// Edge end vertex.
        to: u32,
    },
    /// The boundary edges of a piece do not form one simple closed loop (holes, a
    /// closed surface, or a vertex where the boundary touches itself — two triangles
    /// meeting only at a vertex are one piece with such a boundary).
    #[error("boundary of a piece is not a single simple closed loop (at vertex {vertex})")]
    BoundaryNotSingleLoop {
        /// A vertex where the loop structure fails.
        vertex: u32,
    },
}

/// Twice the signed area of `(a, b, c)`, positive when CCW, with an exact sign
/// (Shewchuk's adaptive predicate via `robust`).
fn orient(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let co = |v: Vec2| robust::Coord { x: v.x, y: v.y };
    robust::orient2d(co(a), co(b), co(c))
}

/// `‖a - b‖²`, spelled out (the sampling loops run it millions of times, also in
/// debug builds).
#[inline]
pub(super) fn dist2(a: Vec2, b: Vec2) -> f64 {
    let (dx, dy) = (a.x - b.x, a.y - b.y);
    dx * dx + dy * dy
}

/// Directed edges of a triangle, in its own winding: `(0,1)`, `(1,2)`, `(2,0)`.
pub(super) fn tri_edges(t: &[u32; 3]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
}

/// The pieces of a consistently oriented triangle set over `n` vertices and their
/// boundary loops, or why they are not a set of discs.
///
/// Returns `(outlines, piece_of)`: one boundary loop per piece (pieces numbered by
/// their first triangle, each loop starting at the first boundary edge of the piece
/// in triangle order) and the piece of every vertex (`u32::MAX` for an unused one).
fn boundary_loops(
    triangles: &[[u32; 3]],
    n: usize,
) -> Result<(Vec<Vec<u32>>, Vec<u32>), MeshError> {
    let mut directed: HashSet<(u32, u32)> = HashSet::with_capacity(triangles.len() * 3);
    for t in triangles {
        for (a, b) in tri_edges(t) {
            if !directed.insert((a, b)) {
                return Err(MeshError::NonManifoldEdge { from: a, to: b });
            }
        }
    }
    // Pieces: union-find over the vertices of each triangle.
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    }
    for t in triangles {
        let r = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let s = find(&mut parent, v);
            parent[s as usize] = r;
        }
    }
    let mut piece_of_root: HashMap<u32, u32> = HashMap::new();
    let mut piece_of = vec![u32::MAX; n];
    for t in triangles {
        let r = find(&mut parent, t[0]);
        let next_id = piece_of_root.len() as u32;
        let id = *piece_of_root.entry(r).or_insert(next_id);
        for &v in t {
            piece_of[v as usize] = id;
        }
    }
    let pieces = piece_of_root.len();
    // Boundary edges: directed edges whose reverse is absent. Walk them in triangle
    // order so each loop's start vertex is deterministic.
    let mut next: HashMap<u32, u32> = HashMap::new();
    let mut starts: Vec<Option<u32>> = vec![None; pieces];
    for t in triangles {
        for (a, b) in tri_edges(t) {
            if !directed.contains(&(b, a)) {
                if next.insert(a, b).is_some() {
                    return Err(MeshError::BoundaryNotSingleLoop { vertex: a });
                }
                starts[piece_of[a as usize] as usize].get_or_insert(a);
            }
        }
    }
    let mut outlines = Vec::with_capacity(pieces);
    let mut walked = 0;
    for (piece, start) in starts.into_iter().enumerate() {
        let Some(start) = start else {
            // A closed surface has no boundary; not a planar formation.
            let vertex = piece_of
                .iter()
                .position(|&p| p as usize == piece)
                .unwrap_or(0);
            return Err(MeshError::BoundaryNotSingleLoop {
                vertex: vertex as u32,
            });
        };
        let mut outline = Vec::new();
        let mut v = start;
        loop {
            outline.push(v);
            let Some(&w) = next.get(&v) else {
                return Err(MeshError::BoundaryNotSingleLoop { vertex: v });
            };
            if w == start {
                break;
            }
            if outline.len() >= next.len() {
                return Err(MeshError::BoundaryNotSingleLoop { vertex: w });
            }
            v = w;
        }
        walked += outline.len();
        outlines.push(outline);
    }
    if walked != next.len() {
        // A boundary edge on no walked loop: some piece has a second loop (a hole).
        let mut on_loop = vec![false; n];
        for &v in outlines.iter().flatten() {
            on_loop[v as usize] = true;
        }
        let vertex = next.keys().copied().filter(|&v| !on_loop[v as usize]).min();
        return Err(MeshError::BoundaryNotSingleLoop {
            vertex: vertex.unwrap_or(0),
        });
    }
    Ok((outlines, piece_of))
}

/// Vertex ids per piece (ascending) and the piece with the largest rest area
/// (lowest index on ties).
fn pieces_of(
    rest: &[Vec2],
    triangles: &[[u32; 3]],
    piece_of: &[u32],
    pieces: usize,
) -> (Vec<Vec<u32>>, usize) {
    let mut components = vec![Vec::new(); pieces];
    for (v, &p) in piece_of.iter().enumerate() {
        if let Some(c) = components.get_mut(p as usize) {
            c.push(v as u32);
        }
    }
    let mut area = vec![0.0; pieces];
    for t in triangles {
        let [a, b, c] = t.map(|v| rest[v as usize]);
        if let Some(s) = area.get_mut(piece_of[t[0] as usize] as usize) {
            *s += 0.5 * cross(b - a, c - a);
        }
    }
    let mut largest = 0;
    for (p, &s) in area.iter().enumerate() {
        if s > area[largest] {
            largest = p;
        }
    }
    (components, largest)
}

impl TriMesh {
    /// Uniform grid over `rect` with `cols × rows` vertices, each quad split into two CCW
    /// triangles with the diagonal alternating per cell (checkerboard), so the mesh has
    /// no preferred shear direction.
    ///
    /// Vertex index = `row * cols + col`, row 0 at `rect.min[1]`, column 0 at
    /// `rect.min[0]`. The outline starts at vertex 0 and runs along row 0 first.
    ///
    /// # Units
    /// `rect` in metres; positions in metres.
    ///
    /// # Complexity
    /// O(cols · rows).
    ///
    /// # Errors
    /// None: `cols` and `rows` below 2 are raised to 2. A rectangle of zero size or with
    /// non-finite corners gives a mesh that fails [`TriMesh::sanity_check`].
    ///
    /// ```
    /// use crowdtouch::crowd::mesh::TriMesh;
    /// use crowdtouch::geom::Rect;
    /// let m = TriMesh::grid(Rect { min: [0.0, 0.0], max: [4.0, 2.0] }, 5, 3);
    /// assert_eq!(m.vertex_count(), 15);
    /// assert_eq!(m.triangles().len(), 2 * 4 * 2);
    /// assert_eq!(m.outline().len(), 2 * (5 + 3) - 4);
    /// assert!((m.area() - 8.0).abs() < 1e-12);
    /// assert!(m.sanity_check().is_ok());
    /// ```
    pub fn grid(rect: Rect, cols: usize, rows: usize) -> TriMesh {
        let cols = cols.max(2);
        let rows = rows.max(2);
        let mut rest = Vec::with_capacity(cols * rows);
        for r in 0..rows {
            let ty = r as f64 / (rows - 1) as f64;
            let y = rect.min[1] + ty * rect.height();
            for c in 0..cols {
                let tx = c as f64 / (cols - 1) as f64;
                rest.push(Vec2::new(rect.min[0] + tx * rect.width(), y));
            }
        }
        let idx = |c: usize, r: usize| (r * cols + c) as u32;
        let mut triangles = Vec::with_capacity(2 * (cols - 1) * (rows - 1));
        for r in 0..rows - 1 {
            for c in 0..cols - 1 {
                let (a, b, d, e) = (idx(c, r), idx(c + 1, r), idx(c, r + 1), idx(c + 1, r + 1));
                if (c + r) % 2 == 0 {
                    // Diagonal a–e.
                    triangles.push([a, b, e]);
                    triangles.push([a, e, d]);
                } else {
                    // Diagonal b–d.
                    triangles.push([a, b, d]);
                    triangles.push([b, e, d]);
                }
            }
        }
        let mut outline = Vec::with_capacity(2 * (cols + rows) - 4);
        outline.extend((0..cols - 1).map(|c| idx(c, 0)));
        outline.extend((0..rows - 1).map(|r| idx(cols - 1, r)));
        outline.extend((1..cols).rev().map(|c| idx(c, rows - 1)));
        outline.extend((1..rows).rev().map(|r| idx(0, r)));
        let n = rest.len();
        TriMesh {
            rest,
            triangles,
            outlines: vec![outline],
            piece_of: vec![0; n],
            components: vec![(0..n as u32).collect()],
            largest: 0,
        }
    }

    /// Builds a mesh from rest positions and triangles (e.g. a Delaunay triangulation of a
    /// formation shape). Clockwise triangles are flipped to CCW; the pieces and their
    /// outlines are derived from the boundary edges. Several pieces are accepted, each
    /// a disc (one boundary loop).
    ///
    /// ```
    /// use crowdtouch::crowd::mesh::TriMesh;
    /// use crowdtouch::geom::Vec2;
    /// // Two triangles 5 m apart: two pieces.
    /// let p = |x: f64, y: f64| Vec2::new(x, y);
    /// let rest = vec![p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0), p(5.0, 0.0), p(7.0, 0.0), p(5.0, 2.0)];
    /// let m = TriMesh::from_triangles(rest, vec![[0, 1, 2], [3, 4, 5]]).unwrap();
    /// assert_eq!(m.piece_count(), 2);
    /// assert_eq!(m.components(), &[vec![0, 1, 2], vec![3, 4, 5]]);
    /// assert_eq!(m.outlines(), &[vec![0, 1, 2], vec![3, 4, 5]]);
    /// assert_eq!(m.outline(), &[3, 4, 5], "the larger piece's loop");
    /// ```
    ///
    /// # Complexity
    /// O(V + T) expected (hashing of edges).
    ///
    /// # Errors
    /// Any violated invariant of [`TriMesh`]: see [`MeshError`].
    pub fn from_triangles(rest: Vec<Vec2>, triangles: Vec<[u32; 3]>) -> Result<TriMesh, MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(vertex) = rest
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(MeshError::NonFinite { vertex });
        }
        let n = rest.len();
        let mut used = vec![false; n];
        let mut triangles = triangles;
        for (ti, t) in triangles.iter_mut().enumerate() {
            for &v in t.iter() {
                if v as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        triangle: ti,
                        vertex: v,
                        vertex_count: n,
                    });
                }
                used[v as usize] = true;
            }
            let o = orient(
                rest[t[0] as usize],
                rest[t[1] as usize],
                rest[t[2] as usize],
            );
            match o.partial_cmp(&0.0) {
                Some(Ordering::Greater) => {}
                Some(Ordering::Less) => t.swap(1, 2),
                _ => return Err(MeshError::DegenerateTriangle { triangle: ti }),
            }
        }
        if let Some(vertex) = used.iter().position(|u| !u) {
            return Err(MeshError::UnusedVertex { vertex });
        }
        let (outlines, piece_of) = boundary_loops(&triangles, n)?;
        let (components, largest) = pieces_of(&rest, &triangles, &piece_of, outlines.len());
        Ok(TriMesh {
            rest,
            triangles,
            outlines,
            piece_of,
            components,
            largest,
        })
    }

    /// Moves the rest pose by `d` (m); topology and goal samples stay valid.
    pub fn translate(&mut self, d: Vec2) {
        for p in &mut self.rest {
            *p += d;
        }
    }

    /// Rest positions (metres), one per vertex.
    pub fn rest(&self) -> &[Vec2] {
        &self.rest
    }

    /// Triangles as CCW vertex-index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The boundary loop (CCW vertex indices, first vertex not repeated at the end)
    /// of the largest piece by rest area: the mesh's only loop for a one-piece mesh.
    /// All pieces' loops: [`TriMesh::outlines`].
    pub fn outline(&self) -> &[u32] {
        &self.outlines[self.largest]
    }

    /// The boundary loop of every piece, in piece order (CCW vertex indices, first
    /// vertex not repeated at the end).
    pub fn outlines(&self) -> &[Vec<u32>] {
        &self.outlines
    }

    /// Number of pieces (connected components, each a disc with one boundary loop).
    pub fn piece_count(&self) -> usize {
        self.outlines.len()
    }

    /// The vertex ids of every piece (ascending), in piece order.
    pub fn components(&self) -> &[Vec<u32>] {
        &self.components
    }

    /// The piece of every vertex (index into [`TriMesh::components`]).
    pub fn piece_of_vertex(&self) -> &[u32] {
        &self.piece_of
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// Total rest area in m² (sum of the triangles' signed areas).
    ///
    /// # Complexity
    /// O(T).
    pub fn area(&self) -> f64 {
        self.area_at(&self.rest)
    }

    /// Total signed area in m² with the vertices at `positions` (a deformed pose;
    /// a missing vertex counts as the origin).
    ///
    /// # Complexity
    /// O(T).
    pub fn area_at(&self, positions: &[Vec2]) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| positions.get(v as usize).copied().unwrap_or_default());
                0.5 * cross(b - a, c - a)
            })
            .sum()
    }

    /// Checks the invariants (finite rest positions, indices in range, CCW positive
    /// rest areas, every vertex used, consistently oriented manifold edges, outline is
    /// the closed boundary loop). Returns a description of the first violation.
    ///
    /// # Complexity
    /// O(V + T) expected.
    ///
    /// # Errors
    /// A human-readable description of the first violated invariant (test helper).
    pub fn sanity_check(&self) -> Result<(), String> {
        let n = self.rest.len();
        if self.triangles.is_empty() {
            return Err("no triangles".into());
        }
        if let Some(v) = self
            .rest
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(format!("rest position of vertex {v} is not finite"));
        }
        let mut used = vec![false; n];
        for (ti, t) in self.triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
                return Err(format!("triangle {ti} references vertex {v} >= {n}"));
            }
            for &v in t {
                used[v as usize] = true;
            }
            let [a, b, c] = t.map(|v| self.rest[v as usize]);
            let o = orient(a, b, c);
            if o.partial_cmp(&0.0) != Some(Ordering::Greater) {
                return Err(format!(
                    "triangle {ti} {t:?} is not CCW with positive area (2A = {o})"
                ));
            }
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(format!("vertex {v} is not used by any triangle"));
        }
        let (expected, piece_of) = boundary_loops(&self.triangles, n).map_err(|e| e.to_string())?;
        if self.outlines.len() != expected.len() {
            return Err(format!(
                "{} outlines stored, the mesh has {} pieces",
                self.outlines.len(),
                expected.len()
            ));
        }
        if self.piece_of != piece_of {
            return Err("stored piece of a vertex differs from its component".into());
        }
        let (components, largest) =
            pieces_of(&self.rest, &self.triangles, &piece_of, expected.len());
        if self.components != components || self.largest != largest {
            return Err("stored components differ from the mesh's".into());
        }
        for (outline, expected) in self.outlines.iter().zip(&expected) {
            same_cycle(outline, expected)?;
        }
        Ok(())
    }

    /// For each vertex, one triangle using it and the corner (0..3) it occupies.
    pub(super) fn incident_corners(&self) -> Vec<Option<(u32, usize)>> {
        let mut inc = vec![None; self.rest.len()];
        for (ti, t) in self.triangles.iter().enumerate() {
            for (corner, &v) in t.iter().enumerate() {
                if let Some(slot) = inc.get_mut(v as usize) {
                    if slot.is_none() {
                        *slot = Some((ti as u32, corner));
                    }
                }
            }
        }
        inc
    }
}

/// Whether `outline` is the cyclic sequence `expected`, possibly starting elsewhere.
fn same_cycle(outline: &[u32], expected: &[u32]) -> Result<(), String> {
    if outline.len() != expected.len() {
        return Err(format!(
            "outline has {} vertices, the boundary loop has {}",
            outline.len(),
            expected.len()
        ));
    }
    let Some(shift) = outline.iter().position(|&v| v == expected[0]) else {
        return Err(format!("outline misses boundary vertex {}", expected[0]));
    };
    let m = expected.len();
    for (k, &e) in expected.iter().enumerate() {
        let got = outline[(shift + k) % m];
        if got != e {
            return Err(format!(
                "outline position {} is vertex {got}, the boundary loop has {e}",
                (shift + k) % m
            ));
        }
    }
    Ok(())
}

/// Nearest vertex of `positions` to `p`: `(index, distance)`.
///
/// # Units
/// Positions and distance in metres.
///
/// # Complexity
/// O(V), no allocation.
///
/// # Errors
/// None. An empty `positions` gives `(0, f64::INFINITY)`; non-finite positions are
/// never nearest.
///
/// ```
/// use crowdtouch::crowd::mesh::nearest_vertex;
/// use crowdtouch::geom::Vec2;
/// let pts = [Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0)];
/// let (i, d) = nearest_vertex(&pts, Vec2::new(1.5, 0.0));
/// assert_eq!(i, 1);
/// assert!((d - 0.5).abs() < 1e-12);
/// ```
pub fn nearest_vertex(positions: &[Vec2], p: Vec2) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for (i, q) in positions.iter().enumerate() {
        let d2 = dist2(*q, p);
        if d2 < best.1 {
            best = (i, d2);
        }
    }
    (best.0, best.1.sqrt())
}

/// Distance from `p` to the mesh whose vertices are at `positions` (0 inside any
/// triangle, whatever its orientation in the deformed pose).
///
/// # Formula
/// `min_t dist(p, triangle_t)`: zero when `p` is inside (or on) some triangle, else the
/// smallest distance to a triangle's edges.
///
/// # Units
/// Metres.
///
/// # Complexity
/// O(T), no allocation.
///
/// # Errors
/// None. Triangles with an index outside `positions` are skipped; no usable triangle
/// gives `f64::INFINITY`.
pub fn distance_to_mesh(mesh: &TriMesh, positions: &[Vec2], p: Vec2) -> f64 {
    let mut best2 = f64::INFINITY;
    for t in &mesh.triangles {
        let (Some(&a), Some(&b), Some(&c)) = (
            positions.get(t[0] as usize),
            positions.get(t[1] as usize),
            positions.get(t[2] as usize),
        ) else {
            continue;
        };
        let d1 = cross(b - a, p - a);
        let d2 = cross(c - b, p - b);
        let d3 = cross(a - c, p - c);
        let area2 = cross(b - a, c - a);
        if area2 != 0.0 {
            let all_pos = d1 >= 0.0 && d2 >= 0.0 && d3 >= 0.0;
            let all_neg = d1 <= 0.0 && d2 <= 0.0 && d3 <= 0.0;
            if all_pos || all_neg {
                return 0.0;
            }
        }
        let e = segment_distance_squared(p, a, b)
            .min(segment_distance_squared(p, b, c))
            .min(segment_distance_squared(p, c, a));
        best2 = best2.min(e);
    }
    best2.sqrt()
}

/// Test mesh of two pieces: a 4×3 grid over 2 m × 1 m at (-1, 2) and a 5×4 grid over
/// 3 m × 2 m `gap_m` to its right; the second's vertices (12..32) after the first's.
#[cfg(test)]
pub(super) fn two_grids(gap_m: f64) -> TriMesh {
    let a = TriMesh::grid(
        Rect {
            min: [-1.0, 2.0],
            max: [1.0, 3.0],
        },
        4,
        3,
    );
    let b = TriMesh::grid(
        Rect {
            min: [1.0 + gap_m, 2.0],
            max: [4.0 + gap_m, 4.0],
        },
        5,
        4,
    );
    let off = a.vertex_count() as u32;
    let rest: Vec<Vec2> = a.rest().iter().chain(b.rest()).copied().collect();
    let tris: Vec<[u32; 3]> = a
        .triangles()
        .iter()
        .copied()
        .chain(b.triangles().iter().map(|t| t.map(|v| v + off)))
        .collect();
    TriMesh::from_triangles(rest, tris).expect("two discs")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: f64, h: f64) -> Rect {
        Rect {
            min: [-1.0, 2.0],
            max: [-1.0 + w, 2.0 + h],
        }
    }

    #[test]
    fn grid_sanity_for_several_sizes() {
        for (c, r) in [(2, 2), (3, 2), (2, 5), (5, 7), (10, 8), (20, 20), (31, 4)] {
            let m = TriMesh::grid(rect(3.0, 2.0), c, r);
            m.sanity_check().unwrap_or_else(|e| panic!("{c}x{r}: {e}"));
            assert_eq!(m.vertex_count(), c * r);
            assert_eq!(m.triangles().len(), 2 * (c - 1) * (r - 1));
            assert_eq!(m.outline().len(), 2 * (c + r) - 4);
            assert!((m.area() - 6.0).abs() < 1e-12);
            assert_eq!(m.rest()[0], Vec2::new(-1.0, 2.0));
            assert_eq!(m.rest()[c * r - 1], Vec2::new(2.0, 4.0));
            assert_eq!(
                m.rest()[c],
                Vec2::new(-1.0, 2.0 + 2.0 / (r - 1) as f64),
                "row 1 starts at index cols"
            );
        }
    }

    #[test]
    fn grid_alternates_the_diagonal() {
        let m = TriMesh::grid(rect(1.0, 1.0), 3, 3);
        // Cell (0,0) has diagonal 0–4, cell (1,0) has diagonal 2–4 (b–d).
        let has_edge = |a: u32, b: u32| {
            m.triangles()
                .iter()
                .any(|t| tri_edges(t).iter().any(|&e| e == (a, b) || e == (b, a)))
        };
        assert!(has_edge(0, 4));
        assert!(!has_edge(1, 3));
        assert!(has_edge(2, 4));
        assert!(!has_edge(1, 5));
    }

    #[test]
    fn grid_clamps_small_counts_and_degenerate_rect_fails_sanity() {
        let m = TriMesh::grid(rect(1.0, 1.0), 0, 1);
        assert_eq!(m.vertex_count(), 4);
        assert!(m.sanity_check().is_ok());
        let flat = TriMesh::grid(rect(1.0, 0.0), 3, 3);
        assert!(flat.sanity_check().is_err());
    }

    #[test]
    fn from_triangles_rebuilds_the_grid_and_flips_cw() {
        let g = TriMesh::grid(rect(2.0, 1.0), 4, 3);
        let mut tris = g.triangles().to_vec();
        tris[3].swap(0, 1);
        let m = TriMesh::from_triangles(g.rest().to_vec(), tris).expect("valid");
        m.sanity_check().expect("sane");
        assert_eq!(m.outline().len(), g.outline().len());
        // Same cyclic outline.
        let shift = g
            .outline()
            .iter()
            .position(|&v| v == m.outline()[0])
            .expect("shared vertex");
        for k in 0..g.outline().len() {
            assert_eq!(m.outline()[k], g.outline()[(shift + k) % g.outline().len()]);
        }
    }

    #[test]
    fn from_triangles_errors() {
        let p = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
        ];
        assert_eq!(
            TriMesh::from_triangles(p.clone(), vec![]),
            Err(MeshError::Empty)
        );
        assert_eq!(
            TriMesh::from_triangles(p.clone(), vec![[0, 1, 7]]),
            Err(MeshError::IndexOutOfRange {
                triangle: 0,
                vertex: 7,
                vertex_count: 4
            })
        );
        assert_eq!(
            TriMesh::from_triangles(p.clone(), vec![[0, 1, 2]]),
            Err(MeshError::UnusedVertex { vertex: 3 })
        );
        let mut q = p.clone();
        q[3] = Vec2::new(2.0, 0.0);
        assert_eq!(
            TriMesh::from_triangles(q, vec![[0, 1, 3], [0, 1, 2]]),
            Err(MeshError::DegenerateTriangle { triangle: 0 })
        );
        let mut nan = p.clone();
        nan[2].x = f64::NAN;
        assert_eq!(
            TriMesh::from_triangles(nan, vec![[0, 1, 2]]),
            Err(MeshError::NonFinite { vertex: 2 })
        );
        // Three triangles on one edge.
        let mut fan = p.clone();
        fan.push(Vec2::new(0.5, -1.0));
        assert!(matches!(
            TriMesh::from_triangles(fan, vec![[0, 1, 2], [0, 1, 3], [1, 0, 4]]),
            Err(MeshError::NonManifoldEdge { .. })
        ));
        // Two triangles touching at one vertex: the boundary is not a simple loop.
        let bow = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(-1.0, 0.0),
            Vec2::new(0.0, -1.0),
        ];
        assert!(matches!(
            TriMesh::from_triangles(bow, vec![[0, 1, 2], [0, 3, 4]]),
            Err(MeshError::BoundaryNotSingleLoop { .. })
        ));
    }

    #[test]
    fn two_pieces_are_accepted_with_one_outline_each() {
        let m = two_grids(1.0);
        m.sanity_check().expect("sane");
        assert_eq!(m.piece_count(), 2);
        assert_eq!(m.components()[0], (0..12).collect::<Vec<u32>>());
        assert_eq!(m.components()[1], (12..32).collect::<Vec<u32>>());
        assert!(m.piece_of_vertex()[..12].iter().all(|&p| p == 0));
        assert!(m.piece_of_vertex()[12..].iter().all(|&p| p == 1));
        assert_eq!(m.outlines()[0].len(), 2 * (4 + 3) - 4);
        assert_eq!(m.outlines()[1].len(), 2 * (5 + 4) - 4);
        assert!(m.outlines()[1].iter().all(|&v| v >= 12));
        // The larger piece's loop is `outline`.
        assert_eq!(m.outline(), m.outlines()[1].as_slice());
        assert!((m.area() - (2.0 + 6.0)).abs() < 1e-12);
        // A one-piece mesh: one outline, the same as `outline`.
        let g = TriMesh::grid(rect(2.0, 1.0), 4, 3);
        assert_eq!(g.outlines(), &[g.outline().to_vec()]);
        assert_eq!(g.piece_count(), 1);
        // A stored piece list that disagrees is caught.
        let mut bad = m.clone();
        bad.outlines.swap(0, 1);
        assert!(bad.sanity_check().is_err());
        let mut bad = m.clone();
        bad.outlines.pop();
        assert!(bad.sanity_check().is_err());
        let mut bad = m;
        bad.largest = 0;
        assert!(bad.sanity_check().is_err());
    }

    #[test]
    fn a_piece_with_a_hole_or_a_closed_piece_is_refused() {
        // A 4x4 grid without its two middle triangles: an annulus.
        let g = TriMesh::grid(rect(3.0, 3.0), 4, 4);
        let centre: Vec<[u32; 3]> = g
            .triangles()
            .iter()
            .copied()
            .filter(|t| !(t.contains(&5) && t.contains(&10)))
            .collect();
        assert_eq!(centre.len(), g.triangles().len() - 2);
        assert!(matches!(
            TriMesh::from_triangles(g.rest().to_vec(), centre.clone()),
            Err(MeshError::BoundaryNotSingleLoop { .. })
        ));
        // The same annulus next to a good piece: still refused.
        let m = two_grids(1.0);
        let off = g.vertex_count() as u32;
        let rest: Vec<Vec2> = g.rest().iter().chain(m.rest()).copied().collect();
        let mut tris = centre;
        tris.extend(m.triangles().iter().map(|t| t.map(|v| v + off)));
        assert!(matches!(
            TriMesh::from_triangles(rest, tris),
            Err(MeshError::BoundaryNotSingleLoop { .. })
        ));
        // A tetrahedron's surface drawn flat cannot be all CCW; but the boundary walk
        // also rejects a piece without boundary edges.
        assert!(matches!(
            boundary_loops(&[[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]], 4),
            Err(MeshError::BoundaryNotSingleLoop { .. })
        ));
    }

    #[test]
    fn sanity_check_catches_broken_outline_and_orientation() {
        let g = TriMesh::grid(rect(1.0, 1.0), 3, 3);
        let mut bad = g.clone();
        bad.outlines[0].reverse();
        assert!(bad.sanity_check().is_err());
        let mut bad = g.clone();
        bad.outlines[0].pop();
        assert!(bad.sanity_check().is_err());
        let mut bad = g.clone();
        bad.triangles[0].swap(1, 2);
        assert!(bad.sanity_check().is_err());
        let mut bad = g;
        bad.triangles[0][0] = 99;
        assert!(bad.sanity_check().is_err());
    }

    #[test]
    fn nearest_vertex_and_distance() {
        let m = TriMesh::grid(
            Rect {
                min: [0.0, 0.0],
                max: [2.0, 1.0],
            },
            3,
            2,
        );
        assert_eq!(
            nearest_vertex(m.rest(), Vec2::new(1.9, 0.8)),
            (5, (0.01f64 + 0.04).sqrt())
        );
        assert_eq!(nearest_vertex(&[], Vec2::zeros()), (0, f64::INFINITY));
        let d = |x: f64, y: f64| distance_to_mesh(&m, m.rest(), Vec2::new(x, y));
        assert_eq!(d(0.3, 0.7), 0.0);
        assert_eq!(d(1.0, 0.5), 0.0);
        assert_eq!(d(2.0, 1.0), 0.0);
        assert!((d(3.0, 0.5) - 1.0).abs() < 1e-12);
        assert!((d(-3.0, 5.0) - 5.0).abs() < 1e-12);
        // A folded (inverted) triangle still counts as covered.
        let mut pos = m.rest().to_vec();
        pos.swap(0, 1);
        assert_eq!(distance_to_mesh(&m, &pos, Vec2::new(0.5, 0.1)), 0.0);
        assert_eq!(distance_to_mesh(&m, &[], Vec2::zeros()), f64::INFINITY);
    }
}
