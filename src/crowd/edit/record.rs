//! Tracks of a running crowd: positions given at every control tick become a
//! [`TrackSet`] sampled on a fixed grid of times (crowd-motion-editing section 3.1:
//! a person's spatial track and the times each point is reached).
//!
//! Ticks need not fall on the grid: a sample at grid time `g` between two ticks is
//! the linear interpolation of the agent's positions at those ticks. Person `i` is
//! the `i`-th position of every tick (an agent's index in the crowd); a person
//! first seen at a later tick starts there. Every person's samples are linked.

use super::flat::MAX_SAMPLES;
use super::tracks::{Track, TrackSet};
use crate::geom::Vec2;
use thiserror::Error;

/// Records positions given tick by tick into tracks on a time grid.
#[derive(Clone, Debug)]
pub struct TrackRecorder {
    step_s: f64,
    /// Index of the next grid time `k * step_s` to sample.
    next_k: u64,
    /// The previous tick: its time and positions.
    prev: Option<(f64, Vec<Vec2>)>,
    tracks: Vec<Track>,
    samples: usize,
}

/// Why positions could not be recorded.
#[derive(Copy, Clone, Debug, Error, PartialEq)]
pub enum RecordError {
    /// The step is not a positive finite number of seconds.
    #[error("the track step must be a positive number of seconds, not {step_s}")]
    Step {
        /// The step given.
        step_s: f64,
    },
    /// A tick's time is not finite or goes back.
    #[error("tick time {t_s} s is not finite or comes before {previous_s} s")]
    Time {
        /// The tick's time.
        t_s: f64,
        /// The previous tick's time.
        previous_s: f64,
    },
    /// A position is NaN or infinite.
    #[error("agent {agent}: position is not finite at {t_s} s")]
    NotFinite {
        /// The agent's index.
        agent: usize,
        /// The tick's time.
        t_s: f64,
    },
    /// The tracks would hold more than [`MAX_SAMPLES`] samples.
    #[error("more than {MAX_SAMPLES} samples: record fewer agents or at a longer step")]
    TooMany,
}

impl TrackRecorder {
    /// A recorder sampling every `step_s` seconds from time 0.
    ///
    /// # Errors
    /// [`RecordError::Step`] for a step that is not positive and finite.
    pub fn new(step_s: f64) -> Result<TrackRecorder, RecordError> {
        if !(step_s.is_finite() && step_s > 0.0) {
            return Err(RecordError::Step { step_s });
        }
        Ok(TrackRecorder {
            step_s,
            next_k: 0,
            prev: None,
            tracks: Vec::new(),
            samples: 0,
        })
    }

    /// The positions of every agent at tick time `t_s` (seconds, not decreasing):
    /// samples every grid time after the previous tick up to `t_s`.
    ///
    /// # Errors
    /// [`RecordError`] for a time that goes back or is not finite, a position that
    /// is not finite, or more than [`MAX_SAMPLES`] samples in all; nothing is
    /// recorded from that tick.
    pub fn tick(&mut self, t_s: f64, positions: &[Vec2]) -> Result<(), RecordError> {
        let previous_s = self.prev.as_ref().map_or(f64::NEG_INFINITY, |p| p.0);
        if !t_s.is_finite() || t_s < previous_s {
            return Err(RecordError::Time { t_s, previous_s });
        }
        if let Some(agent) = positions
            .iter()
            .position(|p| !p.x.is_finite() || !p.y.is_finite())
        {
            return Err(RecordError::NotFinite { agent, t_s });
        }
        while self.tracks.len() < positions.len() {
            let id = self.tracks.len() as u64;
            self.tracks.push(Track::linked(id, Vec::new(), Vec::new()));
        }
        loop {
            let g = self.next_k as f64 * self.step_s;
            if g > t_s {
                break;
            }
            if self.samples + positions.len() > MAX_SAMPLES {
                return Err(RecordError::TooMany);
            }
            for (i, &p) in positions.iter().enumerate() {
                let at = match &self.prev {
                    Some((t0, before)) if g < t_s && i < before.len() && t_s > *t0 => {
                        let s = ((g - t0) / (t_s - t0)).clamp(0.0, 1.0);
                        before[i] + (p - before[i]) * s
                    }
                    _ => p,
                };
                let tr = &mut self.tracks[i];
                if !tr.points.is_empty() {
                    tr.linked.push(true);
                }
                tr.points.push(at);
                tr.times_s.push(g);
            }
            self.samples += positions.len();
            self.next_k += 1;
        }
        match &mut self.prev {
            Some((t, v)) => {
                *t = t_s;
                v.clear();
                v.extend_from_slice(positions);
            }
            None => self.prev = Some((t_s, positions.to_vec())),
        }
        Ok(())
    }

    /// The tracks recorded (people never sampled left out).
    pub fn finish(self) -> TrackSet {
        TrackSet {
            tracks: self.tracks.into_iter().filter(|t| !t.is_empty()).collect(),
            step_s: self.step_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_the_grid_between_ticks() {
        let mut r = TrackRecorder::new(0.25).unwrap();
        r.tick(0.0, &[Vec2::new(0.0, 0.0)]).unwrap();
        r.tick(0.3, &[Vec2::new(3.0, 0.0)]).unwrap();
        r.tick(0.6, &[Vec2::new(6.0, 0.0), Vec2::new(1.0, 1.0)])
            .unwrap();
        let set = r.finish();
        set.validate().unwrap();
        assert_eq!(set.tracks.len(), 2);
        let a = &set.tracks[0];
        assert_eq!(a.times_s, vec![0.0, 0.25, 0.5]);
        assert!((a.points[1].x - 2.5).abs() < 1e-12, "{:?}", a.points);
        assert!((a.points[2].x - 5.0).abs() < 1e-12, "{:?}", a.points);
        assert_eq!(a.linked, vec![true, true]);
        let b = &set.tracks[1];
        assert_eq!(b.id, 1);
        assert_eq!(
            b.times_s,
            vec![0.5],
            "a late agent starts at its first tick"
        );
        assert_eq!(b.points, vec![Vec2::new(1.0, 1.0)]);
    }

    #[test]
    fn refuses_bad_input() {
        assert!(TrackRecorder::new(0.0).is_err());
        assert!(TrackRecorder::new(f64::NAN).is_err());
        let mut r = TrackRecorder::new(0.1).unwrap();
        r.tick(1.0, &[]).unwrap();
        assert!(matches!(r.tick(0.5, &[]), Err(RecordError::Time { .. })));
        assert_eq!(
            r.tick(2.0, &[Vec2::new(f64::NAN, 0.0)]),
            Err(RecordError::NotFinite { agent: 0, t_s: 2.0 })
        );
    }
}
