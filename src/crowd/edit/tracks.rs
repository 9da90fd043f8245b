//! Track sets: per person a spatial track (a polyline of positions) and a temporal
//! track (the time each position is reached), crowd-motion-editing section 3.1.
//!
//! Sample `j` of a person is the pair `(p_j, t_j)`: the person is at `p_j` (metres)
//! at `t_j` (seconds). Consecutive samples are *linked* when the person moves
//! linearly between them (they were one frame step apart when read); an unlinked
//! pair is a gap in which the person is not on the scene. Everything that measures
//! distances between people (collision detection, avoidance) follows these links,
//! so a person present in two stretches is one [`Track`] with a gap, not two people.

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
    if !v.is_finite() {
        Some(format!("{v} is not a finite number"))
    } else if v.abs() > MAX_COORDINATE_M {
        Some(format!(
            "{v:e} m is beyond the coordinate bound of ±{MAX_COORDINATE_M:e} m"
        ))
    } else {
        None
    }
}

/// What is wrong with a time (seconds), if anything: not finite, or beyond
/// [`MAX_TIME_S`].
pub fn time_problem(v: f64) -> Option<String> {
    if !v.is_finite() {
        Some(format!("{v} is not a finite number"))
    } else if v.abs() > MAX_TIME_S {
        Some(format!(
            "{v:e} s is beyond the time bound of ±{MAX_TIME_S:e} s"
        ))
    } else {
        None
    }
}

/// One person's tracks.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// The person's id, as read (unique in the set).
    pub id: u64,
    /// Positions in metres, in time order (the spatial track).
    pub points: Vec<Vec2>,
    /// Arrival time at each position in seconds, strictly increasing (the temporal track).
    pub times_s: Vec<f64>,
    /// `linked[j]`: the person moves linearly from sample `j` to `j + 1`
    /// (length `points.len() - 1`); `false` is a gap.
    pub linked: Vec<bool>,
}

impl Track {
    /// A track whose consecutive samples are all linked.
    pub fn linked(id: u64, points: Vec<Vec2>, times_s: Vec<f64>) -> Track {
        let n = points.len().saturating_sub(1);
        Track {
            id,
            points,
            times_s,
            linked: vec![true; n],
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the track has no samples.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// First and last time (seconds).
    pub fn span_s(&self) -> (f64, f64) {
        (
            self.times_s[0],
            *self.times_s.last().unwrap_or(&self.times_s[0]),
        )
    }

    /// Indices `j` of the linked segments `j → j + 1`.
    pub fn segments(&self) -> impl Iterator<Item = usize> + '_ {
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

    /// Checks the invariants [`TrackSet::validate`] states, for this track alone.
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
        for (j, (p, t)) in self.points.iter().zip(&self.times_s).enumerate() {
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

/// A crowd's tracks: every person's [`Track`], with the frame step they were sampled at.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackSet {
    /// The people, in the order read (ids unique).
    pub tracks: Vec<Track>,
    /// The nominal time between a person's consecutive samples, seconds (the frame
    /// step of the recording or simulation they came from).
    pub step_s: f64,
}

impl TrackSet {
    /// Total number of samples.
    pub fn samples(&self) -> usize {
        self.tracks.iter().map(Track::len).sum()
    }

    /// First and last time of any sample (seconds); `(0, 0)` for an empty set.
    pub fn span_s(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for t in &self.tracks {
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

    /// The index of the track with id `id`.
    pub fn index_of(&self, id: u64) -> Option<usize> {
        self.tracks.iter().position(|t| t.id == id)
    }

    /// Checks that ids are unique, every track is non-empty with finite positions and
    /// strictly increasing times within [`MAX_COORDINATE_M`] and [`MAX_TIME_S`], `linked` has one entry per consecutive pair, and
    /// the step is positive and finite.
    pub fn validate(&self) -> Result<(), TrackError> {
        if !(self.step_s.is_finite() && self.step_s > 0.0) {
            return Err(TrackError::Step {
                step_s: self.step_s,
            });
        }
        let mut ids: Vec<u64> = self.tracks.iter().map(|t| t.id).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(TrackError::DuplicateId { id: w[0] });
        }
        for t in &self.tracks {
            t.validate()?;
        }
        Ok(())
    }
}

/// A track set that breaks [`TrackSet::validate`]'s invariants.
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

#[cfg(test)]
mod tests {
    use super::*;

    fn walk() -> Track {
        Track {
            id: 7,
            points: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(5.0, 0.0),
                Vec2::new(6.0, 0.0),
            ],
            times_s: vec![0.0, 1.0, 3.0, 4.0],
            linked: vec![true, false, true],
        }
    }

    #[test]
    fn position_follows_links_and_gaps() {
        let t = walk();
        assert_eq!(t.position_at(0.5), Some(Vec2::new(0.5, 0.0)));
        assert_eq!(t.position_at(1.0), Some(Vec2::new(1.0, 0.0)));
        assert_eq!(t.position_at(2.0), None, "in the gap the person is away");
        assert_eq!(t.position_at(3.5), Some(Vec2::new(5.5, 0.0)));
        assert_eq!(t.position_at(4.0), Some(Vec2::new(6.0, 0.0)));
        assert_eq!(t.position_at(4.1), None);
        assert_eq!(t.segments().collect::<Vec<_>>(), vec![0, 2]);
    }

    #[test]
    fn validation_names_the_person_and_sample() {
        let mut t = walk();
        t.times_s[2] = 1.0;
        assert_eq!(
            t.validate(),
            Err(TrackError::NotIncreasing {
                id: 7,
                sample: 2,
                t_s: 1.0,
                previous_s: 1.0
            })
        );
        let mut t = walk();
        t.points[1].x = f64::NAN;
        assert_eq!(
            t.validate(),
            Err(TrackError::NotFinite { id: 7, sample: 1 })
        );
        let set = TrackSet {
            tracks: vec![walk(), walk()],
            step_s: 1.0,
        };
        assert_eq!(set.validate(), Err(TrackError::DuplicateId { id: 7 }));
    }
}
