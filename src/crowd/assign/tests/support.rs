//! Instances, reference answers and solver configurations shared by the tests.

use crate::crowd::assign::costs::CostMatrix;
use crate::crowd::assign::solver::{Solver, Strategy as Algo};
use crate::geom::Vec2;
use crate::rng::SplitMix64;
use proptest::test_runner::{Config as ProptestConfig, RngSeed};

pub(super) fn points(rng: &mut SplitMix64, n: usize) -> Vec<Vec2> {
    (0..n).map(|_| Vec2::new(rng.unit(), rng.unit())).collect()
}

/// Minimum total cost over all injections rows -> cols (None if none is finite).
pub(super) fn brute_force(c: &CostMatrix) -> Option<f64> {
    fn rec(c: &CostMatrix, i: usize, used: &mut [bool], acc: f64, best: &mut f64) {
        if i == c.rows() {
            if acc < *best {
                *best = acc;
            }
            return;
        }
        for j in 0..c.cols() {
            let e = c.get(i, j);
            if !used[j] && e < f64::INFINITY {
                used[j] = true;
                rec(c, i + 1, used, acc + e, best);
                used[j] = false;
            }
        }
    }
    let mut best = f64::INFINITY;
    rec(c, 0, &mut vec![false; c.cols()], 0.0, &mut best);
    best.is_finite().then_some(best)
}

/// Every configuration worth exercising: dense, sparse with very few candidates
/// (forces many pricing rounds and repairs), sparse default, auto.
pub(super) fn solvers() -> Vec<Solver> {
    vec![
        Solver::with_strategy(Algo::Dense),
        Solver::with_options(Algo::Sparse, 1),
        Solver::with_options(Algo::Sparse, 2),
        Solver::with_strategy(Algo::Sparse),
        Solver::new(),
    ]
}

pub(super) fn config(cases: u32, seed: u64) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}
