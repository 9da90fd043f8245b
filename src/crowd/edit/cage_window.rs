//! One cage of the spatial editor: a concave hull around one time window's samples,
//! deformed as rigidly as possible (crowd-motion-editing section 3.2, eqs. 1–8).
//! `cage.rs` chains one of these per time window (one for a selection that does not
//! revisit a place); this file is the cage itself.
//!
//! The cage vertices `v̂` (`n` of them, the hull of `hull.rs`) are the unknowns. Every
//! selected sample is tied to them by its mean value coordinates (MVC, `cage_mvc.rs`)
//! with respect to the rest hull, so its deformed position is `λᵀ v̂`. The deformation
//! mesh is the Delaunay triangulation (spade) of the hull vertices and one selected
//! sample per occupied grid cell (the hull's representatives), keeping the triangles
//! whose centroid lies inside the hull; its vertex positions are `T v̂` with `T` the
//! `m × n` matrix of eq. 4 (MVC rows for the samples, identity rows for the hull
//! vertices). Deforming the mesh on a thinned point set and applying the MVC to every
//! selected sample keeps a drag cheap however many samples are selected.
//!
//! A drag solves eq. 1 (no fixed handle) or eq. 6 (with fixed handles):
//!
//! ```text
//! min  ω_D² E_D + ω_F² E_F          (eq. 1)      min  ω_D² E_D + ω_S² E_S     (eq. 6)
//! s.t. M v̂ = h                                   s.t. M v̂ = h
//!
//! E_D = Σ_t Σ_edges c_e^t ‖(T v̂)_i − (T v̂)_j − R_t (p_i − p_j)‖²     ARAP, eq. 2
//! E_F = ‖C (T v̂ − c)‖²,  C_ii = α d_i e^{c_i − k} + β c_i              eqs. 3, 5
//! E_S = ‖D v̂ − R_S D v̂_rest‖²  (hull edge vectors)                    eqs. 7, 8
//! ```
//!
//! `c_e^t` are cotangent weights and `R_S` one rotation fitted to the whole hull, so
//! that a turned hull costs nothing (`cage_solve.rs` says why). `c_i` is the
//! breadth-first layer of mesh vertex `i` from the dragged vertices and `d_i` its
//! distance to the nearest of them (rest positions); the dragged vertices get
//! coefficient 0. By default `k` is [`CageParams::locality_radius_m`] in layers, so a
//! drag bends the cage within about that distance and leaves the rest
//! ([`CageParams::paper`] has the paper's values, which do not localise on our cages).
//! Each handle (a hull vertex, or a selected sample through its MVC row) contributes
//! one row of `M`; dragged handles take their targets, fixed handles keep their rest
//! positions. The local/global iteration fits the rotations (closed-form 2-D
//! Procrustes) and then solves the equality-constrained least squares exactly through
//! its KKT system
//!
//! ```text
//! ⎡ A  Mᵀ ⎤ ⎡ v̂ ⎤   ⎡ ω_D² Tᵀ b_D(R_t) + b_F or b_S(R_S) ⎤
//! ⎣ M  0  ⎦ ⎣ μ ⎦ = ⎣ h                                  ⎦ ,
//! A = ω_D² Tᵀ L T + ω_F² Tᵀ C² T   (or + ω_S² Dᵀ D),
//! ```
//!
//! one LU factorisation shared by x and y, until no cage vertex moves more than
//! [`CageParams::tolerance_m`] (at most [`CageParams::max_iterations`];
//! [`CageWindow::last_solve`] says how many ran). `Tᵀ L T` (`L` the mesh's weighted
//! Laplacian) is computed once per cage; the KKT factorisation once per handle set,
//! so a continuing drag of the same handles costs `iterations` × (two `m × n`
//! products and two triangular solves) plus one `N × n` product for the `N` selected
//! samples, with no allocation. A first drag with fixed handles starts from the rigid
//! motion that best takes the handles to their targets, so a turn needs few
//! iterations.

use super::cage_mvc::{finite, mvc_matrix, HullMvc};
use super::cage_solve::{CageParams, Deformer, Mode};
use super::error::EditError;
use super::hull::{concave_hull, Hull};
use super::select::{point_in_polygon, SampleRef};
use super::tracks::TrackSet;
use crate::geom::{cross, Vec2};
use nalgebra::DMatrix;
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// A hull vertex whose mean value coordinate in a dragged sample's row is at least
/// this fraction of the row's largest is a source of eq. 5's layers (dimensionless):
/// moving the sample moves it, so the mesh around it must stay free.
pub const SUPPORT_FRACTION: f64 = 0.25;

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

/// How the last drag's local/global iteration went.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Iterations run.
    pub iterations: usize,
    /// Whether the last iteration moved no cage vertex more than
    /// [`CageParams::tolerance_m`] (false: stopped at [`CageParams::max_iterations`]).
    pub converged: bool,
}

/// The handle set the deformer is factorised for.
struct HandleSet {
    drags: Vec<Handle>,
    fixed: Vec<Handle>,
    /// The rest position of every handle, drags first (m).
    rest: Vec<Vec2>,
    /// The targets of the solve, drags' then the fixed handles' rest positions (m).
    targets: Vec<Vec2>,
    /// Eq. 5's k the factorisation used (layers).
    k_layers: f64,
}

/// One cage: the spatial editor of one time window's samples (see the module
/// documentation).
pub struct CageWindow {
    params: CageParams,
    hull: Hull,
    deformed: DMatrix<f64>,
    /// The deformation before the drag in progress, restored when it fails.
    backup: DMatrix<f64>,
    /// The deformation kept by [`CageWindow::save`] (and whether it was the rest).
    saved: (DMatrix<f64>, bool),
    selection: Vec<SampleRef>,
    rest_points: Vec<Vec2>,
    points: DMatrix<f64>,
    /// MVC of every selected sample w.r.t. the rest hull (N × n).
    t_all: DMatrix<f64>,
    deformer: Deformer,
    /// Eq. 5's k for this cage (layers).
    k_layers: f64,
    /// The mesh's mean edge length at rest (m): one layer of eq. 5's search.
    mean_edge_m: f64,
    handles: Option<HandleSet>,
    at_rest: bool,
    last: SolveStats,
}

impl CageWindow {
    /// Builds the cage of the samples `selection` (sorted, no duplicates) at
    /// `rest_points`: the hull, the mesh, the MVC of every sample and `Tᵀ L T`.
    ///
    /// # Complexity
    /// O(N n) for the MVC of N samples and n hull vertices, O(m n²) for `Tᵀ L T` on m
    /// mesh vertices.
    ///
    /// # Errors
    /// The errors of [`concave_hull`]; [`EditError::DegenerateHull`] when a sample's
    /// MVC are undefined or the mesh has no triangle.
    pub(super) fn new(
        rest_points: Vec<Vec2>,
        selection: Vec<SampleRef>,
        params: &CageParams,
    ) -> Result<CageWindow, EditError> {
        let hull = concave_hull(&rest_points, &params.hull)?;
        let n = hull.vertices.len();
        let undefined = EditError::DegenerateHull {
            reason: "mean value coordinates undefined for a selected sample",
        };
        let mvc = HullMvc::new(&hull.vertices).ok_or(undefined.clone())?;
        let t_all = mvc_matrix(&mvc, &rest_points).map_err(|_| undefined)?;
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
        let mut t_mesh = DMatrix::zeros(m, n);
        for (i, src) in mesh_source.iter().enumerate() {
            match src {
                None => t_mesh[(i, i)] = 1.0,
                Some(s) => t_mesh.row_mut(i).copy_from(&t_all.row(*s)),
            }
        }
        let deformer = Deformer::new(hull.vertices.clone(), mesh_rest, triangles, t_mesh);
        let mean_edge_m = deformer.mean_edge_m();
        let k_layers = match params.locality_radius_m {
            Some(r) => r / mean_edge_m,
            None => params.k,
        };
        let deformed = DMatrix::from_fn(n, 2, |i, c| hull.vertices[i][c]);
        let mut points = DMatrix::zeros(rest_points.len(), 2);
        points.gemm(1.0, &t_all, &deformed, 0.0);
        Ok(CageWindow {
            params: *params,
            backup: deformed.clone(),
            saved: (deformed.clone(), true),
            deformed,
            selection,
            rest_points,
            points,
            t_all,
            deformer,
            k_layers,
            mean_edge_m,
            handles: None,
            at_rest: true,
            last: SolveStats::default(),
            hull,
        })
    }

    /// The rest hull (counter-clockwise, m).
    pub fn hull(&self) -> &[Vec2] {
        &self.hull.vertices
    }

    /// The grid cell of the hull's thinning (m).
    pub fn cell_m(&self) -> f64 {
        self.hull.cell_m
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
        self.deformer.mesh_rest()
    }

    /// The mesh triangles (indices into [`CageWindow::mesh_vertices`], counter-clockwise).
    pub fn mesh_triangles(&self) -> &[[u32; 3]] {
        self.deformer.triangles()
    }

    /// Eq. 2's weight `c_e^t` of every triangle's edges `(t[e], t[e + 1])`, in the
    /// order of [`CageWindow::mesh_triangles`] (cotangent weights, clamped).
    pub fn edge_weights(&self) -> &[[f64; 3]] {
        self.deformer.edge_weights()
    }

    /// Eq. 4's `T` for the mesh vertices (m × n).
    pub fn mesh_matrix(&self) -> &DMatrix<f64> {
        self.deformer.t_mesh()
    }

    /// The MVC of every selected sample w.r.t. the rest hull (N × n, selection order).
    pub fn sample_matrix(&self) -> &DMatrix<f64> {
        &self.t_all
    }

    /// The selected samples, in the order of [`CageWindow::sample_matrix`]'s rows.
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

    /// Eq. 5's `k` of this cage (layers): [`CageParams::locality_radius_m`] over the
    /// mesh's mean edge length, or [`CageParams::k`].
    pub fn locality_k_layers(&self) -> f64 {
        self.k_layers
    }

    /// How the last drag's iteration went.
    pub fn last_solve(&self) -> SolveStats {
        self.last
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

    /// The mesh vertices a dragged handle starts the breadth-first search from: a hull
    /// vertex itself; for a sample, the mesh vertex nearest it and the hull vertices
    /// that carry its mean value coordinates (at least [`SUPPORT_FRACTION`] of its
    /// largest), which a drag of it must move.
    fn source_vertices(&self, h: Handle, out: &mut Vec<usize>) {
        let mesh = self.deformer.mesh_rest();
        match h {
            Handle::Hull(i) => out.push(i),
            Handle::Sample(r) => {
                let i = self.selection.binary_search(&r).unwrap_or(0);
                let p = self.rest_points[i];
                let nearest = (0..mesh.len())
                    .min_by(|&a, &b| {
                        (mesh[a] - p)
                            .norm_squared()
                            .total_cmp(&(mesh[b] - p).norm_squared())
                    })
                    .unwrap_or(0);
                out.push(nearest);
                let row = self.t_all.row(i);
                let top = row.iter().copied().fold(0.0, f64::max);
                out.extend((0..row.len()).filter(|&j| row[j] >= SUPPORT_FRACTION * top));
            }
        }
    }

    /// Eq. 5's coefficient for every mesh vertex, from the dragged handles (with this
    /// cage's `k`, [`CageWindow::locality_k_layers`]).
    pub fn locality_coefficients(&self, drags: &[Handle]) -> Vec<f64> {
        self.locality_coefficients_k(drags, self.k_layers)
    }

    fn locality_coefficients_k(&self, drags: &[Handle], k_layers: f64) -> Vec<f64> {
        let mut sources = Vec::new();
        for h in drags {
            self.source_vertices(*h, &mut sources);
        }
        let p = &self.params;
        self.deformer
            .locality_coefficients(&sources, p.alpha, k_layers, p.beta)
    }

    fn build_solver(
        &mut self,
        drags: &[Handle],
        fixed: &[Handle],
        k_layers: f64,
    ) -> Result<(), EditError> {
        self.handles = None;
        self.deformer.clear();
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
        let mut rest = Vec::with_capacity(k);
        for (r, h) in all.iter().enumerate() {
            self.handle_row(*h, &mut row)?;
            let mut at = Vec2::zeros();
            for (j, w) in row.iter().enumerate() {
                rows[(r, j)] = *w;
                at += self.hull.vertices[j] * *w;
            }
            rest.push(at);
        }
        let (mode, coef) = if fixed.is_empty() {
            (
                Mode::Locality,
                self.locality_coefficients_k(drags, k_layers),
            )
        } else {
            (Mode::HullShape, Vec::new())
        };
        if !self.deformer.factor(&rows, mode, &coef, &self.params) {
            return Err(EditError::ConflictingHandles {
                reason: "the constraint rows are linearly dependent",
            });
        }
        self.handles = Some(HandleSet {
            drags: drags.to_vec(),
            fixed: fixed.to_vec(),
            targets: rest.clone(),
            rest,
            k_layers,
        });
        Ok(())
    }

    /// Sets the deformation to the rigid motion that best takes the handles' rest
    /// positions to their targets (2-D Procrustes), when they span a distance.
    fn rigid_start(&mut self) {
        let Some(hs) = self.handles.as_ref() else {
            return;
        };
        let k = hs.rest.len() as f64;
        let pc: Vec2 = hs.rest.iter().sum::<Vec2>() / k;
        let qc: Vec2 = hs.targets.iter().sum::<Vec2>() / k;
        let (mut sd, mut sc) = (0.0, 0.0);
        for (p, q) in hs.rest.iter().zip(&hs.targets) {
            sd += (p - pc).dot(&(q - qc));
            sc += cross(p - pc, q - qc);
        }
        let len = (sd * sd + sc * sc).sqrt();
        if !(len > 0.0 && len.is_finite()) {
            return;
        }
        let (co, si) = (sd / len, sc / len);
        for (i, v) in self.hull.vertices.iter().enumerate() {
            let d = v - pc;
            self.deformed[(i, 0)] = qc.x + co * d.x - si * d.y;
            self.deformed[(i, 1)] = qc.y + si * d.x + co * d.y;
        }
    }

    /// Moves the dragged handles to their targets (exactly) and keeps the fixed
    /// handles at their rest positions, deforming from the rest cage by eq. 1 (no fixed
    /// handle) or eq. 6 (with fixed handles); then updates every selected sample's
    /// deformed position. The previous deformation is the starting guess, so a
    /// continuing drag converges across calls; a first drag with fixed handles starts
    /// from the handles' best rigid motion.
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
        self.drag_within(drags, fixed, None)
    }

    /// The rest position of a handle, if this cage has it (m).
    pub fn handle_rest(&self, h: Handle) -> Option<Vec2> {
        match h {
            Handle::Hull(i) => self.hull.vertices.get(i).copied(),
            Handle::Sample(r) => self
                .selection
                .binary_search(&r)
                .ok()
                .map(|i| self.rest_points[i]),
        }
    }

    /// [`CageWindow::drag`] with eq. 5's `k` from `radius_m` instead of the cage's own
    /// (when given and the parameters localise by a radius): `cage.rs` narrows the
    /// locality of windows a drag reaches through shared handles.
    pub(super) fn drag_within(
        &mut self,
        drags: &[(Handle, Vec2)],
        fixed: &[Handle],
        radius_m: Option<f64>,
    ) -> Result<(), EditError> {
        let k_layers = match (radius_m, self.params.locality_radius_m) {
            (Some(r), Some(_)) => r / self.mean_edge_m,
            _ => self.k_layers,
        };
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
        let same = self.handles.as_ref().is_some_and(|s| {
            s.drags.iter().eq(drags.iter().map(|d| &d.0))
                && s.fixed.as_slice() == fixed
                && s.k_layers == k_layers
        });
        if !same {
            let handles: Vec<Handle> = drags.iter().map(|d| d.0).collect();
            self.build_solver(&handles, fixed, k_layers)?;
        }
        let Some(hs) = self.handles.as_mut() else {
            return Ok(());
        };
        for (t, (_, to)) in hs.targets.iter_mut().zip(drags) {
            *t = *to;
        }
        self.backup.copy_from(&self.deformed);
        if self.at_rest && !fixed.is_empty() {
            self.rigid_start();
        }
        let hs = self.handles.as_ref().map_or(&[][..], |h| &h.targets[..]);
        match self.deformer.solve(&mut self.deformed, hs, &self.params) {
            Some((iterations, converged)) => {
                self.last = SolveStats {
                    iterations,
                    converged,
                };
            }
            None => {
                self.deformed.copy_from(&self.backup);
                if !same {
                    self.handles = None;
                    self.deformer.clear();
                }
                return Err(EditError::ConflictingHandles {
                    reason: "the constraint rows are linearly dependent",
                });
            }
        }
        self.at_rest = false;
        self.points.gemm(1.0, &self.t_all, &self.deformed, 0.0);
        Ok(())
    }

    /// Keeps the current deformation for [`CageWindow::restore`] (no allocation).
    pub(super) fn save(&mut self) {
        self.saved.0.copy_from(&self.deformed);
        self.saved.1 = self.at_rest;
    }

    /// Returns to the deformation kept by the last [`CageWindow::save`].
    pub(super) fn restore(&mut self) {
        self.deformed.copy_from(&self.saved.0);
        self.at_rest = self.saved.1;
        self.points.gemm(1.0, &self.t_all, &self.deformed, 0.0);
    }

    /// Returns to the rest cage.
    pub fn reset(&mut self) {
        for (i, v) in self.hull.vertices.iter().enumerate() {
            self.deformed[(i, 0)] = v.x;
            self.deformed[(i, 1)] = v.y;
        }
        self.at_rest = true;
        self.points.gemm(1.0, &self.t_all, &self.deformed, 0.0);
    }

    /// Writes the deformed positions into the selected samples of `set` (the set the
    /// selection was made on; times are left alone, see
    /// [`correct_speeds`](super::correct_speeds)).
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
