//! The plane region a formation covers: pieces, each an outline with holes, and the
//! geometry every formation needs of it: validation (simple rings that neither cross
//! nor touch, holes inside their outline and apart, pieces apart), inside tests and
//! the nearest boundary point, both through a grid of cells over the region so a
//! query costs about the edges of one cell instead of all of them (sampling asks
//! thousands of times per relaxation step, section 3.1 of formation-transform).

use crate::geom::{cross, nearest_on_segment, twice_signed_area, Vec2};

/// Which ring of a definition a problem is in.
#[derive(Copy, Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Ring {
    /// Piece `p`'s outline (piece 0 is the definition's `outline`).
    Outline(usize),
    /// Hole `h` of piece `p`.
    Hole(usize, usize),
}

impl std::fmt::Display for Ring {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Ring::Outline(0) => write!(f, "outline"),
            Ring::Outline(p) => write!(f, "piece {p}'s outline"),
            Ring::Hole(0, h) => write!(f, "hole {h}"),
            Ring::Hole(p, h) => write!(f, "piece {p}'s hole {h}"),
        }
    }
}

/// One piece: an outline (counter-clockwise) and its holes (clockwise).
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Outer boundary, counter-clockwise.
    pub outline: Vec<Vec2>,
    /// Holes, each clockwise, inside the outline.
    pub holes: Vec<Vec<Vec2>>,
}

/// A geometric problem found by [`check`].
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Problem {
    Repeated {
        ring: Ring,
        a: usize,
        b: usize,
    },
    SelfIntersecting {
        ring: Ring,
        a: usize,
        b: usize,
    },
    NoArea {
        ring: Ring,
    },
    RingsCross {
        a: Ring,
        edge_a: usize,
        b: Ring,
        edge_b: usize,
    },
    HoleOutside {
        hole: Ring,
    },
    HolesNested {
        inner: Ring,
        outer: Ring,
    },
    PiecesOverlap {
        a: usize,
        b: usize,
    },
}

/// Whether closed segments `ab` and `cd` share a point.
pub(crate) fn segments_touch(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
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

/// Whether `p` is strictly inside the ring (even-odd rule).
pub(crate) fn inside_ring(poly: &[Vec2], p: Vec2) -> bool {
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

/// Whether `p` is inside piece `k`: in its outline and in none of its holes.
fn inside_piece(k: &Piece, p: Vec2) -> bool {
    inside_ring(&k.outline, p) && !k.holes.iter().any(|h| inside_ring(h, p))
}

/// Every ring with its name, in order: outline, holes, for each piece.
pub(crate) fn rings(pieces: &[Piece]) -> impl Iterator<Item = (Ring, &[Vec2])> {
    pieces.iter().enumerate().flat_map(|(p, k)| {
        std::iter::once((Ring::Outline(p), k.outline.as_slice())).chain(
            k.holes
                .iter()
                .enumerate()
                .map(move |(h, r)| (Ring::Hole(p, h), r.as_slice())),
        )
    })
}

/// Checks rings already known to be finite, of 3 or more vertices, scaled to an
/// extent near 1 (so the exact tests and the area threshold do not depend on where
/// or how large the shape was drawn). Orientation is free. Returns the first
/// problem in ring order.
///
/// # Complexity
/// `O(V log V)` for repeated vertices; the crossing test sweeps edges by `x`, so
/// `O(E log E + K)` with `K` the pairs whose `x` ranges overlap.
pub(crate) fn check(pieces: &[Piece]) -> Result<(), Problem> {
    let all: Vec<(Ring, &[Vec2])> = rings(pieces).collect();
    // Repeated vertices, within a ring (Repeated) or across (rings touch).
    let mut verts: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (r, (_, ring)) in all.iter().enumerate() {
        verts.extend(ring.iter().enumerate().map(|(i, p)| (p.x, p.y, r, i)));
    }
    verts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut first: Option<Problem> = None;
    let keep = |p: Problem, first: &mut Option<Problem>| {
        if first.as_ref().is_none_or(|f| order(&p) < order(f)) {
            *first = Some(p);
        }
    };
    for w in verts.windows(2) {
        if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
            let (a, b) = if (w[0].2, w[0].3) < (w[1].2, w[1].3) {
                (w[0], w[1])
            } else {
                (w[1], w[0])
            };
            let p = if a.2 == b.2 {
                Problem::Repeated {
                    ring: all[a.2].0,
                    a: a.3,
                    b: b.3,
                }
            } else {
                Problem::RingsCross {
                    a: all[a.2].0,
                    edge_a: a.3,
                    b: all[b.2].0,
                    edge_b: b.3,
                }
            };
            keep(p, &mut first);
        }
    }
    if let Some(p) = first {
        return Err(p);
    }
    // Edge crossings: a sweep over x.
    let mut edges: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (r, (_, ring)) in all.iter().enumerate() {
        let n = ring.len();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            edges.push((a.x.min(b.x), a.x.max(b.x), r, i));
        }
    }
    edges.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (k, e) in edges.iter().enumerate() {
        let ring_e = all[e.2].1;
        let ne = ring_e.len();
        let (p0, p1) = (ring_e[e.3], ring_e[(e.3 + 1) % ne]);
        for f in &edges[k + 1..] {
            if f.0 > e.1 {
                break;
            }
            let ring_f = all[f.2].1;
            let nf = ring_f.len();
            let (q0, q1) = (ring_f[f.3], ring_f[(f.3 + 1) % nf]);
            if p0.y.max(p1.y) < q0.y.min(q1.y) || q0.y.max(q1.y) < p0.y.min(p1.y) {
                continue;
            }
            let hit = if e.2 == f.2 {
                let (a, b) = (e.3.min(f.3), e.3.max(f.3));
                let adjacent = b == a + 1 || (a == 0 && b == ne - 1);
                if adjacent {
                    // Neighbours meet at their shared vertex; the far end of one
                    // must not lie on the other.
                    let (pa0, pa1) = (ring_e[a], ring_e[(a + 1) % ne]);
                    let (pb1, pb0) = (ring_e[(b + 1) % ne], ring_e[b]);
                    let (shared, far_a, far_b) = if b == a + 1 {
                        (pa1, pa0, pb1)
                    } else {
                        (pa0, pa1, pb0)
                    };
                    let on = |s: Vec2, e: Vec2, r: Vec2| {
                        cross(e - s, r - s) == 0.0 && (r - s).dot(&(e - s)) > 0.0
                    };
                    on(shared, far_a, far_b) || on(shared, far_b, far_a)
                } else {
                    segments_touch(p0, p1, q0, q1)
                }
            } else {
                segments_touch(p0, p1, q0, q1)
            };
            if hit {
                let ((ra, ea), (rb, eb)) = if (e.2, e.3) < (f.2, f.3) {
                    ((e.2, e.3), (f.2, f.3))
                } else {
                    ((f.2, f.3), (e.2, e.3))
                };
                let p = if ra == rb {
                    Problem::SelfIntersecting {
                        ring: all[ra].0,
                        a: ea,
                        b: eb,
                    }
                } else {
                    Problem::RingsCross {
                        a: all[ra].0,
                        edge_a: ea,
                        b: all[rb].0,
                        edge_b: eb,
                    }
                };
                keep(p, &mut first);
            }
        }
    }
    if let Some(p) = first {
        return Err(p);
    }
    for (ring, r) in &all {
        let a2 = twice_signed_area(r);
        if a2.is_nan() || a2.abs() <= 1e-9 {
            return Err(Problem::NoArea { ring: *ring });
        }
    }
    // No ring crosses another, so one vertex tells on which side a ring lies.
    for (p, k) in pieces.iter().enumerate() {
        for (h, hole) in k.holes.iter().enumerate() {
            if !inside_ring(&k.outline, hole[0]) {
                return Err(Problem::HoleOutside {
                    hole: Ring::Hole(p, h),
                });
            }
            for (g, other) in k.holes.iter().enumerate() {
                if g != h && inside_ring(other, hole[0]) {
                    return Err(Problem::HolesNested {
                        inner: Ring::Hole(p, h),
                        outer: Ring::Hole(p, g),
                    });
                }
            }
        }
    }
    for (a, ka) in pieces.iter().enumerate() {
        for (b, kb) in pieces.iter().enumerate() {
            if a != b && inside_piece(ka, kb.outline[0]) {
                return Err(Problem::PiecesOverlap {
                    a: a.min(b),
                    b: a.max(b),
                });
            }
        }
    }
    Ok(())
}

/// Sort key for "the first problem": by ring, then position.
fn order(p: &Problem) -> (Ring, usize, usize) {
    match *p {
        Problem::Repeated { ring, a, b } | Problem::SelfIntersecting { ring, a, b } => (ring, a, b),
        Problem::RingsCross { a, edge_a, .. } => (a, edge_a, usize::MAX),
        _ => (Ring::Outline(usize::MAX), 0, 0),
    }
}

/// Twice the signed area of every ring together (holes, clockwise, count negative)
/// and the area centroid's numerator `Σ (u + v) · (u × v)`.
pub(crate) fn area_and_moment(pieces: &[Piece]) -> (f64, Vec2) {
    let (mut a2, mut m) = (0.0, Vec2::zeros());
    for (_, r) in rings(pieces) {
        let n = r.len();
        for i in 0..n {
            let (u, v) = (r[i], r[(i + 1) % n]);
            let c = cross(u, v);
            a2 += c;
            m += (u + v) * c;
        }
    }
    (a2, m)
}

/// Cells per side of the index grid at most.
const MAX_CELLS: usize = 128;

/// A grid of cells over a region's bounding box; each cell lists the boundary edges
/// whose bounding box meets it, and whether its centre is inside.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RegionIndex {
    edges: Vec<(Vec2, Vec2)>,
    lo: Vec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
    /// Per cell, a reference point away from every edge, and whether it is inside.
    refs: Vec<Vec2>,
    centre_inside: Vec<bool>,
}

impl RegionIndex {
    /// Indexes the boundary of `pieces` (valid, non-empty).
    pub(crate) fn new(pieces: &[Piece]) -> RegionIndex {
        let mut edges = Vec::new();
        for (_, r) in rings(pieces) {
            let n = r.len();
            edges.extend((0..n).map(|i| (r[i], r[(i + 1) % n])));
        }
        let (mut lo, mut hi) = (edges[0].0, edges[0].0);
        for (a, _) in &edges {
            lo = lo.inf(a);
            hi = hi.sup(a);
        }
        let ext = hi - lo;
        let side = ((edges.len() as f64).sqrt().ceil() as usize).clamp(4, MAX_CELLS);
        let cell = (ext.x.max(ext.y) / side as f64).max(1e-12) * 1.000_001;
        let nx = ((ext.x / cell).floor() as usize + 1).min(MAX_CELLS + 1);
        let ny = ((ext.y / cell).floor() as usize + 1).min(MAX_CELLS + 1);
        let mut count = vec![0u32; nx * ny + 1];
        let span = |a: Vec2, b: Vec2| {
            let c =
                |v: f64, o: f64, n: usize| (((v - o) / cell).floor().max(0.0) as usize).min(n - 1);
            (
                c(a.x.min(b.x), lo.x, nx),
                c(a.x.max(b.x), lo.x, nx),
                c(a.y.min(b.y), lo.y, ny),
                c(a.y.max(b.y), lo.y, ny),
            )
        };
        for &(a, b) in &edges {
            let (x0, x1, y0, y1) = span(a, b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    count[y * nx + x + 1] += 1;
                }
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let start = count.clone();
        let mut fill = count;
        let mut items = vec![0u32; start[nx * ny] as usize];
        for (k, &(a, b)) in edges.iter().enumerate() {
            let (x0, x1, y0, y1) = span(a, b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    items[fill[y * nx + x] as usize] = k as u32;
                    fill[y * nx + x] += 1;
                }
            }
        }
        // Centre status row by row: the crossings of the row's centre line.
        let mut centre_inside = vec![false; nx * ny];
        let mut xs = Vec::new();
        for y in 0..ny {
            let cy = lo.y + (y as f64 + 0.5) * cell;
            xs.clear();
            for &(a, b) in &edges {
                if (a.y > cy) != (b.y > cy) {
                    xs.push(a.x + (cy - a.y) / (b.y - a.y) * (b.x - a.x));
                }
            }
            xs.sort_by(f64::total_cmp);
            for x in 0..nx {
                let cx = lo.x + (x as f64 + 0.5) * cell;
                let right = xs.len() - xs.partition_point(|&v| v <= cx);
                centre_inside[y * nx + x] = right % 2 == 1;
            }
        }
        // A centre (almost) on an edge would make the two side tests disagree: such
        // a cell takes another reference point, its side found by a full ray cast.
        let mut refs = Vec::with_capacity(nx * ny);
        const OFFSETS: [(f64, f64); 5] = [
            (0.0, 0.0),
            (0.23, 0.31),
            (-0.29, 0.19),
            (0.17, -0.27),
            (-0.21, -0.33),
        ];
        for y in 0..ny {
            for x in 0..nx {
                let c = lo + Vec2::new((x as f64 + 0.5) * cell, (y as f64 + 0.5) * cell);
                let list = &items[start[y * nx + x] as usize..start[y * nx + x + 1] as usize];
                let clear = |q: Vec2| {
                    list.iter().all(|&e| {
                        let (a, b) = edges[e as usize];
                        (nearest_on_segment(a, b, q).0 - q).norm() > 1e-6 * cell
                    })
                };
                let pick = OFFSETS
                    .iter()
                    .map(|&(dx, dy)| c + Vec2::new(dx, dy) * cell)
                    .find(|&q| clear(q))
                    .unwrap_or(c);
                if pick != c {
                    let mut inside = false;
                    for &(a, b) in &edges {
                        if (a.y > pick.y) != (b.y > pick.y)
                            && pick.x < a.x + (pick.y - a.y) / (b.y - a.y) * (b.x - a.x)
                        {
                            inside = !inside;
                        }
                    }
                    centre_inside[y * nx + x] = inside;
                }
                refs.push(pick);
            }
        }
        RegionIndex {
            edges,
            lo,
            cell,
            nx,
            ny,
            start,
            items,
            refs,
            centre_inside,
        }
    }

    fn cell_of(&self, p: Vec2) -> Option<(usize, usize)> {
        let x = ((p.x - self.lo.x) / self.cell).floor();
        let y = ((p.y - self.lo.y) / self.cell).floor();
        if x >= 0.0 && y >= 0.0 && (x as usize) < self.nx && (y as usize) < self.ny {
            Some((x as usize, y as usize))
        } else {
            None
        }
    }

    fn cell_edges(&self, x: usize, y: usize) -> &[u32] {
        let k = y * self.nx + x;
        &self.items[self.start[k] as usize..self.start[k + 1] as usize]
    }

    /// Whether `p` is inside the region (even-odd over every ring). `O(edges in
    /// one cell)`.
    pub(crate) fn inside(&self, p: Vec2) -> bool {
        let Some((x, y)) = self.cell_of(p) else {
            return false;
        };
        let c = self.refs[y * self.nx + x];
        let mut inside = self.centre_inside[y * self.nx + x];
        for &e in self.cell_edges(x, y) {
            let (a, b) = self.edges[e as usize];
            if proper_cross(c, p, a, b) {
                inside = !inside;
            }
        }
        inside
    }

    /// The boundary point nearest to `p` and its distance. Searches rings of cells
    /// outwards from `p`'s cell until no nearer edge can be farther out.
    pub(crate) fn nearest_boundary(&self, p: Vec2) -> (Vec2, f64) {
        let fx = ((p.x - self.lo.x) / self.cell).floor();
        let fy = ((p.y - self.lo.y) / self.cell).floor();
        let (cx, cy) = (
            fx.clamp(0.0, (self.nx - 1) as f64) as i64,
            fy.clamp(0.0, (self.ny - 1) as f64) as i64,
        );
        // A cell in ring r around p's (clamped) cell is at least (r - 1) cells
        // from p; an edge's nearest point lies in a cell the edge is listed in.
        let (mut best, mut best_d) = (self.edges[0].0, f64::INFINITY);
        let max_r = self.nx.max(self.ny) as i64;
        for r in 0..=max_r {
            if best_d <= (r as f64 - 1.0) * self.cell {
                break;
            }
            for y in cy - r..=cy + r {
                if y < 0 || y >= self.ny as i64 {
                    continue;
                }
                for x in cx - r..=cx + r {
                    if x < 0 || x >= self.nx as i64 {
                        continue;
                    }
                    if (y - cy).abs() != r && (x - cx).abs() != r {
                        continue;
                    }
                    for &e in self.cell_edges(x as usize, y as usize) {
                        let (a, b) = self.edges[e as usize];
                        let q = nearest_on_segment(a, b, p).0;
                        let d = (q - p).norm();
                        if d < best_d {
                            best_d = d;
                            best = q;
                        }
                    }
                }
            }
        }
        (best, best_d)
    }

    /// Bounding box `(lo, hi)` of the region.
    pub(crate) fn bounds(&self) -> (Vec2, Vec2) {
        (
            self.lo,
            self.lo + Vec2::new(self.nx as f64, self.ny as f64) * self.cell,
        )
    }
}

/// Whether segments `pq` and `ab` cross at a single interior point of `pq`'s
/// half-open span (for parity counting: an endpoint of `ab` on the line counts on
/// one side only).
fn proper_cross(p: Vec2, q: Vec2, a: Vec2, b: Vec2) -> bool {
    let d1 = cross(q - p, a - p);
    let d2 = cross(q - p, b - p);
    if (d1 > 0.0) == (d2 > 0.0) {
        return false;
    }
    let d3 = cross(b - a, p - a);
    let d4 = cross(b - a, q - a);
    (d3 > 0.0) != (d4 > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(pts: &[(f64, f64)]) -> Vec<Vec2> {
        pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
    }

    #[test]
    fn the_index_agrees_with_the_plain_tests() {
        let k = Piece {
            outline: ring(&[(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (2.0, 1.0), (0.0, 3.0)]),
            holes: vec![ring(&[(1.0, 0.5), (1.0, 0.8), (3.0, 0.8), (3.0, 0.5)])],
        };
        let pieces = [k.clone()];
        let idx = RegionIndex::new(&pieces);
        let mut rng = crate::rng::SplitMix64::new(3);
        for _ in 0..20_000 {
            let p = Vec2::new(rng.uniform(-1.0, 5.0), rng.uniform(-1.0, 4.0));
            assert_eq!(idx.inside(p), inside_piece(&k, p), "{p:?}");
            let brute = rings(&pieces)
                .flat_map(|(_, r)| {
                    let n = r.len();
                    (0..n).map(move |i| (nearest_on_segment(r[i], r[(i + 1) % n], p).0 - p).norm())
                })
                .fold(f64::INFINITY, f64::min);
            assert!((idx.nearest_boundary(p).1 - brute).abs() < 1e-12, "{p:?}");
        }
    }
}
