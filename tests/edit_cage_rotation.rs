//! The spatial editor as a user of `edit apply` sees it, on a parade three abreast:
//! a drag that turns the parade keeps its rows across its walking direction and
//! brings no two people together (the hull-shape term of eqs. 7–8 is rotation
//! invariant, the ARAP of eq. 2 is run to convergence), and a drag at one end of a
//! long parade leaves its far end where it was (the locality of eqs. 3 and 5).
//!
//! The parades are made here, by the same rule as `tests/engine_edit.rs`'s: three
//! files 0.8 m apart walking +x at 1.2 m/s, ranks 0.8 m behind one another, a sample
//! every 0.5 s.

use crowdtouch::crowd::edit::{detect, parse_script, run_script, ApplyParams, Track, TrackSet};
use crowdtouch::geom::Vec2;

/// Spacing between files and between ranks (m).
const SPACING_M: f64 = 0.8;
/// Walking speed (m/s).
const SPEED_M_S: f64 = 1.2;
/// Sample step (s).
const STEP_S: f64 = 0.5;
/// The pair threshold of the issue (m).
const THRESHOLD_M: f64 = 0.3;

/// `ranks` ranks of three walking `path_m` metres along +x; person `3 r + f` is
/// rank `r` (0 the front, starting at x = 0), file `f` (y = 0.8 f).
fn parade(ranks: usize, path_m: f64) -> TrackSet {
    let samples = (path_m / (SPEED_M_S * STEP_S)).round() as usize + 1;
    let times: Vec<f64> = (0..samples).map(|k| k as f64 * STEP_S).collect();
    let mut tracks = Vec::new();
    for r in 0..ranks {
        for f in 0..3 {
            let p0 = Vec2::new(-SPACING_M * r as f64, SPACING_M * f as f64);
            let points = times
                .iter()
                .map(|t| p0 + Vec2::new(SPEED_M_S * t, 0.0))
                .collect();
            tracks.push(Track::linked((3 * r + f) as u64, points, times.clone()));
        }
    }
    TrackSet {
        tracks,
        step_s: STEP_S,
    }
}

/// The largest angle (degrees) between a rank's row (its file 0 to file 2) and the
/// perpendicular of its middle person's walking direction, over every rank and
/// sample.
fn worst_row_angle_deg(set: &TrackSet) -> f64 {
    let mut worst: f64 = 0.0;
    for r in 0..set.tracks.len() / 3 {
        let (a, m, b) = (
            &set.tracks[3 * r],
            &set.tracks[3 * r + 1],
            &set.tracks[3 * r + 2],
        );
        let n = m.points.len();
        for j in 0..n {
            let (lo, hi) = (j.saturating_sub(1), (j + 1).min(n - 1));
            let heading = m.points[hi] - m.points[lo];
            let row = b.points[j] - a.points[j];
            // Rows point to the walker's left: +90° from the heading.
            let left = Vec2::new(-heading.y, heading.x);
            let ang = (left.x * row.y - left.y * row.x)
                .atan2(left.dot(&row))
                .to_degrees()
                .abs();
            worst = worst.max(ang);
        }
    }
    worst
}

/// Pairs closer than the threshold, and the closest distance (m) if any.
fn pairs(set: &TrackSet) -> (u64, Option<f64>) {
    let c = detect(set, THRESHOLD_M).unwrap();
    (c.pair_total, c.closest.map(|p| p.closest.distance_m))
}

/// Largest segment speed after the edit over before.
fn worst_speed_ratio(before: &TrackSet, after: &TrackSet) -> f64 {
    let mut worst: f64 = 1.0;
    for (b, a) in before.tracks.iter().zip(&after.tracks) {
        for j in 0..b.points.len() - 1 {
            let r = a.segment_speed(j) / b.segment_speed(j);
            worst = worst.max(r).max(1.0 / r);
        }
    }
    worst
}

fn rotate_about(p: Vec2, centre: Vec2, deg: f64) -> Vec2 {
    let (s, c) = deg.to_radians().sin_cos();
    let d = p - centre;
    centre + Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y)
}

fn fmt(p: Vec2) -> String {
    format!("({:.6}, {:.6})", p.x, p.y)
}

/// Runs a script of `Select` everything, `Fix` the front rank's middle start, and
/// one drag per turn of `step_deg` until `total_deg`, of the front rank's middle end
/// around that start.
/// Returns the largest segment speed ratio (after / before, or its inverse) the
/// drags made before eq. 9's correction, and the largest hull edge-length change
/// (RMS, relative) of a drag.
fn turn(set: &mut TrackSet, step_deg: f64, total_deg: f64) -> (f64, f64) {
    let start = set.tracks[1].points[0];
    let mut end = *set.tracks[1].points.last().unwrap();
    let mut ops = format!(
        "(ops: [Select(rect: Some(((-100.0, -100.0), (100.0, 100.0)))), Fix(at: [{}]),",
        fmt(start)
    );
    let mut done = 0.0;
    while done < total_deg - 1e-9 {
        let to = rotate_about(end, start, step_deg);
        ops += &format!(" Drag(from: {}, to: {}),", fmt(end), fmt(to));
        end = to;
        done += step_deg;
    }
    ops += "])";
    let script = parse_script(&ops).unwrap();
    let r = run_script(set, &script, &ApplyParams::default()).unwrap();
    assert_eq!(r.drags.len(), (total_deg / step_deg).round() as usize);
    let mut speed: f64 = 1.0;
    let mut shape: f64 = 0.0;
    for d in &r.drags {
        shape = shape.max(d.shape_edge_rms);
        assert!(d.handle.starts_with("track 1 sample"), "{}", d.handle);
        speed = speed
            .max(d.speed_ratio_edited.1)
            .max(1.0 / d.speed_ratio_edited.0);
    }
    (speed, shape)
}

#[test]
fn a_90_degree_drag_turns_the_parade_with_its_rows_across() {
    let before = parade(4, 12.0);
    assert_eq!(pairs(&before).0, 0);
    let mut one = before.clone();
    let s1 = turn(&mut one, 90.0, 90.0);
    let mut four = before.clone();
    let s4 = turn(&mut four, 22.5, 90.0);
    let mut report = Vec::new();
    for (what, after, (speed, shape)) in
        [("one 90° drag", &one, s1), ("four 22.5° drags", &four, s4)]
    {
        let angle = worst_row_angle_deg(after);
        let (n, closest) = pairs(after);
        let end = *after.tracks[1].points.last().unwrap() - after.tracks[1].points[0];
        eprintln!(
            "{what}: rows up to {angle:.2}° off perpendicular, {n} pairs under {THRESHOLD_M} m \
             (closest {closest:?} m), speeds up to {speed:.3}× before eq. 9, after it {:.3}×, \
             hull edge lengths changed {shape:.4} (RMS)",
            worst_speed_ratio(&before, after)
        );
        report.push((what, angle, n, closest, end, shape));
    }
    for (what, angle, n, closest, end, shape) in report {
        assert!(
            shape < 0.01,
            "{what}: the hull's edges changed {shape:.4} (RMS)"
        );
        assert!(angle <= 5.0, "{what}: rows {angle:.2}° off perpendicular");
        assert_eq!(
            n, 0,
            "{what}: {n} pairs closer than {THRESHOLD_M} m, closest {closest:?}"
        );
        // The parade turned: its front rank's middle end is north of its start.
        assert!(end.x.abs() < 0.05 && end.y > 11.9, "{what}: {end:?}");
    }
}

/// Drags the front rank's middle sample `sample` by `by` with nothing fixed (eq. 1)
/// and returns the largest move (m) of a sample farther than `away_m` from it.
fn drag_and_far_move(before: &TrackSet, sample: usize, by: Vec2, away_m: f64) -> f64 {
    let mut after = before.clone();
    let from = before.tracks[1].points[sample];
    let to = from + by;
    let ops = format!(
        "(ops: [Select(rect: Some(((-100.0, -100.0), (100.0, 100.0)))), Drag(from: {}, to: {})])",
        fmt(from),
        fmt(to)
    );
    run_script(
        &mut after,
        &parse_script(&ops).unwrap(),
        &ApplyParams::default(),
    )
    .unwrap();
    let held = after.tracks[1].points[sample];
    assert!((held - to).norm() < 1e-6, "the handle lands: {held:?}");
    let mut far: f64 = 0.0;
    for (b, a) in before.tracks.iter().zip(&after.tracks) {
        for (p, q) in b.points.iter().zip(&a.points) {
            if (p - from).norm() > away_m {
                far = far.max((q - p).norm());
            }
        }
    }
    far
}

#[test]
fn a_drag_at_one_end_of_a_20_m_parade_leaves_the_far_end() {
    // Four ranks walking 17.6 m: the tracks cover 20 m, from x = -2.4 to 17.6.
    let before = parade(4, 17.6);
    let last = before.tracks[1].points.len() - 1;
    let drag_m = 1.5;
    for dir in [
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.6, -0.8),
    ] {
        // The far end: samples more than 18 m from the handle (x < -0.4).
        let far = drag_and_far_move(&before, last, dir * drag_m, 18.0);
        eprintln!("end drag {dir:?}: the far end moved up to {far:.3} m for {drag_m} m");
        assert!(
            far <= 0.1 * drag_m,
            "the far end moved {far:.3} m for a {drag_m} m drag"
        );
    }
}

#[test]
fn a_drag_in_the_middle_of_a_parade_leaves_its_ends() {
    // The figure of docs/motion-editing.md (a): the middle of a 14.4 m parade (x from
    // -2.4 to 12) pulled 1.5 m across; the samples more than 6 m away are its ends.
    let before = parade(4, 12.0);
    let drag_m = 1.5;
    let far = drag_and_far_move(&before, 10, Vec2::new(0.0, drag_m), 6.0);
    eprintln!("middle drag: samples over 6 m away moved up to {far:.3} m for {drag_m} m");
    assert!(
        far <= 0.1 * drag_m,
        "the ends moved {far:.3} m for a {drag_m} m drag"
    );
}
