//! Functional PCA of a crowd motion (gesture-driven section 6.2, eq. 16): the mean
//! trajectory, the leading eigenvectors of the agents' serialised trajectories
//! (eq. 15) and each agent's eigenscores.
//!
//! The trajectories are sampled on a common grid of [`S_H`] times, so the functional
//! PCA is the PCA of the `M × TRAJ_DIM` matrix of serialised trajectories: with its
//! centred matrix `X = U Σ Vᵀ`, the eigenvectors are the columns of `V` and the
//! eigenscores are the projections `X V`.
//!
//! `V` and `Σ²` come from nalgebra's symmetric eigen-decomposition of the
//! `TRAJ_DIM × TRAJ_DIM` scatter matrix `XᵀX`, not from its SVD of `X`: on
//! rank-deficient inputs (the normal case here: a translation has rank 2) nalgebra
//! 0.33's SVD returned factors off by 1e-7 of `‖X‖` for some inputs and up to 70 %
//! for tall ones, where the eigen-decomposition stayed at rounding level (1e-13).
//! Squaring costs precision only in the trailing singular values (absolute error
//! about `1e-8 σ_max`), which the reconstruction does not need.

use super::crowd_motion::{serialise, CrowdMotion};
use super::error::MotionError;
use crate::gesture::library::{MAX_COMPONENTS, S_H, TRAJ_DIM};
use nalgebra::DMatrix;

/// A crowd motion's FPCA: `c_m ≈ c̄ + Σ_k s_{m,k} e_k` (eq. 16).
#[derive(Clone, Debug, PartialEq)]
pub struct Fpca {
    /// The mean trajectory `c̄_s`, serialised (eq. 15), [`TRAJ_DIM`] long.
    pub mean: Vec<f64>,
    /// The kept eigenvectors `E_V`, orthonormal, in decreasing order of variance,
    /// each [`TRAJ_DIM`] long. Sign convention: each one's entry of largest
    /// magnitude is positive.
    pub basis: Vec<Vec<f64>>,
    /// Each agent's eigenscores `E_S` (one row per agent, `basis.len()` values).
    pub scores: Vec<Vec<f64>>,
    /// The singular values of the centred matrix, in decreasing order
    /// (`min(M, TRAJ_DIM)` of them, from the eigenvalues of `XᵀX`: the trailing ones
    /// carry an absolute error of about `1e-8 σ_max`); the kept ones come first.
    pub singular_values: Vec<f64>,
    /// The numerical rank of the centred matrix.
    pub rank: usize,
}

/// How well the kept eigenvectors reproduce a motion (eq. 16).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ReconstructionError {
    /// RMS distance between a sample and its reconstruction, over all agents and
    /// samples (crowd units).
    pub rms: f64,
    /// RMS distance of a sample from its agent's start, over all agents and samples
    /// (crowd units): the motion's extent.
    pub rms_displacement: f64,
    /// `rms / rms_displacement`: the error relative to how far the crowd moves (the
    /// measure of section 6.2's "< 1 % error"; 0 when both are 0, infinite when only
    /// the motion is still).
    pub relative: f64,
    /// `‖X − X̂‖_F / ‖X − 1 c̄ᵀ‖_F`: the share of the variation about the mean
    /// trajectory that is lost (0 when there is none).
    pub relative_to_variation: f64,
}

/// An eigenvalue `σ²` of the scatter matrix counts towards the rank when it is above
/// `RANK_TOL · TRAJ_DIM · ε · σ²_max` (so singular values below about `5e-7 σ_max`
/// count as zero).
const RANK_TOL: f64 = 10.0;

/// The FPCA of a motion keeping `min(max_components, MAX_COMPONENTS, rank)`
/// eigenvectors (section 6.2: "the first 15 principal components").
///
/// # Formula
/// `c̄ = (1/M) Σ_m c_m`; `X − 1 c̄ᵀ = U Σ Vᵀ`; `e_k` = column `k` of `V`;
/// `s_{m,k} = e_kᵀ (c_m − c̄)` (eq. 16). With all components kept, the
/// reconstruction is exact; dropping component `k` costs `σ_k²` of
/// `‖X − X̂‖_F²` (Eckart–Young).
///
/// # Complexity
/// `O(M · 128²)` for the scatter matrix, and one symmetric eigen-decomposition of a
/// `128 × 128` matrix.
///
/// # Errors
/// [`CrowdMotion::validate`]'s: no trajectories, a NaN, a bad duration.
pub fn fpca(m: &CrowdMotion, max_components: usize) -> Result<Fpca, MotionError> {
    m.validate()?;
    let rows = m.len();
    let mut x = DMatrix::<f64>::zeros(rows, TRAJ_DIM);
    let mut buf = vec![0.0; TRAJ_DIM];
    for (r, t) in m.trajectories.iter().enumerate() {
        serialise(t, &mut buf);
        for (c, v) in buf.iter().enumerate() {
            x[(r, c)] = *v;
        }
    }
    let mean: Vec<f64> = (0..TRAJ_DIM)
        .map(|c| x.column(c).sum() / rows as f64)
        .collect();
    for (c, &mc) in mean.iter().enumerate() {
        x.column_mut(c).iter_mut().for_each(|v| *v -= mc);
    }
    // The eigen-decomposition of the scatter matrix XᵀX = V Σ² Vᵀ (see the module
    // doc for why not nalgebra's SVD).
    let eig = (x.transpose() * &x).symmetric_eigen();
    let mut order: Vec<usize> = (0..TRAJ_DIM).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let lambda_max = eig.eigenvalues[order[0]].max(0.0);
    let tol = RANK_TOL * TRAJ_DIM as f64 * f64::EPSILON * lambda_max;
    let rank = order
        .iter()
        .take(rows)
        .take_while(|&&i| eig.eigenvalues[i] > tol && eig.eigenvalues[i] > 0.0)
        .count();
    let singular_values: Vec<f64> = order
        .iter()
        .take(rows.min(TRAJ_DIM))
        .map(|&i| eig.eigenvalues[i].max(0.0).sqrt())
        .collect();
    let keep = max_components.min(MAX_COMPONENTS).min(rank);
    let mut basis = Vec::with_capacity(keep);
    for &i in order.iter().take(keep) {
        let mut e: Vec<f64> = eig.eigenvectors.column(i).iter().copied().collect();
        let big =
            e.iter().enumerate().fold(
                (0, 0.0f64),
                |b, (j, v)| if v.abs() > b.1 { (j, v.abs()) } else { b },
            );
        if e[big.0] < 0.0 {
            e.iter_mut().for_each(|v| *v = -*v);
        }
        basis.push(e);
    }
    let scores = (0..rows)
        .map(|r| {
            basis
                .iter()
                .map(|e| e.iter().zip(x.row(r).iter()).map(|(a, b)| a * b).sum())
                .collect()
        })
        .collect();
    Ok(Fpca {
        mean,
        basis,
        scores,
        singular_values,
        rank,
    })
}

impl Fpca {
    /// The serialised trajectory `c̄ + Σ_k s_k e_k` (eq. 16) for eigenscores `s`
    /// (`basis.len()` long; extra scores are ignored) into `out` ([`TRAJ_DIM`] long).
    pub fn reconstruct_into(&self, scores: &[f64], out: &mut [f64]) {
        reconstruct(&self.mean, &self.basis, scores, out);
    }

    /// How well the kept eigenvectors reproduce `m` (normally the motion analysed):
    /// see [`ReconstructionError`].
    pub fn reconstruction_error(&self, m: &CrowdMotion) -> ReconstructionError {
        let mut x = vec![0.0; TRAJ_DIM];
        let mut xh = vec![0.0; TRAJ_DIM];
        let (mut err2, mut disp2, mut var2) = (0.0, 0.0, 0.0);
        for t in &m.trajectories {
            serialise(t, &mut x);
            let s: Vec<f64> = self
                .basis
                .iter()
                .map(|e| {
                    e.iter()
                        .zip(x.iter().zip(&self.mean))
                        .map(|(a, (b, c))| a * (b - c))
                        .sum()
                })
                .collect();
            self.reconstruct_into(&s, &mut xh);
            err2 += x
                .iter()
                .zip(&xh)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>();
            var2 += x
                .iter()
                .zip(&self.mean)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>();
            disp2 += t.iter().map(|p| (p - t[0]).norm_squared()).sum::<f64>();
        }
        let n = (m.len() * S_H).max(1) as f64;
        let rms = (err2 / n).sqrt();
        let rms_displacement = (disp2 / n).sqrt();
        let ratio = |a: f64, b: f64| {
            if a == 0.0 {
                0.0
            } else if b == 0.0 {
                f64::INFINITY
            } else {
                a / b
            }
        };
        ReconstructionError {
            rms,
            rms_displacement,
            relative: ratio(rms, rms_displacement),
            relative_to_variation: ratio(err2.sqrt(), var2.sqrt()),
        }
    }
}

/// `out = mean + Σ_k scores[k] · basis[k]` (eq. 16), for the first
/// `min(basis.len(), scores.len())` components.
pub fn reconstruct(mean: &[f64], basis: &[Vec<f64>], scores: &[f64], out: &mut [f64]) {
    out.copy_from_slice(mean);
    for (e, &s) in basis.iter().zip(scores) {
        for (o, v) in out.iter_mut().zip(e) {
            *o += s * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::rng::SplitMix64;

    /// A motion of `m` agents whose trajectories are `c̄ + Σ_k a_{m,k} f_k` for `r`
    /// fixed random functions `f_k`: rank at most `r`.
    fn low_rank(m: usize, r: usize, seed: u64) -> CrowdMotion {
        let mut rng = SplitMix64::new(seed);
        // Distinct frequencies keep the functions well apart (condition number of
        // the basis about 10).
        let f: Vec<Vec<Vec2>> = (0..r)
            .map(|k| {
                let (a, b) = (rng.uniform(0.0, 6.0), rng.uniform(0.0, 6.0));
                let w = std::f64::consts::PI * (k + 1) as f64;
                (0..S_H)
                    .map(|s| {
                        let t = s as f64 / (S_H - 1) as f64;
                        Vec2::new((w * t + a).sin(), (w * t + b).cos())
                    })
                    .collect()
            })
            .collect();
        let trajectories = (0..m)
            .map(|_| {
                let c: Vec<f64> = (0..r).map(|_| rng.uniform(-2.0, 2.0)).collect();
                let mut t = [Vec2::new(0.3, -0.1); S_H];
                for (k, fk) in f.iter().enumerate() {
                    for (p, q) in t.iter_mut().zip(fk) {
                        *p += q * c[k];
                    }
                }
                t
            })
            .collect();
        CrowdMotion {
            trajectories,
            duration_s: 3.0,
        }
    }

    #[test]
    fn a_motion_of_known_low_rank_is_reconstructed_exactly() {
        for (m, r) in [(40, 1), (40, 3), (60, 7), (20, 15), (200, 12)] {
            let motion = low_rank(m, r, 11 + r as u64);
            let f = fpca(&motion, 15).unwrap();
            assert_eq!(f.rank, r, "m {m} r {r}: {:?}", &f.singular_values[..r + 1]);
            assert_eq!(f.basis.len(), r);
            let e = f.reconstruction_error(&motion);
            assert!(
                e.relative < 1e-10 && e.relative_to_variation < 1e-10,
                "m {m} r {r}: {e:?} {:?}",
                f.singular_values
            );
            // Orthonormal basis.
            for i in 0..r {
                for j in 0..r {
                    let d: f64 = f.basis[i].iter().zip(&f.basis[j]).map(|(a, b)| a * b).sum();
                    assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-10);
                }
            }
        }
    }

    #[test]
    fn truncation_loses_exactly_the_dropped_singular_values() {
        // Eckart–Young: ‖X − X̂_k‖_F² = Σ_{i>k} σ_i².
        let motion = low_rank(50, 8, 5);
        let full = fpca(&motion, 15).unwrap();
        for keep in [0, 1, 3, 5] {
            let f = fpca(&motion, keep).unwrap();
            assert_eq!(f.basis.len(), keep);
            let e = f.reconstruction_error(&motion);
            let lost: f64 = full.singular_values[keep..].iter().map(|s| s * s).sum();
            let err2 = e.rms * e.rms * (50 * S_H) as f64;
            assert!(
                (err2 - lost).abs() < 1e-9 * lost.max(1.0),
                "keep {keep}: {err2} vs {lost}"
            );
        }
    }

    #[test]
    fn a_translation_has_the_closed_form_of_its_starts() {
        // Every agent moves by the same d(t): the centred trajectories are the
        // centred starts repeated S_H times, so the singular values are sqrt(S_H)
        // times those of the centred M × 2 start matrix, and the rank is 2.
        let starts = [(-1.0, 0.0), (1.0, 0.0), (0.0, 2.0), (0.0, -2.0), (0.5, 0.5)];
        let trajectories: Vec<[Vec2; S_H]> = starts
            .iter()
            .map(|&(x, y)| {
                let mut t = [Vec2::zeros(); S_H];
                for (s, p) in t.iter_mut().enumerate() {
                    let u = s as f64 / (S_H - 1) as f64;
                    *p = Vec2::new(x + 3.0 * u, y + u * u);
                }
                t
            })
            .collect();
        let motion = CrowdMotion {
            trajectories,
            duration_s: 1.0,
        };
        let f = fpca(&motion, 15).unwrap();
        assert_eq!(f.rank, 2);
        // Centred starts: mean (0.1, 0.1); scatter matrix is diagonal here up to
        // the 0.5 agent, so take its eigenvalues directly.
        let c: Vec<(f64, f64)> = starts.iter().map(|&(x, y)| (x - 0.1, y - 0.1)).collect();
        let (sxx, syy, sxy) = c.iter().fold((0.0, 0.0, 0.0), |a, &(x, y)| {
            (a.0 + x * x, a.1 + y * y, a.2 + x * y)
        });
        let tr = sxx + syy;
        let det = sxx * syy - sxy * sxy;
        let l1 = tr / 2.0 + (tr * tr / 4.0 - det).sqrt();
        let l2 = tr / 2.0 - (tr * tr / 4.0 - det).sqrt();
        let want = [(S_H as f64 * l1).sqrt(), (S_H as f64 * l2).sqrt()];
        for k in 0..2 {
            assert!(
                (f.singular_values[k] - want[k]).abs() < 1e-10,
                "{:?} {:?}",
                f.singular_values,
                want
            );
        }
        // Each eigenvector's x entries are equal along time (a constant offset),
        // and the mean trajectory is the mean path.
        for e in &f.basis {
            for s in 1..S_H {
                assert!((e[2 * s] - e[0]).abs() < 1e-12 && (e[2 * s + 1] - e[1]).abs() < 1e-12);
            }
        }
        assert!((f.mean[2 * (S_H - 1)] - 3.1).abs() < 1e-12);
    }

    #[test]
    fn one_agent_or_identical_agents_keep_no_component() {
        let motion = low_rank(1, 3, 2);
        let f = fpca(&motion, 15).unwrap();
        assert_eq!((f.rank, f.basis.len()), (0, 0));
        assert_eq!(f.reconstruction_error(&motion).rms, 0.0);
        assert!(fpca(
            &CrowdMotion {
                trajectories: vec![],
                duration_s: 1.0
            },
            15
        )
        .is_err());
    }
}
