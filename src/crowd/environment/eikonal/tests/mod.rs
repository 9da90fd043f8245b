//! Fields solved end to end: the march against exact path lengths, descent on a
//! solved field, and the cost provider against one full field per source.

use super::{sanity_check, Fmm, Grid, Order, Sources};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

mod clusters;
mod costs;
mod march;
mod reads;

fn solve(grid: &Grid, cost: &[f64], src: &[Vec2], order: Order) -> Vec<f64> {
    let mut phi = vec![0.0; grid.len()];
    Fmm::with_order(order)
        .solve_into(grid, cost, Sources::Points(src), &mut phi)
        .unwrap();
    assert_eq!(sanity_check(grid, cost, &phi), Ok(()));
    phi
}

/// Blocks the cells whose centres lie in the rectangle `[x0, x1] × [y0, y1]`.
fn block_rect(grid: &Grid, cost: &mut [f64], x0: f64, y0: f64, x1: f64, y1: f64) {
    for (i, c) in cost.iter_mut().enumerate() {
        let p = grid.center(i);
        if p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1 {
            *c = f64::INFINITY;
        }
    }
}

/// A 12 m × 8 m scene at 10 cm with two walls and a slow patch.
fn scene() -> (Grid, Vec<f64>) {
    scene_at(0.1)
}

/// [`scene`] with cells of `h` metres.
fn scene_at(h: f64) -> (Grid, Vec<f64>) {
    let n = (12.0 / h).round() as usize;
    let grid = Grid::new(n, n * 2 / 3, h, Vec2::new(-1.0, 2.0)).unwrap();
    let mut cost = vec![1.0; grid.len()];
    block_rect(&grid, &mut cost, 3.0, 2.0, 3.4, 8.0);
    block_rect(&grid, &mut cost, 6.0, 4.0, 6.3, 10.0);
    for (i, c) in cost.iter_mut().enumerate() {
        let p = grid.center(i);
        if c.is_finite() && (8.0..9.5).contains(&p.x) && (3.0..6.0).contains(&p.y) {
            *c = 1.0 / 0.33;
        }
    }
    (grid, cost)
}

/// `n` points in free cells of `cost` with `x` in `[x0, x1]`.
fn free_points(
    rng: &mut SplitMix64,
    grid: &Grid,
    cost: &[f64],
    n: usize,
    x0: f64,
    x1: f64,
) -> Vec<Vec2> {
    let o = grid.origin();
    let hgt = grid.rows() as f64 * grid.cell_m();
    let mut v = Vec::new();
    while v.len() < n {
        let p = Vec2::new(x0 + (x1 - x0) * rng.unit(), o.y + hgt * rng.unit());
        if cost[grid.cell_of(p).unwrap()].is_finite() {
            v.push(p);
        }
    }
    v
}
