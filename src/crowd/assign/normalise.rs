//! An affine change of coordinates that leaves the optimal assignment of a square
//! squared-distance instance unchanged and makes its two point sets alike.
//!
//! With `c_ij = |a_i − g_j|² = |a_i|² + |g_j|² − 2·a_i·g_j`, an injection of `n` rows
//! onto `n` columns minimises `Σ c_iσ(i)` exactly when it maximises `Σ a_i·g_σ(i)`:
//! the squared norms add the same total whatever the permutation. Map the agents by
//! `a ↦ A·(a − μ_a)` and the goals by `g ↦ A⁻ᵀ·(g − μ_g)` (any invertible `A`, any
//! shifts): every product becomes `(a_i − μ_a)·(g_j − μ_g)`, which differs from
//! `a_i·g_j` by a term of `i` alone, a term of `j` alone and a constant, so every
//! permutation's total changes by the same amount and the optimum is the same
//! permutation. (Not so for a rectangular instance, where the column terms of the
//! unused goals drop out, nor for the plain distance: those are solved as given.)
//!
//! The solver's geometric fast path ([`PointCosts`]) is quickest when the agents and
//! goals are spread alike: a row's cheapest goals are then its nearest ones and the
//! column prices stay small. A crowd dragged 3 m off its formation, pinched into a
//! 0.3 m disk, or stretched into a line is the opposite: every agent's nearest goals
//! are the same few at one edge, the prices must grow across the whole set before the
//! lists separate, and a solve takes seconds. This map centres both sets and picks
//! the symmetric positive definite `A` that gives them the same covariance:
//!
//! ```text
//!   A·Σa·A = A⁻¹·Σg·A⁻¹   ⇔   M·Σa·M = Σg  with M = A²,
//!   M = Σa^{-1/2} · (Σa^{1/2} · Σg · Σa^{1/2})^{1/2} · Σa^{-1/2}
//! ```
//!
//! (the matrix geometric mean of `Σa⁻¹` and `Σg`). For symmetric `A`, `A⁻ᵀ = A⁻¹`.
//! The covariances' eigenvalues are floored at [`SPREAD_FLOOR`] of the largest, so a
//! line or a point of agents gives a well-conditioned `A` (any invertible `A` is
//! exact; the floor only bounds how far the map stretches).
//!
//! [`PointCosts`]: super::PointCosts

use crate::geom::Vec2;
use nalgebra::{Matrix2, SymmetricEigen};

/// Smallest covariance eigenvalue kept, as a fraction of the largest (a spread ratio
/// of 1 : 100 per axis).
pub const SPREAD_FLOOR: f64 = 1e-8;

/// The map `a ↦ A·(a − μ_a)`, `g ↦ A⁻¹·(g − μ_g)` of the module doc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineMap {
    /// Mean of the agents (m).
    pub agents_mean: Vec2,
    /// Mean of the goals (m).
    pub goals_mean: Vec2,
    /// The symmetric positive definite `A` (dimensionless up to the spread ratio).
    pub a: Matrix2<f64>,
    /// Its inverse.
    pub a_inv: Matrix2<f64>,
}

impl AffineMap {
    /// The map that centres both sets and equalises their covariances; `None` when it
    /// does not apply or is not needed: different sizes, fewer than 3 points, a
    /// non-finite position, or both sets at a single point.
    pub fn equalising(agents: &[Vec2], goals: &[Vec2]) -> Option<AffineMap> {
        if agents.len() != goals.len() || agents.len() < 3 {
            return None;
        }
        let (ma, sa) = moments(agents)?;
        let (mg, sg) = moments(goals)?;
        let scale = sa.trace().max(sg.trace());
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        // Work in units of the larger spread, so the floor and the square roots see
        // numbers near 1.
        let sa = floor_spectrum(sa / scale)?;
        let sg = floor_spectrum(sg / scale)?;
        let sa_half = spd_pow(&sa, 0.5)?;
        let sa_inv_half = spd_pow(&sa, -0.5)?;
        let mid = spd_pow(&symmetrise(sa_half * sg * sa_half), 0.5)?;
        let m = symmetrise(sa_inv_half * mid * sa_inv_half);
        let a = spd_pow(&m, 0.5)?;
        let a_inv = spd_pow(&m, -0.5)?;
        let map = AffineMap {
            agents_mean: ma,
            goals_mean: mg,
            a,
            a_inv,
        };
        map.is_finite().then_some(map)
    }

    /// The image of an agent position.
    pub fn agent(&self, p: Vec2) -> Vec2 {
        self.a * (p - self.agents_mean)
    }

    /// The image of a goal position.
    pub fn goal(&self, p: Vec2) -> Vec2 {
        self.a_inv * (p - self.goals_mean)
    }

    fn is_finite(&self) -> bool {
        self.a
            .iter()
            .chain(self.a_inv.iter())
            .all(|v| v.is_finite())
    }
}

/// Mean and (population) covariance; `None` if a coordinate is not finite.
fn moments(p: &[Vec2]) -> Option<(Vec2, Matrix2<f64>)> {
    let n = p.len() as f64;
    let mut mean = Vec2::zeros();
    for q in p {
        if !(q.x.is_finite() && q.y.is_finite()) {
            return None;
        }
        mean += q;
    }
    mean /= n;
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for q in p {
        let d = *q - mean;
        xx += d.x * d.x;
        xy += d.x * d.y;
        yy += d.y * d.y;
    }
    Some((mean, Matrix2::new(xx / n, xy / n, xy / n, yy / n)))
}

fn symmetrise(m: Matrix2<f64>) -> Matrix2<f64> {
    (m + m.transpose()) * 0.5
}

/// The covariance with its eigenvalues raised to at least [`SPREAD_FLOOR`] of the
/// largest (and to a tiny absolute floor when both vanish).
fn floor_spectrum(s: Matrix2<f64>) -> Option<Matrix2<f64>> {
    let e = SymmetricEigen::new(symmetrise(s));
    let top = e.eigenvalues.max().max(1e-12);
    let vals = e.eigenvalues.map(|l| l.max(top * SPREAD_FLOOR));
    let out = e.eigenvectors * Matrix2::from_diagonal(&vals) * e.eigenvectors.transpose();
    out.iter().all(|v| v.is_finite()).then_some(symmetrise(out))
}

/// `s^p` for a symmetric positive definite `s`; `None` if an eigenvalue is not
/// positive.
fn spd_pow(s: &Matrix2<f64>, p: f64) -> Option<Matrix2<f64>> {
    let e = SymmetricEigen::new(*s);
    if !e.eigenvalues.iter().all(|&l| l > 0.0 && l.is_finite()) {
        return None;
    }
    let vals = e.eigenvalues.map(|l| l.powf(p));
    Some(symmetrise(
        e.eigenvectors * Matrix2::from_diagonal(&vals) * e.eigenvectors.transpose(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn cov(p: &[Vec2]) -> Matrix2<f64> {
        moments(p).unwrap().1
    }

    fn rect(rng: &mut SplitMix64, n: usize, w: f64, h: f64, at: Vec2) -> Vec<Vec2> {
        (0..n)
            .map(|_| at + Vec2::new(w * rng.unit(), h * rng.unit()))
            .collect()
    }

    #[test]
    fn the_images_have_equal_covariance_and_zero_mean() {
        let mut rng = SplitMix64::new(7);
        let agents: Vec<Vec2> = (0..500)
            .map(|_| Vec2::new(0.3 * rng.unit(), 0.02 * rng.unit() + 0.5 * rng.unit()))
            .collect();
        let goals = rect(&mut rng, 500, 4.0, 3.0, Vec2::new(5.0, -2.0));
        let map = AffineMap::equalising(&agents, &goals).unwrap();
        let a: Vec<Vec2> = agents.iter().map(|&p| map.agent(p)).collect();
        let g: Vec<Vec2> = goals.iter().map(|&p| map.goal(p)).collect();
        let (ca, cg) = (cov(&a), cov(&g));
        assert!((ca - cg).norm() < 1e-9 * cg.norm(), "{ca} vs {cg}");
        let (ma, mg) = (moments(&a).unwrap().0, moments(&g).unwrap().0);
        assert!(ma.x.abs() + ma.y.abs() + mg.x.abs() + mg.y.abs() < 1e-9);
    }

    #[test]
    fn products_change_by_a_row_term_and_a_column_term_only() {
        // The invariance the module relies on, checked on every pair:
        // a'_i·g'_j − a_i·g_j = r_i + q_j + k.
        let mut rng = SplitMix64::new(11);
        let agents = rect(&mut rng, 40, 0.3, 0.3, Vec2::new(1.0, 1.0));
        let goals = rect(&mut rng, 40, 8.0, 0.05, Vec2::new(-3.0, 4.0));
        let map = AffineMap::equalising(&agents, &goals).unwrap();
        let d = |i: usize, j: usize| {
            map.agent(agents[i]).dot(&map.goal(goals[j])) - agents[i].dot(&goals[j])
        };
        for i in 0..40 {
            for j in 0..40 {
                // Mixed second difference vanishes iff d splits into r_i + q_j.
                let mixed = d(i, j) - d(i, 0) - d(0, j) + d(0, 0);
                assert!(mixed.abs() < 1e-9, "pair ({i}, {j}): {mixed}");
            }
        }
    }

    #[test]
    fn degenerate_and_unequal_instances_are_left_alone_or_conditioned() {
        let p = Vec2::new(1.0, 2.0);
        assert_eq!(AffineMap::equalising(&[p; 5], &[p; 5]), None);
        assert_eq!(AffineMap::equalising(&[p; 3], &[p; 4]), None);
        let nan = Vec2::new(f64::NAN, 0.0);
        assert_eq!(AffineMap::equalising(&[p, p, nan], &[p, p, p]), None);
        // All agents at one point, goals spread: A is finite and invertible.
        let mut rng = SplitMix64::new(3);
        let goals = rect(&mut rng, 10, 4.0, 3.0, Vec2::new(0.0, 0.0));
        let map = AffineMap::equalising(&[p; 10], &goals).unwrap();
        assert!(
            map.a.determinant() > 0.0 && (map.a * map.a_inv - Matrix2::identity()).norm() < 1e-9
        );
    }
}
