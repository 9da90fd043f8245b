//! The objective measures of formation-transform section 5.1: `I_d` (eq. 17, with
//! `I_v` beside it; computed in `feedback.rs`), the spread of the agents' nearest
//! neighbour distances `σ_min_dis` (eq. 24) and the spread of their current efforts
//! `σ_curr_eft` (eqs. 25–26).

use super::grid::Grid;
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
/// neighbour `min_dis(i)`, found with `grid` (built on `pos`) by a ring search and
/// left in `nearest`; with the smallest of them. `(0, ∞)` for fewer than two agents.
pub(crate) fn sigma_min_dis(grid: &Grid, pos: &[Vec2], nearest: &mut [f64]) -> (f64, f64) {
    let mut min = f64::INFINITY;
    for (i, m) in nearest.iter_mut().enumerate().take(pos.len()) {
        *m = grid.nearest_distance(pos, i);
        min = min.min(*m);
    }
    if pos.len() < 2 {
        return (0.0, min);
    }
    (std_dev(pos.len(), |i| nearest[i]), min)
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
        let mut g = Grid::with_capacity(3);
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
        let mut g = Grid::with_capacity(100);
        g.build(&lattice, 1.0);
        let mut nearest = [0.0; 100];
        let (sigma, min) = sigma_min_dis(&g, &lattice, &mut nearest);
        assert!(sigma < 1e-12 && (min - 0.8).abs() < 1e-12);
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
