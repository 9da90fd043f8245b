//! Motor primitives of the second generator: how a finger gets from one place to
//! another. Point-to-point moves follow the minimum-jerk profile (Flash and Hogan
//! 1985); curved strokes are timed by the two-thirds power law (Lacquaniti, Terzuolo
//! and Viviani 1983: the tangential speed is proportional to the curvature to the
//! power −1/3); hands tremble at 8–12 Hz (physiological tremor) and fingertips drift
//! slowly.

use crate::geom::Vec2;
use crate::rng::SplitMix64;
use std::f64::consts::TAU;

/// The minimum-jerk position profile: `10τ³ − 15τ⁴ + 6τ⁵` for `τ ∈ [0, 1]` (0 before,
/// 1 after); zero velocity and acceleration at both ends.
///
/// ```
/// use crowdtouch::gesture::style2::motor::min_jerk;
/// assert_eq!((min_jerk(0.0), min_jerk(0.5), min_jerk(1.0)), (0.0, 0.5, 1.0));
/// assert!(min_jerk(0.1) < 0.1 && min_jerk(0.9) > 0.9);
/// ```
pub fn min_jerk(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

/// A turn of `v` by `a` rad (+x towards +y).
pub fn rot(v: Vec2, a: f64) -> Vec2 {
    let (s, c) = a.sin_cos();
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// The unit vector at angle `a`.
pub fn unit(a: f64) -> Vec2 {
    Vec2::new(a.cos(), a.sin())
}

/// A standard normal draw (Box–Muller).
pub fn normal(rng: &mut SplitMix64) -> f64 {
    let (u, v) = (rng.unit().max(1e-300), rng.unit());
    (-2.0 * u.ln()).sqrt() * (TAU * v).cos()
}

/// A point-to-point stroke with a sideways bow: `from + d · m(τ) + n · bow · │d│ ·
/// 4 m(τ)(1 − m(τ))`, `m` the minimum-jerk profile over `[start_s, start_s + dur_s]`
/// and `n` the left normal of `d`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Stroke {
    /// Displacement, mm.
    pub d: Vec2,
    /// Sideways bend as a fraction of `│d│` (signed).
    pub bow: f64,
    /// When it starts, s.
    pub start_s: f64,
    /// How long it lasts, s.
    pub dur_s: f64,
}

impl Stroke {
    /// The displacement reached at `t_s`.
    pub fn at(&self, t_s: f64) -> Vec2 {
        let m = min_jerk((t_s - self.start_s) / self.dur_s.max(1e-3));
        let side = Vec2::new(-self.d.y, self.d.x);
        self.d * m + side * (self.bow * 4.0 * m * (1.0 - m))
    }

    /// Its progress at `t_s` (minimum-jerk), `[0, 1]`.
    pub fn progress(&self, t_s: f64) -> f64 {
        min_jerk((t_s - self.start_s) / self.dur_s.max(1e-3))
    }
}

/// A curved path timed by the two-thirds power law: `points` along the path (mm,
/// densely sampled), each given a time so that the speed is `k · κ^(−1/3)` (κ the
/// curvature), softened by a rise and fall over the first and last 15 % of the
/// path, and scaled so that the whole path takes `dur_s`.
///
/// Returns the times (s from the start), one per point.
///
/// # Formula
///
/// Curvature at point `i` from the circle through `p_{i−1}, p_i, p_{i+1}`:
/// `κ = 2 │(b − a) × (c − a)│ / (│b − a│ │c − b│ │c − a│)`; speed
/// `v_i = κ_i^{−1/3} · w(s_i)` with `w` rising as `sin` from 0.25 to 1 over the first
/// 15 % of arc length and falling likewise at the end; `t_{i+1} = t_i + │p_{i+1} − p_i│
/// / v_i`, then all times scaled to end at `dur_s`.
pub fn power_law_times(points: &[Vec2], dur_s: f64) -> Vec<f64> {
    let n = points.len();
    let mut t = vec![0.0; n];
    if n < 2 {
        return t;
    }
    let total: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let mut arc = 0.0;
    for i in 0..n - 1 {
        let step = (points[i + 1] - points[i]).norm();
        let kappa = if i == 0 {
            curvature(points[0], points[1], points[2.min(n - 1)])
        } else {
            curvature(points[i - 1], points[i], points[i + 1])
        };
        // A straight stretch (κ → 0) is fast but not instantaneous.
        let v = kappa.max(1e-4).powf(-1.0 / 3.0);
        let s = if total > 0.0 { arc / total } else { 0.0 };
        let w = 0.25 + 0.75 * ramp(s.min(1.0 - s) / 0.15);
        t[i + 1] = t[i] + step / (v * w);
        arc += step;
    }
    let end = t[n - 1];
    if end > 0.0 {
        for x in &mut t {
            *x *= dur_s / end;
        }
    }
    t
}

/// `sin(π/2 · x)` on `[0, 1]`, 1 beyond.
fn ramp(x: f64) -> f64 {
    (x.clamp(0.0, 1.0) * std::f64::consts::FRAC_PI_2).sin()
}

/// Curvature (1/mm) of the circle through three points; 0 for collinear ones.
fn curvature(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let (ab, bc, ac) = ((b - a).norm(), (c - b).norm(), (c - a).norm());
    let denom = ab * bc * ac;
    if denom <= 1e-12 {
        return 0.0;
    }
    2.0 * crate::geom::cross(b - a, c - a).abs() / denom
}

/// A smooth random wobble: two sinusoids per axis with random phases, at
/// frequencies in `freq_hz`, of amplitude `amp_mm` (physiological tremor at
/// 8–12 Hz; a fingertip's drift at under 1 Hz).
#[derive(Clone, Debug, PartialEq)]
pub struct Wobble {
    terms: [(Vec2, f64, f64); 2],
}

impl Wobble {
    /// A wobble of `amp_mm` at frequencies drawn from `freq_hz`.
    pub fn new(rng: &mut SplitMix64, amp_mm: f64, freq_hz: (f64, f64)) -> Wobble {
        let mut term = || {
            (
                unit(rng.uniform(0.0, TAU)) * amp_mm * rng.uniform(0.4, 0.7),
                rng.uniform(freq_hz.0, freq_hz.1),
                rng.uniform(0.0, TAU),
            )
        };
        Wobble {
            terms: [term(), term()],
        }
    }

    /// The offset at `t_s`, mm.
    pub fn at(&self, t_s: f64) -> Vec2 {
        self.terms
            .iter()
            .map(|(a, f, p)| a * (TAU * f * t_s + p).sin())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stroke_starts_and_ends_at_rest_and_bows_sideways() {
        let s = Stroke {
            d: Vec2::new(100.0, 0.0),
            bow: 0.1,
            start_s: 0.2,
            dur_s: 1.0,
        };
        assert_eq!(s.at(0.0), Vec2::zeros());
        assert!((s.at(1.2) - Vec2::new(100.0, 0.0)).norm() < 1e-9);
        assert!((s.at(0.7) - Vec2::new(50.0, 10.0)).norm() < 1e-9);
        // Slow at the ends: the first 10 % of the time covers under 1 % of the way.
        assert!(s.at(0.3).x < 1.0);
    }

    #[test]
    fn the_power_law_slows_down_where_the_path_bends() {
        // A spiral whose radius grows fivefold: the outer turn is faster.
        let pts: Vec<Vec2> = (0..2000)
            .map(|i| {
                let a = TAU * 2.0 * i as f64 / 1999.0;
                let r = 10.0 * (5.0f64).powf(i as f64 / 1999.0);
                Vec2::new(r * a.cos(), r * a.sin())
            })
            .collect();
        let t = power_law_times(&pts, 2.0);
        assert!((t[1999] - 2.0).abs() < 1e-9);
        assert!(t.windows(2).all(|w| w[1] > w[0]));
        let speed = |i: usize| (pts[i + 1] - pts[i]).norm() / (t[i + 1] - t[i]);
        // Mid-path (no ramp): speed ∝ r^(1/3) on a near-circle.
        let (inner, outer) = (speed(700), speed(1300));
        let want = (10.0 * 5f64.powf(1300.0 / 1999.0)) / (10.0 * 5f64.powf(700.0 / 1999.0));
        assert!(
            (outer / inner - want.powf(1.0 / 3.0)).abs() < 0.05,
            "{}",
            outer / inner
        );
    }

    #[test]
    fn a_wobble_stays_within_its_amplitude() {
        let mut rng = SplitMix64::new(1);
        let w = Wobble::new(&mut rng, 0.5, (8.0, 12.0));
        assert!((0..1000).all(|i| w.at(i as f64 * 1e-3).norm() <= 0.5 * 1.4 + 1e-12));
    }
}
