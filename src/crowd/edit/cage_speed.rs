//! Speed correction after a spatial edit (crowd-motion-editing section 3.2, eq. 9):
//! the edited tracks re-timed so that every segment keeps its pre-edit speed.

use super::error::EditError;
use super::tracks::TrackSet;

/// Fewest speed-corrected interval, as a fraction of the pre-edit interval: a segment
/// the edit shrank to (nearly) nothing keeps at least this share of its time, so times
/// stay strictly increasing.
pub const MIN_INTERVAL_FRACTION: f64 = 1e-3;

/// Speed ratios (after / before) of the retimed segments.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SpeedReport {
    /// Segments considered (linked, moving before the edit).
    pub segments: usize,
    /// Smallest and largest speed ratio after the spatial edit, before correction.
    pub edited_ratio: (f64, f64),
    /// Smallest and largest speed ratio after correction.
    pub corrected_ratio: (f64, f64),
}

/// Re-times the touched tracks so every linked segment's speed returns to its pre-edit
/// speed (eq. 9).
///
/// # Formula
/// Eq. 9's terms are independent, one per segment, and each vanishes at
/// `Δt'_j = Δt_j ‖p'_{j+1} − p'_j‖ / ‖p_{j+1} − p_j‖`, its unconstrained minimiser,
/// which is used; it is clamped below at [`MIN_INTERVAL_FRACTION`] `· Δt_j` so that
/// times stay strictly increasing. A segment that did not move before the edit
/// (`‖p‖ = 0`) and every gap (unlinked pair) keeps its interval. The first time of each
/// track is kept; later samples shift by the accumulated change.
///
/// # Errors
/// [`EditError::SelectionMismatch`] when `before` and `after` differ in shape for a
/// touched track (`sample` then names the first missing sample).
pub fn correct_speeds(
    before: &TrackSet,
    after: &mut TrackSet,
    touched: &[usize],
) -> Result<SpeedReport, EditError> {
    let mut rep = SpeedReport {
        segments: 0,
        edited_ratio: (f64::INFINITY, f64::NEG_INFINITY),
        corrected_ratio: (f64::INFINITY, f64::NEG_INFINITY),
    };
    for &ti in touched {
        let (Some(b), Some(a)) = (before.tracks.get(ti), after.tracks.get(ti)) else {
            return Err(EditError::SelectionMismatch {
                track: ti,
                sample: 0,
            });
        };
        if b.len() != a.len() || a.times_s.len() != a.len() || b.linked.len() != a.linked.len() {
            return Err(EditError::SelectionMismatch {
                track: ti,
                sample: b.len().min(a.len()),
            });
        }
        let a = &mut after.tracks[ti];
        let mut t = a.times_s[0];
        for j in 0..b.len().saturating_sub(1) {
            let dt = b.times_s[j + 1] - b.times_s[j];
            let l0 = (b.points[j + 1] - b.points[j]).norm();
            let l1 = (a.points[j + 1] - a.points[j]).norm();
            let new_dt = if b.linked[j] && l0 > 0.0 {
                let r = l1 / l0;
                rep.segments += 1;
                rep.edited_ratio.0 = rep.edited_ratio.0.min(r);
                rep.edited_ratio.1 = rep.edited_ratio.1.max(r);
                (dt * r).max(MIN_INTERVAL_FRACTION * dt)
            } else {
                dt
            };
            a.times_s[j] = t;
            t += new_dt;
            if b.linked[j] && l0 > 0.0 {
                let r = (l1 / new_dt) / (l0 / dt);
                rep.corrected_ratio.0 = rep.corrected_ratio.0.min(r);
                rep.corrected_ratio.1 = rep.corrected_ratio.1.max(r);
            }
        }
        if let Some(last) = a.times_s.last_mut() {
            *last = t;
        }
    }
    if rep.segments == 0 {
        rep.edited_ratio = (1.0, 1.0);
        rep.corrected_ratio = (1.0, 1.0);
    }
    Ok(rep)
}
