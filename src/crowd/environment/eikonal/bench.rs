//! The fast-marching benchmark instance shared by `benches/fmm.rs` and
//! `crowdtouch bench fmm`.

use super::grid::Grid;
use crate::geom::Vec2;

/// Cell size of [`bench_instance`] grids: 4 cm (a 256² grid is a 10.24 m square).
pub const BENCH_CELL_M: f64 = 0.04;

/// The fast-marching benchmark instance shared by `benches/fmm.rs` and
/// `crowdtouch bench fmm`: a square `n²` grid of [`BENCH_CELL_M`] cells at the origin
/// with unit cost, or with `obstacles`: three long walls with gaps, 40 seeded random
/// blocks (about 12 % of the cells blocked) and a slow patch (speed 0.33), keeping
/// the strips `x ∈ [0.05, 0.32]` and `[0.66, 0.97]` of the side open.
///
/// # Panics
/// If `n` is 0 or too large for a [`Grid`].
pub fn bench_instance(n: usize, obstacles: bool) -> (Grid, Vec<f64>) {
    let grid = Grid::new(n, n, BENCH_CELL_M, Vec2::zeros()).expect("bench grid size");
    let mut cost = vec![1.0; grid.len()];
    if obstacles {
        // Cells whose centres lie in [x0, x1] × [y0, y1] (fractions of the side).
        let mut block = |x0: f64, y0: f64, x1: f64, y1: f64, v: f64| {
            let range = |a: f64, b: f64| {
                let lo = (a * n as f64 - 0.5).ceil().max(0.0) as usize;
                let hi = ((b * n as f64 - 0.5).floor() as usize).min(n - 1);
                lo..=hi
            };
            for r in range(y0, y1) {
                for c in range(x0, x1) {
                    cost[grid.index(c, r)] = v;
                }
            }
        };
        block(0.40, 0.00, 0.43, 0.45, f64::INFINITY);
        block(0.40, 0.55, 0.43, 1.00, f64::INFINITY);
        block(0.55, 0.20, 0.58, 0.80, f64::INFINITY);
        block(0.45, 0.85, 0.55, 0.95, 1.0 / 0.33);
        let mut rng = crate::rng::SplitMix64::new(0xF33D ^ n as u64);
        for _ in 0..40 {
            let (x, y) = (0.05 + 0.9 * rng.unit(), 0.05 + 0.9 * rng.unit());
            if (0.05..0.32).contains(&x) || (0.66..0.97).contains(&x) {
                continue; // keep the crowd and formation areas open
            }
            block(x, y, x + 0.04, y + 0.04, f64::INFINITY);
        }
    }
    (grid, cost)
}
