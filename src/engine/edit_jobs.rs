//! The edit mode's slow work (see `edit.rs`), run on the formation thread or, in
//! replays, in the tick: a drag on the group's cage, the release (speeds
//! corrected, people kept apart), a retime, the collisions of tracks; and the
//! views of tracks the engine publishes.

use super::edit_state::{
    AvoidSettings, CageBox, EditDone, EditDoneKind, EditJob, EditJobKind, HoldSpec, SelectRequest,
    Settled,
};
use crate::crowd::edit::{
    avoid_around_leaving, avoid_obstacles, correct_speeds, detect_keeping, point_in_polygon,
    push_samples_out, retime, samples_in_obstacles, AvoidParams, AvoidReport, Cage, Collisions,
    Handle, ObstacleParams, RetimeParams, SampleRef, Selection, TimeDrag, Track, TrackSet,
};
use crate::crowd::environment::Obstacle;
use crate::geom::Vec2;
use crate::vocab::{CollisionView, PreviewView, TrackView, TracksView};
use std::collections::HashSet;
use std::sync::Arc;

/// Pushes per sample at most when a sample the cage left inside an obstacle is
/// moved out on its own (a push may land in another part).
const PUSH_ROUNDS: usize = 4;

impl EditJob {
    /// Does the slow work (on the formation thread, or in the tick for replays).
    pub fn run(self) -> EditDone {
        let EditJob { epoch, grab, kind } = self;
        let kind = match kind {
            EditJobKind::Drag {
                base,
                selected,
                window_s,
                cage,
                params,
                handles,
                deltas,
                pins,
                version,
                source,
            } => {
                let mut cage = match cage {
                    Some(c) => Ok(c),
                    None => samples_of(&base, &selected, window_s)
                        .and_then(|sel| Cage::new(&base, &sel, &params))
                        .map(|c| CageBox(Box::new(c)))
                        .map_err(|e| e.to_string()),
                };
                let mut resolved = (Vec::new(), Vec::new());
                let mut at = (Vec::new(), Vec::new());
                let edited = match &mut cage {
                    Ok(CageBox(c)) => {
                        resolved = (resolve(c, &handles), resolve(c, &pins));
                        let drags = drags_of(c, &base, &resolved.0, &deltas);
                        let fixed = fixed_of(&resolved.1, &drags);
                        c.drag(&drags, &fixed)
                            .and_then(|()| {
                                at = (
                                    positions(c, drags.iter().map(|d| d.0)),
                                    positions(c, fixed.iter().copied()),
                                );
                                let mut set = (*base).clone();
                                c.apply(&mut set)?;
                                let view = tracks_view(&set, Some(&selected), version, &source);
                                Ok((Arc::new(set), Arc::new(view)))
                            })
                            .map_err(|e| e.to_string())
                    }
                    Err(e) => Err(e.clone()),
                };
                // The outline shown: the cage of the time window the fingers hold
                // (a path that comes back to a place has one cage per window, and
                // their hulls one after another are no polygon).
                let hull = cage
                    .as_ref()
                    .map(|c| {
                        let c = &c.0;
                        let held = resolved.0.iter().find_map(|&s| handle_of(s));
                        match held.and_then(|h| c.window_of(h)) {
                            Some(w) if c.window_count() > 1 => c.window(w).deformed_hull(),
                            _ => c.deformed_hull(),
                        }
                    })
                    .unwrap_or_default();
                EditDoneKind::Dragged {
                    cage: cage.ok(),
                    edited,
                    hull,
                    deltas,
                    handles: resolved.0,
                    pins: resolved.1,
                    handles_at: at.0,
                    pins_at: at.1,
                }
            }
            EditJobKind::Release {
                base,
                edited,
                selected,
                cage,
                handles,
                deltas,
                pins,
                obstacles,
                avoid,
                version,
                source,
            } => {
                let mut set = (*edited).clone();
                let obstacles = obstacles.as_deref().map_or(&[][..], |s| s.obstacles());
                let pushed = keep_out(
                    &mut set, &base, &selected, cage, &handles, &deltas, &pins, obstacles,
                );
                let result = pushed.and_then(|pushed| {
                    correct_speeds(&base, &mut set, &selected).map_err(|e| e.to_string())?;
                    settle(&base, set, avoid, &selected, version, &source, pushed)
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
                people,
                at_s,
                to_s,
                avoid,
                version,
                source,
            } => {
                let mut set = (*base).clone();
                let result = retime_people(&mut set, &people, at_s, to_s).and_then(|()| {
                    settle(&base, set, avoid, &people, version, &source, Vec::new())
                });
                EditDoneKind::Settled {
                    result,
                    release: false,
                }
            }
            EditJobKind::Select {
                set,
                request,
                version,
            } => EditDoneKind::Selected {
                result: select_people(&set, &request),
                request,
                version,
            },
        };
        EditDone { epoch, grab, kind }
    }
}

/// What a finger or a pin holds, on `cage`: a vertex asked for by place is the
/// hull vertex nearest it as deformed now.
fn resolve(cage: &Cage, specs: &[HoldSpec]) -> Vec<HoldSpec> {
    specs
        .iter()
        .map(|&s| match s {
            HoldSpec::NearVertex(p) => HoldSpec::Hull(
                (0..cage.hull().len())
                    .min_by(|&a, &b| {
                        (cage.deformed_vertex(a) - p)
                            .norm_squared()
                            .total_cmp(&(cage.deformed_vertex(b) - p).norm_squared())
                    })
                    .unwrap_or(0),
            ),
            other => other,
        })
        .collect()
}

fn handle_of(s: HoldSpec) -> Option<Handle> {
    match s {
        HoldSpec::Sample(r) => Some(Handle::Sample(r)),
        HoldSpec::Hull(i) => Some(Handle::Hull(i)),
        HoldSpec::NearVertex(_) => None,
    }
}

/// The drags of eq. 1: each resolved handle at its rest place (the sample in
/// `base`, or the rest hull vertex) moved by its finger's displacement.
fn drags_of(
    cage: &Cage,
    base: &TrackSet,
    held: &[HoldSpec],
    deltas: &[Vec2],
) -> Vec<(Handle, Vec2)> {
    held.iter()
        .zip(deltas)
        .filter_map(|(&s, &d)| {
            let rest = match s {
                HoldSpec::Sample(r) => base.tracks[r.track].points[r.sample],
                HoldSpec::Hull(i) => *cage.hull().get(i)?,
                HoldSpec::NearVertex(_) => return None,
            };
            Some((handle_of(s)?, rest + d))
        })
        .collect()
}

/// The fixed handles of eq. 6: the pins, less any a finger drags (a handle is
/// constrained once).
fn fixed_of(pins: &[HoldSpec], drags: &[(Handle, Vec2)]) -> Vec<Handle> {
    let mut fixed: Vec<Handle> = Vec::with_capacity(pins.len());
    for h in pins.iter().filter_map(|&s| handle_of(s)) {
        if !drags.iter().any(|d| d.0 == h) && !fixed.contains(&h) {
            fixed.push(h);
        }
    }
    fixed
}

fn positions(cage: &Cage, hs: impl Iterator<Item = Handle>) -> Vec<Vec2> {
    hs.filter_map(|h| cage.handle_position(h).ok()).collect()
}

/// Keeps the released group out of `obstacles` (section 4.2): the grab's cage is
/// adjusted with the fingers' drags and the pins kept, then every sample of the
/// group still inside an obstacle is moved out on its own. Returns the people
/// moved (track indices); nothing happens when no sample of the group is inside.
#[allow(clippy::too_many_arguments)]
fn keep_out(
    set: &mut TrackSet,
    base: &TrackSet,
    selected: &[usize],
    cage: Option<CageBox>,
    held: &[HoldSpec],
    deltas: &[Vec2],
    pins: &[HoldSpec],
    obstacles: &[Obstacle],
) -> Result<Vec<usize>, String> {
    if obstacles.is_empty()
        || samples_in_obstacles(set, selected, obstacles)
            .iter()
            .all(|&c| c == 0)
    {
        return Ok(Vec::new());
    }
    let before: Vec<Vec<Vec2>> = selected
        .iter()
        .map(|&k| set.tracks[k].points.clone())
        .collect();
    let params = ObstacleParams::default();
    if let Some(CageBox(mut c)) = cage {
        let mut keep = drags_of(&c, base, held, deltas);
        for h in fixed_of(pins, &keep) {
            if let Ok(p) = c.handle_position(h) {
                keep.push((h, p));
            }
        }
        avoid_obstacles(&mut c, obstacles, &keep, &params)
            .and_then(|_| c.apply(set))
            .map_err(|e| format!("obstacle avoidance: {e}"))?;
    }
    push_samples_out(set, selected, obstacles, params.clearance_m, PUSH_ROUNDS);
    Ok(selected
        .iter()
        .zip(&before)
        .filter(|(&k, b)| set.tracks[k].points != **b)
        .map(|(&k, _)| k)
        .collect())
}

/// Collisions avoided around `people` (everyone when empty), leaving the pairs
/// that were pairs in `base` (the tracks before the edit: the edit did not bring
/// them), then the result as the engine shows it: the tracks, the collisions
/// left, the `tracks` message and the preview's summary (`pushed`: the people
/// obstacle avoidance moved).
fn settle(
    base: &TrackSet,
    mut set: TrackSet,
    avoid: AvoidSettings,
    people: &[usize],
    version: u64,
    source: &Arc<str>,
    pushed: Vec<usize>,
) -> Result<Settled, String> {
    let times: Vec<Vec<f64>> = set.tracks.iter().map(|t| t.times_s.clone()).collect();
    let leave: HashSet<(usize, usize)> = if people.is_empty() {
        HashSet::new()
    } else {
        let old = detect_keeping(base, avoid.threshold_m, usize::MAX)
            .map_err(|e| format!("collision detection: {e}"))?;
        old.pairs
            .iter()
            .filter(|q| people.binary_search(&q.a).is_ok() || people.binary_search(&q.b).is_ok())
            .map(|q| (q.a.min(q.b), q.a.max(q.b)))
            .collect()
    };
    let (report, collisions) = keep_apart(&mut set, avoid, people, &leave)?;
    let retimed = set
        .tracks
        .iter()
        .zip(&times)
        .filter(|(t, before)| t.times_s != **before)
        .map(|(t, _)| t.id)
        .collect();
    let preview = PreviewView {
        retimed,
        pushed: pushed.iter().map(|&k| set.tracks[k].id).collect(),
        pairs_before: report.pairs_before,
        pairs_after: report.pairs_after,
        closest_before_m: report.closest_before_m,
        closest_after_m: report.closest_after_m,
    };
    let mut view = tracks_view(&set, None, version, source);
    view.preview = avoid.preview;
    Ok(Settled {
        set: Arc::new(set),
        collisions,
        view: Arc::new(view),
        preview,
    })
}

/// The people `request` picks (track indices, ascending): among its ids (all
/// when none), those with a sample inside its lasso (any, when none) whose time
/// is in its window (any, when none).
fn select_people(set: &TrackSet, request: &SelectRequest) -> Result<Vec<usize>, String> {
    let mut ids: Option<Vec<u64>> = request.ids.clone();
    if let Some(v) = &mut ids {
        v.sort_unstable();
    }
    let (lasso, window) = (request.lasso.as_deref(), request.window_s);
    let bounds = lasso.map(|l| {
        l.iter().fold(
            (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        )
    });
    let picked = set
        .tracks
        .iter()
        .enumerate()
        .filter(|(_, t)| ids.as_ref().is_none_or(|v| v.binary_search(&t.id).is_ok()))
        .filter(|(_, t)| {
            t.points.iter().zip(&t.times_s).any(|(p, ts)| {
                window.is_none_or(|(a, b)| *ts >= a && *ts <= b)
                    && lasso.is_none_or(|l| {
                        let (lo, hi) = bounds.unwrap_or_default();
                        p.x >= lo.x
                            && p.y >= lo.y
                            && p.x <= hi.x
                            && p.y <= hi.y
                            && point_in_polygon(l, *p)
                    })
            })
        })
        .map(|(k, _)| k)
        .collect();
    Ok(picked)
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
        preview: false,
    }
}

/// Every sample of the tracks `selected` (only those whose time is in
/// `window_s`, when given).
fn samples_of(
    set: &TrackSet,
    selected: &[usize],
    window_s: Option<(f64, f64)>,
) -> Result<Selection, crate::crowd::edit::EditError> {
    let samples = selected
        .iter()
        .flat_map(|&k| {
            let t = &set.tracks[k];
            (0..t.len())
                .filter(move |&j| {
                    window_s.is_none_or(|(a, b)| t.times_s[j] >= a && t.times_s[j] <= b)
                })
                .map(move |j| SampleRef {
                    track: k,
                    sample: j,
                })
        })
        .collect();
    Selection::from_samples(set, samples)
}

/// A temporal drag of the node nearest `at_s` to `to_s` (section 3.3) of each of
/// `people` (everyone when empty), each person's first and last node held; no one
/// else's times change.
fn retime_people(set: &mut TrackSet, people: &[usize], at_s: f64, to_s: f64) -> Result<(), String> {
    let all: Vec<usize> = (0..set.tracks.len())
        .filter(|&k| people.is_empty() || people.binary_search(&k).is_ok())
        .filter(|&k| set.tracks[k].len() >= 3)
        .collect();
    if all.is_empty() {
        return Err("no one to retime has three samples".into());
    }
    let sel = samples_of(set, &all, None).map_err(|e| e.to_string())?;
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

/// People kept apart by retiming (section 4.1.2) after an edit, around `people`
/// (the people it changed: they and whoever they now meet are retimed, not
/// strangers who collided already), or around everyone when empty; then the
/// collisions that remain, as published.
fn keep_apart(
    set: &mut TrackSet,
    settings: AvoidSettings,
    people: &[usize],
    leave: &HashSet<(usize, usize)>,
) -> Result<(AvoidReport, Vec<CollisionView>), String> {
    let params = AvoidParams {
        threshold_m: settings.threshold_m,
        ..AvoidParams::default()
    };
    let report = avoid_around_leaving(set, &params, people, leave)
        .map_err(|e| format!("collision avoidance: {e}"))?;
    Ok((report, collisions_of(set, settings.threshold_m)))
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
