//! The spatial editor on paths that come back to a place (crowd-motion-editing
//! section 3.2, cut into time windows: `src/crowd/edit/cage_split.rs`): a U-turn, a
//! loop and a person pacing. Dragging the late part of such a path moves the late
//! part and leaves the early part where it was, the track stays continuous across the
//! windows' borders, and a path that does not come back keeps its single cage.
//!
//! Every path is made here: a walker at 1.2 m/s sampled every 0.5 s.

use crowdtouch::crowd::edit::{
    Cage, CageParams, Handle, SampleRef, Selection, SelectionQuery, Track, TrackSet, WindowParams,
};
use crowdtouch::geom::Vec2;

/// Sample step (s).
const STEP_S: f64 = 0.5;
/// Walking speed (m/s).
const SPEED_M_S: f64 = 1.2;

fn one_track(points: Vec<Vec2>) -> TrackSet {
    let times = (0..points.len()).map(|k| k as f64 * STEP_S).collect();
    TrackSet {
        tracks: vec![Track::linked(7, points, times)],
        step_s: STEP_S,
    }
}

/// Out 10 m along +x, a half circle of radius 0.25 m, and back along y = 0.5 m.
fn u_turn() -> TrackSet {
    let ds = SPEED_M_S * STEP_S;
    let mut pts = Vec::new();
    let mut s = 0.0;
    let (leg, turn) = (10.0, std::f64::consts::PI * 0.25);
    while s <= 2.0 * leg + turn {
        pts.push(if s <= leg {
            Vec2::new(s, 0.0)
        } else if s <= leg + turn {
            let a = (s - leg) / 0.25;
            Vec2::new(leg + 0.25 * a.sin(), 0.25 - 0.25 * a.cos())
        } else {
            Vec2::new(leg - (s - leg - turn), 0.5)
        });
        s += ds;
    }
    one_track(pts)
}

/// Round a circle of radius 3 m one and a half times.
fn loop_path() -> TrackSet {
    let ds = SPEED_M_S * STEP_S;
    let r = 3.0;
    let turns = 1.5;
    let n = (turns * 2.0 * std::f64::consts::PI * r / ds) as usize;
    let pts = (0..=n)
        .map(|k| {
            let a = k as f64 * ds / r;
            Vec2::new(r * a.cos(), r * a.sin())
        })
        .collect();
    one_track(pts)
}

fn cage_of(set: &TrackSet, params: &CageParams) -> Cage {
    let sel = Selection::select(set, &SelectionQuery::default()).unwrap();
    Cage::new(set, &sel, params).unwrap()
}

/// Drags sample `k` of the only track by `by` (no fixed handle) and returns the
/// displacement of every sample.
fn drag_sample(set: &TrackSet, params: &CageParams, k: usize, by: Vec2) -> (Cage, Vec<Vec2>) {
    let mut cage = cage_of(set, params);
    let h = Handle::Sample(SampleRef {
        track: 0,
        sample: k,
    });
    let target = set.tracks[0].points[k] + by;
    cage.drag(&[(h, target)], &[]).unwrap();
    assert!((cage.handle_position(h).unwrap() - target).norm() < 1e-9);
    let mut out = set.clone();
    cage.apply(&mut out).unwrap();
    let moved = out.tracks[0]
        .points
        .iter()
        .zip(&set.tracks[0].points)
        .map(|(a, b)| a - b)
        .collect();
    (cage, moved)
}

/// The largest move (m) of the samples more than `away_s` from sample `k` in time
/// and closer than `near_m` to it in space (the other visit of the place).
fn other_visit_move(set: &TrackSet, moved: &[Vec2], k: usize, away_s: f64, near_m: f64) -> f64 {
    let tr = &set.tracks[0];
    (0..tr.len())
        .filter(|&j| {
            (tr.times_s[j] - tr.times_s[k]).abs() > away_s
                && (tr.points[j] - tr.points[k]).norm() < near_m
        })
        .map(|j| moved[j].norm())
        .fold(0.0, f64::max)
}

/// The largest change of displacement between consecutive samples across a window
/// border (entering or leaving an overlap), and the largest between consecutive
/// samples in the same windows (what the drag does to neighbours).
fn border_and_inside_jumps(cage: &Cage, set: &TrackSet, moved: &[Vec2]) -> (f64, f64) {
    let tr = &set.tracks[0];
    let windows_of = |j: usize| -> Vec<bool> {
        let t = tr.times_s[j];
        let last = cage.window_count() - 1;
        (0..cage.window_count())
            .map(|w| cage.window_span(w).holds(t, w == last))
            .collect()
    };
    let (mut border, mut inside): (f64, f64) = (0.0, 0.0);
    for j in 0..tr.len() - 1 {
        let jump = (moved[j + 1] - moved[j]).norm();
        if windows_of(j) != windows_of(j + 1) {
            border = border.max(jump);
        } else {
            inside = inside.max(jump);
        }
    }
    (border, inside)
}

#[test]
fn a_path_that_does_not_come_back_keeps_one_cage() {
    let pts = (0..60)
        .map(|k| Vec2::new(0.6 * k as f64, 0.2 * (k as f64 * 0.1).sin()))
        .collect();
    let set = one_track(pts);
    assert_eq!(cage_of(&set, &CageParams::default()).window_count(), 1);
}

#[test]
fn u_turn_dragging_the_way_back_leaves_the_way_out() {
    let set = u_turn();
    let tr = &set.tracks[0];
    // A sample of the way back 3 m from the start, dragged 1 m away from the way out.
    let k = (0..tr.len())
        .filter(|&j| tr.points[j].y > 0.4)
        .min_by(|&a, &b| {
            (tr.points[a].x - 3.0)
                .abs()
                .total_cmp(&(tr.points[b].x - 3.0).abs())
        })
        .unwrap();
    let by = Vec2::new(0.0, 1.0);
    let params = CageParams::default();
    let (cage, moved) = drag_sample(&set, &params, k, by);
    assert!(cage.window_count() >= 2, "{} windows", cage.window_count());
    // The way back moves around the handle ...
    assert!((moved[k] - by).norm() < 1e-9);
    assert!(moved[k - 1].norm() > 0.5 && moved[k + 1].norm() > 0.5);
    // ... and the way out beside it (13 s earlier, 0.5 m away) stays, as does every
    // sample of the way out more than 5 m of walking from the handle.
    let beside = other_visit_move(&set, &moved, k, 5.0 / SPEED_M_S, 1.0);
    let way_out = (0..tr.len())
        .filter(|&j| {
            tr.points[j].y < 0.01 && (tr.times_s[j] - tr.times_s[k]).abs() * SPEED_M_S > 5.0
        })
        .map(|j| moved[j].norm())
        .fold(0.0, f64::max);
    eprintln!("u-turn: way out beside the handle moved {beside:.4} m, the way out {way_out:.4} m");
    assert!(
        beside < 0.02,
        "the way out beside the handle moved {beside} m"
    );
    assert!(way_out < 0.02, "the way out moved {way_out} m");
    // One cage for the whole path welds the two legs: the way out follows.
    let one = CageParams {
        windows: WindowParams::one_cage(),
        ..CageParams::default()
    };
    let (single, welded) = drag_sample(&set, &one, k, by);
    assert_eq!(single.window_count(), 1);
    let beside_one = other_visit_move(&set, &welded, k, 5.0 / SPEED_M_S, 1.0);
    eprintln!("u-turn, one cage: the way out beside the handle moved {beside_one:.3} m");
    assert!(
        beside_one > 0.5,
        "one cage moved the way out only {beside_one} m"
    );
}

#[test]
fn u_turn_tracks_stay_continuous_across_window_borders() {
    let set = u_turn();
    let tr = &set.tracks[0];
    let params = CageParams::default();
    // Drags at several places of the way back, near and far from the borders.
    for x in [1.0, 3.0, 5.0, 7.0, 9.0] {
        let k = (0..tr.len())
            .filter(|&j| tr.points[j].y > 0.4)
            .min_by(|&a, &b| {
                (tr.points[a].x - x)
                    .abs()
                    .total_cmp(&(tr.points[b].x - x).abs())
            })
            .unwrap();
        let (cage, moved) = drag_sample(&set, &params, k, Vec2::new(0.3, 1.0));
        assert!(cage.window_count() >= 2);
        let (border, inside) = border_and_inside_jumps(&cage, &set, &moved);
        eprintln!("drag at x = {x}: border jump {border:.4} m, inside the windows {inside:.4} m");
        assert!(
            border <= inside,
            "drag at x = {x}: a jump of {border} m at a border, at most {inside} m inside"
        );
    }
}

#[test]
fn loop_dragging_the_second_pass_leaves_the_first() {
    let set = loop_path();
    let tr = &set.tracks[0];
    // A sample of the second pass at a quarter turn, dragged 1 m outwards.
    let quarter = tr.len() * 5 / 6;
    let k = quarter;
    let by = tr.points[k].normalize();
    let (cage, moved) = drag_sample(&set, &CageParams::default(), k, by);
    assert!(cage.window_count() >= 2, "{} windows", cage.window_count());
    let first_pass = other_visit_move(&set, &moved, k, 8.0, 1.0);
    eprintln!("loop: the first pass beside the handle moved {first_pass:.4} m");
    assert!(first_pass < 0.02, "the first pass moved {first_pass} m");
    let (border, inside) = border_and_inside_jumps(&cage, &set, &moved);
    assert!(
        border <= inside,
        "border jump {border} m, inside {inside} m"
    );
}

#[test]
fn pacing_back_and_forth_is_cut_and_each_pass_edited_alone() {
    // Three passes along a 9.6 m line, each 0.5 m beside the last.
    let ds = SPEED_M_S * STEP_S;
    let per_pass = 17;
    let mut pts = Vec::new();
    for pass in 0..3 {
        let y = 0.5 * pass as f64;
        for k in 0..per_pass {
            let x = k as f64 * ds;
            let x = if pass % 2 == 0 {
                x
            } else {
                ds * (per_pass - 1) as f64 - x
            };
            pts.push(Vec2::new(x, y));
        }
    }
    let set = one_track(pts);
    // The middle of the last pass, dragged 1 m in +y.
    let k = 2 * per_pass + per_pass / 2;
    let (cage, moved) = drag_sample(&set, &CageParams::default(), k, Vec2::new(0.0, 1.0));
    assert!(cage.window_count() >= 3, "{} windows", cage.window_count());
    // The first pass, at the same place 16 s earlier, stays; so does the middle
    // pass away from its turn onto the last one.
    let first = (0..per_pass).map(|j| moved[j].norm()).fold(0.0, f64::max);
    let middle = (per_pass..per_pass + per_pass / 2)
        .map(|j| moved[j].norm())
        .fold(0.0, f64::max);
    eprintln!("pacing: first pass moved {first:.4} m, the middle pass's first half {middle:.4} m");
    assert!(first < 0.02, "the first pass moved {first} m");
    assert!(middle < 0.05, "the middle pass moved {middle} m");
    let (border, inside) = border_and_inside_jumps(&cage, &set, &moved);
    assert!(
        border <= inside,
        "border jump {border} m, inside {inside} m"
    );
}

#[test]
fn windowed_cage_drags_hull_handles_and_keeps_fixed_samples() {
    let set = u_turn();
    let mut cage = cage_of(&set, &CageParams::default());
    let w = cage.window_count() - 1;
    let r = cage.hull_range(w);
    assert!(r.end == cage.hull().len() && cage.hull().len() == cage.deformed_hull().len());
    let h = Handle::Hull(r.start + 1);
    let v = cage.hull()[r.start + 1];
    let fixed = Handle::Sample(SampleRef {
        track: 0,
        sample: set.tracks[0].len() - 1,
    });
    cage.drag(&[(h, v + Vec2::new(0.4, 0.4))], &[fixed])
        .unwrap();
    assert!((cage.handle_position(h).unwrap() - v - Vec2::new(0.4, 0.4)).norm() < 1e-9);
    let last = set.tracks[0].points[set.tracks[0].len() - 1];
    assert!((cage.handle_position(fixed).unwrap() - last).norm() < 1e-9);
    // A continuing drag and a reset.
    cage.drag(&[(h, v + Vec2::new(0.5, 0.3))], &[fixed])
        .unwrap();
    cage.reset();
    for i in 0..cage.selection().len() {
        assert!((cage.deformed_sample(i) - cage.rest_sample(i)).norm() < 1e-12);
    }
    assert!(cage
        .drag(&[(Handle::Hull(cage.hull().len()), v)], &[])
        .is_err());
}
