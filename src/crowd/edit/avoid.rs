//! Collision avoidance by retiming, crowd-motion-editing section 4.1.2 (eqs. 18–28,
//! Algorithm 3): the spatial tracks stay as they are; the times at which people
//! reach their positions move so that no two come closer than the threshold.
//!
//! Each round (Algorithm 3) detects collisions ([`detect`]), then, worst pair first
//! and each person at most once per round:
//!
//! 1. the time separation needed at the collision point is estimated (eqs. 20–22):
//!    `dt = (D_threshold + margin − d_min) / v`, with `v` the slower of the two
//!    people's speeds on their colliding pieces (the faster one's if the slower
//!    stands still). Ours: `v` is replaced by the speed at which a time offset
//!    moves the two apart across their relative path, `|v_i × v_j| / |v_i − v_j|`
//!    (never more than eq. 20's `v`; equal to `v / √2` for equal speeds crossing
//!    at right angles, far less for nearly head-on walkers, for whom eq. 22 alone
//!    needs many rounds), bounded so `dt` is at most [`MAX_DT_FACTOR`] times
//!    eq. 22's;
//! 2. the two colliding pieces are retimed (eqs. 18, 19, 23) — see `retime_pair`;
//! 3. each of the two people's whole temporal tracks is re-solved with the retimed
//!    nodes fixed (eq. 28) — see `smooth_track`.
//!
//! Rounds repeat until nothing collides or [`AvoidParams::max_iterations`] is
//! reached. A pair that retiming cannot separate (both standing still, no feasible
//! retiming) is reported in [`AvoidReport::remaining`]; nothing panics.
//!
//! The work is bounded whatever the input: each round looks at no more than the
//! [`DEFAULT_KEEP`](super::DEFAULT_KEEP) closest pairs detection keeps (when more collide, the next
//! round detects again and takes the next closest), and the people of a
//! [`Cluster`](super::Cluster) of detection (on one identical track, for instance
//! standing at one point, or standing together within the threshold) are left as
//! they are: their pairs, and their pairs with anyone else, are
//! not retimed, and each cluster is one [`Remaining`] ([`Stuck::Cluster`]) for its
//! first two members.

use super::avoid_params::{
    check_params, AvoidError, AvoidParams, AvoidReport, Remaining, Stuck, MIN_PACE_LENGTH_M,
};
use super::avoid_shift as shift;
use super::avoid_solve::{companions, largest_shift, separate_pair, PairFailure, PairState};
use super::collide::{detect, Approach, Collisions, PairCollision};
use super::tracks::TrackSet;
use std::collections::{HashMap, HashSet};

/// Retimes the tracks so no two people come closer than `params.threshold_m`
/// (section 4.1.2, Algorithm 3). Positions are never changed; times stay strictly
/// increasing and non-negative when they start so.
///
/// # Formula
/// Eqs. 20–22 for the separation, eqs. 18, 19 and 23 for the colliding pieces
/// (`retime_pair`), eq. 28 for the whole tracks (`smooth_track`).
///
/// # Complexity
/// Per round one [`detect`] and O(n) per retimed person of n samples.
///
/// # Errors
/// [`AvoidError`]: parameters out of range, a bad threshold or a track set breaking
/// [`TrackSet::validate`]. Pairs that cannot be separated are not errors: they are
/// in [`AvoidReport::remaining`].
pub fn avoid(set: &mut TrackSet, params: &AvoidParams) -> Result<AvoidReport, AvoidError> {
    avoid_around(set, params, &[])
}

/// As [`avoid`], but only the pairs with one of `people` (indices into `set`) are
/// worked on; everyone else's collisions are left as they are (and counted in
/// the report). An empty `people` means everyone. The daemon's edit mode uses it
/// after a drag: the people dragged and whoever they now meet are retimed, not
/// strangers who happened to collide already.
///
/// # Errors
/// As [`avoid`].
pub fn avoid_around(
    set: &mut TrackSet,
    params: &AvoidParams,
    people: &[usize],
) -> Result<AvoidReport, AvoidError> {
    avoid_around_leaving(set, params, people, &HashSet::new())
}

/// As [`avoid_around`], but the pairs in `leave` (track indices, the smaller
/// first) are left as they are, like strangers' pairs: the daemon's edit mode
/// leaves the pairs a drag did not bring (two people who walked together before
/// the edit and still do), so that only the people the edit brought into
/// collision are retimed.
///
/// # Errors
/// As [`avoid`].
pub fn avoid_around_leaving(
    set: &mut TrackSet,
    params: &AvoidParams,
    people: &[usize],
    leave: &HashSet<(usize, usize)>,
) -> Result<AvoidReport, AvoidError> {
    check_params(params)?;
    let n = set.tracks.len();
    let original: Vec<Vec<f64>> = set.tracks.iter().map(|t| t.times_s.clone()).collect();
    // Each person's schedule the piece retimings smooth towards (eq. 28's `t`):
    // the input's times moved by the rigid shifts made so far (`shift`), so a
    // later retiming does not pull a shifted person back.
    let mut base = original.clone();
    let boxes = shift::boxes(set);
    let shifts_s = shift::candidates_s(params.max_shift_s);
    // Groups whose every shift was tried (each group is tried once: a rigid
    // shift that failed is rarely the answer after others moved, and the piece
    // retimings still get their pairs), and how many shifts were kept.
    let mut shift_tried: HashSet<Vec<usize>> = HashSet::new();
    let mut shifts_kept = 0;
    let collisions = detect(set, params.threshold_m)?;
    let pairs_before = collisions.pair_count();
    let closest_before_m = collisions.closest().map(|q| q.closest.distance_m);
    // No retiming may bring two people closer than the input's closest pair.
    let floor = closest_before_m.unwrap_or(f64::INFINITY);
    let limits = shift::Limits {
        threshold_m: params.threshold_m,
        max_shift_s: params.max_shift_s,
        floor_m: floor,
        input: &original,
    };
    // People in clusters are left as they are (their tracks are never retimed, so
    // the clusters stay what they were).
    let mut in_cluster = vec![false; n];
    let mut in_collision = vec![false; n];
    for c in &collisions.clusters {
        for &k in &c.members {
            in_cluster[k] = true;
            in_collision[k] = true;
        }
    }
    for q in &collisions.pairs {
        in_collision[q.a] = true;
        in_collision[q.b] = true;
    }
    let people_in_collision = in_collision.iter().filter(|&&x| x).count();
    let mut in_scope = vec![people.is_empty(); n];
    for &k in people {
        if let Some(x) = in_scope.get_mut(k) {
            *x = true;
        }
    }
    let workable = |q: &PairCollision| {
        !in_cluster[q.a]
            && !in_cluster[q.b]
            && (in_scope[q.a] || in_scope[q.b])
            && !leave.contains(&(q.a.min(q.b), q.a.max(q.b)))
    };
    // The colliding pairs as retimings change them: a retiming changes two people,
    // so only their pairs are detected again, as long as every pair is known
    // (`complete`); else each round detects everything again.
    let mut complete = collisions.is_complete();
    let mut current: Vec<PairCollision> = collisions.pairs.clone();
    let mut stuck: HashMap<(usize, usize), Stuck> = HashMap::new();
    let mut pins: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let (mut iterations, mut retimings, mut corrections, mut undone) = (0, 0, 0, 0);
    let mut orders = HashMap::new();
    let mut kept_last_round = false;
    // The round in which each person last changed, and in which each pair's
    // retiming last failed to help.
    let mut changed_at = vec![0usize; n];
    let mut failed_at: HashMap<(usize, usize), usize> = HashMap::new();
    while iterations < params.max_iterations {
        if !complete {
            let again = detect(set, params.threshold_m)?;
            complete = again.is_complete();
            current = again.pairs.clone();
        }
        // A retiming that did not help may help once one of the two has moved
        // (retrying every such pair after every change anywhere costs a
        // detection per pair per round on a dense file, for little).
        if kept_last_round {
            stuck.retain(|k, w| {
                *w != Stuck::NoImprovement || {
                    let at = failed_at.get(k).copied().unwrap_or(0);
                    changed_at[k.0] <= at && changed_at[k.1] <= at
                }
            });
        }
        let mut pairs: Vec<PairCollision> = current
            .iter()
            .filter(|q| workable(q) && !stuck.contains_key(&(q.a, q.b)))
            .copied()
            .collect();
        if pairs.is_empty() {
            break;
        }
        iterations += 1;
        kept_last_round = false;
        pairs.sort_by(|x, y| x.closest.distance_m.total_cmp(&y.closest.distance_m));
        pairs.retain(|q| {
            let together = companions(set, q, params.companion_rel_speed);
            if together {
                stuck.insert((q.a, q.b), Stuck::Companions);
            }
            !together
        });
        let mut touched = vec![false; n];
        // Rigid shifts first: one side of each connected part of the pairs (for
        // two crossing crowds, one crowd), then (below) each person of a pair alone.
        for part in shift::sides(n, &pairs) {
            for side in part
                .iter()
                .filter(|s| s.len() > 1 || part[0].len() + part[1].len() > 2)
            {
                if side.is_empty() || side.iter().any(|&k| touched[k]) || shift_tried.contains(side)
                {
                    continue;
                }
                match shift::best_shift(set, &boxes, side, &limits, &shifts_s) {
                    Some(sh) => {
                        apply_shift(set, &mut base, &mut pins, &sh);
                        for &k in &sh.group {
                            changed_at[k] = iterations;
                        }
                        refresh_after_shift(set, &boxes, params, &sh, &mut current, &mut complete)?;
                        for &k in &sh.group {
                            touched[k] = true;
                        }
                        shifts_kept += 1;
                        kept_last_round = true;
                        break;
                    }
                    None => {
                        shift_tried.insert(side.clone());
                    }
                }
            }
        }
        for q in &pairs {
            if touched[q.a] || touched[q.b] {
                continue;
            }
            let key = (q.a, q.b);
            // One of the two shifted whole, the smaller shift of the two.
            let mut alone: Option<shift::Shift> = None;
            for k in [q.a, q.b] {
                let g = vec![k];
                if shift_tried.contains(&g) {
                    continue;
                }
                match shift::best_shift(set, &boxes, &g, &limits, &shifts_s) {
                    Some(sh) if alone.as_ref().is_none_or(|a| sh.dt_s.abs() < a.dt_s.abs()) => {
                        alone = Some(sh);
                    }
                    Some(_) => {}
                    None => {
                        shift_tried.insert(g);
                    }
                }
            }
            if let Some(sh) = alone {
                apply_shift(set, &mut base, &mut pins, &sh);
                for &k in &sh.group {
                    changed_at[k] = iterations;
                }
                refresh_after_shift(set, &boxes, params, &sh, &mut current, &mut complete)?;
                touched[q.a] = true;
                touched[q.b] = true;
                shifts_kept += 1;
                kept_last_round = true;
                continue;
            }
            // The pairs of these two now (from the list when it is whole): how
            // many, and how deep into the threshold they reach in all.
            let depth = |ps: &mut dyn Iterator<Item = &PairCollision>| -> (usize, f64) {
                ps.fold((0, 0.0), |(n, d), p| {
                    (
                        n + 1,
                        d + (params.threshold_m - p.closest.distance_m).max(0.0),
                    )
                })
            };
            let before = if complete {
                depth(
                    &mut current
                        .iter()
                        .filter(|p| p.a == q.a || p.b == q.a || p.a == q.b || p.b == q.b),
                )
            } else {
                let c = shift::involving_near(set, &boxes, &pair_of(q), params.threshold_m)?;
                if c.is_complete() {
                    depth(&mut c.pairs.iter())
                } else {
                    (c.pair_count(), f64::INFINITY)
                }
            };
            let saved = PairState::save(set, &pins, &orders, q);
            let verdict =
                match separate_pair(set, q, params, &base, &original, &mut orders, &mut pins) {
                    Err(PairFailure::Collide(e)) => return Err(e.into()),
                    Err(PairFailure::Stuck(why)) => Err(why),
                    Ok(c) => {
                        let after =
                            shift::involving_near(set, &boxes, &pair_of(q), params.threshold_m)?;
                        let closest = after
                            .closest()
                            .map_or(f64::INFINITY, |p| p.closest.distance_m);
                        let now = if after.is_complete() {
                            depth(&mut after.pairs.iter())
                        } else {
                            (after.pair_count(), f64::INFINITY)
                        };
                        // Kept only when it makes things better (the others' pairs
                        // are as they were): fewer colliding pairs, or as many
                        // reaching less deep into the threshold; and nobody closer
                        // than the input's closest pair. So the number of colliding
                        // pairs never grows and the closest approach never shrinks.
                        let better =
                            now.0 < before.0 || (now.0 == before.0 && now.1 < before.1 - 1e-9);
                        if better && closest >= floor {
                            Ok((c, after))
                        } else {
                            undone += 1;
                            Err(Stuck::NoImprovement)
                        }
                    }
                };
            match verdict {
                Ok((c, after)) => {
                    corrections += c;
                    retimings += 1;
                    touched[q.a] = true;
                    touched[q.b] = true;
                    changed_at[q.a] = iterations;
                    changed_at[q.b] = iterations;
                    kept_last_round = true;
                    if complete {
                        current.retain(|p| !(p.a == q.a || p.b == q.a || p.a == q.b || p.b == q.b));
                        current.extend(after.pairs.iter().copied());
                        complete = after.is_complete();
                    }
                }
                Err(why) => {
                    saved.restore(set, &mut pins, &mut orders);
                    stuck.insert(key, why);
                    failed_at.insert(key, iterations);
                }
            }
        }
    }
    // The report's pairs from a full detection; the input back if the result is
    // worse on either count (each kept retiming made things better, so this is a
    // safety net).
    let mut after = detect(set, params.threshold_m)?;
    let closest = |c: &Collisions| c.closest().map(|q| q.closest.distance_m);
    let worse = after.pair_count() > pairs_before
        || match (closest(&after), closest_before_m) {
            (Some(a), Some(b)) => a < b,
            (Some(_), None) => true,
            _ => false,
        };
    if worse {
        for (t, t0) in set.tracks.iter_mut().zip(&original) {
            t.times_s.clone_from(t0);
        }
        after = detect(set, params.threshold_m)?;
    }
    let remaining = remaining_of(set, &after, &in_cluster, &stuck);
    let mut total_abs_dt_s = 0.0;
    let mut max_speed_change_pct: f64 = 0.0;
    let mut shifts: Vec<f64> = Vec::new();
    for (tr, t0) in set.tracks.iter().zip(&original) {
        total_abs_dt_s += tr
            .times_s
            .iter()
            .zip(t0)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>();
        let shift = largest_shift(&tr.times_s, t0);
        if shift > 0.0 {
            shifts.push(shift);
        }
        for j in tr.segments() {
            if (tr.points[j + 1] - tr.points[j]).norm() < MIN_PACE_LENGTH_M {
                continue;
            }
            let ratio = (t0[j + 1] - t0[j]) / (tr.times_s[j + 1] - tr.times_s[j]);
            max_speed_change_pct = max_speed_change_pct.max((ratio - 1.0).abs() * 100.0);
        }
    }
    shifts.sort_by(f64::total_cmp);
    let median_shift_s = match shifts.len() {
        0 => 0.0,
        k if k % 2 == 1 => shifts[k / 2],
        k => 0.5 * (shifts[k / 2 - 1] + shifts[k / 2]),
    };
    let companions = remaining
        .iter()
        .filter(|r| r.why == Stuck::Companions)
        .count();
    Ok(AvoidReport {
        iterations,
        pairs_before,
        pairs_after: after.pair_count(),
        retimings,
        remaining,
        total_abs_dt_s,
        max_speed_change_pct,
        corrections,
        people_in_collision,
        retimed_people: shifts.len(),
        median_shift_s,
        max_shift_s: shifts.last().copied().unwrap_or(0.0),
        max_shift_bound_s: params.max_shift_s,
        companions,
        undone,
        closest_before_m,
        closest_after_m: closest(&after),
        reverted: worse,
        shifts: shifts_kept,
    })
}

/// Makes a rigid shift: every time of the group, its pins and its schedule move
/// by `dt_s`.
fn apply_shift(
    set: &mut TrackSet,
    base: &mut [Vec<f64>],
    pins: &mut [Vec<(usize, f64)>],
    sh: &shift::Shift,
) {
    for &k in &sh.group {
        for t in &mut set.tracks[k].times_s {
            *t += sh.dt_s;
        }
        for t in &mut base[k] {
            *t += sh.dt_s;
        }
        for pin in &mut pins[k] {
            pin.1 += sh.dt_s;
        }
    }
}

/// After `group` changed: their pairs in `current` replaced by a detection of
/// theirs (when the list is whole; otherwise the next round detects everything).
fn refresh(
    set: &TrackSet,
    boxes: &[(crate::geom::Vec2, crate::geom::Vec2)],
    p: &AvoidParams,
    group: &[usize],
    current: &mut Vec<PairCollision>,
    complete: &mut bool,
) -> Result<(), AvoidError> {
    if !*complete {
        return Ok(());
    }
    let found = shift::involving_near(set, boxes, group, p.threshold_m)?;
    current.retain(|q| !(who_has(group, q.a) || who_has(group, q.b)));
    current.extend(found.pairs.iter().copied());
    *complete = found.is_complete();
    Ok(())
}

/// After a rigid shift: when it left the group no pair with anyone outside (its
/// evaluation is exact), those pairs are dropped from `current` without a
/// detection (pairs inside the group do not change); else as [`refresh`].
fn refresh_after_shift(
    set: &TrackSet,
    boxes: &[(crate::geom::Vec2, crate::geom::Vec2)],
    p: &AvoidParams,
    sh: &shift::Shift,
    current: &mut Vec<PairCollision>,
    complete: &mut bool,
) -> Result<(), AvoidError> {
    if sh.pairs_left == 0 {
        current.retain(|q| who_has(&sh.group, q.a) == who_has(&sh.group, q.b));
        // Pairs inside the group meet dt later (or earlier), at the same places.
        for q in current.iter_mut() {
            if who_has(&sh.group, q.a) {
                q.closest.t_s += sh.dt_s;
            }
        }
        return Ok(());
    }
    refresh(set, boxes, p, &sh.group, current, complete)
}

/// The two people of a pair as a sorted group.
fn pair_of(q: &PairCollision) -> [usize; 2] {
    [q.a.min(q.b), q.a.max(q.b)]
}

fn who_has(group: &[usize], k: usize) -> bool {
    group.binary_search(&k).is_ok()
}

/// The pairs that still collide, and why: each cluster once (its first two
/// members), then the kept pairs.
fn remaining_of(
    set: &TrackSet,
    after: &Collisions,
    in_cluster: &[bool],
    stuck: &HashMap<(usize, usize), Stuck>,
) -> Vec<Remaining> {
    let mut out: Vec<Remaining> = after
        .clusters
        .iter()
        .map(|c| Remaining {
            pair: PairCollision {
                a: c.members[0],
                b: c.members[1],
                id_a: c.first_id,
                id_b: set.tracks[c.members[1]].id,
                closest: Approach {
                    t_s: c.start_s,
                    distance_m: 0.0,
                    at_a: c.place,
                    at_b: c.place,
                    sample_a: 0,
                    sample_b: 0,
                    moving_a: false,
                    moving_b: false,
                },
                events: 1,
            },
            why: Stuck::Cluster,
        })
        .collect();
    out.extend(after.pairs.iter().map(|q| Remaining {
        pair: *q,
        why: if in_cluster[q.a] || in_cluster[q.b] {
            Stuck::Cluster
        } else {
            stuck
                .get(&(q.a, q.b))
                .copied()
                .unwrap_or(Stuck::IterationLimit)
        },
    }));
    out
}

#[cfg(test)]
#[path = "avoid_tests.rs"]
mod tests;
