use super::*;
use crate::crowd::edit::avoid_solve::{
    banded_cholesky_solve, retime_pair, smooth_track, PieceNodes,
};
use crate::crowd::edit::io::{read_eth, EthOptions};
use crate::crowd::edit::tracks::Track;
use crate::geom::Vec2;
use nalgebra::{DMatrix, DVector};

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

/// A walker from `from` in direction `dir` (unit) at `speed` for `samples` steps of `step_s`.
fn walker(id: u64, from: Vec2, dir: Vec2, speed: f64, samples: usize, step_s: f64) -> Track {
    Track::linked(
        id,
        (0..samples)
            .map(|k| from + dir * (speed * step_s * k as f64))
            .collect(),
        (0..samples).map(|k| k as f64 * step_s).collect(),
    )
}

/// Two groups of `per_group` people (rows of 5, `spacing` apart, a little
/// jitter) walking at 1.3 m/s through each other: group B heads at `angle` to
/// group A's +x (π/2 perpendicular, near π head-on). Samples every 0.1 s.
pub(super) fn crossing_crowds(per_group: usize, angle: f64, spacing: f64) -> TrackSet {
    let mut rng = crate::rng::SplitMix64::new(0xc0ff ^ per_group as u64);
    let step = 0.1;
    let samples = 201;
    let cols = 5;
    let mut tracks = Vec::new();
    for g in 0..2 {
        let dir = if g == 0 {
            v(1.0, 0.0)
        } else {
            v(angle.cos(), angle.sin())
        };
        let side = v(-dir.y, dir.x);
        for k in 0..per_group {
            let (r, c) = ((k / cols) as f64, (k % cols) as f64);
            let jitter = v(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
            // Start behind the crossing so the groups meet around t = 10 s.
            let from = dir * (-13.0 - c * spacing) + side * ((r - 1.5) * spacing) + jitter;
            tracks.push(walker((g * 1000 + k) as u64, from, dir, 1.3, samples, step));
        }
    }
    TrackSet {
        tracks,
        step_s: step,
    }
}

fn assert_points_unchanged(before: &TrackSet, after: &TrackSet) {
    for (a, b) in before.tracks.iter().zip(&after.tracks) {
        assert_eq!(a.points, b.points, "person {}", a.id);
        assert_eq!(a.linked, b.linked);
        assert_eq!(a.id, b.id);
    }
    after.validate().unwrap();
}

#[test]
fn retime_pair_splits_the_separation_evenly_at_midpoints() {
    let p = |t0: f64| PieceNodes {
        nodes: vec![3, 4],
        weights: vec![0.5, 0.5],
        times: vec![t0, t0 + 1.0],
        original_len_s: 1.0,
        first_s: t0,
        speed_m_s: 1.0,
    };
    let (_, d) = retime_pair(&p(5.0), &p(5.0), 0.4, 0.5, None).unwrap();
    // Both pieces translated by half the separation, in opposite directions.
    let want = [0.2f64, 0.2, -0.2, -0.2];
    for (got, want) in d.iter().zip(want) {
        assert!((got.abs() - want.abs()).abs() < 1e-12, "{d:?}");
    }
    let passes_i = 0.5 * (d[0] + d[1]);
    let passes_j = 0.5 * (d[2] + d[3]);
    assert!(((passes_i - passes_j).abs() - 0.4).abs() < 1e-12);
}

#[test]
fn retime_pair_keeps_the_scale_and_times_non_negative() {
    // Collision at the end of i's short piece and the start of j's: the
    // unconstrained projection would squash i's piece below a_min.
    let pi = PieceNodes {
        nodes: vec![0, 1],
        weights: vec![0.0, 1.0],
        times: vec![1.0, 1.1],
        original_len_s: 0.1,
        first_s: 1.0,
        speed_m_s: 1.0,
    };
    let pj = PieceNodes {
        nodes: vec![7],
        weights: vec![1.0],
        times: vec![1.1],
        original_len_s: 0.0,
        first_s: 0.0,
        speed_m_s: 0.0,
    };
    let (_, d) = retime_pair(&pi, &pj, 2.0, 0.5, None).unwrap();
    let a = (1.1 + d[1] - (1.0 + d[0])) / 0.1;
    assert!(a >= 0.5 - 1e-9, "scale {a}, {d:?}");
    assert!(1.0 + d[0] >= -1e-9 && 1.1 + d[2] >= -1e-9, "{d:?}");
    assert!(((d[1] - d[2]).abs() - 2.0).abs() < 1e-9, "{d:?}");
}

#[test]
fn smooth_track_holds_fixed_nodes_and_stays_increasing() {
    let mut t = walker(1, v(0.0, 0.0), v(1.0, 0.0), 1.0, 30, 0.1);
    let before = t.times_s.clone();
    let fixed = [(10, before[10] + 0.1), (11, before[11] + 0.1)];
    let corrected = smooth_track(&mut t, &before, &fixed, &AvoidParams::default()).unwrap();
    assert!(!corrected);
    assert_eq!(t.times_s[10], before[10] + 0.1);
    assert_eq!(t.times_s[11], before[11] + 0.1);
    assert!(t.times_s.windows(2).all(|w| w[1] > w[0]));
    // The shift spreads: neighbours move the same way, less the further away.
    assert!(t.times_s[9] - before[9] > 0.0 && t.times_s[9] - before[9] < 0.1);
    assert!((t.times_s[0] - before[0]).abs() < t.times_s[9] - before[9]);
    // A shift too large to spread falls back to the anchored correction.
    let mut t = walker(1, v(0.0, 0.0), v(1.0, 0.0), 1.0, 30, 0.1);
    let before = t.times_s.clone();
    let fixed = [(10, 50.0), (11, 50.1)];
    let corrected = smooth_track(&mut t, &before, &fixed, &AvoidParams::default()).unwrap();
    assert!(t.times_s.windows(2).all(|w| w[1] > w[0]), "{:?}", t.times_s);
    assert_eq!(t.times_s[10], 50.0);
    if corrected {
        assert!((t.times_s[0] - (50.0 - 1.0)).abs() < 1e-9);
    }
}

#[test]
fn banded_cholesky_matches_dense() {
    let n = 7;
    let mut dense = DMatrix::<f64>::zeros(n, n);
    let mut band = vec![[0.0; 3]; n];
    for i in 0..n {
        for d in 0..3.min(i + 1) {
            let x = if d == 0 {
                6.0 + i as f64
            } else {
                1.0 / (1.0 + d as f64 + i as f64)
            };
            band[i][d] = x;
            dense[(i, i - d)] = x;
            dense[(i - d, i)] = x;
        }
    }
    let b: Vec<f64> = (0..n).map(|i| i as f64 - 2.0).collect();
    let mut x = b.clone();
    assert!(banded_cholesky_solve(&mut band, &mut x));
    let r = &dense * DVector::from_vec(x) - DVector::from_vec(b);
    assert!(r.norm() < 1e-12);
}

/// Two crossing groups of 20 retimed with the default parameters must end with no
/// pair below the threshold. Convergence depends on density: at 2.5 m spacing
/// 90°, 120° and 150° clear in under 30 rounds and 170° in 151; at 1.5 m (and at
/// 2 m for 90° and 170°) pairs remain after the 200 rounds.
fn check_crossing(angle: f64, spacing: f64) -> AvoidReport {
    let before = crossing_crowds(20, angle, spacing);
    let mut set = before.clone();
    let p = AvoidParams::default();
    let report = avoid(&mut set, &p).unwrap();
    eprintln!("angle {angle}: {report:?}");
    assert!(report.pairs_before > 0);
    assert_eq!(report.pairs_after, 0, "{report:?}");
    assert!(report.remaining.is_empty());
    assert_eq!(detect(&set, p.threshold_m).unwrap().pair_count(), 0);
    assert_points_unchanged(&before, &set);
    assert!(set.tracks.iter().all(|t| t.times_s[0] >= 0.0));
    report
}

#[test]
fn perpendicular_crowds_are_separated_by_retiming() {
    let r = check_crossing(std::f64::consts::FRAC_PI_2, 2.5);
    assert!(r.max_speed_change_pct <= SPEED_BOUND_PCT, "{r:?}");
}

#[test]
fn nearly_head_on_crowds_are_separated_by_retiming() {
    // 150°: paths cross. Exactly opposite paths on one line only separate by one
    // person waiting for the other to leave it.
    let r = check_crossing(150f64.to_radians(), 2.5);
    assert!(r.max_speed_change_pct <= SPEED_BOUND_PCT, "{r:?}");
}

/// The largest speed change: `1 / a_min − 1` with the default `a_min` 0.8 (percent).
const SPEED_BOUND_PCT: f64 = 25.0 + 1e-6;

#[test]
fn people_standing_on_each_other_are_separated_only_by_waiting() {
    let mut set = TrackSet {
        tracks: vec![
            Track::linked(1, vec![v(0.0, 0.0); 3], vec![0.0, 1.0, 2.0]),
            Track::linked(2, vec![v(0.1, 0.0); 3], vec![0.0, 1.0, 2.0]),
        ],
        step_s: 1.0,
    };
    let before = set.clone();
    // Within a 1.5 s bound nothing separates them: no piece retiming moves two
    // people standing still, and one would have to wait 2 s for the other to leave.
    let tight = AvoidParams {
        max_shift_s: 1.5,
        ..AvoidParams::default()
    };
    let r = avoid(&mut set, &tight).unwrap();
    assert_eq!(r.pairs_after, 1);
    assert_eq!(r.remaining[0].why, Stuck::Infeasible);
    assert_eq!(set, before);
    // With the default 10 s, one of them arrives after the other has left: all
    // of that person's times move by one amount, more than the 2 s they stand.
    let r = avoid(&mut set, &AvoidParams::default()).unwrap();
    assert_eq!(r.pairs_after, 0, "{r:?}");
    assert_eq!((r.shifts, r.retimed_people), (1, 1), "{r:?}");
    let moved: Vec<f64> = set
        .tracks
        .iter()
        .zip(&before.tracks)
        .flat_map(|(a, b)| a.times_s.iter().zip(&b.times_s).map(|(x, y)| x - y))
        .filter(|d| *d != 0.0)
        .collect();
    assert_eq!(moved.len(), 3);
    assert!(
        moved
            .iter()
            .all(|d| (d - moved[0]).abs() < 1e-12 && *d > 2.0),
        "{moved:?}"
    );
    assert_points_unchanged(&before, &set);
}

#[test]
fn opposite_walkers_on_one_line_are_separated_by_waiting() {
    let mut set = TrackSet {
        tracks: vec![
            walker(1, v(0.0, 0.0), v(1.0, 0.0), 1.0, 11, 0.5),
            walker(2, v(5.0, 0.0), v(-1.0, 0.0), 1.0, 11, 0.5),
        ],
        step_s: 0.5,
    };
    let before = set.clone();
    let p = AvoidParams {
        max_iterations: 5,
        ..AvoidParams::default()
    };
    let r = avoid(&mut set, &p).unwrap();
    // One waits until the other has left the line.
    assert_eq!(r.pairs_after, 0, "{r:?}");
    assert_eq!(detect(&set, p.threshold_m).unwrap().pair_count(), 0);
    assert_points_unchanged(&before, &set);
}

#[test]
fn bad_parameters_are_errors() {
    let mut set = crossing_crowds(2, 1.0, 2.0);
    for p in [
        AvoidParams {
            gamma: 0.0,
            ..AvoidParams::default()
        },
        AvoidParams {
            min_scale: 0.0,
            ..AvoidParams::default()
        },
        AvoidParams {
            alpha: f64::NAN,
            ..AvoidParams::default()
        },
    ] {
        assert!(matches!(avoid(&mut set, &p), Err(AvoidError::Param { .. })));
    }
    let p = AvoidParams {
        threshold_m: -1.0,
        ..AvoidParams::default()
    };
    assert!(matches!(avoid(&mut set, &p), Err(AvoidError::Collide(_))));
}

#[test]
fn zara_fixture_at_0_3_m() {
    let path = format!(
        "{}/tests/fixtures/crowd/crowds_zara01.txt",
        env!("CARGO_MANIFEST_DIR")
    );
    let before = read_eth(
        &std::fs::read_to_string(path).unwrap(),
        EthOptions::default(),
    )
    .unwrap();
    let mut set = before.clone();
    let r = avoid(&mut set, &AvoidParams::default()).unwrap();
    eprintln!("zara01 at 0.3 m: {r:?}");
    assert_eq!(r.pairs_before, 3);
    assert_points_unchanged(&before, &set);
    assert_eq!(detect(&set, 0.3).unwrap().pair_count(), r.pairs_after);
    // All three separated, each by moving one person's times whole.
    assert_eq!(r.pairs_after, 0, "{r:?}");
    assert!(r.retimed_people <= r.people_in_collision, "{r:?}");
    assert!(r.max_shift_s <= AvoidParams::default().max_shift_s, "{r:?}");
}

#[test]
fn a_crowd_at_one_point_is_left_as_one_cluster() {
    // 2,000 people standing at one point (issue 27, finding 4: before, avoidance
    // took every one of their 2 million pairs each round) and two walkers
    // crossing elsewhere, whom avoidance still separates.
    let mut tracks: Vec<Track> = (0..2_000)
        .map(|id| Track::linked(id, vec![v(5.0, 5.0); 2], vec![0.0, 10.0]))
        .collect();
    tracks.push(walker(5_000, v(-5.0, 0.0), v(1.0, 0.0), 1.0, 101, 0.1));
    tracks.push(walker(5_001, v(0.0, -5.0), v(0.0, 1.0), 1.0, 101, 0.1));
    let mut set = TrackSet {
        tracks,
        step_s: 0.1,
    };
    let before = set.clone();
    let r = avoid(&mut set, &AvoidParams::default()).unwrap();
    let cluster_pairs = 2_000 * 1_999 / 2;
    assert_eq!(r.pairs_before, cluster_pairs + 1);
    assert_eq!(r.pairs_after, cluster_pairs, "{r:?}");
    assert_eq!(r.remaining.len(), 1);
    assert_eq!(r.remaining[0].why, Stuck::Cluster);
    assert_eq!(set.tracks[..2_000], before.tracks[..2_000]);
    assert_points_unchanged(&before, &set);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig {
        cases: 96,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6176_6f69),
        failure_persistence: None,
        ..proptest::prelude::ProptestConfig::default()
    })]

    /// On random small crowds (gaps, people standing, companions, irregular
    /// times): never worse on pairs or closest distance, times strictly
    /// increasing and never negative when they were not, no one's times moved
    /// further than the bound, only people in a collision retimed, positions kept.
    #[test]
    fn prop_avoidance_is_never_worse(
        s in crate::crowd::edit::collide::tests::crowd(),
        d in 0.1f64..1.0,
        bound in 0.5f64..6.0,
    ) {
        let p = AvoidParams { threshold_m: d, max_shift_s: bound, ..AvoidParams::default() };
        let before = detect(&s, d).unwrap();
        let mut set = s.clone();
        let r = avoid(&mut set, &p).unwrap();
        let after = detect(&set, d).unwrap();
        proptest::prop_assert!(after.pair_count() <= before.pair_count(), "{r:?}");
        proptest::prop_assert_eq!(after.pair_count(), r.pairs_after);
        if let (Some(a), Some(b)) = (after.min_distance_m(), before.min_distance_m()) {
            proptest::prop_assert!(a >= b, "closest {a} < {b}: {r:?}");
        }
        set.validate().unwrap();
        let mut in_pair = vec![false; s.tracks.len()];
        for q in &before.pairs {
            in_pair[q.a] = true;
            in_pair[q.b] = true;
        }
        for (k, (a, b)) in set.tracks.iter().zip(&s.tracks).enumerate() {
            proptest::prop_assert_eq!(&a.points, &b.points);
            proptest::prop_assert!(largest_shift(&a.times_s, &b.times_s) <= bound + 1e-9);
            if b.times_s[0] >= 0.0 {
                proptest::prop_assert!(a.times_s[0] >= 0.0);
            }
            if a.times_s != b.times_s {
                proptest::prop_assert!(in_pair[k], "person {k} retimed, never in a collision");
            }
        }
    }
}

#[test]
fn avoidance_around_some_people_leaves_strangers_as_they_are() {
    // Two pairs crossing: 1 and 2 near the origin, 3 and 4 20 m away. Around
    // person 1, only the first pair is worked on; 3 and 4 still collide, their
    // times untouched.
    let mut set = TrackSet {
        tracks: vec![
            walker(1, v(-5.0, 0.0), v(1.0, 0.0), 1.0, 101, 0.1),
            walker(2, v(0.0, -5.0), v(0.0, 1.0), 1.0, 101, 0.1),
            walker(3, v(15.0, 0.0), v(1.0, 0.0), 1.0, 101, 0.1),
            walker(4, v(20.0, -5.0), v(0.0, 1.0), 1.0, 101, 0.1),
        ],
        step_s: 0.1,
    };
    let before = set.clone();
    let r = avoid_around(&mut set, &AvoidParams::default(), &[0]).unwrap();
    assert_eq!((r.pairs_before, r.pairs_after), (2, 1), "{r:?}");
    assert_eq!(set.tracks[2..], before.tracks[2..]);
    assert_ne!(set.tracks[..2], before.tracks[..2]);
    let left = detect(&set, 0.3).unwrap();
    assert_eq!((left.pairs[0].a, left.pairs[0].b), (2, 3));
    // Around everyone, both are.
    let mut all = before.clone();
    assert_eq!(
        avoid(&mut all, &AvoidParams::default())
            .unwrap()
            .pairs_after,
        0
    );
}
