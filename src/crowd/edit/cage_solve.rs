//! The deformation solve of the spatial editor (crowd-motion-editing section 3.2,
//! eqs. 1–8): the ARAP energy with its edge weights, the locality and hull-shape
//! terms, and the local/global iteration run to convergence.
//!
//! [`Deformer`] holds one cage's deformation mesh (rest positions, triangles, eq. 4's
//! `T`) and everything a drag reuses: the weighted `Tᵀ L T`, the KKT factorisation of
//! the current handle set and the buffers of an iteration. `cage.rs` builds it and
//! owns the API; this file is the numerics.
//!
//! # Edge weights (eq. 2)
//! Eq. 2 weighs each triangle edge by `c_i^t`, the weights of the ARAP energy it cites
//! ([23], Sorkine and Alexa): the cotangent weights, `c = ½ cot θ` with `θ` the angle
//! of triangle `t` opposite the edge. They make `E_D` the discretisation of one
//! continuous energy, so a drag deforms the same on a fine and a coarse mesh, where
//! uniform weights let dense places of the mesh (many short edges) outweigh sparse
//! ones. A weight is clamped into [`MIN_EDGE_WEIGHT`, `MAX_EDGE_WEIGHT`]: an obtuse
//! angle (negative cotangent) on the mesh boundary would make `L` indefinite, and a
//! sliver (an angle near 0) would let one triangle dominate.
//!
//! # Rotation-invariant hull shape (eqs. 7–8)
//! Eq. 7 compares the deformed hull's edge vectors `D v̂` (eq. 8's cyclic differences)
//! with the rest ones `d = D v`, in world axes: a turned hull then pays for every
//! edge's change of direction, and a drag that turns a group shears it instead. Here
//! `d` is turned by one rotation `R_S` fitted to the whole hull,
//! `E_S = ‖D v̂ − R_S d‖²`, `R_S` minimising it for the current `v̂` (2-D Procrustes
//! over the hull edges) in the local step, next to the triangles' `R_t`. One rotation
//! keeps what eq. 7 is for (section 3.2: the drag's influence spread along the hull
//! between the dragged and fixed points, each edge's change measured against the
//! others), and a rigid turn of the whole hull costs nothing. Rotations per edge
//! would measure only edge lengths and lose that spreading.
//!
//! # Convergence
//! Each iteration fits the rotations (local step) and solves the KKT system (global
//! step); neither raises the energy, so it decreases monotonically. It stops when no
//! cage vertex moved more than [`CageParams::tolerance_m`] in an iteration, or after
//! [`CageParams::max_iterations`].

use crate::geom::{cross, Vec2};
use nalgebra::{DMatrix, Dyn, LU};
use std::collections::VecDeque;

/// Eq. 5's α (per metre), the paper's value.
pub const PAPER_ALPHA: f64 = 0.01;
/// Eq. 5's threshold k (layers), the paper's value.
pub const PAPER_K: f64 = 300.0;
/// Eq. 5's β (per layer), the paper's value.
pub const PAPER_BETA: f64 = 0.02;

/// Eq. 5's α used by default (per metre): past the locality radius the coefficient
/// grows as `α d e^{c − k}`, a factor e per layer, so the mesh beyond stays put.
pub const DEFAULT_ALPHA: f64 = 0.1;
/// Eq. 5's β used by default (per layer): inside the radius the coefficients stay
/// small against the cotangent weights (a vertex has about six edges of weight ½ to
/// 1), so the region around the handle deforms as rigidly as it can.
pub const DEFAULT_BETA: f64 = 0.02;
/// Eq. 5's `k` used by default, as a distance (m): `k` is this many metres of mesh
/// layers (see [`CageParams::locality_radius_m`]).
pub const DEFAULT_LOCALITY_RADIUS_M: f64 = 5.0;

/// Default convergence tolerance: the local/global iteration stops when no cage
/// vertex moved more than this in an iteration (m).
pub const DEFAULT_TOLERANCE_M: f64 = 1e-4;
/// Default cap on local/global iterations per drag.
pub const DEFAULT_MAX_ITERATIONS: usize = 200;

/// Largest eq. 5 coefficient (dimensionless): a vertex this far past `k` is held at
/// its rest place a million times (the square) more firmly than an edge keeps its
/// shape, and the KKT system stays well conditioned.
pub const MAX_LOCALITY_COEFFICIENT: f64 = 1e3;

/// Smallest ARAP edge weight (dimensionless): obtuse angles' negative cotangents are
/// raised to it.
pub const MIN_EDGE_WEIGHT: f64 = 0.01;
/// Largest ARAP edge weight: `½ cot 5°`, so a sliver counts as a triangle of 5°.
pub const MAX_EDGE_WEIGHT: f64 = 5.715;

/// Parameters of the spatial editor.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CageParams {
    /// The cage polygon.
    pub hull: super::hull::HullParams,
    /// Eq. 5's α (1/m).
    pub alpha: f64,
    /// Eq. 5's k (layers); replaced by [`Self::locality_radius_m`] when that is set.
    pub k: f64,
    /// Eq. 5's β (1/layer).
    pub beta: f64,
    /// Eq. 5's `k` as a distance (m): `k = radius / cell`, the layers of mesh (about
    /// one grid cell of the hull's thinning each) within this distance of the handle.
    /// `None` uses [`Self::k`] as given.
    pub locality_radius_m: Option<f64>,
    /// ω_D, weight of the rigidity energy (eq. 2).
    pub w_d: f64,
    /// ω_F, weight of the locality energy (eq. 3).
    pub w_f: f64,
    /// ω_S, weight of the hull edge energy (eq. 7), used instead of ω_F when a drag
    /// has fixed handles (eq. 6).
    pub w_s: f64,
    /// Convergence tolerance of the local/global iteration (m, see the module doc).
    pub tolerance_m: f64,
    /// Most local/global iterations per drag.
    pub max_iterations: usize,
    /// Drag targets must lie inside this rectangle, when given (m).
    pub world: Option<crate::geom::Rect>,
    /// How a selection whose paths revisit a place is cut into time windows, one
    /// cage each (`cage_split.rs`); [`WindowParams::one_cage`] builds one cage
    /// whatever the paths do.
    ///
    /// [`WindowParams::one_cage`]: super::WindowParams::one_cage
    pub windows: super::cage_split::WindowParams,
}

impl Default for CageParams {
    /// Localising eq. 5 (see [`DEFAULT_ALPHA`]), iterated to 0.1 mm, cut into time
    /// windows where a path revisits a place.
    fn default() -> Self {
        CageParams {
            hull: super::hull::HullParams::default(),
            alpha: DEFAULT_ALPHA,
            k: PAPER_K,
            beta: DEFAULT_BETA,
            locality_radius_m: Some(DEFAULT_LOCALITY_RADIUS_M),
            w_d: 1.0,
            w_f: 1.0,
            w_s: 1.0,
            tolerance_m: DEFAULT_TOLERANCE_M,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            world: None,
            windows: super::cage_split::WindowParams::default(),
        }
    }
}

impl CageParams {
    /// The paper's eq. 5 (α = 0.01, k = 300 layers, β = 0.02). On our cages (10 to
    /// 100 layers) `e^{c − 300}` vanishes, only `β c` acts, and a drag slides most of
    /// the cage rather than bending it locally: kept to compare with.
    pub fn paper() -> CageParams {
        CageParams {
            alpha: PAPER_ALPHA,
            k: PAPER_K,
            beta: PAPER_BETA,
            locality_radius_m: None,
            ..CageParams::default()
        }
    }
}

/// Which energy a handle set solves with.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// Eq. 1: ARAP and locality.
    Locality,
    /// Eq. 6: ARAP and the hull's shape.
    HullShape,
}

/// The factorised KKT system of one handle set.
struct Factored {
    mode: Mode,
    lu: LU<f64, Dyn, Dyn>,
    /// The constant part of the right-hand side: `ω_F² Tᵀ C² c` (eq. 1) or zero
    /// (eq. 6, whose part is refitted every iteration) (n × 2).
    b0: DMatrix<f64>,
    /// Right-hand side and solution ((n + K) × 2).
    rhs: DMatrix<f64>,
}

/// One cage's deformation mesh and solver state (see the module documentation).
pub(super) struct Deformer {
    /// Rest hull (n, counter-clockwise).
    hull: Vec<Vec2>,
    mesh_rest: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
    /// Eq. 2's `c_i^t` of each triangle's edges `(t[e], t[e + 1])`.
    weights: Vec<[f64; 3]>,
    /// Eq. 4's `T` (m × n).
    t_mesh: DMatrix<f64>,
    neighbours: Vec<Vec<u32>>,
    /// `Tᵀ L T`, `L` the cotangent-weighted Laplacian (n × n).
    normal_d: DMatrix<f64>,
    factored: Option<Factored>,
    mesh_pos: DMatrix<f64>,
    b_mesh: DMatrix<f64>,
    b_hull: DMatrix<f64>,
    previous: DMatrix<f64>,
}

/// `½ cot` of the angle at `c` in the triangle `(a, b, c)`, clamped (see the module
/// documentation).
fn cot_weight(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let (u, v) = (a - c, b - c);
    let s = cross(u, v).abs();
    let w = if s > 0.0 { 0.5 * u.dot(&v) / s } else { 0.0 };
    if w.is_finite() {
        w.clamp(MIN_EDGE_WEIGHT, MAX_EDGE_WEIGHT)
    } else {
        MIN_EDGE_WEIGHT
    }
}

/// The rotation `(cos, sin)` of the 2-D Procrustes fit with `Σ r·q = sd`,
/// `Σ r×q = sc`; the identity when undefined.
fn fit_rotation(sd: f64, sc: f64) -> (f64, f64) {
    let len = (sd * sd + sc * sc).sqrt();
    if len > 0.0 && len.is_finite() {
        (sd / len, sc / len)
    } else {
        (1.0, 0.0)
    }
}

impl Deformer {
    /// The solver of the mesh `mesh_rest` (its first `hull.len()` vertices the hull's)
    /// with `triangles` and eq. 4's `t_mesh`.
    ///
    /// # Complexity
    /// O(m n²) for `Tᵀ L T`.
    pub(super) fn new(
        hull: Vec<Vec2>,
        mesh_rest: Vec<Vec2>,
        triangles: Vec<[u32; 3]>,
        t_mesh: DMatrix<f64>,
    ) -> Deformer {
        let (m, n) = (mesh_rest.len(), hull.len());
        let weights: Vec<[f64; 3]> = triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| mesh_rest[i as usize]);
                [0, 1, 2].map(|e| cot_weight(p[e], p[(e + 1) % 3], p[(e + 2) % 3]))
            })
            .collect();
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
        // L T, L the weighted Laplacian of the triangle edges (an interior edge gets
        // the weights of both its triangles).
        let mut lt = DMatrix::zeros(m, n);
        for (t, w) in triangles.iter().zip(&weights) {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                for j in 0..n {
                    let d = w[k] * (t_mesh[(a, j)] - t_mesh[(b, j)]);
                    lt[(a, j)] += d;
                    lt[(b, j)] -= d;
                }
            }
        }
        let mut normal_d = DMatrix::zeros(n, n);
        normal_d.gemm_tr(1.0, &t_mesh, &lt, 0.0);
        Deformer {
            hull,
            mesh_rest,
            triangles,
            weights,
            t_mesh,
            neighbours,
            normal_d,
            factored: None,
            mesh_pos: DMatrix::zeros(m, 2),
            b_mesh: DMatrix::zeros(m, 2),
            b_hull: DMatrix::zeros(n, 2),
            previous: DMatrix::zeros(n, 2),
        }
    }

    /// The mean length of the mesh's edges at rest (m): about one layer of eq. 5's
    /// breadth-first search.
    pub(super) fn mean_edge_m(&self) -> f64 {
        let (mut sum, mut count) = (0.0, 0usize);
        for (i, nb) in self.neighbours.iter().enumerate() {
            for &j in nb {
                sum += (self.mesh_rest[i] - self.mesh_rest[j as usize]).norm();
                count += 1;
            }
        }
        if count == 0 || sum <= 0.0 {
            1.0
        } else {
            sum / count as f64
        }
    }

    pub(super) fn mesh_rest(&self) -> &[Vec2] {
        &self.mesh_rest
    }

    pub(super) fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    pub(super) fn t_mesh(&self) -> &DMatrix<f64> {
        &self.t_mesh
    }

    /// Eq. 2's weight of every triangle edge `(t[e], t[e + 1])`.
    pub(super) fn edge_weights(&self) -> &[[f64; 3]] {
        &self.weights
    }

    /// Forgets the factorisation (the next solve refactors).
    pub(super) fn clear(&mut self) {
        self.factored = None;
    }

    /// Eq. 5's coefficient for every mesh vertex, from the mesh vertices `sources`
    /// (the dragged handles'), with `k` in layers.
    ///
    /// # Formula
    /// `coefficient_i = α d_i e^{c_i − k} + β c_i` (eq. 5), `c_i` the breadth-first
    /// layer of vertex `i` from the sources (a vertex the mesh does not reach counts
    /// one layer past the deepest), `d_i` its rest distance to the nearest source (m);
    /// 0 at the sources. Capped at [`MAX_LOCALITY_COEFFICIENT`].
    pub(super) fn locality_coefficients(
        &self,
        sources: &[usize],
        alpha: f64,
        k: f64,
        beta: f64,
    ) -> Vec<f64> {
        let m = self.mesh_rest.len();
        let mut layer = vec![usize::MAX; m];
        let mut queue = VecDeque::new();
        for &s in sources {
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
                (alpha * d * (c - k).min(700.0).exp() + beta * c).min(MAX_LOCALITY_COEFFICIENT)
            })
            .collect()
    }

    /// Factorises the KKT system of the handle rows `rows` (K × n) for `mode`, with
    /// eq. 5's coefficients `coef` (eq. 1 only).
    ///
    /// # Complexity
    /// O(m n²) for `Tᵀ C² T` (eq. 1), O((n + K)³) for the LU.
    pub(super) fn factor(
        &mut self,
        rows: &DMatrix<f64>,
        mode: Mode,
        coef: &[f64],
        p: &CageParams,
    ) -> bool {
        let n = self.hull.len();
        let k = rows.nrows();
        let mut a = &self.normal_d * (p.w_d * p.w_d);
        let mut b0 = DMatrix::zeros(n, 2);
        match mode {
            Mode::Locality => {
                // Eq. 1: ω_F² Tᵀ C² T and ω_F² Tᵀ C² c.
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
            }
            Mode::HullShape => {
                // Eq. 6: ω_S² Dᵀ D, D the cyclic difference matrix of eq. 8.
                let w = p.w_s * p.w_s;
                for i in 0..n {
                    let j = (i + 1) % n;
                    a[(i, i)] += w;
                    a[(j, j)] += w;
                    a[(i, j)] -= w;
                    a[(j, i)] -= w;
                }
            }
        }
        let mut kkt = DMatrix::zeros(n + k, n + k);
        kkt.view_mut((0, 0), (n, n)).copy_from(&a);
        kkt.view_mut((n, 0), (k, n)).copy_from(rows);
        kkt.view_mut((0, n), (n, k)).copy_from(&rows.transpose());
        let lu = kkt.lu();
        if !lu.is_invertible() {
            self.factored = None;
            return false;
        }
        self.factored = Some(Factored {
            mode,
            lu,
            b0,
            rhs: DMatrix::zeros(n + k, 2),
        });
        true
    }

    /// Runs the local/global iteration from `deformed` (n × 2, updated in place) with
    /// the handles' targets `targets` (K, in the order of the factored rows). Returns
    /// the iterations run and whether the last one moved no vertex more than the
    /// tolerance, or `None` when the solve failed (nothing factored, or a non-finite
    /// solution; `deformed` then holds the last finite iterate).
    ///
    /// # Complexity
    /// O(iterations · m n) and no allocation.
    pub(super) fn solve(
        &mut self,
        deformed: &mut DMatrix<f64>,
        targets: &[Vec2],
        p: &CageParams,
    ) -> Option<(usize, bool)> {
        let n = self.hull.len();
        let w_d2 = p.w_d * p.w_d;
        let w_s2 = p.w_s * p.w_s;
        let tol2 = p.tolerance_m * p.tolerance_m;
        let f = self.factored.as_mut()?;
        let iterations = p.max_iterations.max(1);
        for iter in 1..=iterations {
            // Local step: each triangle's rotation from the current mesh (eq. 2).
            self.mesh_pos.gemm(1.0, &self.t_mesh, deformed, 0.0);
            self.b_mesh.fill(0.0);
            for (t, w) in self.triangles.iter().zip(&self.weights) {
                let (mut sd, mut sc) = (0.0, 0.0);
                for e in 0..3 {
                    let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
                    let r = self.mesh_rest[a] - self.mesh_rest[b];
                    let q = Vec2::new(
                        self.mesh_pos[(a, 0)] - self.mesh_pos[(b, 0)],
                        self.mesh_pos[(a, 1)] - self.mesh_pos[(b, 1)],
                    );
                    sd += w[e] * r.dot(&q);
                    sc += w[e] * cross(r, q);
                }
                let (co, si) = fit_rotation(sd, sc);
                for e in 0..3 {
                    let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
                    let r = (self.mesh_rest[a] - self.mesh_rest[b]) * w[e];
                    let (rx, ry) = (co * r.x - si * r.y, si * r.x + co * r.y);
                    self.b_mesh[(a, 0)] += rx;
                    self.b_mesh[(a, 1)] += ry;
                    self.b_mesh[(b, 0)] -= rx;
                    self.b_mesh[(b, 1)] -= ry;
                }
            }
            self.b_hull.gemm_tr(w_d2, &self.t_mesh, &self.b_mesh, 0.0);
            self.b_hull += &f.b0;
            if f.mode == Mode::HullShape {
                // The hull's rotation R_S (eq. 7 made rotation invariant), then
                // ω_S² Dᵀ R_S d.
                let (mut sd, mut sc) = (0.0, 0.0);
                for i in 0..n {
                    let j = (i + 1) % n;
                    let r = self.hull[i] - self.hull[j];
                    let q = Vec2::new(
                        deformed[(i, 0)] - deformed[(j, 0)],
                        deformed[(i, 1)] - deformed[(j, 1)],
                    );
                    sd += r.dot(&q);
                    sc += cross(r, q);
                }
                let (co, si) = fit_rotation(sd, sc);
                for i in 0..n {
                    let j = (i + 1) % n;
                    let r = (self.hull[i] - self.hull[j]) * w_s2;
                    let (rx, ry) = (co * r.x - si * r.y, si * r.x + co * r.y);
                    self.b_hull[(i, 0)] += rx;
                    self.b_hull[(i, 1)] += ry;
                    self.b_hull[(j, 0)] -= rx;
                    self.b_hull[(j, 1)] -= ry;
                }
            }
            // Global step: the KKT solve.
            f.rhs.view_mut((0, 0), (n, 2)).copy_from(&self.b_hull);
            for (r, t) in targets.iter().enumerate() {
                f.rhs[(n + r, 0)] = t.x;
                f.rhs[(n + r, 1)] = t.y;
            }
            if !f.lu.solve_mut(&mut f.rhs) || f.rhs.iter().any(|v| !v.is_finite()) {
                return None;
            }
            self.previous.copy_from(deformed);
            deformed.copy_from(&f.rhs.view((0, 0), (n, 2)));
            let moved2 = (0..n)
                .map(|i| {
                    let dx = deformed[(i, 0)] - self.previous[(i, 0)];
                    let dy = deformed[(i, 1)] - self.previous[(i, 1)];
                    dx * dx + dy * dy
                })
                .fold(0.0, f64::max);
            if moved2 <= tol2 {
                return Some((iter, true));
            }
        }
        Some((iterations, false))
    }
}
