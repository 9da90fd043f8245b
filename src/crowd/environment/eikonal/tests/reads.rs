//! Descent on a solved field.

use super::{scene, solve};
use crate::crowd::environment::eikonal::{descent_direction, sample, Order};
use crate::geom::Vec2;

#[test]
fn descent_reaches_the_source_monotonically_without_entering_blocked_cells() {
    let (grid, cost) = scene();
    let s = Vec2::new(10.0, 9.0);
    let phi = solve(&grid, &cost, &[s], Order::Second);
    let h = grid.cell_m();
    let step = 0.5 * h;
    let mut starts = 0;
    for k in 0..60 {
        let p0 = Vec2::new(
            -0.8 + 0.2 * (k % 12) as f64 * 1.0,
            2.3 + 0.6 * (k / 12) as f64 + 0.03 * k as f64,
        );
        let Some(cell) = grid.cell_of(p0) else {
            continue;
        };
        if cost[cell] == f64::INFINITY {
            continue;
        }
        starts += 1;
        let mut p = p0;
        let mut last = sample(&grid, &phi, p);
        let mut reached = false;
        for _ in 0..4000 {
            if (p - s).norm() < 1.5 * h {
                reached = true;
                break;
            }
            let Some(d) = descent_direction(&grid, &phi, p) else {
                break;
            };
            p += step * d;
            let cell = grid.cell_of(p).expect("stays on the grid");
            assert!(
                cost[cell].is_finite(),
                "start {p0:?} entered a blocked cell at {p:?}"
            );
            let v = sample(&grid, &phi, p);
            // Φ never rises by more than a rounding-level fraction of a step's cost.
            assert!(
                v <= last + 0.05 * step * cost[cell],
                "start {p0:?}: {last} -> {v} at {p:?}"
            );
            last = v.min(last);
        }
        assert!(reached, "start {p0:?} stuck at {p:?} (Φ = {last})");
    }
    assert!(starts > 40);
}
