//! [`PointCosts`]: the geometric fast path for costs that come from positions
//! (squared or plain Euclidean distance).
//!
//! They compute entries on demand and find each row's candidate list (its `k`
//! smallest reduced costs, the `k` nearest goals when the prices are equal) by a ring
//! search over a bucket grid of the goals, stopped by a lower bound that accounts for
//! the largest price; the lists are exactly those of a streaming pass over the row,
//! so the sparse solve, its rounds and its dual certificate are
//! unchanged (tested to give the same assignment and work counters as the matrix),
//! without the `rows × cols` matrix.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::candidates::{from_ord_bits, key, ord_bits};
use crate::geom::Vec2;

/// The metric of [`PointCosts`].
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum PointMetric {
    /// `|a - g|²` in m², as [`SquaredDistance`].
    ///
    /// [`SquaredDistance`]: super::SquaredDistance
    #[default]
    Squared,
    /// `|a - g|` in metres, as [`Distance`].
    ///
    /// [`Distance`]: super::Distance
    Euclidean,
}

/// Costs computed from agent and goal positions on demand: entry `(i, j)` is
/// [`SquaredDistance`]'s or [`Distance`]'s, bit for bit, without the matrix.
///
/// This is the solver's geometric fast path: the goals are bucketed on a uniform
/// grid (about [`GOALS_PER_BUCKET`] per bucket), and a row's cheapest reduced costs
/// `c_ij - v_j` are found by visiting buckets in rings around the agent until the
/// ring's distance bound, less the largest column price, exceeds the k-th best found:
/// no column further away can enter (see `PointCosts::select_near`). The lists
/// are therefore exactly those a pass over the full row would give, so the answer,
/// its dual certificate and the warm start are the same as on the matrix.
///
/// # Complexity
/// [`PointCosts::set`] copies the positions into per-axis arrays and buckets the
/// goals (a counting sort; reused, no allocation once grown): `O(agents + goals)`.
/// An entry is `O(1)`; a candidate list visits the buckets within its radius.
///
/// # Example
/// ```
/// use crowdtouch::crowd::assign::{PointCosts, PointMetric, Solver};
/// use crowdtouch::geom::Vec2;
/// let agents = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
/// let goals = [Vec2::new(1.1, 0.0), Vec2::new(-0.1, 0.0)];
/// let mut costs = PointCosts::new(PointMetric::Squared);
/// costs.set(&agents, &goals);
/// let mut solver = Solver::new();
/// assert_eq!(solver.solve_with(&costs).unwrap(), &[1, 0]);
/// assert!(solver.verify_optimal(&costs, 1e-12));
/// ```
///
/// [`SquaredDistance`]: super::SquaredDistance
/// [`Distance`]: super::Distance
#[derive(Clone, Debug, Default)]
pub struct PointCosts {
    pub(super) metric: PointMetric,
    pub(super) ax: Vec<f64>,
    pub(super) ay: Vec<f64>,
    pub(super) gx: Vec<f64>,
    pub(super) gy: Vec<f64>,
    /// Bucket side (world units) and the corner of bucket (0, 0).
    cell: f64,
    origin: (f64, f64),
    /// Buckets along x and y.
    nb: (usize, usize),
    /// Start of each bucket in `order` (`nb.0 * nb.1 + 1` entries).
    pub(super) start: Vec<u32>,
    /// Goal indices grouped by bucket, and their coordinates in that order.
    pub(super) order: Vec<u32>,
    pub(super) bx: Vec<f64>,
    pub(super) by: Vec<f64>,
    /// Whether every position is finite (else the index is not built).
    pub(super) finite: bool,
}

/// Goals per bucket of the [`PointCosts`] index, on average over the goals' bounding
/// box.
pub const GOALS_PER_BUCKET: f64 = 2.0;

/// Largest number of buckets per axis of the [`PointCosts`] index.
const MAX_BUCKETS_PER_AXIS: usize = 1024;

impl PointCosts {
    /// Empty costs with the given metric.
    pub fn new(metric: PointMetric) -> PointCosts {
        PointCosts {
            metric,
            ..PointCosts::default()
        }
    }

    /// The metric.
    pub fn metric(&self) -> PointMetric {
        self.metric
    }

    /// Takes new positions (agents are the rows, goals the columns).
    pub fn set(&mut self, agents: &[Vec2], goals: &[Vec2]) {
        fn axes(xs: &mut Vec<f64>, ys: &mut Vec<f64>, p: &[Vec2]) {
            xs.clear();
            ys.clear();
            xs.extend(p.iter().map(|q| q.x));
            ys.extend(p.iter().map(|q| q.y));
        }
        axes(&mut self.ax, &mut self.ay, agents);
        axes(&mut self.gx, &mut self.gy, goals);
        let fin = |v: &[f64]| v.iter().all(|c| c.is_finite());
        self.finite = fin(&self.ax) && fin(&self.ay) && fin(&self.gx) && fin(&self.gy);
        self.build_index();
    }

    /// Buckets the goals (counting sort) on a grid of square buckets over their
    /// bounding box.
    fn build_index(&mut self) {
        let n = self.gx.len();
        self.start.clear();
        self.order.clear();
        self.bx.clear();
        self.by.clear();
        if !self.finite || n == 0 {
            self.nb = (0, 0);
            return;
        }
        let (mut x0, mut x1, mut y0, mut y1) = (self.gx[0], self.gx[0], self.gy[0], self.gy[0]);
        for (&x, &y) in self.gx.iter().zip(&self.gy) {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        let (w, h) = (x1 - x0, y1 - y0);
        let buckets = (n as f64 / GOALS_PER_BUCKET).max(1.0);
        let mut cell = ((w.max(h * 1e-9) * h.max(w * 1e-9)) / buckets).sqrt();
        if !(cell > 0.0 && cell.is_finite()) {
            cell = 1.0; // every goal at one point
        }
        let axis = |len: f64| ((len / cell).floor() as usize + 1).min(MAX_BUCKETS_PER_AXIS);
        let (nx, ny) = (axis(w), axis(h));
        // With the per-axis cap the buckets may have to grow to cover the box.
        let cell = cell.max(w / (nx as f64 - 0.5)).max(h / (ny as f64 - 0.5));
        self.cell = cell;
        self.origin = (x0, y0);
        self.nb = (nx, ny);
        let bucket = |x: f64, y: f64| {
            let cx = (((x - x0) / cell) as usize).min(nx - 1);
            let cy = (((y - y0) / cell) as usize).min(ny - 1);
            cy * nx + cx
        };
        self.start.resize(nx * ny + 1, 0);
        for (&x, &y) in self.gx.iter().zip(&self.gy) {
            self.start[bucket(x, y) + 1] += 1;
        }
        for b in 1..self.start.len() {
            self.start[b] += self.start[b - 1];
        }
        self.order.resize(n, 0);
        self.bx.resize(n, 0.0);
        self.by.resize(n, 0.0);
        // Fill each bucket from its end down, using `start[b + 1]` as a cursor; the
        // cursors end at the bucket starts.
        for j in (0..n).rev() {
            let b = bucket(self.gx[j], self.gy[j]);
            self.start[b + 1] -= 1;
            let at = self.start[b + 1] as usize;
            self.order[at] = j as u32;
            self.bx[at] = self.gx[j];
            self.by[at] = self.gy[j];
        }
        // Now start[b + 1] is the start of bucket b; shift back by one.
        self.start.rotate_left(1);
        let last = self.start.len() - 1;
        self.start[last] = n as u32;
    }

    /// The `k` smallest [`key`]s `key(c_ij - v_j, j ^ salt)` of row `i` that are at
    /// least `lo`, sorted in `buf[..n]` (returns `n`): the same keys as [`select_k`]
    /// over the full row, found through the bucket index. `v_hi` is an upper bound
    /// of every price `v_j`; `thr0` as in [`select_k`]. Positions must be finite.
    ///
    /// # Proof of exactness
    /// Buckets are visited in Chebyshev rings `r = 0, 1, ...` around the agent's
    /// (clamped) bucket; every goal in ring `r ≥ 1` is at least `(r − 1)·s + m` away
    /// (`s` the bucket side, `m` the agent's distance to its bucket's nearest side,
    /// 0 outside the grid), so its reduced cost is at least `B = f((r − 1)·s + m) −
    /// v_hi` with `f` the metric. Once at least `k` keys are held, all at or below
    /// the admission threshold, and `key(B)` exceeds that threshold, no unvisited
    /// goal can displace them. `B` is shrunk by a relative `1e-9` against rounding.
    ///
    /// [`select_k`]: super::candidates::select_k
    #[allow(clippy::too_many_arguments)]
    pub(super) fn select_near(
        &self,
        i: usize,
        v: &[f64],
        v_hi: f64,
        k: usize,
        mask: u64,
        lo: u64,
        thr0: f64,
        salt: u32,
        buf: &mut [u64],
    ) -> usize {
        let cap = buf.len();
        debug_assert!(k >= 1 && cap >= 2 * k);
        let (nx, ny) = self.nb;
        let mut n = 0usize;
        // As in `select_k`: keys above `thr_key` are rejected, and so are reduced
        // costs above `thr` (never above `thr0`): the k smallest keys of the entries
        // with `w <= thr0`, whatever the visiting order, so both give the same keys.
        let (mut thr_key, mut thr) = if thr0 < f64::INFINITY {
            (ord_bits(thr0) | mask, thr0)
        } else {
            (u64::MAX, f64::INFINITY)
        };
        let (x, y) = (self.ax[i], self.ay[i]);
        let s = self.cell;
        let (fx, fy) = ((x - self.origin.0) / s, (y - self.origin.1) / s);
        let clampi = |f: f64, len: usize| (f.max(0.0) as usize).min(len - 1);
        let (ci, cj) = (clampi(fx, nx), clampi(fy, ny));
        // Distance from the agent to the nearest side of its (clamped) bucket.
        let side = |f: f64, c: usize| {
            let off = (f - c as f64).clamp(0.0, 1.0);
            off.min(1.0 - off) * s
        };
        let m = side(fx, ci).min(side(fy, cj));
        let rmax = ci.max(nx - 1 - ci).max(cj).max(ny - 1 - cj);
        let squared = self.metric == PointMetric::Squared;
        let visit = |b: usize, buf: &mut [u64], n: &mut usize, thr_key: &mut u64, thr: &mut f64| {
            for t in self.start[b] as usize..self.start[b + 1] as usize {
                let (dx, dy) = (x - self.bx[t], y - self.by[t]);
                let d2 = dx * dx + dy * dy;
                let c = if squared { d2 } else { d2.sqrt() };
                let j = self.order[t];
                let w = c - v[j as usize];
                if w < f64::INFINITY && !(w > *thr) {
                    let kk = key(w, j ^ salt, mask);
                    if kk >= lo && kk <= *thr_key {
                        buf[*n] = kk;
                        *n += 1;
                        if *n == cap {
                            let (_, kth, _) = buf.select_nth_unstable(k - 1);
                            *thr_key = *kth;
                            *thr = from_ord_bits(*kth | mask).min(thr0);
                            *n = k;
                        }
                    }
                }
            }
        };
        for r in 0..=rmax {
            if r >= 1 && n >= k {
                if n > k || thr_key == u64::MAX {
                    let (_, kth, _) = buf[..n].select_nth_unstable(k - 1);
                    if *kth < thr_key {
                        thr_key = *kth;
                        thr = from_ord_bits(*kth | mask).min(thr0);
                    }
                    n = k;
                }
                let d = ((r - 1) as f64 * s + m) * (1.0 - 1e-9);
                let f = if squared { d * d } else { d };
                let b = f - v_hi;
                let b = b - 1e-9 * b.abs();
                if (ord_bits(b) & !mask) > (thr_key | mask) {
                    break;
                }
            }
            let (x0, x1) = (ci.saturating_sub(r), (ci + r).min(nx - 1));
            for yy in cj.saturating_sub(r)..=(cj + r).min(ny - 1) {
                let row = yy * nx;
                if yy + r == cj || yy == cj + r {
                    for xx in x0..=x1 {
                        visit(row + xx, buf, &mut n, &mut thr_key, &mut thr);
                    }
                } else {
                    if ci >= r {
                        visit(row + ci - r, buf, &mut n, &mut thr_key, &mut thr);
                    }
                    if r > 0 && ci + r < nx {
                        visit(row + ci + r, buf, &mut n, &mut thr_key, &mut thr);
                    }
                }
            }
        }
        if n > k {
            buf[..n].select_nth_unstable(k - 1);
            n = k;
        }
        buf[..n].sort_unstable();
        n
    }
}
