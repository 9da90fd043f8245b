//! The social forces of a transform (formation-transform eqs. 7–10 and 21–23), as
//! accelerations (unit mass, m/s²).
//!
//! - Inter-agent repulsion, eq. 10: `A e^{−d/B} / d` along the line from the other
//!   agent, `d` the distance between centres, for pairs closer than
//!   [`MoveParams::interaction_range_m`] (found with the grid, never all pairs).
//! - Cross-subgroup repulsion, eq. 22: `A' e^{−d/B'} / d` on the same pairs when
//!   the two are in different subgroups.
//! - Subgroup attraction, eq. 21, and the subgroup moved as a whole on its
//!   Delaunay graph: `social_groups.rs` (four variants, chosen by
//!   [`MoveParams::subgroup_attraction`]).
//! - Obstacles, eq. 9: `A e^{−d/B}` along the obstacle's outward normal, `d` the
//!   distance from the centre to the nearest obstacle boundary (zero inside).
//!
//! Each agent's forces other than the driving force are scaled by its `fade`
//! (`run.rs`: it falls to zero on the last metres to the target), and the
//! repulsion between two agents by both their fades, so that
//! neighbours standing at their own targets cannot hold an arriving agent off its
//! target; contacts are kept apart positionally in `run.rs`.

use super::params::MoveParams;
use crate::crowd::agents::{unit_or_fixed, NeighbourGrid};
use crate::crowd::environment::Scene;
use crate::geom::Vec2;

/// Adds eq. 10's repulsion (and eq. 22's cross-subgroup repulsion when `groups`)
/// between every pair closer than the interaction range, to both agents, each
/// scaled by its own `fade`. `grid` is built on `pos` with cells of at least the
/// interaction range.
///
/// The force between two agents is scaled by both their fades, and an agent that
/// has settled at its target (`settled`) repels no one: an agent at or near its
/// target steps aside when a walker reaches it (the positional contacts of
/// `run.rs` give the walker right of way) and walks back after. Were it to repel,
/// the settled outer rows of a formation would hold off the agents whose targets
/// lie behind them, whose driving force weakens as they near their targets.
pub(crate) fn repulse(
    grid: &NeighbourGrid,
    pos: &[Vec2],
    groups: Option<&[u32]>,
    fade: &[f64],
    settled: &[bool],
    p: &MoveParams,
    acc: &mut [Vec2],
) {
    let range = p.interaction_range_m.min(grid.cell_m());
    let (a, inv_b) = (p.repulsion_a_m_s2, 1.0 / p.repulsion_b_m.max(1e-6));
    let (a2, inv_b2) = (p.subgroup_a_m_s2, 1.0 / p.subgroup_b_m.max(1e-6));
    // Closer than this the 1/d of eqs. 10 and 22 is held at its value here.
    let d_floor = 0.25 * p.radius_m.max(1e-3);
    grid.for_each_pair_d2(pos, range, |i, j, dv, d2| {
        // Settled pairs are skipped before the square root.
        if fade[i] <= 0.0 && fade[j] <= 0.0 {
            return;
        }
        let d = d2.sqrt();
        let n = unit_or_fixed(dv, d, i, j);
        let dd = d.max(d_floor);
        let mut f = a * (-dd * inv_b).exp() / dd;
        if let Some(g) = groups {
            if g[i] != g[j] {
                f += a2 * (-dd * inv_b2).exp() / dd;
            }
        }
        let w = if settled[i] || settled[j] {
            0.0
        } else {
            f * fade[i] * fade[j]
        };
        acc[i] += n * w;
        acc[j] -= n * w;
    });
}

/// Adds eq. 9's obstacle force of `scene` at time `t_s` to every agent with
/// `fade[i] > 0` within the interaction range of an obstacle.
pub(crate) fn obstacles(
    scene: &Scene,
    t_s: f64,
    pos: &[Vec2],
    fade: &[f64],
    p: &MoveParams,
    acc: &mut [Vec2],
) {
    let inv_b = 1.0 / p.repulsion_b_m.max(1e-6);
    for i in 0..pos.len() {
        if fade[i] <= 0.0 {
            continue;
        }
        if let Some(hit) = scene.nearest_obstacle(pos[i], t_s) {
            let d = hit.boundary.signed_distance_m.max(0.0);
            if d < p.interaction_range_m {
                let f = p.obstacle_a_m_s2 * (-d * inv_b).exp();
                acc[i] += hit.boundary.normal * (f * fade[i]);
            }
        }
    }
}
