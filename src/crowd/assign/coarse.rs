//! [`CoarseToFine`]: the exact assignment of `n` agents to `n` goals by least total
//! squared distance, solved on ever coarser groups of both sets first, each finer
//! level started from the prices the level below implies.
//!
//! # Why
//!
//! The optimal prices of a squared-distance instance are samples of one function,
//! the dual potential of the optimal transport between the two point clouds: for
//! `c(a, g) = |a − g|²` the duals `u(a)`, `v(g)` do not scale with `n`. A cold solve
//! must grow these prices from nothing across the whole set (a filled rectangle of
//! agents against the two blobs of a split: every agent's nearest goals are at
//! first the same few), which is most of its work (gesture-driven section 7.3 at
//! 1,000 agents: 4,000–9,000 full-row pricings and 25,000–45,000 auction bids).
//!
//! Both sets are sorted along a Hilbert curve, and each coarser level replaces
//! [`LEVEL_FACTOR`] consecutive points (or groups) by their centroid: 1,000 → 333
//! → 111 groups, each of the same number of agents on both sides, so a level is an
//! assignment problem again and keeps the counts of both sets at every scale above
//! its group size. (Random subsets would not: two samples of a mixture differ in
//! their counts at every scale, and prices from a subset had to be repaired across
//! the whole set, slower than a cold solve.) The coarsest level is solved cold;
//! the row duals `u` of a level give each goal of the next finer level the price
//!
//! ```text
//!   v(g) = min_{A in coarser agent groups} ( |A − g|² − u(A) )   (the c-transform)
//! ```
//!
//! the coarser level's own price on its goal groups, and near the optimal price
//! elsewhere, and that level starts from them ([`Solver::solve_from_prices`]): about
//! half the rows take their cheapest goal at once, and a short auction and the exact
//! searches repair the rest (1,000 agents: 2,000–2,800 pricings, about 20,000 bids).
//!
//! # Exactness
//!
//! Each level is solved exactly from its start; the finest level is the whole
//! instance, so the answer is the optimum of the given instance (any finite prices
//! are a valid start; they only decide the work). The unit tests compare it with a
//! cold solve of the dense matrix.
//!
//! # Coordinates
//!
//! Every level is solved in the coordinates of [`AffineMap::equalising`] (agents
//! and goals centred, the same covariance), which keeps the optimal permutation and
//! makes the potentials small and smooth.

use super::cancel::Cancel;
use super::costs::CostMatrix;
use super::error::AssignError;
use super::normalise::AffineMap;
use super::solver::{SolveStats, Solver};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// Each coarser level groups `LEVEL_FACTOR` consecutive points (or groups) of
/// the level above along the Hilbert curve.
const LEVEL_FACTOR: usize = 3;

/// A level of at most this many points is solved cold (the coarsest); above it,
/// from the prices of a coarser level. At 128 columns and below the solver runs its
/// dense strategy, whose cold solve is cheap at that size.
const COARSEST_MAX: usize = 128;

/// Bits per axis of the Hilbert curve the points are ordered along.
const HILBERT_BITS: u32 = 16;

/// Seed of the column orders (any seed gives the same optimum; a fixed one keeps
/// the work reproducible).
const COLUMN_ORDER_SEED: u64 = 0x5EED_C0A5_2E70_F14E;

/// Largest number of levels (a guard: `LEVEL_FACTOR^8` points is far beyond any
/// crowd).
const MAX_LEVELS: usize = 8;

/// Work counters of the last [`CoarseToFine::solve`].
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct CoarseStats {
    /// Levels solved (1: the instance was small enough to solve cold).
    pub levels: usize,
    /// Groups of the coarsest level.
    pub coarsest: usize,
    /// The finest level's solve (the whole instance).
    pub finest: SolveStats,
}

/// One level: the centroids of its agent groups and of its goal groups (level 0:
/// the points themselves), in Hilbert order; the goals again in the order of the
/// level's cost matrix columns, a fixed random permutation of that order (a row's
/// streaming selection of its cheapest columns tightens its threshold fastest when
/// near and far columns come mixed, not far ones first).
#[derive(Clone, Debug, Default)]
struct Level {
    agents: Vec<Vec2>,
    goals: Vec<Vec2>,
    /// `cols[c] = goals[rank[c]]`.
    cols: Vec<Vec2>,
    rank: Vec<u32>,
}

impl Level {
    /// Draws `rank` (a random permutation, when the size changed) and fills `cols`.
    fn scramble_columns(&mut self) {
        let m = self.goals.len();
        if self.rank.len() != m {
            self.rank.clear();
            self.rank.extend(0..m as u32);
            let mut rng = SplitMix64::new(COLUMN_ORDER_SEED ^ m as u64);
            for i in (1..m).rev() {
                let j = (rng.next_u64() % (i as u64 + 1)) as usize;
                self.rank.swap(i, j);
            }
        }
        self.cols.clear();
        self.cols
            .extend(self.rank.iter().map(|&r| self.goals[r as usize]));
    }
}

/// Exact square assignment by least total squared distance, coarse to fine (module
/// doc). Keeps every workspace (one solver and one cost matrix per level, the
/// orders, centroids and prices) from call to call: after the first solve at a
/// size, a solve at the same size does not allocate.
///
/// # Example
/// ```
/// use crowdtouch::crowd::assign::CoarseToFine;
/// use crowdtouch::geom::Vec2;
/// let agents = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
/// let goals = [Vec2::new(1.1, 0.0), Vec2::new(0.0, 1.2), Vec2::new(-0.1, 0.0)];
/// let mut c2f = CoarseToFine::new();
/// assert_eq!(c2f.solve(&agents, &goals).unwrap(), &[2, 0, 1]);
/// ```
#[derive(Clone, Debug, Default)]
pub struct CoarseToFine {
    /// One solver, one cost matrix and one set of centroids per level, the finest
    /// first.
    solvers: Vec<Solver>,
    matrices: Vec<CostMatrix>,
    levels: Vec<Level>,
    /// Hilbert keys with the point's index, sorted (agents, goals).
    keys_a: Vec<(u64, u32)>,
    keys_g: Vec<(u64, u32)>,
    /// Prices of the level being solved.
    prices: Vec<f64>,
    /// The answer, in the callers' indices (agent -> goal).
    goal_of: Vec<usize>,
    stats: CoarseStats,
}

impl CoarseToFine {
    /// Empty workspaces.
    pub fn new() -> CoarseToFine {
        CoarseToFine::default()
    }

    /// Work counters of the last solve.
    pub fn stats(&self) -> CoarseStats {
        self.stats
    }

    /// The optimal assignment of `agents` to `goals`: agent `i` gets goal
    /// `result[i]`, and `Σ |agents[i] − goals[result[i]]|²` is the least over all
    /// permutations. With more goals than agents (some left over), or all agents
    /// or all goals on one spot (every permutation ties), the instance is solved in
    /// one level, cold.
    ///
    /// # Formula
    /// Mesh-formation-control section 6.1, eq. 2 with unit weights and the squared
    /// Euclidean cost; gesture-driven section 7.3 (agents to trajectory starts).
    ///
    /// # Units
    /// Positions in any one unit (m); indices in the result.
    ///
    /// # Complexity
    /// Two sorts along the Hilbert curve, one `n × n` cost matrix filled and priced
    /// at the finest level, `(n/4)²` at the next and so on, the c-transforms
    /// (`n² / 4` at the finest), and the augmentations of the rows each level's
    /// prices leave in conflict.
    ///
    /// # Errors
    /// [`AssignError::Empty`] without agents, [`AssignError::MoreRowsThanCols`]
    /// with more agents than goals, [`AssignError::NotFinite`] for a position that
    /// is not finite.
    pub fn solve(&mut self, agents: &[Vec2], goals: &[Vec2]) -> Result<&[usize], AssignError> {
        self.solve_with_cancel(agents, goals, Cancel::NEVER)
    }

    /// [`CoarseToFine::solve`] that gives up when `cancel` says so (polled by every
    /// level's solver, as [`Solver::solve_with_cancel`]).
    ///
    /// # Errors
    /// As [`CoarseToFine::solve`], and [`AssignError::Cancelled`].
    pub fn solve_with_cancel(
        &mut self,
        agents: &[Vec2],
        goals: &[Vec2],
        cancel: Cancel<'_>,
    ) -> Result<&[usize], AssignError> {
        let n = agents.len();
        if n == 0 {
            return Err(AssignError::Empty);
        }
        if n > goals.len() {
            return Err(AssignError::MoreRowsThanCols {
                rows: n,
                cols: goals.len(),
            });
        }
        if let Some(row) = agents.iter().position(|p| !finite(p)) {
            return Err(AssignError::NotFinite { row, col: 0 });
        }
        if let Some(col) = goals.iter().position(|p| !finite(p)) {
            return Err(AssignError::NotFinite { row: 0, col });
        }
        self.build_levels(agents, goals);
        let levels = self.levels.len();
        if self.solvers.len() < levels {
            self.solvers.resize_with(levels, Solver::new);
            self.matrices.resize_with(levels, || CostMatrix::new(0, 0));
        }
        for l in (0..levels).rev() {
            let lv = &mut self.levels[l];
            lv.scramble_columns();
            fill_costs(&lv.agents, &lv.cols, &mut self.matrices[l]);
            if l + 1 == levels {
                self.solvers[l].solve_with_cancel(&self.matrices[l], cancel)?;
            } else {
                self.c_transform(l);
                let (solvers, prices) = (&mut self.solvers, &self.prices);
                solvers[l].solve_from_prices_with_cancel(&self.matrices[l], prices, cancel)?;
            }
        }
        let x = self.solvers[0].assignment();
        self.goal_of.clear();
        self.goal_of.resize(n, 0);
        for (k, &j) in x.iter().enumerate() {
            let rank = self.levels[0].rank[j] as usize;
            self.goal_of[self.keys_a[k].1 as usize] = self.keys_g[rank].1 as usize;
        }
        self.stats = CoarseStats {
            levels,
            coarsest: self.levels[levels - 1].agents.len(),
            finest: self.solvers[0].stats(),
        };
        Ok(&self.goal_of)
    }

    /// Level 0: both sets mapped to the equalised coordinates and sorted along a
    /// Hilbert curve over their common bounding box; level `l + 1`: the centroids
    /// of `LEVEL_FACTOR` consecutive groups of level `l` (a last incomplete group
    /// is left out of the coarser levels), as long as level `l` has more than
    /// [`COARSEST_MAX`]. A rectangular instance, or one whose agents or goals are
    /// all on one spot, has one level in the given order.
    fn build_levels(&mut self, agents: &[Vec2], goals: &[Vec2]) {
        // A set on one spot ties every permutation: the coarse levels' rounding
        // (centroids) would only break the ties with noise, which the exact
        // searches then explore (agents on one spot against a grid: 1.5 s against
        // 17 ms in one level).
        let square = agents.len() == goals.len() && !on_one_spot(agents) && !on_one_spot(goals);
        let map = AffineMap::equalising(agents, goals);
        let tf_a = |p: Vec2| map.as_ref().map_or(p, |m| m.agent(p));
        let tf_g = |p: Vec2| map.as_ref().map_or(p, |m| m.goal(p));
        let (mut lo, mut hi) = (
            Vec2::new(f64::INFINITY, f64::INFINITY),
            Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in agents
            .iter()
            .map(|&p| tf_a(p))
            .chain(goals.iter().map(|&p| tf_g(p)))
        {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let side = (hi - lo).max().max(f64::MIN_POSITIVE);
        let cells = f64::from((1u32 << HILBERT_BITS) - 1);
        let key = |p: Vec2| -> u64 {
            let q = (p - lo) / side * cells;
            hilbert_index(q.x.clamp(0.0, cells) as u32, q.y.clamp(0.0, cells) as u32)
        };
        for (keys, pts, tf) in [
            (&mut self.keys_a, agents, &tf_a as &dyn Fn(Vec2) -> Vec2),
            (&mut self.keys_g, goals, &tf_g),
        ] {
            keys.clear();
            if square {
                keys.extend(pts.iter().enumerate().map(|(i, &p)| (key(tf(p)), i as u32)));
                keys.sort_unstable();
            } else {
                keys.extend((0..pts.len()).map(|i| (0, i as u32)));
            }
        }
        if self.levels.is_empty() {
            self.levels.push(Level::default());
        }
        let l0 = &mut self.levels[0];
        l0.agents.clear();
        l0.goals.clear();
        l0.agents
            .extend(self.keys_a.iter().map(|&(_, i)| tf_a(agents[i as usize])));
        l0.goals
            .extend(self.keys_g.iter().map(|&(_, j)| tf_g(goals[j as usize])));
        let mut used = 1;
        while square && self.levels[used - 1].agents.len() > COARSEST_MAX && used < MAX_LEVELS {
            if self.levels.len() == used {
                self.levels.push(Level::default());
            }
            let (fine, coarse) = self.levels.split_at_mut(used);
            let (fine, coarse) = (&fine[used - 1], &mut coarse[0]);
            group_centroids(&fine.agents, &mut coarse.agents);
            group_centroids(&fine.goals, &mut coarse.goals);
            used += 1;
        }
        self.levels.truncate(used.max(1));
    }

    /// The prices of level `l`'s goals from the row duals of level `l + 1`: the
    /// c-transform of the module doc, over level `l + 1`'s agent centroids.
    fn c_transform(&mut self, l: usize) {
        let u = self.solvers[l + 1].row_duals();
        let coarse = &self.levels[l + 1].agents;
        self.prices.clear();
        self.prices.extend(self.levels[l].cols.iter().map(|g| {
            coarse
                .iter()
                .zip(u)
                .map(|(a, &ui)| (a - g).norm_squared() - ui)
                .fold(f64::INFINITY, f64::min)
        }));
    }
}

/// The centroids of consecutive groups of [`LEVEL_FACTOR`] points (an incomplete
/// last group left out).
fn group_centroids(fine: &[Vec2], out: &mut Vec<Vec2>) {
    out.clear();
    out.extend(
        fine.chunks_exact(LEVEL_FACTOR)
            .map(|g| g.iter().fold(Vec2::zeros(), |s, p| s + p) / LEVEL_FACTOR as f64),
    );
}

/// Position of cell `(x, y)` along the Hilbert curve over a `2^HILBERT_BITS`
/// square grid (consecutive positions are neighbouring cells, so consecutive points
/// of a sorted set lie close together).
fn hilbert_index(mut x: u32, mut y: u32) -> u64 {
    let n: u32 = 1 << HILBERT_BITS;
    let mut d = 0u64;
    let mut s = n / 2;
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        d += u64::from(s) * u64::from(s) * u64::from((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    d
}

/// Whether every point is the first one.
fn on_one_spot(p: &[Vec2]) -> bool {
    p.iter().all(|q| *q == p[0])
}

fn finite(p: &Vec2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

/// `out[i][j] = |agents[i] − goals[j]|²`.
fn fill_costs(agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {
    out.resize(agents.len(), goals.len());
    for (i, a) in agents.iter().enumerate() {
        for (c, g) in out.row_mut(i).iter_mut().zip(goals) {
            let (dx, dy) = (a.x - g.x, a.y - g.y);
            *c = dx * dx + dy * dy;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Total squared distance of an assignment.
    fn total(agents: &[Vec2], goals: &[Vec2], goal_of: &[usize]) -> f64 {
        goal_of
            .iter()
            .enumerate()
            .map(|(i, &j)| (agents[i] - goals[j]).norm_squared())
            .sum()
    }

    /// The dense matrix's optimum by a cold solve.
    fn dense_optimum(agents: &[Vec2], goals: &[Vec2]) -> f64 {
        let mut c = CostMatrix::new(0, 0);
        fill_costs(agents, goals, &mut c);
        let mut s = Solver::new();
        let x = s.solve(&c).unwrap().to_vec();
        total(agents, goals, &x)
    }

    fn is_permutation(x: &[usize]) -> bool {
        let mut seen = vec![false; x.len()];
        x.iter()
            .all(|&j| j < seen.len() && !std::mem::replace(&mut seen[j], true))
    }

    #[test]
    fn a_grid_against_two_blobs_gets_the_dense_optimum() {
        // The synthesis's hard case: a filled rectangle of agents against the two
        // blobs of a split, at sizes with one, two and three levels.
        let mut c2f = CoarseToFine::new();
        for (n, seed) in [(100usize, 1u64), (300, 2), (1000, 3), (1000, 4)] {
            let mut rng = SplitMix64::new(seed);
            let side = (n as f64).sqrt().ceil() as usize;
            let agents: Vec<Vec2> = (0..n)
                .map(|i| Vec2::new((i % side) as f64 * 0.8, (i / side) as f64 * 0.8))
                .collect();
            let goals: Vec<Vec2> = (0..n)
                .map(|i| {
                    let c = if i % 3 == 0 { 3.0 } else { 40.0 };
                    Vec2::new(c + rng.uniform(-3.0, 3.0), 10.0 + rng.uniform(-9.0, 9.0))
                })
                .collect();
            let x = c2f.solve(&agents, &goals).unwrap().to_vec();
            assert!(is_permutation(&x));
            let (got, best) = (total(&agents, &goals, &x), dense_optimum(&agents, &goals));
            assert!((got - best).abs() <= 1e-9 * best, "n {n}: {got} vs {best}");
            let st = c2f.stats();
            assert_eq!(
                st.levels,
                if n <= 128 {
                    1
                } else if n <= 512 {
                    2
                } else {
                    3
                }
            );
            if st.levels > 1 {
                assert!(st.finest.seeded);
            }
        }
    }

    #[test]
    fn uniform_clouds_and_ties_get_the_dense_optimum() {
        let mut c2f = CoarseToFine::new();
        let mut rng = SplitMix64::new(9);
        let agents: Vec<Vec2> = (0..600)
            .map(|_| Vec2::new(rng.unit(), rng.unit()))
            .collect();
        let goals: Vec<Vec2> = (0..600)
            .map(|_| Vec2::new(rng.unit() * 3.0 + 5.0, rng.unit()))
            .collect();
        let x = c2f.solve(&agents, &goals).unwrap().to_vec();
        let (got, best) = (total(&agents, &goals, &x), dense_optimum(&agents, &goals));
        assert!((got - best).abs() <= 1e-9 * best, "{got} vs {best}");
        // Exact ties: agents and goals on the same integer grid.
        let grid: Vec<Vec2> = (0..400)
            .map(|i| Vec2::new((i % 20) as f64, (i / 20) as f64))
            .collect();
        let x = c2f.solve(&grid, &grid).unwrap().to_vec();
        assert_eq!(total(&grid, &grid, &x), 0.0);
    }

    #[test]
    fn solves_of_the_same_size_reuse_every_buffer() {
        let mut rng = SplitMix64::new(21);
        let mut cloud = |n: usize, dx: f64| -> Vec<Vec2> {
            (0..n)
                .map(|_| Vec2::new(rng.unit() + dx, rng.unit()))
                .collect()
        };
        let (a1, g1, a2, g2) = (
            cloud(700, 0.0),
            cloud(700, 2.0),
            cloud(700, 0.0),
            cloud(700, 0.5),
        );
        let mut c2f = CoarseToFine::new();
        let fingerprint = |c: &CoarseToFine| -> Vec<(usize, usize)> {
            fn f<T>(v: &Vec<T>) -> (usize, usize) {
                (v.as_ptr() as usize, v.capacity())
            }
            let mut out = vec![
                f(&c.keys_a),
                f(&c.keys_g),
                f(&c.levels),
                f(&c.prices),
                f(&c.goal_of),
            ];
            for l in &c.levels {
                out.extend([f(&l.agents), f(&l.goals), f(&l.cols), f(&l.rank)]);
            }
            for s in &c.solvers {
                out.extend(s.buffer_fingerprint());
            }
            for m in &c.matrices {
                out.push((m.as_slice().as_ptr() as usize, m.as_slice().len()));
            }
            out
        };
        c2f.solve(&a1, &g1).unwrap();
        let before = fingerprint(&c2f);
        let x = c2f.solve(&a2, &g2).unwrap().to_vec();
        assert_eq!(fingerprint(&c2f), before);
        let best = dense_optimum(&a2, &g2);
        assert!((total(&a2, &g2, &x) - best).abs() <= 1e-9 * best);
    }

    #[test]
    fn clouds_on_one_spot_are_solved() {
        // Every start on one spot (a motion of zero variance), or every agent: all
        // permutations tie, and the instance is solved in one level.
        let grid: Vec<Vec2> = (0..1000)
            .map(|i| Vec2::new((i % 40) as f64 * 0.5, (i / 40) as f64 * 0.5))
            .collect();
        let spot = vec![Vec2::new(3.0, -1.0); 1000];
        let mut c2f = CoarseToFine::new();
        for (agents, goals) in [(&grid, &spot), (&spot, &grid)] {
            let x = c2f.solve(agents, goals).unwrap().to_vec();
            assert!(is_permutation(&x));
            let want: f64 = grid.iter().map(|p| (p - spot[0]).norm_squared()).sum();
            let got = total(agents, goals, &x);
            assert!((got - want).abs() <= 1e-9 * want, "{got} vs {want}");
            assert_eq!(c2f.stats().levels, 1);
        }
    }

    #[test]
    fn the_hilbert_order_steps_to_a_neighbouring_cell() {
        // Every cell of an 8 × 8 corner of the grid, in curve order: each step
        // moves to an edge neighbour, and the 64 cells are the curve's first 64.
        let mut cells: Vec<(u64, u32, u32)> = (0..64u32)
            .map(|c| (hilbert_index(c % 8, c / 8), c % 8, c / 8))
            .collect();
        cells.sort_unstable();
        assert!(cells.iter().enumerate().all(|(k, c)| c.0 == k as u64));
        for w in cells.windows(2) {
            let d = w[0].1.abs_diff(w[1].1) + w[0].2.abs_diff(w[1].2);
            assert_eq!(d, 1, "{:?} -> {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn bad_input_is_refused() {
        let mut c2f = CoarseToFine::new();
        let p = [Vec2::zeros(), Vec2::new(1.0, 0.0)];
        assert_eq!(c2f.solve(&[], &[]), Err(AssignError::Empty));
        assert!(matches!(
            c2f.solve(&p, &p[..1]),
            Err(AssignError::MoreRowsThanCols { rows: 2, cols: 1 })
        ));
        // One agent, two goals: the nearer one, in one level.
        assert_eq!(c2f.solve(&p[1..], &p).unwrap(), &[1]);
        assert_eq!(c2f.stats().levels, 1);
        let nan = [Vec2::zeros(), Vec2::new(f64::NAN, 0.0)];
        assert_eq!(
            c2f.solve(&nan, &p),
            Err(AssignError::NotFinite { row: 1, col: 0 })
        );
        assert_eq!(
            c2f.solve(&p, &nan),
            Err(AssignError::NotFinite { row: 0, col: 1 })
        );
        // A refused call leaves it usable.
        assert_eq!(c2f.solve(&p, &p).unwrap(), &[0, 1]);
    }
}
