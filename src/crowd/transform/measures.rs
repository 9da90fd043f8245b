//! The objective measures of formation-transform section 5.1: `I_d` (eq. 17, with
//! `I_v` beside it; computed in `feedback.rs`), the spread of the agents' nearest
//! neighbour distances `σ_min_dis` (eq. 24) and the spread of their current efforts
//! `σ_curr_eft` (eqs. 25–26).

use crate::crowd::agents::NeighbourGrid;
use crate::geom::Vec2;

/// The three measures of section 5.1 (and `I_v`), for one instant or averaged.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Measures {
    /// `I_d`, eq. 17 (bits).
    pub i_d: f64,
    /// `I_v`: as `I_d`, with speed bins for directions (bits).
    pub i_v: f64,
    /// `σ_min_dis`, eq. 24 (m).
    pub sigma_min_dis_m: f64,
    /// `σ_curr_eft`, eq. 26 (m).
    pub sigma_curr_eft_m: f64,
}

/// Population standard deviation `sqrt(Σ (x − μ)² / N)` of the values `f(i)`,
/// `i < n` (eqs. 24, 26), in two passes; zero for `n = 0`.
pub(crate) fn std_dev(n: usize, f: impl Fn(usize) -> f64) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mean = (0..n).map(&f).sum::<f64>() / n as f64;
    ((0..n).map(|i| (f(i) - mean).powi(2)).sum::<f64>() / n as f64).sqrt()
}

/// `σ_min_dis` (eq. 24): the deviation of each agent's distance to its nearest
/// neighbour `min_dis(i)`, found with `grid` (built on `pos`) by
/// [`nearest_distances`] and left in `nearest`; with the smallest of them. `(0, ∞)`
/// for fewer than two agents.
#[cfg(test)]
pub(crate) fn sigma_min_dis(grid: &NeighbourGrid, pos: &[Vec2], nearest: &mut [f64]) -> (f64, f64) {
    nearest_distances(grid, pos, nearest, |_, _, _| {});
    spread_and_min(&nearest[..pos.len()])
}

/// The deviation (eq. 24) and the smallest of the nearest-neighbour distances
/// `nearest`; `(0, ∞)` for fewer than two.
pub(crate) fn spread_and_min(nearest: &[f64]) -> (f64, f64) {
    let min = nearest.iter().cloned().fold(f64::INFINITY, f64::min);
    if nearest.len() < 2 {
        return (0.0, min);
    }
    (std_dev(nearest.len(), |i| nearest[i]), min)
}

/// Each agent's distance to its nearest other agent into `nearest` (m, `∞` when
/// alone), `grid` built on `pos`. One pass over the pairs closer than the grid's
/// cell side finds it for every agent with a neighbour that near (each such pair
/// is also handed to `visit(i, j, squared distance)`); the others, in sparse
/// places, by the grid's ring search. The same values as a ring search for every
/// agent, without one.
pub(crate) fn nearest_distances(
    grid: &NeighbourGrid,
    pos: &[Vec2],
    nearest: &mut [f64],
    mut visit: impl FnMut(usize, usize, f64),
) {
    let n = pos.len();
    let best2 = &mut nearest[..n];
    best2.fill(f64::INFINITY);
    grid.for_each_pair_d2(pos, grid.cell_m(), |i, j, _, d2| {
        best2[i] = best2[i].min(d2);
        best2[j] = best2[j].min(d2);
        visit(i, j, d2);
    });
    for (i, m) in best2.iter_mut().enumerate() {
        *m = if m.is_finite() {
            m.sqrt()
        } else {
            grid.nearest_distance(pos, i)
        };
    }
}

/// `σ_curr_eft` (eq. 26) of `curr_eft(i) = |s_i − pos(a_i)|` (eq. 25).
pub(crate) fn sigma_curr_eft(sources: &[Vec2], pos: &[Vec2]) -> f64 {
    std_dev(pos.len(), |i| (sources[i] - pos[i]).norm())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_min_dis_matches_the_direct_formula() {
        // Three agents on a line at 0, 1, 3: nearest distances 1, 1, 2.
        let pos = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(3.0, 0.0),
        ];
        let mut g = NeighbourGrid::with_capacity(3);
        g.build(&pos, 0.5);
        let mean = 4.0 / 3.0;
        let want = ((2.0 * (1.0f64 - mean).powi(2) + (2.0f64 - mean).powi(2)) / 3.0).sqrt();
        let mut nearest = [0.0; 3];
        let (sigma, min) = sigma_min_dis(&g, &pos, &mut nearest);
        assert!((sigma - want).abs() < 1e-12);
        assert_eq!((min, nearest), (1.0, [1.0, 1.0, 2.0]));
        // A square lattice: every nearest distance equal.
        let lattice: Vec<Vec2> = (0..100)
            .map(|i| Vec2::new((i % 10) as f64 * 0.8, (i / 10) as f64 * 0.8))
            .collect();
        let mut g = NeighbourGrid::with_capacity(100);
        g.build(&lattice, 1.0);
        let mut nearest = [0.0; 100];
        let (sigma, min) = sigma_min_dis(&g, &lattice, &mut nearest);
        assert!(sigma < 1e-12 && (min - 0.8).abs() < 1e-12);
    }

    #[test]
    fn nearest_distances_match_brute_force_dense_and_sparse() {
        // A dense cluster (neighbours within a cell) and scattered stragglers (found
        // by the ring search), with the pairs handed over checked too.
        let mut r = crate::rng::SplitMix64::new(7);
        let mut pos: Vec<Vec2> = (0..200)
            .map(|_| Vec2::new(r.uniform(0.0, 5.0), r.uniform(0.0, 5.0)))
            .collect();
        pos.extend((0..20).map(|_| Vec2::new(r.uniform(10.0, 60.0), r.uniform(-40.0, 0.0))));
        pos.push(pos[3]);
        let mut g = NeighbourGrid::with_capacity(pos.len());
        g.build(&pos, 0.6);
        let mut nearest = vec![0.0; pos.len()];
        let mut seen = vec![];
        nearest_distances(&g, &pos, &mut nearest, |i, j, d2| {
            assert_eq!(d2, (pos[i] - pos[j]).norm_squared());
            seen.push((i.min(j), i.max(j)));
        });
        for i in 0..pos.len() {
            let brute = (0..pos.len())
                .filter(|&j| j != i)
                .map(|j| (pos[i] - pos[j]).norm())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(nearest[i], brute, "agent {i}");
        }
        seen.sort();
        let c = g.cell_m();
        let want: Vec<(usize, usize)> = (0..pos.len())
            .flat_map(|i| (i + 1..pos.len()).map(move |j| (i, j)))
            .filter(|&(i, j)| (pos[i] - pos[j]).norm_squared() < c * c)
            .collect();
        assert_eq!(seen, want);
        assert!(nearest[200..220].iter().any(|&d| d > c));
    }

    #[test]
    fn sigma_curr_eft_matches_the_direct_formula() {
        let s = [Vec2::zeros(); 4];
        let p = [
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 2.0),
            Vec2::new(-3.0, 0.0),
            Vec2::new(0.0, -4.0),
        ];
        // Efforts 1, 2, 3, 4: mean 2.5, variance 1.25.
        assert!((sigma_curr_eft(&s, &p) - 1.25f64.sqrt()).abs() < 1e-12);
    }
}
