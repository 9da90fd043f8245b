//! The spatial editor: a concave-hull cage deformed as rigidly as possible
//! (crowd-motion-editing section 3.2, eqs. 1–9).
//!
//! The cage vertices `v̂` (`n` of them, the hull of `hull.rs`) are the unknowns. Every
//! selected sample is tied to them by its mean value coordinates (MVC) with respect to
//! the rest hull, so its deformed position is `λᵀ v̂`. The deformation mesh is the
//! Delaunay triangulation (spade) of the hull vertices and one selected sample per
//! occupied grid cell (the hull's representatives), keeping the triangles whose
//! centroid lies inside the hull; its vertex positions are `T v̂` with `T` the `m × n`
//! matrix of eq. 4 (MVC rows for the samples, identity rows for the hull vertices).
//! Deforming the mesh on a thinned point set and applying the MVC to every selected
//! sample keeps a drag cheap however many samples are selected.
//!
//! A drag solves eq. 1 (no fixed handle) or eq. 6 (with fixed handles):
//!
//! ```text
//! min  ω_D² E_D + ω_F² E_F          (eq. 1)      min  ω_D² E_D + ω_S² E_S     (eq. 6)
//! s.t. M v̂ = h                                   s.t. M v̂ = h
//!
//! E_D = Σ_t Σ_edges ‖(T v̂)_i − (T v̂)_j − R_t (p_i − p_j)‖²      ARAP, eq. 2
//! E_F = ‖C (T v̂ − c)‖²,  C_ii = α d_i e^{c_i − k} + β c_i          eqs. 3, 5
//! E_S = ‖D v̂ − D v̂_rest‖²  (hull edge vectors)                     eqs. 7, 8
//! ```
//!
//! `c_i` is the breadth-first layer of mesh vertex `i` from the dragged vertices and
//! `d_i` its distance to the nearest of them (rest positions); the dragged vertices
//! get coefficient 0. Each handle (a hull vertex, or a selected sample through its MVC
//! row) contributes one row of `M`; dragged handles take their targets, fixed handles
//! keep their rest positions. The local/global iteration fits one rotation per triangle
//! (closed-form 2-D Procrustes) and then solves the equality-constrained least squares
//! exactly through its KKT system
//!
//! ```text
//! ⎡ A  Mᵀ ⎤ ⎡ v̂ ⎤   ⎡ ω_D² Tᵀ b_D(R) + b_0 ⎤
//! ⎣ M  0  ⎦ ⎣ μ ⎦ = ⎣ h                    ⎦ ,
//! A = ω_D² Tᵀ L T + ω_F² Tᵀ C² T   (or + ω_S² Dᵀ D),
//! ```
//!
//! one LU factorisation shared by x and y. `Tᵀ L T` (`L` the mesh's edge Laplacian)
//! is computed once per cage; the KKT factorisation once per handle set, so a
//! continuing drag of the same handles costs `iterations` × (two `m × n` products and
//! two triangular solves) plus one `N × n` product for the `N` selected samples, with no
//! allocation.

use super::error::EditError;
use super::hull::{concave_hull, Hull, HullParams};
use super::select::{point_in_polygon, SampleRef, Selection};
use super::tracks::TrackSet;
use crate::crowd::mesh::{MVC_EDGE_EPS, MVC_VERTEX_EPS};
use crate::geom::{cross, Rect, Vec2};
use nalgebra::{DMatrix, Dyn, LU};
use spade::{DelaunayTriangulation, Point2, Triangulation};
use std::collections::VecDeque;

/// Eq. 5's α (per metre), the paper's value.
pub const PAPER_ALPHA: f64 = 0.01;
/// Eq. 5's threshold k (layers), the paper's value.
pub const PAPER_K: f64 = 300.0;
/// Eq. 5's β (per layer), the paper's value.
pub const PAPER_BETA: f64 = 0.02;

/// Fewest speed-corrected interval, as a fraction of the pre-edit interval: a segment
/// the edit shrank to (nearly) nothing keeps at least this share of its time, so times
/// stay strictly increasing.
pub const MIN_INTERVAL_FRACTION: f64 = 1e-3;

/// Parameters of the spatial editor.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CageParams {
    /// The cage polygon.
    pub hull: HullParams,
    /// Eq. 5's α (1/m).
    pub alpha: f64,
    /// Eq. 5's k (layers).
    pub k: f64,
    /// Eq. 5's β (1/layer).
    pub beta: f64,
    /// ω_D, weight of the rigidity energy (eq. 2).
    pub w_d: f64,
    /// ω_F, weight of the locality energy (eq. 3).
    pub w_f: f64,
    /// ω_S, weight of the hull edge energy (eq. 7), used instead of ω_F when a drag
    /// has fixed handles (eq. 6).
    pub w_s: f64,
    /// Local/global iterations per drag.
    pub iterations: usize,
    /// Drag targets must lie inside this rectangle, when given (m).
    pub world: Option<Rect>,
}

impl Default for CageParams {
    fn default() -> Self {
        CageParams {
            hull: HullParams::default(),
            alpha: PAPER_ALPHA,
            k: PAPER_K,
            beta: PAPER_BETA,
            w_d: 1.0,
            w_f: 1.0,
            w_s: 1.0,
            iterations: 4,
            world: None,
        }
    }
}

/// Something a drag can hold: a cage vertex, or a selected sample (held through its
/// mean value coordinates).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Handle {
    /// Hull vertex index.
    Hull(usize),
    /// A selected sample.
    Sample(SampleRef),
}

impl std::fmt::Display for Handle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Handle::Hull(i) => write!(f, "hull vertex {i}"),
            Handle::Sample(r) => write!(f, "track {} sample {}", r.track, r.sample),
        }
    }
}

/// How far the deformed hull's shape is from the rest hull's.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ShapeError {
    /// `sqrt(mean_i ((‖e'_i‖ − ‖e_i‖) / ‖e_i‖)²)` over the hull edges (dimensionless).
    pub edge_length_rms: f64,
    /// `sqrt(mean_i (θ'_i − θ_i)²)` over the hull's turning angles, radians.
    pub angle_rms_rad: f64,
}

/// The factorised KKT system of one handle set.
struct Solver {
    drags: Vec<Handle>,
    fixed: Vec<Handle>,
    /// Rows of `M` (K × n).
    rows: DMatrix<f64>,
    lu: LU<f64, Dyn, Dyn>,
    /// The constant part of the right-hand side, `ω_F² Tᵀ C² c` or `ω_S² Dᵀ D v̂_rest`
    /// (n × 2).
    b0: DMatrix<f64>,
    /// Right-hand side and solution ((n + K) × 2).
    rhs: DMatrix<f64>,
}

/// The spatial editor of one selection (see the module documentation).
pub struct Cage {
    params: CageParams,
    hull: Hull,
    deformed: DMatrix<f64>,
    selection: Vec<SampleRef>,
    rest_points: Vec<Vec2>,
    points: DMatrix<f64>,
    /// MVC of every selected sample w.r.t. the rest hull (N × n).
    t_all: DMatrix<f64>,
    mesh_rest: Vec<Vec2>,
    /// Eq. 4's T for the mesh vertices (m × n).
    t_mesh: DMatrix<f64>,
    triangles: Vec<[u32; 3]>,
    neighbours: Vec<Vec<u32>>,
    /// `Tᵀ L T` (n × n).
    normal_d: DMatrix<f64>,
    solver: Option<Solver>,
    mesh_pos: DMatrix<f64>,
    b_mesh: DMatrix<f64>,
    b_hull: DMatrix<f64>,
}

/// Mean value coordinates w.r.t. one polygon, with the per-polygon checks done once:
/// the same arithmetic as [`crate::crowd::mesh::mean_value_coordinates`] (each `‖v_i − p‖` computed once and
/// shared by the vertex test and both adjacent edges), so the same coordinates.
struct HullMvc<'a> {
    poly: &'a [Vec2],
    /// `MVC_VERTEX_EPS` × the polygon's bounding-box diagonal.
    vertex_eps: f64,
}

impl<'a> HullMvc<'a> {
    /// `None` when `mean_value_coordinates` would fail for every point: fewer than
    /// three vertices, a non-finite vertex, or a degenerate bounding box.
    fn new(poly: &'a [Vec2]) -> Option<HullMvc<'a>> {
        if poly.len() < 3 || !poly.iter().all(|v| finite(*v)) {
            return None;
        }
        let (mut lo, mut hi) = (poly[0], poly[0]);
        for v in poly {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        let scale = (hi - lo).norm();
        if scale.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        Some(HullMvc {
            poly,
            vertex_eps: MVC_VERTEX_EPS * scale,
        })
    }

    /// The coordinates of `p` into `out` (`r` is scratch, both of the polygon's
    /// length); `None` where `mean_value_coordinates` returns an error.
    fn coordinates(&self, p: Vec2, r: &mut [f64], out: &mut [f64]) -> Option<()> {
        let poly = self.poly;
        let n = poly.len();
        out.fill(0.0);
        if !finite(p) {
            return None;
        }
        for (ri, v) in r.iter_mut().zip(poly) {
            *ri = (v - p).norm();
        }
        if let Some(i) = r.iter().position(|&ri| ri <= self.vertex_eps) {
            out[i] = 1.0;
            return Some(());
        }
        let mut tan_prev = 0.0;
        for i in 0..n {
            let j = if i + 1 == n { 0 } else { i + 1 };
            let (di, dj) = (poly[i] - p, poly[j] - p);
            let (ri, rj) = (r[i], r[j]);
            let a = cross(di, dj);
            let d = di.dot(&dj);
            let rr = ri * rj;
            if a.abs() <= MVC_EDGE_EPS * rr && d < 0.0 {
                out.fill(0.0);
                out[i] = rj / (ri + rj);
                out[j] = ri / (ri + rj);
                return Some(());
            }
            let t = if d >= 0.0 { a / (rr + d) } else { (rr - d) / a };
            out[i] = t / ri;
            if i > 0 {
                out[i] += tan_prev / ri;
            }
            tan_prev = t;
        }
        out[0] += tan_prev / r[0];
        let sum: f64 = out.iter().sum();
        if !(sum.is_finite() && sum != 0.0) {
            out.fill(0.0);
            return None;
        }
        for w in out.iter_mut() {
            *w /= sum;
        }
        if !out.iter().all(|w| w.is_finite()) {
            out.fill(0.0);
            return None;
        }
        Some(())
    }
}

fn finite(p: Vec2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

impl Cage {
    /// Builds the cage, the mesh, the MVC of every selected sample and `Tᵀ L T`.
    ///
    /// # Complexity
    /// O(N n) for the MVC of N samples and n hull vertices, O(m n²) for `Tᵀ L T` on m
    /// mesh vertices.
    ///
    /// # Errors
    /// [`EditError::SelectionMismatch`] when `sel` was made on another set; the
    /// errors of [`concave_hull`]; [`EditError::DegenerateHull`] when a sample's MVC
    /// are undefined or the mesh has no triangle.
    pub fn new(set: &TrackSet, sel: &Selection, params: &CageParams) -> Result<Cage, EditError> {
        let rest_points = sel.points(set)?;
        let hull = concave_hull(&rest_points, &params.hull)?;
        let n = hull.vertices.len();
        let big_n = rest_points.len();
        let mvc = HullMvc::new(&hull.vertices).ok_or(EditError::DegenerateHull {
            reason: "mean value coordinates undefined for a selected sample",
        })?;
        // Rows are computed a block of samples at a time into a small row-major buffer
        // and copied into the column-major matrix column by column.
        const BLOCK: usize = 32;
        let mut t_all = DMatrix::zeros(big_n, n);
        let mut rows = vec![0.0; BLOCK * n];
        let mut r = vec![0.0; n];
        for (b, block) in rest_points.chunks(BLOCK).enumerate() {
            for (p, row) in block.iter().zip(rows.chunks_exact_mut(n)) {
                mvc.coordinates(*p, &mut r, row)
                    .ok_or(EditError::DegenerateHull {
                        reason: "mean value coordinates undefined for a selected sample",
                    })?;
            }
            let i0 = b * BLOCK;
            for j in 0..n {
                let col = &mut t_all.column_mut(j);
                for k in 0..block.len() {
                    col[i0 + k] = rows[k * n + j];
                }
            }
        }
        // Mesh: hull vertices then the representatives, duplicates skipped.
        let mut dt: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
        let mut spade_to_mesh: Vec<u32> = Vec::new();
        let mut mesh_rest: Vec<Vec2> = Vec::new();
        let mut mesh_source: Vec<Option<usize>> = Vec::new();
        let candidates = hull.vertices.iter().map(|v| (*v, None)).chain(
            hull.representatives
                .iter()
                .map(|&i| (rest_points[i], Some(i))),
        );
        for (p, src) in candidates {
            let h = dt
                .insert(Point2::new(p.x, p.y))
                .map_err(|_| EditError::DegenerateHull {
                    reason: "a mesh vertex cannot be triangulated",
                })?;
            if h.index() >= spade_to_mesh.len() {
                spade_to_mesh.resize(h.index() + 1, u32::MAX);
            }
            if spade_to_mesh[h.index()] == u32::MAX {
                spade_to_mesh[h.index()] = mesh_rest.len() as u32;
                mesh_rest.push(p);
                mesh_source.push(src);
            }
        }
        let m = mesh_rest.len();
        let mut triangles = Vec::new();
        for f in dt.inner_faces() {
            let t = f.vertices().map(|h| spade_to_mesh[h.fix().index()]);
            let c =
                (mesh_rest[t[0] as usize] + mesh_rest[t[1] as usize] + mesh_rest[t[2] as usize])
                    / 3.0;
            if point_in_polygon(&hull.vertices, c) {
                triangles.push(t);
            }
        }
        if triangles.is_empty() {
            return Err(EditError::DegenerateHull {
                reason: "the deformation mesh has no triangle inside the hull",
            });
        }
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); m];
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
            }
        }
        for nb in &mut neighbours {
            nb.sort_unstable();
            nb.dedup();
        }
        let mut t_mesh = DMatrix::zeros(m, n);
        for (i, src) in mesh_source.iter().enumerate() {
            match src {
                None => t_mesh[(i, i)] = 1.0,
                Some(s) => t_mesh.row_mut(i).copy_from(&t_all.row(*s)),
            }
        }
        // L T, L the Laplacian of the triangle edges (an interior edge twice).
        let mut lt = DMatrix::zeros(m, n);
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                for j in 0..n {
                    let d = t_mesh[(a, j)] - t_mesh[(b, j)];
                    lt[(a, j)] += d;
                    lt[(b, j)] -= d;
                }
            }
        }
        let mut normal_d = DMatrix::zeros(n, n);
        normal_d.gemm_tr(1.0, &t_mesh, &lt, 0.0);
        let deformed = DMatrix::from_fn(n, 2, |i, c| hull.vertices[i][c]);
        let mut points = DMatrix::zeros(big_n, 2);
        points.gemm(1.0, &t_all, &deformed, 0.0);
        Ok(Cage {
            params: *params,
            deformed,
            selection: sel.samples().to_vec(),
            rest_points,
            points,
            t_all,
            mesh_rest,
            t_mesh,
            triangles,
            neighbours,
            normal_d,
            solver: None,
            mesh_pos: DMatrix::zeros(m, 2),
            b_mesh: DMatrix::zeros(m, 2),
            b_hull: DMatrix::zeros(n, 2),
            hull,
        })
    }

    /// The rest hull (counter-clockwise, m).
    pub fn hull(&self) -> &[Vec2] {
        &self.hull.vertices
    }

    /// Whether the hull is the convex fallback (see `hull.rs`).
    pub fn hull_is_convex_fallback(&self) -> bool {
        self.hull.convex_fallback
    }

    /// The deformed hull vertex `i` (m).
    pub fn deformed_vertex(&self, i: usize) -> Vec2 {
        Vec2::new(self.deformed[(i, 0)], self.deformed[(i, 1)])
    }

    /// The deformed hull (m).
    pub fn deformed_hull(&self) -> Vec<Vec2> {
        (0..self.hull.vertices.len())
            .map(|i| self.deformed_vertex(i))
            .collect()
    }

    /// The mesh vertices at rest (hull vertices first) (m).
    pub fn mesh_vertices(&self) -> &[Vec2] {
        &self.mesh_rest
    }

    /// The mesh triangles (indices into [`Cage::mesh_vertices`], counter-clockwise).
    pub fn mesh_triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Eq. 4's `T` for the mesh vertices (m × n).
    pub fn mesh_matrix(&self) -> &DMatrix<f64> {
        &self.t_mesh
    }

    /// The MVC of every selected sample w.r.t. the rest hull (N × n, selection order).
    pub fn sample_matrix(&self) -> &DMatrix<f64> {
        &self.t_all
    }

    /// The selected samples, in the order of [`Cage::sample_matrix`]'s rows.
    pub fn selection(&self) -> &[SampleRef] {
        &self.selection
    }

    /// The deformed position of the `i`-th selected sample (m).
    pub fn deformed_sample(&self, i: usize) -> Vec2 {
        Vec2::new(self.points[(i, 0)], self.points[(i, 1)])
    }

    /// The rest position of the `i`-th selected sample (m).
    pub fn rest_sample(&self, i: usize) -> Vec2 {
        self.rest_points[i]
    }

    /// The current (deformed) position of a handle.
    ///
    /// # Errors
    /// [`EditError::UnknownHandle`].
    pub fn handle_position(&self, h: Handle) -> Result<Vec2, EditError> {
        match h {
            Handle::Hull(i) if i < self.hull.vertices.len() => Ok(self.deformed_vertex(i)),
            Handle::Sample(r) => match self.selection.binary_search(&r) {
                Ok(i) => Ok(self.deformed_sample(i)),
                Err(_) => Err(EditError::UnknownHandle {
                    handle: h.to_string(),
                }),
            },
            _ => Err(EditError::UnknownHandle {
                handle: h.to_string(),
            }),
        }
    }

    /// The handle nearest to `p` within `radius_m` in the deformed state: a hull vertex
    /// when one is that close, else the nearest selected sample.
    pub fn handle_near(&self, p: Vec2, radius_m: f64) -> Option<Handle> {
        let r2 = radius_m * radius_m;
        let mut best: Option<(f64, Handle)> = None;
        for i in 0..self.hull.vertices.len() {
            let d2 = (self.deformed_vertex(i) - p).norm_squared();
            if d2 <= r2 && best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, Handle::Hull(i)));
            }
        }
        if best.is_some() {
            return best.map(|b| b.1);
        }
        for (i, r) in self.selection.iter().enumerate() {
            let d2 = (self.deformed_sample(i) - p).norm_squared();
            if d2 <= r2 && best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, Handle::Sample(*r)));
            }
        }
        best.map(|b| b.1)
    }

    /// The row of `M` for a handle (its MVC row, or a unit row), into `out`.
    fn handle_row(&self, h: Handle, out: &mut [f64]) -> Result<(), EditError> {
        out.fill(0.0);
        match h {
            Handle::Hull(i) if i < out.len() => out[i] = 1.0,
            Handle::Sample(r) => {
                let i = self
                    .selection
                    .binary_search(&r)
                    .map_err(|_| EditError::UnknownHandle {
                        handle: h.to_string(),
                    })?;
                for (j, o) in out.iter_mut().enumerate() {
                    *o = self.t_all[(i, j)];
                }
            }
            _ => {
                return Err(EditError::UnknownHandle {
                    handle: h.to_string(),
                })
            }
        }
        Ok(())
    }

    /// The mesh vertex a dragged handle starts the breadth-first search from.
    fn source_vertex(&self, h: Handle) -> usize {
        match h {
            Handle::Hull(i) => i,
            Handle::Sample(r) => {
                let p = self.rest_points[self.selection.binary_search(&r).unwrap_or(0)];
                (0..self.mesh_rest.len())
                    .min_by(|&a, &b| {
                        (self.mesh_rest[a] - p)
                            .norm_squared()
                            .total_cmp(&(self.mesh_rest[b] - p).norm_squared())
                    })
                    .unwrap_or(0)
            }
        }
    }

    /// Eq. 5's coefficient for every mesh vertex, from the dragged handles.
    pub fn locality_coefficients(&self, drags: &[Handle]) -> Vec<f64> {
        let m = self.mesh_rest.len();
        let mut layer = vec![usize::MAX; m];
        let mut queue = VecDeque::new();
        let sources: Vec<usize> = drags.iter().map(|h| self.source_vertex(*h)).collect();
        for &s in &sources {
            if layer[s] != 0 {
                layer[s] = 0;
                queue.push_back(s);
            }
        }
        let mut deepest = 0;
        while let Some(v) = queue.pop_front() {
            for &w in &self.neighbours[v] {
                let w = w as usize;
                if layer[w] == usize::MAX {
                    layer[w] = layer[v] + 1;
                    deepest = deepest.max(layer[w]);
                    queue.push_back(w);
                }
            }
        }
        (0..m)
            .map(|i| {
                // A vertex the mesh does not reach counts as one layer past the deepest.
                let c = if layer[i] == usize::MAX {
                    deepest + 1
                } else {
                    layer[i]
                } as f64;
                if c == 0.0 {
                    return 0.0;
                }
                let d = sources
                    .iter()
                    .map(|&s| (self.mesh_rest[s] - self.mesh_rest[i]).norm())
                    .fold(f64::INFINITY, f64::min);
                self.params.alpha * d * (c - self.params.k).exp() + self.params.beta * c
            })
            .collect()
    }

    fn build_solver(&mut self, drags: &[Handle], fixed: &[Handle]) -> Result<(), EditError> {
        let n = self.hull.vertices.len();
        let all: Vec<Handle> = drags.iter().chain(fixed).copied().collect();
        for (i, h) in all.iter().enumerate() {
            if all[..i].contains(h) {
                return Err(EditError::ConflictingHandles {
                    reason: "a handle appears twice among the dragged and fixed handles",
                });
            }
        }
        let k = all.len();
        if k > n {
            return Err(EditError::ConflictingHandles {
                reason: "more handles than cage vertices",
            });
        }
        let mut rows = DMatrix::zeros(k, n);
        let mut row = vec![0.0; n];
        for (r, h) in all.iter().enumerate() {
            self.handle_row(*h, &mut row)?;
            for (j, w) in row.iter().enumerate() {
                rows[(r, j)] = *w;
            }
        }
        let p = &self.params;
        let mut a = &self.normal_d * (p.w_d * p.w_d);
        let mut b0 = DMatrix::zeros(n, 2);
        let rest = DMatrix::from_fn(n, 2, |i, c| self.hull.vertices[i][c]);
        if fixed.is_empty() {
            // Eq. 1: ω_F² Tᵀ C² T and ω_F² Tᵀ C² c.
            let coef = self.locality_coefficients(drags);
            let mut ct = self.t_mesh.clone();
            let mut cc = DMatrix::zeros(self.mesh_rest.len(), 2);
            for (i, c) in coef.iter().enumerate() {
                let c2 = p.w_f * p.w_f * c * c;
                ct.row_mut(i).scale_mut(c2);
                cc[(i, 0)] = c2 * self.mesh_rest[i].x;
                cc[(i, 1)] = c2 * self.mesh_rest[i].y;
            }
            a.gemm_tr(1.0, &self.t_mesh, &ct, 1.0);
            b0.gemm_tr(1.0, &self.t_mesh, &cc, 0.0);
        } else {
            // Eq. 6: ω_S² Dᵀ D with D the cyclic difference matrix of eq. 8.
            let w = p.w_s * p.w_s;
            for i in 0..n {
                let j = (i + 1) % n;
                a[(i, i)] += w;
                a[(j, j)] += w;
                a[(i, j)] -= w;
                a[(j, i)] -= w;
                for c in 0..2 {
                    let d = rest[(i, c)] - rest[(j, c)];
                    b0[(i, c)] += w * d;
                    b0[(j, c)] -= w * d;
                }
            }
        }
        let mut kkt = DMatrix::zeros(n + k, n + k);
        kkt.view_mut((0, 0), (n, n)).copy_from(&a);
        kkt.view_mut((n, 0), (k, n)).copy_from(&rows);
        kkt.view_mut((0, n), (n, k)).copy_from(&rows.transpose());
        self.solver = Some(Solver {
            drags: drags.to_vec(),
            fixed: fixed.to_vec(),
            rows,
            lu: kkt.lu(),
            b0,
            rhs: DMatrix::zeros(n + k, 2),
        });
        Ok(())
    }

    /// Moves the dragged handles to their targets (exactly) and keeps the fixed
    /// handles at their rest positions, deforming from the rest cage by eq. 1 (no fixed
    /// handle) or eq. 6 (with fixed handles); then updates every selected sample's
    /// deformed position. The previous deformation is the starting guess, so a
    /// continuing drag converges across calls.
    ///
    /// # Complexity
    /// The first call for a handle set factorises the KKT system, O(m n² + (n + K)³);
    /// later calls with the same handles cost O(iterations · m n + N n) and do not
    /// allocate.
    ///
    /// # Errors
    /// [`EditError::DragNotFinite`], [`EditError::DragOutsideWorld`],
    /// [`EditError::UnknownHandle`], [`EditError::ConflictingHandles`] (a handle twice,
    /// more handles than cage vertices, or dependent constraint rows). On error the
    /// cage keeps its previous deformation.
    pub fn drag(&mut self, drags: &[(Handle, Vec2)], fixed: &[Handle]) -> Result<(), EditError> {
        for (_, t) in drags {
            if !finite(*t) {
                return Err(EditError::DragNotFinite { x: t.x, y: t.y });
            }
            if self.params.world.is_some_and(|w| !w.contains(*t)) {
                return Err(EditError::DragOutsideWorld { x: t.x, y: t.y });
            }
        }
        if drags.is_empty() && fixed.is_empty() {
            self.reset();
            return Ok(());
        }
        let same = self.solver.as_ref().is_some_and(|s| {
            s.drags.iter().eq(drags.iter().map(|d| &d.0)) && s.fixed.as_slice() == fixed
        });
        if !same {
            let handles: Vec<Handle> = drags.iter().map(|d| d.0).collect();
            self.build_solver(&handles, fixed)?;
        }
        let n = self.hull.vertices.len();
        let w_d2 = self.params.w_d * self.params.w_d;
        let Some(solver) = self.solver.as_mut() else {
            return Ok(());
        };
        let k = solver.rows.nrows();
        for iter in 0..self.params.iterations.max(1) {
            // Local step: rotations from the current mesh positions (eq. 2).
            self.mesh_pos.gemm(1.0, &self.t_mesh, &self.deformed, 0.0);
            self.b_mesh.fill(0.0);
            for t in &self.triangles {
                let (mut sd, mut sc) = (0.0, 0.0);
                for e in 0..3 {
                    let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
                    let r = self.mesh_rest[a] - self.mesh_rest[b];
                    let q = Vec2::new(
                        self.mesh_pos[(a, 0)] - self.mesh_pos[(b, 0)],
                        self.mesh_pos[(a, 1)] - self.mesh_pos[(b, 1)],
                    );
                    sd += r.dot(&q);
                    sc += cross(r, q);
                }
                let len = (sd * sd + sc * sc).sqrt();
                let (co, si) = if len > 0.0 && len.is_finite() {
                    (sd / len, sc / len)
                } else {
                    (1.0, 0.0)
                };
                for e in 0..3 {
                    let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
                    let r = self.mesh_rest[a] - self.mesh_rest[b];
                    let rr = Vec2::new(co * r.x - si * r.y, si * r.x + co * r.y);
                    self.b_mesh[(a, 0)] += rr.x;
                    self.b_mesh[(a, 1)] += rr.y;
                    self.b_mesh[(b, 0)] -= rr.x;
                    self.b_mesh[(b, 1)] -= rr.y;
                }
            }
            // Global step: the KKT solve.
            self.b_hull.gemm_tr(w_d2, &self.t_mesh, &self.b_mesh, 0.0);
            self.b_hull += &solver.b0;
            solver.rhs.view_mut((0, 0), (n, 2)).copy_from(&self.b_hull);
            for (r, (_, t)) in drags.iter().enumerate() {
                solver.rhs[(n + r, 0)] = t.x;
                solver.rhs[(n + r, 1)] = t.y;
            }
            for r in drags.len()..k {
                // Fixed handle: its rest position, row · v̂_rest.
                let (mut x, mut y) = (0.0, 0.0);
                for j in 0..n {
                    x += solver.rows[(r, j)] * self.hull.vertices[j].x;
                    y += solver.rows[(r, j)] * self.hull.vertices[j].y;
                }
                solver.rhs[(n + r, 0)] = x;
                solver.rhs[(n + r, 1)] = y;
            }
            let ok = solver.lu.solve_mut(&mut solver.rhs);
            if !ok || solver.rhs.iter().any(|v| !v.is_finite()) {
                if iter == 0 {
                    self.solver = None;
                }
                return Err(EditError::ConflictingHandles {
                    reason: "the constraint rows are linearly dependent",
                });
            }
            self.deformed.copy_from(&solver.rhs.view((0, 0), (n, 2)));
        }
        self.points.gemm(1.0, &self.t_all, &self.deformed, 0.0);
        Ok(())
    }

    /// Returns to the rest cage.
    pub fn reset(&mut self) {
        for (i, v) in self.hull.vertices.iter().enumerate() {
            self.deformed[(i, 0)] = v.x;
            self.deformed[(i, 1)] = v.y;
        }
        self.points.gemm(1.0, &self.t_all, &self.deformed, 0.0);
    }

    /// Writes the deformed positions into the selected samples of `set` (the set the
    /// selection was made on; times are left alone, see [`correct_speeds`]).
    ///
    /// # Errors
    /// [`EditError::SelectionMismatch`] when `set` lacks a selected sample (nothing is
    /// written then).
    pub fn apply(&self, set: &mut TrackSet) -> Result<(), EditError> {
        for r in &self.selection {
            if set
                .tracks
                .get(r.track)
                .is_none_or(|t| r.sample >= t.points.len())
            {
                return Err(EditError::SelectionMismatch {
                    track: r.track,
                    sample: r.sample,
                });
            }
        }
        for (i, r) in self.selection.iter().enumerate() {
            set.tracks[r.track].points[r.sample] = self.deformed_sample(i);
        }
        Ok(())
    }

    /// How much the hull's shape changed (see [`ShapeError`]): a rigid motion gives 0.
    pub fn hull_shape_error(&self) -> ShapeError {
        let n = self.hull.vertices.len();
        let rest = &self.hull.vertices;
        let def = self.deformed_hull();
        let turn = |p: &[Vec2], i: usize| {
            let (a, b, c) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
            let (u, v) = (b - a, c - b);
            cross(u, v).atan2(u.dot(&v))
        };
        let (mut el, mut an) = (0.0, 0.0);
        for i in 0..n {
            let j = (i + 1) % n;
            let l0 = (rest[j] - rest[i]).norm();
            let l1 = (def[j] - def[i]).norm();
            el += ((l1 - l0) / l0).powi(2);
            let mut d = turn(&def, i) - turn(rest, i);
            if d > std::f64::consts::PI {
                d -= 2.0 * std::f64::consts::PI;
            } else if d < -std::f64::consts::PI {
                d += 2.0 * std::f64::consts::PI;
            }
            an += d * d;
        }
        ShapeError {
            edge_length_rms: (el / n as f64).sqrt(),
            angle_rms_rad: (an / n as f64).sqrt(),
        }
    }
}

/// Speed ratios (after / before) of the retimed segments.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SpeedReport {
    /// Segments considered (linked, moving before the edit).
    pub segments: usize,
    /// Smallest and largest speed ratio after the spatial edit, before correction.
    pub edited_ratio: (f64, f64),
    /// Smallest and largest speed ratio after correction.
    pub corrected_ratio: (f64, f64),
}

/// Re-times the touched tracks so every linked segment's speed returns to its pre-edit
/// speed (eq. 9).
///
/// # Formula
/// Eq. 9's terms are independent, one per segment, and each vanishes at
/// `Δt'_j = Δt_j ‖p'_{j+1} − p'_j‖ / ‖p_{j+1} − p_j‖`, its unconstrained minimiser,
/// which is used; it is clamped below at [`MIN_INTERVAL_FRACTION`] `· Δt_j` so that
/// times stay strictly increasing. A segment that did not move before the edit
/// (`‖p‖ = 0`) and every gap (unlinked pair) keeps its interval. The first time of each
/// track is kept; later samples shift by the accumulated change.
///
/// # Errors
/// [`EditError::SelectionMismatch`] when `before` and `after` differ in shape for a
/// touched track (`sample` then names the first missing sample).
pub fn correct_speeds(
    before: &TrackSet,
    after: &mut TrackSet,
    touched: &[usize],
) -> Result<SpeedReport, EditError> {
    let mut rep = SpeedReport {
        segments: 0,
        edited_ratio: (f64::INFINITY, f64::NEG_INFINITY),
        corrected_ratio: (f64::INFINITY, f64::NEG_INFINITY),
    };
    for &ti in touched {
        let (Some(b), Some(a)) = (before.tracks.get(ti), after.tracks.get(ti)) else {
            return Err(EditError::SelectionMismatch {
                track: ti,
                sample: 0,
            });
        };
        if b.len() != a.len() || a.times_s.len() != a.len() || b.linked.len() != a.linked.len() {
            return Err(EditError::SelectionMismatch {
                track: ti,
                sample: b.len().min(a.len()),
            });
        }
        let a = &mut after.tracks[ti];
        let mut t = a.times_s[0];
        for j in 0..b.len().saturating_sub(1) {
            let dt = b.times_s[j + 1] - b.times_s[j];
            let l0 = (b.points[j + 1] - b.points[j]).norm();
            let l1 = (a.points[j + 1] - a.points[j]).norm();
            let new_dt = if b.linked[j] && l0 > 0.0 {
                let r = l1 / l0;
                rep.segments += 1;
                rep.edited_ratio.0 = rep.edited_ratio.0.min(r);
                rep.edited_ratio.1 = rep.edited_ratio.1.max(r);
                (dt * r).max(MIN_INTERVAL_FRACTION * dt)
            } else {
                dt
            };
            a.times_s[j] = t;
            t += new_dt;
            if b.linked[j] && l0 > 0.0 {
                let r = (l1 / new_dt) / (l0 / dt);
                rep.corrected_ratio.0 = rep.corrected_ratio.0.min(r);
                rep.corrected_ratio.1 = rep.corrected_ratio.1.max(r);
            }
        }
        if let Some(last) = a.times_s.last_mut() {
            *last = t;
        }
    }
    if rep.segments == 0 {
        rep.edited_ratio = (1.0, 1.0);
        rep.corrected_ratio = (1.0, 1.0);
    }
    Ok(rep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::edit::select::SelectionQuery;
    use crate::crowd::edit::tracks::Track;

    /// `rows` people side by side 0.8 m apart walking along +x at 1.2 m/s, sampled
    /// every 0.5 s for `samples` samples.
    pub(crate) fn band(rows: usize, samples: usize) -> TrackSet {
        let tracks = (0..rows)
            .map(|i| {
                let pts = (0..samples)
                    .map(|j| Vec2::new(0.6 * j as f64, 0.8 * i as f64))
                    .collect();
                let ts = (0..samples).map(|j| 0.5 * j as f64).collect();
                Track::linked(i as u64, pts, ts)
            })
            .collect();
        TrackSet {
            tracks,
            step_s: 0.5,
        }
    }

    fn cage(set: &TrackSet) -> Cage {
        let sel = Selection::select(set, &SelectionQuery::default()).unwrap();
        Cage::new(set, &sel, &CageParams::default()).unwrap()
    }

    #[test]
    fn mvc_rows_sum_to_one_and_reproduce_the_rest_points() {
        let set = band(8, 25);
        let c = cage(&set);
        let t = c.sample_matrix();
        for i in 0..t.nrows() {
            let s: f64 = t.row(i).iter().sum();
            assert!((s - 1.0).abs() < 1e-9, "row {i} sums to {s}");
            let q: Vec2 = (0..t.ncols()).map(|j| c.hull()[j] * t[(i, j)]).sum();
            assert!((q - c.rest_sample(i)).norm() < 1e-9);
            assert!((c.deformed_sample(i) - c.rest_sample(i)).norm() < 1e-9);
        }
        let tm = c.mesh_matrix();
        for i in 0..c.hull().len() {
            assert_eq!(tm[(i, i)], 1.0);
        }
    }

    #[test]
    fn sample_matrix_equals_mean_value_coordinates_exactly() {
        let set = band(8, 25);
        let c = cage(&set);
        let t = c.sample_matrix();
        let mut row = vec![0.0; c.hull().len()];
        for i in 0..t.nrows() {
            crate::crowd::mesh::mean_value_coordinates(c.hull(), c.rest_sample(i), &mut row)
                .unwrap();
            for (j, w) in row.iter().enumerate() {
                assert_eq!(t[(i, j)].to_bits(), w.to_bits(), "row {i} column {j}");
            }
        }
        // On a vertex, on an edge, and outside.
        let mvc = HullMvc::new(c.hull()).unwrap();
        let (v0, v1) = (c.hull()[0], c.hull()[1]);
        let mut r = vec![0.0; c.hull().len()];
        let mut fast = vec![0.0; c.hull().len()];
        for p in [v0, (v0 + v1) / 2.0, v0 + (v0 - v1) * 3.0] {
            let a = crate::crowd::mesh::mean_value_coordinates(c.hull(), p, &mut row);
            let b = mvc.coordinates(p, &mut r, &mut fast);
            assert_eq!(a.is_ok(), b.is_some());
            for (x, y) in row.iter().zip(&fast) {
                assert_eq!(x.to_bits(), y.to_bits());
            }
        }
    }

    #[test]
    fn dragging_to_the_rest_position_leaves_the_rest_pose() {
        let set = band(6, 20);
        let mut c = cage(&set);
        let v = c.hull()[2];
        c.drag(&[(Handle::Hull(2), v)], &[Handle::Hull(7)]).unwrap();
        for i in 0..c.selection().len() {
            assert!((c.deformed_sample(i) - c.rest_sample(i)).norm() < 1e-9);
        }
        c.drag(&[(Handle::Hull(2), v)], &[]).unwrap();
        for i in 0..c.hull().len() {
            assert!((c.deformed_vertex(i) - c.hull()[i]).norm() < 1e-9);
        }
    }

    #[test]
    fn dragged_hull_vertex_and_sample_land_exactly() {
        let set = band(8, 25);
        let mut c = cage(&set);
        let target = c.hull()[0] + Vec2::new(0.7, -0.4);
        c.drag(&[(Handle::Hull(0), target)], &[]).unwrap();
        assert!((c.deformed_vertex(0) - target).norm() <= 1e-9);
        let r = SampleRef {
            track: 3,
            sample: 12,
        };
        let i = c.selection().binary_search(&r).unwrap();
        let t2 = c.rest_sample(i) + Vec2::new(0.5, 0.5);
        c.drag(&[(Handle::Sample(r), t2)], &[]).unwrap();
        assert!((c.handle_position(Handle::Sample(r)).unwrap() - t2).norm() <= 1e-9);
        let mut out = set.clone();
        c.apply(&mut out).unwrap();
        assert!((out.tracks[3].points[12] - t2).norm() <= 1e-9);
    }

    #[test]
    fn far_points_move_less_than_near_ones() {
        let set = band(8, 40);
        let mut c = cage(&set);
        // Drag the hull vertex nearest the far right end outwards by 1 m.
        let right = (0..c.hull().len())
            .max_by(|&a, &b| c.hull()[a].x.total_cmp(&c.hull()[b].x))
            .unwrap();
        let v = c.hull()[right];
        c.drag(&[(Handle::Hull(right), v + Vec2::new(1.0, 0.5))], &[])
            .unwrap();
        let (mut near, mut nn, mut far, mut nf) = (0.0, 0, 0.0, 0);
        for i in 0..c.selection().len() {
            let p = c.rest_sample(i);
            let moved = (c.deformed_sample(i) - p).norm();
            let d = (p - v).norm();
            if d < 3.0 {
                near += moved;
                nn += 1;
            } else if d > 15.0 {
                far += moved;
                nf += 1;
            }
        }
        let (near, far) = (near / nn as f64, far / nf as f64);
        assert!(near > 0.3, "near points moved {near} m");
        assert!(far < 0.25 * near, "far {far} m vs near {near} m");
    }

    #[test]
    fn moderate_drag_keeps_the_hull_shape() {
        let set = band(8, 40);
        let mut c = cage(&set);
        let v = c.hull()[0];
        c.drag(&[(Handle::Hull(0), v + Vec2::new(0.5, 0.5))], &[])
            .unwrap();
        let e = c.hull_shape_error();
        // A 0.7 m drag on a 24 m × 6 m cage.
        assert!(e.edge_length_rms < 0.1, "{e:?}");
        assert!(e.angle_rms_rad < 0.1, "{e:?}");
        c.reset();
        let e = c.hull_shape_error();
        assert!(e.edge_length_rms < 1e-12 && e.angle_rms_rad < 1e-12);
    }

    #[test]
    fn fixed_handles_stay_and_drag_lands() {
        let set = band(8, 40);
        let mut c = cage(&set);
        let n = c.hull().len();
        let (a, b) = (0, n / 2);
        let target = c.hull()[a] + Vec2::new(0.0, -1.0);
        c.drag(&[(Handle::Hull(a), target)], &[Handle::Hull(b)])
            .unwrap();
        assert!((c.deformed_vertex(a) - target).norm() <= 1e-9);
        assert!((c.deformed_vertex(b) - c.hull()[b]).norm() <= 1e-9);
        assert!(matches!(
            c.drag(&[(Handle::Hull(a), target)], &[Handle::Hull(a)]),
            Err(EditError::ConflictingHandles { .. })
        ));
    }

    #[test]
    fn bad_targets_are_refused() {
        let set = band(4, 10);
        let sel = Selection::select(&set, &SelectionQuery::default()).unwrap();
        let params = CageParams {
            world: Some(Rect {
                min: [-5.0, -5.0],
                max: [20.0, 20.0],
            }),
            ..CageParams::default()
        };
        let mut c = Cage::new(&set, &sel, &params).unwrap();
        assert!(matches!(
            c.drag(&[(Handle::Hull(0), Vec2::new(f64::NAN, 0.0))], &[]),
            Err(EditError::DragNotFinite { .. })
        ));
        assert!(matches!(
            c.drag(&[(Handle::Hull(0), Vec2::new(50.0, 0.0))], &[]),
            Err(EditError::DragOutsideWorld { .. })
        ));
        assert!(matches!(
            c.drag(&[(Handle::Hull(999), Vec2::new(1.0, 0.0))], &[]),
            Err(EditError::UnknownHandle { .. })
        ));
    }

    #[test]
    fn speed_correction_restores_speeds() {
        let before = band(8, 40);
        let mut c = cage(&before);
        let v = c.hull()[0];
        c.drag(&[(Handle::Hull(0), v + Vec2::new(-2.0, -1.5))], &[])
            .unwrap();
        let mut after = before.clone();
        c.apply(&mut after).unwrap();
        let touched: Vec<usize> = (0..8).collect();
        let rep = correct_speeds(&before, &mut after, &touched).unwrap();
        assert!(
            rep.edited_ratio.0 < 0.99 || rep.edited_ratio.1 > 1.01,
            "{rep:?}"
        );
        assert!(
            rep.corrected_ratio.0 > 0.99 && rep.corrected_ratio.1 < 1.01,
            "{rep:?}"
        );
        for (tb, ta) in before.tracks.iter().zip(&after.tracks) {
            assert_eq!(ta.times_s[0], tb.times_s[0]);
            ta.validate().unwrap();
            for j in 0..tb.len() - 1 {
                let r = ta.segment_speed(j) / tb.segment_speed(j);
                assert!((r - 1.0).abs() < 0.01, "speed ratio {r}");
            }
        }
    }
}
