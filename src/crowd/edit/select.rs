//! Selecting the samples an edit applies to: by person id, rectangle, lasso polygon
//! and time window, combined (a sample is selected when it meets every criterion
//! given).

use super::error::EditError;
use super::tracks::TrackSet;
use crate::geom::{Rect, Vec2};

/// One sample of a track set: `set.tracks[track].points[sample]`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SampleRef {
    /// Index into `TrackSet::tracks`.
    pub track: usize,
    /// Index into the track's samples.
    pub sample: usize,
}

/// What to select. Every criterion left `None` selects everything; the criteria given
/// are combined by intersection.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SelectionQuery {
    /// Only these people (ids).
    pub ids: Option<Vec<u64>>,
    /// Only samples inside this rectangle (border included), metres.
    pub rect: Option<Rect>,
    /// Only samples inside this closed polygon (either orientation), metres.
    pub lasso: Option<Vec<Vec2>>,
    /// Only samples whose time lies in `[start, end]`, seconds.
    pub window_s: Option<(f64, f64)>,
}

impl SelectionQuery {
    /// Restricts to people with these ids.
    pub fn ids(mut self, ids: &[u64]) -> Self {
        self.ids = Some(ids.to_vec());
        self
    }
    /// Restricts to a rectangle.
    pub fn rect(mut self, r: Rect) -> Self {
        self.rect = Some(r);
        self
    }
    /// Restricts to a lasso polygon.
    pub fn lasso(mut self, poly: &[Vec2]) -> Self {
        self.lasso = Some(poly.to_vec());
        self
    }
    /// Restricts to a time window (seconds, inclusive).
    pub fn window(mut self, start_s: f64, end_s: f64) -> Self {
        self.window_s = Some((start_s, end_s));
        self
    }
}

/// The selected samples, sorted by track then sample, no duplicates, at least three
/// distinct positions.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    samples: Vec<SampleRef>,
}

/// Whether `p` lies inside the closed polygon `poly` (even–odd crossing rule; points on
/// the boundary may go either way).
///
/// # Complexity
/// O(n), no allocation.
pub fn point_in_polygon(poly: &[Vec2], p: Vec2) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

impl Selection {
    /// Selects the samples of `set` that meet every criterion of `q`.
    ///
    /// # Errors
    /// [`EditError::UnknownId`] for an id not in the set, [`EditError::BadLasso`],
    /// [`EditError::BadCriterion`] for a non-finite or empty rectangle or window, and
    /// [`EditError::NoHull`] when fewer than 3 distinct positions are selected.
    pub fn select(set: &TrackSet, q: &SelectionQuery) -> Result<Selection, EditError> {
        let mut tracks: Vec<usize> = match &q.ids {
            Some(ids) => {
                let mut v = Vec::with_capacity(ids.len());
                for &id in ids {
                    v.push(set.index_of(id).ok_or(EditError::UnknownId { id })?);
                }
                v.sort_unstable();
                v.dedup();
                v
            }
            None => (0..set.tracks.len()).collect(),
        };
        if let Some(r) = &q.rect {
            let ok = r.min.iter().chain(&r.max).all(|v| v.is_finite())
                && r.min[0] <= r.max[0]
                && r.min[1] <= r.max[1];
            if !ok {
                return Err(EditError::BadCriterion { what: "rect" });
            }
        }
        if let Some((a, b)) = q.window_s {
            if !(a.is_finite() && b.is_finite() && a <= b) {
                return Err(EditError::BadCriterion {
                    what: "time window",
                });
            }
        }
        if let Some(l) = &q.lasso {
            if l.len() < 3 || !l.iter().all(|v| v.x.is_finite() && v.y.is_finite()) {
                return Err(EditError::BadLasso { vertices: l.len() });
            }
        }
        let mut samples = Vec::new();
        for &ti in &tracks {
            let t = &set.tracks[ti];
            for (j, (p, ts)) in t.points.iter().zip(&t.times_s).enumerate() {
                if q.rect.is_some_and(|r| !r.contains(*p))
                    || q.window_s.is_some_and(|(a, b)| *ts < a || *ts > b)
                    || q.lasso.as_ref().is_some_and(|l| !point_in_polygon(l, *p))
                {
                    continue;
                }
                samples.push(SampleRef {
                    track: ti,
                    sample: j,
                });
            }
        }
        tracks.clear();
        Selection::from_samples(set, samples)
    }

    /// A selection of explicit samples (sorted and deduplicated here).
    ///
    /// # Errors
    /// [`EditError::SelectionMismatch`] for a sample the set does not have,
    /// [`EditError::NoHull`] for fewer than 3 distinct positions.
    pub fn from_samples(
        set: &TrackSet,
        mut samples: Vec<SampleRef>,
    ) -> Result<Selection, EditError> {
        samples.sort_unstable();
        samples.dedup();
        for s in &samples {
            if set
                .tracks
                .get(s.track)
                .is_none_or(|t| s.sample >= t.points.len())
            {
                return Err(EditError::SelectionMismatch {
                    track: s.track,
                    sample: s.sample,
                });
            }
        }
        let mut pts: Vec<[u64; 2]> = samples
            .iter()
            .map(|s| {
                let p = set.tracks[s.track].points[s.sample].add_scalar(0.0);
                [p.x.to_bits(), p.y.to_bits()]
            })
            .collect();
        pts.sort_unstable();
        pts.dedup();
        if pts.len() < 3 {
            return Err(EditError::NoHull {
                distinct: pts.len(),
            });
        }
        Ok(Selection { samples })
    }

    /// The selected samples, sorted by track then sample.
    pub fn samples(&self) -> &[SampleRef] {
        &self.samples
    }

    /// Number of selected samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Always `false`: a selection holds at least three samples.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The distinct track indices, ascending.
    pub fn tracks(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.samples.iter().map(|s| s.track).collect();
        v.dedup();
        v
    }

    /// The selected positions, in selection order.
    ///
    /// # Errors
    /// [`EditError::SelectionMismatch`] when `set` lacks a selected sample.
    pub fn points(&self, set: &TrackSet) -> Result<Vec<Vec2>, EditError> {
        self.samples
            .iter()
            .map(|s| {
                set.tracks
                    .get(s.track)
                    .and_then(|t| t.points.get(s.sample))
                    .copied()
                    .ok_or(EditError::SelectionMismatch {
                        track: s.track,
                        sample: s.sample,
                    })
            })
            .collect()
    }

    /// Position of `r` in the selection, if selected.
    pub fn index_of(&self, r: SampleRef) -> Option<usize> {
        self.samples.binary_search(&r).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::edit::tracks::Track;

    fn set() -> TrackSet {
        let tracks = (0..4)
            .map(|i| {
                let pts = (0..10)
                    .map(|j| Vec2::new(j as f64, i as f64))
                    .collect::<Vec<_>>();
                let ts = (0..10).map(|j| j as f64 * 0.5).collect();
                Track::linked(100 + i as u64, pts, ts)
            })
            .collect();
        TrackSet {
            tracks,
            step_s: 0.5,
        }
    }

    #[test]
    fn criteria_combine_by_intersection() {
        let s = set();
        let q = SelectionQuery::default()
            .ids(&[101, 102])
            .rect(Rect {
                min: [2.0, 0.0],
                max: [5.0, 10.0],
            })
            .window(1.0, 2.0);
        let sel = Selection::select(&s, &q).unwrap();
        // Samples 2..=4 (x in [2, 5], t in [1, 2]) of tracks 1 and 2.
        assert_eq!(sel.len(), 6);
        assert_eq!(sel.tracks(), vec![1, 2]);
        assert!(sel.samples().iter().all(|r| (2..=4).contains(&r.sample)));
    }

    #[test]
    fn lasso_selects_inside() {
        let s = set();
        let lasso = [
            Vec2::new(-0.5, -0.5),
            Vec2::new(3.5, -0.5),
            Vec2::new(-0.5, 3.5),
        ];
        let sel = Selection::select(&s, &SelectionQuery::default().lasso(&lasso)).unwrap();
        for r in sel.samples() {
            let p = s.tracks[r.track].points[r.sample];
            assert!(p.x + p.y <= 3.0 + 1e-12);
        }
        assert!((6..=10).contains(&sel.len()), "{}", sel.len());
    }

    #[test]
    fn unknown_id_and_no_hull_are_errors() {
        let s = set();
        assert_eq!(
            Selection::select(&s, &SelectionQuery::default().ids(&[7])),
            Err(EditError::UnknownId { id: 7 })
        );
        let q = SelectionQuery::default().ids(&[100]).window(0.0, 0.5);
        assert_eq!(
            Selection::select(&s, &q),
            Err(EditError::NoHull { distinct: 2 })
        );
        let bad = SelectionQuery::default().lasso(&[Vec2::zeros(), Vec2::x()]);
        assert_eq!(
            Selection::select(&s, &bad),
            Err(EditError::BadLasso { vertices: 2 })
        );
    }
}
