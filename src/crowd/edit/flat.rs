//! What every track keeps to, and tracks read but not edited (crowd-motion-editing
//! section 3.1). The bounds ([`MAX_SAMPLES`], [`MAX_COORDINATE_M`], [`MAX_TIME_S`],
//! [`MIN_SAMPLE_STEP_S`]) and [`TrackError`]; [`TrackRef`], one person's track
//! borrowed; [`Tracks`], what collision detection reads (the person count, the
//! frame step, a [`TrackRef`] per person); and [`FlatTracks`], every person's
//! samples in one array of positions, one of times and one of links, so a million
//! people cost their samples and an id each (62 MB for two samples per person,
//! against ~200 MB as a million `Track`s of three vectors each). `tracks.rs` builds
//! the editable `TrackSet` on these and converts between the two.

use crate::geom::Vec2;
use thiserror::Error;

/// The most samples a track set may hold (all people together): a file larger than
/// this is refused rather than exhausting memory.
pub const MAX_SAMPLES: usize = 5_000_000;

/// The largest coordinate a track may hold, in metres either way of the origin
/// (1,000 km). Within it every quantity detection and editing derive (differences,
/// midpoints, squared distances, velocities over [`MIN_SAMPLE_STEP_S`]) is finite;
/// a place near 1e308 m would print as `(inf, -inf)`.
pub const MAX_COORDINATE_M: f64 = 1e6;

/// The largest time a track may hold, in seconds either way of 0 (about 31.7 years).
pub const MAX_TIME_S: f64 = 1e9;

/// The least time between a person's consecutive samples the track readers accept
/// (seconds): 1 µs, well above the spacing of doubles near [`MAX_TIME_S`] (0.12 µs),
/// so speeds stay below 2e12 m/s.
pub const MIN_SAMPLE_STEP_S: f64 = 1e-6;

/// What is wrong with a coordinate (metres), if anything: not finite, or beyond
/// [`MAX_COORDINATE_M`].
pub fn coordinate_problem(v: f64) -> Option<String> {
    bound_problem(v, MAX_COORDINATE_M, "m", "coordinate")
}

/// What is wrong with a time (seconds), if anything: not finite, or beyond
/// [`MAX_TIME_S`].
pub fn time_problem(v: f64) -> Option<String> {
    bound_problem(v, MAX_TIME_S, "s", "time")
}

/// `v` not finite, or beyond `±bound` (in `unit`, the bound named `what`).
fn bound_problem(v: f64, bound: f64, unit: &str, what: &str) -> Option<String> {
    if !v.is_finite() {
        Some(format!("{v} is not a finite number"))
    } else if v.abs() > bound {
        Some(format!(
            "{v:e} {unit} is beyond the {what} bound of ±{bound:e} {unit}"
        ))
    } else {
        None
    }
}

/// One person's track, borrowed: the fields of [`Track`](super::Track) as slices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackRef<'a> {
    /// The person's id.
    pub id: u64,
    /// Positions in metres, in time order.
    pub points: &'a [Vec2],
    /// Arrival time at each position in seconds, strictly increasing.
    pub times_s: &'a [f64],
    /// `linked[j]`: the person moves linearly from sample `j` to `j + 1`.
    pub linked: &'a [bool],
}

impl<'a> TrackRef<'a> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the track has no samples.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// First and last time (seconds); the track must not be empty.
    pub fn span_s(&self) -> (f64, f64) {
        (
            self.times_s[0],
            *self.times_s.last().unwrap_or(&self.times_s[0]),
        )
    }

    /// Indices `j` of the linked segments `j → j + 1`.
    pub fn segments(&self) -> impl Iterator<Item = usize> + 'a {
        self.linked
            .iter()
            .enumerate()
            .filter(|(_, l)| **l)
            .map(|(j, _)| j)
    }

    /// Where the person is at `t_s`, if present then (on a sample, or on a linked
    /// segment, moving linearly).
    pub fn position_at(&self, t_s: f64) -> Option<Vec2> {
        let n = self.times_s.len();
        if n == 0 || t_s < self.times_s[0] || t_s > self.times_s[n - 1] {
            return None;
        }
        let j = self.times_s.partition_point(|&t| t <= t_s);
        // times_s[j - 1] <= t_s < times_s[j] (or j == n at the last sample).
        let a = j - 1;
        if self.times_s[a] == t_s || a + 1 == n {
            return Some(self.points[a]);
        }
        if !self.linked[a] {
            return None;
        }
        let s = (t_s - self.times_s[a]) / (self.times_s[a + 1] - self.times_s[a]);
        Some(self.points[a] + (self.points[a + 1] - self.points[a]) * s)
    }

    /// Speed on segment `j → j + 1` in m/s.
    pub fn segment_speed(&self, j: usize) -> f64 {
        (self.points[j + 1] - self.points[j]).norm() / (self.times_s[j + 1] - self.times_s[j])
    }

    /// Checks the invariants [`Tracks::validate`] states, for this track alone.
    pub fn validate(&self) -> Result<(), TrackError> {
        let id = self.id;
        if self.points.len() != self.times_s.len()
            || self.linked.len() + 1 != self.points.len().max(1)
        {
            return Err(TrackError::Shape { id });
        }
        if self.points.is_empty() {
            return Err(TrackError::Empty { id });
        }
        for (j, (p, t)) in self.points.iter().zip(self.times_s).enumerate() {
            if !p.x.is_finite() || !p.y.is_finite() || !t.is_finite() {
                return Err(TrackError::NotFinite { id, sample: j });
            }
            if p.x.abs() > MAX_COORDINATE_M || p.y.abs() > MAX_COORDINATE_M || t.abs() > MAX_TIME_S
            {
                return Err(TrackError::OutOfRange { id, sample: j });
            }
            if j > 0 && *t <= self.times_s[j - 1] {
                return Err(TrackError::NotIncreasing {
                    id,
                    sample: j,
                    t_s: *t,
                    previous_s: self.times_s[j - 1],
                });
            }
        }
        Ok(())
    }
}

/// A crowd's tracks as detection reads them: [`TrackSet`](super::TrackSet) (editable) and
/// [`FlatTracks`] (compact) both are.
pub trait Tracks {
    /// Number of people.
    fn people(&self) -> usize;
    /// Person `k`'s track, `k < people()`.
    fn track(&self, k: usize) -> TrackRef<'_>;
    /// The nominal time between a person's consecutive samples, seconds.
    fn step_s(&self) -> f64;

    /// Total number of samples.
    fn samples(&self) -> usize {
        (0..self.people()).map(|k| self.track(k).len()).sum()
    }

    /// First and last time of any sample (seconds); `(0, 0)` without people.
    fn span_s(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for k in 0..self.people() {
            let t = self.track(k);
            if t.is_empty() {
                continue;
            }
            let (a, b) = t.span_s();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        if lo > hi {
            (0.0, 0.0)
        } else {
            (lo, hi)
        }
    }

    /// Checks that ids are unique, every track is non-empty with finite positions
    /// and strictly increasing times within [`MAX_COORDINATE_M`] and
    /// [`MAX_TIME_S`], links number one per consecutive pair of samples, and the
    /// step is positive and finite.
    ///
    /// # Errors
    /// The first broken invariant, naming the person and sample.
    fn validate(&self) -> Result<(), TrackError> {
        let step_s = self.step_s();
        if !(step_s.is_finite() && step_s > 0.0) {
            return Err(TrackError::Step { step_s });
        }
        let mut ids: Vec<u64> = (0..self.people()).map(|k| self.track(k).id).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(TrackError::DuplicateId { id: w[0] });
        }
        drop(ids);
        (0..self.people()).try_for_each(|k| self.track(k).validate())
    }
}

/// A track set that breaks [`Tracks::validate`]'s invariants.
#[derive(Debug, Error, PartialEq)]
pub enum TrackError {
    /// The step is not a positive finite number of seconds.
    #[error("the frame step must be a positive number of seconds, not {step_s}")]
    Step {
        /// The step given.
        step_s: f64,
    },
    /// Two tracks have one id.
    #[error("person {id} appears twice")]
    DuplicateId {
        /// The id.
        id: u64,
    },
    /// A track has no samples.
    #[error("person {id} has no samples")]
    Empty {
        /// The id.
        id: u64,
    },
    /// `points`, `times_s` and `linked` disagree in length.
    #[error("person {id}: positions, times and links differ in length")]
    Shape {
        /// The id.
        id: u64,
    },
    /// A position or time is NaN or infinite.
    #[error("person {id}, sample {sample}: position or time is not a finite number")]
    NotFinite {
        /// The id.
        id: u64,
        /// The sample's index.
        sample: usize,
    },
    /// A position or time is beyond [`MAX_COORDINATE_M`] or [`MAX_TIME_S`].
    #[error("person {id}, sample {sample}: position beyond ±{MAX_COORDINATE_M:e} m or time beyond ±{MAX_TIME_S:e} s")]
    OutOfRange {
        /// The id.
        id: u64,
        /// The sample's index.
        sample: usize,
    },
    /// Times do not strictly increase.
    #[error("person {id}, sample {sample}: time {t_s} s does not come after {previous_s} s")]
    NotIncreasing {
        /// The id.
        id: u64,
        /// The sample's index.
        sample: usize,
        /// Its time.
        t_s: f64,
        /// The time before it.
        previous_s: f64,
    },
}

/// Every person's samples in three flat arrays (see the module's text). Person
/// `k`'s samples are `starts[k]..starts[k + 1]`; `linked` has one entry per sample,
/// the last of each person unused (false).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatTracks {
    ids: Vec<u64>,
    starts: Vec<u32>,
    points: Vec<Vec2>,
    times_s: Vec<f64>,
    linked: Vec<bool>,
    step_s: f64,
}

impl FlatTracks {
    /// People `ids` (in order) whose samples are `points`/`times_s`/`linked`,
    /// person `k`'s at `starts[k]..starts[k + 1]` (`starts` one longer than `ids`,
    /// from 0 to the sample count, non-decreasing; `linked` one per sample, the
    /// entry of a person's last sample unused), sampled every `step_s` seconds.
    ///
    /// # Panics
    /// When the arrays disagree in length or `starts` is not as described: a
    /// caller's bug, never a file's.
    pub fn from_parts(
        ids: Vec<u64>,
        starts: Vec<u32>,
        points: Vec<Vec2>,
        times_s: Vec<f64>,
        linked: Vec<bool>,
        step_s: f64,
    ) -> FlatTracks {
        assert_eq!(starts.len(), ids.len() + 1);
        assert_eq!(points.len(), times_s.len());
        assert_eq!(points.len(), linked.len());
        assert_eq!(starts.first().copied(), Some(0));
        assert_eq!(starts.last().map(|&s| s as usize), Some(points.len()));
        assert!(starts.windows(2).all(|w| w[0] <= w[1]));
        FlatTracks {
            ids,
            starts,
            points,
            times_s,
            linked,
            step_s,
        }
    }

    /// Sets the frame step to `step_s` and links every two consecutive samples of
    /// a person at most `max_gap_s` apart (a longer wait is a gap).
    pub fn link_within(&mut self, step_s: f64, max_gap_s: f64) {
        self.step_s = step_s;
        for k in 0..self.ids.len() {
            let (s, e) = (self.starts[k] as usize, self.starts[k + 1] as usize);
            for j in s..e {
                self.linked[j] = j + 1 < e && self.times_s[j + 1] - self.times_s[j] <= max_gap_s;
            }
        }
    }

    /// Every person's consecutive time differences, in no particular order.
    pub fn time_steps(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.ids.len()).flat_map(move |k| {
            let (s, e) = (self.starts[k] as usize, self.starts[k + 1] as usize);
            self.times_s[s..e].windows(2).map(|w| w[1] - w[0])
        })
    }
}

impl Tracks for FlatTracks {
    fn people(&self) -> usize {
        self.ids.len()
    }

    fn track(&self, k: usize) -> TrackRef<'_> {
        let (s, e) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        TrackRef {
            id: self.ids[k],
            points: &self.points[s..e],
            times_s: &self.times_s[s..e],
            linked: &self.linked[s..e.max(s + 1) - 1],
        }
    }

    fn step_s(&self) -> f64 {
        self.step_s
    }

    fn samples(&self) -> usize {
        self.points.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Person 7: three samples, a gap after the second; person 3: one sample.
    fn two() -> FlatTracks {
        FlatTracks::from_parts(
            vec![7, 3],
            vec![0, 3, 4],
            vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(5.0, 0.0),
                Vec2::new(2.0, 2.0),
            ],
            vec![0.0, 1.0, 3.0, 0.5],
            vec![true, false, false, false],
            1.0,
        )
    }

    #[test]
    fn each_person_reads_as_their_own_slices() {
        let f = two();
        assert_eq!(f.people(), 2);
        assert_eq!(f.samples(), 4);
        assert_eq!(f.span_s(), (0.0, 3.0));
        let a = f.track(0);
        assert_eq!((a.id, a.len(), a.linked), (7, 3, &[true, false][..]));
        assert_eq!(a.position_at(0.5), Some(Vec2::new(0.5, 0.0)));
        assert_eq!(a.position_at(2.0), None, "in the gap the person is away");
        assert_eq!(a.segments().collect::<Vec<_>>(), vec![0]);
        let b = f.track(1);
        assert_eq!((b.id, b.times_s, b.linked), (3, &[0.5][..], &[] as &[bool]));
        f.validate().unwrap();
    }

    #[test]
    fn links_come_from_the_gap_between_samples() {
        let mut f = FlatTracks::from_parts(
            vec![1, 2],
            vec![0, 3, 5],
            vec![Vec2::zeros(); 5],
            vec![0.0, 1.0, 3.0, 0.0, 1.5],
            vec![false; 5],
            1.0,
        );
        f.link_within(0.5, 1.5);
        assert_eq!(f.step_s(), 0.5);
        assert_eq!(f.track(0).linked, &[true, false]);
        assert_eq!(f.track(1).linked, &[true]);
        let mut steps: Vec<f64> = f.time_steps().collect();
        steps.sort_by(f64::total_cmp);
        assert_eq!(steps, vec![1.0, 1.5, 2.0]);
    }

    #[test]
    fn validation_finds_a_duplicate_id_a_bad_sample_and_a_bad_step() {
        let mut f = two();
        f.ids[1] = 7;
        assert_eq!(f.validate(), Err(TrackError::DuplicateId { id: 7 }));
        let mut f = two();
        f.times_s[2] = 1.0;
        assert!(matches!(
            f.validate(),
            Err(TrackError::NotIncreasing {
                id: 7,
                sample: 2,
                ..
            })
        ));
        let mut f = two();
        f.points[3].y = 2e6;
        assert_eq!(
            f.validate(),
            Err(TrackError::OutOfRange { id: 3, sample: 0 })
        );
        let mut f = two();
        f.step_s = 0.0;
        assert!(matches!(f.validate(), Err(TrackError::Step { .. })));
    }
}
