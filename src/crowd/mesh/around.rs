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
//! The mesh is the Delaunay triangulation of the agents (spade) sculpted inwards from
//! its convex hull like a chi-shape (Duckham et al. 2008, "Efficient generation of
//! simple polygons for characterizing the shape of a set of points in the plane"):
//! the boundary triangle behind the longest boundary edge is removed while that edge
//! is longer than [`ALPHA_FACTOR`] times the crowd's spacing (the median
//! nearest-neighbour distance, at least two body radii) and the triangle's third
//! vertex is interior. Removing only such triangles keeps a single disc with a simple
//! boundary loop and every agent on a triangle, which [`TriMesh`] requires (one
//! boundary loop: no holes, no separate pieces).
//!
//! Consequences, chosen deliberately:
//! - An isolated agent keeps the (long) triangles that tie it to the crowd; nobody
//!   is left without a triangle.
//! - Two groups far apart (a split crowd) become two dense pieces joined by a
//!   corridor of long triangles, not two meshes: [`TriMesh`] holds one boundary
//!   loop. ARAP treats the corridor like any triangle, so a hand on one piece
//!   carries the other along rigidly rather than leaving it in place.
//! - Degenerate crowds (one or two distinct positions, all on a line) get two helper
//!   vertices off the line ([`HELPER_OFFSET_FACTOR`]) so a triangle exists; agents at
//!   the same position share a vertex.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use spade::{DelaunayTriangulation, Point2, Triangulation};

use super::goals::GoalSample;
use super::trimesh::{MeshError, TriMesh};
use crate::geom::{cross, Vec2};

/// A boundary edge longer than this many times the crowd's spacing is cut away.
pub const ALPHA_FACTOR: f64 = 3.0;

/// Helper vertices of a degenerate crowd sit this many spacings off its line.
pub const HELPER_OFFSET_FACTOR: f64 = 1.0;

/// Spacing assumed when neither the agents nor `radius_m` give one (m).
const FALLBACK_SPACING_M: f64 = 0.5;

/// A mesh whose vertices are the agents at `positions` (plus helpers for a
/// degenerate crowd), and one goal sample per agent at its own vertex.
///
/// `radius_m` is the agents' body radius: the spacing used for cutting long edges is
/// at least `2 · radius_m` (a non-positive or non-finite radius is ignored).
///
/// # Errors
/// [`MeshError::Empty`] without agents; [`MeshError::NonFinite`] naming the first
/// agent with a NaN or infinite coordinate (or one too large for the triangulation).
///
/// # Complexity
/// O(n log n): the triangulation, then each triangle removed at most once through a
/// heap of boundary edges.
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
    let mut rest: Vec<Vec2> = Vec::with_capacity(positions.len() + 2);
    let agent_vertex: Vec<u32> = positions
        .iter()
        .map(|&p| {
            *index.entry(key(p)).or_insert_with(|| {
                rest.push(p);
                (rest.len() - 1) as u32
            })
        })
        .collect();
    let body = if radius_m.is_finite() && radius_m > 0.0 {
        2.0 * radius_m
    } else {
        0.0
    };
    let mut tris = delaunay(&rest, positions, &agent_vertex)?;
    let nn = median_nearest(&rest, &tris);
    let spacing = nn.unwrap_or(0.0).max(body);
    let spacing = if spacing > 0.0 {
        spacing
    } else {
        FALLBACK_SPACING_M
    };
    if tris.is_empty() {
        // One point or a line: two helpers across it, at the centroid.
        let c = rest.iter().fold(Vec2::zeros(), |a, p| a + p) / rest.len() as f64;
        let far = rest
            .iter()
            .copied()
            .max_by(|a, b| (a - c).norm().total_cmp(&(b - c).norm()))
            .unwrap_or(c);
        let along = if (far - c).norm() > 0.0 {
            (far - c).normalize()
        } else {
            Vec2::new(1.0, 0.0)
        };
        let across = Vec2::new(-along.y, along.x) * (HELPER_OFFSET_FACTOR * spacing);
        if rest.len() == 1 {
            rest.push(c + along * spacing + across * 0.5);
            rest.push(c + across);
        } else {
            rest.push(c + across);
            rest.push(c - across);
        }
        tris = delaunay(&rest, positions, &agent_vertex)?;
    }
    sculpt(&rest, &mut tris, ALPHA_FACTOR * spacing);
    let mesh = TriMesh::from_triangles(rest, tris)?;
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

/// The Delaunay triangles of `rest`, counter-clockwise, as vertex indices.
fn delaunay(
    rest: &[Vec2],
    positions: &[Vec2],
    agent_vertex: &[u32],
) -> Result<Vec<[u32; 3]>, MeshError> {
    let mut dt: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    let mut handle_to_vertex: Vec<u32> = vec![u32::MAX; rest.len()];
    for (v, p) in rest.iter().enumerate() {
        match dt.insert(Point2::new(p.x, p.y)) {
            Ok(h) => handle_to_vertex[h.index()] = v as u32,
            Err(_) => {
                let agent = agent_vertex
                    .iter()
                    .position(|&a| a as usize == v)
                    .unwrap_or(positions.len());
                return Err(MeshError::NonFinite { vertex: agent });
            }
        }
    }
    Ok(dt
        .inner_faces()
        .map(|f| {
            let mut t = f.vertices().map(|h| handle_to_vertex[h.fix().index()]);
            let [a, b, c] = t.map(|v| rest[v as usize]);
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
    fn two_far_groups_give_two_pieces_joined_by_a_thin_corridor() {
        let mut p = jittered(25, Vec2::zeros(), 1);
        p.extend(jittered(25, Vec2::new(8.0, 0.5), 2));
        let (mesh, _) = check(&p);
        assert_eq!(short_pieces(&mesh, ALPHA_FACTOR * 0.5), 2);
        // The corridor: few triangles reach across the gap.
        let r = mesh.rest();
        let across = mesh
            .triangles()
            .iter()
            .filter(|t| {
                let xs = t.map(|v| r[v as usize].x);
                xs.iter().any(|&x| x < 3.0) && xs.iter().any(|&x| x > 7.0)
            })
            .count();
        assert!(
            (1..=4).contains(&across),
            "{across} triangles across the gap"
        );
        // Far less area than the convex hull's.
        assert!(mesh.area() < 2.0 * 4.0 + 2.0 * 4.0 + 6.0, "{}", mesh.area());
    }

    #[test]
    fn an_outlier_keeps_a_triangle() {
        let mut p = jittered(30, Vec2::zeros(), 4);
        p.push(Vec2::new(10.0, 10.0));
        let (mesh, samples) = check(&p);
        let t = mesh.triangles()[samples[30].tri as usize];
        assert!(t.contains(&30));
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
}
