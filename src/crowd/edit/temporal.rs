//! The temporal editor: dragging time nodes of the selected tracks
//! (crowd-motion-editing section 3.3, eqs. 10–12).
//!
//! Per selected track the unknowns `û` are the times of its selected samples; the
//! track's other samples keep their times and act as constants. A drag names one node
//! and its new time; its shift `Δ = t_new − t_old` is applied to every selected track
//! at that track's selected node nearest in time to `t_old` (the named node itself for
//! the named track), so a drag moves the whole selected group in time together. Fixed
//! nodes keep their times. Then, per track,
//!
//! ```text
//! min  ω_D² ‖D û − d‖² + ω_F² ‖F û − p‖²      s.t.  M û = h      (eqs. 10–12)
//! ```
//!
//! with `D û` the intervals between consecutive samples (every interval with a
//! selected end), `d` their pre-edit values, `F = diag(f)` the locality weights of
//! eq. 5 taken in index and time (`f_j = α |t_j − t_drag| e^{c_j − k} + β c_j`, `c_j`
//! the index distance to the nearest dragged node of the track) and `p` the pre-edit
//! times. The constrained nodes (dragged and fixed) are eliminated; what remains is a
//! tridiagonal positive definite system, solved by the Thomas algorithm.
//!
//! Times must stay strictly increasing: a drag that would reverse them is refused with
//! [`EditError::InfeasibleRetiming`] naming the person and node, and nothing is written.

use super::cage::{PAPER_ALPHA, PAPER_BETA, PAPER_K};
use super::error::EditError;
use super::select::{SampleRef, Selection};
use super::tracks::TrackSet;

/// Parameters of [`retime`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RetimeParams {
    /// ω_D, weight of keeping the intervals (eq. 11).
    pub w_d: f64,
    /// ω_F, weight of locality (eq. 12).
    pub w_f: f64,
    /// Eq. 5's α (1/s here).
    pub alpha: f64,
    /// Eq. 5's k (nodes).
    pub k: f64,
    /// Eq. 5's β (1/node).
    pub beta: f64,
}

impl Default for RetimeParams {
    fn default() -> Self {
        RetimeParams {
            w_d: 1.0,
            w_f: 1.0,
            alpha: PAPER_ALPHA,
            k: PAPER_K,
            beta: PAPER_BETA,
        }
    }
}

/// A time drag: node `node` to time `t_s` (seconds).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TimeDrag {
    /// The dragged node (a selected sample).
    pub node: SampleRef,
    /// Its new time (s).
    pub t_s: f64,
}

/// What [`retime`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct RetimeReport {
    /// The nodes dragged, after propagating each drag to every selected track, with
    /// their new times (s).
    pub dragged: Vec<(SampleRef, f64)>,
    /// Samples whose time changed.
    pub moved: usize,
    /// Largest time change of any sample (s).
    pub max_shift_s: f64,
}

/// Re-times the selected samples of `set` (see the module documentation).
///
/// # Complexity
/// O(selected samples + drags × selected tracks × samples per track).
///
/// # Errors
/// [`EditError::TimeNotFinite`]; [`EditError::UnknownHandle`] for a dragged or fixed
/// node outside the selection; [`EditError::ConflictingHandles`] for a node both
/// dragged and fixed, or dragged twice to different times;
/// [`EditError::SelectionMismatch`]; [`EditError::InfeasibleRetiming`]. On error `set` is
/// unchanged.
pub fn retime(
    set: &mut TrackSet,
    sel: &Selection,
    drags: &[TimeDrag],
    fixed: &[SampleRef],
    params: &RetimeParams,
) -> Result<RetimeReport, EditError> {
    let samples = sel.samples();
    for s in samples {
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
    for d in drags {
        if !d.t_s.is_finite() {
            return Err(EditError::TimeNotFinite { t_s: d.t_s });
        }
        if sel.index_of(d.node).is_none() {
            return Err(EditError::UnknownHandle {
                handle: format!("track {} sample {}", d.node.track, d.node.sample),
            });
        }
    }
    for f in fixed {
        if sel.index_of(*f).is_none() {
            return Err(EditError::UnknownHandle {
                handle: format!("track {} sample {}", f.track, f.sample),
            });
        }
    }
    if fixed.iter().any(|f| drags.iter().any(|d| d.node == *f)) {
        return Err(EditError::ConflictingHandles {
            reason: "a node is both dragged and fixed",
        });
    }
    // The named nodes first, then each drag propagated to the other selected tracks at
    // their selected node nearest in time (unless named, fixed or reached already).
    let mut dragged: Vec<(SampleRef, f64)> = Vec::new();
    for d in drags {
        match dragged.iter().find(|(n, _)| *n == d.node) {
            Some((_, t)) if *t != d.t_s => {
                return Err(EditError::ConflictingHandles {
                    reason: "a node is dragged to two different times",
                })
            }
            Some(_) => {}
            None => dragged.push((d.node, d.t_s)),
        }
    }
    let tracks = sel.tracks();
    for d in drags {
        let t_old = set.tracks[d.node.track].times_s[d.node.sample];
        let shift = d.t_s - t_old;
        for &ti in tracks.iter().filter(|&&ti| ti != d.node.track) {
            let times = &set.tracks[ti].times_s;
            let nearest = samples.iter().filter(|s| s.track == ti).min_by(|a, b| {
                (times[a.sample] - t_old)
                    .abs()
                    .total_cmp(&(times[b.sample] - t_old).abs())
            });
            if let Some(&node) = nearest {
                if !fixed.contains(&node) && !dragged.iter().any(|(n, _)| *n == node) {
                    dragged.push((node, times[node.sample] + shift));
                }
            }
        }
    }

    let mut new_times: Vec<(usize, Vec<f64>)> = Vec::new();
    for &ti in &tracks {
        let track = &set.tracks[ti];
        let len = track.len();
        let old = &track.times_s;
        let mut selected = vec![false; len];
        for s in samples.iter().filter(|s| s.track == ti) {
            selected[s.sample] = true;
        }
        // Constrained value per node: Some(time) for constants (unselected, fixed,
        // dragged), None for unknowns.
        let mut known: Vec<Option<f64>> = (0..len)
            .map(|j| if selected[j] { None } else { Some(old[j]) })
            .collect();
        for f in fixed.iter().filter(|f| f.track == ti) {
            known[f.sample] = Some(old[f.sample]);
        }
        let drag_nodes: Vec<(usize, f64)> = dragged
            .iter()
            .filter(|(n, _)| n.track == ti)
            .map(|(n, t)| (n.sample, *t))
            .collect();
        if drag_nodes.is_empty() {
            continue;
        }
        for &(j, t) in &drag_nodes {
            known[j] = Some(t);
        }
        // Locality weight (eq. 5 in index and time) of each node.
        let f: Vec<f64> = (0..len)
            .map(|j| {
                let (c, d) = drag_nodes
                    .iter()
                    .map(|&(s, _)| (s.abs_diff(j) as f64, (old[j] - old[s]).abs()))
                    .fold((f64::INFINITY, f64::INFINITY), |a, b| {
                        if b.0 < a.0 {
                            b
                        } else {
                            a
                        }
                    });
                params.alpha * d * (c - params.k).exp() + params.beta * c
            })
            .collect();
        // Tridiagonal normal equations over the free nodes (indexed by sample).
        let wd = params.w_d * params.w_d;
        let wf = params.w_f * params.w_f;
        let mut diag = vec![0.0; len];
        let mut off = vec![0.0; len]; // off[j]: coupling of j and j + 1
        let mut rhs = vec![0.0; len];
        for j in 0..len {
            if known[j].is_none() {
                diag[j] += wf * f[j] * f[j];
                rhs[j] += wf * f[j] * f[j] * old[j];
            }
        }
        for j in 0..len.saturating_sub(1) {
            if !(selected[j] || selected[j + 1]) {
                continue;
            }
            let d = old[j + 1] - old[j];
            // Term wd (u_{j+1} − u_j − d)².
            match (known[j], known[j + 1]) {
                (None, None) => {
                    diag[j] += wd;
                    diag[j + 1] += wd;
                    off[j] -= wd;
                    rhs[j] -= wd * d;
                    rhs[j + 1] += wd * d;
                }
                (None, Some(b)) => {
                    diag[j] += wd;
                    rhs[j] += wd * (b - d);
                }
                (Some(a), None) => {
                    diag[j + 1] += wd;
                    rhs[j + 1] += wd * (a + d);
                }
                (Some(_), Some(_)) => {}
            }
        }
        let mut u: Vec<f64> = known
            .iter()
            .zip(old)
            .map(|(k, o)| k.unwrap_or(*o))
            .collect();
        // Thomas algorithm on each run of free nodes (runs are independent: a known
        // node between them has been moved to the right-hand side).
        let mut j = 0;
        while j < len {
            if known[j].is_some() {
                j += 1;
                continue;
            }
            let start = j;
            while j < len && known[j].is_none() {
                j += 1;
            }
            let end = j; // exclusive
            let mut c = vec![0.0; end - start];
            let mut y = vec![0.0; end - start];
            for i in start..end {
                let k = i - start;
                let lower = if k > 0 { off[i - 1] } else { 0.0 };
                let denom = diag[i] - if k > 0 { lower * c[k - 1] } else { 0.0 };
                c[k] = if i + 1 < end { off[i] / denom } else { 0.0 };
                y[k] = (rhs[i] - if k > 0 { lower * y[k - 1] } else { 0.0 }) / denom;
            }
            for k in (0..end - start).rev() {
                let next = if k + 1 < end - start {
                    c[k] * u[start + k + 1]
                } else {
                    0.0
                };
                u[start + k] = y[k] - next;
            }
        }
        for j in 1..len {
            if u[j].partial_cmp(&u[j - 1]) != Some(std::cmp::Ordering::Greater) {
                return Err(EditError::InfeasibleRetiming {
                    id: track.id,
                    sample: j,
                    t_s: u[j],
                    previous: j - 1,
                    previous_s: u[j - 1],
                });
            }
        }
        new_times.push((ti, u));
    }
    let mut rep = RetimeReport {
        dragged,
        moved: 0,
        max_shift_s: 0.0,
    };
    for (ti, u) in new_times {
        let t = &mut set.tracks[ti];
        for (old, new) in t.times_s.iter_mut().zip(u) {
            let d = (new - *old).abs();
            if d > 0.0 {
                rep.moved += 1;
                rep.max_shift_s = rep.max_shift_s.max(d);
            }
            *old = new;
        }
    }
    Ok(rep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::edit::select::SelectionQuery;
    use crate::crowd::edit::tracks::Track;
    use crate::geom::Vec2;

    fn set() -> TrackSet {
        let tracks = (0..3)
            .map(|i| {
                let pts = (0..30)
                    .map(|j| Vec2::new(0.6 * j as f64, i as f64))
                    .collect();
                let ts = (0..30).map(|j| 0.5 * j as f64 + 0.1 * i as f64).collect();
                Track::linked(10 + i as u64, pts, ts)
            })
            .collect();
        TrackSet {
            tracks,
            step_s: 0.5,
        }
    }

    fn r(track: usize, sample: usize) -> SampleRef {
        SampleRef { track, sample }
    }

    #[test]
    fn drag_lands_fixed_stay_times_increase() {
        let mut s = set();
        let before = s.clone();
        let sel = Selection::select(&s, &SelectionQuery::default().window(2.0, 12.0)).unwrap();
        let drag = TimeDrag {
            node: r(0, 10),
            t_s: 5.0 + 1.5,
        };
        let fixed = [r(0, 20)];
        let rep = retime(&mut s, &sel, &[drag], &fixed, &RetimeParams::default()).unwrap();
        assert!((s.tracks[0].times_s[10] - 6.5).abs() <= 1e-12);
        assert_eq!(s.tracks[0].times_s[20], before.tracks[0].times_s[20]);
        // Outside the window nothing moves.
        assert_eq!(s.tracks[0].times_s[2], before.tracks[0].times_s[2]);
        assert_eq!(s.tracks[0].times_s[29], before.tracks[0].times_s[29]);
        for t in &s.tracks {
            t.validate().unwrap();
        }
        // The drag reached the other tracks at their nearest node in time.
        assert!(rep.dragged.contains(&(r(1, 10), 5.1 + 1.5)));
        assert!((s.tracks[2].times_s[10] - (5.2 + 1.5)).abs() < 1e-12);
        // Locality: the dragged node's neighbour moves more than a node further off.
        let d9 = (s.tracks[0].times_s[9] - before.tracks[0].times_s[9]).abs();
        let d6 = (s.tracks[0].times_s[6] - before.tracks[0].times_s[6]).abs();
        assert!(d9 > d6, "{d9} {d6}");
    }

    #[test]
    fn reversing_time_is_refused_and_names_the_person() {
        let mut s = set();
        let before = s.clone();
        let sel = Selection::select(&s, &SelectionQuery::default().window(2.0, 12.0)).unwrap();
        let drag = TimeDrag {
            node: r(1, 10),
            t_s: 30.0,
        };
        let e = retime(&mut s, &sel, &[drag], &[], &RetimeParams::default()).unwrap_err();
        assert!(matches!(e, EditError::InfeasibleRetiming { .. }), "{e}");
        assert_eq!(s, before);
        let nan = TimeDrag {
            node: r(1, 10),
            t_s: f64::NAN,
        };
        assert!(matches!(
            retime(&mut s, &sel, &[nan], &[], &RetimeParams::default()),
            Err(EditError::TimeNotFinite { .. })
        ));
        let both = TimeDrag {
            node: r(1, 10),
            t_s: 5.0,
        };
        assert!(matches!(
            retime(&mut s, &sel, &[both], &[r(1, 10)], &RetimeParams::default()),
            Err(EditError::ConflictingHandles { .. })
        ));
    }
}
