//! The [`Assigner`] (positions mapped by [`AffineMap`], warm starts, cold restarts) on
//! the hard layouts: the same optimum as the dense solver on the unmapped matrix.

use crate::crowd::assign::costs::{CostMatrix, CostProvider, SquaredDistance};
use crate::crowd::assign::solver::{Solver, Strategy};
use crate::crowd::assign::{Assigner, Layout, PointMetric};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// The optimum of the unmapped instance (dense strategy, certificate checked).
fn reference(agents: &[Vec2], goals: &[Vec2]) -> f64 {
    let mut c = CostMatrix::new(agents.len(), goals.len());
    SquaredDistance.fill(agents, goals, &mut c);
    let mut s = Solver::with_strategy(Strategy::Dense);
    s.solve(&c).expect("feasible");
    assert!(s.verify_optimal(&c, 1e-9));
    s.total_cost(&c)
}

/// Checks the assigner's answer: a permutation whose cost is the reference optimum.
fn check(assigner: &Assigner, agents: &[Vec2], goals: &[Vec2], goal_of: &[u32], what: &str) {
    let mut seen = vec![false; goals.len()];
    for &g in goal_of {
        assert!(
            !std::mem::replace(&mut seen[g as usize], true),
            "{what}: goal {g} twice"
        );
    }
    let total: f64 = agents
        .iter()
        .zip(goal_of)
        .map(|(a, &g)| (a - goals[g as usize]).norm_squared())
        .sum();
    let best = reference(agents, goals);
    assert!(
        (total - best).abs() <= 1e-9 * best.max(1.0),
        "{what}: total {total} against the optimum {best}"
    );
    assert!(assigner.verify_optimal(1e-9), "{what}: certificate");
}

#[test]
fn every_layout_cold_and_warm_gives_the_optimum_of_the_unmapped_matrix() {
    let n = 300; // above the dense cut-off: the sparse strategy and the spatial lists
    let mut goal_of = Vec::new();
    for layout in Layout::ALL {
        let (agents, mut goals) = layout.instance(&mut SplitMix64::new(21), n);
        let mut a = Assigner::new(PointMetric::Squared);
        a.solve(&agents, &goals, &mut goal_of).unwrap();
        check(&a, &agents, &goals, &goal_of, &format!("{layout:?} cold"));
        let step = 0.04 * layout.goal_extent();
        let mut moves = SplitMix64::new(5);
        for f in 0..3 {
            for p in &mut goals {
                p.x += step.x * (moves.unit() - 0.5);
                p.y += step.y * (moves.unit() - 0.5);
            }
            a.solve(&agents, &goals, &mut goal_of).unwrap();
            assert!(a.stats().warm, "{layout:?} frame {f} warm");
            check(
                &a,
                &agents,
                &goals,
                &goal_of,
                &format!("{layout:?} warm {f}"),
            );
        }
    }
}

#[test]
fn a_warm_start_far_from_its_prices_restarts_cold_and_stays_exact() {
    // A formation deformed by several goal spacings between two frames: the old
    // prices are far off, the solve goes on cold.
    let n = 600;
    let (agents, goals) = Layout::Uniform.instance(&mut SplitMix64::new(8), n);
    let mut goal_of = Vec::new();
    let mut a = Assigner::new(PointMetric::Squared);
    a.solve(&agents, &goals, &mut goal_of).unwrap();
    let bent: Vec<Vec2> = goals
        .iter()
        .map(|g| {
            Vec2::new(
                g.x + 0.25 * (6.0 * g.y).sin(),
                g.y + 0.25 * (5.0 * g.x).cos(),
            )
        })
        .collect();
    a.solve(&agents, &bent, &mut goal_of).unwrap();
    let stats = a.stats();
    assert!(stats.restarted_cold && !stats.warm, "{stats:?}");
    check(&a, &agents, &bent, &goal_of, "restarted");
    // A small drift afterwards stays warm.
    let drift: Vec<Vec2> = bent.iter().map(|g| g + Vec2::new(0.001, 0.0)).collect();
    a.solve(&agents, &drift, &mut goal_of).unwrap();
    assert!(a.stats().warm && !a.stats().restarted_cold);
    check(&a, &agents, &drift, &goal_of, "drift");
}

#[test]
fn the_plain_distance_and_rectangular_instances_are_solved_unmapped() {
    // Neither is invariant under the map; both must still give their own optimum.
    let (agents, goals) = Layout::Shifted.instance(&mut SplitMix64::new(2), 200);
    let mut goal_of = Vec::new();
    let mut a = Assigner::new(PointMetric::Squared);
    a.solve(&agents[..150], &goals, &mut goal_of).unwrap();
    let mut c = CostMatrix::new(150, 200);
    SquaredDistance.fill(&agents[..150], &goals, &mut c);
    let mut s = Solver::with_strategy(Strategy::Dense);
    s.solve(&c).unwrap();
    let total: f64 = goal_of
        .iter()
        .enumerate()
        .map(|(i, &g)| c.get(i, g as usize))
        .sum();
    assert!((total - s.total_cost(&c)).abs() <= 1e-9 * total);
}
