//! Rejection (issue 28, item 3): a gesture the library does not explain well is not
//! a command. After the vote of section 8.2 the outcome is "none" when
//!
//! - **the fingers barely moved relative to their jitter**: the farthest any finger
//!   got from where it landed is under [`RejectParams::min_travel_to_jitter`] times
//!   the gesture's jitter (estimated from the raw samples, before any resampling),
//!   or under [`RejectParams::min_travel_mm`] — resting fingers, a touch and release;
//! - **the vote is weak**: the winning class holds less than
//!   [`RejectParams::min_vote`] of the neighbours' eq. 18 weight;
//! - **the nearest neighbours are far**: the nearest library gesture is farther than
//!   [`RejectParams::max_nearest`] (in the units of the recogniser's distance).
//!
//! The thresholds are chosen on generated gestures held out from everything else
//! (other seeds than the weights were fitted on, both generators): see
//! docs/gestures.md "Rejection" for the figures and the command.

use super::track::GestureTracks;

/// The rejection thresholds (module doc).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RejectParams {
    /// Smallest winning share of the vote, `[0, 1]`.
    pub min_vote: f64,
    /// Largest distance to the nearest library gesture.
    pub max_nearest: f64,
    /// Smallest ratio of the fingers' travel to their jitter.
    pub min_travel_to_jitter: f64,
    /// Smallest travel of the farthest-moving finger, mm.
    pub min_travel_mm: f64,
}

impl RejectParams {
    /// Nothing is rejected (the paper's recogniser).
    pub const NONE: RejectParams = RejectParams {
        min_vote: 0.0,
        max_nearest: f64::INFINITY,
        min_travel_to_jitter: 0.0,
        min_travel_mm: 0.0,
    };
}

impl Default for RejectParams {
    /// The thresholds chosen on held-out generated gestures (docs/gestures.md).
    fn default() -> RejectParams {
        RejectParams {
            min_vote: 0.5,
            max_nearest: 1.5,
            min_travel_to_jitter: 20.0,
            min_travel_mm: 12.0,
        }
    }
}

/// Why a gesture was rejected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Rejection {
    /// The fingers barely moved.
    #[error("still: the fingers moved {travel_mm:.1} mm, {ratio:.1} times their jitter of {jitter_mm:.2} mm (at least {min_ratio} times and {min_mm} mm needed)")]
    Still {
        /// The farthest any finger got from where it landed, mm.
        travel_mm: f64,
        /// The jitter estimate, mm.
        jitter_mm: f64,
        /// `travel_mm / jitter_mm`.
        ratio: f64,
        /// The threshold on the ratio.
        min_ratio: f64,
        /// The threshold on the travel, mm.
        min_mm: f64,
    },
    /// The vote is weak.
    #[error(
        "weak_vote: {weight:.2} of the neighbours' weight for {class} (at least {min} needed)"
    )]
    WeakVote {
        /// The class that won (its name in the library).
        class: String,
        /// Its share of the vote.
        weight: f64,
        /// The threshold.
        min: f64,
    },
    /// The nearest library gesture is far.
    #[error("far: the nearest library gesture is {distance:.2} away (at most {max} allowed)")]
    Far {
        /// Distance to the nearest library gesture.
        distance: f64,
        /// The threshold.
        max: f64,
    },
}

impl Rejection {
    /// A short code for the reason (`still`, `weak_vote`, `far`).
    pub fn as_str(&self) -> &'static str {
        match self {
            Rejection::Still { .. } => "still",
            Rejection::WeakVote { .. } => "weak_vote",
            Rejection::Far { .. } => "far",
        }
    }
}

/// How far a gesture's fingers moved, and how much they jitter (mm).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Movement {
    /// The farthest any finger got from its first sample.
    pub travel_mm: f64,
    /// The samples' jitter: the median length of the second differences of
    /// consecutive samples over `√6 · √(2 ln 2)` (the median of that length for
    /// independent Gaussian noise of this standard deviation per axis), or 0 with
    /// fewer than three samples per finger.
    pub jitter_mm: f64,
}

/// `√6 · √(2 ln 2)`: the median of `│p₊ − 2p + p₋│` over σ for 2-D Gaussian noise of σ
/// per axis (the second difference has variance 6σ² per axis; its length is Rayleigh).
pub const SECOND_DIFF_MEDIAN_PER_SIGMA: f64 = 2.884_208_2;

/// The smallest jitter a ratio is taken against, mm: a device that reports a still
/// finger on the same point has jitter 0.
pub const JITTER_FLOOR_MM: f64 = 0.15;

impl Movement {
    /// The movement of raw tracks (mm of glass).
    ///
    /// # Complexity
    ///
    /// `O(n log n)` in the samples (a median).
    pub fn of(tracks: &GestureTracks) -> Movement {
        let mut travel = 0.0f64;
        let mut d2: Vec<f64> = Vec::new();
        for f in &tracks.fingers {
            let s = &f.samples;
            if let Some(first) = s.first() {
                for p in s {
                    travel = travel.max((p.mm - first.mm).norm());
                }
            }
            for w in s.windows(3) {
                d2.push((w[2].mm - w[1].mm * 2.0 + w[0].mm).norm());
            }
        }
        let jitter_mm = if d2.is_empty() {
            0.0
        } else {
            let mid = d2.len() / 2;
            let (_, m, _) = d2.select_nth_unstable_by(mid, f64::total_cmp);
            *m / SECOND_DIFF_MEDIAN_PER_SIGMA
        };
        Movement {
            travel_mm: travel,
            jitter_mm,
        }
    }

    /// `travel / max(jitter, JITTER_FLOOR_MM)`.
    pub fn ratio(&self) -> f64 {
        self.travel_mm / self.jitter_mm.max(JITTER_FLOOR_MM)
    }

    /// [`Rejection::Still`] when the fingers barely moved under `p`.
    pub fn check(&self, p: &RejectParams) -> Option<Rejection> {
        let ratio = self.ratio();
        (ratio < p.min_travel_to_jitter || self.travel_mm < p.min_travel_mm).then_some(
            Rejection::Still {
                travel_mm: self.travel_mm,
                jitter_mm: self.jitter_mm,
                ratio,
                min_ratio: p.min_travel_to_jitter,
                min_mm: p.min_travel_mm,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;
    use crate::gesture::track::{TouchTrack, TrackSample};
    use crate::rng::SplitMix64;
    use crate::vocab::Micros;

    fn normal(rng: &mut SplitMix64) -> f64 {
        // Box–Muller.
        let (u, v) = (rng.unit().max(1e-300), rng.unit());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    fn track(rng: &mut SplitMix64, sigma: f64, travel: f64) -> TouchTrack {
        let n = 400;
        TouchTrack {
            samples: (0..n)
                .map(|i| TrackSample {
                    t: Micros(i * 8_000),
                    mm: Vec2::new(travel * i as f64 / (n - 1) as f64, 0.0)
                        + Vec2::new(normal(rng), normal(rng)) * sigma,
                })
                .collect(),
        }
    }

    #[test]
    fn the_jitter_estimate_recovers_gaussian_noise_under_motion() {
        let mut rng = SplitMix64::new(9);
        for sigma in [0.2, 0.5, 1.0] {
            let m = Movement::of(&GestureTracks {
                fingers: vec![track(&mut rng, sigma, 80.0), track(&mut rng, sigma, 60.0)],
            });
            assert!((m.jitter_mm / sigma - 1.0).abs() < 0.1, "{sigma}: {m:?}");
            assert!(m.travel_mm > 78.0);
        }
    }

    #[test]
    fn resting_fingers_are_still_and_a_stroke_is_not() {
        let mut rng = SplitMix64::new(10);
        let p = RejectParams::default();
        let rest = Movement::of(&GestureTracks {
            fingers: vec![track(&mut rng, 0.5, 3.0)],
        });
        let r = rest.check(&p);
        assert!(matches!(r, Some(Rejection::Still { .. })), "{rest:?}");
        assert!(r.is_some_and(|r| r.to_string().starts_with("still: ")));
        let stroke = Movement::of(&GestureTracks {
            fingers: vec![track(&mut rng, 0.5, 100.0)],
        });
        assert_eq!(stroke.check(&p), None, "{stroke:?}");
        // Nothing is still under NONE.
        assert_eq!(rest.check(&RejectParams::NONE), None);
    }
}
