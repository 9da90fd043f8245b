//! The subgroup terms of a transform that hold a subgroup together: eq. 21 of
//! formation-transform (section 3.5) in three readings, and the manipulation of a
//! subgroup as a whole on its Delaunay graph (section 3, pipeline step 3), as
//! accelerations (unit mass, m/s²). [`MoveParams::subgroup_attraction`] chooses one.
//!
//! Every variant uses the group's progress
//! `α_g = 1 − |c_g − t̂_g| / |ŝ_g − t̂_g|`, clamped to `[0, 1]` (`c_g` the group's
//! centroid now, `ŝ_g`, `t̂_g` its source and target centroids; 1 when they
//! coincide). `d = |pos(a) − pos(b)|` is in metres, `A'` = [`MoveParams::subgroup_a_m_s2`],
//! `B'` = [`MoveParams::subgroup_b_m`]. Each agent's term is scaled by its `fade`
//! (`run.rs`), as the other forces but the driving one.
//!
//! - [`SubgroupAttraction::Place`] (ours, the default): a bounded pull towards the
//!   agent's place in its subgroup, the centroid plus its offset blended from the
//!   source to the target layout:
//!   `p_a = c_g + (1 − α_g)(s_a − ŝ_g) + α_g (t_a − t̂_g)` and
//!   `f = A' (1 − e^{−|p_a − x_a| / B'}) (p_a − x_a) / |p_a − x_a|`, at most `A'`.
//!   O(N) a step.
//! - [`SubgroupAttraction::AsPrinted`]: eq. 21 exactly as printed,
//!   `f = Σ_b A' e^{d}` directed from `a` towards each other member `b` of its
//!   subgroup. It grows without bound with the distance: at `A'` = 1 m/s², a
//!   member 1 m away pulls with 2.7 m/s², 3 m away with 20 m/s², so with tens of
//!   members the sum is far above the run's `max_accel`, and only that clamp
//!   (`run.rs`, step 4) bounds the total acceleration, driving force included:
//!   every agent accelerates at the clamp towards its group. The exponent is held
//!   at [`AS_PRINTED_MAX_EXPONENT_M`] so that the sum stays finite in `f64`.
//! - [`SubgroupAttraction::Decaying`]: `f = Σ_b A' e^{−d/B'}` towards each other
//!   member. A guess at a misprint in eq. 21, not the paper's text: eq. 22's
//!   form without its `1/d`, attracting; it pulls the near members together and
//!   ignores the far ones. At most `A'` per member.
//! - [`SubgroupAttraction::DelaunayGraph`]: our reading of section 3, pipeline
//!   step 3 (no equation given): "to reflect the collective movements in
//!   subgroups, each subgroup is manipulated as a whole using a DT graph". Each
//!   edge `(a, b)` of the Delaunay triangulation of a group's source positions
//!   (built once) is a damped spring with rest length
//!   `L = (1 − α_g) |s_a s_b| + α_g |Ψ(s_a) Ψ(s_b)|` (`Ψ(s)` the agent's target,
//!   read each step so exchanged targets are followed):
//!   `f_a = (k (|x_b − x_a| − L) + c (v_b − v_a)·u) u`, `u` the unit vector from
//!   `a` to `b`, and `f_b = −f_a`; `k` =
//!   [`MoveParams::subgroup_dt_stiffness_m_s2_per_m`], `c` =
//!   [`MoveParams::subgroup_dt_damping_m_s2_per_m_s`]. The group moves and
//!   deforms as one graph; O(edges) = O(N) a step. Agents at one source position
//!   share a vertex: only the first of them is on the graph.
//!
//! Members are listed per group once in [`Groups::new`]; nothing here allocates
//! in a step. The sums over members are O(Σ_g |g|²) a step.

use super::params::{MoveParams, SubgroupAttraction};
use crate::geom::Vec2;
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// [`SubgroupAttraction::AsPrinted`] holds `d` at this in `e^{d}` (m). `e^{300}` is
/// about 2·10¹³⁰, so a sum over a million members stays well below the ~10¹⁵⁴
/// at which the square in the clamp's norm overflows `f64` (an infinite norm
/// would scale the acceleration to zero); groups never span that far, and the
/// run's acceleration clamp acts long before.
pub const AS_PRINTED_MAX_EXPONENT_M: f64 = 300.0;

/// One spring of [`SubgroupAttraction::DelaunayGraph`].
#[derive(Copy, Clone, Debug, PartialEq)]
struct Edge {
    a: u32,
    b: u32,
    /// `|s_a s_b|` (m).
    source_m: f64,
}

/// Per-subgroup layout: source and target centroids, the current centroid and
/// progress, the members of each group, and (for the Delaunay graph) the edges.
#[derive(Clone, Debug)]
pub(crate) struct Groups {
    /// `group_of[i]`.
    pub group_of: Vec<u32>,
    src_c: Vec<Vec2>,
    tgt_c: Vec<Vec2>,
    now_c: Vec<Vec2>,
    /// `α_g` of the last [`centroids`](Self::centroids).
    alpha: Vec<f64>,
    count: Vec<u32>,
    /// The members of group `k` are `members[start[k]..start[k + 1]]`.
    start: Vec<usize>,
    members: Vec<u32>,
    /// The Delaunay edges of every group's source layout (with
    /// [`SubgroupAttraction::DelaunayGraph`] only).
    edges: Vec<Edge>,
}

impl Groups {
    /// The layout of `group_of` (values `>= n` are taken as their own group `0`)
    /// between `sources` and `targets`; the Delaunay edges when `attraction` is
    /// [`SubgroupAttraction::DelaunayGraph`]. Allocates.
    pub(crate) fn new(
        group_of: &[u32],
        sources: &[Vec2],
        targets: &[Vec2],
        attraction: SubgroupAttraction,
    ) -> Groups {
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
            alpha: vec![0.0; m],
            count: vec![0; m],
            start: vec![0; m + 1],
            members: vec![0; n],
            edges: Vec::new(),
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
            g.start[k + 1] = g.start[k] + g.count[k] as usize;
        }
        let mut next = g.start.clone();
        for i in 0..n {
            let k = g.group_of[i] as usize;
            g.members[next[k]] = i as u32;
            next[k] += 1;
        }
        if attraction == SubgroupAttraction::DelaunayGraph {
            for k in 0..m {
                let members = &g.members[g.start[k]..g.start[k + 1]];
                delaunay_edges(members, sources, &mut g.edges);
            }
        }
        g
    }

    /// Every target moved by `by_m`: the target centroids with them.
    pub(crate) fn shift_targets(&mut self, by_m: Vec2) {
        for c in &mut self.tgt_c {
            *c += by_m;
        }
    }

    /// Agents `i` and `j` exchanged targets `ti` and `tj` (`i` had `ti`): the
    /// groups' target centroids follow.
    pub(crate) fn swapped(&mut self, i: usize, j: usize, ti: Vec2, tj: Vec2) {
        let (gi, gj) = (self.group_of[i] as usize, self.group_of[j] as usize);
        if gi != gj {
            self.tgt_c[gi] += (tj - ti) / self.count[gi].max(1) as f64;
            self.tgt_c[gj] += (ti - tj) / self.count[gj].max(1) as f64;
        }
    }

    /// The Delaunay edges (agent pairs), with
    /// [`SubgroupAttraction::DelaunayGraph`]; empty otherwise.
    #[cfg(test)]
    fn edge_pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.edges.iter().map(|e| (e.a as usize, e.b as usize))
    }

    /// Every group's centroid at `pos` and its progress `α_g` (module docs).
    fn centroids(&mut self, pos: &[Vec2]) {
        self.now_c.fill(Vec2::zeros());
        for (i, x) in pos.iter().enumerate() {
            self.now_c[self.group_of[i] as usize] += x;
        }
        for k in 0..self.now_c.len() {
            self.now_c[k] /= self.count[k].max(1) as f64;
            let (c, s, t) = (self.now_c[k], self.src_c[k], self.tgt_c[k]);
            let span = (s - t).norm();
            self.alpha[k] = if span > 1e-9 {
                (1.0 - (c - t).norm() / span).clamp(0.0, 1.0)
            } else {
                1.0
            };
        }
    }

    /// Adds the subgroup term chosen by `p.subgroup_attraction` (module docs) to
    /// `acc[i]`, scaled by `fade[i]`, for every agent with `fade[i] > 0`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn attract(
        &mut self,
        pos: &[Vec2],
        vel: &[Vec2],
        sources: &[Vec2],
        targets: &[Vec2],
        fade: &[f64],
        p: &MoveParams,
        acc: &mut [Vec2],
    ) {
        self.centroids(pos);
        match p.subgroup_attraction {
            SubgroupAttraction::Place => self.place(pos, sources, targets, fade, p, acc),
            SubgroupAttraction::AsPrinted => {
                let a = p.subgroup_a_m_s2;
                self.pairwise(pos, fade, acc, |d_m| {
                    a * d_m.min(AS_PRINTED_MAX_EXPONENT_M).exp()
                });
            }
            SubgroupAttraction::Decaying => {
                let (a, inv_b) = (p.subgroup_a_m_s2, 1.0 / p.subgroup_b_m.max(1e-6));
                self.pairwise(pos, fade, acc, |d_m| a * (-d_m * inv_b).exp());
            }
            SubgroupAttraction::DelaunayGraph => self.springs(pos, vel, targets, fade, p, acc),
        }
    }

    /// [`SubgroupAttraction::Place`]: the pull towards the agent's place.
    fn place(
        &self,
        pos: &[Vec2],
        sources: &[Vec2],
        targets: &[Vec2],
        fade: &[f64],
        p: &MoveParams,
        acc: &mut [Vec2],
    ) {
        let b = p.subgroup_b_m.max(1e-6);
        for i in 0..pos.len() {
            if fade[i] <= 0.0 {
                continue;
            }
            let k = self.group_of[i] as usize;
            if self.count[k] < 2 {
                continue;
            }
            let (c, s, t, alpha) = (self.now_c[k], self.src_c[k], self.tgt_c[k], self.alpha[k]);
            let place = c + (sources[i] - s) * (1.0 - alpha) + (targets[i] - t) * alpha;
            let d = place - pos[i];
            let dn = d.norm();
            if dn > 1e-9 {
                acc[i] += d * (p.subgroup_a_m_s2 * (1.0 - (-dn / b).exp()) / dn * fade[i]);
            }
        }
    }

    /// Eq. 21's sum: `magnitude(d)` (m/s²) from each agent towards every other
    /// member of its group at distance `d` (m). Coincident members pull nowhere.
    fn pairwise(
        &self,
        pos: &[Vec2],
        fade: &[f64],
        acc: &mut [Vec2],
        magnitude: impl Fn(f64) -> f64,
    ) {
        for i in 0..pos.len() {
            if fade[i] <= 0.0 {
                continue;
            }
            let k = self.group_of[i] as usize;
            let mut f = Vec2::zeros();
            for &j in &self.members[self.start[k]..self.start[k + 1]] {
                let d = pos[j as usize] - pos[i];
                let dn = d.norm();
                if dn > 1e-9 {
                    f += d * (magnitude(dn) / dn);
                }
            }
            acc[i] += f * fade[i];
        }
    }

    /// [`SubgroupAttraction::DelaunayGraph`]: every edge's damped spring.
    fn springs(
        &self,
        pos: &[Vec2],
        vel: &[Vec2],
        targets: &[Vec2],
        fade: &[f64],
        p: &MoveParams,
        acc: &mut [Vec2],
    ) {
        let (k_s, k_d) = (
            p.subgroup_dt_stiffness_m_s2_per_m,
            p.subgroup_dt_damping_m_s2_per_m_s,
        );
        for e in &self.edges {
            let (a, b) = (e.a as usize, e.b as usize);
            if fade[a] <= 0.0 && fade[b] <= 0.0 {
                continue;
            }
            let alpha = self.alpha[self.group_of[a] as usize];
            let rest_m = (1.0 - alpha) * e.source_m + alpha * (targets[b] - targets[a]).norm();
            let d = pos[b] - pos[a];
            let dn = d.norm();
            if dn <= 1e-9 {
                continue;
            }
            let u = d / dn;
            let f = u * (k_s * (dn - rest_m) + k_d * (vel[b] - vel[a]).dot(&u));
            acc[a] += f * fade[a];
            acc[b] -= f * fade[b];
        }
    }

    /// How spread out the subgroups are at `pos`: the members' summed distance
    /// from their group's centroid over that of the layout the group should have
    /// at its progress (`|(1 − α_g)(s_a − ŝ_g) + α_g (t_a − t̂_g)|`), over groups
    /// of two or more. 1: the groups have their layout's size; below 1 they have
    /// contracted, above 1 spread out. `None` without such a group or when the
    /// layouts have no extent.
    pub(crate) fn spread(
        &mut self,
        pos: &[Vec2],
        sources: &[Vec2],
        targets: &[Vec2],
    ) -> Option<f64> {
        self.centroids(pos);
        let (mut now_m, mut layout_m) = (0.0, 0.0);
        for i in 0..pos.len() {
            let k = self.group_of[i] as usize;
            if self.count[k] < 2 {
                continue;
            }
            let alpha = self.alpha[k];
            now_m += (pos[i] - self.now_c[k]).norm();
            layout_m += ((sources[i] - self.src_c[k]) * (1.0 - alpha)
                + (targets[i] - self.tgt_c[k]) * alpha)
                .norm();
        }
        (layout_m > 1e-9).then(|| now_m / layout_m)
    }
}

/// Appends the edges of the Delaunay triangulation of `members`' positions in
/// `sources` to `edges` (two members: their one edge; collinear members: the
/// chain). Members at a position taken already are left off the graph, as are
/// positions the triangulation rejects (not finite).
fn delaunay_edges(members: &[u32], sources: &[Vec2], edges: &mut Vec<Edge>) {
    if members.len() < 2 {
        return;
    }
    let mut dt: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    let mut agent_at: Vec<u32> = Vec::with_capacity(members.len());
    for &i in members {
        let s = sources[i as usize];
        if let Ok(h) = dt.insert(Point2::new(s.x, s.y)) {
            if h.index() == agent_at.len() {
                agent_at.push(i);
            }
        }
    }
    for e in dt.undirected_edges() {
        let [v, w] = e.vertices();
        let (a, b) = (agent_at[v.fix().index()], agent_at[w.fix().index()]);
        edges.push(Edge {
            a,
            b,
            source_m: (sources[b as usize] - sources[a as usize]).norm(),
        });
    }
}

/// The Delaunay edges of `sources` as one group: agent pairs and source lengths (m).
#[cfg(test)]
pub(crate) fn tests_edges(sources: &[Vec2]) -> Vec<(usize, usize, f64)> {
    let members: Vec<u32> = (0..sources.len() as u32).collect();
    let mut edges = Vec::new();
    delaunay_edges(&members, sources, &mut edges);
    edges
        .iter()
        .map(|e| (e.a as usize, e.b as usize, e.source_m))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(attraction: SubgroupAttraction) -> MoveParams {
        MoveParams {
            subgroup_attraction: attraction,
            ..MoveParams::default()
        }
    }

    /// The term on two agents of one group `d_m` apart along x, both at rest.
    fn two(attraction: SubgroupAttraction, d_m: f64) -> [Vec2; 2] {
        let pos = [Vec2::new(0.0, 0.0), Vec2::new(d_m, 0.0)];
        // Source and target layouts the same: at rest in their places for Place.
        let mut g = Groups::new(&[0, 0], &pos, &pos, attraction);
        let mut acc = [Vec2::zeros(); 2];
        g.attract(
            &pos,
            &[Vec2::zeros(); 2],
            &pos,
            &pos,
            &[1.0, 1.0],
            &params(attraction),
            &mut acc,
        );
        acc
    }

    #[test]
    fn as_printed_pulls_each_towards_the_other_with_a_prime_e_to_the_distance() {
        let p = MoveParams::default();
        for d_m in [0.3, 1.0, 2.5] {
            let acc = two(SubgroupAttraction::AsPrinted, d_m);
            let want = p.subgroup_a_m_s2 * f64::exp(d_m);
            assert!(
                (acc[0].x - want).abs() < 1e-12 * want,
                "{d_m}: {:?}",
                acc[0]
            );
            assert!(
                (acc[1].x + want).abs() < 1e-12 * want,
                "{d_m}: {:?}",
                acc[1]
            );
            assert_eq!((acc[0].y, acc[1].y), (0.0, 0.0));
        }
    }

    #[test]
    fn decaying_pulls_each_towards_the_other_with_a_prime_e_to_minus_d_over_b_prime() {
        let p = MoveParams::default();
        for d_m in [0.3, 1.0, 2.5] {
            let acc = two(SubgroupAttraction::Decaying, d_m);
            let want = p.subgroup_a_m_s2 * f64::exp(-d_m / p.subgroup_b_m);
            assert!((acc[0].x - want).abs() < 1e-12, "{d_m}: {:?}", acc[0]);
            assert!((acc[1].x + want).abs() < 1e-12, "{d_m}: {:?}", acc[1]);
        }
    }

    #[test]
    fn place_pulls_a_stray_back_to_its_place_and_leaves_placed_agents_alone() {
        // In their places (source = target layout, centroid where it should be).
        let acc = two(SubgroupAttraction::Place, 1.0);
        assert!(acc.iter().all(|a| a.norm() < 1e-12), "{acc:?}");
        // Agent 1 strays 0.6 m beyond its place: the centroid moves by 0.3 m, so
        // its place is 0.3 m short of it and agent 0's 0.3 m ahead of it.
        let p = MoveParams::default();
        let layout = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
        let pos = [Vec2::new(0.0, 0.0), Vec2::new(1.6, 0.0)];
        let mut g = Groups::new(&[0, 0], &layout, &layout, SubgroupAttraction::Place);
        let mut acc = [Vec2::zeros(); 2];
        g.attract(
            &pos,
            &[Vec2::zeros(); 2],
            &layout,
            &layout,
            &[1.0; 2],
            &p,
            &mut acc,
        );
        let want = p.subgroup_a_m_s2 * (1.0 - f64::exp(-0.3 / p.subgroup_b_m));
        assert!((acc[0].x - want).abs() < 1e-9 && (acc[1].x + want).abs() < 1e-9);
    }

    #[test]
    fn delaunay_springs_pull_a_stretched_edge_and_push_a_squeezed_one_to_their_rest_length() {
        let p = params(SubgroupAttraction::DelaunayGraph);
        let layout = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
        let mut g = Groups::new(&[0, 0], &layout, &layout, SubgroupAttraction::DelaunayGraph);
        assert_eq!(g.edge_pairs().count(), 1);
        for (d_m, vel_b) in [(1.5, 0.0), (0.7, 0.0), (1.0, 0.4)] {
            let pos = [Vec2::new(0.0, 0.0), Vec2::new(d_m, 0.0)];
            let vel = [Vec2::zeros(), Vec2::new(vel_b, 0.0)];
            let mut acc = [Vec2::zeros(); 2];
            g.attract(&pos, &vel, &layout, &layout, &[1.0; 2], &p, &mut acc);
            // Rest length 1 m (source and target lengths both 1 m).
            let want = p.subgroup_dt_stiffness_m_s2_per_m * (d_m - 1.0)
                + p.subgroup_dt_damping_m_s2_per_m_s * vel_b;
            assert!((acc[0].x - want).abs() < 1e-12, "{d_m}: {acc:?}");
            assert!((acc[1].x + want).abs() < 1e-12, "{d_m}: {acc:?}");
        }
    }

    #[test]
    fn the_rest_length_goes_from_the_source_to_the_target_length_with_progress() {
        let p = params(SubgroupAttraction::DelaunayGraph);
        let src = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
        // Targets 10 m away, 3 m apart.
        let tgt = [Vec2::new(9.0, 0.0), Vec2::new(12.0, 0.0)];
        let mut g = Groups::new(&[0, 0], &src, &tgt, SubgroupAttraction::DelaunayGraph);
        // Centroids 0.5 m (source) and 10.5 m (target): halfway at 5.5 m, α = 0.5.
        for (pos, alpha) in [
            ([Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)], 0.0),
            ([Vec2::new(4.5, 0.0), Vec2::new(6.5, 0.0)], 0.5),
            ([Vec2::new(9.0, 0.0), Vec2::new(12.0, 0.0)], 1.0),
        ] {
            let mut acc = [Vec2::zeros(); 2];
            g.attract(
                &pos,
                &[Vec2::zeros(); 2],
                &src,
                &tgt,
                &[1.0; 2],
                &p,
                &mut acc,
            );
            let rest_m = (1.0 - alpha) * 1.0 + alpha * 3.0;
            let want = p.subgroup_dt_stiffness_m_s2_per_m * ((pos[1] - pos[0]).norm() - rest_m);
            assert!((acc[0].x - want).abs() < 1e-9, "α {alpha}: {acc:?}");
        }
    }

    #[test]
    fn the_graph_is_each_groups_delaunay_triangulation_and_never_crosses_groups() {
        // A 3 × 3 grid in group 0 and a pair far off in group 1.
        let mut src: Vec<Vec2> = (0..9)
            .map(|i| Vec2::new((i % 3) as f64, (i / 3) as f64))
            .collect();
        src.push(Vec2::new(20.0, 0.0));
        src.push(Vec2::new(21.0, 0.0));
        let group_of = [0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1];
        let g = Groups::new(&group_of, &src, &src, SubgroupAttraction::DelaunayGraph);
        // 9 points, 8 on the hull (exact predicates: the side midpoints are on
        // it): 3·9 − 3 − 8 = 16 edges, the 12 sides of the cells and one
        // diagonal each; and the pair's one.
        assert_eq!(g.edge_pairs().count(), 17);
        assert!(g.edge_pairs().all(|(a, b)| group_of[a] == group_of[b]));
        // No other variant builds the graph.
        let none = Groups::new(&group_of, &src, &src, SubgroupAttraction::Place);
        assert_eq!(none.edge_pairs().count(), 0);
    }

    #[test]
    fn spread_is_one_in_the_layout_and_falls_as_the_group_contracts() {
        let src = [Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0)];
        let tgt = [Vec2::new(10.0, 0.0), Vec2::new(14.0, 0.0)];
        let mut g = Groups::new(&[0, 0], &src, &tgt, SubgroupAttraction::Place);
        let s = |g: &mut Groups, pos: [Vec2; 2]| g.spread(&pos, &src, &tgt).unwrap();
        assert!((s(&mut g, src) - 1.0).abs() < 1e-12);
        assert!((s(&mut g, tgt) - 1.0).abs() < 1e-12);
        let half = s(&mut g, [Vec2::new(0.5, 0.0), Vec2::new(1.5, 0.0)]);
        assert!((half - 0.5).abs() < 1e-12, "{half}");
        // A single agent has no spread.
        let mut lone = Groups::new(&[0], &src[..1], &tgt[..1], SubgroupAttraction::Place);
        assert_eq!(lone.spread(&src[..1], &src[..1], &tgt[..1]), None);
    }
}
