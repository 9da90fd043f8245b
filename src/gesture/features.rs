//! The four gesture features of gesture-driven section 5.2, computed per time step of
//! a resampled gesture: centroid (eqs. 4–5), spread (eqs. 6–7), cumulative rotation
//! (eqs. 8–9) and the sides of the minimum oriented bounding box (eq. 10). Together
//! they are the gesture's point in the gesture space (eq. 11), independent of the
//! number of fingers.
//!
//! # One finger
//!
//! The centroid is the finger's path; the spread is 0; the box is 0 × 0. Eq. 9's
//! rotation about the centroid is 0 for one finger (it does not turn about itself),
//! which would leave a one-finger circle told apart from a line only by its
//! centroid path, under the smallest weight of eq. 12 (α = 0.04). The project's
//! convention draws a twist with one finger as a circle or spiral arc, so for one
//! finger the rotation is the cumulative turning of its *path*: eq. 9 applied to
//! consecutive displacements `d(t) = g(t) − g(t−1)` instead of to positions about
//! the centroid (steps shorter than [`ROTATION_MIN_STEP`] turn nothing). A finger
//! circling a centre turns its heading exactly as fast as its position turns about
//! the centre, so the sign and size agree with eq. 9's for several fingers turning
//! together; a straight or gently bowed stroke turns little.

use super::library::{Resampled, T_H};
use super::mobb::Mobb;
use crate::geom::{cross, Vec2};

/// A finger closer to the centroid than this (normalised units) at either of two
/// consecutive steps contributes no rotation at that step (its angle is undefined).
pub const ROTATION_MIN_RADIUS: f64 = 1e-9;

/// A one-finger step shorter than this (normalised units) turns nothing: a finger
/// at rest has no heading.
pub const ROTATION_MIN_STEP: f64 = 1e-4;

/// A gesture's features (gesture-driven eq. 11), one value per resampled time step.
#[derive(Clone, Debug, PartialEq)]
pub struct GestureFeatures {
    /// `C(G)`: the mean finger position (eqs. 4–5), normalised units.
    pub centroid: [Vec2; T_H],
    /// `S(G)`: the mean distance of the fingers to the centroid (eqs. 6–7).
    pub spread: [f64; T_H],
    /// `R(G)`: the cumulative mean rotation of the fingers about the centroid
    /// (eqs. 8–9), radians, positive anticlockwise as seen on the glass (x right,
    /// y down); `rotation[0] = 0`.
    pub rotation: [f64; T_H],
    /// `B(G)`: the minimum oriented bounding box of the fingers, `(width, height)`
    /// with width the shorter side (eq. 10).
    pub mobb: [Vec2; T_H],
}

impl GestureFeatures {
    /// The features of a resampled gesture.
    ///
    /// # Formula
    ///
    /// With `u_n(t) = g_n(t) − c(t)`: `c(t) = Σ g_n(t) / N`, `s(t) = Σ |u_n(t)| / N`,
    /// `r(t) = Σ atan2(u_n(t) × u_n(t−1), u_n(t) · u_n(t−1)) / N` (eq. 9 with the
    /// quadrant-correct, division-free `atan2`; a term is 0 when either vector is
    /// shorter than [`ROTATION_MIN_RADIUS`]), `R(t) = Σ_{τ ≤ t} r(τ)`, `r(0) = 0`.
    ///
    /// # Complexity
    ///
    /// `O(T_H · N log N)` (the hull at each step).
    ///
    /// A gesture with no finger has all features 0.
    ///
    /// ```
    /// use crowdtouch::geom::Vec2;
    /// use crowdtouch::gesture::features::GestureFeatures;
    /// use crowdtouch::gesture::library::{Resampled, T_H};
    /// // Two fingers opposite each other turning a quarter turn about (0.5, 0.5).
    /// let at = |k: usize, phase: f64| {
    ///     let a = phase + std::f64::consts::FRAC_PI_2 * k as f64 / (T_H - 1) as f64;
    ///     Vec2::new(0.5 + 0.5 * a.cos(), 0.5 - 0.5 * a.sin())
    /// };
    /// let g = Resampled { fingers: vec![
    ///     std::array::from_fn(|k| at(k, 0.0)), std::array::from_fn(|k| at(k, std::f64::consts::PI))] };
    /// let f = GestureFeatures::of(&g);
    /// assert!((f.rotation[T_H - 1] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    /// assert!((f.spread[10] - 0.5).abs() < 1e-12);
    /// assert!((f.mobb[10] - Vec2::new(0.0, 1.0)).norm() < 1e-12);
    /// ```
    pub fn of(g: &Resampled) -> GestureFeatures {
        let n = g.fingers.len();
        let mut f = GestureFeatures {
            centroid: [Vec2::zeros(); T_H],
            spread: [0.0; T_H],
            rotation: [0.0; T_H],
            mobb: [Vec2::zeros(); T_H],
        };
        if n == 0 {
            return f;
        }
        let inv_n = 1.0 / n as f64;
        let mut mobb = Mobb::new();
        let mut points: Vec<Vec2> = Vec::with_capacity(n);
        for t in 0..T_H {
            let c = g.fingers.iter().map(|p| p[t]).sum::<Vec2>() * inv_n;
            f.centroid[t] = c;
            f.spread[t] = g.fingers.iter().map(|p| (p[t] - c).norm()).sum::<f64>() * inv_n;
            if n == 1 && t > 1 {
                // One finger: its path's turning (module doc).
                let p = &g.fingers[0];
                let (u, w) = (p[t] - p[t - 1], p[t - 1] - p[t - 2]);
                let r = if u.norm() < ROTATION_MIN_STEP || w.norm() < ROTATION_MIN_STEP {
                    0.0
                } else {
                    cross(u, w).atan2(u.dot(&w))
                };
                f.rotation[t] = f.rotation[t - 1] + r;
            } else if n > 1 && t > 0 {
                let prev_c = f.centroid[t - 1];
                let r: f64 = g
                    .fingers
                    .iter()
                    .map(|p| {
                        let (u, w) = (p[t] - c, p[t - 1] - prev_c);
                        if u.norm() < ROTATION_MIN_RADIUS || w.norm() < ROTATION_MIN_RADIUS {
                            0.0
                        } else {
                            cross(u, w).atan2(u.dot(&w))
                        }
                    })
                    .sum();
                f.rotation[t] = f.rotation[t - 1] + r * inv_n;
            }
            points.clear();
            points.extend(g.fingers.iter().map(|p| p[t]));
            f.mobb[t] = mobb.sides(&points);
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{PI, TAU};

    fn finger(f: impl Fn(f64) -> Vec2) -> [Vec2; T_H] {
        std::array::from_fn(|k| f(k as f64 / (T_H - 1) as f64))
    }

    #[test]
    fn one_finger_has_its_path_as_centroid_and_its_turning_as_rotation() {
        let line = Resampled {
            fingers: vec![finger(|s| Vec2::new(s, 0.3 + 0.2 * s))],
        };
        let f = GestureFeatures::of(&line);
        for t in 0..T_H {
            assert_eq!(f.centroid[t], line.fingers[0][t]);
            assert_eq!(f.spread[t], 0.0);
            assert!(
                f.rotation[t].abs() < 1e-9,
                "a straight stroke turns nothing"
            );
            assert_eq!(f.mobb[t], Vec2::zeros());
        }
        // Three quarters of a circle, anticlockwise on the glass (y down), as the
        // several-finger rotation counts it: +3π/2 within the sampling's error.
        let arc = Resampled {
            fingers: vec![finger(|s| {
                let a = 1.5 * PI * s;
                Vec2::new(0.5 + 0.5 * a.cos(), 0.5 - 0.5 * a.sin())
            })],
        };
        let three = Resampled {
            fingers: (0..3)
                .map(|k| {
                    finger(move |s| {
                        let a = 1.5 * PI * s + TAU * k as f64 / 3.0;
                        Vec2::new(0.5 + 0.5 * a.cos(), 0.5 - 0.5 * a.sin())
                    })
                })
                .collect(),
        };
        let (r1, r3) = (
            GestureFeatures::of(&arc).rotation[T_H - 1],
            GestureFeatures::of(&three).rotation[T_H - 1],
        );
        let step = 1.5 * PI / (T_H - 1) as f64;
        assert!((r3 - 1.5 * PI).abs() < 1e-9, "{r3}");
        // The path's turning misses the first step (no heading before it).
        assert!((r1 - (1.5 * PI - step)).abs() < 1e-9, "{r1}");
    }

    #[test]
    fn rotation_is_cumulative_and_signed_beyond_half_a_turn() {
        // Three fingers on a circle turning 1.5 turns clockwise in x-right/y-up terms,
        // which is anticlockwise as seen on glass with y down: positive.
        let turn = |phase: f64| {
            finger(move |s| {
                let a = phase + 1.5 * TAU * s;
                Vec2::new(0.5 + 0.4 * a.cos(), 0.5 - 0.4 * a.sin())
            })
        };
        let g = Resampled {
            fingers: vec![turn(0.0), turn(TAU / 3.0), turn(2.0 * TAU / 3.0)],
        };
        let f = GestureFeatures::of(&g);
        assert!(
            (f.rotation[T_H - 1] - 3.0 * PI).abs() < 1e-9,
            "{}",
            f.rotation[T_H - 1]
        );
        for t in 1..T_H {
            assert!(f.rotation[t] > f.rotation[t - 1]);
        }
        // Mirrored: the opposite sign.
        let mirrored = Resampled {
            fingers: g
                .fingers
                .iter()
                .map(|p| std::array::from_fn(|k| Vec2::new(p[k].x, 1.0 - p[k].y)))
                .collect(),
        };
        let m = GestureFeatures::of(&mirrored);
        assert!((m.rotation[T_H - 1] + 3.0 * PI).abs() < 1e-9);
    }

    #[test]
    fn spread_and_box_of_a_pinch() {
        // Two fingers on a horizontal line closing from 1.0 apart to 0.2 apart.
        let left = finger(|s| Vec2::new(0.4 * s, 0.5));
        let right = finger(|s| Vec2::new(1.0 - 0.4 * s, 0.5));
        let f = GestureFeatures::of(&Resampled {
            fingers: vec![left, right],
        });
        for t in 0..T_H {
            let gap = 1.0 - 0.8 * t as f64 / (T_H - 1) as f64;
            assert!((f.spread[t] - gap / 2.0).abs() < 1e-12);
            assert!((f.mobb[t] - Vec2::new(0.0, gap)).norm() < 1e-12);
            assert!((f.centroid[t] - Vec2::new(0.5, 0.5)).norm() < 1e-12);
            assert!(f.rotation[t].abs() < 1e-12);
        }
    }

    #[test]
    fn a_finger_on_the_centroid_adds_no_rotation_but_counts_in_the_mean() {
        let turn = |phase: f64| {
            finger(move |s| {
                let a = phase + PI * s;
                Vec2::new(0.5 + 0.5 * a.cos(), 0.5 - 0.5 * a.sin())
            })
        };
        let centre = finger(|_| Vec2::new(0.5, 0.5));
        let f = GestureFeatures::of(&Resampled {
            fingers: vec![turn(0.0), turn(PI), centre],
        });
        assert!((f.rotation[T_H - 1] - PI * 2.0 / 3.0).abs() < 1e-9);
        assert!(f.rotation.iter().all(|r| r.is_finite()));
    }
}
