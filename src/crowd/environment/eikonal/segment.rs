//! Straight segments across the grid: the cells they cross (Amanatides–Woo) and the
//! cost along them.

use super::grid::Grid;
use crate::geom::Vec2;

/// Line integral of the cost along the straight segment `a → b`, cell by cell.
///
/// # Formula
/// `∫ C ds` over the segment with `C` constant per cell (the exact cost of that
/// path, an upper bound on `Φ_a(b)`); `+inf` if the segment crosses a blocked cell.
///
/// # Units
/// Points in metres, cost per metre, result in cost units.
///
/// # Complexity
/// `O(cells crossed)`.
///
/// # Panics
/// Never for finite points; points outside the grid are clamped to it.
pub fn segment_cost(grid: &Grid, cost: &[f64], a: Vec2, b: Vec2) -> f64 {
    let mut sum = 0.0;
    walk_segment(grid, a, b, |cell, len_m| {
        let c = cost[cell];
        if c == f64::INFINITY {
            sum = f64::INFINITY;
            return false;
        }
        sum += c * len_m;
        true
    });
    sum
}

/// Visits the cells crossed by the segment `a → b` in order (Amanatides–Woo), with
/// the length in metres of the segment inside each; stops when `f` returns false.
fn walk_segment(grid: &Grid, a: Vec2, b: Vec2, mut f: impl FnMut(usize, f64) -> bool) {
    let h = grid.cell_m;
    let (ax, ay) = grid.frac(a);
    let (bx, by) = grid.frac(b);
    let clampc = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
    let (mut c, mut r) = (clampc(ax, grid.cols), clampc(ay, grid.rows));
    let (ec, er) = (clampc(bx, grid.cols), clampc(by, grid.rows));
    let (dx, dy) = (bx - ax, by - ay);
    let total = (dx * dx + dy * dy).sqrt();
    if total == 0.0 {
        f(grid.index(c, r), 0.0);
        return;
    }
    let step_c: isize = if dx > 0.0 { 1 } else { -1 };
    let step_r: isize = if dy > 0.0 { 1 } else { -1 };
    // Parameter t in [0, 1] along the segment of the next x / y cell boundary.
    let next_boundary = |p: f64, cell: usize, d: f64| -> f64 {
        if d > 0.0 {
            ((cell + 1) as f64 - p) / d
        } else if d < 0.0 {
            (cell as f64 - p) / d
        } else {
            f64::INFINITY
        }
    };
    let mut tx = next_boundary(ax, c, dx);
    let mut ty = next_boundary(ay, r, dy);
    let dtx = if dx != 0.0 {
        1.0 / dx.abs()
    } else {
        f64::INFINITY
    };
    let dty = if dy != 0.0 {
        1.0 / dy.abs()
    } else {
        f64::INFINITY
    };
    let mut t = 0.0;
    let max_steps = grid.cols + grid.rows + 2;
    for _ in 0..max_steps {
        let last = c == ec && r == er;
        let t_next = if last { 1.0 } else { tx.min(ty).min(1.0) };
        let len_m = (t_next - t).max(0.0) * total * h;
        if !f(grid.index(c, r), len_m) || last || t_next >= 1.0 {
            return;
        }
        t = t_next;
        if tx <= ty {
            let nc = c as isize + step_c;
            if nc < 0 || nc >= grid.cols as isize {
                return;
            }
            c = nc as usize;
            tx += dtx;
        } else {
            let nr = r as isize + step_r;
            if nr < 0 || nr >= grid.rows as isize {
                return;
            }
            r = nr as usize;
            ty += dty;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_cost_integrates_per_cell() {
        let grid = Grid::new(10, 10, 1.0, Vec2::zeros()).unwrap();
        let mut cost = vec![1.0; grid.len()];
        for r in 0..10 {
            cost[grid.index(5, r)] = 3.0;
        }
        let v = segment_cost(&grid, &cost, Vec2::new(0.5, 0.5), Vec2::new(9.5, 0.5));
        assert!((v - (8.0 + 3.0)).abs() < 1e-12, "{v}");
        let d = segment_cost(&grid, &cost, Vec2::new(0.0, 0.0), Vec2::new(4.0, 3.0));
        assert!((d - 5.0).abs() < 1e-12, "{d}");
        cost[grid.index(2, 0)] = f64::INFINITY;
        assert_eq!(
            segment_cost(&grid, &cost, Vec2::new(0.5, 0.5), Vec2::new(9.5, 0.5)),
            f64::INFINITY
        );
    }
}
