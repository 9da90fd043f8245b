//! The cost provider against brute force: one full field per source cell.

use super::{block_rect, free_points, scene, scene_at};
use crate::crowd::assign::{CostMatrix, CostProvider};
use crate::crowd::environment::eikonal::{
    sample, EikonalCosts, EikonalError, EikonalOptions, FieldSources, Fmm, Grid, Order, Sources,
};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// Brute force: one full field per source cell, read bilinearly.
fn brute(
    grid: &Grid,
    cost: &[f64],
    agents: &[Vec2],
    goals: &[Vec2],
    from_goals: bool,
    order: Order,
) -> CostMatrix {
    let mut m = CostMatrix::new(agents.len(), goals.len());
    let mut fmm = Fmm::with_order(order);
    let mut phi = vec![0.0; grid.len()];
    let (sources, readers) = if from_goals {
        (goals, agents)
    } else {
        (agents, goals)
    };
    for (k, &s) in sources.iter().enumerate() {
        let c = grid.center(grid.cell_of(s).unwrap());
        fmm.solve_into(grid, cost, Sources::Points(&[c]), &mut phi)
            .unwrap();
        for (j, &p) in readers.iter().enumerate() {
            let v = sample(grid, &phi, p);
            if from_goals {
                m.set(j, k, v);
            } else {
                m.set(k, j, v);
            }
        }
    }
    m
}

#[test]
fn provider_equals_brute_force_fields_exactly() {
    let (grid, mut cost) = scene_at(0.2);
    // An enclosed free pocket: points there are unreachable from outside.
    for k in 50..=55 {
        for (c, r) in [(k, 30), (k, 35), (50, k - 20), (55, k - 20)] {
            cost[grid.index(c, r)] = f64::INFINITY;
        }
    }
    let pocket = grid.center(grid.index(52, 32));
    let cases = [
        (Order::Second, FieldSources::Goals),
        (Order::Second, FieldSources::Agents),
        (Order::Second, FieldSources::Auto),
        (Order::First, FieldSources::Goals),
    ];
    for (order, sources) in cases {
        let mut rng = SplitMix64::new(0x5eed_f1e1d);
        let mut agents = free_points(&mut rng, &grid, &cost, 9, -0.9, 2.9);
        let mut goals = free_points(&mut rng, &grid, &cost, 12, 6.5, 10.9);
        goals[11] = pocket;
        let provs: Vec<EikonalCosts> = [0usize, 4, 64]
            .iter()
            .map(|&cache_fields| {
                let opts = EikonalOptions {
                    sources,
                    cache_fields,
                    order,
                };
                EikonalCosts::new(grid, &cost, opts).unwrap()
            })
            .collect();
        let mut out = CostMatrix::new(0, 0);
        for frame in 0..4 {
            let fg = provs[0].from_goals(agents.len(), goals.len());
            let want = brute(&grid, &cost, &agents, &goals, fg, order);
            for prov in &provs {
                prov.fill(&agents, &goals, &mut out);
                assert_eq!(prov.last_error(), None);
                let opts = prov.options();
                for (a, b) in out.as_slice().iter().zip(want.as_slice()) {
                    assert_eq!(
                        a.to_bits(),
                        b.to_bits(),
                        "{opts:?} frame {frame}: {a} vs {b}"
                    );
                }
                assert!(out.row(0)[11] == f64::INFINITY);
            }
            // Move a few points a little (most stay in their cell), one far.
            for p in agents.iter_mut().chain(goals.iter_mut()).take(5) {
                let q = *p + Vec2::new(0.03, 0.0);
                if cost[grid.cell_of(q).unwrap()].is_finite() {
                    *p = q;
                }
            }
            agents[frame] = free_points(&mut rng, &grid, &cost, 1, -0.9, 2.9)[0];
        }
        assert_eq!(provs[0].stats().cache_hits, 0);
        assert!(provs[2].stats().cache_hits > 0, "{:?}", provs[2].stats());
    }
}

#[test]
fn field_direction_agrees_within_discretisation_error() {
    let (grid, cost) = scene();
    let mut rng = SplitMix64::new(7);
    let agents = free_points(&mut rng, &grid, &cost, 10, -0.9, 2.9);
    let goals = free_points(&mut rng, &grid, &cost, 10, 6.5, 10.9);
    let a = brute(&grid, &cost, &agents, &goals, true, Order::Second);
    let b = brute(&grid, &cost, &agents, &goals, false, Order::Second);
    let mut worst = 0.0f64;
    for (x, y) in a.as_slice().iter().zip(b.as_slice()) {
        worst = worst.max((x - y).abs() / x);
    }
    eprintln!("worst relative asymmetry {worst:.3e}");
    // Sources snap to cell centres (half a diagonal, 7 cm) and corners are
    // resolved to a cell: 2 % at 10 cm cells and paths of 4–14 m.
    assert!(worst < 0.02, "{worst}");
}

#[test]
fn provider_reports_bad_points_and_fills_infinity() {
    let (grid, cost) = scene();
    let mut cost = cost;
    block_rect(&grid, &mut cost, 0.0, 6.0, 1.0, 7.0);
    let prov = EikonalCosts::new(grid, &cost, EikonalOptions::default()).unwrap();
    let mut out = CostMatrix::new(0, 0);
    let agents = [Vec2::new(0.0, 3.0), Vec2::new(f64::NAN, 3.0)];
    let goals = [Vec2::new(10.0, 9.0), Vec2::new(10.0, 8.0)];
    prov.fill(&agents, &goals, &mut out);
    assert_eq!(
        prov.last_error(),
        Some(EikonalError::PointNotFinite { point: 1 })
    );
    assert!(out.as_slice().iter().all(|&v| v == f64::INFINITY));
    let outside = [Vec2::new(0.0, 3.0), Vec2::new(50.0, 3.0)];
    assert_eq!(
        prov.try_fill(&outside, &goals, &mut out),
        Err(EikonalError::SourceOutside { index: 1 })
    );
    let deep = [Vec2::new(0.0, 3.0), Vec2::new(0.5, 6.5)];
    assert_eq!(
        prov.try_fill(&deep, &goals, &mut out),
        Err(EikonalError::SourceBlocked { index: 1 })
    );
    // Inside a wall but within two cells of free space: marches from the nearest
    // free cell, as that cell's own source would.
    let wall = [
        grid.center(grid.cell_of(Vec2::new(3.12, 3.0)).unwrap()),
        Vec2::new(0.0, 3.0),
    ];
    prov.try_fill(&goals, &wall, &mut out).unwrap();
    let near = [
        grid.center(grid.cell_of(Vec2::new(2.95, 3.0)).unwrap()),
        Vec2::new(0.0, 3.0),
    ];
    let mut want = CostMatrix::new(0, 0);
    prov.try_fill(&goals, &near, &mut want).unwrap();
    assert!(out.as_slice().iter().all(|v| v.is_finite()));
    assert_eq!(out.get(0, 0), want.get(0, 0));
    let ok = [Vec2::new(0.0, 3.0), Vec2::new(1.0, 3.0)];
    prov.fill(&ok, &goals, &mut out);
    assert_eq!(prov.last_error(), None);
    assert!(out.as_slice().iter().all(|v| v.is_finite()));
}

#[test]
fn set_cost_invalidates_only_on_change() {
    let (grid, cost) = scene();
    let mut prov = EikonalCosts::new(grid, &cost, EikonalOptions::default()).unwrap();
    let agents = [Vec2::new(0.0, 3.0), Vec2::new(1.0, 3.0)];
    let goals = [Vec2::new(10.0, 9.0), Vec2::new(10.0, 8.0)];
    let mut out = CostMatrix::new(0, 0);
    prov.fill(&agents, &goals, &mut out);
    assert!(!prov.set_cost(&cost).unwrap());
    prov.fill(&agents, &goals, &mut out);
    assert_eq!(prov.stats().cache_hits, 2);
    let mut slower = cost.clone();
    for c in slower.iter_mut().filter(|c| c.is_finite()) {
        *c *= 2.0;
    }
    assert!(prov.set_cost(&slower).unwrap());
    let before = out.clone();
    prov.fill(&agents, &goals, &mut out);
    assert_eq!(prov.stats().cache_hits, 2);
    for (a, b) in out.as_slice().iter().zip(before.as_slice()) {
        assert!((a - 2.0 * b).abs() < 1e-9 * b);
    }
    let mut bad = cost.clone();
    bad[3] = f64::NAN;
    assert_eq!(prov.set_cost(&bad), Err(EikonalError::CostNan { cell: 3 }));
}

/// A fill checks its [`Cancel`](crate::crowd::assign::Cancel) before each march and
/// stops at the first check that fires: exactly one march per check that said "go
/// on"; the cache then serves the next fill as if nothing happened.
#[test]
fn a_cancelled_fill_stops_before_the_next_march() {
    use crate::crowd::assign::Cancel;
    use std::cell::Cell;
    let (grid, cost) = scene_at(0.2);
    let mut rng = SplitMix64::new(0xca7ce1);
    let agents = free_points(&mut rng, &grid, &cost, 6, -0.9, 2.9);
    let goals = free_points(&mut rng, &grid, &cost, 10, 6.5, 10.9);
    let opts = EikonalOptions {
        sources: FieldSources::Goals,
        cache_fields: 0,
        order: Order::Second,
    };
    let prov = EikonalCosts::new(grid, &cost, opts).unwrap();
    let mut out = CostMatrix::new(0, 0);
    for n in 1..=goals.len() as u64 {
        let calls = Cell::new(0u64);
        let fires = || {
            calls.set(calls.get() + 1);
            calls.get() >= n
        };
        let before = prov.stats().fields;
        assert_eq!(
            prov.try_fill_cancellable(&agents, &goals, &mut out, Cancel::new(&fires)),
            Err(EikonalError::Cancelled)
        );
        assert_eq!(calls.get(), n);
        assert_eq!(
            prov.stats().fields - before,
            n - 1,
            "marches before the check fired"
        );
    }
    let want = brute(&grid, &cost, &agents, &goals, true, Order::Second);
    prov.try_fill(&agents, &goals, &mut out).unwrap();
    assert_eq!(out.as_slice(), want.as_slice());
}
