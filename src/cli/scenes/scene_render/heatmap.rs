//! The heat map of `Φ`: the grid gathered into blocks, each blocked, unreachable or
//! at a colour level.

use super::picture::Picture;
use crowdtouch::crowd::environment::eikonal::sample;
use crowdtouch::geom::{Rect, Vec2};

/// The heat map has at most this many blocks across …
pub const MAX_HEAT_COLS: usize = 160;
/// … and this many down.
pub const MAX_HEAT_ROWS: usize = 90;
/// Colour levels of the heat map and its scale.
pub const HEAT_LEVELS: usize = 40;

/// How a heat-map block is shown.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) enum Heat {
    /// Most of its cells are blocked.
    Blocked,
    /// No path from it to the goal.
    Unreachable,
    /// Colour level `0..HEAT_LEVELS`.
    Level(usize),
}

impl Picture {
    /// Heat-map blocks: `(factor, nx, ny, class per block, Φ at block centres)`.
    pub(super) fn heat_blocks(
        &self,
        bounds: Rect,
        vmax: f64,
    ) -> (usize, usize, usize, Vec<Heat>, Vec<f64>) {
        let g = &self.grid;
        let f = g
            .cols()
            .div_ceil(MAX_HEAT_COLS)
            .max(g.rows().div_ceil(MAX_HEAT_ROWS))
            .max(1);
        let (nx, ny) = (g.cols().div_ceil(f), g.rows().div_ceil(f));
        let mut heat = Vec::with_capacity(nx * ny);
        let mut vals = Vec::with_capacity(nx * ny);
        for bj in 0..ny {
            for bi in 0..nx {
                let (c0, c1) = (bi * f, ((bi + 1) * f).min(g.cols()));
                let (r0, r1) = (bj * f, ((bj + 1) * f).min(g.rows()));
                let (mut inside, mut blocked) = (0usize, 0usize);
                for r in r0..r1 {
                    for c in c0..c1 {
                        let i = g.index(c, r);
                        if bounds.contains(g.center(i)) {
                            inside += 1;
                            blocked += usize::from(self.blocked[i]);
                        }
                    }
                }
                let centre = self.block_centre(bounds, f, bi, bj);
                let v = sample(g, &self.phi, centre);
                let h = if inside == 0 || 2 * blocked > inside {
                    Heat::Blocked
                } else if !v.is_finite() {
                    Heat::Unreachable
                } else {
                    Heat::Level(((v / vmax * HEAT_LEVELS as f64) as usize).min(HEAT_LEVELS - 1))
                };
                vals.push(if matches!(h, Heat::Level(_)) {
                    v
                } else {
                    f64::INFINITY
                });
                heat.push(h);
            }
        }
        (f, nx, ny, heat, vals)
    }

    /// World rectangle of heat block `(bi, bj)`, clipped to the bounds.
    pub(super) fn block_rect(&self, bounds: Rect, f: usize, bi: usize, bj: usize) -> Rect {
        let g = &self.grid;
        let s = g.cell_m() * f as f64;
        let o = g.origin();
        Rect {
            min: [
                (o.x + bi as f64 * s).max(bounds.min[0]),
                (o.y + bj as f64 * s).max(bounds.min[1]),
            ],
            max: [
                (o.x + (bi + 1) as f64 * s).min(bounds.max[0]),
                (o.y + (bj + 1) as f64 * s).min(bounds.max[1]),
            ],
        }
    }

    pub(super) fn block_centre(&self, bounds: Rect, f: usize, bi: usize, bj: usize) -> Vec2 {
        self.block_rect(bounds, f, bi, bj).center()
    }
}
