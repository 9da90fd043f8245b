//! The edit mode's selection and preview commands (see `edit.rs`): `edit.select`
//! and the lasso drawn with one finger in open space (crowd-motion-editing
//! section 3.2's lasso and time-window selection; the people are picked on the
//! formation thread), and `edit.accept`.

use super::edit_state::{EditJob, EditJobKind, EditSelection, SelectRequest};
use super::error::CommandError;
use super::state::Engine;
use crate::crowd::edit::TrackSet;
use crate::geom::Vec2;
use crate::gesture::track::GestureTracks;
use crate::vocab::{MAX_LASSO_VERTICES, MAX_SELECT_IDS};
use std::sync::Arc;

/// A one-finger stroke is a lasso when it is at least this long on the glass (mm).
pub const LASSO_MIN_PATH_MM: f64 = 120.0;
/// … and ends within this fraction of its length from where it began (it closes
/// on itself).
pub const LASSO_CLOSE_FRACTION: f64 = 0.2;
/// … and encloses at least this area on the glass (mm², a 40 mm square): a
/// stroke out and back along one line encloses nothing.
pub const LASSO_MIN_AREA_MM2: f64 = 1600.0;
/// A lasso drawn on the table keeps at most this many of its samples.
pub const LASSO_KEPT_POINTS: usize = 256;

impl Engine {
    /// `edit.select`: the people with a sample inside `lasso` (m) whose time is in
    /// `window_s` (s), among `ids`, are picked off the control thread; none of the
    /// three clears the selection.
    pub(super) fn edit_select(
        &mut self,
        lasso: Option<&[[f64; 2]]>,
        window_s: Option<[f64; 2]>,
        ids: Option<&[u64]>,
    ) -> Result<(), CommandError> {
        let lasso: Option<Vec<Vec2>> = match lasso {
            Some(l) if l.len() < 3 || l.len() > MAX_LASSO_VERTICES => {
                return Err(CommandError::Edit(format!(
                    "edit.select: `lasso` needs 3 to {MAX_LASSO_VERTICES} points, got {}",
                    l.len()
                )))
            }
            Some(l) => match l
                .iter()
                .position(|p| !(p[0].is_finite() && p[1].is_finite()))
            {
                Some(i) => {
                    return Err(CommandError::Edit(format!(
                        "edit.select: lasso[{i}] is not a finite point"
                    )))
                }
                None => Some(l.iter().map(|p| Vec2::new(p[0], p[1])).collect()),
            },
            None => None,
        };
        let window_s = match window_s {
            Some([a, b]) if !(a.is_finite() && b.is_finite() && a <= b) => {
                return Err(CommandError::Edit(format!(
                    "edit.select: `window_s` must be [start, end] seconds with start <= end, got [{a}, {b}]"
                )))
            }
            w => w.map(|[a, b]| (a, b)),
        };
        let m = self.edit_mode_mut()?;
        if let Some(ids) = ids {
            indices_of(&m.set, ids, "edit.select")?;
        }
        let request = SelectRequest {
            ids: ids.map(<[u64]>::to_vec),
            lasso,
            window_s,
        };
        self.ask_selection(request);
        Ok(())
    }

    /// Sends `request` to the formation thread (replacing one still waiting), or
    /// clears the selection when it asks for nothing.
    fn ask_selection(&mut self, request: SelectRequest) {
        let epoch = self.edits.epoch;
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        if request.ids.is_none() && request.lasso.is_none() && request.window_s.is_none() {
            m.selection = None;
            self.edits
                .outbox
                .retain(|j| !matches!(j.kind, EditJobKind::Select { .. }));
            self.edits.view_dirty = true;
            return;
        }
        let job = EditJob {
            epoch,
            grab: 0,
            kind: EditJobKind::Select {
                set: Arc::clone(&m.set),
                request,
                version: m.version,
            },
        };
        match self
            .edits
            .outbox
            .iter_mut()
            .find(|j| matches!(j.kind, EditJobKind::Select { .. }))
        {
            Some(waiting) => *waiting = job,
            None => self.edits.outbox.push_back(job),
        }
    }

    /// The people a selection job picked: the selection for the next grab (a
    /// result for tracks of another version is used as long as the people are
    /// the same ones: an edit changes places and times, not who is in the set).
    pub(super) fn apply_selection(
        &mut self,
        result: Result<Vec<usize>, String>,
        request: SelectRequest,
        _version: u64,
    ) {
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        match result {
            Ok(tracks) => {
                let ids = tracks.iter().map(|&k| m.set.tracks[k].id).collect();
                if tracks.is_empty() {
                    log::info!("edit: the selection picked no one");
                }
                m.selection = Some(EditSelection {
                    tracks: tracks.into(),
                    ids,
                    window_s: request.window_s,
                    lasso: request.lasso,
                });
            }
            Err(e) => log::info!("edit: the selection could not be made: {e}"),
        }
        self.edits.view_dirty = true;
    }

    /// `edit.accept`: the edit shown as a preview is kept.
    pub(super) fn edit_accept(&mut self) -> Result<(), CommandError> {
        let m = self.edit_mode_mut()?;
        if m.preview.take().is_none() {
            return Err(CommandError::Edit(
                "no edit is shown as a preview (state is not `preview`)".into(),
            ));
        }
        self.edits.edits += 1;
        self.edits.view_dirty = true;
        Ok(())
    }

    /// A gesture in edit mode that is a lasso ([`lasso_on_glass`]) selects the
    /// people inside it (in the selection's time window, if it has one). Returns
    /// whether it was one.
    pub(super) fn edit_lasso(&mut self, tracks: &GestureTracks) -> bool {
        let Some(poly_mm) = lasso_on_glass(tracks) else {
            return false;
        };
        let Some(m) = self.edits.mode.as_ref() else {
            return false;
        };
        let window_s = m.selection.as_ref().and_then(|s| s.window_s);
        let (min, size) = (
            Vec2::new(self.world.min[0], self.world.min[1]),
            Vec2::new(self.world.width(), self.world.height()),
        );
        let glass = self.glass_mm;
        let lasso = poly_mm
            .iter()
            .map(|p| min + p.component_div(&glass).component_mul(&size))
            .collect();
        self.ask_selection(SelectRequest {
            ids: None,
            lasso: Some(lasso),
            window_s,
        });
        true
    }
}

/// Track indices of `ids` in `set`, ascending (an unknown id, or too many, is
/// refused naming the command).
pub(super) fn indices_of(
    set: &TrackSet,
    ids: &[u64],
    command: &str,
) -> Result<Vec<usize>, CommandError> {
    if ids.len() > MAX_SELECT_IDS {
        return Err(CommandError::Edit(format!(
            "{command}: at most {MAX_SELECT_IDS} `ids`, got {}",
            ids.len()
        )));
    }
    let mut by_id: Vec<(u64, usize)> = set
        .tracks
        .iter()
        .enumerate()
        .map(|(k, t)| (t.id, k))
        .collect();
    by_id.sort_unstable();
    let mut out = Vec::with_capacity(ids.len());
    for &id in ids {
        match by_id.binary_search_by_key(&id, |e| e.0) {
            Ok(i) => out.push(by_id[i].1),
            Err(_) => {
                return Err(CommandError::Edit(format!(
                    "{command}: no person has id {id}"
                )))
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// The stroke of a one-finger gesture that closes on itself (on the glass, mm):
/// at least [`LASSO_MIN_PATH_MM`] long, ending within [`LASSO_CLOSE_FRACTION`] of
/// its length from its start, enclosing at least [`LASSO_MIN_AREA_MM2`] (shoelace
/// formula). At most [`LASSO_KEPT_POINTS`] of its samples are kept. `None` for
/// anything else (several fingers, an open stroke, a tap).
pub fn lasso_on_glass(tracks: &GestureTracks) -> Option<Vec<Vec2>> {
    let [finger] = tracks.fingers.as_slice() else {
        return None;
    };
    let pts: Vec<Vec2> = finger.samples.iter().map(|s| s.mm).collect();
    if pts.len() < 4 {
        return None;
    }
    let length_mm: f64 = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let gap_mm = (pts[pts.len() - 1] - pts[0]).norm();
    let area_mm2 = 0.5
        * pts
            .iter()
            .zip(pts.iter().cycle().skip(1))
            .map(|(a, b)| a.x * b.y - b.x * a.y)
            .sum::<f64>()
            .abs();
    if length_mm < LASSO_MIN_PATH_MM
        || gap_mm > LASSO_CLOSE_FRACTION * length_mm
        || area_mm2 < LASSO_MIN_AREA_MM2
    {
        return None;
    }
    let stride = pts.len().div_ceil(LASSO_KEPT_POINTS);
    Some(pts.into_iter().step_by(stride).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gesture::track::{TouchTrack, TrackSample};
    use crate::vocab::Micros;

    fn stroke(points: impl Iterator<Item = Vec2>) -> GestureTracks {
        GestureTracks {
            fingers: vec![TouchTrack {
                samples: points
                    .enumerate()
                    .map(|(k, mm)| TrackSample {
                        t: Micros(k as u64 * 10_000),
                        mm,
                    })
                    .collect(),
            }],
        }
    }

    #[test]
    fn a_closed_loop_is_a_lasso_and_an_open_or_flat_stroke_is_not() {
        // A circle of radius 40 mm (length 251 mm, area 5027 mm²), 400 samples.
        let circle = |turns: f64| {
            stroke((0..=400).map(move |k| {
                let a = turns * std::f64::consts::TAU * k as f64 / 400.0;
                Vec2::new(100.0 + 40.0 * a.cos(), 100.0 + 40.0 * a.sin())
            }))
        };
        let l = lasso_on_glass(&circle(1.0)).expect("a closed circle");
        assert!(l.len() <= LASSO_KEPT_POINTS && l.len() > 100, "{}", l.len());
        // Three quarters: the end is 56.6 mm from the start, 30 % of 188 mm.
        assert!(lasso_on_glass(&circle(0.75)).is_none());
        // Out and back along a line: closed, but encloses nothing.
        let back = stroke((0..=200).map(|k| {
            let x = if k <= 100 { k as f64 } else { 200.0 - k as f64 };
            Vec2::new(x, 5.0)
        }));
        assert!(lasso_on_glass(&back).is_none());
        // Two fingers drawing circles are a gesture, not a lasso.
        let mut two = circle(1.0);
        two.fingers.push(two.fingers[0].clone());
        assert!(lasso_on_glass(&two).is_none());
    }

    #[test]
    fn ids_are_found_and_an_unknown_one_is_refused() {
        use crate::crowd::edit::Track;
        let set = TrackSet {
            tracks: [5u64, 3, 9]
                .iter()
                .map(|&id| Track::linked(id, vec![Vec2::zeros(); 2], vec![0.0, 1.0]))
                .collect(),
            step_s: 1.0,
        };
        assert_eq!(indices_of(&set, &[9, 5, 9], "x").unwrap(), vec![0, 2]);
        let e = indices_of(&set, &[4], "edit.select")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no person has id 4"), "{e}");
    }
}
