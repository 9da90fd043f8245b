//! A crowd motion's features `C = [c̄_s, E_V, φ(E_S)]` (gesture-driven eq. 17): its
//! FPCA ([`fpca`]) and a Gaussian mixture over the eigenscores ([`fit`] /
//! [`fit_auto`]); and the checks every consumer of features runs.

use super::crowd_motion::CrowdMotion;
use super::error::MotionError;
use super::fpca::fpca;
use super::gmm::{fit, fit_auto, validate_mixture, GmmParams};
use crate::gesture::library::{ClassId, MotionFeatures, MAX_COMPONENTS, TRAJ_DIM};

/// Parameters of [`features`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct FeatureParams {
    /// Eigenvectors kept (at most [`MAX_COMPONENTS`]; fewer when the motion's rank
    /// is lower). Section 6.2: 15.
    pub components: usize,
    /// Gaussian components of the mixture when not chosen automatically.
    /// Section 6.2: "two Gaussian components are enough to model our database".
    pub gmm_components: usize,
    /// `Some(k_max)`: choose the number of Gaussian components in `1..=k_max` by BIC
    /// ([`fit_auto`]) instead of `gmm_components`.
    pub auto_components: Option<usize>,
    /// Seed of the mixture's initialisation.
    pub seed: u64,
}

impl Default for FeatureParams {
    fn default() -> FeatureParams {
        FeatureParams {
            components: MAX_COMPONENTS,
            gmm_components: 2,
            auto_components: None,
            seed: 0,
        }
    }
}

/// The features of a crowd motion (eq. 17): its mean trajectory and eigenvectors
/// (FPCA, eq. 16) and a Gaussian mixture fitted to its agents' eigenscores with the
/// default [`GmmParams`].
///
/// # Errors
/// [`fpca`]'s and [`fit`]'s.
pub fn features(
    class: ClassId,
    m: &CrowdMotion,
    p: &FeatureParams,
) -> Result<MotionFeatures, MotionError> {
    let f = fpca(m, p.components)?;
    let gp = GmmParams::default();
    let g = match p.auto_components {
        Some(k_max) => fit_auto(&f.scores, k_max, p.seed, &gp)?,
        None => fit(&f.scores, p.gmm_components, p.seed, &gp)?,
    };
    Ok(MotionFeatures {
        class,
        duration_s: m.duration_s,
        mean: f.mean,
        basis: f.basis,
        gmm: g.components,
    })
}

/// Checks features before they are blended or synthesised: a finite positive
/// duration, a finite mean of [`TRAJ_DIM`] values, at most [`MAX_COMPONENTS`]
/// finite basis vectors of [`TRAJ_DIM`] values, and a valid mixture over
/// `basis.len()` dimensions ([`validate_mixture`]). Orthonormality is not required
/// (blending re-orthonormalises).
///
/// # Errors
/// [`MotionError::BadValue`], [`MotionError::Dimension`], [`MotionError::NotFinite`],
/// and [`validate_mixture`]'s.
pub fn validate_features(f: &MotionFeatures) -> Result<(), MotionError> {
    if !(f.duration_s.is_finite() && f.duration_s > 0.0) {
        return Err(MotionError::BadValue {
            what: "duration_s",
            value: f.duration_s,
            why: "finite and > 0",
        });
    }
    if f.mean.len() != TRAJ_DIM {
        return Err(MotionError::Dimension {
            what: "mean trajectory",
            expected: TRAJ_DIM,
            found: f.mean.len(),
        });
    }
    if let Some(j) = f.mean.iter().position(|v| !v.is_finite()) {
        return Err(MotionError::NotFinite {
            what: "mean trajectory",
            index: 0,
            sample: j,
        });
    }
    if f.basis.len() > MAX_COMPONENTS {
        return Err(MotionError::Dimension {
            what: "basis",
            expected: MAX_COMPONENTS,
            found: f.basis.len(),
        });
    }
    for (i, e) in f.basis.iter().enumerate() {
        if e.len() != TRAJ_DIM {
            return Err(MotionError::Dimension {
                what: "basis vector",
                expected: TRAJ_DIM,
                found: e.len(),
            });
        }
        if let Some(j) = e.iter().position(|v| !v.is_finite()) {
            return Err(MotionError::NotFinite {
                what: "basis vector",
                index: i,
                sample: j,
            });
        }
    }
    validate_mixture(&f.gmm, f.basis.len())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::gesture::library::S_H;
    use crate::rng::SplitMix64;

    /// A split: agents on a jittered grid, the left half walking left and the right
    /// half right by `reach` (in start RMS radii), along smooth paths with a little
    /// per-agent wobble; `m` agents.
    pub(crate) fn split_motion(m: usize, reach: f64, seed: u64) -> CrowdMotion {
        let mut rng = SplitMix64::new(seed);
        let side = (m as f64).sqrt().ceil() as usize;
        let tracks: Vec<Vec<Vec2>> = (0..m)
            .map(|i| {
                let start = Vec2::new(
                    (i % side) as f64 + rng.uniform(-0.2, 0.2),
                    (i / side) as f64 + rng.uniform(-0.2, 0.2),
                );
                let dir = if (i % side) * 2 < side { -1.0 } else { 1.0 };
                let (a, ph) = (rng.uniform(0.0, 0.1), rng.uniform(0.0, 6.0));
                (0..100)
                    .map(|s| {
                        let t = s as f64 / 99.0;
                        let ease = t * t * (3.0 - 2.0 * t);
                        start
                            + Vec2::new(dir * reach * side as f64 * 0.3 * ease, 0.0)
                            + Vec2::new(0.0, a * (3.0 * t + ph).sin() * t)
                    })
                    .collect()
            })
            .collect();
        CrowdMotion::from_world(&tracks, 5.0).unwrap()
    }

    #[test]
    fn features_of_a_split_separate_its_two_groups() {
        let m = split_motion(60, 2.0, 3);
        let f = features(
            crate::gesture::library::MotionClass::Split.id(),
            &m,
            &FeatureParams::default(),
        )
        .unwrap();
        validate_features(&f).unwrap();
        assert_eq!(f.basis.len(), fpca(&m, 15).unwrap().rank.min(15));
        assert!(f.basis.len() >= 3);
        assert_eq!(f.gmm.len(), 2);
        // The two components are the two halves: equal weights, means far apart
        // on the leading eigenvector (the split direction).
        assert!(
            (f.gmm[0].weight - 0.5).abs() < 0.05,
            "{:?}",
            f.gmm[0].weight
        );
        let gap = (f.gmm[0].mean[0] - f.gmm[1].mean[0]).abs();
        let sd = f.gmm[0].cov[0].sqrt().max(f.gmm[1].cov[0].sqrt());
        assert!(gap > 5.0 * sd, "gap {gap} sd {sd}");
        assert_eq!(f.mean.len(), TRAJ_DIM);
        // Reconstruction with 15 components is well under 1 % of the motion.
        let e = fpca(&m, 15).unwrap().reconstruction_error(&m);
        assert!(e.relative < 0.01, "{e:?}");
        assert_eq!(S_H * 2, TRAJ_DIM);
        // Chosen by BIC: a clean split needs at least two.
        let p = FeatureParams {
            auto_components: Some(4),
            ..FeatureParams::default()
        };
        let g = features(crate::gesture::library::MotionClass::Split.id(), &m, &p).unwrap();
        assert!(!g.gmm.is_empty());
    }

    #[test]
    fn validate_features_names_what_is_wrong() {
        let m = split_motion(20, 1.0, 1);
        let f = features(
            crate::gesture::library::MotionClass::Split.id(),
            &m,
            &FeatureParams::default(),
        )
        .unwrap();
        let mut bad = f.clone();
        bad.basis[1].pop();
        assert!(matches!(
            validate_features(&bad),
            Err(MotionError::Dimension {
                what: "basis vector",
                ..
            })
        ));
        let mut bad = f.clone();
        bad.mean[7] = f64::INFINITY;
        assert!(matches!(
            validate_features(&bad),
            Err(MotionError::NotFinite { sample: 7, .. })
        ));
        let mut bad = f.clone();
        bad.gmm[0].mean.push(0.0);
        assert!(matches!(
            validate_features(&bad),
            Err(MotionError::Dimension {
                what: "mixture mean",
                ..
            })
        ));
        let mut bad = f;
        bad.duration_s = -1.0;
        assert!(matches!(
            validate_features(&bad),
            Err(MotionError::BadValue { .. })
        ));
    }
}
