//! From a captured gesture to the input of the features: validate, resample every
//! finger to [`T_H`] samples with a cubic Hermite spline on the gesture's common time
//! axis, and normalise (gesture-driven section 5.1, eqs. 1–3).
//!
//! # Choices
//!
//! - **One time axis for all fingers.** The `T_H` samples are taken at the same
//!   instants for every finger, evenly spaced from the first landing to the last
//!   sample. The features compare fingers *at the same time step* (the centroid of
//!   eq. 5, the spread of eq. 7, the rotation of eq. 9), so fingers must stay in sync.
//! - **Early lifts and late landings hold.** A finger that lifts before the end keeps
//!   its last position; a finger that lands late sits on its first position before it
//!   landed. This keeps the finger count `N` constant over the gesture, so `C`, `S`
//!   and `R` have no jump at the instant a finger comes or goes, and the held point is
//!   where the user left the finger (dropping it instead would move the centroid by
//!   the finger's offset at that instant).
//! - **Brief fingers are dropped.** A finger present for less than
//!   [`MIN_PRESENCE_FRACTION`] of the gesture (a bounce, a graze of the palm) is left
//!   out, unless every finger is that brief (then all are kept).
//! - **Normalisation after resampling.** Eq. 2 (translate the minimum x, y to 0, scale
//!   by `1 / max(d_v, d_h)`) is applied to the resampled points, so every resampled
//!   point is in `[0, 1]²` even where the spline overshoots between raw samples.
//!   Coordinates are millimetres of glass before the scaling, so devices of different
//!   size and resolution compare.
//! - Samples out of time order are sorted; samples of one finger with the same time
//!   are merged into their mean position.

use super::error::GestureError;
use super::library::{Resampled, T_H};
use super::track::{GestureTracks, TrackSample, MAX_GESTURE_FINGERS};
use crate::geom::Vec2;

/// A finger present for less than this fraction of the gesture's duration is dropped
/// (a bounce or a graze), unless that would drop every finger.
pub const MIN_PRESENCE_FRACTION: f64 = 0.1;

/// A gesture whose resampled bounding box has no side longer than this (mm) has no
/// extent to normalise by.
pub const MIN_EXTENT_MM: f64 = 1e-6;

/// Validates, resamples and normalises a gesture (gesture-driven eqs. 1–3).
///
/// # Formula
///
/// Each finger's samples `(t_i, p_i)` are interpolated by the cubic Hermite spline
/// with Catmull–Rom tangents `m_i = (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1})`
/// (one-sided at the ends) and evaluated at `τ_k = t_0 + k (t_end − t_0) / (T_H − 1)`,
/// `k = 0 … T_H − 1`, where `t_0` is the first landing and `t_end` the last sample of
/// the gesture. Before its first sample a finger holds its first position, after its
/// last its last. Then eq. 2: `g ← λ (g − min)`, `λ = 1 / max(d_v, d_h)`.
///
/// # Units
///
/// Input in millimetres of glass and microseconds; output dimensionless in `[0, 1]²`.
///
/// # Complexity
///
/// `O(n)` in the number of samples when each finger's times are sorted (as captured),
/// `O(n log n)` otherwise.
///
/// # Errors
///
/// [`GestureError`]: no finger with a sample, more than [`MAX_GESTURE_FINGERS`]
/// fingers, a NaN or infinite coordinate (naming the finger and sample), a single
/// sample, all samples at one instant, or all samples on one point.
///
/// ```
/// use crowdtouch::geom::Vec2;
/// use crowdtouch::gesture::resample::prepare;
/// use crowdtouch::gesture::track::{GestureTracks, TouchTrack, TrackSample};
/// use crowdtouch::vocab::Micros;
/// let line = TouchTrack { samples: (0..5).map(|i| TrackSample {
///     t: Micros(i * 10_000), mm: Vec2::new(10.0 + 20.0 * i as f64, 50.0) }).collect() };
/// let r = prepare(&GestureTracks { fingers: vec![line] }).unwrap();
/// assert_eq!(r.fingers.len(), 1);
/// assert!((r.fingers[0][0].x - 0.0).abs() < 1e-12 && (r.fingers[0][63].x - 1.0).abs() < 1e-12);
/// assert!((r.fingers[0][21].x - 21.0 / 63.0).abs() < 1e-12); // a line at constant speed stays one
/// ```
pub fn prepare(tracks: &GestureTracks) -> Result<Resampled, GestureError> {
    prepare_scaled(tracks).map(|(r, _)| r)
}

/// [`prepare`], with eq. 2's scale: the larger side of the resampled gesture's
/// bounding box on the glass (mm), which `physical` features need.
///
/// # Errors
/// As [`prepare`].
pub fn prepare_scaled(tracks: &GestureTracks) -> Result<(Resampled, f64), GestureError> {
    let present: Vec<usize> = (0..tracks.fingers.len())
        .filter(|&f| !tracks.fingers[f].samples.is_empty())
        .collect();
    if present.is_empty() {
        return Err(GestureError::NoFingers);
    }
    if present.len() > MAX_GESTURE_FINGERS {
        return Err(GestureError::TooManyFingers {
            count: present.len(),
        });
    }
    let mut samples = 0usize;
    for &f in &present {
        for (i, s) in tracks.fingers[f].samples.iter().enumerate() {
            if !(s.mm.x.is_finite() && s.mm.y.is_finite()) {
                return Err(GestureError::NonFinite {
                    finger: f,
                    sample: i,
                    x: s.mm.x,
                    y: s.mm.y,
                });
            }
        }
        samples += tracks.fingers[f].samples.len();
    }
    if samples == 1 {
        return Err(GestureError::SingleSample);
    }
    // The span over every sample (the tracks may be out of time order).
    let times = || {
        present
            .iter()
            .flat_map(|&f| tracks.fingers[f].samples.iter().map(|s| s.t))
    };
    let (t0, t_end) = (
        times().min().ok_or(GestureError::NoFingers)?,
        times().max().ok_or(GestureError::NoFingers)?,
    );
    if t_end == t0 {
        return Err(GestureError::NoDuration {
            samples,
            t_us: t0.0,
        });
    }
    let duration = (t_end.0 - t0.0) as f64;

    // Knots per finger, times in µs since t0, sorted, duplicates merged.
    let mut knots: Vec<Vec<(f64, Vec2)>> = present
        .iter()
        .map(|&f| knots_of(&tracks.fingers[f].samples, t0.0))
        .collect();
    let presence =
        |k: &Vec<(f64, Vec2)>| k.last().map_or(0.0, |l| l.0) - k.first().map_or(0.0, |f| f.0);
    if knots
        .iter()
        .any(|k| presence(k) >= MIN_PRESENCE_FRACTION * duration)
    {
        knots.retain(|k| presence(k) >= MIN_PRESENCE_FRACTION * duration);
    }

    let mut fingers: Vec<[Vec2; T_H]> =
        knots.iter().map(|k| resample_finger(k, duration)).collect();
    let scale_mm = normalise(&mut fingers)?;
    Ok((Resampled { fingers }, scale_mm))
}

/// One finger's samples as spline knots: `(µs since t0, position mm)`, sorted by
/// time, samples with equal times merged into their mean.
fn knots_of(samples: &[TrackSample], t0: u64) -> Vec<(f64, Vec2)> {
    let mut sorted: Vec<TrackSample>;
    let samples = if samples.windows(2).all(|w| w[0].t <= w[1].t) {
        samples
    } else {
        sorted = samples.to_vec();
        sorted.sort_by_key(|s| s.t);
        &sorted
    };
    let mut knots: Vec<(f64, Vec2)> = Vec::with_capacity(samples.len());
    let mut i = 0;
    while i < samples.len() {
        let t = samples[i].t;
        let mut sum = Vec2::zeros();
        let mut n = 0.0;
        while i < samples.len() && samples[i].t == t {
            sum += samples[i].mm;
            n += 1.0;
            i += 1;
        }
        knots.push(((t.0 - t0) as f64, sum / n));
    }
    knots
}

/// Catmull–Rom tangent at knot `i` (mm/µs): central difference over the neighbours,
/// one-sided at the ends, zero for a single knot.
fn tangent(k: &[(f64, Vec2)], i: usize) -> Vec2 {
    let lo = i.saturating_sub(1);
    let hi = (i + 1).min(k.len() - 1);
    if hi == lo {
        return Vec2::zeros();
    }
    (k[hi].1 - k[lo].1) / (k[hi].0 - k[lo].0)
}

/// The finger's spline evaluated at the `T_H` instants of the common axis
/// `[0, duration]` (µs), holding the first/last position outside its own span.
/// One pass over the knots: `O(knots + T_H)`.
fn resample_finger(k: &[(f64, Vec2)], duration: f64) -> [Vec2; T_H] {
    let mut out = [Vec2::zeros(); T_H];
    let mut seg = 0usize;
    for (j, o) in out.iter_mut().enumerate() {
        let tau = duration * j as f64 / (T_H - 1) as f64;
        if tau <= k[0].0 {
            *o = k[0].1;
            continue;
        }
        if tau >= k[k.len() - 1].0 {
            *o = k[k.len() - 1].1;
            continue;
        }
        while k[seg + 1].0 < tau {
            seg += 1;
        }
        *o = hermite(k, seg, tau);
    }
    out
}

/// The cubic Hermite segment between knots `i` and `i + 1` at time `tau`.
fn hermite(k: &[(f64, Vec2)], i: usize, tau: f64) -> Vec2 {
    let (t_a, p_a) = k[i];
    let (t_b, p_b) = k[i + 1];
    let h = t_b - t_a;
    let s = (tau - t_a) / h;
    let (s2, s3) = (s * s, s * s * s);
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    p_a * h00 + tangent(k, i) * (h10 * h) + p_b * h01 + tangent(k, i + 1) * (h11 * h)
}

/// Eq. 2 on the resampled points: translate the minimum x, y to 0 and scale by
/// `1 / max(d_v, d_h)`; returns `max(d_v, d_h)` (mm).
fn normalise(fingers: &mut [[Vec2; T_H]]) -> Result<f64, GestureError> {
    let mut lo = Vec2::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in fingers.iter().flatten() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let extent_mm = (hi.x - lo.x).max(hi.y - lo.y);
    if extent_mm.is_nan() || extent_mm <= MIN_EXTENT_MM {
        return Err(GestureError::NoExtent { extent_mm });
    }
    let lambda = 1.0 / extent_mm;
    for p in fingers.iter_mut().flatten() {
        *p = ((*p - lo) * lambda).map(|c| c.clamp(0.0, 1.0));
    }
    Ok(extent_mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gesture::track::TouchTrack;
    use crate::vocab::Micros;

    fn track(points: &[(u64, f64, f64)]) -> TouchTrack {
        TouchTrack {
            samples: points
                .iter()
                .map(|&(t, x, y)| TrackSample {
                    t: Micros(t),
                    mm: Vec2::new(x, y),
                })
                .collect(),
        }
    }

    fn gesture(fingers: Vec<TouchTrack>) -> GestureTracks {
        GestureTracks { fingers }
    }

    #[test]
    fn errors_name_what_is_wrong() {
        assert_eq!(prepare(&gesture(vec![])), Err(GestureError::NoFingers));
        assert_eq!(
            prepare(&gesture(vec![TouchTrack::default()])),
            Err(GestureError::NoFingers)
        );
        let e = prepare(&gesture(vec![track(&[(0, 1.0, 1.0), (10, f64::NAN, 2.0)])])).unwrap_err();
        assert_eq!(
            e.to_string(),
            "finger 0 sample 1 has a non-finite coordinate (NaN, 2) mm"
        );
        let e = prepare(&gesture(vec![
            track(&[(0, 1.0, 1.0)]),
            track(&[(0, f64::INFINITY, 1.0)]),
        ]));
        assert!(matches!(
            e,
            Err(GestureError::NonFinite {
                finger: 1,
                sample: 0,
                ..
            })
        ));
        assert_eq!(
            prepare(&gesture(vec![track(&[(5, 1.0, 1.0)])])),
            Err(GestureError::SingleSample)
        );
        let e = prepare(&gesture(vec![
            track(&[(5, 1.0, 1.0)]),
            track(&[(5, 3.0, 1.0)]),
        ]))
        .unwrap_err();
        assert_eq!(
            e,
            GestureError::NoDuration {
                samples: 2,
                t_us: 5
            }
        );
        let still = gesture(vec![
            track(&[(0, 7.0, 7.0), (50, 7.0, 7.0)]),
            track(&[(10, 7.0, 7.0), (90, 7.0, 7.0)]),
        ]);
        let e = prepare(&still).unwrap_err();
        assert!(e.to_string().starts_with("gesture has no extent"), "{e}");
        let many = gesture(
            (0..11)
                .map(|i| track(&[(0, i as f64, 0.0), (9, i as f64, 5.0)]))
                .collect(),
        );
        assert_eq!(
            prepare(&many),
            Err(GestureError::TooManyFingers { count: 11 })
        );
        let ten = gesture(
            (0..10)
                .map(|i| track(&[(0, i as f64, 0.0), (9, i as f64, 5.0)]))
                .collect(),
        );
        assert_eq!(prepare(&ten).unwrap().fingers.len(), 10);
    }

    #[test]
    fn normalised_into_the_unit_square_with_the_larger_side_one() {
        // A finger moving 40 mm right and 10 mm down, far from the origin.
        let g = gesture(vec![track(&[
            (0, 100.0, 200.0),
            (1000, 120.0, 205.0),
            (2000, 140.0, 210.0),
        ])]);
        let r = prepare(&g).unwrap();
        let f = &r.fingers[0];
        assert!((f[0] - Vec2::new(0.0, 0.0)).norm() < 1e-12);
        assert!((f[T_H - 1] - Vec2::new(1.0, 0.25)).norm() < 1e-12);
        for p in f {
            assert!((0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y));
        }
    }

    #[test]
    fn hermite_reproduces_a_cubic_in_the_interior_and_passes_through_knots() {
        // Catmull–Rom tangents are exact for quadratics on a uniform grid: x(t) = t².
        let pts: Vec<(u64, f64, f64)> = (0..=20).map(|i| (i * 100, (i * i) as f64, 0.0)).collect();
        let k = knots_of(&track(&pts).samples, 0);
        for i in 1..18 {
            for s in [0.0, 0.25, 0.5, 0.9] {
                let t = (i as f64 + s) * 100.0;
                let x = hermite(&k, i, t).x;
                assert!((x - (t / 100.0).powi(2)).abs() < 1e-9, "t={t} x={x}");
            }
        }
    }

    #[test]
    fn fingers_share_the_time_axis_and_hold_outside_their_span() {
        // Finger 0: the whole gesture, 0..1000 µs, x from 0 to 100 mm at constant speed.
        // Finger 1: lands at 500 µs at (50, 50) and stays still.
        let f0: Vec<(u64, f64, f64)> = (0..=10).map(|i| (i * 100, i as f64 * 10.0, 0.0)).collect();
        let g = gesture(vec![
            track(&f0),
            track(&[(500, 50.0, 50.0), (1000, 50.0, 50.0)]),
        ]);
        let r = prepare(&g).unwrap();
        assert_eq!(r.fingers.len(), 2);
        for j in 0..T_H {
            let x0 = r.fingers[0][j].x;
            assert!(
                (x0 - j as f64 / (T_H - 1) as f64).abs() < 1e-12,
                "sample {j}: {x0}"
            );
            assert!((r.fingers[1][j] - Vec2::new(0.5, 0.5)).norm() < 1e-12);
        }
    }

    #[test]
    fn early_lift_holds_the_last_position() {
        let f0: Vec<(u64, f64, f64)> = (0..=10).map(|i| (i * 100, 0.0, i as f64 * 10.0)).collect();
        let f1 = [(0, 20.0, 0.0), (200, 30.0, 0.0), (400, 40.0, 0.0)];
        let r = prepare(&gesture(vec![track(&f0), track(&f1)])).unwrap();
        let last = r.fingers[1][T_H - 1];
        assert!((last - Vec2::new(0.4, 0.0)).norm() < 1e-12, "{last}");
        let mid = r.fingers[1][T_H / 2];
        assert_eq!(mid, last);
    }

    #[test]
    fn brief_fingers_are_dropped_unless_all_are_brief() {
        let f0: Vec<(u64, f64, f64)> = (0..=10).map(|i| (i * 1000, i as f64, 0.0)).collect();
        let bounce = [(3000, 50.0, 50.0), (3500, 51.0, 50.0)];
        let r = prepare(&gesture(vec![track(&bounce), track(&f0)])).unwrap();
        assert_eq!(r.fingers.len(), 1);
        assert!((r.fingers[0][T_H - 1] - Vec2::new(1.0, 0.0)).norm() < 1e-12);
        // Two taps far apart in time, each 5 % of the gesture: both are kept.
        let a = [(0, 0.0, 0.0), (50, 1.0, 0.0)];
        let b = [(950, 5.0, 5.0), (1000, 6.0, 5.0)];
        assert_eq!(
            prepare(&gesture(vec![track(&a), track(&b)]))
                .unwrap()
                .fingers
                .len(),
            2
        );
    }

    #[test]
    fn unsorted_and_duplicate_times_are_handled() {
        let sorted = track(&[
            (0, 0.0, 0.0),
            (100, 10.0, 0.0),
            (200, 20.0, 5.0),
            (300, 30.0, 5.0),
        ]);
        let shuffled = track(&[
            (200, 20.0, 5.0),
            (0, 0.0, 0.0),
            (300, 30.0, 5.0),
            (100, 10.0, 0.0),
        ]);
        let a = prepare(&gesture(vec![sorted])).unwrap();
        assert_eq!(a, prepare(&gesture(vec![shuffled])).unwrap());
        // Two reports at 100 µs average to the sorted track's sample.
        let dup = track(&[
            (0, 0.0, 0.0),
            (100, 9.0, 0.0),
            (100, 11.0, 0.0),
            (200, 20.0, 5.0),
            (300, 30.0, 5.0),
        ]);
        let b = prepare(&gesture(vec![dup])).unwrap();
        for j in 0..T_H {
            assert!((a.fingers[0][j] - b.fingers[0][j]).norm() < 1e-12);
        }
    }

    #[test]
    fn a_long_gesture_is_resampled_in_one_pass() {
        // 100 000 samples (a circle traced for 100 s at 1 kHz).
        let samples: Vec<(u64, f64, f64)> = (0..100_000)
            .map(|i| {
                let a = i as f64 * 1e-4 * std::f64::consts::TAU;
                (i * 1000, 50.0 + 40.0 * a.cos(), 50.0 + 40.0 * a.sin())
            })
            .collect();
        let r = prepare(&gesture(vec![track(&samples)])).unwrap();
        // The circle at the 64 instants, normalised by the same eq. 2.
        let mut want: [Vec2; T_H] = std::array::from_fn(|k| {
            let a = 9.9999 * std::f64::consts::TAU * k as f64 / (T_H - 1) as f64;
            Vec2::new(50.0 + 40.0 * a.cos(), 50.0 + 40.0 * a.sin())
        });
        normalise(std::slice::from_mut(&mut want)).unwrap();
        for (p, w) in r.fingers[0].iter().zip(&want) {
            assert!((p - w).norm() < 1e-9, "{p} vs {w}");
        }
    }
}
