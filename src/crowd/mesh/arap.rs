//! As-rigid-as-possible deformation of the crowd mesh.
//!
//! The two-step method of Igarashi, Moscovich and Hughes 2005, "As-Rigid-As-Possible
//! Shape Manipulation" (cited as mesh-formation-control reference \[28\], section 4.1),
//! with soft constraints — on vertices ([`Constraint`]) and on points inside
//! triangles, held through the triangle's corners by their barycentric coordinates
//! ([`PointConstraint`], the supplementary points an area control samples,
//! mesh-formation-control section 4.2):
//!
//! 1. **Similarity step.** Each triangle edge `(i, j)` expresses the opposite vertex `k`
//!    in the edge's local frame, `v_k = v_i + x (v_j - v_i) + y R90 (v_j - v_i)`, with
//!    `(x, y)` taken from the rest pose. Minimising the squared violation of these
//!    relations over all triangles and edges, plus the weighted constraint and anchor
//!    terms, is one sparse SPD linear system in the `2n` interleaved unknowns
//!    `(x_0, y_0, x_1, y_1, …)`. Its solution allows rotation and uniform scaling.
//! 2. **Rotation fitting and scale adjustment.** Every rest triangle is fitted to its
//!    step-1 image by a similarity (closed-form Procrustes) whose scale is then removed,
//!    leaving a rotation `R_t`. Minimising `Σ_t Σ_edges ‖(v_j - v_i) - R_t (r_j - r_i)‖²`
//!    plus the constraint and anchor terms gives one `n × n` SPD matrix (a weighted graph
//!    Laplacian) shared by the x and y coordinates.
//!
//! Both matrices depend only on the mesh and on the constraint *set* (vertices, points
//! and weights), not on the targets, so they are factorised once per constraint set
//! by [`Arap::set_constraints`] or [`Arap::set_constraints_and_points`].
//! [`Arap::solve`] then costs two right-hand-side assemblies and three pairs of
//! triangular solves, with no allocation.
//!
//! Meshes of several pieces ([`TriMesh::piece_count`]): the systems have no terms
//! between pieces, so they are block diagonal and each piece deforms on its own.
//! Every vertex carries the anchor term, so each piece's block is positive
//! definite even when no constraint is on it, and the rigid motion that carries the
//! anchor pose is fitted per piece (the identity for a piece without constraints):
//! a piece no finger holds stays where it is.
//!
//! The sparse factorisation is a reverse Cuthill–McKee ordering of the vertices followed
//! by an envelope (skyline, profile) Cholesky factorisation (`envelope.rs`), which
//! suits the banded matrices of grid-like meshes: for a `c × r` grid the envelope has
//! about `2n · 2 min(c, r)` entries in step 1 and `n · min(c, r)` in step 2. A point
//! constraint couples only the corners of its triangle, which the envelope already
//! holds.

use super::envelope::Envelope;
use crate::crowd::mesh::TriMesh;
use crate::geom::Vec2;

/// Weight of the anchor term `ANCHOR_WEIGHT · ‖v - T(a_v)‖²` on every vertex, relative
/// to the unit weight of each rigidity (edge) term (see [`Arap::solve`] for the rigid
/// motion `T`, one per piece). Keeps both systems positive definite with zero or one
/// constraint on any piece and resolves the free rotation and scale; small enough
/// not to be felt next to handle weights (≥ 1).
pub const ANCHOR_WEIGHT: f64 = 1e-4;

/// Largest accepted constraint weight; larger weights make the systems ill-conditioned
/// against [`ANCHOR_WEIGHT`] (condition number about `MAX / ANCHOR_WEIGHT`).
pub const MAX_CONSTRAINT_WEIGHT: f64 = 1e9;

/// Relative size below which a triangle's similarity fit is treated as degenerate
/// (collapsed step-1 triangle) and the identity rotation is used instead.
const ROTATION_FIT_EPS: f64 = 1e-12;

/// One constrained vertex and its weight in the least-squares solve (large = hard handle,
/// smaller = soft supplementary point).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Constraint {
    /// Vertex index in the mesh.
    pub vertex: u32,
    /// Weight of `‖v - target‖²` relative to a rigidity term (dimensionless, finite,
    /// in `(0, MAX_CONSTRAINT_WEIGHT]`).
    pub weight: f64,
}

/// A soft constraint on a point of the mesh that need not be a vertex: the point
/// `Σ_k bary[k] · v[corners[k]]` inside one triangle is pulled towards its target
/// (mesh-formation-control section 4.2: the supplementary control points an area
/// control samples inside its hull).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PointConstraint {
    /// The corners of the triangle holding the point (vertex indices).
    pub corners: [u32; 3],
    /// The point's barycentric coordinates in that triangle (sum 1).
    pub bary: [f64; 3],
    /// Weight of `‖Σ_k bary_k v_k - target‖²` relative to a rigidity term
    /// (dimensionless, finite, in `(0, MAX_CONSTRAINT_WEIGHT]`).
    pub weight: f64,
}

impl PointConstraint {
    /// Where the point is on the mesh pose `verts`.
    pub fn position(&self, verts: &[Vec2]) -> Vec2 {
        self.corners
            .iter()
            .zip(&self.bary)
            .fold(Vec2::zeros(), |acc, (&c, &b)| acc + verts[c as usize] * b)
    }
}

/// Which caller buffer an [`ArapError`] is about.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ArapBuffer {
    /// The `targets` argument of [`Arap::solve`].
    Targets,
    /// The `anchor` argument of [`Arap::solve`].
    Anchor,
    /// The `out` argument of [`Arap::solve`].
    Out,
}

impl std::fmt::Display for ArapBuffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ArapBuffer::Targets => "targets",
            ArapBuffer::Anchor => "anchor",
            ArapBuffer::Out => "out",
        })
    }
}

/// Errors of the ARAP solver.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum ArapError {
    /// A constraint names a vertex the mesh does not have.
    #[error("constraint on vertex {vertex}, but the mesh has {vertex_count} vertices")]
    VertexOutOfRange {
        /// The offending vertex index.
        vertex: u32,
        /// Number of mesh vertices.
        vertex_count: usize,
    },
    /// A constraint weight is not finite or outside `(0, MAX_CONSTRAINT_WEIGHT]`.
    #[error("constraint on vertex {vertex} has unusable weight {weight}")]
    BadWeight {
        /// The constrained vertex.
        vertex: u32,
        /// The rejected weight.
        weight: f64,
    },
    /// A buffer has the wrong length.
    #[error("{buffer} has {got} entries, expected {expected}")]
    LengthMismatch {
        /// Which buffer.
        buffer: ArapBuffer,
        /// Required length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// An input position is NaN or infinite.
    #[error("{buffer}[{index}] is not finite")]
    NonFinite {
        /// Which buffer.
        buffer: ArapBuffer,
        /// Index of the first bad entry.
        index: usize,
    },
    /// The Cholesky factorisation failed (a non-positive pivot: degenerate mesh or
    /// extreme weights); [`Arap::solve`] refuses until a set factorises.
    #[error("ARAP system is not positive definite (degenerate mesh or weights)")]
    Degenerate,
    /// A point constraint's corners are out of range, or not corners of one mesh
    /// triangle (the solver couples only vertices that share a triangle).
    #[error("point constraint {index} is not inside a mesh triangle")]
    PointNotInTriangle {
        /// Index of the point constraint.
        index: usize,
    },
    /// A point constraint's weight or barycentric coordinates are unusable (weight
    /// not finite or outside `(0, MAX_CONSTRAINT_WEIGHT]`, a coordinate not finite).
    #[error("point constraint {index} has an unusable weight or coordinates")]
    BadPoint {
        /// Index of the point constraint.
        index: usize,
    },
}

/// Reverse Cuthill–McKee ordering of a graph in CSR form (`adj_start`, `adj`): returns
/// `perm` with `perm[new] = old`. Each connected component starts from a
/// pseudo-peripheral vertex (George–Liu); neighbours are visited by increasing degree.
fn reverse_cuthill_mckee(adj_start: &[usize], adj: &[u32]) -> Vec<u32> {
    let n = adj_start.len().saturating_sub(1);
    let degree = |v: usize| adj_start[v + 1] - adj_start[v];
    let neighbours = |v: usize| {
        adj[adj_start[v]..adj_start[v + 1]]
            .iter()
            .map(|&w| w as usize)
    };
    let mut level = vec![usize::MAX; n];
    let mut queue: Vec<usize> = Vec::with_capacity(n);
    // BFS from `root`: (eccentricity, min-degree vertex of the last level).
    let mut bfs = |root: usize, level: &mut Vec<usize>| -> (usize, usize) {
        queue.clear();
        queue.push(root);
        level[root] = 0;
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head];
            head += 1;
            for w in neighbours(v) {
                if level[w] == usize::MAX {
                    level[w] = level[v] + 1;
                    queue.push(w);
                }
            }
        }
        let ecc = level[*queue.last().unwrap_or(&root)];
        let mut best = root;
        let mut best_deg = usize::MAX;
        for &v in queue.iter().rev() {
            if level[v] != ecc {
                break;
            }
            if degree(v) < best_deg || (degree(v) == best_deg && v < best) {
                best = v;
                best_deg = degree(v);
            }
        }
        for &v in queue.iter() {
            level[v] = usize::MAX;
        }
        (ecc, best)
    };
    let mut visited = vec![false; n];
    let mut order: Vec<usize> = Vec::with_capacity(n);
    let mut nbrs: Vec<usize> = Vec::new();
    for seed in 0..n {
        if visited[seed] {
            continue;
        }
        let mut root = seed;
        let (mut ecc, mut cand) = bfs(root, &mut level);
        loop {
            let (e2, c2) = bfs(cand, &mut level);
            if e2 > ecc {
                root = cand;
                ecc = e2;
                cand = c2;
            } else {
                if cand != root && e2 == ecc && degree(cand) < degree(root) {
                    root = cand;
                }
                break;
            }
        }
        let begin = order.len();
        order.push(root);
        visited[root] = true;
        let mut head = begin;
        while head < order.len() {
            let v = order[head];
            head += 1;
            nbrs.clear();
            nbrs.extend(neighbours(v).filter(|&w| !visited[w]));
            nbrs.sort_unstable_by_key(|&w| (degree(w), w));
            nbrs.dedup();
            for &w in &nbrs {
                visited[w] = true;
                order.push(w);
            }
        }
    }
    order.reverse();
    order.into_iter().map(|v| v as u32).collect()
}

/// First column of each row's envelope for the vertex graph `pairs` (both directions)
/// under the ordering `inv[vertex] = position`.
fn envelope_first(pairs: &[(u32, u32)], inv: &[u32]) -> Vec<usize> {
    let mut first: Vec<usize> = (0..inv.len()).collect();
    for &(a, b) in pairs {
        let (pa, pb) = (inv[a as usize] as usize, inv[b as usize] as usize);
        if pb < first[pa] {
            first[pa] = pb;
        }
    }
    first
}

/// Step-1 coefficient matrix of one (edge, opposite vertex) relation, as the 2×2
/// similarity blocks `M = α I + β R90` for corners `(i, j, k)`:
/// residual `= M_i v_i + M_j v_j + M_k v_k` (Igarashi et al. 2005, section 4.1).
/// Adds the step-1 (similarity) energy of every triangle, measured on `rest`, to
/// `fac1`, and records each triangle's rest corners about their centroid.
fn assemble_step1(
    fac1: &mut Envelope,
    tris_orig: &[[u32; 3]],
    tris: &[[u32; 3]],
    rest: &[Vec2],
    rest_centered: &mut Vec<[Vec2; 3]>,
) {
    rest_centered.clear();
    for (t, tp) in tris_orig.iter().zip(tris) {
        let p = t.map(|v| rest[v as usize]);
        let centroid = (p[0] + p[1] + p[2]) / 3.0;
        rest_centered.push(p.map(|q| q - centroid));
        // Step 1: three (edge, opposite vertex) relations per triangle.
        for c in 0..3 {
            let corners = [c, (c + 1) % 3, (c + 2) % 3];
            let Some(blocks) = step1_blocks(p[corners[0]], p[corners[1]], p[corners[2]]) else {
                continue;
            };
            for (ma, &ca) in blocks.iter().zip(&corners) {
                for (mb, &cb) in blocks.iter().zip(&corners) {
                    let (va, vb) = (tp[ca] as usize, tp[cb] as usize);
                    // (M_aᵀ M_b)[r][s] = Σ_m M_a[m][r] M_b[m][s]
                    for r in 0..2 {
                        for s in 0..2 {
                            let (row, col) = (2 * va + r, 2 * vb + s);
                            if row < col {
                                continue;
                            }
                            let v = sim_entry(*ma, 0, r) * sim_entry(*mb, 0, s)
                                + sim_entry(*ma, 1, r) * sim_entry(*mb, 1, s);
                            fac1.add(row, col, v);
                        }
                    }
                }
            }
        }
    }
}

fn step1_blocks(vi: Vec2, vj: Vec2, vk: Vec2) -> Option<[(f64, f64); 3]> {
    let e = vj - vi;
    let l2 = e.norm_squared();
    if !(l2 > 0.0 && l2.is_finite()) {
        return None;
    }
    let d = vk - vi;
    let x = d.dot(&e) / l2;
    let y = d.dot(&r90(e)) / l2;
    // v_k - v_i - x (v_j - v_i) - y R90 (v_j - v_i)
    Some([(x - 1.0, y), (-x, -y), (1.0, 0.0)])
}

/// Rotation by +90°: `R90 (x, y) = (-y, x)`.
fn r90(v: Vec2) -> Vec2 {
    Vec2::new(-v.y, v.x)
}

/// Entry `(r, s)` of the 2×2 matrix `α I + β R90 = [[α, -β], [β, α]]`.
fn sim_entry((a, b): (f64, f64), r: usize, s: usize) -> f64 {
    match (r, s) {
        (0, 0) | (1, 1) => a,
        (0, 1) => -b,
        _ => b,
    }
}

/// As-rigid-as-possible solver for one mesh: the vertex ordering, the step-1 and
/// step-2 matrices (assembled from the per-triangle coefficients) and their factors,
/// the centred rest triangles for the rotation fit, and the solve workspaces.
///
/// ```
/// use crowdtouch::crowd::mesh::{Arap, Constraint};
/// use crowdtouch::crowd::mesh::TriMesh;
/// use crowdtouch::geom::{Rect, Vec2};
/// let mesh = TriMesh::grid(Rect { min: [0.0, 0.0], max: [4.0, 3.0] }, 5, 4);
/// let mut arap = Arap::new(&mesh);
/// let handles = [Constraint { vertex: 0, weight: 1000.0 }, Constraint { vertex: 19, weight: 1000.0 }];
/// arap.set_constraints(&handles).unwrap();
/// // Translate both handles by (1, 2): the whole mesh follows rigidly.
/// let d = Vec2::new(1.0, 2.0);
/// let targets = [mesh.rest()[0] + d, mesh.rest()[19] + d];
/// let mut out = vec![Vec2::zeros(); mesh.vertex_count()];
/// arap.solve(&targets, mesh.rest(), &mut out).unwrap();
/// for (p, r) in out.iter().zip(mesh.rest()) {
///     assert!((p - r - d).norm() < 1e-3);
/// }
/// ```
#[derive(Clone, Debug)]
pub struct Arap {
    n: usize,
    /// `inv[vertex]` = position of the vertex in the RCM ordering.
    inv: Vec<u32>,
    /// Triangles with permuted vertex indices.
    tris: Vec<[u32; 3]>,
    /// Triangles with the caller's vertex indices.
    tris_orig: Vec<[u32; 3]>,
    /// Rest corners minus the rest centroid, per triangle (for the rotation fit).
    rest_centered: Vec<[Vec2; 3]>,
    /// Step-1 matrix without constraint weights (envelope layout of `fac1`).
    base1: Vec<f64>,
    fac1: Envelope,
    /// Step-2 matrix without constraint weights (envelope layout of `fac2`).
    base2: Vec<f64>,
    fac2: Envelope,
    constraints: Vec<Constraint>,
    /// Point constraints of the current factorisation.
    points: Vec<PointConstraint>,
    /// Sum of constraint weights per permuted vertex in the current factorisation.
    diag_weight: Vec<f64>,
    scratch_weight: Vec<f64>,
    factored: bool,
    factorizations: u64,
    /// Step-1 right-hand side, then solution (permuted, interleaved x, y).
    rhs1: Vec<f64>,
    /// Step-2 right-hand sides, then solutions (permuted, `[x, y]`).
    rhs2: Vec<[f64; 2]>,
    /// Piece of every vertex (caller's indices).
    piece: Vec<u32>,
    /// Per piece: the rigid motion carrying the anchor pose in the current solve.
    motions: Vec<RigidMotion>,
    /// Per piece: the sums the rigid motion is fitted from.
    fits: Vec<MotionFit>,
}

impl Arap {
    /// Precomputes the solver for `mesh` (rest shape = the mesh's rest pose): the vertex
    /// ordering, both system matrices, and a first factorisation with no constraints.
    ///
    /// # Complexity
    /// O(T) assembly plus one factorisation, O(Σ_i bandwidth_i²) (about O(n · b²) for
    /// bandwidth `b`; for a `c × r` grid `b ≈ 2 min(c, r)` in step 1). Allocates.
    ///
    /// # Errors
    /// None here: triangles with out-of-range vertices are ignored and zero-length rest
    /// edges contribute nothing; if the resulting systems are not positive definite,
    /// [`Arap::solve`] returns [`ArapError::Degenerate`].
    pub fn new(mesh: &TriMesh) -> Arap {
        let n = mesh.vertex_count();
        let pieces = mesh.piece_count().max(1);
        let piece: Vec<u32> = (0..n)
            .map(|v| {
                mesh.piece_of_vertex()
                    .get(v)
                    .copied()
                    .filter(|&p| (p as usize) < pieces)
                    .unwrap_or(0)
            })
            .collect();
        let rest = mesh.rest();
        let tris_orig: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&v| (v as usize) < n))
            .collect();

        // Vertex graph in CSR form.
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(tris_orig.len() * 6);
        for t in &tris_orig {
            for c in 0..3 {
                let (a, b) = (t[c], t[(c + 1) % 3]);
                if a != b {
                    pairs.push((a, b));
                    pairs.push((b, a));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut adj_start = vec![0usize; n + 1];
        for &(a, _) in &pairs {
            adj_start[a as usize + 1] += 1;
        }
        for i in 0..n {
            adj_start[i + 1] += adj_start[i];
        }
        let adj: Vec<u32> = pairs.iter().map(|&(_, b)| b).collect();

        // RCM, unless the given order already has a smaller envelope (row-major grids
        // with fewer columns than rows do).
        let rcm = reverse_cuthill_mckee(&adj_start, &adj);
        let mut inv = vec![0u32; n];
        for (new, &old) in rcm.iter().enumerate() {
            inv[old as usize] = new as u32;
        }
        let identity: Vec<u32> = (0..n as u32).collect();
        let (rcm_first, ident_first) = (
            envelope_first(&pairs, &inv),
            envelope_first(&pairs, &identity),
        );
        let profile = |first: &[usize]| first.iter().enumerate().map(|(i, f)| i - f).sum::<usize>();
        let first_v = if profile(&ident_first) < profile(&rcm_first) {
            inv = identity;
            ident_first
        } else {
            rcm_first
        };
        let first1: Vec<usize> = first_v.iter().flat_map(|&f| [2 * f, 2 * f]).collect();
        let mut fac1 = Envelope::new(first1);
        let mut fac2 = Envelope::new(first_v);

        let tris: Vec<[u32; 3]> = tris_orig
            .iter()
            .map(|t| t.map(|v| inv[v as usize]))
            .collect();
        let mut rest_centered = Vec::with_capacity(tris_orig.len());
        assemble_step1(&mut fac1, &tris_orig, &tris, rest, &mut rest_centered);
        for tp in &tris {
            // Step 2: edge differences, unit weight per triangle edge.
            for c in 0..3 {
                let (a, b) = (tp[c] as usize, tp[(c + 1) % 3] as usize);
                fac2.add(a, a, 1.0);
                fac2.add(b, b, 1.0);
                fac2.add(a, b, -1.0);
            }
        }
        for p in 0..n {
            fac1.add(2 * p, 2 * p, ANCHOR_WEIGHT);
            fac1.add(2 * p + 1, 2 * p + 1, ANCHOR_WEIGHT);
            fac2.add(p, p, ANCHOR_WEIGHT);
        }
        let mut arap = Arap {
            n,
            inv,
            tris,
            tris_orig,
            rest_centered,
            base1: fac1.vals.clone(),
            fac1,
            base2: fac2.vals.clone(),
            fac2,
            constraints: Vec::new(),
            points: Vec::new(),
            diag_weight: vec![0.0; n],
            scratch_weight: vec![0.0; n],
            factored: false,
            factorizations: 0,
            rhs1: vec![0.0; 2 * n],
            rhs2: vec![[0.0; 2]; n],
            piece,
            motions: vec![RigidMotion::IDENTITY; pieces],
            fits: vec![MotionFit::default(); pieces],
        };
        // A failure is reported by `solve` as `Degenerate`.
        let _ = arap.refactor();
        arap
    }

    /// Number of mesh vertices.
    pub fn vertex_count(&self) -> usize {
        self.n
    }

    /// The current constraint set (as last given to [`Arap::set_constraints`]).
    pub fn constraints(&self) -> &[Constraint] {
        &self.constraints
    }

    /// The current point constraints (as last given to
    /// [`Arap::set_constraints_and_points`]).
    pub fn points(&self) -> &[PointConstraint] {
        &self.points
    }

    /// How many numeric factorisations have run (one in [`Arap::new`], one per effective
    /// constraint-set change). For tests and stats.
    pub fn factorizations(&self) -> u64 {
        self.factorizations
    }

    /// Makes `rest` (one position per vertex) the shape the mesh is as rigid as
    /// possible to, keeping the topology, ordering and constraint set. The
    /// factorisation is redone by the next [`Arap::set_constraints`] (so setting a
    /// new rest shape and a new constraint set costs one factorisation) or, failing
    /// that, by the next [`Arap::solve`].
    ///
    /// The direct-manipulation controller calls this whenever its constraint set
    /// changes, so a deformation made by one control persists when that control ends
    /// while others go on.
    ///
    /// # Complexity
    /// O(T) assembly; no allocation.
    ///
    /// # Errors
    /// [`ArapError::LengthMismatch`] or [`ArapError::NonFinite`] for a bad `rest`
    /// (the solver keeps its previous rest shape); [`ArapError::Degenerate`] when the
    /// new systems cannot be factorised.
    pub fn set_rest(&mut self, rest: &[Vec2]) -> Result<(), ArapError> {
        if rest.len() != self.n {
            return Err(ArapError::LengthMismatch {
                buffer: ArapBuffer::Anchor,
                expected: self.n,
                got: rest.len(),
            });
        }
        if let Some(i) = rest
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(ArapError::NonFinite {
                buffer: ArapBuffer::Anchor,
                index: i,
            });
        }
        self.fac1.vals.fill(0.0);
        assemble_step1(
            &mut self.fac1,
            &self.tris_orig,
            &self.tris,
            rest,
            &mut self.rest_centered,
        );
        for p in 0..self.n {
            self.fac1.add(2 * p, 2 * p, ANCHOR_WEIGHT);
            self.fac1.add(2 * p + 1, 2 * p + 1, ANCHOR_WEIGHT);
        }
        self.base1.copy_from_slice(&self.fac1.vals);
        self.factored = false;
        Ok(())
    }

    /// Stored entries of the step-1 and step-2 factors (profile sizes, for diagnostics).
    pub fn factor_sizes(&self) -> (usize, usize) {
        (self.fac1.stored(), self.fac2.stored())
    }

    /// Sets the constraint set and refactors both systems.
    ///
    /// Nothing is refactored if the set is identical to the current one, or if it only
    /// differs in order or in how equal per-vertex weight sums are split (the matrices
    /// depend only on the sum of weights per vertex); the stored list (which fixes the
    /// meaning of `targets` in [`Arap::solve`]) is still updated. Several constraints on
    /// one vertex are allowed and add up.
    ///
    /// # Complexity
    /// O(n + k) to compare; a refactorisation is O(Σ_i bandwidth_i²), no allocation
    /// unless the constraint list outgrows its capacity.
    ///
    /// # Errors
    /// [`ArapError::VertexOutOfRange`], [`ArapError::BadWeight`] (the state is then
    /// unchanged), or [`ArapError::Degenerate`] if the factorisation fails (the set is
    /// stored, and [`Arap::solve`] fails until a set factorises).
    pub fn set_constraints(&mut self, constraints: &[Constraint]) -> Result<(), ArapError> {
        self.set_constraints_and_points(constraints, &[])
    }

    /// Sets vertex constraints and point constraints ([`PointConstraint`]: a point
    /// inside a triangle, held through its corners), and refactors both systems when
    /// the matrices change. As [`Arap::set_constraints`], which is this with no points;
    /// in [`Arap::solve`] the targets of `points` follow those of `constraints`.
    ///
    /// A point constraint adds `w · b bᵀ` on its triangle's corners to both systems;
    /// the corners share a triangle, so the entries lie inside the factor's envelope
    /// and nothing is reallocated.
    ///
    /// # Complexity
    /// As [`Arap::set_constraints`], plus O(points).
    ///
    /// # Errors
    /// As [`Arap::set_constraints`]; [`ArapError::PointNotInTriangle`] or
    /// [`ArapError::BadPoint`] for a bad point (the state is then unchanged).
    pub fn set_constraints_and_points(
        &mut self,
        constraints: &[Constraint],
        points: &[PointConstraint],
    ) -> Result<(), ArapError> {
        for c in constraints {
            if c.vertex as usize >= self.n {
                return Err(ArapError::VertexOutOfRange {
                    vertex: c.vertex,
                    vertex_count: self.n,
                });
            }
            if !(c.weight > 0.0 && c.weight <= MAX_CONSTRAINT_WEIGHT) {
                return Err(ArapError::BadWeight {
                    vertex: c.vertex,
                    weight: c.weight,
                });
            }
        }
        for (index, p) in points.iter().enumerate() {
            let usable = p.weight > 0.0
                && p.weight <= MAX_CONSTRAINT_WEIGHT
                && p.bary.iter().all(|b| b.is_finite());
            if !usable {
                return Err(ArapError::BadPoint { index });
            }
            if !self.couples(p.corners) {
                return Err(ArapError::PointNotInTriangle { index });
            }
        }
        let same_points = points == self.points.as_slice();
        if self.factored && same_points && constraints == self.constraints.as_slice() {
            return Ok(());
        }
        self.scratch_weight.fill(0.0);
        for c in constraints {
            self.scratch_weight[self.inv[c.vertex as usize] as usize] += c.weight;
        }
        self.constraints.clear();
        self.constraints.extend_from_slice(constraints);
        if self.factored && same_points && self.scratch_weight == self.diag_weight {
            return Ok(());
        }
        self.points.clear();
        self.points.extend_from_slice(points);
        std::mem::swap(&mut self.diag_weight, &mut self.scratch_weight);
        self.refactor()
    }

    /// Whether the three vertices are in range and pairwise inside the envelope
    /// (corners of one triangle always are).
    fn couples(&self, corners: [u32; 3]) -> bool {
        if corners.iter().any(|&c| c as usize >= self.n) {
            return false;
        }
        let p = corners.map(|c| self.inv[c as usize] as usize);
        (0..3).all(|a| (a + 1..3).all(|b| self.fac2.contains(p[a], p[b])))
    }

    /// Rebuilds both factorisations from the base matrices and `diag_weight`.
    fn refactor(&mut self) -> Result<(), ArapError> {
        self.factorizations += 1;
        self.fac1.vals.copy_from_slice(&self.base1);
        self.fac2.vals.copy_from_slice(&self.base2);
        for (p, &w) in self.diag_weight.iter().enumerate() {
            if w != 0.0 {
                self.fac1.add(2 * p, 2 * p, w);
                self.fac1.add(2 * p + 1, 2 * p + 1, w);
                self.fac2.add(p, p, w);
            }
        }
        for pc in &self.points {
            let p = pc.corners.map(|c| self.inv[c as usize] as usize);
            for a in 0..3 {
                for b in a..3 {
                    // The stored entry (i, j) stands for (j, i) too: each unordered
                    // pair once, twice when two corners are one vertex.
                    let mut v = pc.weight * pc.bary[a] * pc.bary[b];
                    if a != b && p[a] == p[b] {
                        v *= 2.0;
                    }
                    self.fac1.add(2 * p[a], 2 * p[b], v);
                    self.fac1.add(2 * p[a] + 1, 2 * p[b] + 1, v);
                    self.fac2.add(p[a], p[b], v);
                }
            }
        }
        self.factored = self.fac1.factor().is_ok() && self.fac2.factor().is_ok();
        if self.factored {
            Ok(())
        } else {
            Err(ArapError::Degenerate)
        }
    }

    /// Two-step ARAP deformation.
    ///
    /// `targets[k]` is the target of `constraints()[k]`, then
    /// `targets[constraints().len() + j]` that of `points()[j]`; `anchor` (one per vertex) is the
    /// pose the anchor term pulls towards (the mesh pose when the constraint set last
    /// changed); the result is written to `out` (one per vertex). Rest shape = the
    /// mesh's rest pose.
    ///
    /// The anchor pose is first carried along by the rigid motion `T` (rotation and
    /// translation, weighted least squares) that best maps the constrained vertices'
    /// anchor positions onto their targets: the identity without constraints, a pure
    /// translation with one. So the anchor only settles what the constraints leave free
    /// (with one handle: the rotation and scale about it), dragging one handle
    /// translates the mesh, and a rigid motion of all targets moves the mesh exactly
    /// rigidly instead of being held back by the old pose. On a mesh of several
    /// pieces each piece has its own `T`, fitted to the constraints on that piece:
    /// a piece without constraints keeps its anchor pose (the identity), so dragging
    /// one piece leaves the others where they are.
    ///
    /// # Formula
    /// Igarashi, Moscovich, Hughes 2005, sections 4.1–4.2 (mesh-formation-control
    /// reference \[28\]), with soft constraints:
    /// step 1 minimises
    /// `Σ_t Σ_(i,j,k) ‖v_k - v_i - x_ij (v_j - v_i) - y_ij R90 (v_j - v_i)‖²`
    /// `+ Σ_c w_c ‖v_c - q_c‖² + Σ_p w_p ‖Σ_k b_pk v_pk - q_p‖²`
    /// `+ ANCHOR_WEIGHT Σ_v ‖v - T_piece(v)(a_v)‖²`;
    /// step 2 minimises `Σ_t Σ_(i,j) ‖(v_j - v_i) - R_t (r_j - r_i)‖²` plus the same
    /// constraint and anchor terms, with `R_t` the rotation of the similarity that best
    /// maps the rest triangle onto its step-1 image.
    ///
    /// # Units
    /// Positions in metres; weights dimensionless.
    ///
    /// # Complexity
    /// O(T + profile) per call: two right-hand sides, one 2n and two n triangular
    /// solve pairs. No allocation.
    ///
    /// # Errors
    /// [`ArapError::LengthMismatch`], [`ArapError::NonFinite`] for bad inputs (nothing
    /// is written), [`ArapError::Degenerate`] if the current set did not factorise.
    pub fn solve(
        &mut self,
        targets: &[Vec2],
        anchor: &[Vec2],
        out: &mut [Vec2],
    ) -> Result<(), ArapError> {
        let check_len = |buffer, expected, got| {
            if expected == got {
                Ok(())
            } else {
                Err(ArapError::LengthMismatch {
                    buffer,
                    expected,
                    got,
                })
            }
        };
        check_len(
            ArapBuffer::Targets,
            self.constraints.len() + self.points.len(),
            targets.len(),
        )?;
        check_len(ArapBuffer::Anchor, self.n, anchor.len())?;
        check_len(ArapBuffer::Out, self.n, out.len())?;
        let finite = |p: &Vec2| p.x.is_finite() && p.y.is_finite();
        if let Some(index) = targets.iter().position(|p| !finite(p)) {
            return Err(ArapError::NonFinite {
                buffer: ArapBuffer::Targets,
                index,
            });
        }
        if let Some(index) = anchor.iter().position(|p| !finite(p)) {
            return Err(ArapError::NonFinite {
                buffer: ArapBuffer::Anchor,
                index,
            });
        }
        if !self.factored {
            self.refactor()?;
        }
        self.fit_anchor_motions(targets, anchor);
        let motions = std::mem::take(&mut self.motions);
        self.step1(targets, anchor, &motions);
        self.step2(targets, anchor, &motions);
        self.motions = motions;
        for (o, &p) in out.iter_mut().zip(&self.inv) {
            let [x, y] = self.rhs2[p as usize];
            *o = Vec2::new(x, y);
        }
        Ok(())
    }

    /// Per piece, the rigid motion that best carries the piece's constrained
    /// vertices' and points' anchor positions to their targets (weighted least
    /// squares; [`RigidMotion::IDENTITY`] for a piece without constraints, a
    /// translation with one constrained position), into `motions`. No allocation.
    fn fit_anchor_motions(&mut self, targets: &[Vec2], anchor: &[Vec2]) {
        let (vt, pt) = targets.split_at(self.constraints.len());
        let piece = &self.piece;
        let anchored = self
            .constraints
            .iter()
            .map(|c| {
                (
                    piece[c.vertex as usize],
                    c.weight,
                    anchor[c.vertex as usize],
                )
            })
            .chain(
                self.points
                    .iter()
                    .map(|p| (piece[p.corners[0] as usize], p.weight, p.position(anchor))),
            );
        self.fits.fill(MotionFit::default());
        for ((k, w, a), q) in anchored.clone().zip(vt.iter().chain(pt)) {
            let f = &mut self.fits[k as usize];
            f.wsum += w;
            f.abar += a * w;
            f.qbar += q * w;
        }
        for f in &mut self.fits {
            if f.wsum > 0.0 {
                f.abar /= f.wsum;
                f.qbar /= f.wsum;
            }
        }
        for ((k, w, a), q) in anchored.zip(vt.iter().chain(pt)) {
            let f = &mut self.fits[k as usize];
            let a = a - f.abar;
            let q = q - f.qbar;
            f.dot += w * a.dot(&q);
            f.crs += w * (a.x * q.y - a.y * q.x);
            f.aa += w * a.norm_squared();
            f.qq += w * q.norm_squared();
        }
        for (m, f) in self.motions.iter_mut().zip(&self.fits) {
            *m = f.motion();
        }
    }

    /// Step 1 (similarity-invariant energy); the solution is left in `rhs1`.
    fn step1(&mut self, targets: &[Vec2], anchor: &[Vec2], motions: &[RigidMotion]) {
        for ((a, &p), &k) in anchor.iter().zip(&self.inv).zip(&self.piece) {
            let p = 2 * p as usize;
            let a = motions[k as usize].apply(*a);
            self.rhs1[p] = ANCHOR_WEIGHT * a.x;
            self.rhs1[p + 1] = ANCHOR_WEIGHT * a.y;
        }
        for (c, q) in self.constraints.iter().zip(targets) {
            let p = 2 * self.inv[c.vertex as usize] as usize;
            self.rhs1[p] += c.weight * q.x;
            self.rhs1[p + 1] += c.weight * q.y;
        }
        for (pc, q) in self.points.iter().zip(&targets[self.constraints.len()..]) {
            for (&c, &b) in pc.corners.iter().zip(&pc.bary) {
                let p = 2 * self.inv[c as usize] as usize;
                self.rhs1[p] += pc.weight * b * q.x;
                self.rhs1[p + 1] += pc.weight * b * q.y;
            }
        }
        self.fac1.solve(&mut self.rhs1);
    }

    /// Step 2 (rotation fit + scale adjustment) from the step-1 solution in `rhs1`;
    /// the solution is left in `rhs2`.
    fn step2(&mut self, targets: &[Vec2], anchor: &[Vec2], motions: &[RigidMotion]) {
        for ((a, &p), &k) in anchor.iter().zip(&self.inv).zip(&self.piece) {
            let a = motions[k as usize].apply(*a);
            self.rhs2[p as usize] = [ANCHOR_WEIGHT * a.x, ANCHOR_WEIGHT * a.y];
        }
        for (c, q) in self.constraints.iter().zip(targets) {
            let b = &mut self.rhs2[self.inv[c.vertex as usize] as usize];
            b[0] += c.weight * q.x;
            b[1] += c.weight * q.y;
        }
        for (pc, q) in self.points.iter().zip(&targets[self.constraints.len()..]) {
            for (&c, &bc) in pc.corners.iter().zip(&pc.bary) {
                let b = &mut self.rhs2[self.inv[c as usize] as usize];
                b[0] += pc.weight * bc * q.x;
                b[1] += pc.weight * bc * q.y;
            }
        }
        // Σ over the triangle's edges of ±R (r_j - r_i) lands on corner c as
        // R (e_{c-1} - e_c) = R (2 r_c - r_{c-1} - r_{c+1}) = 3 R (r_c - r̄).
        let u = &self.rhs1;
        for (t, pc) in self.tris.iter().zip(&self.rest_centered) {
            let q = t.map(|p| Vec2::new(u[2 * p as usize], u[2 * p as usize + 1]));
            let (cos, sin) = fit_rotation(pc, &q);
            for (&v, g) in t.iter().zip(pc) {
                let b = &mut self.rhs2[v as usize];
                b[0] += 3.0 * (cos * g.x - sin * g.y);
                b[1] += 3.0 * (sin * g.x + cos * g.y);
            }
        }
        self.fac2.solve2(&mut self.rhs2);
    }
}

/// Weighted sums over one piece's constrained positions (anchor `a`, target `q`)
/// from which its rigid motion is fitted: total weight, weighted means, then about
/// the means `Σ w a·q`, `Σ w a×q`, `Σ w ‖a‖²`, `Σ w ‖q‖²`.
#[derive(Copy, Clone, Debug, Default)]
struct MotionFit {
    wsum: f64,
    abar: Vec2,
    qbar: Vec2,
    dot: f64,
    crs: f64,
    aa: f64,
    qq: f64,
}

impl MotionFit {
    /// The rigid motion of the weighted Procrustes fit (rotation from the summed dot
    /// and cross products); the identity without weight.
    fn motion(&self) -> RigidMotion {
        if self.wsum.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return RigidMotion::IDENTITY;
        }
        let norm = self.dot.hypot(self.crs);
        let (cos, sin) = if norm > ROTATION_FIT_EPS * (self.aa * self.qq).sqrt() && norm.is_finite()
        {
            (self.dot / norm, self.crs / norm)
        } else {
            (1.0, 0.0)
        };
        RigidMotion {
            cos,
            sin,
            from: self.abar,
            to: self.qbar,
        }
    }
}

/// A rigid motion `x ↦ R (x - from) + to` with `R` the rotation by `(cos, sin)`.
#[derive(Copy, Clone, Debug, PartialEq)]
struct RigidMotion {
    cos: f64,
    sin: f64,
    from: Vec2,
    to: Vec2,
}

impl RigidMotion {
    const IDENTITY: RigidMotion = RigidMotion {
        cos: 1.0,
        sin: 0.0,
        from: Vec2::new(0.0, 0.0),
        to: Vec2::new(0.0, 0.0),
    };

    fn apply(&self, x: Vec2) -> Vec2 {
        let d = x - self.from;
        Vec2::new(
            self.cos * d.x - self.sin * d.y,
            self.sin * d.x + self.cos * d.y,
        ) + self.to
    }
}

/// Rotation `(cos θ, sin θ)` of the similarity `T = [[a, -b], [b, a]]` minimising
/// `Σ ‖(q_c - q̄) - T p_c‖²` for rest corners `p_c` (already centred), normalised to unit
/// scale; the identity if the fit is degenerate.
///
/// # Formula
/// `a = Σ p_c · q̃_c`, `b = Σ p_c × q̃_c` (the common factor `1 / Σ‖p_c‖²` cancels in the
/// normalisation); Igarashi et al. 2005, section 4.2 (fitting step).
fn fit_rotation(p: &[Vec2; 3], q: &[Vec2; 3]) -> (f64, f64) {
    // The p_c are centred, so Σ p_c · (q_c - q̄) = Σ p_c · q_c (same for the cross).
    let (mut a, mut b, mut pp, mut qq) = (0.0, 0.0, 0.0, 0.0);
    let qbar = (q[0] + q[1] + q[2]) / 3.0;
    for (pc, qc) in p.iter().zip(q) {
        let qc = qc - qbar;
        a += pc.x * qc.x + pc.y * qc.y;
        b += pc.x * qc.y - pc.y * qc.x;
        pp += pc.x * pc.x + pc.y * pc.y;
        qq += qc.x * qc.x + qc.y * qc.y;
    }
    let norm2 = a * a + b * b;
    if norm2 > ROTATION_FIT_EPS * ROTATION_FIT_EPS * pp * qq && norm2.is_finite() {
        let inv = 1.0 / norm2.sqrt();
        (a * inv, b * inv)
    } else {
        (1.0, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Rect;
    use crate::rng::SplitMix64;
    use nalgebra::{DMatrix, DVector, Matrix2, Rotation2};
    use proptest::prelude::*;
    use proptest::test_runner::{Config as ProptestConfig, RngSeed};

    const W_HARD: f64 = 1000.0;

    fn grid(cols: usize, rows: usize) -> TriMesh {
        TriMesh::grid(
            Rect {
                min: [1.0, -2.0],
                max: [
                    1.0 + 0.5 * (cols - 1) as f64,
                    -2.0 + 0.5 * (rows - 1) as f64,
                ],
            },
            cols,
            rows,
        )
    }

    fn mesh_size(m: &TriMesh) -> f64 {
        let r = m.rest();
        let (mut lo, mut hi) = (r[0], r[0]);
        for p in r {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (hi - lo).norm()
    }

    fn hard(vs: &[u32]) -> Vec<Constraint> {
        vs.iter()
            .map(|&vertex| Constraint {
                vertex,
                weight: W_HARD,
            })
            .collect()
    }

    fn solve(arap: &mut Arap, targets: &[Vec2], anchor: &[Vec2]) -> Vec<Vec2> {
        let mut out = vec![Vec2::zeros(); arap.vertex_count()];
        arap.solve(targets, anchor, &mut out).expect("solve");
        out
    }

    fn max_err(a: &[Vec2], b: &[Vec2]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max)
    }

    #[test]
    fn rcm_is_a_permutation_with_a_small_profile() {
        for (c, r) in [(20, 20), (10, 8), (30, 3)] {
            let m = grid(c, r);
            let arap = Arap::new(&m);
            let mut seen = vec![false; m.vertex_count()];
            for &p in &arap.inv {
                assert!(!seen[p as usize]);
                seen[p as usize] = true;
            }
            let (s1, s2) = arap.factor_sizes();
            let n = m.vertex_count();
            let band = c.min(r) + 2;
            assert!(
                s2 <= n * band,
                "{c}x{r}: step-2 profile {s2} > {n} * {band}"
            );
            assert!(s1 <= 2 * n * 2 * band, "{c}x{r}: step-1 profile {s1}");
        }
    }

    #[test]
    fn fit_rotation_recovers_a_similarity() {
        let p = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(0.5, 1.0),
        ];
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let pc = p.map(|v| v - c);
        for theta in [-3.0, -1.0, 0.0, 0.3, 2.5] {
            let rot = Rotation2::new(theta);
            let q = p.map(|v| rot * v * 1.7 + Vec2::new(5.0, -1.0));
            let (cos, sin) = fit_rotation(&pc, &q);
            assert!((cos - theta.cos()).abs() < 1e-12 && (sin - theta.sin()).abs() < 1e-12);
        }
        assert_eq!(fit_rotation(&pc, &[Vec2::new(1.0, 1.0); 3]), (1.0, 0.0));
    }

    /// After `set_rest`, the new shape is the one kept: constraints at their new
    /// rest positions reproduce it, and a rigid motion of them moves it rigidly.
    #[test]
    fn set_rest_makes_a_deformed_pose_the_rest_shape() {
        let m = grid(8, 6);
        let mut arap = Arap::new(&m);
        // A sheared, stretched pose.
        let bent: Vec<Vec2> = m
            .rest()
            .iter()
            .map(|p| Vec2::new(p.x * 1.3 + 0.4 * p.y, p.y * 0.8))
            .collect();
        arap.set_rest(&bent).unwrap();
        let cons = hard(&[0, 7, 40, 47]);
        let before = arap.factorizations();
        arap.set_constraints(&cons).unwrap();
        assert_eq!(
            arap.factorizations(),
            before + 1,
            "one factorisation for rest + constraints"
        );
        let targets: Vec<Vec2> = cons.iter().map(|c| bent[c.vertex as usize]).collect();
        let out = solve(&mut arap, &targets, &bent);
        assert!(
            max_err(&out, &bent) < 1e-9 * mesh_size(&m),
            "{}",
            max_err(&out, &bent)
        );
        let rot = Rotation2::new(0.7);
        let moved: Vec<Vec2> = bent
            .iter()
            .map(|p| rot * p + Vec2::new(2.0, -1.0))
            .collect();
        let targets: Vec<Vec2> = cons.iter().map(|c| moved[c.vertex as usize]).collect();
        let out = solve(&mut arap, &targets, &bent);
        assert!(max_err(&out, &moved) < 1e-3 * mesh_size(&m));
        assert!(matches!(
            arap.set_rest(&bent[1..]),
            Err(ArapError::LengthMismatch { .. })
        ));
        let mut nan = bent.clone();
        nan[3].x = f64::NAN;
        assert!(matches!(
            arap.set_rest(&nan),
            Err(ArapError::NonFinite { index: 3, .. })
        ));
    }

    #[test]
    fn rest_pose_is_unchanged() {
        let m = grid(10, 8);
        let mut arap = Arap::new(&m);
        let rest = m.rest();
        let tol = 1e-9 * mesh_size(&m);
        // No constraints: the anchor alone.
        assert!(max_err(&solve(&mut arap, &[], rest), rest) <= tol);
        let cs = [
            Constraint {
                vertex: 0,
                weight: W_HARD,
            },
            Constraint {
                vertex: 79,
                weight: W_HARD,
            },
            Constraint {
                vertex: 33,
                weight: 100.0,
            },
            Constraint {
                vertex: 34,
                weight: 100.0,
            },
        ];
        arap.set_constraints(&cs).expect("valid");
        let targets: Vec<Vec2> = cs.iter().map(|c| rest[c.vertex as usize]).collect();
        assert!(max_err(&solve(&mut arap, &targets, rest), rest) <= tol);
    }

    #[test]
    fn without_constraints_a_rigidly_moved_anchor_is_reproduced() {
        let m = grid(6, 5);
        let mut arap = Arap::new(&m);
        let rot = Rotation2::new(0.8);
        let anchor: Vec<Vec2> = m
            .rest()
            .iter()
            .map(|p| rot * p + Vec2::new(-3.0, 4.0))
            .collect();
        let out = solve(&mut arap, &[], &anchor);
        assert!(max_err(&out, &anchor) <= 1e-9 * mesh_size(&m));
    }

    fn rigid_case(cols: usize, rows: usize, handles: &[u32], theta: f64, t: Vec2) -> f64 {
        let m = grid(cols, rows);
        let mut arap = Arap::new(&m);
        arap.set_constraints(&hard(handles)).expect("valid");
        let rot = Rotation2::new(theta);
        let moved: Vec<Vec2> = m.rest().iter().map(|p| rot * p + t).collect();
        let targets: Vec<Vec2> = handles.iter().map(|&v| moved[v as usize]).collect();
        let out = solve(&mut arap, &targets, m.rest());
        max_err(&out, &moved) / mesh_size(&m)
    }

    #[test]
    fn rigid_motion_of_the_constraints_moves_the_mesh_rigidly() {
        let e = rigid_case(10, 8, &[0, 9, 70, 79], 0.7, Vec2::new(3.0, -2.0));
        assert!(e <= 1e-3, "relative error {e}");
        let e = rigid_case(10, 8, &[0, 79], 2.5, Vec2::new(-1.0, 0.5));
        assert!(e <= 1e-3, "relative error {e}");
    }

    #[test]
    fn one_moved_constraint_translates_the_mesh() {
        let m = grid(10, 8);
        let mut arap = Arap::new(&m);
        arap.set_constraints(&hard(&[34])).expect("valid");
        let d = Vec2::new(0.7, -1.3);
        let out = solve(&mut arap, &[m.rest()[34] + d], m.rest());
        for (p, r) in out.iter().zip(m.rest()) {
            assert!((p - r - d).norm() <= 1e-3 * d.norm(), "{p} vs {}", r + d);
        }
    }

    #[test]
    fn stretching_is_more_rigid_than_scaling() {
        let m = grid(10, 8);
        let n = m.vertex_count() as u32;
        let mut arap = Arap::new(&m);
        let (a, b) = (0, n - 1);
        arap.set_constraints(&hard(&[a, b])).expect("valid");
        let (ra, rb) = (m.rest()[a as usize], m.rest()[b as usize]);
        let c = (ra + rb) / 2.0;
        let scale = 1.5;
        let targets = [c + (ra - c) * scale, c + (rb - c) * scale];
        let out = solve(&mut arap, &targets, m.rest());
        // The handles reach their targets.
        assert!((out[a as usize] - targets[0]).norm() < 0.05);
        assert!((out[b as usize] - targets[1]).norm() < 0.05);
        let mut sum = 0.0;
        let mut count = 0.0;
        for t in m.triangles() {
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let l0 = (m.rest()[j] - m.rest()[i]).norm();
                let l = (out[j] - out[i]).norm();
                sum += (l / l0 - 1.0).abs();
                count += 1.0;
            }
        }
        let mean = sum / count;
        // Pure scaling changes every edge by 50 %.
        assert!(
            mean < 0.5 * (scale - 1.0),
            "mean relative edge change {mean}"
        );
    }

    /// Dense reference of both steps, assembled from residual functions in the
    /// original vertex order.
    fn dense_reference(
        m: &TriMesh,
        cs: &[Constraint],
        targets: &[Vec2],
        anchor: &[Vec2],
    ) -> (Vec<Vec2>, Vec<Vec2>) {
        let n = m.vertex_count();
        let rest = m.rest();
        // The anchor carried by the weighted rigid fit of constrained anchors to targets.
        let wsum: f64 = cs.iter().map(|c| c.weight).sum();
        let abar = cs
            .iter()
            .map(|c| anchor[c.vertex as usize] * c.weight)
            .sum::<Vec2>()
            / wsum;
        let qbar = cs
            .iter()
            .zip(targets)
            .map(|(c, q)| q * c.weight)
            .sum::<Vec2>()
            / wsum;
        let (mut dot, mut crs) = (0.0, 0.0);
        for (c, q) in cs.iter().zip(targets) {
            let (a, q) = (anchor[c.vertex as usize] - abar, q - qbar);
            dot += c.weight * a.dot(&q);
            crs += c.weight * a.perp(&q);
        }
        let fit = Rotation2::new(crs.atan2(dot));
        let anchor: Vec<Vec2> = anchor.iter().map(|a| fit * (a - abar) + qbar).collect();
        let at = |u: &DVector<f64>, v: usize| Vec2::new(u[2 * v], u[2 * v + 1]);
        let rot90 = Matrix2::new(0.0, -1.0, 1.0, 0.0);
        let mut a1 = DMatrix::<f64>::zeros(2 * n, 2 * n);
        let mut b1 = DVector::<f64>::zeros(2 * n);
        for t in m.triangles() {
            for c in 0..3 {
                let (i, j, k) = (
                    t[c] as usize,
                    t[(c + 1) % 3] as usize,
                    t[(c + 2) % 3] as usize,
                );
                let e = rest[j] - rest[i];
                // Solve [e, R90 e] (x, y)ᵀ = v_k - v_i for the local coordinates.
                let basis = Matrix2::from_columns(&[e, rot90 * e]);
                let xy = basis.lu().solve(&(rest[k] - rest[i])).expect("invertible");
                let residual = |u: &DVector<f64>| {
                    let (vi, vj, vk) = (at(u, i), at(u, j), at(u, k));
                    vk - vi - (vj - vi) * xy.x - rot90 * (vj - vi) * xy.y
                };
                let mut jac = DMatrix::<f64>::zeros(2, 2 * n);
                for col in 0..2 * n {
                    let mut unit = DVector::zeros(2 * n);
                    unit[col] = 1.0;
                    let r = residual(&unit);
                    jac[(0, col)] = r.x;
                    jac[(1, col)] = r.y;
                }
                a1 += jac.transpose() * &jac;
            }
        }
        let mut lap = DMatrix::<f64>::zeros(n, n);
        for v in 0..n {
            for d in 0..2 {
                a1[(2 * v + d, 2 * v + d)] += ANCHOR_WEIGHT;
                b1[2 * v + d] += ANCHOR_WEIGHT * anchor[v][d];
            }
            lap[(v, v)] += ANCHOR_WEIGHT;
        }
        for (c, q) in cs.iter().zip(targets) {
            let v = c.vertex as usize;
            for d in 0..2 {
                a1[(2 * v + d, 2 * v + d)] += c.weight;
                b1[2 * v + d] += c.weight * q[d];
            }
            lap[(v, v)] += c.weight;
        }
        let u1 = a1.cholesky().expect("spd").solve(&b1);
        let step1: Vec<Vec2> = (0..n).map(|v| at(&u1, v)).collect();

        let mut bx = DVector::<f64>::zeros(n);
        let mut by = DVector::<f64>::zeros(n);
        for v in 0..n {
            bx[v] += ANCHOR_WEIGHT * anchor[v].x;
            by[v] += ANCHOR_WEIGHT * anchor[v].y;
        }
        for (c, q) in cs.iter().zip(targets) {
            bx[c.vertex as usize] += c.weight * q.x;
            by[c.vertex as usize] += c.weight * q.y;
        }
        for t in m.triangles() {
            let p = t.map(|v| rest[v as usize]);
            let q = t.map(|v| step1[v as usize]);
            let (pc, qc) = ((p[0] + p[1] + p[2]) / 3.0, (q[0] + q[1] + q[2]) / 3.0);
            let (mut dot, mut crs) = (0.0, 0.0);
            for c in 0..3 {
                let (a, b) = (p[c] - pc, q[c] - qc);
                dot += a.dot(&b);
                crs += a.x * b.y - a.y * b.x;
            }
            let rot = Rotation2::new(crs.atan2(dot));
            for c in 0..3 {
                let (i, j) = (t[c] as usize, t[(c + 1) % 3] as usize);
                let f = rot * (rest[j] - rest[i]);
                lap[(i, i)] += 1.0;
                lap[(j, j)] += 1.0;
                lap[(i, j)] -= 1.0;
                lap[(j, i)] -= 1.0;
                bx[j] += f.x;
                by[j] += f.y;
                bx[i] -= f.x;
                by[i] -= f.y;
            }
        }
        let chol = lap.cholesky().expect("spd");
        let (x, y) = (chol.solve(&bx), chol.solve(&by));
        (step1, (0..n).map(|v| Vec2::new(x[v], y[v])).collect())
    }

    #[test]
    fn sparse_solves_equal_dense_solves() {
        let m = grid(6, 5);
        let n = m.vertex_count();
        let mut rng = SplitMix64::new(42);
        let cs = [
            Constraint {
                vertex: 0,
                weight: W_HARD,
            },
            Constraint {
                vertex: 29,
                weight: W_HARD,
            },
            Constraint {
                vertex: 14,
                weight: 100.0,
            },
            Constraint {
                vertex: 8,
                weight: 3.0,
            },
        ];
        let targets: Vec<Vec2> = cs
            .iter()
            .map(|c| m.rest()[c.vertex as usize] + Vec2::new(rng.unit() - 0.5, rng.unit() - 0.5))
            .collect();
        let anchor: Vec<Vec2> = m
            .rest()
            .iter()
            .map(|p| p + 0.1 * Vec2::new(rng.unit() - 0.5, rng.unit() - 0.5))
            .collect();
        let mut arap = Arap::new(&m);
        arap.set_constraints(&cs).expect("valid");
        let out = solve(&mut arap, &targets, &anchor);
        let step1: Vec<Vec2> = (0..n)
            .map(|v| {
                let p = 2 * arap.inv[v] as usize;
                Vec2::new(arap.rhs1[p], arap.rhs1[p + 1])
            })
            .collect();
        let (d1, d2) = dense_reference(&m, &cs, &targets, &anchor);
        let tol = 1e-9 * mesh_size(&m);
        assert!(
            max_err(&step1, &d1) <= tol,
            "step 1: {}",
            max_err(&step1, &d1)
        );
        assert!(max_err(&out, &d2) <= tol, "step 2: {}", max_err(&out, &d2));
        // The envelope factor reproduces the assembled matrix entries.
        let mut dense_check = Arap::new(&m);
        dense_check.fac1.vals.copy_from_slice(&dense_check.base1);
        let (p0, p1) = (dense_check.inv[0] as usize, dense_check.inv[1] as usize);
        assert!(
            dense_check.fac1.get(2 * p1, 2 * p0) != 0.0,
            "edge 0-1 couples x0 and x1"
        );
    }

    /// Point constraints at the centroids of a few triangles.
    fn centroid_points(m: &TriMesh, tris: &[usize], weight: f64) -> Vec<PointConstraint> {
        tris.iter()
            .map(|&t| PointConstraint {
                corners: m.triangles()[t],
                bary: [1.0 / 3.0; 3],
                weight,
            })
            .collect()
    }

    #[test]
    fn point_constraints_inside_triangles_move_the_mesh_rigidly() {
        // No vertex is constrained: only three points inside triangles far apart.
        let m = grid(10, 8);
        let last = m.triangles().len() - 1;
        let pts = centroid_points(&m, &[0, last / 2, last], 100.0);
        let mut arap = Arap::new(&m);
        arap.set_constraints_and_points(&[], &pts).expect("valid");
        let (rot, t) = (Rotation2::new(0.9), Vec2::new(-2.0, 1.5));
        let moved: Vec<Vec2> = m.rest().iter().map(|p| rot * p + t).collect();
        let targets: Vec<Vec2> = pts.iter().map(|p| p.position(&moved)).collect();
        let out = solve(&mut arap, &targets, m.rest());
        let e = max_err(&out, &moved) / mesh_size(&m);
        assert!(e <= 1e-3, "relative error {e}");
        for (p, q) in pts.iter().zip(&targets) {
            assert!((p.position(&out) - q).norm() < 1e-3);
        }
    }

    #[test]
    fn a_point_constraint_on_a_corner_acts_as_a_vertex_constraint() {
        let m = grid(6, 5);
        let t = m.triangles()[7];
        let (v, target) = (t[1], Vec2::new(9.0, 4.0));
        let mut by_vertex = Arap::new(&m);
        by_vertex
            .set_constraints(&[Constraint {
                vertex: v,
                weight: 50.0,
            }])
            .expect("valid");
        let a = solve(&mut by_vertex, &[target], m.rest());
        let mut by_point = Arap::new(&m);
        let corner = PointConstraint {
            corners: t,
            bary: [0.0, 1.0, 0.0],
            weight: 50.0,
        };
        by_point
            .set_constraints_and_points(&[], &[corner])
            .expect("valid");
        let b = solve(&mut by_point, &[target], m.rest());
        assert!(max_err(&a, &b) < 1e-9, "{}", max_err(&a, &b));
        // Mixed: the vertex targets come first, then the points'.
        let mut both = Arap::new(&m);
        let far = Constraint {
            vertex: 0,
            weight: 50.0,
        };
        both.set_constraints_and_points(&[far], &[corner])
            .expect("valid");
        let c = solve(&mut both, &[m.rest()[0], target], m.rest());
        let mut two = Arap::new(&m);
        let mut at_v = far;
        at_v.vertex = v;
        two.set_constraints(&[far, at_v]).expect("valid");
        let d = solve(&mut two, &[m.rest()[0], target], m.rest());
        assert!(max_err(&c, &d) < 1e-9, "{}", max_err(&c, &d));
        assert!(matches!(
            solve_err(&mut both, &[target], m.rest()),
            ArapError::LengthMismatch { expected: 2, .. }
        ));
    }

    fn solve_err(arap: &mut Arap, targets: &[Vec2], anchor: &[Vec2]) -> ArapError {
        let mut out = vec![Vec2::zeros(); arap.vertex_count()];
        arap.solve(targets, anchor, &mut out).unwrap_err()
    }

    #[test]
    fn bad_point_constraints_are_refused_and_same_points_do_not_refactor() {
        let m = grid(5, 4);
        let mut arap = Arap::new(&m);
        let pts = centroid_points(&m, &[0, 5], 100.0);
        arap.set_constraints_and_points(&[], &pts).expect("valid");
        assert_eq!(arap.factorizations(), 2);
        arap.set_constraints_and_points(&[], &pts).expect("valid");
        assert_eq!(arap.factorizations(), 2, "same points");
        // Opposite corners of the grid share no triangle.
        let apart = PointConstraint {
            corners: [0, 19, 1],
            bary: [0.2, 0.3, 0.5],
            weight: 1.0,
        };
        assert_eq!(
            arap.set_constraints_and_points(&[], &[pts[0], apart]),
            Err(ArapError::PointNotInTriangle { index: 1 })
        );
        let outside = PointConstraint {
            corners: [0, 1, 99],
            ..apart
        };
        assert_eq!(
            arap.set_constraints_and_points(&[], &[outside]),
            Err(ArapError::PointNotInTriangle { index: 0 })
        );
        for bad in [
            PointConstraint {
                weight: 0.0,
                ..pts[0]
            },
            PointConstraint {
                bary: [f64::NAN, 0.5, 0.5],
                ..pts[0]
            },
        ] {
            assert_eq!(
                arap.set_constraints_and_points(&[], &[bad]),
                Err(ArapError::BadPoint { index: 0 })
            );
        }
        assert_eq!(arap.points(), pts.as_slice(), "state unchanged");
        assert_eq!(arap.factorizations(), 2);
        arap.set_constraints(&[]).expect("valid");
        assert!(arap.points().is_empty());
        assert_eq!(arap.factorizations(), 3);
    }

    #[test]
    fn identical_set_does_not_refactor() {
        let m = grid(5, 4);
        let mut arap = Arap::new(&m);
        assert_eq!(arap.factorizations(), 1);
        let cs = hard(&[0, 19, 7]);
        arap.set_constraints(&cs).expect("valid");
        assert_eq!(arap.factorizations(), 2);
        arap.set_constraints(&cs).expect("valid");
        assert_eq!(arap.factorizations(), 2, "identical set");
        let reordered = hard(&[19, 7, 0]);
        arap.set_constraints(&reordered).expect("valid");
        assert_eq!(arap.factorizations(), 2, "same matrix");
        assert_eq!(
            arap.constraints(),
            reordered.as_slice(),
            "list still updated"
        );
        let mut changed = reordered.clone();
        changed[1].weight = 10.0;
        arap.set_constraints(&changed).expect("valid");
        assert_eq!(arap.factorizations(), 3);
        arap.set_constraints(&[]).expect("valid");
        assert_eq!(arap.factorizations(), 4);
    }

    #[test]
    fn bad_inputs_are_errors_and_leave_the_state() {
        let m = grid(5, 4);
        let mut arap = Arap::new(&m);
        let cs = hard(&[0, 19]);
        arap.set_constraints(&cs).expect("valid");
        assert_eq!(
            arap.set_constraints(&[Constraint {
                vertex: 20,
                weight: 1.0
            }]),
            Err(ArapError::VertexOutOfRange {
                vertex: 20,
                vertex_count: 20
            })
        );
        for weight in [0.0, -1.0, f64::INFINITY, 2.0 * MAX_CONSTRAINT_WEIGHT] {
            assert_eq!(
                arap.set_constraints(&[Constraint { vertex: 3, weight }]),
                Err(ArapError::BadWeight { vertex: 3, weight })
            );
        }
        assert!(matches!(
            arap.set_constraints(&[Constraint {
                vertex: 3,
                weight: f64::NAN
            }]),
            Err(ArapError::BadWeight { vertex: 3, .. })
        ));
        assert_eq!(arap.constraints(), cs.as_slice());
        assert_eq!(arap.factorizations(), 2);

        let rest = m.rest();
        let t = [rest[0], rest[19]];
        let mut out = vec![Vec2::zeros(); 20];
        assert_eq!(
            arap.solve(&t[..1], rest, &mut out),
            Err(ArapError::LengthMismatch {
                buffer: ArapBuffer::Targets,
                expected: 2,
                got: 1
            })
        );
        assert_eq!(
            arap.solve(&t, &rest[..3], &mut out),
            Err(ArapError::LengthMismatch {
                buffer: ArapBuffer::Anchor,
                expected: 20,
                got: 3
            })
        );
        assert_eq!(
            arap.solve(&t, rest, &mut out[..19]),
            Err(ArapError::LengthMismatch {
                buffer: ArapBuffer::Out,
                expected: 20,
                got: 19
            })
        );
        let nan = [rest[0], Vec2::new(f64::NAN, 0.0)];
        assert_eq!(
            arap.solve(&nan, rest, &mut out),
            Err(ArapError::NonFinite {
                buffer: ArapBuffer::Targets,
                index: 1
            })
        );
        let mut bad_anchor = rest.to_vec();
        bad_anchor[5].y = f64::INFINITY;
        assert_eq!(
            arap.solve(&t, &bad_anchor, &mut out),
            Err(ArapError::NonFinite {
                buffer: ArapBuffer::Anchor,
                index: 5
            })
        );
        assert!(
            out.iter().all(|p| *p == Vec2::zeros()),
            "nothing written on error"
        );
        arap.solve(&t, rest, &mut out).expect("still usable");
    }

    #[test]
    fn solve_reuses_its_workspaces() {
        let m = grid(10, 8);
        let mut arap = Arap::new(&m);
        arap.set_constraints(&hard(&[0, 79])).expect("valid");
        let ptrs = (
            arap.rhs1.as_ptr(),
            arap.rhs2.as_ptr(),
            arap.fac1.vals.as_ptr(),
        );
        let t = [m.rest()[0], m.rest()[79] + Vec2::new(1.0, 0.0)];
        let mut out = vec![Vec2::zeros(); 80];
        for _ in 0..3 {
            arap.solve(&t, m.rest(), &mut out).expect("solve");
        }
        assert_eq!(
            ptrs,
            (
                arap.rhs1.as_ptr(),
                arap.rhs2.as_ptr(),
                arap.fac1.vals.as_ptr()
            )
        );
    }

    /// One piece of `two_grids` as a mesh of its own: vertices `range`, renumbered.
    fn piece_alone(m: &TriMesh, range: std::ops::Range<u32>) -> TriMesh {
        let rest = m.rest()[range.start as usize..range.end as usize].to_vec();
        let tris = m
            .triangles()
            .iter()
            .filter(|t| range.contains(&t[0]))
            .map(|t| t.map(|v| v - range.start))
            .collect();
        TriMesh::from_triangles(rest, tris).expect("a disc")
    }

    #[test]
    fn a_piece_without_constraints_stays_where_it_is() {
        let m = crate::crowd::mesh::trimesh::two_grids(1.0);
        let mut arap = Arap::new(&m);
        let rest = m.rest();
        let tol = 1e-9 * mesh_size(&m);
        // No constraints anywhere: nothing moves (each piece's anchor alone).
        assert!(max_err(&solve(&mut arap, &[], rest), rest) <= tol);
        // Stretch the left piece (vertices 0..12) between two handles.
        let cs = hard(&[0, 11]);
        arap.set_constraints(&cs).expect("factorises");
        let targets = [rest[0], rest[11] + Vec2::new(1.0, 0.5)];
        let out = solve(&mut arap, &targets, rest);
        assert!((out[11] - targets[1]).norm() < 1e-2, "{:?}", out[11]);
        assert!(max_err(&out[12..], &rest[12..]) <= tol, "right piece moved");
        // One handle drags the left piece; the right one stays.
        arap.set_constraints(&hard(&[5])).expect("factorises");
        let d = Vec2::new(-2.0, 0.3);
        let out = solve(&mut arap, &[rest[5] + d], rest);
        for (p, r) in out[..12].iter().zip(&rest[..12]) {
            assert!((p - r - d).norm() <= 1e-3 * d.norm());
        }
        assert!(max_err(&out[12..], &rest[12..]) <= tol);
    }

    /// The two-piece system is block diagonal: solving it equals solving each piece
    /// as a mesh of its own, with each piece's own constraints (vertex and point).
    #[test]
    fn two_pieces_solve_as_two_separate_meshes() {
        let m = crate::crowd::mesh::trimesh::two_grids(0.5);
        let (left, right) = (piece_alone(&m, 0..12), piece_alone(&m, 12..32));
        let mut rng = SplitMix64::new(9);
        let mut jitter = |p: Vec2, s: f64| p + s * Vec2::new(rng.unit() - 0.5, rng.unit() - 0.5);
        let anchor: Vec<Vec2> = m.rest().iter().map(|&p| jitter(p, 0.05)).collect();
        let cs = [
            Constraint {
                vertex: 2,
                weight: W_HARD,
            },
            Constraint {
                vertex: 9,
                weight: 30.0,
            },
            Constraint {
                vertex: 13,
                weight: W_HARD,
            },
            Constraint {
                vertex: 31,
                weight: W_HARD,
            },
        ];
        let pt = PointConstraint {
            corners: m.triangles()[20],
            bary: [0.2, 0.3, 0.5],
            weight: 100.0,
        };
        assert!(
            pt.corners.iter().all(|&v| v >= 12),
            "a right-piece triangle"
        );
        let mut targets: Vec<Vec2> = cs
            .iter()
            .map(|c| jitter(m.rest()[c.vertex as usize], 0.8))
            .collect();
        targets.push(jitter(pt.position(m.rest()), 0.8));
        let mut both = Arap::new(&m);
        both.set_constraints_and_points(&cs, &[pt])
            .expect("factorises");
        let out = solve(&mut both, &targets, &anchor);

        let mut a = Arap::new(&left);
        a.set_constraints(&cs[..2]).expect("factorises");
        let out_l = solve(&mut a, &targets[..2], &anchor[..12]);
        let shift = |c: &Constraint| Constraint {
            vertex: c.vertex - 12,
            ..*c
        };
        let mut b = Arap::new(&right);
        b.set_constraints_and_points(
            &[shift(&cs[2]), shift(&cs[3])],
            &[PointConstraint {
                corners: pt.corners.map(|v| v - 12),
                ..pt
            }],
        )
        .expect("factorises");
        let out_r = solve(&mut b, &targets[2..], &anchor[12..]);
        let tol = 1e-9 * mesh_size(&m);
        assert!(
            max_err(&out[..12], &out_l) <= tol,
            "{}",
            max_err(&out[..12], &out_l)
        );
        assert!(
            max_err(&out[12..], &out_r) <= tol,
            "{}",
            max_err(&out[12..], &out_r)
        );
    }

    #[test]
    fn each_piece_follows_its_own_rigid_motion() {
        let m = crate::crowd::mesh::trimesh::two_grids(1.0);
        let mut arap = Arap::new(&m);
        let cs = hard(&[0, 11, 12, 31]);
        arap.set_constraints(&cs).expect("factorises");
        let (rl, tl) = (Rotation2::new(0.4), Vec2::new(-1.0, 2.0));
        let (rr, tr) = (Rotation2::new(-1.1), Vec2::new(3.0, 0.5));
        let moved: Vec<Vec2> = m
            .rest()
            .iter()
            .enumerate()
            .map(|(v, p)| if v < 12 { rl * p + tl } else { rr * p + tr })
            .collect();
        let targets: Vec<Vec2> = cs.iter().map(|c| moved[c.vertex as usize]).collect();
        let out = solve(&mut arap, &targets, m.rest());
        let e = max_err(&out, &moved) / mesh_size(&m);
        assert!(e <= 1e-3, "relative error {e}");
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 32,
            rng_seed: RngSeed::Fixed(0x6172_6170),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn prop_rest_pose_is_fixed(cols in 2usize..9, rows in 2usize..9,
                                   picks in proptest::collection::vec((0usize..1000, 0.5f64..2000.0), 0..6)) {
            let m = grid(cols, rows);
            let n = m.vertex_count();
            let cs: Vec<Constraint> = picks.iter().map(|&(v, w)| Constraint { vertex: (v % n) as u32, weight: w }).collect();
            let mut arap = Arap::new(&m);
            arap.set_constraints(&cs).expect("valid");
            let targets: Vec<Vec2> = cs.iter().map(|c| m.rest()[c.vertex as usize]).collect();
            let out = solve(&mut arap, &targets, m.rest());
            prop_assert!(max_err(&out, m.rest()) <= 1e-9 * mesh_size(&m));
        }

        #[test]
        fn prop_rigid_motion(theta in -3.1f64..3.1, tx in -5.0f64..5.0, ty in -5.0f64..5.0,
                             a in 0u32..80, b in 0u32..80) {
            prop_assume!(a != b);
            let e = rigid_case(10, 8, &[a, b], theta, Vec2::new(tx, ty));
            prop_assert!(e <= 1e-3, "relative error {}", e);
        }
    }
}
