//! [`CrowdMotion`]: a crowd motion as M trajectories of `S_H` samples in crowd units
//! (gesture-driven section 6.1, eqs. 13–14), built from raw world tracks by cubic
//! Hermite resampling and normalisation; and the serialisation of a trajectory as
//! one vector (eq. 15).
//!
//! Crowd units: the *whole* motion is translated so that the crowd's starting
//! centroid is at the origin and scaled so that its starting RMS radius about that
//! centroid is 1 (section 6.1: "translating the whole motion such that the starting
//! point is at the origin"; the uniform scale is ours, so that motions of crowds of
//! any size and density blend, and synthesis scales them to the crowd at hand).

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::error::MotionError;
use crate::geom::Vec2;
use crate::gesture::library::{S_H, TRAJ_DIM};

/// A crowd motion: one trajectory of [`S_H`] samples per agent, in crowd units.
///
/// Samples are evenly spaced in time over `duration_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct CrowdMotion {
    /// The agents' trajectories (crowd units).
    pub trajectories: Vec<[Vec2; S_H]>,
    /// Time from the first sample to the last (s).
    pub duration_s: f64,
}

impl CrowdMotion {
    /// A crowd motion from raw world tracks (any units, e.g. metres; one track per
    /// agent, each at least 2 samples, samples evenly spaced in time over
    /// `duration_s`): each track is resampled to [`S_H`] samples by cubic Hermite
    /// interpolation ([`resample_hermite`], eq. 14), then the whole motion is
    /// normalised to crowd units ([`CrowdMotion::normalised`]).
    ///
    /// # Errors
    /// [`MotionError::Empty`] without tracks, [`MotionError::TooShort`] for a track of
    /// fewer than 2 samples, [`MotionError::NotFinite`] for a NaN or infinite
    /// coordinate, [`MotionError::BadValue`] for a duration that is not finite and
    /// positive, [`MotionError::ZeroSpread`] when every track starts at one point.
    pub fn from_world(
        trajs_world: &[Vec<Vec2>],
        duration_s: f64,
    ) -> Result<CrowdMotion, MotionError> {
        if trajs_world.is_empty() {
            return Err(MotionError::Empty("crowd motion"));
        }
        let mut out = Vec::with_capacity(trajs_world.len());
        for (agent, track) in trajs_world.iter().enumerate() {
            if track.len() < 2 {
                return Err(MotionError::TooShort {
                    agent,
                    samples: track.len(),
                });
            }
            if let Some(sample) = track
                .iter()
                .position(|p| !(p.x.is_finite() && p.y.is_finite()))
            {
                return Err(MotionError::NotFinite {
                    what: "trajectory",
                    index: agent,
                    sample,
                });
            }
            let mut r = [Vec2::zeros(); S_H];
            resample_hermite(track, &mut r);
            out.push(r);
        }
        CrowdMotion::normalised(out, duration_s)
    }

    /// Trajectories already at [`S_H`] samples (any units) normalised to crowd units:
    /// every sample translated by minus the starting centroid `c₀ = (1/M) Σ c_m(1)` and
    /// scaled by `1 / r₀`, `r₀ = sqrt((1/M) Σ |c_m(1) − c₀|²)`.
    ///
    /// # Errors
    /// As [`CrowdMotion::from_world`].
    pub fn normalised(
        mut trajectories: Vec<[Vec2; S_H]>,
        duration_s: f64,
    ) -> Result<CrowdMotion, MotionError> {
        check_duration(duration_s)?;
        check_trajectories(&trajectories)?;
        let (c0, r0) = start_centroid_radius(&trajectories);
        let scale = c0.x.abs().max(c0.y.abs()).max(1.0);
        if !(r0 > SPREAD_FLOOR_REL * scale) {
            return Err(MotionError::ZeroSpread { rms_radius: r0 });
        }
        let inv = 1.0 / r0;
        for t in &mut trajectories {
            for p in t.iter_mut() {
                *p = (*p - c0) * inv;
            }
        }
        Ok(CrowdMotion {
            trajectories,
            duration_s,
        })
    }

    /// Checks that the motion has trajectories, finite coordinates and a finite,
    /// positive duration (its normalisation is not checked: the FPCA works on any).
    ///
    /// # Errors
    /// [`MotionError::Empty`], [`MotionError::NotFinite`], [`MotionError::BadValue`].
    pub fn validate(&self) -> Result<(), MotionError> {
        check_duration(self.duration_s)?;
        check_trajectories(&self.trajectories)
    }

    /// Number of agents `M`.
    pub fn len(&self) -> usize {
        self.trajectories.len()
    }

    /// Whether it has no trajectories.
    pub fn is_empty(&self) -> bool {
        self.trajectories.is_empty()
    }
}

/// Smallest starting RMS radius accepted, relative to the larger of 1 and the
/// magnitude of the starting centroid (below it the crowd is one point to rounding).
pub const SPREAD_FLOOR_REL: f64 = 1e-9;

fn check_duration(duration_s: f64) -> Result<(), MotionError> {
    if duration_s.is_finite() && duration_s > 0.0 {
        Ok(())
    } else {
        Err(MotionError::BadValue {
            what: "duration_s",
            value: duration_s,
            why: "finite and > 0",
        })
    }
}

fn check_trajectories(trajectories: &[[Vec2; S_H]]) -> Result<(), MotionError> {
    if trajectories.is_empty() {
        return Err(MotionError::Empty("crowd motion"));
    }
    for (index, t) in trajectories.iter().enumerate() {
        if let Some(sample) = t.iter().position(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(MotionError::NotFinite {
                what: "trajectory",
                index,
                sample,
            });
        }
    }
    Ok(())
}

/// The starting centroid `c₀` and starting RMS radius `r₀` about it.
pub fn start_centroid_radius(trajectories: &[[Vec2; S_H]]) -> (Vec2, f64) {
    let n = trajectories.len().max(1) as f64;
    let c0 = trajectories.iter().fold(Vec2::zeros(), |a, t| a + t[0]) / n;
    let ms = trajectories
        .iter()
        .map(|t| (t[0] - c0).norm_squared())
        .sum::<f64>()
        / n;
    (c0, ms.sqrt())
}

/// Resamples a track of `n >= 2` samples, evenly spaced in time, to `out.len()`
/// samples by cubic Hermite interpolation (gesture-driven section 6.1, eq. 14).
///
/// # Formula
/// Sample `i` sits at parameter `i`; output sample `j` at `u = j (n−1)/(len−1)`. On
/// `[i, i+1]`, with `s = u − i`,
/// `p(s) = h00 p_i + h10 m_i + h01 p_{i+1} + h11 m_{i+1}` (the cubic Hermite basis),
/// tangents `m_i = (p_{i+1} − p_{i−1}) / 2` inside (Catmull–Rom) and one-sided
/// differences at the ends. The first and last samples are kept exactly; a straight
/// track at constant speed is reproduced exactly; `n == out.len()` is the identity.
///
/// # Panics
/// Never; with `n < 2` every output is the one sample (or zero when `track` is empty).
pub fn resample_hermite(track: &[Vec2], out: &mut [Vec2]) {
    let n = track.len();
    let len = out.len();
    if n == 0 {
        out.iter_mut().for_each(|p| *p = Vec2::zeros());
        return;
    }
    if n == 1 || len == 1 {
        out.iter_mut().for_each(|p| *p = track[0]);
        return;
    }
    let tangent = |i: usize| -> Vec2 {
        if i == 0 {
            track[1] - track[0]
        } else if i == n - 1 {
            track[n - 1] - track[n - 2]
        } else {
            (track[i + 1] - track[i - 1]) * 0.5
        }
    };
    let step = (n - 1) as f64 / (len - 1) as f64;
    for (j, o) in out.iter_mut().enumerate() {
        if j == len - 1 {
            *o = track[n - 1];
            continue;
        }
        let u = j as f64 * step;
        let i = (u.floor() as usize).min(n - 2);
        let s = u - i as f64;
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        *o = track[i] * h00 + tangent(i) * h10 + track[i + 1] * h01 + tangent(i + 1) * h11;
    }
}

/// Writes a trajectory as one vector `[x₁, y₁, x₂, y₂, …, x_{S_H}, y_{S_H}]`
/// (gesture-driven eq. 15) into `out` ([`TRAJ_DIM`] long).
pub fn serialise(traj: &[Vec2; S_H], out: &mut [f64]) {
    debug_assert_eq!(out.len(), TRAJ_DIM);
    for (s, p) in traj.iter().enumerate() {
        out[2 * s] = p.x;
        out[2 * s + 1] = p.y;
    }
}

/// The inverse of [`serialise`]: a [`TRAJ_DIM`]-long vector back to a trajectory.
pub fn deserialise(v: &[f64], out: &mut [Vec2; S_H]) {
    debug_assert_eq!(v.len(), TRAJ_DIM);
    for (s, p) in out.iter_mut().enumerate() {
        *p = Vec2::new(v[2 * s], v[2 * s + 1]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize, a: Vec2, b: Vec2) -> Vec<Vec2> {
        (0..n)
            .map(|i| a + (b - a) * (i as f64 / (n - 1) as f64))
            .collect()
    }

    #[test]
    fn hermite_keeps_ends_reproduces_lines_and_is_the_identity_at_s_h() {
        let a = Vec2::new(1.0, -2.0);
        let b = Vec2::new(4.0, 3.0);
        for n in [2, 3, 7, 64, 300] {
            let mut out = [Vec2::zeros(); S_H];
            resample_hermite(&line(n, a, b), &mut out);
            for (j, p) in out.iter().enumerate() {
                let want = a + (b - a) * (j as f64 / (S_H - 1) as f64);
                assert!((p - want).norm() < 1e-12, "n {n} j {j}: {p:?} vs {want:?}");
            }
        }
        let curve: Vec<Vec2> = (0..S_H)
            .map(|i| Vec2::new((i as f64).sin(), (i * i) as f64))
            .collect();
        let mut out = [Vec2::zeros(); S_H];
        resample_hermite(&curve, &mut out);
        for (p, q) in out.iter().zip(&curve) {
            assert!((p - q).norm() < 1e-9);
        }
    }

    #[test]
    fn hermite_reproduces_a_quadratic_inside_and_stays_close_near_the_ends() {
        // Catmull-Rom tangents are exact for a quadratic at interior samples.
        let f = |t: f64| Vec2::new(t, 0.5 * t * t);
        let n = 20;
        let track: Vec<Vec2> = (0..n).map(|i| f(i as f64)).collect();
        let mut out = [Vec2::zeros(); S_H];
        resample_hermite(&track, &mut out);
        for (j, p) in out.iter().enumerate() {
            let u = j as f64 * (n - 1) as f64 / (S_H - 1) as f64;
            let err = (p - f(u)).norm();
            if (1.0..=(n - 2) as f64).contains(&u) {
                assert!(err < 1e-9, "j {j}: {err}");
            } else {
                assert!(err < 0.2, "j {j}: {err}");
            }
        }
    }

    #[test]
    fn from_world_normalises_the_whole_motion_by_its_start() {
        // Three agents translating by (10, 0): starts at (2,2),(4,2),(3,5).
        let starts = [
            Vec2::new(2.0, 2.0),
            Vec2::new(4.0, 2.0),
            Vec2::new(3.0, 5.0),
        ];
        let d = Vec2::new(10.0, 0.0);
        let tracks: Vec<Vec<Vec2>> = starts.iter().map(|&s| line(5, s, s + d)).collect();
        let m = CrowdMotion::from_world(&tracks, 4.0).unwrap();
        let (c0, r0) = start_centroid_radius(&m.trajectories);
        assert!(c0.norm() < 1e-12 && (r0 - 1.0).abs() < 1e-12);
        // The whole motion moves: the end centroid is d / r0_world from the origin.
        let c_world = Vec2::new(3.0, 3.0);
        let r_world = (starts
            .iter()
            .map(|s| (s - c_world).norm_squared())
            .sum::<f64>()
            / 3.0)
            .sqrt();
        let end = m
            .trajectories
            .iter()
            .fold(Vec2::zeros(), |a, t| a + t[S_H - 1])
            / 3.0;
        assert!((end - d / r_world).norm() < 1e-12, "{end:?}");
        assert_eq!(m.duration_s, 4.0);
    }

    #[test]
    fn from_world_rejects_bad_input() {
        let ok = line(4, Vec2::zeros(), Vec2::new(1.0, 0.0));
        let other = line(4, Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0));
        assert_eq!(
            CrowdMotion::from_world(&[], 1.0),
            Err(MotionError::Empty("crowd motion"))
        );
        assert_eq!(
            CrowdMotion::from_world(&[ok.clone(), vec![Vec2::zeros()]], 1.0),
            Err(MotionError::TooShort {
                agent: 1,
                samples: 1
            })
        );
        let mut bad = other.clone();
        bad[2].y = f64::NAN;
        assert_eq!(
            CrowdMotion::from_world(&[ok.clone(), bad], 1.0),
            Err(MotionError::NotFinite {
                what: "trajectory",
                index: 1,
                sample: 2
            })
        );
        assert!(matches!(
            CrowdMotion::from_world(&[ok.clone(), ok.clone()], 1.0),
            Err(MotionError::ZeroSpread { .. })
        ));
        assert!(matches!(
            CrowdMotion::from_world(&[ok.clone(), other.clone()], f64::NAN),
            Err(MotionError::BadValue {
                what: "duration_s",
                ..
            })
        ));
        assert!(matches!(
            CrowdMotion::from_world(&[ok, other], 0.0),
            Err(MotionError::BadValue { .. })
        ));
    }

    #[test]
    fn serialise_round_trips_in_the_order_of_eq_15() {
        let mut t = [Vec2::zeros(); S_H];
        for (s, p) in t.iter_mut().enumerate() {
            *p = Vec2::new(s as f64, -(s as f64));
        }
        let mut v = vec![0.0; TRAJ_DIM];
        serialise(&t, &mut v);
        assert_eq!(&v[..4], &[0.0, -0.0, 1.0, -1.0]);
        let mut back = [Vec2::zeros(); S_H];
        deserialise(&v, &mut back);
        assert_eq!(back, t);
    }
}
