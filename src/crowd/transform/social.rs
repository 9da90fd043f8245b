//! The social forces of a transform (formation-transform eqs. 7–10 and 21–23), as
//! accelerations (unit mass, m/s²).
//!
//! - Inter-agent repulsion, eq. 10: `A e^{−d/B} / d` along the line from the other
//!   agent, `d` the distance between centres, for pairs closer than
//!   [`MoveParams::interaction_range_m`] (found with the grid, never all pairs).
//! - Cross-subgroup repulsion, eq. 22: `A' e^{−d/B'} / d` on the same pairs when
//!   the two are in different subgroups.
//! - Subgroup attraction, eq. 21. As printed, `A' e^{|pos(a) − pos(b)|}` grows
//!   without bound with the distance and sums over every member, O(N²) and
//!   explosive. It is read here as a bounded pull towards the agent's place in its
//!   subgroup: the group's current centroid `c_g` plus the agent's offset in the
//!   group, blended from its source layout to its target layout as the group
//!   advances (`α_g = 1 − |c_g − t̂_g| / |ŝ_g − t̂_g|`, clamped to `[0, 1]`, `ŝ_g`,
//!   `t̂_g` the group's source and target centroids):
//!   `p_a = c_g + (1 − α_g)(s_a − ŝ_g) + α_g (t_a − t̂_g)` and
//!   `f = A' (1 − e^{−|p_a − x_a| / B'}) (p_a − x_a) / |p_a − x_a|`, at most `A'`.
//!   Members that strayed from the group are pulled back towards it, O(N) a step.
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

/// Per-subgroup layout: source and target centroids, and the current centroid.
#[derive(Clone, Debug)]
pub(crate) struct Groups {
    /// `group_of[i]`.
    pub group_of: Vec<u32>,
    src_c: Vec<Vec2>,
    tgt_c: Vec<Vec2>,
    now_c: Vec<Vec2>,
    count: Vec<u32>,
}

impl Groups {
    /// The layout of `group_of` (values `>= n` are taken as their own group `0`)
    /// between `sources` and `targets`.
    pub(crate) fn new(group_of: &[u32], sources: &[Vec2], targets: &[Vec2]) -> Groups {
        let n = sources.len();
        let group_of: Vec<u32> = (0..n)
            .map(|i| {
                group_of
                    .get(i)
                    .copied()
                    .filter(|&g| (g as usize) < n.max(1))
                    .unwrap_or(0)
            })
            .collect();
        let m = group_of.iter().map(|&g| g as usize + 1).max().unwrap_or(1);
        let mut g = Groups {
            group_of,
            src_c: vec![Vec2::zeros(); m],
            tgt_c: vec![Vec2::zeros(); m],
            now_c: vec![Vec2::zeros(); m],
            count: vec![0; m],
        };
        for i in 0..n {
            let k = g.group_of[i] as usize;
            g.src_c[k] += sources[i];
            g.tgt_c[k] += targets[i];
            g.count[k] += 1;
        }
        for k in 0..m {
            let c = g.count[k].max(1) as f64;
            g.src_c[k] /= c;
            g.tgt_c[k] /= c;
        }
        g
    }

    /// Agents `i` and `j` exchanged targets `ti` and `tj` (`i` had `ti`): the
    /// groups' target centroids follow.
    /// Every target moved by `by_m`: the target centroids with them.
    pub(crate) fn shift_targets(&mut self, by_m: Vec2) {
        for c in &mut self.tgt_c {
            *c += by_m;
        }
    }

    pub(crate) fn swapped(&mut self, i: usize, j: usize, ti: Vec2, tj: Vec2) {
        let (gi, gj) = (self.group_of[i] as usize, self.group_of[j] as usize);
        if gi != gj {
            self.tgt_c[gi] += (tj - ti) / self.count[gi].max(1) as f64;
            self.tgt_c[gj] += (ti - tj) / self.count[gj].max(1) as f64;
        }
    }

    /// Adds the bounded subgroup attraction (eq. 21 as read in the module docs) to
    /// `acc[i] · fade[i]` for every agent with `fade[i] > 0`.
    pub(crate) fn attract(
        &mut self,
        pos: &[Vec2],
        sources: &[Vec2],
        targets: &[Vec2],
        fade: &[f64],
        p: &MoveParams,
        acc: &mut [Vec2],
    ) {
        self.now_c.fill(Vec2::zeros());
        for (i, x) in pos.iter().enumerate() {
            self.now_c[self.group_of[i] as usize] += x;
        }
        for k in 0..self.now_c.len() {
            self.now_c[k] /= self.count[k].max(1) as f64;
        }
        let b = p.subgroup_b_m.max(1e-6);
        for i in 0..pos.len() {
            if fade[i] <= 0.0 {
                continue;
            }
            let k = self.group_of[i] as usize;
            if self.count[k] < 2 {
                continue;
            }
            let (c, s, t) = (self.now_c[k], self.src_c[k], self.tgt_c[k]);
            let span = (s - t).norm();
            let alpha = if span > 1e-9 {
                (1.0 - (c - t).norm() / span).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let place = c + (sources[i] - s) * (1.0 - alpha) + (targets[i] - t) * alpha;
            let d = place - pos[i];
            let dn = d.norm();
            if dn > 1e-9 {
                acc[i] += d * (p.subgroup_a_m_s2 * (1.0 - (-dn / b).exp()) / dn * fade[i]);
            }
        }
    }
}

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
