//! Track sets: per person a spatial track (a polyline of positions) and a temporal
//! track (the time each position is reached), crowd-motion-editing section 3.1.
//!
//! Sample `j` of a person is the pair `(p_j, t_j)`: the person is at `p_j` (metres)
//! at `t_j` (seconds). Consecutive samples are *linked* when the person moves
//! linearly between them (they were one frame step apart when read); an unlinked
//! pair is a gap in which the person is not on the scene. Everything that measures
//! distances between people (collision detection, avoidance) follows these links,
//! so a person present in two stretches is one [`Track`] with a gap, not two people.

use super::flat::{FlatTracks, TrackError, TrackRef, Tracks};
use crate::geom::Vec2;

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

    /// The track borrowed as a [`TrackRef`].
    pub fn as_ref(&self) -> TrackRef<'_> {
        TrackRef {
            id: self.id,
            points: &self.points,
            times_s: &self.times_s,
            linked: &self.linked,
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
        self.as_ref().span_s()
    }

    /// Indices `j` of the linked segments `j → j + 1`.
    pub fn segments(&self) -> impl Iterator<Item = usize> + '_ {
        self.as_ref().segments()
    }

    /// Where the person is at `t_s`, if present then (on a sample, or on a linked
    /// segment, moving linearly).
    pub fn position_at(&self, t_s: f64) -> Option<Vec2> {
        self.as_ref().position_at(t_s)
    }

    /// Speed on segment `j → j + 1` in m/s.
    pub fn segment_speed(&self, j: usize) -> f64 {
        self.as_ref().segment_speed(j)
    }

    /// Checks the invariants [`TrackSet::validate`] states, for this track alone.
    ///
    /// # Errors
    /// The first broken invariant, naming the sample.
    pub fn validate(&self) -> Result<(), TrackError> {
        self.as_ref().validate()
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
        Tracks::samples(self)
    }

    /// First and last time of any sample (seconds); `(0, 0)` for an empty set.
    pub fn span_s(&self) -> (f64, f64) {
        Tracks::span_s(self)
    }

    /// The index of the track with id `id`.
    pub fn index_of(&self, id: u64) -> Option<usize> {
        self.tracks.iter().position(|t| t.id == id)
    }

    /// Checks that ids are unique, every track is non-empty with finite positions and
    /// strictly increasing times within [`MAX_COORDINATE_M`](super::MAX_COORDINATE_M) and [`MAX_TIME_S`](super::MAX_TIME_S), `linked` has one entry per consecutive pair, and
    /// the step is positive and finite ([`Tracks::validate`]).
    ///
    /// # Errors
    /// The first broken invariant, naming the person and sample.
    pub fn validate(&self) -> Result<(), TrackError> {
        Tracks::validate(self)
    }
}

impl From<&FlatTracks> for TrackSet {
    /// The same people as editable [`Track`]s, each vector at its exact size.
    fn from(f: &FlatTracks) -> TrackSet {
        TrackSet {
            tracks: (0..f.people())
                .map(|k| {
                    let t = f.track(k);
                    Track {
                        id: t.id,
                        points: t.points.to_vec(),
                        times_s: t.times_s.to_vec(),
                        linked: t.linked.to_vec(),
                    }
                })
                .collect(),
            step_s: f.step_s(),
        }
    }
}

impl From<&TrackSet> for FlatTracks {
    /// The people of a valid [`TrackSet`], in its order.
    fn from(set: &TrackSet) -> FlatTracks {
        let samples = set.samples();
        let mut ids = Vec::with_capacity(set.tracks.len());
        let mut starts = Vec::with_capacity(set.tracks.len() + 1);
        let mut points = Vec::with_capacity(samples);
        let mut times_s = Vec::with_capacity(samples);
        let mut linked = Vec::with_capacity(samples);
        starts.push(0);
        for t in &set.tracks {
            ids.push(t.id);
            points.extend_from_slice(&t.points);
            times_s.extend_from_slice(&t.times_s);
            linked.extend_from_slice(&t.linked);
            // The unused entry after a person's last sample.
            linked.resize(points.len(), false);
            starts.push(points.len() as u32);
        }
        FlatTracks::from_parts(ids, starts, points, times_s, linked, set.step_s)
    }
}

impl Tracks for TrackSet {
    fn people(&self) -> usize {
        self.tracks.len()
    }

    fn track(&self, k: usize) -> TrackRef<'_> {
        self.tracks[k].as_ref()
    }

    fn step_s(&self) -> f64 {
        self.step_s
    }
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

    #[test]
    fn a_flat_store_reads_as_the_set_it_came_from() {
        let set = TrackSet {
            tracks: vec![
                walk(),
                Track::linked(3, vec![Vec2::new(2.0, 2.0)], vec![0.5]),
            ],
            step_s: 1.0,
        };
        let flat = FlatTracks::from(&set);
        assert_eq!(flat.people(), 2);
        assert_eq!(flat.samples(), set.samples());
        assert_eq!(Tracks::span_s(&flat), set.span_s());
        for k in 0..2 {
            assert_eq!(flat.track(k), set.tracks[k].as_ref());
        }
        assert_eq!(TrackSet::from(&flat), set);
    }
}
