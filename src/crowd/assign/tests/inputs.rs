//! What the solver does with every kind of input: errors instead of panics, NaN and
//! `-inf` named at their position, unreachable (`+inf`) goals, the providers'
//! matrices, and workspaces kept across same-sized inputs.

use super::support::{points, solvers};
use crate::crowd::assign::costs::{CostMatrix, CostProvider, Distance, SquaredDistance};
use crate::crowd::assign::error::AssignError;
use crate::crowd::assign::solver::{Solver, Strategy as Algo};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

#[test]
fn errors_are_reported_not_panicked() {
    for mut s in solvers() {
        assert_eq!(s.solve(&CostMatrix::new(0, 0)), Err(AssignError::Empty));
        assert_eq!(s.solve(&CostMatrix::new(0, 3)), Err(AssignError::Empty));
        assert_eq!(
            s.solve(&CostMatrix::new(3, 2)),
            Err(AssignError::MoreRowsThanCols { rows: 3, cols: 2 })
        );
        let mut c = CostMatrix::new(3, 3);
        c.set(1, 2, f64::NAN);
        assert_eq!(s.solve(&c), Err(AssignError::NotFinite { row: 1, col: 2 }));
        c.set(1, 2, 0.0);
        c.set(2, 0, f64::NEG_INFINITY);
        assert_eq!(
            s.solve_warm(&c),
            Err(AssignError::NotFinite { row: 2, col: 0 })
        );
        assert!(s.assignment().is_empty());
        c.set(2, 0, 1.0);
        c.row_mut(1).fill(f64::INFINITY);
        assert_eq!(s.solve(&c), Err(AssignError::Infeasible { row: 1 }));
        // Square with an all-+inf column: some row is left without a finite goal.
        let mut c = CostMatrix::from_fn(3, 3, |i, j| (i + j) as f64);
        for i in 0..3 {
            c.set(i, 1, f64::INFINITY);
        }
        assert!(matches!(s.solve(&c), Err(AssignError::Infeasible { .. })));
        // Hall violation: rows 0 and 1 can only use column 0.
        let c = CostMatrix::from_fn(2, 3, |_, j| if j == 0 { 1.0 } else { f64::INFINITY });
        assert_eq!(s.solve(&c), Err(AssignError::Infeasible { row: 1 }));
        assert!(s.assignment().is_empty());
        assert!(s.total_cost(&c).is_nan());
        assert!(!s.verify_optimal(&c, 1.0));
        // Recovers after errors, warm falls back to cold.
        let c = CostMatrix::from_fn(2, 3, |i, j| ((i + 2 * j) % 3) as f64);
        assert!(s.solve_warm(&c).is_ok());
        assert!(s.verify_optimal(&c, 0.0));
    }
}

/// The streaming pass of the sparse strategy filters whole blocks by their
/// smallest reduced cost, which may skip a NaN lane: a NaN or `-inf` hidden among
/// large entries must still be reported, cold and warm, at its exact position.
#[test]
fn not_finite_hidden_in_a_block_is_reported() {
    let mut rng = SplitMix64::new(21);
    let (a, g) = (points(&mut rng, 300), points(&mut rng, 300));
    let mut c = CostMatrix::new(0, 0);
    for bad in [f64::NAN, f64::NEG_INFINITY] {
        for (row, col) in [(0usize, 3usize), (150, 151), (299, 297)] {
            SquaredDistance.fill(&a, &g, &mut c);
            let mut s = Solver::with_strategy(Algo::Sparse);
            s.solve(&c).unwrap();
            // The other lanes of the block are far above any candidate threshold.
            for e in &mut c.row_mut(row)[col & !7..((col & !7) + 8).min(300)] {
                *e = 1e6;
            }
            c.set(row, col, bad);
            assert_eq!(
                s.solve_warm(&c),
                Err(AssignError::NotFinite { row, col }),
                "warm {bad} at ({row}, {col})"
            );
            assert_eq!(
                s.solve(&c),
                Err(AssignError::NotFinite { row, col }),
                "cold {bad} at ({row}, {col})"
            );
        }
    }
}

/// `+inf` is a legitimate "unreachable" cost in large (sparse) problems too, and an
/// all-`+inf` row names its agent.
#[test]
fn unreachable_goals_in_a_large_problem() {
    let mut rng = SplitMix64::new(22);
    let (a, g) = (points(&mut rng, 300), points(&mut rng, 320));
    let mut c = CostMatrix::new(0, 0);
    SquaredDistance.fill(&a, &g, &mut c);
    for (i, j) in (0..300).map(|i| (i, (i * 7) % 320)) {
        c.set(i, j, f64::INFINITY);
    }
    let mut s = Solver::with_strategy(Algo::Sparse);
    s.solve(&c).unwrap();
    assert!(s.verify_optimal(&c, 1e-9));
    assert!(s
        .assignment()
        .iter()
        .enumerate()
        .all(|(i, &j)| c.get(i, j).is_finite()));
    c.row_mut(123).fill(f64::INFINITY);
    assert_eq!(s.solve_warm(&c), Err(AssignError::Infeasible { row: 123 }));
    assert_eq!(s.solve(&c), Err(AssignError::Infeasible { row: 123 }));
}

#[test]
fn infinite_entries_are_avoided() {
    // The only finite assignment is the anti-diagonal.
    let c = CostMatrix::from_fn(4, 4, |i, j| if i + j == 3 { 100.0 } else { f64::INFINITY });
    for mut s in solvers() {
        assert_eq!(s.solve(&c).unwrap(), &[3, 2, 1, 0]);
        assert_eq!(s.total_cost(&c), 400.0);
    }
}

#[test]
fn repeated_same_size_solves_keep_buffers() {
    let mut rng = SplitMix64::new(9);
    let mut c = CostMatrix::new(0, 0);
    for (strategy, cols) in [(Algo::Dense, 300), (Algo::Sparse, 300), (Algo::Sparse, 350)] {
        let (mut a, g) = (points(&mut rng, 300), points(&mut rng, cols));
        let mut s = Solver::with_strategy(strategy);
        SquaredDistance.fill(&a, &g, &mut c);
        s.solve(&c).unwrap();
        let fp = s.buffer_fingerprint();
        for frame in 0..6 {
            for p in &mut a {
                p.x += 0.01 * (rng.unit() - 0.5);
            }
            SquaredDistance.fill(&a, &g, &mut c);
            if frame % 2 == 0 {
                s.solve_warm(&c).unwrap();
            } else {
                s.solve(&c).unwrap();
            }
            assert_eq!(fp, s.buffer_fingerprint(), "{strategy:?} frame {frame}");
        }
    }
}

#[test]
fn providers_fill_expected_costs() {
    let agents = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)];
    let goals = [
        Vec2::new(3.0, 4.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    let mut c = CostMatrix::new(5, 5);
    SquaredDistance.fill(&agents, &goals, &mut c);
    assert_eq!((c.rows(), c.cols()), (2, 3));
    assert_eq!(c.row(0), &[25.0, 2.0, 1.0]);
    Distance.fill(&agents, &goals, &mut c);
    assert!((c.get(0, 0) - 5.0).abs() < 1e-12);
    assert!((c.get(0, 1) - 2f64.sqrt()).abs() < 1e-12);
    assert_eq!(c.get(1, 1), 0.0);
    let mut s = Solver::new();
    assert_eq!(s.solve(&c).unwrap(), &[2, 1]);
}
