//! A crowd mesh rebuilt around where the agents are.
//!
//! After a gesture motion (gesture-driven section 7.3) the crowd stands in a new
//! layout that no formation mesh describes; direct touch control
//! (mesh-formation-control section 4.1) needs a mesh over the crowd again.
//! [`mesh_around`] builds one whose vertices are the agents themselves and gives one
//! goal sample per agent exactly at its vertex, so installing it
//! (`crowd::control::DirectController::set_mesh_sampled`) moves
//! nobody.
//!
//! The mesh is the Delaunay triangulation of the agents (spade), cut into one piece
//! per group and each piece sculpted inwards like a chi-shape (Duckham et al. 2008,
//! "Efficient generation of simple polygons for characterizing the shape of a set
//! of points in the plane"):
//! 1. *Groups*: agents joined by Delaunay edges no longer than [`ALPHA_FACTOR`]
//!    times the crowd's spacing (the median nearest-neighbour distance, at least two
//!    body radii) form one group (single linkage: two agents of different groups
//!    are farther apart than that threshold, since the Euclidean minimum spanning
//!    tree is part of the triangulation). Triangles with corners in two groups —
//!    the corridor between a split crowd's halves — are dropped, so each group is a
//!    piece of its own ([`TriMesh`] holds several pieces) and a finger dragging one
//!    group leaves the others where they are.
//! 2. *Chi-shape per group*: from the group's own triangles, the boundary triangle
//!    behind the longest boundary edge is removed while that edge is longer than the
//!    threshold and the triangle's third vertex is interior, which keeps the piece a
//!    disc with every agent on a triangle.
//! 3. *Groups without a triangle* (an isolated agent, two agents, agents on a line)
//!    get two helper vertices off their line, [`HELPER_OFFSET_FACTOR`] spacings away
//!    or less — at most a third of the clearance to everything else, so the helper
//!    triangles overlap no other piece — and are triangulated on their own. An
//!    isolated agent thus gets a small triangle of its own rather than joining the
//!    nearest group: joining would be a corridor again, and a drag of the group would
//!    pull the straggler along (and the straggler's drag the group). Agents at the
//!    same position share a vertex.
//!
//! A group whose own triangles are not one disc — a ring of agents around another
//! group has a hole — is merged with the group nearest to it (shortest Delaunay edge)
//! and the pieces rebuilt; an agent of a group left without a triangle becomes a
//! group of its own. At worst all groups merge and the mesh is the single sculpted
//! disc over the whole crowd. Agents all on one line are one group.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use spade::{DelaunayTriangulation, Point2, Triangulation};

use super::goals::GoalSample;
use super::trimesh::{MeshError, TriMesh};
use crate::geom::{cross, segment_distance_squared, Vec2};

/// A boundary edge longer than this many times the crowd's spacing is cut away, and
/// groups farther apart than this many spacings are separate pieces.
pub const ALPHA_FACTOR: f64 = 3.0;

/// Helper vertices of a group without a triangle sit at most this many spacings
/// off its line.
pub const HELPER_OFFSET_FACTOR: f64 = 1.0;

/// Spacing assumed when neither the agents nor `radius_m` give one (m).
const FALLBACK_SPACING_M: f64 = 0.5;

/// A helper triangle reaches at most this fraction of its group's clearance (the
/// distance to the nearest other agent or piece).
const HELPER_CLEARANCE_FRACTION: f64 = 1.0 / 3.0;

/// A mesh whose vertices are the agents at `positions` (plus helpers for groups
/// without a triangle), one piece per group of agents, and one goal sample per
/// agent at its own vertex.
///
/// `radius_m` is the agents' body radius: the spacing used for cutting long edges
/// and separating groups is at least `2 · radius_m` (a non-positive or non-finite
/// radius is ignored).
///
/// # Errors
/// [`MeshError::Empty`] without agents; [`MeshError::NonFinite`] naming the first
/// agent with a NaN or infinite coordinate (or one too large for the triangulation).
///
/// # Complexity
/// O(n log n) per build: the triangulation, then each triangle removed at most once
/// through a heap of boundary edges; plus O(g · (n + T)) for the clearances of `g`
/// groups without a triangle. A group that must be merged costs one more build.
pub fn mesh_around(
    positions: &[Vec2],
    radius_m: f64,
) -> Result<(TriMesh, Vec<GoalSample>), MeshError> {
    if positions.is_empty() {
        return Err(MeshError::Empty);
    }
    if let Some(vertex) = positions
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(MeshError::NonFinite { vertex });
    }
    // Distinct positions become vertices; agents on the same spot share one.
    let key = |p: Vec2| ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits());
    let mut index: HashMap<(u64, u64), u32> = HashMap::with_capacity(positions.len());
    let mut points: Vec<Vec2> = Vec::with_capacity(positions.len());
    let agent_vertex: Vec<u32> = positions
        .iter()
        .map(|&p| {
            *index.entry(key(p)).or_insert_with(|| {
                points.push(p);
                (points.len() - 1) as u32
            })
        })
        .collect();
    let body = if radius_m.is_finite() && radius_m > 0.0 {
        2.0 * radius_m
    } else {
        0.0
    };
    let not_finite = |v: usize| {
        let agent = agent_vertex
            .iter()
            .position(|&a| a as usize == v)
            .unwrap_or(positions.len());
        MeshError::NonFinite { vertex: agent }
    };
    let tris = delaunay(&points).map_err(not_finite)?;
    let nn = median_nearest(&points, &tris);
    let spacing = nn.unwrap_or(0.0).max(body);
    let spacing = if spacing > 0.0 {
        spacing
    } else {
        FALLBACK_SPACING_M
    };
    let max_edge_m = ALPHA_FACTOR * spacing;
    let mut group = groups(points.len(), &points, &tris, max_edge_m);
    let mesh = loop {
        let (rest, pieces, vertex_group) =
            build(&points, &tris, &group, spacing).map_err(not_finite)?;
        let err = match TriMesh::from_triangles(rest, pieces) {
            Ok(mesh) => break mesh,
            Err(e) => e,
        };
        // Repair the group the error is about and build again; every repair splits
        // an agent off a group that has triangles (at most once per agent) or
        // merges two groups, so this ends.
        let culprit = match err {
            MeshError::UnusedVertex { vertex } => {
                let g = vertex_group.get(vertex).copied();
                let shared = g.is_some_and(|g| group.iter().filter(|&&h| h == g).count() > 1);
                if vertex < points.len() && shared {
                    group[vertex] = next_group(&group);
                    continue;
                }
                g
            }
            MeshError::NonManifoldEdge { from, .. } => vertex_group.get(from as usize).copied(),
            MeshError::BoundaryNotSingleLoop { vertex } => {
                vertex_group.get(vertex as usize).copied()
            }
            _ => None,
        };
        if !merge_nearest(&mut group, culprit, &points, &tris) {
            return Err(err);
        }
    };
    // One triangle and corner per vertex, then each agent's sample at its vertex.
    let mut corner_of: Vec<Option<(u32, usize)>> = vec![None; mesh.vertex_count()];
    for (ti, t) in mesh.triangles().iter().enumerate() {
        for (k, &v) in t.iter().enumerate() {
            corner_of[v as usize].get_or_insert((ti as u32, k));
        }
    }
    let samples = agent_vertex
        .iter()
        .map(|&v| {
            // Every vertex is on a triangle (TriMesh::from_triangles checked it).
            let (tri, k) = corner_of[v as usize].unwrap_or((0, 0));
            let mut bary = [0.0; 3];
            bary[k] = 1.0;
            GoalSample { tri, bary }
        })
        .collect();
    Ok((mesh, samples))
}

/// The group of every point: connected components of the Delaunay edges no longer
/// than `max_edge_m`, numbered by their lowest point. All points are one group when
/// the triangulation is empty (one point, or all on a line).
fn groups(n: usize, points: &[Vec2], tris: &[[u32; 3]], max_edge_m: f64) -> Vec<u32> {
    if tris.is_empty() {
        return vec![0; n];
    }
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if (points[a] - points[b]).norm() <= max_edge_m {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    (0..n).map(|v| find(&mut parent, v) as u32).collect()
}

/// A group id no point has.
fn next_group(group: &[u32]) -> u32 {
    group.iter().max().map_or(0, |g| g + 1)
}

/// Merges group `culprit` (all groups when `None`) with the group nearest to it
/// (across its shortest Delaunay edge to another group). `false` when there is
/// only one group.
fn merge_nearest(
    group: &mut [u32],
    culprit: Option<u32>,
    points: &[Vec2],
    tris: &[[u32; 3]],
) -> bool {
    let distinct = {
        let mut g: Vec<u32> = group.to_vec();
        g.sort_unstable();
        g.dedup();
        g.len()
    };
    if distinct <= 1 {
        return false;
    }
    let Some(c) = culprit else {
        group.fill(0);
        return true;
    };
    let mut best: Option<(f64, u32)> = None;
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if group[a] == c && group[b] != c {
                let d = (points[a] - points[b]).norm();
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, group[b]));
                }
            }
        }
    }
    // A group split off without a Delaunay edge to another (cannot happen in a
    // connected triangulation): join everything.
    let into = match best {
        Some((_, g)) => g,
        None => {
            group.fill(0);
            return true;
        }
    };
    for g in group.iter_mut() {
        if *g == c {
            *g = into;
        }
    }
    true
}

/// A built mesh: vertices, triangles, and the group of every vertex.
type Built = (Vec<Vec2>, Vec<[u32; 3]>, Vec<u32>);

/// The vertices (the points, then helpers), triangles and vertex groups of one mesh
/// with a piece per group: each group's own Delaunay triangles sculpted, then the
/// groups without a triangle with their helpers. `Err(point)` if the triangulation
/// refuses a point.
fn build(points: &[Vec2], tris: &[[u32; 3]], group: &[u32], spacing: f64) -> Result<Built, usize> {
    let max_edge_m = ALPHA_FACTOR * spacing;
    let mut own: HashMap<u32, Vec<[u32; 3]>> = HashMap::new();
    for t in tris {
        let g = group[t[0] as usize];
        if t.iter().all(|&v| group[v as usize] == g) {
            own.entry(g).or_default().push(*t);
        }
    }
    let mut ids: Vec<u32> = group.to_vec();
    ids.sort_unstable();
    ids.dedup();
    let mut rest = points.to_vec();
    let mut vertex_group = group.to_vec();
    let mut out: Vec<[u32; 3]> = Vec::with_capacity(tris.len());
    for g in &ids {
        if let Some(mut piece) = own.remove(g) {
            sculpt(&rest, &mut piece, max_edge_m);
            out.extend(piece);
        }
    }
    // Groups without a triangle: the segment their points span.
    let lone: Vec<(u32, Vec<u32>, Vec2, Vec2)> = ids
        .iter()
        .filter(|g| !out.iter().any(|t| group[t[0] as usize] == **g))
        .map(|&g| {
            let members: Vec<u32> = (0..points.len() as u32)
                .filter(|&v| group[v as usize] == g)
                .collect();
            let (a, b) = span(points, &members);
            (g, members, a, b)
        })
        .collect();
    for (g, members, a, b) in &lone {
        // Clearance: the other groups' points and segments, and the triangles built.
        let mut clear2 = f64::INFINITY;
        for (v, p) in points.iter().enumerate() {
            if group[v] != *g {
                clear2 = clear2.min(segment_distance_squared(*p, *a, *b));
            }
        }
        for (h, _, c, d) in &lone {
            if h != g {
                clear2 = clear2.min(segments_distance2(*a, *b, *c, *d));
            }
        }
        for t in &out {
            for k in 0..3 {
                let (c, d) = (rest[t[k] as usize], rest[t[(k + 1) % 3] as usize]);
                clear2 = clear2.min(segments_distance2(*a, *b, c, d));
            }
        }
        let reach = (HELPER_CLEARANCE_FRACTION * clear2.sqrt()).min(spacing);
        let offset = (HELPER_OFFSET_FACTOR * spacing).min(reach);
        let c = members
            .iter()
            .fold(Vec2::zeros(), |acc, &v| acc + points[v as usize])
            / members.len() as f64;
        let along = if (b - a).norm() > 0.0 {
            (b - a).normalize()
        } else {
            Vec2::new(1.0, 0.0)
        };
        let across = Vec2::new(-along.y, along.x) * offset;
        let first = rest.len() as u32;
        if members.len() == 1 {
            rest.push(c + along * reach + across * 0.5);
            rest.push(c + across);
        } else {
            rest.push(c + across);
            rest.push(c - across);
        }
        vertex_group.extend([*g, *g]);
        // Triangulate the group with its helpers on their own.
        let local: Vec<u32> = members.iter().copied().chain([first, first + 1]).collect();
        let local_points: Vec<Vec2> = local.iter().map(|&v| rest[v as usize]).collect();
        let mut piece: Vec<[u32; 3]> = delaunay(&local_points)
            .map_err(|i| local.get(i).map_or(0, |&v| v as usize))?
            .into_iter()
            .map(|t| t.map(|i| local[i as usize]))
            .collect();
        sculpt(&rest, &mut piece, max_edge_m);
        out.extend(piece);
    }
    Ok((rest, out, vertex_group))
}

/// The two extreme points of `members` along their longest direction from the
/// centroid (the same point twice for a single member).
fn span(points: &[Vec2], members: &[u32]) -> (Vec2, Vec2) {
    let c = members
        .iter()
        .fold(Vec2::zeros(), |acc, &v| acc + points[v as usize])
        / members.len().max(1) as f64;
    let far = members
        .iter()
        .map(|&v| points[v as usize])
        .max_by(|a, b| (a - c).norm().total_cmp(&(b - c).norm()))
        .unwrap_or(c);
    let other = members
        .iter()
        .map(|&v| points[v as usize])
        .max_by(|a, b| (a - far).norm().total_cmp(&(b - far).norm()))
        .unwrap_or(far);
    (far, other)
}

/// Squared distance between segments `ab` and `cd` (0 when they cross or touch).
fn segments_distance2(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> f64 {
    let (d1, d2) = (cross(b - a, c - a), cross(b - a, d - a));
    let (d3, d4) = (cross(d - c, a - c), cross(d - c, b - c));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    segment_distance_squared(c, a, b)
        .min(segment_distance_squared(d, a, b))
        .min(segment_distance_squared(a, c, d))
        .min(segment_distance_squared(b, c, d))
}

/// The Delaunay triangles of `points`, counter-clockwise, as indices into `points`;
/// `Err(index)` of a point the triangulation refuses.
fn delaunay(points: &[Vec2]) -> Result<Vec<[u32; 3]>, usize> {
    let mut dt: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    let mut handle_to_vertex: Vec<u32> = vec![u32::MAX; points.len()];
    for (v, p) in points.iter().enumerate() {
        match dt.insert(Point2::new(p.x, p.y)) {
            Ok(h) => handle_to_vertex[h.index()] = v as u32,
            Err(_) => return Err(v),
        }
    }
    Ok(dt
        .inner_faces()
        .map(|f| {
            let mut t = f.vertices().map(|h| handle_to_vertex[h.fix().index()]);
            let [a, b, c] = t.map(|v| points[v as usize]);
            if cross(b - a, c - a) < 0.0 {
                t.swap(1, 2);
            }
            t
        })
        .collect())
}

/// Median over vertices of the distance to the nearest other vertex, read from the
/// triangulation's edges (a nearest neighbour is always a Delaunay neighbour).
fn median_nearest(rest: &[Vec2], tris: &[[u32; 3]]) -> Option<f64> {
    let mut nearest = vec![f64::INFINITY; rest.len()];
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let d = (rest[a] - rest[b]).norm();
            nearest[a] = nearest[a].min(d);
            nearest[b] = nearest[b].min(d);
        }
    }
    let mut d: Vec<f64> = nearest.into_iter().filter(|d| d.is_finite()).collect();
    if d.is_empty() {
        return None;
    }
    d.sort_by(f64::total_cmp);
    Some(d[d.len() / 2])
}

/// A boundary edge in the sculpting heap: longest first, ties by vertex indices.
#[derive(Copy, Clone, PartialEq)]
struct Edge {
    len: f64,
    from: u32,
    to: u32,
}

impl Eq for Edge {}

impl PartialOrd for Edge {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Edge {
    fn cmp(&self, other: &Self) -> Ordering {
        self.len
            .total_cmp(&other.len)
            .then_with(|| other.from.cmp(&self.from))
            .then_with(|| other.to.cmp(&self.to))
    }
}

/// Removes boundary triangles behind boundary edges longer than `max_edge_m` whose
/// third vertex is interior (chi-shape), keeping one disc with every vertex used.
fn sculpt(rest: &[Vec2], tris: &mut Vec<[u32; 3]>, max_edge_m: f64) {
    let mut owner: HashMap<(u32, u32), usize> = HashMap::with_capacity(tris.len() * 3);
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            owner.insert((t[k], t[(k + 1) % 3]), ti);
        }
    }
    let mut on_boundary = vec![false; rest.len()];
    let mut heap = BinaryHeap::new();
    let len = |a: u32, b: u32| (rest[a as usize] - rest[b as usize]).norm();
    for &(a, b) in owner.keys() {
        if !owner.contains_key(&(b, a)) {
            on_boundary[a as usize] = true;
            on_boundary[b as usize] = true;
            heap.push(Edge {
                len: len(a, b),
                from: a,
                to: b,
            });
        }
    }
    let mut alive = vec![true; tris.len()];
    while let Some(e) = heap.pop() {
        if e.len <= max_edge_m {
            break;
        }
        let Some(&ti) = owner.get(&(e.from, e.to)) else {
            continue;
        };
        let t = tris[ti];
        let k = (0..3).find(|&k| t[k] == e.from).unwrap_or(0);
        let c = t[(k + 2) % 3];
        if on_boundary[c as usize] {
            continue;
        }
        alive[ti] = false;
        for j in 0..3 {
            owner.remove(&(t[j], t[(j + 1) % 3]));
        }
        on_boundary[c as usize] = true;
        // The edges c–to and from–c are now on the boundary, held by the neighbours.
        for (a, b) in [(c, e.to), (e.from, c)] {
            if owner.contains_key(&(a, b)) {
                heap.push(Edge {
                    len: len(a, b),
                    from: a,
                    to: b,
                });
            }
        }
    }
    let mut ti = 0;
    tris.retain(|_| {
        ti += 1;
        alive[ti - 1]
    });
}

/// A mesh around the agents at `positions` made of one piece per part: each of
/// `parts` (agent indices; every agent in exactly one) meshed on its own with
/// [`mesh_around`] and the pieces put side by side, so two parts stay two pieces
/// however close they stand. Within a part, a group of fewer than
/// `min_piece_agents` agents farther than [`ALPHA_FACTOR`] spacings (the part's
/// median nearest-neighbour distance, at least two body radii) from the rest — a
/// straggler, or a few — has its goals drawn in as a block to one spacing from
/// the nearest of the rest, so it joins its part instead of making a piece of its
/// own. Goal `i` is agent `i`'s: at its vertex, or where it was drawn in to.
///
/// # Errors
/// As [`mesh_around`]; [`MeshError::Empty`] also when `parts` leaves an agent out
/// or names one twice or out of range.
///
/// # Complexity
/// O(Σ nₚ²) for the stragglers plus [`mesh_around`] per part.
pub fn mesh_around_parts(
    positions: &[Vec2],
    parts: &[Vec<usize>],
    radius_m: f64,
    min_piece_agents: usize,
) -> Result<(TriMesh, Vec<GoalSample>), MeshError> {
    let n = positions.len();
    let mut seen = vec![false; n];
    for &i in parts.iter().flatten() {
        if i >= n || seen[i] {
            return Err(MeshError::Empty);
        }
        seen[i] = true;
    }
    if n == 0 || seen.iter().any(|s| !s) {
        return Err(MeshError::Empty);
    }
    let body = if radius_m.is_finite() && radius_m > 0.0 {
        2.0 * radius_m
    } else {
        0.0
    };
    let mut rest: Vec<Vec2> = Vec::with_capacity(n);
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(2 * n);
    let mut samples: Vec<Option<GoalSample>> = vec![None; n];
    for part in parts {
        let mut pts: Vec<Vec2> = part.iter().map(|&i| positions[i]).collect();
        draw_in_stragglers(&mut pts, body, min_piece_agents);
        let (mesh, goals) = mesh_around(&pts, radius_m)?;
        let (v0, t0) = (rest.len() as u32, triangles.len() as u32);
        rest.extend_from_slice(mesh.rest());
        triangles.extend(mesh.triangles().iter().map(|t| t.map(|v| v + v0)));
        for (&i, g) in part.iter().zip(goals) {
            samples[i] = Some(GoalSample {
                tri: g.tri + t0,
                bary: g.bary,
            });
        }
    }
    let mesh = TriMesh::from_triangles(rest, triangles)?;
    let samples = samples
        .into_iter()
        .map(|s| s.ok_or(MeshError::Empty))
        .collect::<Result<_, _>>()?;
    Ok((mesh, samples))
}

/// Draws stragglers in: the points fall into groups joined by steps of at most
/// [`ALPHA_FACTOR`] spacings (the median nearest-neighbour distance, at least
/// `body_m`); while a group has fewer than `min` points (and is not the only one),
/// the smallest is moved as a block until its point nearest to the rest stands one
/// spacing from that rest. A lone straggler, a pair or a small cluster thus joins
/// its part with its own shape; groups of `min` or more stay pieces of their own.
fn draw_in_stragglers(pts: &mut [Vec2], body_m: f64, min: usize) {
    let n = pts.len();
    if n < 2 {
        return;
    }
    let nearest = |pts: &[Vec2], i: usize| -> f64 {
        (0..pts.len())
            .filter(|&j| j != i)
            .map(|j| (pts[j] - pts[i]).norm())
            .fold(f64::INFINITY, f64::min)
    };
    let mut nn: Vec<f64> = (0..n)
        .map(|i| nearest(pts, i))
        .filter(|d| d.is_finite())
        .collect();
    if nn.is_empty() {
        return;
    }
    nn.sort_by(f64::total_cmp);
    let spacing = nn[nn.len() / 2].max(body_m);
    if spacing <= 0.0 {
        return;
    }
    let far = ALPHA_FACTOR * spacing;
    for _ in 0..n {
        // Single linkage at `far`.
        let mut label: Vec<usize> = (0..n).collect();
        loop {
            let mut changed = false;
            for i in 0..n {
                for j in 0..n {
                    if label[j] < label[i] && (pts[i] - pts[j]).norm() <= far {
                        label[i] = label[j];
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        let mut size: HashMap<usize, usize> = HashMap::new();
        for &l in &label {
            *size.entry(l).or_default() += 1;
        }
        if size.len() <= 1 {
            return;
        }
        let Some((&small, _)) = size
            .iter()
            .filter(|(_, &s)| s < min)
            .min_by_key(|(&l, &s)| (s, l))
        else {
            return;
        };
        let mut best = (f64::INFINITY, 0, 0);
        for i in (0..n).filter(|&i| label[i] == small) {
            for j in (0..n).filter(|&j| label[j] != small) {
                let d = (pts[i] - pts[j]).norm();
                if d < best.0 {
                    best = (d, i, j);
                }
            }
        }
        let (d, i, j) = best;
        if !(d.is_finite() && d > 0.0) {
            return;
        }
        let shift = pts[j] + (pts[i] - pts[j]) / d * spacing - pts[i];
        for k in (0..n).filter(|&k| label[k] == small) {
            pts[k] += shift;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::mesh::{goal_positions, Arap, Constraint, PointConstraint};
    use crate::rng::SplitMix64;

    fn jittered(n: usize, centre: Vec2, seed: u64) -> Vec<Vec2> {
        let mut rng = SplitMix64::new(seed);
        let cols = (n as f64).sqrt().ceil() as usize;
        (0..n)
            .map(|k| {
                centre
                    + Vec2::new((k % cols) as f64 * 0.5, (k / cols) as f64 * 0.5)
                    + Vec2::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1))
            })
            .collect()
    }

    fn check(positions: &[Vec2]) -> (TriMesh, Vec<GoalSample>) {
        let (mesh, samples) = mesh_around(positions, 0.15).unwrap();
        mesh.sanity_check().unwrap();
        assert_eq!(samples.len(), positions.len());
        let mut goals = Vec::new();
        goal_positions(&mesh, &samples, mesh.rest(), &mut goals);
        for (g, p) in goals.iter().zip(positions) {
            assert!((g - p).norm() < 1e-12, "goal {g:?} for agent at {p:?}");
        }
        (mesh, samples)
    }

    /// Edge-connected pieces of the triangles whose edges are all at most `max_m`.
    fn short_pieces(mesh: &TriMesh, max_m: f64) -> usize {
        let r = mesh.rest();
        let short: Vec<&[u32; 3]> = mesh
            .triangles()
            .iter()
            .filter(|t| {
                (0..3).all(|k| (r[t[k] as usize] - r[t[(k + 1) % 3] as usize]).norm() <= max_m)
            })
            .collect();
        let mut parent: Vec<usize> = (0..r.len()).collect();
        fn find(p: &mut [usize], x: usize) -> usize {
            let mut x = x;
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for t in &short {
            for k in 1..3 {
                let (a, b) = (
                    find(&mut parent, t[0] as usize),
                    find(&mut parent, t[k] as usize),
                );
                parent[a] = b;
            }
        }
        let mut roots: Vec<usize> = short
            .iter()
            .map(|t| find(&mut parent, t[0] as usize))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        roots.len()
    }

    #[test]
    fn goals_sit_on_the_agents_and_the_mesh_covers_a_compact_crowd() {
        let p = jittered(40, Vec2::new(2.0, 1.0), 3);
        let (mesh, _) = check(&p);
        assert_eq!(mesh.vertex_count(), 40);
        assert_eq!(short_pieces(&mesh, ALPHA_FACTOR * 0.5), 1);
    }

    #[test]
    fn a_concave_crowd_loses_its_notch() {
        // An L of agents: the convex hull's long diagonal edges are cut away.
        let mut p = Vec::new();
        for i in 0..10 {
            for j in 0..2 {
                p.push(Vec2::new(i as f64 * 0.5, j as f64 * 0.5));
                p.push(Vec2::new(j as f64 * 0.5, 1.0 + i as f64 * 0.5));
            }
        }
        let (mesh, _) = check(&p);
        // The bars cover 2 × 4.5 × 0.5 m² and the gap at their corner 0.25 m²; the
        // convex hull 13.75 m².
        assert!(mesh.area() < 6.0, "area {}", mesh.area());
    }

    #[test]
    fn two_far_groups_give_two_pieces_without_a_corridor() {
        let mut p = jittered(25, Vec2::zeros(), 1);
        p.extend(jittered(25, Vec2::new(8.0, 0.5), 2));
        let (mesh, _) = check(&p);
        assert_eq!(mesh.piece_count(), 2);
        assert_eq!(mesh.components()[0], (0..25).collect::<Vec<u32>>());
        assert_eq!(mesh.components()[1], (25..50).collect::<Vec<u32>>());
        assert_eq!(short_pieces(&mesh, ALPHA_FACTOR * 0.5), 2);
        // No triangle reaches across the gap.
        let r = mesh.rest();
        let across = mesh
            .triangles()
            .iter()
            .filter(|t| {
                let xs = t.map(|v| r[v as usize].x);
                xs.iter().any(|&x| x < 3.0) && xs.iter().any(|&x| x > 7.0)
            })
            .count();
        assert_eq!(across, 0);
        assert!(mesh.area() < 10.0, "{}", mesh.area());
        // Groups closer than the threshold stay one piece.
        let mut q = jittered(25, Vec2::zeros(), 1);
        q.extend(jittered(25, Vec2::new(3.0, 0.0), 2));
        assert_eq!(check(&q).0.piece_count(), 1);
    }

    #[test]
    fn an_outlier_gets_a_small_triangle_of_its_own() {
        let mut p = jittered(30, Vec2::zeros(), 4);
        p.push(Vec2::new(10.0, 10.0));
        let (mesh, samples) = check(&p);
        assert_eq!(mesh.piece_count(), 2);
        let t = mesh.triangles()[samples[30].tri as usize];
        assert!(t.contains(&30));
        let piece = mesh.piece_of_vertex()[30] as usize;
        assert_eq!(
            mesh.components()[piece],
            vec![30, 31, 32],
            "agent + 2 helpers"
        );
        for &v in &t {
            assert!((mesh.rest()[v as usize] - p[30]).norm() <= 1.2 * 0.5);
        }
    }

    #[test]
    fn stragglers_and_lines_far_apart_get_helper_pieces_that_overlap_nothing() {
        // A group, a pair, a line of four and a lone agent, all far apart, with the
        // line passing close by the pair.
        let mut p = jittered(16, Vec2::zeros(), 8);
        p.extend([Vec2::new(6.0, 0.0), Vec2::new(6.3, 0.1)]);
        p.extend((0..4).map(|k| Vec2::new(6.0 + 0.5 * k as f64, 2.0)));
        p.push(Vec2::new(-6.0, 5.0));
        let (mesh, _) = check(&p);
        assert_eq!(mesh.piece_count(), 4);
        // Every agent is inside exactly the triangles of its own piece: no two
        // pieces overlap (each triangle's centroid lies in no other piece).
        let r = mesh.rest();
        for (ti, t) in mesh.triangles().iter().enumerate() {
            let c = t.iter().map(|&v| r[v as usize]).sum::<Vec2>() / 3.0;
            let piece = mesh.piece_of_vertex()[t[0] as usize];
            for (tj, u) in mesh.triangles().iter().enumerate() {
                if ti == tj || mesh.piece_of_vertex()[u[0] as usize] == piece {
                    continue;
                }
                let [a, b, d] = u.map(|v| r[v as usize]);
                let inside = cross(b - a, c - a) > 0.0
                    && cross(d - b, c - b) > 0.0
                    && cross(a - d, c - d) > 0.0;
                assert!(!inside, "triangle {ti} overlaps {tj}");
            }
        }
    }

    #[test]
    fn a_group_ringed_by_another_is_joined_to_it() {
        // A ring of agents around a small group: the ring alone would be a piece
        // with a hole, so the two are merged into one disc.
        let mut p: Vec<Vec2> = (0..40)
            .map(|k| {
                let a = k as f64 / 40.0 * std::f64::consts::TAU;
                Vec2::new(a.cos(), a.sin()) * 3.2
            })
            .collect();
        p.extend(jittered(9, Vec2::new(-0.5, -0.5), 9));
        let (mesh, _) = check(&p);
        assert_eq!(mesh.piece_count(), 1);
    }

    #[test]
    fn degenerate_crowds_get_helpers_and_duplicates_share_a_vertex() {
        for p in [
            vec![Vec2::new(1.0, 2.0)],
            vec![Vec2::new(1.0, 2.0), Vec2::new(1.0, 2.0)],
            vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.5)],
            (0..7)
                .map(|k| Vec2::new(k as f64 * 0.4, k as f64 * 0.2))
                .collect(),
        ] {
            let (mesh, samples) = check(&p);
            let distinct = if p.len() == 2 && p[0] == p[1] {
                1
            } else {
                p.len()
            };
            assert_eq!(mesh.vertex_count(), distinct + 2, "{p:?}");
            assert_eq!(samples.len(), p.len());
        }
        let mut p = jittered(20, Vec2::zeros(), 5);
        p.push(p[3]);
        p.push(p[7]);
        let (mesh, _) = check(&p);
        assert_eq!(mesh.vertex_count(), 20);
    }

    #[test]
    fn bad_input_is_refused() {
        assert_eq!(mesh_around(&[], 0.15).unwrap_err(), MeshError::Empty);
        let p = [Vec2::zeros(), Vec2::new(f64::NAN, 1.0), Vec2::new(1.0, 1.0)];
        assert_eq!(
            mesh_around(&p, 0.15).unwrap_err(),
            MeshError::NonFinite { vertex: 1 }
        );
        // A bad radius is ignored, not fatal.
        check(&jittered(9, Vec2::zeros(), 6));
        assert!(mesh_around(&jittered(9, Vec2::zeros(), 6), f64::NAN).is_ok());
    }

    #[test]
    fn arap_with_a_point_constraint_on_one_piece_deforms_it() {
        let mut p = jittered(25, Vec2::zeros(), 1);
        p.extend(jittered(25, Vec2::new(8.0, 0.5), 2));
        let (mesh, samples) = check(&p);
        let mut arap = Arap::new(&mesh);
        // Hold agent 0 by its vertex; pull agent 24 (the far corner of the same
        // group) through a point constraint at its goal sample, 1 m further out.
        let s = samples[24];
        let corners = mesh.triangles()[s.tri as usize];
        arap.set_constraints_and_points(
            &[Constraint {
                vertex: 0,
                weight: 1000.0,
            }],
            &[PointConstraint {
                corners,
                bary: s.bary,
                weight: 1000.0,
            }],
        )
        .unwrap();
        let d = (p[24] - p[0]).normalize();
        let targets = [p[0], p[24] + d];
        let mut out = vec![Vec2::zeros(); mesh.vertex_count()];
        arap.solve(&targets, mesh.rest(), &mut out).unwrap();
        let mut goals = Vec::new();
        goal_positions(&mesh, &samples, &out, &mut goals);
        assert!((goals[0] - p[0]).norm() < 0.05, "{:?}", goals[0]);
        assert!((goals[24] - targets[1]).norm() < 0.05, "{:?}", goals[24]);
        // The piece between the hands stretches: not a rigid motion.
        let (before, after) = ((p[12] - p[0]).norm(), (goals[12] - goals[0]).norm());
        assert!(after > before + 0.2, "{before} -> {after}");
        assert!(goals.iter().all(|q| q.x.is_finite() && q.y.is_finite()));
    }

    #[test]
    fn parts_stay_pieces_of_their_own_and_a_straggler_joins_its_part() {
        let grid = |x0: f64| -> Vec<Vec2> {
            (0..16)
                .map(|k| Vec2::new(x0 + (k % 4) as f64 * 0.5, (k / 4) as f64 * 0.5))
                .collect()
        };
        // Two blocks 0.6 m apart (one piece for mesh_around), and a straggler.
        let mut pts = grid(0.0);
        pts.extend(grid(2.1));
        pts.push(Vec2::new(-4.0, 0.0));
        let (joined, _) = mesh_around(&pts, 0.1).unwrap();
        assert_eq!(
            joined.piece_count(),
            2,
            "the blocks join, the straggler is alone"
        );
        let mut first: Vec<usize> = (0..16).collect();
        first.push(32);
        let parts = vec![first, (16..32).collect()];
        let (mesh, goals) = mesh_around_parts(&pts, &parts, 0.1, 5).unwrap();
        assert_eq!(mesh.piece_count(), 2);
        assert_eq!(goals.len(), 33);
        let at = |g: &GoalSample| {
            let t = mesh.triangles()[g.tri as usize];
            (0..3)
                .map(|k| mesh.rest()[t[k] as usize] * g.bary[k])
                .sum::<Vec2>()
        };
        for i in 0..32 {
            assert!((at(&goals[i]) - pts[i]).norm() < 1e-9, "agent {i} stays");
        }
        let g = at(&goals[32]);
        assert!(
            (g - Vec2::new(-0.5, 0.0)).norm() < 1e-9,
            "the straggler is drawn in: {g:?}"
        );
        let pieces: std::collections::BTreeSet<u32> = (0..33)
            .map(|i| mesh.piece_of_vertex()[mesh.triangles()[goals[i].tri as usize][0] as usize])
            .collect();
        assert_eq!(pieces.len(), 2);
        assert!(
            mesh_around_parts(&pts, &[(0..32).collect()], 0.1, 5).is_err(),
            "an agent left out"
        );
        // A pair of stragglers joins as a pair, keeping its own spacing.
        let mut pair = grid(0.0);
        pair.extend([Vec2::new(-4.0, 0.0), Vec2::new(-4.5, 0.0)]);
        let (mesh, goals) = mesh_around_parts(&pair, &[(0..18).collect()], 0.1, 5).unwrap();
        assert_eq!(mesh.piece_count(), 1, "the pair joins its part");
        let at = |g: &GoalSample| {
            let t = mesh.triangles()[g.tri as usize];
            (0..3)
                .map(|k| mesh.rest()[t[k] as usize] * g.bary[k])
                .sum::<Vec2>()
        };
        let (a, b) = (at(&goals[16]), at(&goals[17]));
        assert!((a - Vec2::new(-0.5, 0.0)).norm() < 1e-9, "{a:?}");
        assert!(
            ((a - b).norm() - 0.5).abs() < 1e-9,
            "the pair keeps its shape"
        );
    }
}
