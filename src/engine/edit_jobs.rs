//! The edit mode's slow work (see `edit.rs`), run on the formation thread or, in
//! replays, in the tick: a drag on the group's cage, the release (speeds
//! corrected, people kept apart), a retime, the collisions of tracks; and the
//! views of tracks the engine publishes.

use super::edit_state::{AvoidSettings, CageBox, EditDone, EditDoneKind, EditJob, EditJobKind};
use crate::crowd::edit::{
    avoid_around, correct_speeds, detect_keeping, retime, AvoidParams, Cage, Collisions, Handle,
    RetimeParams, SampleRef, Selection, TimeDrag, Track, TrackSet,
};
use crate::geom::Vec2;
use crate::vocab::{CollisionView, TrackView, TracksView};
use std::sync::Arc;

impl EditJob {
    /// Does the slow work (on the formation thread, or in the tick for replays).
    pub fn run(self) -> EditDone {
        let EditJob { epoch, grab, kind } = self;
        let kind = match kind {
            EditJobKind::Drag {
                base,
                selected,
                cage,
                params,
                handles,
                targets,
                version,
                source,
            } => {
                let mut cage = match cage {
                    Some(c) => Ok(c),
                    None => every_sample(&base, &selected)
                        .and_then(|sel| Cage::new(&base, &sel, &params))
                        .map(|c| CageBox(Box::new(c)))
                        .map_err(|e| e.to_string()),
                };
                let edited = match &mut cage {
                    Ok(CageBox(c)) => {
                        let drags: Vec<(Handle, Vec2)> = handles
                            .iter()
                            .map(|&h| Handle::Sample(h))
                            .zip(targets.iter().copied())
                            .collect();
                        c.drag(&drags, &[])
                            .and_then(|()| {
                                let mut set = (*base).clone();
                                c.apply(&mut set)?;
                                let view = tracks_view(&set, Some(&selected), version, &source);
                                Ok((Arc::new(set), Arc::new(view)))
                            })
                            .map_err(|e| e.to_string())
                    }
                    Err(e) => Err(e.clone()),
                };
                let hull = cage
                    .as_ref()
                    .map(|c| c.0.deformed_hull())
                    .unwrap_or_default();
                EditDoneKind::Dragged {
                    cage: cage.ok(),
                    edited,
                    hull,
                    targets,
                }
            }
            EditJobKind::Release {
                base,
                edited,
                selected,
                avoid,
                version,
                source,
            } => {
                let mut set = (*edited).clone();
                let result = correct_speeds(&base, &mut set, &selected)
                    .map_err(|e| e.to_string())
                    .and_then(|_| keep_apart(&mut set, avoid, &selected))
                    .map(|c| {
                        let view = Arc::new(tracks_view(&set, None, version, &source));
                        (Arc::new(set), c, view)
                    });
                EditDoneKind::Settled {
                    result,
                    release: true,
                }
            }
            EditJobKind::Check {
                set,
                threshold_m,
                version,
            } => EditDoneKind::Checked {
                collisions: collisions_of(&set, threshold_m),
                version,
            },
            EditJobKind::Retime {
                base,
                at_s,
                to_s,
                avoid,
                version,
                source,
            } => {
                let mut set = (*base).clone();
                let result = retime_all(&mut set, at_s, to_s)
                    .and_then(|()| keep_apart(&mut set, avoid, &[]))
                    .map(|c| {
                        let view = Arc::new(tracks_view(&set, None, version, &source));
                        (Arc::new(set), c, view)
                    });
                EditDoneKind::Settled {
                    result,
                    release: false,
                }
            }
        };
        EditDone { epoch, grab, kind }
    }
}

/// The `tracks` message of `set` at `version`: every person, or the people
/// `changed` (track indices).
pub(super) fn tracks_view(
    set: &TrackSet,
    changed: Option<&[usize]>,
    version: u64,
    source: &Arc<str>,
) -> TracksView {
    let view = |k: usize| {
        let t = &set.tracks[k];
        TrackView {
            id: t.id,
            points: t.points.clone(),
            times_s: t.times_s.clone(),
        }
    };
    let tracks = match changed {
        Some(ks) => ks.iter().map(|&k| view(k)).collect(),
        None => (0..set.tracks.len()).map(view).collect(),
    };
    TracksView {
        version,
        source: Arc::clone(source),
        tracks,
        full: changed.is_none(),
        span_s: set.span_s(),
    }
}

/// Every sample of the tracks `selected`.
fn every_sample(
    set: &TrackSet,
    selected: &[usize],
) -> Result<Selection, crate::crowd::edit::EditError> {
    let samples = selected
        .iter()
        .flat_map(|&k| {
            (0..set.tracks[k].len()).map(move |j| SampleRef {
                track: k,
                sample: j,
            })
        })
        .collect();
    Selection::from_samples(set, samples)
}

/// A temporal drag of every person's node nearest `at_s` to `to_s` (section 3.3),
/// each person's first and last node held.
fn retime_all(set: &mut TrackSet, at_s: f64, to_s: f64) -> Result<(), String> {
    let all: Vec<usize> = (0..set.tracks.len())
        .filter(|&k| set.tracks[k].len() >= 3)
        .collect();
    if all.is_empty() {
        return Err("no one has three samples to retime".into());
    }
    let sel = every_sample(set, &all).map_err(|e| e.to_string())?;
    let mut drags = Vec::new();
    let mut fixed = Vec::new();
    for &k in &all {
        let t = &set.tracks[k];
        let j = nearest_node(t, at_s);
        let last = t.len() - 1;
        if j == 0 || j == last {
            fixed.push(SampleRef {
                track: k,
                sample: j,
            });
            continue;
        }
        drags.push(TimeDrag {
            node: SampleRef {
                track: k,
                sample: j,
            },
            t_s: t.times_s[j] + (to_s - at_s),
        });
        fixed.push(SampleRef {
            track: k,
            sample: 0,
        });
        fixed.push(SampleRef {
            track: k,
            sample: last,
        });
    }
    fixed.sort_unstable();
    fixed.dedup();
    if drags.is_empty() {
        return Err(format!(
            "no one has a time node near {at_s} s between their first and last"
        ));
    }
    retime(set, &sel, &drags, &fixed, &RetimeParams::default())
        .map(|_| ())
        .map_err(|e| e.to_string())
}

pub(super) fn nearest_node(t: &Track, at_s: f64) -> usize {
    let j = t.times_s.partition_point(|&ts| ts < at_s).min(t.len() - 1);
    if j > 0 && (t.times_s[j] - at_s).abs() > (at_s - t.times_s[j - 1]).abs() {
        j - 1
    } else {
        j
    }
}

/// People kept apart by retiming (section 4.1.2), then the collisions that remain,
/// as published.
/// Collision avoidance after an edit: around `people` (the people a drag
/// moved: they and whoever they now meet are retimed, not strangers who
/// collided already), or around everyone when empty (a retime of everyone).
fn keep_apart(
    set: &mut TrackSet,
    settings: AvoidSettings,
    people: &[usize],
) -> Result<Vec<CollisionView>, String> {
    let params = AvoidParams {
        threshold_m: settings.threshold_m,
        ..AvoidParams::default()
    };
    avoid_around(set, &params, people).map_err(|e| format!("collision avoidance: {e}"))?;
    Ok(collisions_of(set, settings.threshold_m))
}

/// The most collisions an `edit` message lists: each cluster of people on one
/// identical track as one (its first two people, distance 0), then the earliest
/// events. Detection keeps no more than this, so a load of people at one point
/// costs memory and time in their number, not in their pairs.
pub const COLLISIONS_PUBLISHED: usize = 256;

/// The collisions of `set` as an `edit` message lists them (at most
/// [`COLLISIONS_PUBLISHED`]).
pub(super) fn collisions_of(set: &TrackSet, threshold_m: f64) -> Vec<CollisionView> {
    match detect_keeping(set, threshold_m, COLLISIONS_PUBLISHED) {
        Ok(c) => collision_views(set, &c),
        Err(e) => {
            log::warn!("edit: collisions could not be checked: {e}");
            Vec::new()
        }
    }
}

/// Where a person is shown at `t_s`, and whether they are on the scene then: on
/// their tracks, or at their first or last sample (or the sample before a gap).
pub(super) fn shown_position(t: &Track, t_s: f64) -> (Vec2, bool) {
    if let Some(p) = t.position_at(t_s) {
        return (p, true);
    }
    let j = t.times_s.partition_point(|&ts| ts <= t_s);
    (t.points[j.saturating_sub(1)], false)
}

pub(super) fn velocity_at(t: &Track, t_s: f64) -> Vec2 {
    let j = t.times_s.partition_point(|&ts| ts <= t_s);
    if j == 0 || j >= t.len() || !t.linked[j - 1] {
        return Vec2::zeros();
    }
    (t.points[j] - t.points[j - 1]) / (t.times_s[j] - t.times_s[j - 1])
}

fn collision_views(set: &TrackSet, c: &Collisions) -> Vec<CollisionView> {
    let clusters = c.clusters.iter().map(|k| CollisionView {
        a: k.first_id,
        b: set.tracks[k.members[1]].id,
        t_s: k.start_s,
        place: k.place,
        distance_m: 0.0,
    });
    let events = c.events_by_time().into_iter().map(|e| CollisionView {
        a: e.id_a,
        b: e.id_b,
        t_s: e.closest.t_s,
        place: e.closest.place(),
        distance_m: e.closest.distance_m,
    });
    clusters.chain(events).take(COLLISIONS_PUBLISHED).collect()
}
