//! A crowd motion from recorded tracks (people's trajectories from a track file: the
//! pedestrian datasets, our JSON Lines or CSV, a daemon run's `replay --tracks`),
//! turned into the library's representation the way `library build` turns a
//! simulated crowd into one (gesture-driven sections 6.1–6.2): the people present
//! throughout a time window, sampled evenly over it, resampled to `S_H` samples and
//! normalised ([`CrowdMotion::from_world`], eqs. 13–15), then their FPCA and the
//! Gaussian mixture of their eigenscores ([`features`], eqs. 16–17).
//!
//! A track file holds people who come and go; a crowd motion is M people over one
//! duration. The window is given, or chosen: the [`DEFAULT_IMPORT_DURATION_S`]
//! stretch with the most people present from its start to its end (the earliest of
//! equals), never longer than the file.

use super::crowd_motion::CrowdMotion;
use super::error::MotionError;
use super::features::{features, FeatureParams};
use crate::geom::Vec2;
use crate::gesture::library::{ClassId, MotionFeatures};

/// Length of the window chosen when none is given (s): about as long as the
/// simulator's motions of the shipped library (2–8 s).
pub const DEFAULT_IMPORT_DURATION_S: f64 = 6.0;

/// Fewest people a crowd motion is made of: with one there is no crowd to
/// normalise (eq. 13's spread) nor eigenscores to fit a mixture to.
pub const MIN_IMPORT_PEOPLE: usize = 2;

/// Most samples taken of each person over the window before resampling to `S_H`.
pub const MAX_IMPORT_SAMPLES: usize = 10_000;

/// One person's samples as a track file holds them (metres, seconds).
#[derive(Copy, Clone, Debug)]
pub struct PersonSamples<'a> {
    /// The person's id in the file.
    pub id: u64,
    /// Arrival time at each position, strictly increasing (s).
    pub times_s: &'a [f64],
    /// Positions (m).
    pub points: &'a [Vec2],
    /// `linked[j]`: the person moves linearly from sample `j` to `j + 1`; `false`
    /// is a gap in which the person is not on the scene (`points.len() - 1` long).
    pub linked: &'a [bool],
}

impl PersonSamples<'_> {
    /// Whether the person is on the scene from `from_s` to `to_s`, with no gap.
    pub fn covers(&self, from_s: f64, to_s: f64) -> bool {
        let t = self.times_s;
        let (Some(&first), Some(&last)) = (t.first(), t.last()) else {
            return false;
        };
        if !(first <= from_s && last >= to_s) {
            return false;
        }
        // Segments from the sample at or before `from_s` to the one at or after `to_s`.
        let a = t.partition_point(|&x| x <= from_s).saturating_sub(1);
        let b = t.partition_point(|&x| x < to_s).min(t.len() - 1);
        self.linked.get(a..b).is_some_and(|l| l.iter().all(|&k| k))
    }

    /// Where the person is at `t_s`: on a sample, or moving linearly along a linked
    /// segment; `None` outside the track or in a gap.
    pub fn position_at(&self, t_s: f64) -> Option<Vec2> {
        let t = self.times_s;
        let n = t.len();
        if n == 0 || t_s < t[0] || t_s > t[n - 1] {
            return None;
        }
        let j = t.partition_point(|&x| x <= t_s);
        let a = j - 1;
        if t[a] == t_s || a + 1 == n {
            return self.points.get(a).copied();
        }
        if !self.linked.get(a).copied().unwrap_or(false) {
            return None;
        }
        let s = (t_s - t[a]) / (t[a + 1] - t[a]);
        Some(self.points[a] + (self.points[a + 1] - self.points[a]) * s)
    }
}

/// The time window a motion is taken from.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ImportWindow {
    /// Start (s), `None`: chosen.
    pub from_s: Option<f64>,
    /// End (s), `None`: the start plus `duration_s`.
    pub to_s: Option<f64>,
    /// Length of a chosen or open-ended window (s).
    pub duration_s: f64,
}

impl Default for ImportWindow {
    fn default() -> ImportWindow {
        ImportWindow {
            from_s: None,
            to_s: None,
            duration_s: DEFAULT_IMPORT_DURATION_S,
        }
    }
}

/// A crowd motion imported: its features and what it was taken from.
#[derive(Clone, Debug)]
pub struct ImportedMotion {
    /// The motion's features (eq. 17), of the class asked for.
    pub features: MotionFeatures,
    /// The window (s).
    pub from_s: f64,
    /// The window's end (s).
    pub to_s: f64,
    /// The ids of the people it is made of, in the file's order.
    pub people: Vec<u64>,
}

/// Why tracks give no crowd motion.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ImportError {
    /// No one in the file.
    #[error("the track file holds no person")]
    NoPeople,
    /// A window that is not a finite, positive stretch of time.
    #[error(
        "the window {from_s} s to {to_s} s is not a stretch of time (finite, start before end)"
    )]
    BadWindow {
        /// Start (s).
        from_s: f64,
        /// End (s).
        to_s: f64,
    },
    /// Too few people on the scene over the whole window.
    #[error("{found} {} on the scene from {from_s:.3} s to {to_s:.3} s without a gap (of {total} in the file); a crowd motion needs at least {needed}", if *.found == 1 { "person is" } else { "people are" })]
    TooFewPeople {
        /// People present throughout.
        found: usize,
        /// People in the file.
        total: usize,
        /// The least needed ([`MIN_IMPORT_PEOPLE`]).
        needed: usize,
        /// Window start (s).
        from_s: f64,
        /// Window end (s).
        to_s: f64,
    },
    /// A NaN or infinite position or time.
    #[error("person {id}, sample {sample}: {what} is NaN or infinite")]
    NotFinite {
        /// The person's id.
        id: u64,
        /// The sample.
        sample: usize,
        /// `position` or `time`.
        what: &'static str,
    },
    /// The motion's features could not be computed.
    #[error("no crowd motion from people {people:?}: {source}")]
    Motion {
        /// The ids of the people taken.
        people: Vec<u64>,
        /// Why.
        source: MotionError,
    },
}

/// The window with the most people present throughout, of `duration_s` (or the
/// whole span when shorter), starting at a multiple of `step_s` from the earliest
/// sample; the earliest of equals. `None` without samples.
///
/// # Complexity
/// O(W · P · log S) for W candidate starts, P people, S samples each.
pub fn busiest_window(
    people: &[PersonSamples<'_>],
    duration_s: f64,
    step_s: f64,
) -> Option<(f64, f64, usize)> {
    let first = people
        .iter()
        .filter_map(|p| p.times_s.first())
        .copied()
        .fold(f64::INFINITY, f64::min);
    let last = people
        .iter()
        .filter_map(|p| p.times_s.last())
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    if !(first.is_finite() && last.is_finite()) {
        return None;
    }
    let d = duration_s.min(last - first);
    let step = if step_s.is_finite() && step_s > 0.0 {
        step_s
    } else {
        d.max(1e-3)
    };
    let starts = (((last - first - d) / step).floor().max(0.0) as usize).min(1_000_000);
    let mut best: Option<(f64, f64, usize)> = None;
    for k in 0..=starts {
        let a = first + k as f64 * step;
        let b = a + d;
        let n = people.iter().filter(|p| p.covers(a, b)).count();
        if best.is_none_or(|(_, _, m)| n > m) {
            best = Some((a, b, n));
        }
    }
    best
}

/// Imports a crowd motion of class `class` from `people` (see the module doc):
/// the window, the people present throughout it, each sampled every `step_s` (the
/// file's frame step; at least 2 and at most [`MAX_IMPORT_SAMPLES`] samples), then
/// [`CrowdMotion::from_world`] and [`features`] with `fp`, as `library build` does.
///
/// # Errors
/// [`ImportError`]: no people, a bad window, fewer than [`MIN_IMPORT_PEOPLE`]
/// present throughout it, a NaN, or the features' own error.
pub fn import_motion(
    people: &[PersonSamples<'_>],
    step_s: f64,
    window: &ImportWindow,
    class: ClassId,
    fp: &FeatureParams,
) -> Result<ImportedMotion, ImportError> {
    if people.is_empty() {
        return Err(ImportError::NoPeople);
    }
    for p in people {
        if let Some(sample) = p.times_s.iter().position(|t| !t.is_finite()) {
            return Err(ImportError::NotFinite {
                id: p.id,
                sample,
                what: "time",
            });
        }
        if let Some(sample) = p
            .points
            .iter()
            .position(|q| !(q.x.is_finite() && q.y.is_finite()))
        {
            return Err(ImportError::NotFinite {
                id: p.id,
                sample,
                what: "position",
            });
        }
    }
    let (from_s, to_s) = match (window.from_s, window.to_s) {
        (Some(a), Some(b)) => (a, b),
        (Some(a), None) => (a, a + window.duration_s),
        (None, Some(b)) => (b - window.duration_s, b),
        (None, None) => match busiest_window(people, window.duration_s, step_s) {
            Some((a, b, _)) => (a, b),
            None => return Err(ImportError::NoPeople),
        },
    };
    if !(from_s.is_finite() && to_s.is_finite() && to_s > from_s) {
        return Err(ImportError::BadWindow { from_s, to_s });
    }
    let present: Vec<&PersonSamples<'_>> =
        people.iter().filter(|p| p.covers(from_s, to_s)).collect();
    if present.len() < MIN_IMPORT_PEOPLE {
        return Err(ImportError::TooFewPeople {
            found: present.len(),
            total: people.len(),
            needed: MIN_IMPORT_PEOPLE,
            from_s,
            to_s,
        });
    }
    let span = to_s - from_s;
    let samples = if step_s.is_finite() && step_s > 0.0 {
        ((span / step_s).round() as usize + 1).clamp(2, MAX_IMPORT_SAMPLES)
    } else {
        2
    };
    let tracks: Vec<Vec<Vec2>> = present
        .iter()
        .map(|p| {
            (0..samples)
                .map(|k| {
                    let t = from_s + span * k as f64 / (samples - 1) as f64;
                    // Present throughout: every time in the window has a position.
                    p.position_at(t.min(to_s)).unwrap_or(Vec2::zeros())
                })
                .collect()
        })
        .collect();
    let ids: Vec<u64> = present.iter().map(|p| p.id).collect();
    let features = CrowdMotion::from_world(&tracks, span)
        .and_then(|m| features(class, &m, fp))
        .map_err(|source| ImportError::Motion {
            people: ids.clone(),
            source,
        })?;
    Ok(ImportedMotion {
        features,
        from_s,
        to_s,
        people: ids,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gesture::library::{validate_with, Library, LoadPolicy};

    struct Owned {
        id: u64,
        times: Vec<f64>,
        points: Vec<Vec2>,
        linked: Vec<bool>,
    }

    impl Owned {
        fn walking(id: u64, t0: f64, t1: f64, start: Vec2, v: Vec2) -> Owned {
            let n = ((t1 - t0) / 0.4).round() as usize + 1;
            let times: Vec<f64> = (0..n).map(|k| t0 + 0.4 * k as f64).collect();
            let points = times.iter().map(|t| start + v * (t - t0)).collect();
            Owned {
                id,
                linked: vec![true; n - 1],
                times,
                points,
            }
        }

        fn view(&self) -> PersonSamples<'_> {
            PersonSamples {
                id: self.id,
                times_s: &self.times,
                points: &self.points,
                linked: &self.linked,
            }
        }
    }

    fn crowd() -> Vec<Owned> {
        // Five people walking right from 0 to 20 s, two more from 10 s to 20 s,
        // one who leaves at 4 s.
        let mut v: Vec<Owned> = (0..5)
            .map(|i| {
                Owned::walking(
                    i,
                    0.0,
                    20.0,
                    Vec2::new(0.0, i as f64),
                    Vec2::new(1.0, 0.1 * i as f64),
                )
            })
            .collect();
        v.push(Owned::walking(
            5,
            10.0,
            20.0,
            Vec2::new(3.0, 0.5),
            Vec2::new(1.2, 0.0),
        ));
        v.push(Owned::walking(
            6,
            10.0,
            20.0,
            Vec2::new(3.0, 2.5),
            Vec2::new(0.8, 0.0),
        ));
        v.push(Owned::walking(
            7,
            0.0,
            4.0,
            Vec2::new(9.0, 9.0),
            Vec2::new(0.0, 1.0),
        ));
        v
    }

    #[test]
    fn coverage_follows_links_and_spans() {
        let mut p = Owned::walking(1, 0.0, 8.0, Vec2::zeros(), Vec2::new(1.0, 0.0));
        assert!(p.view().covers(0.0, 8.0));
        assert!(p.view().covers(1.1, 3.3));
        assert!(!p.view().covers(-0.1, 3.0));
        assert!(!p.view().covers(1.0, 8.1));
        // A gap from 2.0 to 2.4 s.
        p.linked[5] = false;
        assert!(!p.view().covers(1.0, 3.0));
        let (gap_start, gap_end) = (p.times[5], p.times[6]);
        assert!(p.view().covers(gap_end, 8.0));
        assert!(p.view().covers(0.0, gap_start));
        assert!(!p.view().covers(gap_end - 1e-9, 8.0));
        assert_eq!(p.view().position_at(2.2), None);
        let at = p.view().position_at(1.0).unwrap();
        assert!((at - Vec2::new(1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn the_busiest_window_is_the_earliest_with_most_people() {
        let owned = crowd();
        let people: Vec<_> = owned.iter().map(Owned::view).collect();
        let (a, b, n) = busiest_window(&people, 6.0, 0.4).unwrap();
        assert_eq!(n, 7, "five all along and two from 10 s");
        assert!(
            (a - 10.0).abs() < 1e-9 && (b - 16.0).abs() < 1e-9,
            "{a}..{b}"
        );
        // Longer than the file: the whole span.
        let (a, b, n) = busiest_window(&people, 100.0, 0.4).unwrap();
        assert_eq!((a, b, n), (0.0, 20.0, 5));
    }

    #[test]
    fn an_imported_motion_is_a_valid_library_motion_of_its_class() {
        let owned = crowd();
        let people: Vec<_> = owned.iter().map(Owned::view).collect();
        let m = import_motion(
            &people,
            0.4,
            &ImportWindow::default(),
            ClassId(1),
            &FeatureParams::default(),
        )
        .unwrap();
        assert_eq!(m.people, [0, 1, 2, 3, 4, 5, 6]);
        assert_eq!(m.features.class, ClassId(1));
        assert!((m.features.duration_s - 6.0).abs() < 1e-9);
        let lib = Library {
            classes: vec!["a".into(), "walk".into()],
            motions: vec![m.features.clone()],
            gestures: vec![],
        };
        validate_with(&lib, LoadPolicy::Partial).unwrap();
        // Everyone walks right: the mean trajectory (crowd units, eq. 15) ends to
        // the right of where it starts.
        let mean = &m.features.mean;
        let n = mean.len();
        assert!(mean[n - 2] - mean[0] > 1.0, "{} → {}", mean[0], mean[n - 2]);
    }

    #[test]
    fn too_few_people_a_bad_window_and_nan_are_named() {
        let owned = crowd();
        let people: Vec<_> = owned.iter().map(Owned::view).collect();
        let one = &people[7..];
        let e = import_motion(
            one,
            0.4,
            &ImportWindow::default(),
            ClassId(0),
            &FeatureParams::default(),
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                ImportError::TooFewPeople {
                    found: 1,
                    total: 1,
                    needed: 2,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("1 person is on the scene"), "{e}");
        let w = ImportWindow {
            from_s: Some(5.0),
            to_s: Some(5.0),
            ..ImportWindow::default()
        };
        let e = import_motion(&people, 0.4, &w, ClassId(0), &FeatureParams::default()).unwrap_err();
        assert!(matches!(e, ImportError::BadWindow { .. }), "{e}");
        let mut bad = crowd();
        bad[3].points[4].y = f64::NAN;
        let people: Vec<_> = bad.iter().map(Owned::view).collect();
        let e = import_motion(
            &people,
            0.4,
            &ImportWindow::default(),
            ClassId(0),
            &FeatureParams::default(),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "person 3, sample 4: position is NaN or infinite"
        );
        assert_eq!(
            import_motion(
                &[],
                0.4,
                &ImportWindow::default(),
                ClassId(0),
                &FeatureParams::default()
            )
            .unwrap_err(),
            ImportError::NoPeople
        );
    }
}
