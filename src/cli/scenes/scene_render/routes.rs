//! Agents on a lattice in the start rectangle, their routes down `Φ`, and the
//! simplification of a route for drawing.

use crowdtouch::crowd::environment::eikonal::{descent_direction, Grid};
use crowdtouch::geom::{Rect, Vec2};

/// Route step, in cells.
pub const ROUTE_STEP_CELLS: f64 = 0.5;
/// Route step budget, per cell of the grid's width plus height.
pub const ROUTE_STEPS_PER_CELL: usize = 8;
/// Routes are simplified to within this many pixels (Douglas–Peucker).
pub const ROUTE_TOLERANCE_PX: f64 = 0.4;

/// One agent's route.
#[derive(Clone, Debug)]
pub struct Route {
    /// Points from the agent to where it stopped (m).
    pub points: Vec<Vec2>,
    /// Whether it ended within a cell of the goal.
    pub reached: bool,
}

/// `n` agents on a lattice over `start` (columns and rows in about the rectangle's
/// aspect), skipping positions in blocked cells; the lattice is refined until
/// `n` fit or it has 16 times as many points as asked. Row-major order.
pub fn sample_agents(start: Rect, n: usize, grid: &Grid, blocked: &[bool]) -> Vec<Vec2> {
    if n == 0 {
        return Vec::new();
    }
    let (w, h) = (start.width().max(1e-9), start.height().max(1e-9));
    let mut cols = ((n as f64 * w / h).sqrt().ceil() as usize).max(1);
    let mut best = Vec::new();
    loop {
        let rows = n.div_ceil(cols).max(1);
        let mut pts = Vec::with_capacity(cols * rows);
        for r in 0..rows {
            for c in 0..cols {
                let p = Vec2::new(
                    start.min[0] + (c as f64 + 0.5) / cols as f64 * w,
                    start.min[1] + (r as f64 + 0.5) / rows as f64 * h,
                );
                if grid.cell_of(p).is_some_and(|i| !blocked[i]) {
                    pts.push(p);
                }
            }
        }
        if pts.len() > best.len() {
            best = pts;
        }
        if best.len() >= n || cols * rows >= 16 * n {
            break;
        }
        cols += 1;
    }
    best.truncate(n);
    best
}

/// Descends `Φ` from `p` in steps of [`ROUTE_STEP_CELLS`] cells until within one
/// cell of `goal`, no descent direction is left, or the step budget runs out.
pub fn trace_route(grid: &Grid, phi: &[f64], p: Vec2, goal: Vec2) -> Route {
    let h = grid.cell_m();
    let step = ROUTE_STEP_CELLS * h;
    let budget = ROUTE_STEPS_PER_CELL * (grid.cols() + grid.rows());
    let mut points = vec![p];
    let mut q = p;
    for _ in 0..budget {
        if (q - goal).norm() <= h {
            points.push(goal);
            return Route {
                points,
                reached: true,
            };
        }
        match descent_direction(grid, phi, q) {
            Some(d) => {
                q += d * step;
                points.push(q);
            }
            None => break,
        }
    }
    let reached = (q - goal).norm() <= h;
    if reached {
        points.push(goal);
    }
    Route { points, reached }
}

/// Douglas–Peucker: the points of `pts` to keep so that no dropped point is more
/// than `tol` from the kept polyline. Always keeps the ends.
pub fn simplify(pts: &[Vec2], tol: f64) -> Vec<Vec2> {
    if pts.len() <= 2 {
        return pts.to_vec();
    }
    let mut keep = vec![false; pts.len()];
    keep[0] = true;
    keep[pts.len() - 1] = true;
    let mut stack = vec![(0, pts.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let (pa, pb) = (pts[a], pts[b]);
        let d = pb - pa;
        let len = d.norm();
        let mut far = (0.0, a);
        for (i, &p) in pts.iter().enumerate().take(b).skip(a + 1) {
            let dist = if len > 0.0 {
                (d.x * (p.y - pa.y) - d.y * (p.x - pa.x)).abs() / len
            } else {
                (p - pa).norm()
            };
            if dist > far.0 {
                far = (dist, i);
            }
        }
        if far.0 > tol {
            keep[far.1] = true;
            stack.push((a, far.1));
            stack.push((far.1, b));
        }
    }
    pts.iter()
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|(&p, _)| p)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simplify_keeps_corners_and_drops_collinear_points() {
        let pts: Vec<Vec2> = (0..=10)
            .map(|i| Vec2::new(i as f64, 0.0))
            .chain((1..=10).map(|i| Vec2::new(10.0, i as f64)))
            .collect();
        let s = simplify(&pts, 0.01);
        assert_eq!(
            s,
            [
                Vec2::new(0.0, 0.0),
                Vec2::new(10.0, 0.0),
                Vec2::new(10.0, 10.0)
            ]
        );
        assert_eq!(simplify(&pts[..2], 0.01), &pts[..2]);
    }

    #[test]
    fn agents_fill_the_start_and_skip_blocked_cells() {
        let grid = Grid::new(16, 9, 1.0, Vec2::zeros()).unwrap();
        let mut blocked = vec![false; grid.len()];
        let start = Rect {
            min: [6.0, 3.0],
            max: [10.0, 6.0],
        };
        let a = sample_agents(start, 40, &grid, &blocked);
        assert_eq!(a.len(), 40);
        assert!(a.iter().all(|p| start.contains(*p)));
        // Block the start's west half: still 40, none in it.
        for r in 3..6 {
            for c in 6..8 {
                blocked[grid.index(c, r)] = true;
            }
        }
        let b = sample_agents(start, 40, &grid, &blocked);
        assert_eq!(b.len(), 40);
        assert!(b.iter().all(|p| p.x >= 8.0));
        assert!(sample_agents(start, 0, &grid, &blocked).is_empty());
    }
}
