//! Pair assignment of a formation transform (formation-transform section 3.2, eqs. 2–6;
//! the alternative costs of section 5.2): every agent gets one target, the sum of
//! the pairing costs minimal, solved exactly by the project's [`Solver`].
//!
//! Three costs:
//!
//! * least effort `ΔE(i, j)` of eq. 3 ([`LeastEffort`]: Delaunay mean edge lengths,
//!   eqs. 4–5), read by the solver through [`LeastEffortCosts`](crate::crowd::assign::LeastEffortCosts);
//! * the Euclidean distance `|s_i t_j|` in metres — the plain distance, not its
//!   square, as the paper's Euclidean baseline of section 5.2 ranks pairings by
//!   the total path length (squared distance would be least effort at `λ = 1`,
//!   which the comparison already covers); it runs on the solver's geometric fast
//!   path ([`PointCosts`] with [`PointMetric::Euclidean`]: a bucket grid, exact
//!   candidate lists);
//! * the Manhattan distance `|Δx| + |Δy|` in metres ([`ManhattanCosts`]).
//!
//! Every solve is exact: the sparse strategy's candidate lists carry a threshold
//! below which no other column lies, and the dual certificate holds over the whole
//! cost matrix when the solver returns (`Solver`'s module documentation).

use crate::crowd::assign::{
    mean_edge_lengths, AffineMap, AssignError, Cancel, CoarseToFine, CostSource, LeastEffort,
    LeastEffortCosts, PointCosts, PointMetric, Solver,
};
use crate::geom::Vec2;

/// Least-effort pairings of at least this many agents start from the prices of
/// coarser groups of the same points ([`CoarseToFine::prices_3d`]) instead of
/// cold.
const COARSE_PAIRING_MIN: usize = 1000;

/// The cost that pairs agents with targets (formation-transform section 3.2; the
/// alternatives of section 5.2).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum PairCost {
    /// `ΔE(i, j)` of eq. 3 with this `λ` in `[0, 1]`.
    LeastEffort {
        /// `λ` of eq. 3.
        lambda: f64,
    },
    /// The Euclidean distance `|s_i t_j|`.
    Euclidean,
    /// The Manhattan distance `|x_i − x_j| + |y_i − y_j|`.
    Manhattan,
    /// `ΔE(i, j)` of eq. 3 with both terms normalised: each divided by its mean
    /// over every (agent, target) pair, so that `λ = 0.5` weighs travel and
    /// local structure alike ([`raw_lambda`]). The raw terms differ by orders of
    /// magnitude (m² of travel against m² of edge-length change), so at the raw
    /// `λ = 0.5` the local-structure term has no effect.
    LeastEffortNormalised {
        /// `λ` of eq. 3 on the normalised terms.
        lambda: f64,
    },
}

impl PairCost {
    /// `least-effort`, `euclidean` or `manhattan`.
    pub fn name(&self) -> &'static str {
        match self {
            PairCost::LeastEffort { .. } => "least-effort",
            PairCost::Euclidean => "euclidean",
            PairCost::Manhattan => "manhattan",
            PairCost::LeastEffortNormalised { .. } => "least-effort-normalised",
        }
    }

    /// The cost named `name` (as [`PairCost::name`] writes it), least effort with `lambda`.
    pub fn parse(name: &str, lambda: f64) -> Option<PairCost> {
        match name {
            "least-effort" => Some(PairCost::LeastEffort { lambda }),
            "euclidean" => Some(PairCost::Euclidean),
            "manhattan" => Some(PairCost::Manhattan),
            "least-effort-normalised" => Some(PairCost::LeastEffortNormalised { lambda }),
            _ => None,
        }
    }

    /// `λ` of eq. 3, for the two least-effort costs.
    pub fn lambda(&self) -> Option<f64> {
        match *self {
            PairCost::LeastEffort { lambda } | PairCost::LeastEffortNormalised { lambda } => {
                Some(lambda)
            }
            PairCost::Euclidean | PairCost::Manhattan => None,
        }
    }
}

/// The means over every (agent, target) pair of eq. 3's two terms:
/// `D² = mean_{i,j} |s_i − t_j|²` (m²) and `Δ² = mean_{i,j} (δs_i − δt_j)²` (m²),
/// `δ` the mean Delaunay edge lengths of eqs. 4–5.
///
/// # Closed form
/// `mean_{i,j} |s_i − t_j|² = mean|s|² + mean|t|² − 2 mean(s)·mean(t)`, and the
/// same for `δ`: `O(n)` after the two triangulations, no `n²` sum.
pub fn term_means(agents: &[Vec2], goals: &[Vec2]) -> (f64, f64) {
    let (mut ds, mut dt) = (Vec::new(), Vec::new());
    mean_edge_lengths(agents, &mut ds);
    mean_edge_lengths(goals, &mut dt);
    (
        pair_mean_square(
            agents.iter().map(|p| (p.x, p.y)),
            goals.iter().map(|p| (p.x, p.y)),
        ),
        pair_mean_square(ds.iter().map(|&d| (d, 0.0)), dt.iter().map(|&d| (d, 0.0))),
    )
}

/// `mean_{i,j} |a_i − b_j|²` of two sets of plane vectors (0 for an empty set).
fn pair_mean_square(
    a: impl Iterator<Item = (f64, f64)> + Clone,
    b: impl Iterator<Item = (f64, f64)> + Clone,
) -> f64 {
    let moments = |it: &mut dyn Iterator<Item = (f64, f64)>| {
        let (mut n, mut sx, mut sy, mut s2) = (0usize, 0.0, 0.0, 0.0);
        for (x, y) in it {
            n += 1;
            sx += x;
            sy += y;
            s2 += x * x + y * y;
        }
        if n == 0 {
            None
        } else {
            let k = n as f64;
            Some((sx / k, sy / k, s2 / k))
        }
    };
    match (moments(&mut a.clone()), moments(&mut b.clone())) {
        (Some((ax, ay, a2)), Some((bx, by, b2))) => (a2 + b2 - 2.0 * (ax * bx + ay * by)).max(0.0),
        _ => 0.0,
    }
}

/// The `λ` of eq. 3 on the raw terms that pairs as `lambda` does on the
/// normalised terms ([`PairCost::LeastEffortNormalised`]).
///
/// # Normalisation
/// `ΔE'(i, j) = λ |s_i t_j|² / D² + (1 − λ)(δs_i − δt_j)² / Δ²` ([`term_means`]).
/// Multiplying by the positive constant `D² Δ² / (λ Δ² + (1 − λ) D²)` gives
/// eq. 3's raw form with `λ_raw = λ Δ² / (λ Δ² + (1 − λ) D²)`, and a positive
/// factor changes no optimal pairing. So the normalised cost is solved as the
/// raw one at `λ_raw`. Where a term has no spread (`D²` or `Δ²` zero, or not
/// finite) it cannot be normalised and `lambda` is returned as given.
pub fn raw_lambda(lambda: f64, agents: &[Vec2], goals: &[Vec2]) -> f64 {
    let (d2, delta2) = term_means(agents, goals);
    let lambda = lambda.clamp(0.0, 1.0);
    if !(d2.is_finite() && delta2.is_finite() && d2 > 0.0 && delta2 > 0.0) {
        return lambda;
    }
    let den = lambda * delta2 + (1.0 - lambda) * d2;
    if den > 0.0 {
        lambda * delta2 / den
    } else {
        lambda
    }
}

/// The two terms of eq. 3 summed over a pairing (agent `i` to `targets[i]`):
/// `Σ |s_i t_i|²` and `Σ (δs_i − δt_i)²` (m²), `δ` the mean Delaunay edge
/// lengths of the agents' and of the targets' own triangulations (eqs. 4–5).
pub fn pairing_terms(agents: &[Vec2], targets: &[Vec2]) -> (f64, f64) {
    let (mut ds, mut dt) = (Vec::new(), Vec::new());
    mean_edge_lengths(agents, &mut ds);
    mean_edge_lengths(targets, &mut dt);
    let travel = agents
        .iter()
        .zip(targets)
        .map(|(s, t)| (s - t).norm_squared())
        .sum();
    let local = ds.iter().zip(&dt).map(|(a, b)| (a - b).powi(2)).sum();
    (travel, local)
}

/// The Manhattan distance `|x_i − x_j| + |y_i − y_j|` (m) between agents and
/// targets, computed when the solver reads it (formation-transform section 5.2).
///
/// # Complexity
/// `O(1)` an entry, `O(targets)` a row; no matrix.
#[derive(Clone, Debug, Default)]
pub struct ManhattanCosts {
    ax: Vec<f64>,
    ay: Vec<f64>,
    gx: Vec<f64>,
    gy: Vec<f64>,
}

impl ManhattanCosts {
    /// The costs of sending `agents` to `goals`.
    pub fn new(agents: &[Vec2], goals: &[Vec2]) -> ManhattanCosts {
        ManhattanCosts {
            ax: agents.iter().map(|p| p.x).collect(),
            ay: agents.iter().map(|p| p.y).collect(),
            gx: goals.iter().map(|p| p.x).collect(),
            gy: goals.iter().map(|p| p.y).collect(),
        }
    }
}

impl CostSource for ManhattanCosts {
    fn rows(&self) -> usize {
        self.ax.len()
    }
    fn cols(&self) -> usize {
        self.gx.len()
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        (self.ax[i] - self.gx[j]).abs() + (self.ay[i] - self.gy[j]).abs()
    }
    fn row<'a>(&'a self, i: usize, buf: &'a mut Vec<f64>) -> &'a [f64] {
        let (ax, ay) = (self.ax[i], self.ay[i]);
        buf.resize(self.gx.len(), 0.0);
        for (e, (&gx, &gy)) in buf.iter_mut().zip(self.gx.iter().zip(&self.gy)) {
            *e = (ax - gx).abs() + (ay - gy).abs();
        }
        buf
    }
}

/// The least-effort costs of eq. 3 of sending `agents` to `goals` (same number) with
/// `λ`, in coordinates where the agents and the targets are alike, with the same
/// optimal pairing as [`LeastEffort::costs`]. The positions are left as given where
/// [`AffineMap::equalising`] does not apply, and the edge lengths unscaled where one
/// side has no spread.
///
/// # Why the optimum is the same
/// `ΔE(i, j) = λ|s_i − t_j|² + (1 − λ)(δs_i − δt_j)²` expands to a term of `i`
/// alone, a term of `j` alone, and `−2(λ s_i·t_j + (1 − λ) δs_i δt_j)`. Over the
/// permutations of a square instance the first two add the same total, so the
/// optimum maximises `Σ λ s_i·t_σ(i) + (1 − λ) δs_i δt_σ(i)`. Mapping
/// `s ↦ A(s − μ_s)`, `t ↦ A⁻¹(t − μ_t)` ([`AffineMap::equalising`]: centred, the same
/// covariance) and `δs ↦ α(δs − m_s)`, `δt ↦ α⁻¹(δt − m_t)` (centred, `α² = σ_t/σ_s`:
/// the same spread) changes each product by terms of `i` alone, of `j` alone and a
/// constant, so every permutation's total changes by the same amount and the
/// optimal permutation is the same, up to rounding on exact ties.
///
/// # Why
/// The solver's candidate lists and prices work best when a row's cheapest columns
/// are its nearest ones and the prices stay small: a crowd turning into a larger
/// shape, or a local edge length that changes everywhere by the same factor (a
/// crowd packed tighter), otherwise makes every row favour the same few targets
/// until the prices have grown across the whole set. At `λ = 0` on a crowd of
/// even density (every `δ` nearly equal) the unmapped solve took 1.6 s at 2,000
/// agents (`benches/transform_prepare.rs`).
///
/// # Units
/// Dimensionless mapped coordinates; entries are not the costs in m² (use
/// [`LeastEffortCosts`](crate::crowd::assign::LeastEffortCosts) for those).
fn equalised_least_effort(lambda: f64, agents: &[Vec2], goals: &[Vec2]) -> LeastEffortCosts {
    let (mut ds, mut dt) = (Vec::new(), Vec::new());
    mean_edge_lengths(agents, &mut ds);
    mean_edge_lengths(goals, &mut dt);
    let map = if agents.len() == goals.len() {
        AffineMap::equalising(agents, goals)
    } else {
        None
    };
    let (a, g): (Vec<Vec2>, Vec<Vec2>) = match &map {
        Some(m) => (
            agents.iter().map(|&p| m.agent(p)).collect(),
            goals.iter().map(|&p| m.goal(p)).collect(),
        ),
        None => (agents.to_vec(), goals.to_vec()),
    };
    if agents.len() == goals.len() && !agents.is_empty() {
        let stats = |d: &[f64]| {
            let mean = d.iter().sum::<f64>() / d.len() as f64;
            let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / d.len() as f64;
            (mean, var.sqrt())
        };
        let ((ms, ss), (mt, st)) = (stats(&ds), stats(&dt));
        let alpha = if ss > 0.0 && st > 0.0 && (st / ss).is_finite() {
            (st / ss).sqrt()
        } else {
            1.0
        };
        if ms.is_finite() && mt.is_finite() {
            ds.iter_mut().for_each(|x| *x = alpha * (*x - ms));
            dt.iter_mut().for_each(|x| *x = (*x - mt) / alpha);
        }
    }
    LeastEffort::new(lambda).costs_with_lengths(&a, &g, ds, dt)
}

/// The exact pairing minimising the sum of `cost` (eq. 6): `target_of[i]` is the
/// index in `targets` of agent `i`'s target. `sources.len() == targets.len()`.
///
/// # Formula
/// `min_σ Σ_i c(s_i, t_σ(i))` over the permutations `σ` (formation-transform eq. 6),
/// `c` the chosen [`PairCost`].
///
/// # Complexity
/// Least effort: two Delaunay triangulations (`O(n log n)`), then the sparse solve
/// on costs computed as read, in equalised coordinates (`equalised_least_effort`)
/// when `λ > 0`. Euclidean: the solver's bucket-grid candidate lists.
/// Allocates.
///
/// # Errors
/// What the solver reports ([`AssignError::Empty`] for no agents,
/// [`AssignError::NotFinite`] for a NaN position, [`AssignError::MoreRowsThanCols`]
/// for more agents than targets); [`AssignError::Cancelled`] when `cancel` said so.
pub fn pair(
    sources: &[Vec2],
    targets: &[Vec2],
    cost: PairCost,
    cancel: Cancel<'_>,
) -> Result<Vec<u32>, AssignError> {
    let mut solver = Solver::new();
    let cols = match cost {
        // λ = 0 (edge lengths alone) is quicker unmapped: 1.1 s against 1.9 s at
        // 2,000 agents; λ = 0.5: 79 ms mapped against 128 ms, 0.48 s against 0.75 s
        // at 5,000 (bench `transform_prepare`'s instance, a loaded machine).
        PairCost::LeastEffort { lambda } if lambda > 0.0 => {
            let c = equalised_least_effort(lambda, sources, targets);
            if sources.len() >= COARSE_PAIRING_MIN && sources.len() == targets.len() {
                // Started from the prices of coarser groups of the same points
                // (the answer is the same optimum; only the work differs).
                let (mut a, mut g) = (Vec::new(), Vec::new());
                c.points_3d(&mut a, &mut g);
                let mut c2f = CoarseToFine::new();
                let prices = c2f.prices_3d(&a, &g, cancel)?;
                solver.solve_from_prices_with_cancel(&c, prices, cancel)?
            } else {
                solver.solve_with_cancel(&c, cancel)?
            }
        }
        PairCost::LeastEffort { lambda } => {
            let c = LeastEffort::new(lambda).costs(sources, targets);
            solver.solve_with_cancel(&c, cancel)?
        }
        PairCost::LeastEffortNormalised { lambda } => {
            let raw = raw_lambda(lambda, sources, targets);
            return pair(
                sources,
                targets,
                PairCost::LeastEffort { lambda: raw },
                cancel,
            );
        }
        PairCost::Euclidean => {
            let mut c = PointCosts::new(PointMetric::Euclidean);
            c.set(sources, targets);
            solver.solve_with_cancel(&c, cancel)?
        }
        PairCost::Manhattan => {
            let c = ManhattanCosts::new(sources, targets);
            solver.solve_with_cancel(&c, cancel)?
        }
    };
    Ok(cols.iter().map(|&j| j as u32).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::assign::{CostSource, Strategy};
    use crate::rng::SplitMix64;
    use pathfinding::kuhn_munkres::kuhn_munkres_min;
    use pathfinding::matrix::Matrix;

    fn points(rng: &mut SplitMix64, n: usize, side: f64) -> Vec<Vec2> {
        (0..n)
            .map(|_| Vec2::new(side * rng.unit(), side * rng.unit()))
            .collect()
    }

    /// The cost of one pair as the solver reads it, for every [`PairCost`].
    fn source(s: &[Vec2], t: &[Vec2], cost: PairCost) -> Box<dyn Fn(usize, usize) -> f64> {
        match cost {
            PairCost::LeastEffort { lambda } => {
                let c = LeastEffort::new(lambda).costs(s, t);
                Box::new(move |i, j| c.get(i, j))
            }
            PairCost::Euclidean => {
                let (s, t) = (s.to_vec(), t.to_vec());
                Box::new(move |i, j| (s[i] - t[j]).norm())
            }
            PairCost::Manhattan => {
                let c = ManhattanCosts::new(s, t);
                Box::new(move |i, j| c.get(i, j))
            }
            PairCost::LeastEffortNormalised { lambda } => source(
                s,
                t,
                PairCost::LeastEffort {
                    lambda: raw_lambda(lambda, s, t),
                },
            ),
        }
    }

    fn total(c: &dyn Fn(usize, usize) -> f64, to: &[u32]) -> f64 {
        to.iter().enumerate().map(|(i, &j)| c(i, j as usize)).sum()
    }

    /// Every permutation of `0..n` (Heap's algorithm), the least total.
    fn brute_force(n: usize, c: &dyn Fn(usize, usize) -> f64) -> f64 {
        let mut p: Vec<usize> = (0..n).collect();
        let mut best = f64::INFINITY;
        let mut cnt = vec![0usize; n];
        let eval = |p: &[usize]| p.iter().enumerate().map(|(i, &j)| c(i, j)).sum::<f64>();
        best = best.min(eval(&p));
        let mut i = 0;
        while i < n {
            if cnt[i] < i {
                if i % 2 == 0 {
                    p.swap(0, i);
                } else {
                    p.swap(cnt[i], i);
                }
                best = best.min(eval(&p));
                cnt[i] += 1;
                i = 0;
            } else {
                cnt[i] = 0;
                i += 1;
            }
        }
        best
    }

    const COSTS: [PairCost; 5] = [
        PairCost::LeastEffort { lambda: 0.5 },
        PairCost::LeastEffort { lambda: 0.0 },
        PairCost::Euclidean,
        PairCost::Manhattan,
        PairCost::LeastEffortNormalised { lambda: 0.5 },
    ];

    #[test]
    fn names_round_trip() {
        for c in COSTS {
            assert_eq!(
                PairCost::parse(c.name(), 0.5).map(|p| p.name()),
                Some(c.name())
            );
        }
        assert_eq!(
            PairCost::parse("least-effort", 0.25),
            Some(PairCost::LeastEffort { lambda: 0.25 })
        );
        assert_eq!(PairCost::parse("Euclidean", 0.5), None);
        assert_eq!(PairCost::parse("", 0.5), None);
    }

    /// From `COARSE_PAIRING_MIN` agents on, least effort starts from coarser
    /// groups' prices; the pairing is still the optimum of a cold solve of the same
    /// costs (a grid into a ring, and two clouds of different densities).
    #[test]
    fn large_least_effort_pairings_equal_the_cold_optimum() {
        let mut rng = SplitMix64::new(0xc0a5);
        let n = COARSE_PAIRING_MIN + 200;
        let side = (n as f64).sqrt().ceil() as usize;
        let grid: Vec<Vec2> = (0..n)
            .map(|i| Vec2::new((i % side) as f64 * 0.4, (i / side) as f64 * 0.4))
            .collect();
        let ring: Vec<Vec2> = (0..n)
            .map(|i| {
                let a = i as f64 * 2.399963;
                let r = 6.0 + 2.0 * rng.unit();
                Vec2::new(20.0 + r * a.cos(), r * a.sin())
            })
            .collect();
        let (dense, sparse) = (points(&mut rng, n, 10.0), points(&mut rng, n, 25.0));
        for (s, t) in [(&grid, &ring), (&dense, &sparse)] {
            for lambda in [0.5, 0.9] {
                let to = pair(s, t, PairCost::LeastEffort { lambda }, Cancel::NEVER).unwrap();
                let c = equalised_least_effort(lambda, s, t);
                let mut cold = Solver::new();
                cold.solve_with(&c).unwrap();
                let want = cold.total_cost(&c);
                let got: f64 = to
                    .iter()
                    .enumerate()
                    .map(|(i, &j)| c.get(i, j as usize))
                    .sum();
                assert!(
                    (got - want).abs() <= 1e-9 * want,
                    "λ {lambda}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn small_instances_match_brute_force() {
        let mut rng = SplitMix64::new(0x9a1e);
        for n in 1..=7 {
            for _ in 0..6 {
                let (s, t) = (points(&mut rng, n, 2.0), points(&mut rng, n, 3.0));
                for cost in COSTS {
                    let to = pair(&s, &t, cost, Cancel::NEVER).unwrap();
                    let mut seen = to.clone();
                    seen.sort_unstable();
                    assert_eq!(seen, (0..n as u32).collect::<Vec<_>>());
                    let c = source(&s, &t, cost);
                    let (got, want) = (total(&*c, &to), brute_force(n, &*c));
                    assert!(
                        (got - want).abs() <= 1e-9 * want.max(1.0),
                        "{cost:?} n={n}: {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn medium_instances_match_kuhn_munkres() {
        let mut rng = SplitMix64::new(0xb00c);
        for n in [40usize, 90] {
            let (s, t) = (points(&mut rng, n, 1.0), points(&mut rng, n, 1.5));
            for cost in COSTS {
                let c = source(&s, &t, cost);
                // Integer weights at 1e-9 resolution: the optima agree to n·1e-9.
                let w = Matrix::from_fn(n, n, |(i, j)| (c(i, j) * 1e9).round() as i64);
                let (km, _): (i64, _) = kuhn_munkres_min(&w);
                let to = pair(&s, &t, cost, Cancel::NEVER).unwrap();
                let (got, want) = (total(&*c, &to), km as f64 * 1e-9);
                assert!(
                    (got - want).abs() <= n as f64 * 1e-9,
                    "{cost:?} n={n}: {got} vs {want}"
                );
            }
        }
    }

    /// Sources on a line at x = 0, 1, 2, 10 (mean edge lengths 1, 1, 4.5, 8), targets
    /// at 0, 8, 9, 10 (8, 4.5, 1, 1): travel pairs them in order, local structure
    /// pairs the far source with the lone target.
    #[test]
    fn lambda_changes_the_pairing() {
        let line = |xs: [f64; 4]| xs.map(|x| Vec2::new(x, 0.0));
        let (s, t) = (line([0.0, 1.0, 2.0, 10.0]), line([0.0, 8.0, 9.0, 10.0]));
        let by = |lambda| pair(&s, &t, PairCost::LeastEffort { lambda }, Cancel::NEVER).unwrap();
        assert_eq!(by(1.0), [0, 1, 2, 3]);
        let local = by(0.0);
        assert_eq!(local[3], 0);
        assert_eq!(local[2], 1);
        assert_ne!(by(0.02), by(1.0));
    }

    /// The automatic strategy (sparse candidate lists above 128 targets) returns the
    /// dense strategy's pairing on 500-point instances: the same pairs where the
    /// optimum is unique (least effort, Euclidean), the same total where it is not
    /// (Manhattan distances tie on every pair of monotone paths).
    #[test]
    fn sparse_equals_dense_at_500() {
        let mut rng = SplitMix64::new(0x5a77);
        for round in 0..2 {
            let s = points(&mut rng, 500, 4.0);
            let mut t = points(&mut rng, 500, 3.0);
            if round == 1 {
                for p in &mut t {
                    p.x += 5.0;
                }
            }
            for cost in COSTS {
                let got = pair(&s, &t, cost, Cancel::NEVER).unwrap();
                let c = source(&s, &t, cost);
                let m = crate::crowd::assign::CostMatrix::from_fn(500, 500, &*c);
                let mut dense = Solver::with_strategy(Strategy::Dense);
                let want: Vec<u32> = dense.solve(&m).unwrap().iter().map(|&j| j as u32).collect();
                let (a, b) = (total(&*c, &got), total(&*c, &want));
                assert!(
                    (a - b).abs() <= 1e-9 * b,
                    "{cost:?} round {round}: {a} vs {b}"
                );
                if cost != PairCost::Manhattan {
                    assert_eq!(got, want, "{cost:?} round {round}");
                }
            }
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let p = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
        let nan = [Vec2::new(0.0, 0.0), Vec2::new(f64::NAN, 0.0)];
        for cost in COSTS {
            assert_eq!(pair(&[], &[], cost, Cancel::NEVER), Err(AssignError::Empty));
            assert!(matches!(
                pair(&p, &nan, cost, Cancel::NEVER),
                Err(AssignError::NotFinite { .. })
            ));
            assert!(matches!(
                pair(&nan, &p, cost, Cancel::NEVER),
                Err(AssignError::NotFinite { .. })
            ));
            assert!(matches!(
                pair(&p, &p[..1], cost, Cancel::NEVER),
                Err(AssignError::MoreRowsThanCols { .. })
            ));
            let mut rng = SplitMix64::new(3);
            let (s, t) = (points(&mut rng, 400, 1.0), points(&mut rng, 400, 1.0));
            let stop = || true;
            assert_eq!(
                pair(&s, &t, cost, Cancel::new(&stop)),
                Err(AssignError::Cancelled)
            );
        }
    }

    /// The closed forms of [`term_means`] against the sum over every pair.
    #[test]
    fn term_means_are_the_means_over_every_pair() {
        let mut rng = SplitMix64::new(0x7e);
        let s = points(&mut rng, 60, 3.0);
        let t: Vec<Vec2> = points(&mut rng, 60, 5.0)
            .into_iter()
            .map(|p| p + Vec2::new(4.0, 1.0))
            .collect();
        let (mut ds, mut dt) = (Vec::new(), Vec::new());
        mean_edge_lengths(&s, &mut ds);
        mean_edge_lengths(&t, &mut dt);
        let (mut d2, mut delta2) = (0.0, 0.0);
        for i in 0..60 {
            for j in 0..60 {
                d2 += (s[i] - t[j]).norm_squared();
                delta2 += (ds[i] - dt[j]).powi(2);
            }
        }
        let (d2, delta2) = (d2 / 3600.0, delta2 / 3600.0);
        let (a, b) = term_means(&s, &t);
        assert!((a - d2).abs() <= 1e-9 * d2, "{a} {d2}");
        assert!((b - delta2).abs() <= 1e-9 * delta2, "{b} {delta2}");
        // The raw terms differ by orders of magnitude: why λ needs normalising.
        assert!(d2 > 100.0 * delta2, "{d2} {delta2}");
    }

    /// The normalised cost's pairing is optimal for `ΔE'` itself, computed
    /// directly from its definition (each term over its mean), by brute force
    /// over every permutation of small instances.
    #[test]
    fn the_normalised_pairing_is_optimal_for_the_normalised_cost() {
        let mut rng = SplitMix64::new(0x4e0);
        for round in 0..12 {
            let n = 7;
            let s = points(&mut rng, n, 2.0);
            let t: Vec<Vec2> = points(&mut rng, n, 3.0 + round as f64)
                .into_iter()
                .map(|p| p + Vec2::new(1.0, 0.0))
                .collect();
            let (d2, delta2) = term_means(&s, &t);
            let (mut ds, mut dt) = (Vec::new(), Vec::new());
            mean_edge_lengths(&s, &mut ds);
            mean_edge_lengths(&t, &mut dt);
            for lambda in [0.0, 0.1, 0.5, 0.9, 1.0] {
                let c = |i: usize, j: usize| {
                    lambda * (s[i] - t[j]).norm_squared() / d2
                        + (1.0 - lambda) * (ds[i] - dt[j]).powi(2) / delta2
                };
                let got = pair(
                    &s,
                    &t,
                    PairCost::LeastEffortNormalised { lambda },
                    Cancel::NEVER,
                )
                .unwrap();
                let (a, b) = (total(&c, &got), brute_force(n, &c));
                assert!(
                    a <= b + 1e-9 * b.max(1.0),
                    "round {round} λ {lambda}: {a} vs {b}"
                );
            }
        }
    }

    /// Across a sweep of the normalised `λ` the pairing changes, and as `λ`
    /// rises the travel term of the optimum never grows and the local-structure
    /// term never shrinks (the optimum of `λA + (1 − λ)B` over a fixed set of
    /// pairings moves monotonically). At the raw `λ`, 0.25 to 1 all give the
    /// travel-only pairing: the local term is too small to matter.
    #[test]
    fn the_lambda_sweep_changes_the_pairing_monotonically() {
        let mut rng = SplitMix64::new(0x1a3b);
        // A dense square to a sparser ring-like band: local edge lengths change.
        let s = points(&mut rng, 200, 4.0);
        let t: Vec<Vec2> = (0..200)
            .map(|_| {
                let a = std::f64::consts::TAU * rng.unit();
                let r = 3.0 + 2.0 * rng.unit() * rng.unit();
                Vec2::new(2.0 + r * a.cos(), 2.0 + r * a.sin())
            })
            .collect();
        let sweep = [0.0, 0.25, 0.5, 0.75, 1.0];
        let terms = |cost: PairCost| {
            let to = pair(&s, &t, cost, Cancel::NEVER).unwrap();
            let paired: Vec<Vec2> = to.iter().map(|&j| t[j as usize]).collect();
            (to, pairing_terms(&s, &paired))
        };
        let norm: Vec<_> = sweep
            .iter()
            .map(|&lambda| terms(PairCost::LeastEffortNormalised { lambda }))
            .collect();
        for w in norm.windows(2) {
            let ((_, (ta, la)), (_, (tb, lb))) = (&w[0], &w[1]);
            assert!(tb <= &(ta * (1.0 + 1e-9)), "travel {ta} then {tb}");
            assert!(lb >= &(la * (1.0 - 1e-9)), "local {la} then {lb}");
        }
        let distinct: std::collections::HashSet<&Vec<u32>> =
            norm.iter().map(|(to, _)| to).collect();
        assert!(distinct.len() >= 4, "{} distinct pairings", distinct.len());
        let (t0, l0) = norm[0].1;
        let (t1, l1) = norm[4].1;
        assert!(t0 > 1.5 * t1, "travel at λ 0: {t0}, at λ 1: {t1}");
        assert!(l1 > 1.3 * l0, "local at λ 1: {l1}, at λ 0: {l0}");
        // Raw λ: from 0.25 up the travel term decides, within 1 % of the
        // travel-only optimum (the local term only picks among near-ties of
        // travel); the normalised λ = 0.5 trades more than 5 % of travel for a
        // lower local term.
        let (t_half, l_half) = norm[2].1;
        for lambda in [0.25, 0.5, 0.75] {
            let (_, (tr, lr)) = terms(PairCost::LeastEffort { lambda });
            assert!(tr <= 1.01 * t1, "raw λ {lambda}: travel {tr}, λ 1: {t1}");
            assert!(
                lr > l_half,
                "raw λ {lambda}: local {lr}, normalised 0.5: {l_half}"
            );
        }
        assert!(
            t_half > 1.05 * t1,
            "normalised λ 0.5: travel {t_half}, λ 1: {t1}"
        );
    }
}
