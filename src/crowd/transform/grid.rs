//! A uniform grid over the agents for the transform's neighbour queries: pairs
//! within a radius (forces, overlap resolution, overlap counting) and each agent's
//! nearest neighbour by a ring search (`σ_min_dis`, formation-transform eq. 24).
//! Rebuilt in place each step by a counting sort; no allocation once its buffers
//! have the crowd's size (they are reserved in [`Grid::with_capacity`]).

use crate::geom::Vec2;

/// Most cells per agent; a sparse crowd gets coarser cells instead of more.
const MAX_CELLS_PER_AGENT: usize = 4;

/// Agents bucketed into square cells.
#[derive(Clone, Debug, Default)]
pub(crate) struct Grid {
    origin: Vec2,
    cell_m: f64,
    nx: usize,
    ny: usize,
    cell_start: Vec<u32>,
    items: Vec<u32>,
    cell_of: Vec<u32>,
}

impl Grid {
    /// A grid for `n` agents with every buffer reserved.
    pub(crate) fn with_capacity(n: usize) -> Grid {
        let cells = (MAX_CELLS_PER_AGENT * n).max(16) + 1;
        Grid {
            cell_start: Vec::with_capacity(cells),
            items: Vec::with_capacity(n),
            cell_of: Vec::with_capacity(n),
            ..Grid::default()
        }
    }

    /// Side of a cell (m), at least the `cell_m` asked of [`build`](Self::build).
    pub(crate) fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// Buckets `pos` into cells of at least `cell_m` metres. Non-finite positions
    /// leave the grid empty.
    pub(crate) fn build(&mut self, pos: &[Vec2], cell_m: f64) {
        let n = pos.len();
        let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
        for p in pos {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        self.items.clear();
        self.cell_of.clear();
        self.cell_start.clear();
        if n == 0 || !(lo.x.is_finite() && lo.y.is_finite() && hi.x.is_finite() && hi.y.is_finite())
        {
            self.nx = 0;
            self.ny = 0;
            return;
        }
        let ext = hi - lo;
        let mut cell = cell_m.max(1e-6);
        let max_cells = (MAX_CELLS_PER_AGENT * n).max(16);
        while ((ext.x / cell) as usize + 1) * ((ext.y / cell) as usize + 1) > max_cells {
            cell *= 2.0;
        }
        self.origin = lo;
        self.cell_m = cell;
        self.nx = (ext.x / cell) as usize + 1;
        self.ny = (ext.y / cell) as usize + 1;
        let cells = self.nx * self.ny;
        self.cell_start.resize(cells + 1, 0);
        for p in pos {
            let c = self.cell_index(*p);
            self.cell_of.push(c as u32);
            self.cell_start[c + 1] += 1;
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.items.resize(n, 0);
        for (i, &c) in self.cell_of.iter().enumerate() {
            let slot = self.cell_start[c as usize];
            self.items[slot as usize] = i as u32;
            self.cell_start[c as usize] += 1;
        }
        for c in (1..=cells).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
    }

    fn cell_xy(&self, p: Vec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell_m;
        let cx = (q.x.max(0.0) as usize).min(self.nx - 1);
        let cy = (q.y.max(0.0) as usize).min(self.ny - 1);
        (cx, cy)
    }

    fn cell_index(&self, p: Vec2) -> usize {
        let (cx, cy) = self.cell_xy(p);
        cy * self.nx + cx
    }

    fn cell_items(&self, c: usize) -> &[u32] {
        &self.items[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    /// Calls `f(i, j, distance, unit vector from j to i)` once for every pair closer
    /// than `radius` (at most the cell side), `pos` being the positions the grid was
    /// built on. Coincident agents get a direction fixed by their indices.
    pub(crate) fn for_each_pair(
        &self,
        pos: &[Vec2],
        radius: f64,
        mut f: impl FnMut(usize, usize, f64, Vec2),
    ) {
        self.for_each_pair_d2(pos, radius, |i, j, d, d2| {
            let dist = d2.sqrt();
            f(i, j, dist, unit_or_fixed(d, dist, i, j));
        });
    }

    /// Calls `f(i, j, pos[i] − pos[j], squared distance)` once for every pair closer
    /// than `radius` (at most the cell side), in the order of
    /// [`for_each_pair`](Self::for_each_pair), without a square root: for callers
    /// that need only a cut-off test or the squared distance.
    #[inline]
    pub(crate) fn for_each_pair_d2(
        &self,
        pos: &[Vec2],
        radius: f64,
        mut f: impl FnMut(usize, usize, Vec2, f64),
    ) {
        if self.nx == 0 {
            return;
        }
        let r2 = radius * radius;
        for cy in 0..self.ny {
            for cx in 0..self.nx {
                let c = cy * self.nx + cx;
                let a = self.cell_items(c);
                if a.is_empty() {
                    continue;
                }
                // This cell and the four "forward" neighbours: each pair seen once.
                for (dx, dy) in [(0i64, 0i64), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                    let (ox, oy) = (cx as i64 + dx, cy as i64 + dy);
                    if ox < 0 || oy < 0 || ox >= self.nx as i64 || oy >= self.ny as i64 {
                        continue;
                    }
                    let o = oy as usize * self.nx + ox as usize;
                    let b = self.cell_items(o);
                    for (ai, &i) in a.iter().enumerate() {
                        let i = i as usize;
                        let pi = pos[i];
                        let rest = if o == c { &b[ai + 1..] } else { b };
                        for &j in rest {
                            let j = j as usize;
                            let d = pi - pos[j];
                            let d2 = d.norm_squared();
                            if d2 < r2 {
                                f(i, j, d, d2);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Distance from agent `i` to its nearest other agent (m), by rings of cells
    /// around its own until no closer agent can be farther out; `INFINITY` alone.
    pub(crate) fn nearest_distance(&self, pos: &[Vec2], i: usize) -> f64 {
        if self.nx == 0 {
            return f64::INFINITY;
        }
        let p = pos[i];
        let (cx, cy) = self.cell_xy(p);
        let (cx, cy) = (cx as i64, cy as i64);
        let mut best2 = f64::INFINITY;
        let max_ring = self.nx.max(self.ny) as i64;
        for k in 0..=max_ring {
            // Every agent in ring k is at least (k − 1)·cell away.
            let reach = (k - 1).max(0) as f64 * self.cell_m;
            if reach * reach > best2 {
                break;
            }
            for oy in (cy - k)..=(cy + k) {
                if oy < 0 || oy >= self.ny as i64 {
                    continue;
                }
                let on_edge_row = oy == cy - k || oy == cy + k;
                let mut ox = cx - k;
                while ox <= cx + k {
                    if ox >= 0 && ox < self.nx as i64 {
                        for &j in self.cell_items(oy as usize * self.nx + ox as usize) {
                            if j as usize != i {
                                best2 = best2.min((pos[j as usize] - p).norm_squared());
                            }
                        }
                    }
                    // Inner rows of the ring: only the two end cells.
                    ox += if on_edge_row || k == 0 { 1 } else { 2 * k };
                }
            }
        }
        best2.sqrt()
    }
}

/// `d / dist`, or for coincident agents (`dist ≤ 1e-12`) a unit vector fixed by
/// their indices, opposite for `(i, j)` and `(j, i)`.
#[inline]
pub(crate) fn unit_or_fixed(d: Vec2, dist: f64, i: usize, j: usize) -> Vec2 {
    if dist > 1e-12 {
        d / dist
    } else {
        let a = (i.min(j) as f64) * 2.399963;
        let s = if i < j { 1.0 } else { -1.0 };
        Vec2::new(a.cos(), a.sin()) * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn cloud(n: usize, seed: u64, side: f64) -> Vec<Vec2> {
        let mut r = SplitMix64::new(seed);
        (0..n)
            .map(|_| Vec2::new(r.uniform(0.0, side), r.uniform(0.0, side)))
            .collect()
    }

    #[test]
    fn pairs_and_nearest_match_brute_force() {
        for (seed, side, cell) in [(1, 10.0, 0.7), (2, 40.0, 0.5), (3, 3.0, 2.0)] {
            let pos = cloud(300, seed, side);
            let mut g = Grid::with_capacity(pos.len());
            g.build(&pos, cell);
            let r = g.cell_m().min(cell);
            let mut got = vec![];
            g.for_each_pair(&pos, r, |i, j, _, _| got.push((i.min(j), i.max(j))));
            got.sort();
            let mut want = vec![];
            for i in 0..pos.len() {
                for j in i + 1..pos.len() {
                    if (pos[i] - pos[j]).norm() < r {
                        want.push((i, j));
                    }
                }
            }
            assert_eq!(got, want);
            for i in 0..pos.len() {
                let brute = (0..pos.len())
                    .filter(|&j| j != i)
                    .map(|j| (pos[i] - pos[j]).norm())
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(g.nearest_distance(&pos, i), brute, "agent {i}");
            }
        }
    }

    #[test]
    fn a_lone_agent_has_no_neighbour() {
        let pos = [Vec2::new(1.0, 2.0)];
        let mut g = Grid::with_capacity(1);
        g.build(&pos, 1.0);
        assert_eq!(g.nearest_distance(&pos, 0), f64::INFINITY);
    }
}
