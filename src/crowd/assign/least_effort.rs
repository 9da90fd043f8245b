//! Least-effort pairing cost of a formation transform (formation-transform, Xu et al.
//! 2015, section 3.2).
//!
//! The source formation `S` (agent positions) and the target formation `T` (goal
//! positions) are each Delaunay-triangulated; a point's *local edge length* is the
//! mean length of its triangulation edges. Pairing an agent with a goal costs its
//! squared travel distance plus the squared change of its local edge length, balanced
//! by `λ`, and the exact assignment solver minimises the sum (eq. 6).

use crate::crowd::assign::{CostMatrix, CostProvider, CostSource};
use crate::geom::Vec2;
use spade::{DelaunayTriangulation, Point2, Triangulation};

/// The least-effort cost `ΔE(i, j)` of formation-transform eq. 3.
///
/// # Formula
/// formation-transform (Xu et al. 2015) eqs. 3–5, with `G(S, E_S)` and `G(T, E_T)` the
/// Delaunay triangulations of the agents `S` and of the goals `T`:
///
/// ```text
///   ΔE(i, j) = λ |s_i t_j|² + (1 − λ) |δs_i − δt_j|²                      (3)
///   δs_i     = 1 / |{s_i}_np| · Σ_{s_p ∈ {s_i}_np} |s_i s_p|               (4)
///   δt_j     = 1 / |{t_j}_np| · Σ_{t_q ∈ {t_j}_np} |t_j t_q|               (5)
/// ```
///
/// where `{s_i}_np` are the triangulation neighbours of `s_i` (likewise for `t_j`).
/// `λ = 1` is the plain squared distance ([`crate::crowd::assign::SquaredDistance`]); `λ = 0`
/// pairs by local structure alone.
///
/// A point without triangulation neighbours (a formation of one point) has `δ = 0`.
/// Points at the same position share one triangulation vertex and so one `δ`. A point
/// the triangulation rejects (a coordinate that is NaN, infinite or beyond spade's
/// range) gets `δ = 0`; its distance term is then not finite either where it is
/// NaN, which the solver reports ([`crate::crowd::assign::AssignError::NotFinite`]).
///
/// # Units
/// Positions in metres; `λ` dimensionless in `[0, 1]`; costs in m².
///
/// # Complexity
/// Two triangulations, `O(n log n)` expected each (incremental insertion), then
/// `O(agents · goals)` for the matrix. Allocates the triangulations on every call:
/// meant for a formation change, not for every frame.
///
/// # Example
/// ```
/// use crowdtouch::crowd::assign::{CostMatrix, CostProvider};
/// use crowdtouch::crowd::assign::LeastEffort;
/// use crowdtouch::geom::Vec2;
/// // A unit right triangle and the same triangle scaled by 2.
/// let s = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
/// let t = [Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0), Vec2::new(0.0, 2.0)];
/// let mut c = CostMatrix::new(0, 0);
/// LeastEffort::new(0.5).fill(&s, &t, &mut c);
/// // δs_0 = 1 (two unit edges), δt_0 = 2: ΔE(0, 0) = 0.5·0 + 0.5·(1 − 2)².
/// assert!((c.get(0, 0) - 0.5).abs() < 1e-12);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LeastEffort {
    /// `λ` of eq. 3: weight of the squared distance; `1 − λ` weighs the change of the
    /// local edge length.
    pub lambda: f64,
}

impl LeastEffort {
    /// The cost with the given `λ` (clamped to `[0, 1]`; NaN becomes 1, the plain
    /// squared distance).
    pub fn new(lambda: f64) -> LeastEffort {
        let lambda = if lambda.is_nan() {
            1.0
        } else {
            lambda.clamp(0.0, 1.0)
        };
        LeastEffort { lambda }
    }
}

/// Mean Delaunay edge length of every point (formation-transform eqs. 4–5), written
/// into `out` (resized to `points.len()`).
///
/// # Units
/// Metres in, metres out.
///
/// # Complexity
/// `O(n log n)` expected (incremental Delaunay insertion with spade's default hint)
/// plus `O(n)` over the edges. Allocates the triangulation.
pub fn mean_edge_lengths(points: &[Vec2], out: &mut Vec<f64>) {
    out.clear();
    out.resize(points.len(), 0.0);
    let mut dt: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    // Vertex of each point (`None` when the triangulation rejected it); points at the
    // same position map to the same vertex.
    let handles: Vec<_> = points
        .iter()
        .map(|p| dt.insert(Point2::new(p.x, p.y)).ok())
        .collect();
    for (d, h) in out.iter_mut().zip(&handles) {
        let Some(h) = *h else { continue };
        let v = dt.vertex(h);
        let p = v.position();
        let (mut sum, mut n) = (0.0, 0usize);
        for e in v.out_edges() {
            let q = e.to().position();
            sum += ((q.x - p.x).powi(2) + (q.y - p.y).powi(2)).sqrt();
            n += 1;
        }
        if n > 0 {
            *d = sum / n as f64;
        }
    }
}

/// The least-effort costs of one agents → goals instance, computed when the solver
/// reads them ([`CostSource`]): the same numbers as [`CostProvider::fill`] writes,
/// bit for bit, without the `agents × goals` matrix (3.2 GB at 20,000 agents).
///
/// # Complexity
/// Two triangulations when built ([`LeastEffort::costs`]); `O(1)` per entry.
#[derive(Clone, Debug, Default)]
pub struct LeastEffortCosts {
    ax: Vec<f64>,
    ay: Vec<f64>,
    gx: Vec<f64>,
    gy: Vec<f64>,
    ds: Vec<f64>,
    dt: Vec<f64>,
    l: f64,
    m: f64,
}

impl LeastEffort {
    /// The costs of sending `agents` to `goals`, computed on demand
    /// ([`LeastEffortCosts`]).
    pub fn costs(&self, agents: &[Vec2], goals: &[Vec2]) -> LeastEffortCosts {
        let (mut ds, mut dt) = (Vec::new(), Vec::new());
        mean_edge_lengths(agents, &mut ds);
        mean_edge_lengths(goals, &mut dt);
        self.costs_with_lengths(agents, goals, ds, dt)
    }

    /// The costs of sending `agents` to `goals` with the local edge lengths given
    /// (`ds` of the agents, `dt` of the goals, one each) instead of triangulated:
    /// for callers that solve in other coordinates, positions and lengths mapped
    /// alike.
    pub fn costs_with_lengths(
        &self,
        agents: &[Vec2],
        goals: &[Vec2],
        ds: Vec<f64>,
        dt: Vec<f64>,
    ) -> LeastEffortCosts {
        debug_assert_eq!((ds.len(), dt.len()), (agents.len(), goals.len()));
        LeastEffortCosts {
            ax: agents.iter().map(|p| p.x).collect(),
            ay: agents.iter().map(|p| p.y).collect(),
            gx: goals.iter().map(|p| p.x).collect(),
            gy: goals.iter().map(|p| p.y).collect(),
            ds,
            dt,
            l: self.lambda,
            m: 1.0 - self.lambda,
        }
    }
}

impl LeastEffortCosts {
    /// The points whose squared distances are these costs:
    /// `(√λ x, √λ y, √(1 − λ) δ)` of every agent and every goal (eq. 3 is
    /// `λ |s − t|² + (1 − λ)(δs − δt)²`), for a solver that groups them
    /// ([`crate::crowd::assign::CoarseToFine::prices_3d`]). The entries equal these
    /// squared distances up to rounding.
    pub fn points_3d(&self, agents: &mut Vec<[f64; 3]>, goals: &mut Vec<[f64; 3]>) {
        let (l, m) = (self.l.sqrt(), self.m.sqrt());
        agents.clear();
        agents.extend((0..self.ax.len()).map(|i| [l * self.ax[i], l * self.ay[i], m * self.ds[i]]));
        goals.clear();
        goals.extend((0..self.gx.len()).map(|j| [l * self.gx[j], l * self.gy[j], m * self.dt[j]]));
    }
}

impl CostSource for LeastEffortCosts {
    fn rows(&self) -> usize {
        self.ax.len()
    }
    fn cols(&self) -> usize {
        self.gx.len()
    }
    #[inline]
    fn get(&self, i: usize, j: usize) -> f64 {
        let (dx, dy) = (self.ax[i] - self.gx[j], self.ay[i] - self.gy[j]);
        let de = self.ds[i] - self.dt[j];
        self.l * (dx * dx + dy * dy) + self.m * (de * de)
    }
    fn row<'a>(&'a self, i: usize, buf: &'a mut Vec<f64>) -> &'a [f64] {
        let (ax, ay, da) = (self.ax[i], self.ay[i], self.ds[i]);
        buf.resize(self.gx.len(), 0.0);
        for (e, ((&gx, &gy), &dg)) in buf
            .iter_mut()
            .zip(self.gx.iter().zip(&self.gy).zip(&self.dt))
        {
            let (dx, dy) = (ax - gx, ay - gy);
            let de = da - dg;
            *e = self.l * (dx * dx + dy * dy) + self.m * (de * de);
        }
        buf
    }
}

impl CostProvider for LeastEffort {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {
        let (mut ds, mut dt) = (Vec::new(), Vec::new());
        mean_edge_lengths(agents, &mut ds);
        mean_edge_lengths(goals, &mut dt);
        let (l, m) = (self.lambda, 1.0 - self.lambda);
        out.resize(agents.len(), goals.len());
        for (r, (a, &da)) in agents.iter().zip(&ds).enumerate() {
            for ((e, g), &dg) in out.row_mut(r).iter_mut().zip(goals).zip(&dt) {
                let (dx, dy) = (a.x - g.x, a.y - g.y);
                let de = da - dg;
                *e = l * (dx * dx + dy * dy) + m * (de * de);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::assign::{Solver, SquaredDistance};
    use proptest::prelude::{prop_assert, proptest};
    use proptest::test_runner::{Config as ProptestConfig, RngSeed};

    const SQRT2: f64 = std::f64::consts::SQRT_2;

    /// Hand-computed case: a unit right triangle S and the same triangle scaled by 2
    /// (T). Every triangle edge is a Delaunay edge:
    /// δs = [1, (1 + √2)/2, (1 + √2)/2], δt = [2, 1 + √2, 1 + √2].
    #[test]
    fn right_triangle_by_hand() {
        let s = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ];
        let t = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(0.0, 2.0),
        ];
        let mut d = Vec::new();
        mean_edge_lengths(&s, &mut d);
        let h = (1.0 + SQRT2) / 2.0;
        for (got, want) in d.iter().zip([1.0, h, h]) {
            assert!((got - want).abs() < 1e-12, "{d:?}");
        }
        let mut c = CostMatrix::new(0, 0);
        LeastEffort::new(0.5).fill(&s, &t, &mut c);
        let want = |dist2: f64, ds: f64, dt: f64| 0.5 * dist2 + 0.5 * (ds - dt) * (ds - dt);
        let dt = [2.0, 1.0 + SQRT2, 1.0 + SQRT2];
        let ds = [1.0, h, h];
        for (i, (si, &dsi)) in s.iter().zip(&ds).enumerate() {
            for (j, (tj, &dtj)) in t.iter().zip(&dt).enumerate() {
                let w = want((si - tj).norm_squared(), dsi, dtj);
                assert!((c.get(i, j) - w).abs() < 1e-12, "({i},{j})");
            }
        }
        // (0,0): no travel, δ from 1 to 2.
        assert!((c.get(0, 0) - 0.5).abs() < 1e-12);
        // (1,1): travel 1, δ from h to 2h.
        assert!((c.get(1, 1) - (0.5 + 0.5 * h * h)).abs() < 1e-12);
        let mut solver = Solver::new();
        assert_eq!(solver.solve(&c).unwrap(), &[0, 1, 2]);
    }

    #[test]
    fn degenerate_formations() {
        let mut d = Vec::new();
        mean_edge_lengths(&[Vec2::new(1.0, 1.0)], &mut d);
        assert_eq!(d, [0.0]);
        // Collinear: the triangulation is a path.
        mean_edge_lengths(
            &[
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(3.0, 0.0),
            ],
            &mut d,
        );
        assert_eq!(d, [1.0, 1.5, 2.0]);
        // Duplicates share a vertex; NaN is rejected with δ = 0, no panic.
        mean_edge_lengths(
            &[
                Vec2::new(0.0, 0.0),
                Vec2::new(2.0, 0.0),
                Vec2::new(0.0, 0.0),
                Vec2::new(f64::NAN, 0.0),
            ],
            &mut d,
        );
        assert_eq!(d, [2.0, 2.0, 2.0, 0.0]);
        mean_edge_lengths(&[], &mut d);
        assert!(d.is_empty());
    }

    /// The costs computed on demand are the matrix's, bit for bit, and solve to
    /// the same assignment.
    #[test]
    fn on_demand_costs_are_the_matrix() {
        let mut rng = crate::rng::SplitMix64::new(0x1ea57);
        let pts = |rng: &mut crate::rng::SplitMix64, n: usize, s: f64| -> Vec<Vec2> {
            (0..n)
                .map(|_| Vec2::new(s * rng.unit(), s * rng.unit()))
                .collect()
        };
        let (a, g) = (pts(&mut rng, 150, 1.0), pts(&mut rng, 170, 2.0));
        for lambda in [0.0, 0.4, 1.0] {
            let le = LeastEffort::new(lambda);
            let mut c = CostMatrix::new(0, 0);
            le.fill(&a, &g, &mut c);
            let od = le.costs(&a, &g);
            assert_eq!((od.rows(), od.cols()), (150, 170));
            let mut buf = Vec::new();
            for i in 0..a.len() {
                assert_eq!(od.row(i, &mut buf), CostSource::row(&c, i, &mut Vec::new()));
                for j in (0..g.len()).step_by(13) {
                    assert_eq!(od.get(i, j).to_bits(), c.get(i, j).to_bits());
                }
            }
            let want = Solver::new().solve(&c).unwrap().to_vec();
            assert_eq!(Solver::new().solve_with(&od).unwrap(), want);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 64,
            rng_seed: RngSeed::Fixed(0x00EF_F0E7),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        /// λ = 1 leaves only the distance term of eq. 3: the squared distance exactly;
        /// λ = 0 leaves only the edge-length term.
        #[test]
        fn lambda_limits(
            pts in proptest::collection::vec((-5.0..5.0f64, -5.0..5.0f64), 2..40),
            split in 1usize..20,
        ) {
            let pts: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
            let split = split.min(pts.len() - 1);
            let (a, g) = pts.split_at(split);
            let (mut c, mut sq) = (CostMatrix::new(0, 0), CostMatrix::new(0, 0));
            LeastEffort::new(1.0).fill(a, g, &mut c);
            SquaredDistance.fill(a, g, &mut sq);
            prop_assert!(c == sq);
            let (mut da, mut dg) = (Vec::new(), Vec::new());
            mean_edge_lengths(a, &mut da);
            mean_edge_lengths(g, &mut dg);
            LeastEffort::new(0.0).fill(a, g, &mut c);
            for (i, &di) in da.iter().enumerate() {
                for (j, &dj) in dg.iter().enumerate() {
                    prop_assert!(c.get(i, j) == (di - dj).powi(2));
                }
            }
        }
    }
}
