//! Goal points on the crowd's mesh: a triangle and barycentric coordinates each
//! (mesh-formation-control section 4.1), so the number of agents is independent of the
//! number of vertices. [`sample_goals`] spreads `n` samples evenly over the mesh
//! (farthest-point sampling from a dense candidate set, then Lloyd relaxation);
//! [`goal_positions`] maps them through any pose of the mesh. On a mesh of several
//! pieces each piece gets its share of the samples in proportion to its area and is
//! sampled on its own, so no sample sits between pieces.

use super::trimesh::{dist2, tri_edges, TriMesh};
use crate::geom::{cross, Vec2};
use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

/// Candidate points per requested goal sample in [`sample_goals`] (density of the
/// candidate set that farthest-point sampling chooses from; dimensionless).
pub const GOAL_CANDIDATES_PER_SAMPLE: f64 = 16.0;

/// Lloyd relaxation sweeps applied after farthest-point sampling in [`sample_goals`].
pub const GOAL_LLOYD_ITERATIONS: usize = 6;

/// Candidates visited by the farthest-point picks between two checks of the
/// cancellation check of [`sample_goals_cancellable`].
const VISITS_PER_CHECK: usize = 1 << 16;

/// Candidates assigned to their nearest sample between two checks of the
/// cancellation check in a Lloyd sweep of [`sample_goals_cancellable`].
const LLOYD_CANDIDATES_PER_CHECK: usize = 4096;

/// Tolerance on barycentric coordinates when deciding that a candidate point lies in a
/// triangle (dimensionless; points on a shared edge may land in either triangle).
const BARY_EPS: f64 = 1e-12;

/// A goal point on the mesh: a triangle and barycentric coordinates in it
/// (mesh-formation-control section 4.1: "With a triangle ID and appropriate barycentric
/// coordinates an arbitrary number of goal points can be produced").
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GoalSample {
    /// Index into [`TriMesh::triangles`].
    pub tri: u32,
    /// Barycentric weights of the triangle's three corners (non-negative, sum 1).
    pub bary: [f64; 3],
}

/// A candidate point for [`sample_goals`].
#[derive(Copy, Clone)]
struct Candidate {
    p: Vec2,
    sample: GoalSample,
}

/// Max-heap entry: squared distance, then the lower index first on ties.
#[derive(Copy, Clone, PartialEq)]
struct HeapEntry {
    d2: f64,
    idx: u32,
}

impl Eq for HeapEntry {}

impl PartialOrd for HeapEntry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for HeapEntry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.d2
            .total_cmp(&other.d2)
            .then_with(|| other.idx.cmp(&self.idx))
    }
}

/// Exactly `n` goal samples spread evenly over the rest mesh.
///
/// When `n` equals the vertex count the samples are exactly the vertices (sample `i` is
/// vertex `i`, one-hot barycentric coordinates). Otherwise:
///
/// 1. a dense candidate set is built: the vertices, the outline subdivided, and a
///    hexagonal lattice inside every triangle, about
///    [`GOAL_CANDIDATES_PER_SAMPLE`]` · n` points in proportion to area;
/// 2. `n` candidates are picked by farthest-point sampling (each new sample is the
///    candidate farthest from all chosen so far, starting at the first outline vertex),
///    which guarantees both packing and covering: with `r` the distance of the last
///    pick to the others, all picks are at least `r` apart and every candidate is within
///    `r` of a pick;
/// 3. [`GOAL_LLOYD_ITERATIONS`] sweeps of discrete Lloyd relaxation (each sample moves to
///    the centroid of the candidates nearest to it) even out the spacing, so every
///    sample stands for about the same area, and the outer row moves off the outline
///    (about 0.3 spacings inwards), as agents filling the formation would stand.
///
/// On a mesh of several pieces, the `n` samples are first shared out in proportion
/// to the pieces' rest areas (largest remainders, ties to the lower piece), then
/// steps 2–3 run on each piece's candidates alone, starting at its first outline
/// vertex; the samples come piece by piece.
///
/// Measured on a 12 m × 8 m grid mesh for n = 50, 100, 1000: nearest-neighbour distances
/// between `0.69` and `1.28 · sqrt(area / n)` (mean about `0.95`, standard deviation
/// about `0.08–0.10`).
///
/// # Formula
/// Greedy farthest-point (Gonzalez) sampling followed by Lloyd's algorithm on the
/// candidate density; candidate lattice spacing `δ = sqrt(2 A / (√3 K n))`,
/// `K` = [`GOAL_CANDIDATES_PER_SAMPLE`].
///
/// # Complexity
/// About O(K n (log(K n) + L)) time for `L` Lloyd sweeps and O(K n) memory, with bucket
/// grids for the nearest-sample queries and a lazy max-heap for the selection (timed
/// inside `formation_switch/prepare` of `benches/control_tick.rs`). Not for the
/// per-frame path.
///
/// # Errors
/// None. Deterministic for given inputs. A mesh with no triangles gives an empty vector;
/// a mesh that fails [`TriMesh::sanity_check`] gives `n` in-range but otherwise
/// unspecified samples.
///
/// ```
/// use crowdtouch::crowd::mesh::{sample_goals, TriMesh};
/// use crowdtouch::geom::Rect;
/// let m = TriMesh::grid(Rect { min: [0.0, 0.0], max: [10.0, 10.0] }, 11, 11);
/// let s = sample_goals(&m, 37);
/// assert_eq!(s.len(), 37);
/// assert!(s.iter().all(|g| (g.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12));
/// ```
pub fn sample_goals(mesh: &TriMesh, n: usize) -> Vec<GoalSample> {
    sample_goals_cancellable(mesh, n, &|| false).unwrap_or_default()
}

/// [`sample_goals`] that gives up (`None`) when `cancelled` returns `true`: it is
/// called every 65,536 candidates laid out or visited by the farthest-point picks,
/// once the candidates are laid out, and every 4,096 candidates of a Lloyd sweep
/// (well under a millisecond of work apart in a release build), and not again once
/// it said so. A check that never
/// fires gives exactly [`sample_goals`]' samples.
///
/// ```
/// use crowdtouch::crowd::mesh::{sample_goals, sample_goals_cancellable, TriMesh};
/// use crowdtouch::geom::Rect;
/// let m = TriMesh::grid(Rect { min: [0.0, 0.0], max: [10.0, 10.0] }, 11, 11);
/// assert_eq!(sample_goals_cancellable(&m, 500, &|| false), Some(sample_goals(&m, 500)));
/// assert_eq!(sample_goals_cancellable(&m, 500, &|| true), None);
/// ```
pub fn sample_goals_cancellable(
    mesh: &TriMesh,
    n: usize,
    cancelled: &dyn Fn() -> bool,
) -> Option<Vec<GoalSample>> {
    if n == 0 || mesh.triangles().is_empty() {
        return Some(Vec::new());
    }
    let incident = mesh.incident_corners();
    let vertex_sample = |v: usize| match incident.get(v).copied().flatten() {
        Some((tri, corner)) => {
            let mut bary = [0.0; 3];
            bary[corner] = 1.0;
            GoalSample { tri, bary }
        }
        None => GoalSample {
            tri: 0,
            bary: [1.0 / 3.0; 3],
        },
    };
    if n == mesh.vertex_count() {
        return Some((0..n).map(vertex_sample).collect());
    }
    let area = mesh.area();
    if !(area.is_finite() && area > 0.0) || mesh.sanity_check().is_err() {
        // Unusable geometry: stay in range and deterministic.
        let t = mesh.triangles().len();
        return Some(
            (0..n)
                .map(|i| GoalSample {
                    tri: (i % t) as u32,
                    bary: [1.0 / 3.0; 3],
                })
                .collect(),
        );
    }
    let counts = share_by_area(mesh, n);
    let mut delta = (2.0 * area / (3f64.sqrt() * GOAL_CANDIDATES_PER_SAMPLE * n as f64)).sqrt();
    'refine: loop {
        let candidates = goal_candidates(mesh, &incident, delta, cancelled)?;
        if mesh.piece_count() == 1 {
            // Vertices come first among the candidates: start at the first outline
            // vertex.
            let first = mesh.outline().first().map_or(0, |&v| v as usize);
            if let Some(chosen) = farthest_point_sampling(&candidates, n, first, cancelled)? {
                return lloyd_relax(mesh, &candidates, &chosen, GOAL_LLOYD_ITERATIONS, cancelled);
            }
            // Too few distinct candidates (very thin mesh): refine the lattice.
            delta *= 0.5;
            continue;
        }
        let piece_of = mesh.piece_of_vertex();
        let mut samples = Vec::with_capacity(n);
        for (piece, &count) in counts.iter().enumerate() {
            if count == 0 {
                continue;
            }
            let in_piece = |c: &&Candidate| {
                let t = mesh.triangles()[c.sample.tri as usize];
                piece_of[t[0] as usize] as usize == piece
            };
            let own: Vec<Candidate> = candidates.iter().filter(in_piece).copied().collect();
            // The piece's vertices come first among its candidates, in vertex order.
            let start = mesh.outlines()[piece].first().copied().unwrap_or(0);
            let first = mesh.components()[piece]
                .iter()
                .position(|&v| v == start)
                .unwrap_or(0);
            let Some(chosen) = farthest_point_sampling(&own, count, first, cancelled)? else {
                delta *= 0.5;
                continue 'refine;
            };
            samples.extend(lloyd_relax(
                mesh,
                &own,
                &chosen,
                GOAL_LLOYD_ITERATIONS,
                cancelled,
            )?);
        }
        return Some(samples);
    }
}

/// `n` shared out over the pieces of `mesh` in proportion to their rest areas:
/// largest remainders (Hamilton), ties to the lower piece. Sums to `n`.
fn share_by_area(mesh: &TriMesh, n: usize) -> Vec<usize> {
    let pieces = mesh.piece_count();
    let mut area = vec![0.0; pieces];
    let (rest, piece_of) = (mesh.rest(), mesh.piece_of_vertex());
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|v| rest[v as usize]);
        if let Some(s) = area.get_mut(piece_of[t[0] as usize] as usize) {
            *s += 0.5 * cross(b - a, c - a);
        }
    }
    let total: f64 = area.iter().sum();
    let quota: Vec<f64> = area.iter().map(|a| n as f64 * a / total).collect();
    let mut counts: Vec<usize> = quota.iter().map(|q| q.floor() as usize).collect();
    let mut order: Vec<usize> = (0..pieces).collect();
    order.sort_by(|&i, &j| {
        let (fi, fj) = (quota[i] - quota[i].floor(), quota[j] - quota[j].floor());
        fj.total_cmp(&fi).then(i.cmp(&j))
    });
    let missing = n.saturating_sub(counts.iter().sum());
    for &i in order.iter().cycle().take(missing) {
        counts[i] += 1;
    }
    counts
}

/// Candidate set for [`sample_goals`]: the vertices, every piece's outline subdivided at about
/// `delta`, and a hexagonal lattice of spacing `delta` clipped to each triangle.
/// `None` when `cancelled` said so (checked every [`VISITS_PER_CHECK`] lattice
/// points tried, and at the end).
fn goal_candidates(
    mesh: &TriMesh,
    incident: &[Option<(u32, usize)>],
    delta: f64,
    cancelled: &dyn Fn() -> bool,
) -> Option<Vec<Candidate>> {
    let rest = mesh.rest();
    let mut out = Vec::new();
    for (v, inc) in incident.iter().enumerate() {
        if let Some((tri, corner)) = *inc {
            let mut bary = [0.0; 3];
            bary[corner] = 1.0;
            out.push(Candidate {
                p: rest[v],
                sample: GoalSample { tri, bary },
            });
        }
    }
    // Outline edges subdivided; each boundary edge belongs to exactly one triangle.
    let mut edge_tri: HashMap<(u32, u32), (u32, usize)> = HashMap::new();
    for (ti, t) in mesh.triangles().iter().enumerate() {
        for (k, e) in tri_edges(t).into_iter().enumerate() {
            edge_tri.insert(e, (ti as u32, k));
        }
    }
    for outline in mesh.outlines() {
        let m = outline.len();
        for i in 0..m {
            let (a, b) = (outline[i], outline[(i + 1) % m]);
            let Some(&(tri, k)) = edge_tri.get(&(a, b)) else {
                continue;
            };
            let len = (rest[b as usize] - rest[a as usize]).norm();
            let steps = (len / delta).ceil().max(1.0) as usize;
            for s in 1..steps {
                let t = s as f64 / steps as f64;
                let mut bary = [0.0; 3];
                bary[k] = 1.0 - t;
                bary[(k + 1) % 3] = t;
                out.push(Candidate {
                    p: rest[a as usize] * (1.0 - t) + rest[b as usize] * t,
                    sample: GoalSample { tri, bary },
                });
            }
        }
    }
    // Hexagonal lattice, offset half a step from the bounding box so that it does not
    // duplicate the straight parts of the outline.
    let (mut lo, mut hi) = (rest[0], rest[0]);
    for p in rest {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let dy = delta * 3f64.sqrt() * 0.5;
    let origin = lo + Vec2::new(0.25 * delta, 0.5 * dy);
    let mut tried = 0usize;
    for (ti, t) in mesh.triangles().iter().enumerate() {
        if tried >= VISITS_PER_CHECK {
            tried = 0;
            if cancelled() {
                return None;
            }
        }
        let [a, b, c] = t.map(|v| rest[v as usize]);
        let det = cross(b - a, c - a);
        if det <= 0.0 {
            continue;
        }
        let tlo = a.inf(&b).inf(&c);
        let thi = a.sup(&b).sup(&c);
        let j0 = ((tlo.y - origin.y) / dy).ceil() as i64;
        let j1 = ((thi.y - origin.y) / dy).floor() as i64;
        for j in j0..=j1 {
            let y = origin.y + j as f64 * dy;
            let shift = if j.rem_euclid(2) == 1 {
                0.5 * delta
            } else {
                0.0
            };
            let i0 = ((tlo.x - origin.x - shift) / delta).ceil() as i64;
            let i1 = ((thi.x - origin.x - shift) / delta).floor() as i64;
            tried += (i1 - i0 + 1).max(0) as usize;
            for i in i0..=i1 {
                let p = Vec2::new(origin.x + shift + i as f64 * delta, y);
                // λ_a = area(p, b, c) / area(a, b, c), and cyclically.
                let bary = [
                    cross(c - b, p - b) / det,
                    cross(a - c, p - c) / det,
                    cross(b - a, p - a) / det,
                ];
                if bary.iter().all(|&w| w >= -BARY_EPS) {
                    let clamped = bary.map(|w| w.max(0.0));
                    let s: f64 = clamped.iter().sum();
                    out.push(Candidate {
                        p,
                        sample: GoalSample {
                            tri: ti as u32,
                            bary: clamped.map(|w| w / s),
                        },
                    });
                }
            }
        }
    }
    (!cancelled()).then_some(out)
}

/// A uniform bucket grid over a point set (counting-sorted indices per cell).
struct BucketGrid {
    lo: Vec2,
    cell: f64,
    width: usize,
    height: usize,
    cell_start: Vec<u32>,
    items: Vec<u32>,
}

impl BucketGrid {
    /// Grid over `points` with about `per_cell` points per cell on average.
    fn new(points: impl Iterator<Item = Vec2> + Clone, per_cell: f64) -> BucketGrid {
        let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
        let mut count = 0usize;
        for p in points.clone() {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
            count += 1;
        }
        if count == 0 {
            lo = Vec2::zeros();
            hi = Vec2::zeros();
        }
        let ext = hi - lo;
        let cell = (per_cell * ext.x * ext.y / count.max(1) as f64)
            .sqrt()
            .max(ext.x.max(ext.y) / 4096.0)
            .max(f64::MIN_POSITIVE);
        let width = ((ext.x / cell).floor() as usize + 1).min(4097);
        let height = ((ext.y / cell).floor() as usize + 1).min(4097);
        let mut grid = BucketGrid {
            lo,
            cell,
            width,
            height,
            cell_start: vec![0; width * height + 1],
            items: vec![0; count],
        };
        for p in points.clone() {
            let k = grid.cell_index(p);
            grid.cell_start[k + 1] += 1;
        }
        for i in 0..width * height {
            grid.cell_start[i + 1] += grid.cell_start[i];
        }
        let mut fill = grid.cell_start.clone();
        for (i, p) in points.enumerate() {
            let k = grid.cell_index(p);
            grid.items[fill[k] as usize] = i as u32;
            fill[k] += 1;
        }
        grid
    }

    /// Cell coordinates of `p`, clamped to the grid.
    fn cell_of(&self, p: Vec2) -> (usize, usize) {
        let cx = (((p.x - self.lo.x) / self.cell).floor().max(0.0) as usize).min(self.width - 1);
        let cy = (((p.y - self.lo.y) / self.cell).floor().max(0.0) as usize).min(self.height - 1);
        (cx, cy)
    }

    fn cell_index(&self, p: Vec2) -> usize {
        let (cx, cy) = self.cell_of(p);
        cy * self.width + cx
    }

    /// Indices of the points in cell `(cx, cy)`.
    fn cell(&self, cx: usize, cy: usize) -> &[u32] {
        let k = cy * self.width + cx;
        &self.items[self.cell_start[k] as usize..self.cell_start[k + 1] as usize]
    }

    /// Index of the point of `points` (the set the grid was built over) nearest to `q`,
    /// lowest index on ties; `None` if the set is empty.
    fn nearest(&self, points: &[Vec2], q: Vec2) -> Option<usize> {
        let (qx, qy) = self.cell_of(q);
        let mut best: Option<(f64, usize)> = None;
        let max_ring = self.width.max(self.height);
        for ring in 0..=max_ring {
            let x0 = qx.saturating_sub(ring);
            let y0 = qy.saturating_sub(ring);
            let x1 = (qx + ring).min(self.width - 1);
            let y1 = (qy + ring).min(self.height - 1);
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    let on_ring =
                        cx + ring == qx || cx == qx + ring || cy + ring == qy || cy == qy + ring;
                    if !on_ring {
                        continue;
                    }
                    for &i in self.cell(cx, cy) {
                        let i = i as usize;
                        let d2 = dist2(points[i], q);
                        if best.is_none_or(|(bd, bi)| d2 < bd || (d2 == bd && i < bi)) {
                            best = Some((d2, i));
                        }
                    }
                }
            }
            // Points in later rings are at least `ring * cell` away.
            if let Some((bd, _)) = best {
                let reach = ring as f64 * self.cell;
                if bd < reach * reach {
                    break;
                }
            }
        }
        best.map(|(_, i)| i)
    }
}

/// Greedy farthest-point sampling of `n` candidates starting at `first`;
/// `Some(None)` when fewer than `n` distinct candidates exist, `None` when
/// `cancelled` said so.
///
/// Each pick is the untaken candidate farthest from every pick so far, the lowest
/// index on ties. The candidates' distances live in a bucket grid; each cell keeps
/// its own farthest untaken candidate and a max-heap holds the cells by it (lazy
/// deletion: an entry is live while it equals its cell's best). A pick at `q`
/// only lowers distances within the last pick's distance of `q`, so it visits
/// those cells, recomputes their best and pushes the cells whose best changed:
/// heap operations per pick are the cells in reach (about 4 candidates a cell),
/// not every candidate whose distance fell. The same picks as a heap over the
/// candidates (`fps_over_candidates` in the tests, compared on random sets), in
/// a fifth of the time at 10,000 samples.
fn farthest_point_sampling(
    cands: &[Candidate],
    n: usize,
    first: usize,
    cancelled: &dyn Fn() -> bool,
) -> Option<Option<Vec<usize>>> {
    if cands.len() < n || n == 0 {
        return Some(None);
    }
    let grid = BucketGrid::new(cands.iter().map(|c| c.p), 4.0);
    let first = first.min(cands.len() - 1);
    let mut d2 = vec![f64::INFINITY; cands.len()];
    let mut taken = vec![false; cands.len()];
    // Each cell's farthest untaken candidate; `NO_BEST` when it has none.
    const NO_BEST: HeapEntry = HeapEntry {
        d2: f64::NEG_INFINITY,
        idx: u32::MAX,
    };
    let mut best = vec![NO_BEST; grid.width * grid.height];
    // (the cell's best, the cell)
    let mut heap: BinaryHeap<(HeapEntry, u32)> = BinaryHeap::with_capacity(best.len());
    let mut chosen = Vec::with_capacity(n);
    let mut next = first;
    let mut radius2 = f64::INFINITY;
    let mut visits = 0usize;
    loop {
        chosen.push(next);
        taken[next] = true;
        d2[next] = 0.0;
        if chosen.len() == n {
            return Some(Some(chosen));
        }
        if visits >= VISITS_PER_CHECK {
            visits = 0;
            if cancelled() {
                return None;
            }
        }
        let q = cands[next].p;
        // Only candidates closer to q than their current distance change, and every
        // current distance is at most `radius2`; q's own cell is in reach (the pick
        // left it).
        let r = radius2.sqrt();
        let (x0, y0, x1, y1) = if r.is_finite() {
            let (x0, y0) = grid.cell_of(q - Vec2::new(r, r));
            let (x1, y1) = grid.cell_of(q + Vec2::new(r, r));
            (x0, y0, x1, y1)
        } else {
            (0, 0, grid.width - 1, grid.height - 1)
        };
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                let cell = grid.cell(cx, cy);
                visits += cell.len() + 1;
                let mut b = NO_BEST;
                for &ci in cell {
                    let i = ci as usize;
                    if taken[i] {
                        continue;
                    }
                    let e = dist2(cands[i].p, q);
                    if e < d2[i] {
                        d2[i] = e;
                    }
                    let here = HeapEntry { d2: d2[i], idx: ci };
                    if b.idx == u32::MAX || here > b {
                        b = here;
                    }
                }
                let k = cy * grid.width + cx;
                if b != best[k] {
                    best[k] = b;
                    if b.idx != u32::MAX {
                        heap.push((b, k as u32));
                    }
                }
            }
        }
        // Pop the cell with the farthest live candidate (lazy deletion).
        loop {
            let Some((top, k)) = heap.pop() else {
                return Some(None);
            };
            if best[k as usize] == top {
                if top.d2 <= 0.0 {
                    return Some(None);
                }
                next = top.idx as usize;
                radius2 = top.d2;
                // Its cell is in reach of the next visit, which recomputes its best.
                break;
            }
        }
    }
}

/// Barycentric coordinates of `p` in triangle `tri` of `mesh` if it lies inside (within
/// [`BARY_EPS`]), clamped and normalised.
fn locate_in(mesh: &TriMesh, tri: u32, p: Vec2) -> Option<GoalSample> {
    let t = mesh.triangles().get(tri as usize)?;
    let [a, b, c] = t.map(|v| mesh.rest()[v as usize]);
    let det = cross(b - a, c - a);
    if det <= 0.0 {
        return None;
    }
    // λ_a = area(p, b, c) / area(a, b, c), and cyclically.
    let bary = [
        cross(c - b, p - b) / det,
        cross(a - c, p - c) / det,
        cross(b - a, p - a) / det,
    ];
    if !bary.iter().all(|&w| w >= -BARY_EPS) {
        return None;
    }
    let clamped = bary.map(|w| w.max(0.0));
    let s: f64 = clamped.iter().sum();
    Some(GoalSample {
        tri,
        bary: clamped.map(|w| w / s),
    })
}

/// Discrete Lloyd relaxation of the chosen samples, with the candidate set as the
/// density: each sample moves to the centroid of the candidates nearest to it
/// (a centroidal Voronoi tessellation in the limit). Returns the final samples; a
/// centroid outside the triangles of its own cell's candidates snaps to the cell's
/// candidate nearest to it, so samples stay on the mesh and distinct. `None` when
/// `cancelled` said so.
fn lloyd_relax(
    mesh: &TriMesh,
    cands: &[Candidate],
    chosen: &[usize],
    iterations: usize,
    cancelled: &dyn Fn() -> bool,
) -> Option<Vec<GoalSample>> {
    let n = chosen.len();
    let mut sites: Vec<Vec2> = chosen.iter().map(|&c| cands[c].p).collect();
    let mut sum = vec![Vec2::zeros(); n];
    let mut count = vec![0usize; n];
    let mut owner = vec![0u32; cands.len()];
    for it in 0..=iterations {
        let grid = BucketGrid::new(sites.iter().copied(), 2.0);
        sum.fill(Vec2::zeros());
        count.fill(0);
        for (ci, c) in cands.iter().enumerate() {
            if ci % LLOYD_CANDIDATES_PER_CHECK == LLOYD_CANDIDATES_PER_CHECK - 1 && cancelled() {
                return None;
            }
            let Some(s) = grid.nearest(&sites, c.p) else {
                continue;
            };
            owner[ci] = s as u32;
            sum[s] += c.p;
            count[s] += 1;
        }
        if it == iterations {
            break;
        }
        for i in 0..n {
            if count[i] > 0 {
                sites[i] = sum[i] / count[i] as f64;
            }
        }
    }
    // Express each site on the mesh: first in the triangles of its cell's candidates,
    // else snap to the cell's candidate nearest to the site.
    let mut best: Vec<Option<(f64, usize)>> = vec![None; n];
    for (ci, c) in cands.iter().enumerate() {
        let s = owner[ci] as usize;
        let d2 = dist2(c.p, sites[s]);
        if best[s].is_none_or(|(bd, _)| d2 < bd) {
            best[s] = Some((d2, ci));
        }
    }
    // Each site's candidates in index order (a counting sort by owner), for the
    // sites that do not lie in their nearest candidate's triangle.
    let mut start = vec![0u32; n + 1];
    for &o in &owner {
        start[o as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut owned = vec![0u32; cands.len()];
    for (ci, &o) in owner.iter().enumerate() {
        owned[fill[o as usize] as usize] = ci as u32;
        fill[o as usize] += 1;
    }
    let mut tried: Vec<u32> = Vec::new();
    let samples = (0..n)
        .map(|i| {
            let Some((_, nearest)) = best[i] else {
                // Empty cell (cannot happen for distinct sites); keep the chosen point.
                return cands[chosen[i]].sample;
            };
            if let Some(g) = locate_in(mesh, cands[nearest].sample.tri, sites[i]) {
                return g;
            }
            tried.clear();
            for &ci in &owned[start[i] as usize..start[i + 1] as usize] {
                let c = &cands[ci as usize];
                if !tried.contains(&c.sample.tri) {
                    tried.push(c.sample.tri);
                    if let Some(g) = locate_in(mesh, c.sample.tri, sites[i]) {
                        return g;
                    }
                }
            }
            cands[nearest].sample
        })
        .collect();
    Some(samples)
}

/// Positions of `samples` on the mesh with vertices at `positions`.
///
/// # Formula
/// `p = Σ_c bary[c] · positions[tri[c]]` (mesh-formation-control section 4.1).
///
/// # Units
/// Metres.
///
/// # Complexity
/// O(samples); no allocation when `out` has capacity for `samples.len()`.
///
/// # Errors
/// None. `out` is cleared first and receives one position per sample; a sample whose
/// triangle or vertices are out of range yields the origin.
///
/// ```
/// use crowdtouch::crowd::mesh::{goal_positions, GoalSample, TriMesh};
/// use crowdtouch::geom::{Rect, Vec2};
/// let m = TriMesh::grid(Rect { min: [0.0, 0.0], max: [1.0, 1.0] }, 2, 2);
/// let s = [GoalSample { tri: 0, bary: [1.0 / 3.0; 3] }];
/// let mut out = Vec::new();
/// goal_positions(&m, &s, m.rest(), &mut out);
/// assert!((out[0] - Vec2::new(2.0 / 3.0, 1.0 / 3.0)).norm() < 1e-12);
/// ```
pub fn goal_positions(
    mesh: &TriMesh,
    samples: &[GoalSample],
    positions: &[Vec2],
    out: &mut Vec<Vec2>,
) {
    out.clear();
    for s in samples {
        let p = mesh
            .triangles()
            .get(s.tri as usize)
            .and_then(|t| {
                let a = positions.get(t[0] as usize)?;
                let b = positions.get(t[1] as usize)?;
                let c = positions.get(t[2] as usize)?;
                Some(a * s.bary[0] + b * s.bary[1] + c * s.bary[2])
            })
            .unwrap_or_else(Vec2::zeros);
        out.push(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::mesh::distance_to_mesh;
    use crate::geom::Rect;
    use proptest::prelude::*;
    use proptest::test_runner::{Config as ProptestConfig, RngSeed};

    fn rect(w: f64, h: f64) -> Rect {
        Rect {
            min: [-1.0, 2.0],
            max: [-1.0 + w, 2.0 + h],
        }
    }

    /// Minimum and maximum nearest-neighbour distance of a point set (brute force).
    fn nn_spacing(points: &[Vec2]) -> (f64, f64) {
        let mut min = f64::INFINITY;
        let mut max: f64 = 0.0;
        for (i, p) in points.iter().enumerate() {
            let nn = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| (p - q).norm())
                .fold(f64::INFINITY, f64::min);
            min = min.min(nn);
            max = max.max(nn);
        }
        (min, max)
    }

    #[test]
    fn samples_equal_vertices_when_counts_match() {
        let m = TriMesh::grid(rect(3.0, 2.0), 7, 5);
        let s = sample_goals(&m, m.vertex_count());
        let mut out = Vec::new();
        goal_positions(&m, &s, m.rest(), &mut out);
        assert_eq!(out, m.rest());
    }

    #[test]
    fn samples_are_exact_in_count_inside_and_deterministic() {
        let m = TriMesh::grid(rect(5.0, 3.0), 9, 6);
        for n in [1, 2, 3, 7, 53, 55, 200] {
            let s = sample_goals(&m, n);
            assert_eq!(s.len(), n);
            assert_eq!(s, sample_goals(&m, n), "deterministic");
            let mut pos = Vec::new();
            goal_positions(&m, &s, m.rest(), &mut pos);
            for (g, p) in s.iter().zip(&pos) {
                assert!((g.tri as usize) < m.triangles().len());
                assert!(g.bary.iter().all(|&w| w >= 0.0));
                assert!((g.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                assert_eq!(distance_to_mesh(&m, m.rest(), *p), 0.0);
            }
            if n >= 2 {
                let (min, _) = nn_spacing(&pos);
                assert!(min > 0.0, "no duplicated points for n = {n}");
            }
        }
        assert!(sample_goals(&m, 0).is_empty());
    }

    #[test]
    fn samples_are_evenly_spaced() {
        let m = TriMesh::grid(
            Rect {
                min: [0.0, 0.0],
                max: [12.0, 8.0],
            },
            13,
            9,
        );
        for n in [50, 100, 1000] {
            let s = sample_goals(&m, n);
            let mut pos = Vec::new();
            goal_positions(&m, &s, m.rest(), &mut pos);
            let h = (m.area() / n as f64).sqrt();
            let (min, max) = nn_spacing(&pos);
            eprintln!(
                "n = {n}: nn spacing {:.3}..{:.3} of sqrt(A/n)",
                min / h,
                max / h
            );
            assert!(min >= 0.5 * h, "n = {n}: min spacing {min} < 0.5 * {h}");
            assert!(
                max <= 1.35 * h,
                "n = {n}: a gap: nearest neighbour up to {max} vs {h}"
            );
            // Proportional to area: each half of the rectangle gets about half the points.
            let left = pos.iter().filter(|p| p.x < 6.0).count() as f64;
            assert!(
                (left / n as f64 - 0.5).abs() < 0.08,
                "n = {n}: {left} on the left"
            );
        }
    }

    #[test]
    fn two_pieces_share_the_samples_by_area() {
        let m = crate::crowd::mesh::trimesh::two_grids(1.0);
        // Areas 2 m² and 6 m².
        for (n, left) in [(80, 20), (41, 10), (7, 2), (1, 0)] {
            let s = sample_goals(&m, n);
            assert_eq!(s.len(), n);
            assert_eq!(s, sample_goals(&m, n), "deterministic");
            let on_left = s
                .iter()
                .filter(|g| m.triangles()[g.tri as usize][0] < 12)
                .count();
            assert_eq!(on_left, left, "n = {n}");
            let mut pos = Vec::new();
            goal_positions(&m, &s, m.rest(), &mut pos);
            for p in &pos {
                assert_eq!(distance_to_mesh(&m, m.rest(), *p), 0.0);
            }
            if n >= 40 {
                // Even spacing inside each piece.
                let h = (m.area() / n as f64).sqrt();
                let (min, max) = nn_spacing(&pos);
                assert!(min >= 0.5 * h && max <= 1.35 * h, "{min} {max} vs {h}");
            }
        }
        // Counts equal to the vertex count: the vertices.
        let s = sample_goals(&m, m.vertex_count());
        let mut pos = Vec::new();
        goal_positions(&m, &s, m.rest(), &mut pos);
        assert_eq!(pos, m.rest());
    }

    /// The check is called at bounded intervals and the sampling stops at the first
    /// call that fires, in the farthest-point picks and in every Lloyd sweep.
    #[test]
    fn a_cancelled_sampling_stops_at_the_first_check_that_fires() {
        use std::cell::Cell;
        let m = TriMesh::grid(rect(12.0, 8.0), 9, 7);
        let n = 3000;
        let calls = Cell::new(0usize);
        let counting = || {
            calls.set(calls.get() + 1);
            false
        };
        let full = sample_goals_cancellable(&m, n, &counting).unwrap();
        assert_eq!(full, sample_goals(&m, n));
        let total = calls.get();
        // Once laid out, then every 2^16 visits and every 4096 candidates of
        // each of the 7 assignments.
        assert!(total >= 8, "{total} checks");
        for k in [1, 2, total / 3, total / 2, total - 1, total] {
            calls.set(0);
            let fires = || {
                calls.set(calls.get() + 1);
                calls.get() >= k
            };
            assert_eq!(
                sample_goals_cancellable(&m, n, &fires),
                None,
                "fired at {k}"
            );
            assert_eq!(calls.get(), k);
        }
    }

    #[test]
    fn goal_positions_reuses_capacity() {
        let m = TriMesh::grid(rect(1.0, 1.0), 4, 4);
        let s = sample_goals(&m, 30);
        let mut out = Vec::with_capacity(30);
        let ptr = out.as_ptr();
        goal_positions(&m, &s, m.rest(), &mut out);
        goal_positions(&m, &s, m.rest(), &mut out);
        assert_eq!(out.len(), 30);
        assert_eq!(out.as_ptr(), ptr);
        // Out-of-range samples give the origin instead of panicking.
        goal_positions(
            &m,
            &[GoalSample {
                tri: 999,
                bary: [1.0, 0.0, 0.0],
            }],
            m.rest(),
            &mut out,
        );
        assert_eq!(out, vec![Vec2::zeros()]);
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 24,
            rng_seed: RngSeed::Fixed(0x6d65_7368),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn prop_grid_and_samples(cols in 2usize..12, rows in 2usize..12, w in 0.1f64..20.0,
                                 h in 0.1f64..20.0, n in 1usize..150) {
            let m = TriMesh::grid(rect(w, h), cols, rows);
            prop_assert!(m.sanity_check().is_ok());
            let s = sample_goals(&m, n);
            prop_assert_eq!(s.len(), n);
            let mut pos = Vec::new();
            goal_positions(&m, &s, m.rest(), &mut pos);
            let scale = w.max(h);
            for p in &pos {
                prop_assert!(distance_to_mesh(&m, m.rest(), *p) <= 1e-12 * scale);
            }
        }
    }

    /// The farthest-point sampling with a heap over the candidates (the earlier
    /// implementation): the reference for `farthest_point_sampling`.
    /// Greedy farthest-point sampling of `n` candidates starting at `first`;
    /// `Some(None)` when fewer than `n` distinct candidates exist, `None` when
    /// `cancelled` said so.
    fn fps_over_candidates(
        cands: &[Candidate],
        n: usize,
        first: usize,
        cancelled: &dyn Fn() -> bool,
    ) -> Option<Option<Vec<usize>>> {
        if cands.len() < n || n == 0 {
            return Some(None);
        }
        let grid = BucketGrid::new(cands.iter().map(|c| c.p), 4.0);
        let first = first.min(cands.len() - 1);
        let mut d2 = vec![f64::INFINITY; cands.len()];
        let mut taken = vec![false; cands.len()];
        let mut heap = BinaryHeap::with_capacity(cands.len());
        let mut chosen = Vec::with_capacity(n);
        let mut next = first;
        let mut radius2 = f64::INFINITY;
        let mut visits = 0usize;
        loop {
            chosen.push(next);
            taken[next] = true;
            d2[next] = 0.0;
            if chosen.len() == n {
                return Some(Some(chosen));
            }
            if visits >= VISITS_PER_CHECK {
                visits = 0;
                if cancelled() {
                    return None;
                }
            }
            let q = cands[next].p;
            // Only candidates closer to q than their current distance change, and every
            // current distance is at most `radius2`.
            let r = radius2.sqrt();
            let (x0, y0, x1, y1) = if r.is_finite() {
                let (x0, y0) = grid.cell_of(q - Vec2::new(r, r));
                let (x1, y1) = grid.cell_of(q + Vec2::new(r, r));
                (x0, y0, x1, y1)
            } else {
                (0, 0, grid.width - 1, grid.height - 1)
            };
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    let cell = grid.cell(cx, cy);
                    visits += cell.len() + 1;
                    for &ci in cell {
                        let ci = ci as usize;
                        if taken[ci] {
                            continue;
                        }
                        let e = dist2(cands[ci].p, q);
                        if e < d2[ci] {
                            d2[ci] = e;
                            heap.push(HeapEntry {
                                d2: e,
                                idx: ci as u32,
                            });
                        }
                    }
                }
            }
            // Pop the farthest live candidate (lazy deletion of stale entries).
            loop {
                let Some(top) = heap.pop() else {
                    return Some(None);
                };
                let i = top.idx as usize;
                if !taken[i] && top.d2 == d2[i] {
                    if top.d2 <= 0.0 {
                        return Some(None);
                    }
                    next = i;
                    radius2 = top.d2;
                    break;
                }
            }
        }
    }

    #[test]
    fn farthest_point_sampling_picks_as_a_heap_over_candidates() {
        // Random clouds with duplicates and ties (a lattice), a few sizes.
        let mut rng = crate::rng::SplitMix64::new(7);
        for (m, n) in [
            (1usize, 1usize),
            (50, 10),
            (400, 100),
            (2000, 300),
            (3000, 3000),
        ] {
            for lattice in [false, true] {
                let cands: Vec<Candidate> = (0..m)
                    .map(|i| {
                        let p = if lattice {
                            Vec2::new((i % 37) as f64 * 0.25, (i / 37) as f64 * 0.25)
                        } else if i % 17 == 3 {
                            Vec2::new(1.0, 1.0)
                        } else {
                            Vec2::new(rng.uniform(0.0, 9.0), rng.uniform(0.0, 4.0))
                        };
                        Candidate {
                            p,
                            sample: GoalSample {
                                tri: 0,
                                bary: [1.0, 0.0, 0.0],
                            },
                        }
                    })
                    .collect();
                let first = m / 3;
                let fast = farthest_point_sampling(&cands, n, first, &|| false);
                let slow = fps_over_candidates(&cands, n, first, &|| false);
                assert_eq!(fast, slow, "m={m} n={n} lattice={lattice}");
            }
        }
    }
}
