//! Random libraries that pass [`validate`](fn@super::validate): the inputs of the
//! format's property tests, its benchmark and its fuzz seeds. Their numbers satisfy
//! every invariant (orthonormal bases, symmetric positive definite covariances,
//! weights summing to 1) but describe no real gesture or crowd motion.

use super::class::{ClassId, MotionClass};
use super::model::{
    GmmComponent, Library, LibraryGesture, MotionFeatures, Resampled, MAX_COMPONENTS, TRAJ_DIM, T_H,
};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// The shape of a random library.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct RandomLibrarySpec {
    /// Crowd motions; motion `i` has class `i % 10` of the ten [`MotionClass`]
    /// names (the class table), so ten or more cover every class.
    pub motions: usize,
    /// Gestures; gesture `j` names motion `j % motions` (none when there is no motion).
    pub gestures: usize,
    /// Eigenvectors per motion (at most [`MAX_COMPONENTS`]).
    pub components: usize,
    /// Gaussians per motion's mixture (at least 1).
    pub gmm_components: usize,
    /// Most fingers per gesture: each has 1 to this many (1..=10).
    pub max_fingers: usize,
}

/// A random library of the given shape, the same for the same seed.
pub fn random_library(spec: &RandomLibrarySpec, seed: u64) -> Library {
    let mut rng = SplitMix64::new(seed);
    let d = spec.components.min(MAX_COMPONENTS);
    let motions: Vec<MotionFeatures> = (0..spec.motions)
        .map(|i| {
            random_motion(
                &mut rng,
                ClassId((i % 10) as u16),
                d,
                spec.gmm_components.max(1),
            )
        })
        .collect();
    let gestures = if motions.is_empty() {
        Vec::new()
    } else {
        (0..spec.gestures)
            .map(|j| {
                let m = j % motions.len();
                let n = 1 + (rng.next_u64() % spec.max_fingers.clamp(1, 10) as u64) as usize;
                let fingers = (0..n)
                    .map(|_| {
                        let mut f = [Vec2::zeros(); T_H];
                        for p in &mut f {
                            *p = Vec2::new(rng.unit(), rng.unit());
                        }
                        f
                    })
                    .collect();
                LibraryGesture {
                    class: motions[m].class,
                    motion: m as u32,
                    gesture: Resampled { fingers },
                    origin: format!("random seed {seed} gesture {j}"),
                    participant: if j % 3 == 0 {
                        String::new()
                    } else {
                        format!("p{}", j % 4)
                    },
                    device: if j % 2 == 0 {
                        String::new()
                    } else {
                        "random table".to_string()
                    },
                    scale_mm: Some(40.0 + 30.0 * (j % 9) as f64),
                }
            })
            .collect()
    };
    Library {
        classes: MotionClass::all_names(),
        motions,
        gestures,
    }
}

fn random_motion(rng: &mut SplitMix64, class: ClassId, d: usize, k: usize) -> MotionFeatures {
    let mean: Vec<f64> = (0..TRAJ_DIM).map(|_| rng.uniform(-3.0, 3.0)).collect();
    // Gram–Schmidt (twice, for orthonormality to rounding) on random vectors.
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(d);
    while basis.len() < d {
        let mut v: Vec<f64> = (0..TRAJ_DIM).map(|_| rng.uniform(-1.0, 1.0)).collect();
        for _ in 0..2 {
            for e in &basis {
                let dot: f64 = v.iter().zip(e).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(e).for_each(|(a, b)| *a -= dot * b);
            }
        }
        let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        if norm > 1e-3 {
            v.iter_mut().for_each(|a| *a /= norm);
            basis.push(v);
        }
    }
    let raw: Vec<f64> = (0..k).map(|_| rng.uniform(0.1, 1.0)).collect();
    let total: f64 = raw.iter().sum();
    let gmm = raw
        .iter()
        .map(|w| {
            // A Aᵀ + 0.1 I: symmetric positive definite, exactly symmetric as each
            // entry sums the same products in the same order.
            let a: Vec<f64> = (0..d * d).map(|_| rng.uniform(-1.0, 1.0)).collect();
            let mut cov = vec![0.0; d * d];
            for i in 0..d {
                for j in 0..d {
                    let s: f64 = (0..d).map(|t| a[i * d + t] * a[j * d + t]).sum();
                    cov[i * d + j] = s + if i == j { 0.1 } else { 0.0 };
                }
            }
            GmmComponent {
                weight: w / total,
                mean: (0..d).map(|_| rng.uniform(-2.0, 2.0)).collect(),
                cov,
            }
        })
        .collect();
    MotionFeatures {
        class,
        duration_s: rng.uniform(0.5, 20.0),
        mean,
        basis,
        gmm,
    }
}
