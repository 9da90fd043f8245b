//! The solver's answers against references: brute force on small matrices, the dense
//! strategy on medium ones, `pathfinding`'s Kuhn–Munkres, and the dual certificate
//! over chains of warm frames.

use super::support::{brute_force, config, points, solvers};
use crate::crowd::assign::costs::{CostMatrix, CostProvider, Distance, SquaredDistance};
use crate::crowd::assign::solver::{Solver, Strategy as Algo, MAX_ROUNDS};
use crate::rng::SplitMix64;
use proptest::prelude::{prop_assert, prop_oneof, proptest, Just, TestCaseError};
use proptest::strategy::Strategy as _;

fn check_against_brute(s: &mut Solver, c: &CostMatrix, warm: bool) -> Result<(), TestCaseError> {
    let want = brute_force(c).expect("instances are feasible by construction");
    let res = if warm {
        s.solve_warm(c).map(|_| ())
    } else {
        s.solve(c).map(|_| ())
    };
    prop_assert!(res.is_ok(), "{:?} failed: {:?}", s.strategy(), res);
    let got = s.total_cost(c);
    prop_assert!(
        (got - want).abs() <= 1e-9 * (1.0 + want.abs()),
        "{:?} (k={}) warm={}: got {} want {}",
        s.strategy(),
        s.k,
        warm,
        got,
        want
    );
    prop_assert!(s.verify_optimal(c, 1e-9));
    Ok(())
}

/// A feasible matrix: rows <= cols <= 8, integer (tie-heavy) or real entries, some
/// `+inf`, and a hidden injection kept finite so a finite assignment exists.
fn matrix() -> impl proptest::strategy::Strategy<Value = CostMatrix> {
    (1usize..=8)
        .prop_flat_map(|r| (Just(r), r..=8usize))
        .prop_flat_map(|(r, c)| {
            let entry = prop_oneof![
                4 => (0i32..4).prop_map(f64::from),
                4 => -10.0..10.0f64,
                1 => Just(f64::INFINITY),
            ];
            (
                Just(r),
                Just(c),
                proptest::collection::vec(entry, r * c),
                Just((0..c).collect::<Vec<usize>>()).prop_shuffle(),
            )
        })
        .prop_map(|(r, c, data, perm)| {
            let mut m = CostMatrix::from_fn(r, c, |i, j| data[i * c + j]);
            for (i, &j) in perm.iter().take(r).enumerate() {
                if m.get(i, j) == f64::INFINITY {
                    m.set(i, j, 3.0);
                }
            }
            m
        })
}

proptest! {
    #![proptest_config(config(160, 0x00A5_5167))]

    #[test]
    fn cold_equals_brute_force(c in matrix()) {
        for mut s in solvers() {
            check_against_brute(&mut s, &c, false)?;
        }
    }
}

proptest! {
    #![proptest_config(config(96, 0x0005_1A7E))]

    #[test]
    fn warm_after_perturbation_equals_brute_force(
        c in matrix(),
        noise in proptest::collection::vec((0usize..64, -2i32..=2, -0.5..0.5f64), 0..12),
        frames in 1usize..4,
    ) {
        for mut s in solvers() {
            check_against_brute(&mut s, &c, false)?;
            let mut cur = c.clone();
            for f in 0..frames {
                // Perturb some finite entries (integer steps keep ties; real steps
                // break them), never creating an infeasible instance.
                for (t, &(idx, step, real)) in noise.iter().enumerate() {
                    let e = (idx + 7 * t + 13 * f) % (cur.rows() * cur.cols());
                    let (i, j) = (e / cur.cols(), e % cur.cols());
                    let old = cur.get(i, j);
                    if old.is_finite() {
                        let new = if t % 2 == 0 { old + f64::from(step) } else { old + real };
                        cur.set(i, j, new);
                    }
                }
                check_against_brute(&mut s, &cur, true)?;
            }
        }
    }
}

fn run_chain(rows: usize, cols: usize, seed: u64, strategy: Algo) {
    let mut rng = SplitMix64::new(seed);
    let mut agents = points(&mut rng, rows);
    let mut goals = points(&mut rng, cols);
    let mut c = CostMatrix::new(0, 0);
    let mut s = Solver::with_strategy(strategy);
    SquaredDistance.fill(&agents, &goals, &mut c);
    s.solve(&c).unwrap();
    assert!(
        s.verify_optimal(&c, 1e-9),
        "cold {rows}x{cols} {strategy:?}"
    );
    let mut cold = Solver::with_strategy(Algo::Dense);
    for frame in 0..20 {
        for p in goals.iter_mut().chain(agents.iter_mut().take(rows / 10)) {
            p.x += 0.04 * (rng.unit() - 0.5);
            p.y += 0.04 * (rng.unit() - 0.5);
        }
        SquaredDistance.fill(&agents, &goals, &mut c);
        s.solve_warm(&c).unwrap();
        // Warm, or restarted cold because the old prices were far off.
        assert!(
            s.stats().warm || s.stats().restarted_cold,
            "{:?}",
            s.stats()
        );
        assert!(
            s.verify_optimal(&c, 1e-9),
            "warm frame {frame} {rows}x{cols} {strategy:?}"
        );
        if frame % 5 == 0 {
            cold.solve(&c).unwrap();
            assert!(cold.verify_optimal(&c, 1e-9));
            let (a, b) = (s.total_cost(&c), cold.total_cost(&c));
            assert!((a - b).abs() < 1e-9, "frame {frame}: warm {a} cold {b}");
        }
    }
}

/// A medium instance: random real or small-integer costs (ties), some `+inf`
/// entries off a hidden feasible injection.
fn medium(rows: usize, cols: usize, seed: u64, ints: bool, inf_per_mille: u64) -> CostMatrix {
    let mut rng = SplitMix64::new(seed);
    let mut perm: Vec<usize> = (0..cols).collect();
    for i in (1..cols).rev() {
        perm.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let mut c = CostMatrix::from_fn(rows, cols, |_, _| {
        if rng.next_u64() % 1000 < inf_per_mille {
            f64::INFINITY
        } else if ints {
            (rng.next_u64() % 6) as f64
        } else {
            10.0 * rng.unit() - 3.0
        }
    });
    for (i, &j) in perm.iter().take(rows).enumerate() {
        if c.get(i, j) == f64::INFINITY {
            c.set(i, j, 2.0);
        }
    }
    c
}

proptest! {
    #![proptest_config(config(48, 0x0000_3D1A))]

    /// The sparse machinery (auction, tightening, lazy lists, list refills,
    /// rectangular price raises, dense finish) against the dense solver on
    /// instances too large for brute force, cold and over warm frames.
    #[test]
    fn sparse_matches_dense_on_medium_instances(
        rows in 5usize..40,
        extra in 0usize..12,
        seed in 0u64..u64::MAX,
        ints: bool,
        inf_per_mille in prop_oneof![Just(0u64), Just(100), Just(400)],
        k in 1usize..6,
        max_rounds in prop_oneof![Just(0u32), Just(1), Just(MAX_ROUNDS)],
    ) {
        let cols = rows + extra;
        let mut dense = Solver::with_strategy(Algo::Dense);
        let mut sparse = Solver::with_options(Algo::Sparse, k);
        sparse.max_rounds = Some(max_rounds);
        let mut c = medium(rows, cols, seed, ints, inf_per_mille);
        for frame in 0..4u64 {
            dense.solve(&c).unwrap();
            let res = if frame == 0 { sparse.solve(&c) } else { sparse.solve_warm(&c) };
            prop_assert!(res.is_ok(), "{:?}", res);
            prop_assert!(sparse.verify_optimal(&c, 1e-9), "frame {}", frame);
            let (a, b) = (sparse.total_cost(&c), dense.total_cost(&c));
            prop_assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "frame {}: {} vs {}", frame, a, b);
            // Next frame: perturb the finite entries.
            let mut rng = SplitMix64::new(seed ^ (frame + 1));
            for i in 0..rows {
                for e in c.row_mut(i) {
                    if e.is_finite() && rng.next_u64() % 3 == 0 {
                        *e += if ints { (rng.next_u64() % 3) as f64 - 1.0 } else { rng.unit() - 0.5 };
                    }
                }
            }
        }
    }
}

#[test]
fn certificate_square_200_cold_and_warm_chain() {
    run_chain(200, 200, 1, Algo::Sparse);
    run_chain(200, 200, 2, Algo::Dense);
}

#[test]
fn certificate_rectangular_300x400_cold_and_warm_chain() {
    run_chain(300, 400, 3, Algo::Sparse);
    run_chain(300, 400, 4, Algo::Dense);
}

#[test]
fn sparse_with_one_candidate_matches_dense_on_200() {
    let mut rng = SplitMix64::new(5);
    let (a, g) = (points(&mut rng, 200), points(&mut rng, 230));
    let mut c = CostMatrix::new(0, 0);
    Distance.fill(&a, &g, &mut c);
    let mut sparse = Solver::with_options(Algo::Sparse, 1);
    let mut dense = Solver::with_strategy(Algo::Dense);
    sparse.solve(&c).unwrap();
    dense.solve(&c).unwrap();
    assert!(sparse.verify_optimal(&c, 1e-9));
    assert!((sparse.total_cost(&c) - dense.total_cost(&c)).abs() < 1e-9);
}

#[test]
fn matches_pathfinding_kuhn_munkres_on_integer_costs() {
    use pathfinding::kuhn_munkres::kuhn_munkres;
    use pathfinding::matrix::Matrix;
    for (seed, (rows, cols)) in [(10u64, (50, 50)), (11, (50, 50)), (12, (40, 50))] {
        let mut rng = SplitMix64::new(seed);
        let ints: Vec<i64> = (0..rows * cols)
            .map(|_| (rng.next_u64() % 100) as i64)
            .collect();
        let c = CostMatrix::from_fn(rows, cols, |i, j| ints[i * cols + j] as f64);
        let neg = Matrix::from_vec(rows, cols, ints.iter().map(|&x| -x).collect()).unwrap();
        let (best, _) = kuhn_munkres(&neg);
        for mut s in solvers() {
            s.solve(&c).unwrap();
            assert_eq!(s.total_cost(&c), -best as f64, "{:?}", s.strategy());
            assert!(s.verify_optimal(&c, 1e-9));
        }
    }
}

#[test]
fn default_solver_is_new() {
    let c = CostMatrix::from_fn(200, 200, |i, j| ((i * 31 + j * 17) % 97) as f64);
    let mut a = Solver::default();
    a.solve(&c).unwrap();
    assert_eq!(a.strategy(), Algo::Auto);
    assert!(!a.stats().dense_finish);
    assert!(a.verify_optimal(&c, 1e-9));
}

#[test]
fn warm_with_changed_dimensions_is_cold() {
    let mut s = Solver::new();
    let c = CostMatrix::from_fn(3, 3, |i, j| ((i * 7 + j * 3) % 5) as f64);
    s.solve(&c).unwrap();
    let c2 = CostMatrix::from_fn(3, 4, |i, j| ((i * 5 + j * 3) % 7) as f64);
    s.solve_warm(&c2).unwrap();
    assert!(!s.stats().warm);
    assert_eq!(brute_force(&c2), Some(s.total_cost(&c2)));
    s.solve_warm(&c2).unwrap();
    assert!(s.stats().warm);
    assert_eq!(s.stats().kept_rows, 3);
}

/// With warm restarts off, a warm start whose pairs nearly all broke goes on from
/// the old prices (never restarted cold) and still reaches the optimum: Euclidean
/// costs (flat along the direction of travel) of 300 agents whose formation jumps
/// by about a spacing each frame, against the dense cold solve.
#[test]
fn warm_without_restarts_stays_optimal_when_every_pair_breaks() {
    let mut rng = SplitMix64::new(17);
    let agents = points(&mut rng, 300);
    let mut goals = points(&mut rng, 300);
    for g in &mut goals {
        g.x += 3.0;
    }
    let mut c = CostMatrix::new(0, 0);
    let mut s = Solver::with_strategy(Algo::Sparse);
    s.set_warm_restarts(false);
    let mut cold = Solver::with_strategy(Algo::Dense);
    Distance.fill(&agents, &goals, &mut c);
    s.solve(&c).unwrap();
    for frame in 0..8 {
        for g in &mut goals {
            g.x -= 0.3 * rng.unit();
            g.y += 0.1 * (rng.unit() - 0.5);
        }
        Distance.fill(&agents, &goals, &mut c);
        s.solve_warm(&c).unwrap();
        let st = s.stats();
        assert!(st.warm && !st.restarted_cold, "frame {frame}: {st:?}");
        assert!(s.verify_optimal(&c, 1e-9), "frame {frame}");
        cold.solve(&c).unwrap();
        let (a, b) = (s.total_cost(&c), cold.total_cost(&c));
        assert!((a - b).abs() < 1e-9, "frame {frame}: warm {a} cold {b}");
    }
}
