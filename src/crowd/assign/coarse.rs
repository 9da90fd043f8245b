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
use nalgebra::Vector3;

/// A point of a level: a position and a third coordinate (0 for the plain squared
/// distance; the weighted local edge length of the least-effort cost,
/// [`CoarseToFine::prices_3d`]).
type P3 = Vector3<f64>;

/// The point `(x, y, 0)`.
fn flat(p: Vec2) -> P3 {
    P3::new(p.x, p.y, 0.0)
}

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
    agents: Vec<P3>,
    goals: Vec<P3>,
    /// `cols[c] = goals[rank[c]]`.
    cols: Vec<P3>,
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
    /// The finest level's goal prices in the caller's goal order
    /// ([`CoarseToFine::prices_3d`]).
    seed: Vec<f64>,
    /// The points of the caller's instance in 3-D (`flat` for [`CoarseToFine::solve`]).
    pts_a: Vec<P3>,
    pts_g: Vec<P3>,
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
        check_points(agents, goals, |p| p.x.is_finite() && p.y.is_finite())?;
        let map = if agents.len() == goals.len() {
            AffineMap::equalising(agents, goals)
        } else {
            None
        };
        let tf_a = |p: Vec2| flat(map.as_ref().map_or(p, |m| m.agent(p)));
        let tf_g = |p: Vec2| flat(map.as_ref().map_or(p, |m| m.goal(p)));
        self.pts_a.clear();
        self.pts_a.extend(agents.iter().map(|&p| tf_a(p)));
        self.pts_g.clear();
        self.pts_g.extend(goals.iter().map(|&p| tf_g(p)));
        self.build_levels();
        let levels = self.levels.len();
        self.solve_levels(0, cancel)?;
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

    /// Column prices that start an exact solve of the square instance
    /// `c(i, j) = |agents[i] − goals[j]|²` of points in three dimensions near its
    /// optimum ([`Solver::solve_from_prices`]), one per goal in the caller's order:
    /// the coarser levels are solved as in [`CoarseToFine::solve`] and the finest
    /// goals priced by the c-transform of the module doc. The finest level itself
    /// is left to the caller, who may solve it on costs it computes on the fly
    /// (an `n × n` matrix at 5,000 agents is 200 MB).
    ///
    /// The least-effort cost of formation-transform eq. 3 is such an instance:
    /// `λ |s − t|² + (1 − λ)(δs − δt)²` is the squared distance between
    /// `(√λ s, √(1 − λ) δs)` and `(√λ t, √(1 − λ) δt)`.
    ///
    /// Returns an empty slice when the instance has no coarser level (too small,
    /// rectangular, or a set on one spot); a cold solve is then the way.
    ///
    /// # Units
    /// Coordinates in any one unit; prices in that unit squared.
    ///
    /// # Errors
    /// [`AssignError::Empty`] without agents, [`AssignError::MoreRowsThanCols`],
    /// [`AssignError::NotFinite`] for a coordinate that is not finite,
    /// [`AssignError::Cancelled`].
    pub fn prices_3d(
        &mut self,
        agents: &[[f64; 3]],
        goals: &[[f64; 3]],
        cancel: Cancel<'_>,
    ) -> Result<&[f64], AssignError> {
        check_points(agents, goals, |p| p.iter().all(|c| c.is_finite()))?;
        self.pts_a.clear();
        self.pts_a.extend(agents.iter().map(|&p| P3::from(p)));
        self.pts_g.clear();
        self.pts_g.extend(goals.iter().map(|&p| P3::from(p)));
        self.build_levels();
        self.seed.clear();
        if self.levels.len() < 2 {
            return Ok(&self.seed);
        }
        self.solve_levels(1, cancel)?;
        self.levels[0].scramble_columns();
        self.c_transform(0);
        // `prices[c]` is the price of level 0's column `c`: goal `keys_g[rank[c]]`.
        self.seed.resize(goals.len(), 0.0);
        for (&r, &p) in self.levels[0].rank.iter().zip(&self.prices) {
            self.seed[self.keys_g[r as usize].1 as usize] = p;
        }
        Ok(&self.seed)
    }

    /// Solves the levels from the coarsest down to `finest` (cold the coarsest,
    /// each other from the prices of the one below).
    fn solve_levels(&mut self, finest: usize, cancel: Cancel<'_>) -> Result<(), AssignError> {
        let levels = self.levels.len();
        if self.solvers.len() < levels {
            self.solvers.resize_with(levels, Solver::new);
            self.matrices.resize_with(levels, || CostMatrix::new(0, 0));
        }
        for l in (finest..levels).rev() {
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
        Ok(())
    }

    /// Level 0: the caller's points (`pts_a`, `pts_g`; for [`CoarseToFine::solve`]
    /// in the equalised coordinates) sorted along a Hilbert curve over their
    /// common bounding box in the plane; level `l + 1`: the centroids
    /// of `LEVEL_FACTOR` consecutive groups of level `l` (a last incomplete group
    /// is left out of the coarser levels), as long as level `l` has more than
    /// [`COARSEST_MAX`]. A rectangular instance, or one whose agents or goals are
    /// all on one spot, has one level in the given order.
    fn build_levels(&mut self) {
        let (agents, goals) = (&self.pts_a, &self.pts_g);
        // A set on one spot ties every permutation: the coarse levels' rounding
        // (centroids) would only break the ties with noise, which the exact
        // searches then explore (agents on one spot against a grid: 1.5 s against
        // 17 ms in one level).
        let square = agents.len() == goals.len() && !on_one_spot(agents) && !on_one_spot(goals);
        let (mut lo, mut hi) = (
            Vec2::new(f64::INFINITY, f64::INFINITY),
            Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in agents.iter().chain(goals) {
            let p = p.xy();
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let side = (hi - lo).max().max(f64::MIN_POSITIVE);
        let cells = f64::from((1u32 << HILBERT_BITS) - 1);
        // Along the curve by position; the third coordinate only joins the groups'
        // centroids.
        let key = |p: &P3| -> u64 {
            let q = (p.xy() - lo) / side * cells;
            hilbert_index(q.x.clamp(0.0, cells) as u32, q.y.clamp(0.0, cells) as u32)
        };
        for (keys, pts) in [(&mut self.keys_a, agents), (&mut self.keys_g, goals)] {
            keys.clear();
            if square {
                keys.extend(pts.iter().enumerate().map(|(i, p)| (key(p), i as u32)));
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
            .extend(self.keys_a.iter().map(|&(_, i)| agents[i as usize]));
        l0.goals
            .extend(self.keys_g.iter().map(|&(_, j)| goals[j as usize]));
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
                .map(|(a, &ui)| dist2(a, g) - ui)
                .fold(f64::INFINITY, f64::min)
        }));
    }
}

/// The centroids of consecutive groups of [`LEVEL_FACTOR`] points (an incomplete
/// last group left out).
fn group_centroids(fine: &[P3], out: &mut Vec<P3>) {
    out.clear();
    out.extend(
        fine.chunks_exact(LEVEL_FACTOR)
            .map(|g| g.iter().fold(P3::zeros(), |s, p| s + p) / LEVEL_FACTOR as f64),
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
fn on_one_spot(p: &[P3]) -> bool {
    p.iter().all(|q| *q == p[0])
}

/// The errors of an instance of `agents` and `goals`: none, more agents than
/// goals, or the first point that is not `finite` (agents first).
fn check_points<P>(
    agents: &[P],
    goals: &[P],
    finite: impl Fn(&P) -> bool,
) -> Result<(), AssignError> {
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
    Ok(())
}

/// `out[i][j] = |agents[i] − goals[j]|²`.
fn fill_costs(agents: &[P3], goals: &[P3], out: &mut CostMatrix) {
    out.resize(agents.len(), goals.len());
    for (i, a) in agents.iter().enumerate() {
        for (c, g) in out.row_mut(i).iter_mut().zip(goals) {
            *c = dist2(a, g);
        }
    }
}

/// `|a − g|²`, summed in the order x, y, z (with `z = 0` the bits of the plane's
/// `dx² + dy²`).
#[inline]
fn dist2(a: &P3, g: &P3) -> f64 {
    let (dx, dy, dz) = (a.x - g.x, a.y - g.y, a.z - g.z);
    dx * dx + dy * dy + dz * dz
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
        let flat_all = |p: &[Vec2]| p.iter().map(|&q| flat(q)).collect::<Vec<P3>>();
        fill_costs(&flat_all(agents), &flat_all(goals), &mut c);
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
                f(&c.pts_a),
                f(&c.pts_g),
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

    /// Points in three dimensions: a cloud, and the same shape moved and its third
    /// coordinate varied (a least-effort instance's scaled edge lengths).
    fn cloud_3d(rng: &mut SplitMix64, n: usize, dx: f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| [dx + 4.0 * rng.unit(), 3.0 * rng.unit(), 0.8 * rng.unit()])
            .collect()
    }

    /// The dense matrix of squared distances between points in three dimensions.
    fn matrix_3d(a: &[[f64; 3]], g: &[[f64; 3]]) -> CostMatrix {
        let mut c = CostMatrix::new(0, 0);
        let (a, g): (Vec<P3>, Vec<P3>) = (
            a.iter().map(|&p| P3::from(p)).collect(),
            g.iter().map(|&p| P3::from(p)).collect(),
        );
        fill_costs(&a, &g, &mut c);
        c
    }

    #[test]
    fn prices_3d_start_a_solve_that_ends_at_the_dense_optimum() {
        let mut rng = SplitMix64::new(0x3d);
        let mut c2f = CoarseToFine::new();
        for (n, levels) in [(300usize, 2usize), (1500, 4)] {
            let (a, g) = (cloud_3d(&mut rng, n, 0.0), cloud_3d(&mut rng, n, 2.5));
            let c = matrix_3d(&a, &g);
            let prices = c2f.prices_3d(&a, &g, Cancel::NEVER).unwrap().to_vec();
            assert_eq!(prices.len(), n);
            assert_eq!(c2f.levels.len(), levels);
            let mut seeded = Solver::new();
            seeded.solve_from_prices(&c, &prices).unwrap();
            assert!(seeded.stats().seeded);
            let mut cold = Solver::new();
            cold.solve(&c).unwrap();
            let (got, best) = (seeded.total_cost(&c), cold.total_cost(&c));
            assert!((got - best).abs() <= 1e-9 * best, "n {n}: {got} vs {best}");
            // The prices are near optimal: most rows take their cheapest goal in
            // the first pass, so the seeded solve prices far fewer rows than the
            // cold one.
            assert!(
                seeded.stats().rows_priced < cold.stats().rows_priced,
                "n {n}: {:?} against {:?}",
                seeded.stats(),
                cold.stats()
            );
        }
    }

    #[test]
    fn prices_3d_without_a_coarser_level_are_empty_and_bad_points_refused() {
        let mut rng = SplitMix64::new(5);
        let mut c2f = CoarseToFine::new();
        let (a, g) = (cloud_3d(&mut rng, 100, 0.0), cloud_3d(&mut rng, 100, 1.0));
        assert!(c2f.prices_3d(&a, &g, Cancel::NEVER).unwrap().is_empty());
        let (a, g) = (cloud_3d(&mut rng, 300, 0.0), cloud_3d(&mut rng, 400, 1.0));
        assert!(c2f.prices_3d(&a, &g, Cancel::NEVER).unwrap().is_empty());
        assert_eq!(
            c2f.prices_3d(&[], &g, Cancel::NEVER),
            Err(AssignError::Empty)
        );
        assert!(matches!(
            c2f.prices_3d(&g, &a, Cancel::NEVER),
            Err(AssignError::MoreRowsThanCols {
                rows: 400,
                cols: 300
            })
        ));
        let mut bad = a.clone();
        bad[7][2] = f64::NAN;
        assert_eq!(
            c2f.prices_3d(&bad, &bad, Cancel::NEVER),
            Err(AssignError::NotFinite { row: 7, col: 0 })
        );
        let stop = || true;
        let (a, g) = (cloud_3d(&mut rng, 1500, 0.0), cloud_3d(&mut rng, 1500, 1.0));
        assert_eq!(
            c2f.prices_3d(&a, &g, Cancel::new(&stop)),
            Err(AssignError::Cancelled)
        );
        // Still usable afterwards.
        assert_eq!(c2f.prices_3d(&a, &g, Cancel::NEVER).unwrap().len(), 1500);
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
