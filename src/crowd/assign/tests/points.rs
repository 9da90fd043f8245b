//! [`PointCosts`] against the matrix they describe: the same assignment, work
//! counters and certificate; errors naming the first bad position; no reallocation
//! on same-sized frames.

use super::support::{config, points};
use crate::crowd::assign::costs::{
    CostMatrix, CostProvider, CostSource, Distance, SquaredDistance,
};
use crate::crowd::assign::error::AssignError;
use crate::crowd::assign::points::{PointCosts, PointMetric};
use crate::crowd::assign::solver::{SolveStats, Solver, Strategy as Algo};
use crate::geom::Vec2;
use crate::rng::SplitMix64;
use proptest::prelude::{prop_assert, prop_oneof, proptest, Just};

/// Point sets for the geometric fast path: uniform, clustered (most goals in two
/// small clumps), duplicated positions, all goals on one line, and a crowd far
/// from its formation.
fn layout(rng: &mut SplitMix64, n: usize, kind: u8) -> Vec<Vec2> {
    (0..n)
        .map(|k| match kind {
            0 => Vec2::new(rng.unit(), rng.unit()),
            1 => {
                let c = if k % 3 == 0 { 0.2 } else { 0.8 };
                Vec2::new(c + 0.01 * rng.unit(), c + 0.01 * rng.unit())
            }
            2 => Vec2::new((k % 5) as f64 * 0.25, 0.5),
            3 => Vec2::new(rng.unit(), 0.3),
            _ => Vec2::new(40.0 + rng.unit(), -7.0 + rng.unit()),
        })
        .collect()
}

proptest! {
    #![proptest_config(config(64, 0x09E0_FA57))]

    /// The spatial candidate lists of `PointCosts` are exactly the streamed
    /// ones: the same assignment and the same work counters as on the matrix,
    /// cold and over warm frames in which the goals move, square and
    /// rectangular, both metrics, every layout.
    #[test]
    fn point_costs_solve_exactly_as_the_matrix(
        rows in 8usize..60,
        extra in prop_oneof![Just(0usize), Just(3), Just(40)],
        candidates in prop_oneof![Just(0usize), Just(2), Just(5)],
        seed in 0u64..u64::MAX,
        agents_kind in 0u8..5,
        goals_kind in 0u8..5,
        euclid: bool,
    ) {
        let mut rng = SplitMix64::new(seed);
        let cols = rows + extra;
        let agents = layout(&mut rng, rows, agents_kind);
        let mut goals = layout(&mut rng, cols, goals_kind);
        let metric = if euclid { PointMetric::Euclidean } else { PointMetric::Squared };
        let mut pc = PointCosts::new(metric);
        let mut c = CostMatrix::new(0, 0);
        // The sparse strategy at any size (Auto turns to it above 128 columns);
        // short lists exercise the list refills.
        let solver = || Solver::with_options(Algo::Sparse, candidates);
        let (mut sp, mut sm) = (solver(), solver());
        for frame in 0..3 {
            pc.set(&agents, &goals);
            if euclid {
                Distance.fill(&agents, &goals, &mut c);
            } else {
                SquaredDistance.fill(&agents, &goals, &mut c);
            }
            for i in 0..rows {
                for j in (0..cols).step_by(17) {
                    prop_assert!(pc.get(i, j).to_bits() == c.get(i, j).to_bits());
                }
            }
            let a = sp.solve_warm_with(&pc).unwrap().to_vec();
            let b = sm.solve_warm(&c).unwrap().to_vec();
            prop_assert!(a == b, "frame {}: assignments differ", frame);
            // The same work; polls follow each source's own work units.
            let (ws, wm) = (SolveStats { polls: 0, ..sp.stats() }, SolveStats { polls: 0, ..sm.stats() });
            prop_assert!(ws == wm, "frame {}: {:?} vs {:?}", frame, ws, wm);
            prop_assert!(sp.verify_optimal(&c, 1e-9));
            prop_assert!(sp.verify_optimal(&pc, 1e-9));
            for g in &mut goals {
                g.x += 0.04 * (rng.unit() - 0.5);
                g.y += 0.04 * (rng.unit() - 0.5);
            }
        }
    }
}

#[test]
fn point_costs_name_the_first_bad_position() {
    let mut pc = PointCosts::new(PointMetric::Squared);
    let mut s = Solver::new();
    let ok = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 1.0)];
    pc.set(&[ok[0], Vec2::new(f64::NAN, 0.0)], &ok);
    assert_eq!(
        s.solve_with(&pc),
        Err(AssignError::NotFinite { row: 1, col: 0 })
    );
    pc.set(&ok, &[ok[1], Vec2::new(0.0, f64::INFINITY)]);
    assert_eq!(
        s.solve_with(&pc),
        Err(AssignError::NotFinite { row: 0, col: 1 })
    );
    pc.set(&[], &ok);
    assert_eq!(s.solve_with(&pc), Err(AssignError::Empty));
    pc.set(&ok, &ok[..1]);
    assert_eq!(
        s.solve_with(&pc),
        Err(AssignError::MoreRowsThanCols { rows: 2, cols: 1 })
    );
    // The solver recovers: the next good instance solves.
    pc.set(&ok, &[ok[1], ok[0]]);
    assert_eq!(s.solve_with(&pc).unwrap(), &[1, 0]);
}

#[test]
fn point_costs_do_not_reallocate_on_same_sized_frames() {
    let mut rng = SplitMix64::new(7);
    let agents = points(&mut rng, 300);
    let mut goals = points(&mut rng, 300);
    let mut pc = PointCosts::new(PointMetric::Squared);
    let mut s = Solver::new();
    pc.set(&agents, &goals);
    s.solve_with(&pc).unwrap();
    let caps = |p: &PointCosts| {
        [&p.ax, &p.ay, &p.gx, &p.gy, &p.bx, &p.by]
            .iter()
            .map(|v| (v.as_ptr() as usize, v.capacity()))
            .chain(
                [&p.start, &p.order]
                    .iter()
                    .map(|v| (v.as_ptr() as usize, v.capacity())),
            )
            .collect::<Vec<_>>()
    };
    let (before, fp) = (caps(&pc), s.buffer_fingerprint());
    for _ in 0..5 {
        for g in &mut goals {
            g.x += 0.01 * (rng.unit() - 0.5);
        }
        pc.set(&agents, &goals);
        s.solve_warm_with(&pc).unwrap();
    }
    assert_eq!(caps(&pc), before);
    assert_eq!(s.buffer_fingerprint(), fp);
}
