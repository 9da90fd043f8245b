//! Holes in a formation mesh, made acceptable to [`TriMesh`], whose pieces each have
//! one boundary loop: every hole is joined to the piece's outer boundary by a seam,
//! a path of mesh edges whose vertices are doubled, the triangles on its left taking
//! the copies. The mesh keeps its shape and triangles (no triangle in the hole); the
//! two sides of a seam are at the same place but not joined, so a piece with holes
//! becomes a piece with one (longer) boundary loop.

use crate::geom::{twice_signed_area, Vec2};
use std::collections::{HashMap, VecDeque};

/// Boundary loops (directed edges whose reverse is absent, followed head to tail).
/// The triangle holding each directed edge `(from, to)`.
type EdgeTriangles = HashMap<(u32, u32), usize>;

fn loops(triangles: &[[u32; 3]]) -> (Vec<Vec<u32>>, EdgeTriangles) {
    let mut tri_of = HashMap::with_capacity(triangles.len() * 3);
    for (t, tr) in triangles.iter().enumerate() {
        for k in 0..3 {
            tri_of.insert((tr[k], tr[(k + 1) % 3]), t);
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in tri_of.keys() {
        if !tri_of.contains_key(&(b, a)) {
            next.insert(a, b);
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut ring = Vec::new();
        let mut v = s;
        while seen.insert(v) {
            ring.push(v);
            match next.get(&v) {
                Some(&n) => v = n,
                None => break,
            }
        }
        out.push(ring);
    }
    (out, tri_of)
}

/// Cuts every hole (a clockwise boundary loop) open to another boundary loop.
/// Returns `false` when some hole has no path of interior vertices to another loop
/// (the mesh is then left as it is).
pub(crate) fn cut_holes(rest: &mut Vec<Vec2>, triangles: &mut [[u32; 3]]) -> bool {
    // Each cut removes one hole loop; bounded by the number of loops.
    for _ in 0..=triangles.len() {
        let (rings, tri_of) = loops(triangles);
        let pos = |r: &[u32]| r.iter().map(|&v| rest[v as usize]).collect::<Vec<_>>();
        let Some(hole) = rings.iter().position(|r| twice_signed_area(&pos(r)) < 0.0) else {
            return true;
        };
        let mut on_loop: HashMap<u32, usize> = HashMap::new();
        for (i, r) in rings.iter().enumerate() {
            for &v in r {
                on_loop.insert(v, i);
            }
        }
        // Breadth-first from the hole's vertices over interior edges, through
        // interior vertices, to a vertex of another loop.
        let mut prev: HashMap<u32, u32> = HashMap::new();
        let mut queue: VecDeque<u32> = rings[hole].iter().copied().collect();
        for &v in &rings[hole] {
            prev.insert(v, v);
        }
        let mut adj: HashMap<u32, Vec<u32>> = HashMap::new();
        for &(a, b) in tri_of.keys() {
            if tri_of.contains_key(&(b, a)) {
                adj.entry(a).or_default().push(b);
            }
        }
        for l in adj.values_mut() {
            l.sort_unstable();
        }
        let mut end = None;
        'bfs: while let Some(v) = queue.pop_front() {
            if on_loop.get(&v).is_some_and(|&l| l != hole) {
                end = Some(v);
                break;
            }
            if v != prev[&v] && on_loop.contains_key(&v) {
                continue;
            }
            for &w in adj.get(&v).map(Vec::as_slice).unwrap_or(&[]) {
                if prev.contains_key(&w) {
                    continue;
                }
                prev.insert(w, v);
                if on_loop.get(&w).is_some_and(|&l| l != hole) {
                    end = Some(w);
                    break 'bfs;
                }
                if !on_loop.contains_key(&w) {
                    queue.push_back(w);
                }
            }
        }
        let Some(end) = end else {
            return false;
        };
        let mut path = vec![end];
        while prev[path.last().unwrap_or(&end)] != *path.last().unwrap_or(&end) {
            let p = prev[path.last().unwrap_or(&end)];
            path.push(p);
        }
        path.reverse(); // hole vertex first
                        // The triangles on the left of the path at each of its vertices take a copy.
        let corner = |t: usize, v: u32| triangles[t].iter().position(|&x| x == v);
        let mut retag: Vec<(usize, u32, u32)> = Vec::new();
        let k = path.len() - 1;
        for i in 0..=k {
            let v = path[i];
            let copy = rest.len() as u32;
            rest.push(rest[v as usize]);
            let mut fan = Vec::new();
            if i < k {
                // Counter-clockwise from the left of v → next, to the previous path
                // vertex or the boundary.
                let mut t = tri_of.get(&(v, path[i + 1])).copied();
                while let Some(tt) = t {
                    fan.push(tt);
                    let Some(c) = corner(tt, v) else { break };
                    let last = triangles[tt][(c + 2) % 3];
                    if i > 0 && last == path[i - 1] {
                        break;
                    }
                    t = tri_of.get(&(v, last)).copied();
                    if fan.len() > triangles.len() {
                        return false;
                    }
                }
            } else {
                // The end: clockwise from the left of prev → v to the boundary.
                let mut t = tri_of.get(&(path[i - 1], v)).copied();
                while let Some(tt) = t {
                    fan.push(tt);
                    let Some(c) = corner(tt, v) else { break };
                    let after = triangles[tt][(c + 1) % 3];
                    t = tri_of.get(&(after, v)).copied();
                    if fan.len() > triangles.len() {
                        return false;
                    }
                }
            }
            retag.extend(fan.into_iter().map(|t| (t, v, copy)));
        }
        for (t, v, copy) in retag {
            for x in triangles[t].iter_mut() {
                if *x == v {
                    *x = copy;
                }
            }
        }
    }
    false
}
