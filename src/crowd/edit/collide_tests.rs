use super::*;
use crate::crowd::edit::io::{read_eth, EthOptions};
use crate::crowd::edit::{FlatTracks, Track, TrackSet};
use proptest::prelude::*;
use proptest::test_runner::{Config as ProptestConfig, RngSeed};

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

fn fixture(name: &str) -> TrackSet {
    let path = format!("{}/tests/fixtures/crowd/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(path).unwrap();
    read_eth(&text, EthOptions::default()).unwrap()
}

/// README's continuous counts: pairs closer than 0.2/0.3/0.5/1.0 m, and the minimum.
#[test]
fn fixtures_agree_with_the_readme_continuous_counts() {
    for (name, want, min) in [
        ("crowds_zara01.txt", [0, 3, 27, 160], 0.236),
        ("students001.txt", [48, 168, 606, 1840], 0.078),
    ] {
        let set = fixture(name);
        let got: Vec<usize> = [0.2, 0.3, 0.5, 1.0]
            .iter()
            .map(|&d| detect(&set, d).unwrap().pair_count())
            .collect();
        let m = detect(&set, 1.0).unwrap().min_distance_m().unwrap();
        let flat = FlatTracks::from(&set);
        for d in [0.3, 1.0] {
            assert_eq!(
                detect(&flat, d).unwrap(),
                detect(&set, d).unwrap(),
                "{name}"
            );
        }
        eprintln!("{name}: {got:?} min {m}");
        assert_eq!(got, want, "{name}");
        assert!((m - min).abs() < 5e-4, "{name}: {m}");
    }
}

fn set(tracks: Vec<Track>) -> TrackSet {
    TrackSet {
        tracks,
        step_s: 1.0,
    }
}

fn line(id: u64, from: Vec2, to: Vec2, t0: f64, t1: f64) -> Track {
    Track::linked(id, vec![from, to], vec![t0, t1])
}

/// Detection, checked against the all-pairs reference and against detection on
/// the same people in the flat store.
fn both(s: &TrackSet, d: f64) -> Collisions {
    let fast = detect(s, d).unwrap();
    let reference = collisions_all_pairs(s, d).unwrap();
    assert_eq!(fast, reference);
    assert_eq!(detect(&FlatTracks::from(s), d).unwrap(), fast, "flat store");
    fast
}

#[test]
fn head_on_meets_at_the_midpoint() {
    let s = set(vec![
        line(1, v(0.0, 0.0), v(4.0, 0.0), 0.0, 4.0),
        line(2, v(4.0, 0.1), v(0.0, 0.1), 0.0, 4.0),
    ]);
    let c = both(&s, 0.3);
    assert_eq!(c.pair_count(), 1);
    let a = c.events[0].closest;
    assert!((a.t_s - 2.0).abs() < 1e-12);
    assert!((a.distance_m - 0.1).abs() < 1e-12);
    assert!((a.place() - v(2.0, 0.05)).norm() < 1e-12);
    assert_eq!(
        both(&s, 0.1).pair_count(),
        0,
        "strictly below the threshold"
    );
}

#[test]
fn equal_velocities_keep_their_distance() {
    // Eq. 16: w = 0, the distance at the overlap's start.
    let s = set(vec![
        line(1, v(0.0, 0.0), v(3.0, 0.0), 0.0, 3.0),
        line(2, v(1.0, 0.2), v(3.0, 0.2), 1.0, 3.0),
    ]);
    let c = both(&s, 0.25);
    assert_eq!(c.events.len(), 1);
    assert!((c.events[0].closest.distance_m - 0.2).abs() < 1e-12);
    assert_eq!(c.events[0].closest.t_s, 1.0);
    assert_eq!(c.events[0].start_s, 1.0);
    assert_eq!(c.events[0].end_s, 3.0);
}

#[test]
fn closest_approach_is_clamped_to_the_overlap() {
    // Eq. 17: they would meet at t = 2, but 2 only walks until t = 1.
    let s = set(vec![
        line(1, v(0.0, 0.0), v(4.0, 0.0), 0.0, 4.0),
        line(2, v(4.0, 0.0), v(3.0, 0.0), 0.0, 1.0),
    ]);
    let c = both(&s, 2.5);
    let a = c.events[0].closest;
    assert_eq!(a.t_s, 1.0);
    assert!((a.distance_m - 2.0).abs() < 1e-12);
    assert_eq!(both(&s, 2.0).pair_count(), 0);
}

#[test]
fn single_shared_instants_count() {
    // 1 ends at (1, 0) at t = 1 as 2 starts 0.1 m away.
    let s = set(vec![
        line(1, v(0.0, 0.0), v(1.0, 0.0), 0.0, 1.0),
        line(2, v(1.1, 0.0), v(3.0, 0.0), 1.0, 2.0),
    ]);
    let c = both(&s, 0.2);
    assert_eq!(c.pair_count(), 1);
    assert_eq!(c.events[0].closest.t_s, 1.0);
    assert_eq!((c.events[0].start_s, c.events[0].end_s), (1.0, 1.0));
    // An isolated sample inside the other's segment.
    let s = set(vec![
        line(1, v(0.0, 0.0), v(2.0, 0.0), 0.0, 2.0),
        Track::linked(2, vec![v(0.5, 0.1)], vec![0.5]),
    ]);
    let c = both(&s, 0.2);
    let a = c.events[0].closest;
    assert_eq!(a.t_s, 0.5);
    assert!((a.distance_m - 0.1).abs() < 1e-12);
    assert!(!a.moving_b && a.moving_a);
    // Two isolated samples at one time.
    let s = set(vec![
        Track::linked(1, vec![v(0.0, 0.0)], vec![3.0]),
        Track::linked(2, vec![v(0.0, 0.1)], vec![3.0]),
        Track::linked(3, vec![v(0.0, 0.0)], vec![3.5]),
    ]);
    let c = both(&s, 0.2);
    assert_eq!(c.pair_count(), 1);
    assert_eq!((c.pairs[0].id_a, c.pairs[0].id_b), (1, 2));
    // At the set's last instant, on a slab's edge (span one step) and inside the
    // last slab (span 2.5 steps): the last slab is closed.
    for (t0, far_t) in [(0.0, 0.0), (1.5, 0.0)] {
        let s = set(vec![
            line(1, v(0.0, 0.0), v(1.0, 0.0), t0, t0 + 1.0),
            Track::linked(2, vec![v(1.1, 0.0)], vec![t0 + 1.0]),
            Track::linked(3, vec![v(50.0, 50.0)], vec![far_t]),
        ]);
        let c = both(&s, 0.2);
        assert_eq!(c.pair_count(), 1, "ending at {}", t0 + 1.0);
        assert_eq!(c.events[0].closest.t_s, t0 + 1.0);
    }
}

#[test]
fn a_gap_is_absence() {
    // 1 stands at the origin during [0, 1] and [3, 4], away in between; 2 walks
    // through the origin at t = 2.
    let s = set(vec![
        Track {
            id: 1,
            points: vec![v(0.0, 0.0); 4],
            times_s: vec![0.0, 1.0, 3.0, 4.0],
            linked: vec![true, false, true],
        },
        line(2, v(-2.0, 0.0), v(2.0, 0.0), 0.0, 4.0),
    ]);
    assert_eq!(both(&s, 0.5).pair_count(), 0);
    let mut linked = s.clone();
    linked.tracks[0].linked[1] = true;
    assert_eq!(both(&linked, 0.5).pair_count(), 1);
}

#[test]
fn two_separate_runs_are_two_events() {
    // 2 stands by 1's path, 1 walks past, then comes back after a pause far away.
    let s = set(vec![
        Track::linked(
            1,
            vec![
                v(-2.0, 0.0),
                v(2.0, 0.0),
                v(2.0, 5.0),
                v(2.0, 0.0),
                v(-2.0, 0.0),
            ],
            vec![0.0, 4.0, 9.0, 14.0, 18.0],
        ),
        Track::linked(2, vec![v(0.0, 0.1), v(0.0, 0.1)], vec![0.0, 20.0]),
    ]);
    let c = both(&s, 0.2);
    assert_eq!(c.pair_count(), 1);
    assert_eq!(c.pairs[0].events, 2);
    let t: Vec<f64> = c.events.iter().map(|e| e.closest.t_s).collect();
    assert!(
        (t[0] - 2.0).abs() < 1e-12 && (t[1] - 16.0).abs() < 1e-12,
        "{t:?}"
    );
    // Consecutive overlaps that all collide are one event.
    let s = set(vec![
        Track::linked(
            1,
            (0..6).map(|k| v(k as f64 * 0.1, 0.0)).collect(),
            (0..6).map(f64::from).collect(),
        ),
        Track::linked(2, vec![v(0.0, 0.05), v(0.5, 0.05)], vec![0.0, 5.0]),
    ]);
    let c = both(&s, 0.2);
    assert_eq!(c.events.len(), 1);
    assert_eq!((c.events[0].start_s, c.events[0].end_s), (0.0, 5.0));
}

#[test]
fn bad_threshold_and_tracks_are_errors() {
    let s = set(vec![line(1, v(0.0, 0.0), v(1.0, 0.0), 0.0, 1.0)]);
    for d in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(detect(&s, d), Err(CollideError::Threshold { .. })));
    }
    let mut bad = s.clone();
    bad.tracks[0].times_s[1] = 0.0;
    assert!(matches!(detect(&bad, 0.3), Err(CollideError::Tracks(_))));
    // Near 1e308 m a place printed as (inf, -inf); beyond ±1e6 m is refused.
    let far = set(vec![
        line(1, v(1e308, -1e308), v(1e308, -1e308), 0.0, 1.0),
        line(2, v(1e308, -1e308), v(-1e308, 1e308), 0.0, 1.0),
    ]);
    assert!(matches!(
        detect(&far, 0.3),
        Err(CollideError::Tracks(TrackError::OutOfRange {
            id: 1,
            sample: 0
        }))
    ));
    assert_eq!(detect(&set(vec![]), 0.3).unwrap().pair_count(), 0);
}

/// Random small crowds in a 3 × 3 m square: regular and irregular times, gaps,
/// single samples, people standing still, and pairs walking with equal velocities.
pub(in crate::crowd::edit) fn crowd() -> impl Strategy<Value = TrackSet> {
    let person = (
        1usize..8,
        0.0f64..3.0,
        prop::collection::vec((0.0f64..3.0, 0.0f64..3.0, 0.05f64..1.0, 0u8..10), 8),
        any::<bool>(),
        any::<bool>(),
    );
    (
        prop::collection::vec(person, 1..9),
        0.1f64..1.0,
        any::<bool>(),
    )
        .prop_map(|(people, step, twin)| {
            let mut tracks = Vec::new();
            for (k, (n, start, samples, regular, still)) in people.into_iter().enumerate() {
                let mut t = start;
                let mut tr = Track {
                    id: k as u64,
                    points: vec![],
                    times_s: vec![],
                    linked: vec![],
                };
                for (j, &(x, y, dt, link)) in samples.iter().take(n).enumerate() {
                    if j > 0 {
                        t += if regular { step } else { dt };
                        tr.linked.push(link < 8);
                    }
                    let p = if still {
                        tr.points.first().copied().unwrap_or(v(x, y))
                    } else {
                        v(x, y)
                    };
                    tr.points.push(p);
                    tr.times_s.push(t);
                }
                tracks.push(tr);
            }
            if twin {
                // Same velocities as person 0, 0.1 m to the side.
                let mut t = tracks[0].clone();
                t.id = 1000;
                for p in &mut t.points {
                    p.y += 0.1;
                }
                tracks.push(t);
            }
            TrackSet {
                tracks,
                step_s: step,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x636f_6c6c),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn prop_grid_sweep_equals_all_pairs(s in crowd(), d in 0.05f64..1.5) {
        let fast = detect(&s, d).unwrap();
        let reference = collisions_all_pairs(&s, d).unwrap();
        let pairs = |c: &Collisions| c.pairs.iter().map(|p| (p.a, p.b)).collect::<Vec<_>>();
        prop_assert_eq!(pairs(&fast), pairs(&reference));
        for (f, r) in fast.pairs.iter().zip(&reference.pairs) {
            prop_assert!((f.closest.distance_m - r.closest.distance_m).abs() <= 1e-12);
            prop_assert!(f.closest.distance_m < d);
        }
        prop_assert_eq!(fast, reference);
    }

    #[test]
    fn prop_pairs_involving_marked_people_equal_the_reference(s in crowd(), d in 0.05f64..1.5, mask in any::<u64>()) {
        // The avoidance loop's incremental detection: the reference's pairs with a
        // marked person, nothing more.
        let who: Vec<bool> = (0..s.tracks.len()).map(|k| mask >> (k % 64) & 1 == 1).collect();
        let part = super::collisions_involving(&s, d, &who, DEFAULT_KEEP).unwrap();
        let reference = collisions_all_pairs(&s, d).unwrap();
        let want: Vec<_> = reference.pairs.iter().filter(|p| who[p.a] || who[p.b]).copied().collect();
        prop_assert_eq!(part.pairs, want);
    }

    #[test]
    fn prop_minimum_is_no_more_than_any_sampled_distance(s in crowd()) {
        // Every shared sample instant bounds the pair's closest approach from above.
        let c = detect(&s, 10.0).unwrap();
        for p in &c.pairs {
            let (ta, tb) = (&s.tracks[p.a], &s.tracks[p.b]);
            for (&t, &q) in ta.times_s.iter().zip(&ta.points) {
                if let Some(r) = tb.position_at(t) {
                    prop_assert!(p.closest.distance_m <= (q - r).norm() + 1e-12);
                }
            }
        }
    }
}

#[test]
fn random_walkers_grid_equals_all_pairs() {
    // 300 walkers at 1.3 m/s in a 20 × 20 m square, 0.1 s steps, some entering late
    // and some leaving for a while.
    let mut rng = crate::rng::SplitMix64::new(17);
    let mut tracks = Vec::new();
    for id in 0..300u64 {
        let mut p = v(rng.uniform(0.0, 20.0), rng.uniform(0.0, 20.0));
        let start = (rng.uniform(0.0, 20.0) as usize) as f64 * 0.1;
        let mut tr = Track::linked(id, vec![], vec![]);
        for j in 0..40 {
            let a = rng.uniform(0.0, std::f64::consts::TAU);
            if j > 0 {
                tr.linked.push(rng.unit() > 0.05);
                p += v(a.cos(), a.sin()) * 0.13;
            }
            tr.points.push(p);
            tr.times_s.push(start + j as f64 * 0.1);
        }
        tracks.push(tr);
    }
    let s = TrackSet {
        tracks,
        step_s: 0.1,
    };
    for d in [0.2, 0.5, 1.0] {
        let c = both(&s, d);
        assert!(c.pair_count() > 0);
    }
}

/// `n` people at one point for one second, as the CSV `t,id,x,y` with `0,i,5,5`
/// and `1,i,5,5` (issue 27, finding 4).
fn at_one_point(n: usize) -> TrackSet {
    let mut text = String::from("t,id,x,y\n");
    for i in 0..n {
        text.push_str(&format!("0,{i},5,5\n1,{i},5,5\n"));
    }
    crate::crowd::edit::io::read_csv(&text, None).unwrap()
}

#[test]
fn people_at_one_point_are_one_cluster_with_bounded_lists() {
    // Before: every pair stored (5,000 people: 12.5 million pairs and events,
    // 4.3 GB); now one cluster, the pairs counted in closed form.
    for n in [300usize, 5_000, 20_000] {
        let c = detect(&at_one_point(n), 0.3).unwrap();
        let pairs = (n * (n - 1) / 2) as u64;
        assert_eq!(c.pair_count() as u64, pairs, "{n}");
        assert!(c.pairs.len() <= 1000 && c.events.len() <= 1000, "{n}");
        assert_eq!(c.clusters.len(), 1, "{n}");
        assert_eq!(c.clusters[0].size(), n);
        assert_eq!(c.clusters[0].pairs(), pairs);
        assert_eq!(c.event_total, pairs, "one event per pair: no gap");
        assert_eq!(c.min_distance_m(), Some(0.0));
        assert_eq!(c.clusters[0].place, v(5.0, 5.0));
    }
}

#[test]
fn a_cluster_counts_as_the_reference_does() {
    // 30 people on one track (standing, with a gap), a walker through them, 40
    // random walkers nearby and a second cluster of 3 walking.
    let mut rng = crate::rng::SplitMix64::new(27);
    let mut tracks = Vec::new();
    for id in 0..30 {
        tracks.push(Track {
            id,
            points: vec![v(1.0, 1.0); 4],
            times_s: vec![0.0, 1.0, 3.0, 4.0],
            linked: vec![true, false, true],
        });
    }
    tracks.push(line(100, v(-1.0, 1.1), v(3.0, 1.1), 0.0, 4.0));
    for id in 200..240 {
        let from = v(rng.uniform(0.0, 2.0), rng.uniform(0.0, 2.0));
        let to = v(rng.uniform(0.0, 2.0), rng.uniform(0.0, 2.0));
        tracks.push(line(id, from, to, 0.0, 4.0));
    }
    for id in 300..303 {
        tracks.push(line(id, v(0.0, 0.5), v(2.0, 1.5), 0.0, 4.0));
    }
    let s = set(tracks);
    let fast = detect(&s, 0.3).unwrap();
    let reference = collisions_all_pairs(&s, 0.3).unwrap();
    assert_eq!(fast.clusters.len(), 2);
    assert_eq!(fast.cluster_total, 2);
    assert_eq!(fast.pair_total, reference.pair_total);
    assert_eq!(fast.event_total, reference.event_total);
    assert_eq!(fast.closest, reference.closest);
    assert!(
        reference.pair_total > 435 + 3 + 30,
        "{}",
        reference.pair_total
    );
}

#[test]
fn kept_pairs_are_the_closest_and_everything_is_counted() {
    let s = fixture("students001.txt");
    let all = detect(&s, 1.0).unwrap();
    let few = detect_keeping(&s, 1.0, 10).unwrap();
    assert_eq!((all.pair_count(), few.pair_count()), (1840, 1840));
    assert_eq!(few.event_total, all.event_total);
    assert_eq!((few.pairs.len(), few.events.len()), (10, 10));
    assert_eq!(all.pairs.len(), 1000, "DEFAULT_KEEP");
    let mut by_distance = all.pairs.clone();
    by_distance.sort_by(|x, y| x.closest.distance_m.total_cmp(&y.closest.distance_m));
    let mut want: Vec<_> = by_distance[..10].to_vec();
    want.sort_by_key(|p| (p.a, p.b));
    assert_eq!(few.pairs, want);
    let earliest: Vec<f64> = all.events_by_time()[..10]
        .iter()
        .map(|e| e.closest.t_s)
        .collect();
    let kept: Vec<f64> = few.events_by_time().iter().map(|e| e.closest.t_s).collect();
    assert_eq!(kept, earliest);
    assert_eq!(few.closest, all.closest);
    assert!(!few.is_complete());
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        rng_seed: RngSeed::Fixed(0x636c_7573),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn prop_copies_of_tracks_count_as_the_reference(s in crowd(), copies in prop::collection::vec((0usize..9, 1usize..5), 0..4), d in 0.05f64..1.5, keep in 1usize..6) {
        // Some people copied (new ids, one identical track): clusters counted in
        // closed form must count what comparing every pair counts.
        let mut s = s;
        let mut id = 10_000;
        for (who, k) in copies {
            let src = s.tracks[who % s.tracks.len()].clone();
            for _ in 0..k {
                let mut t = src.clone();
                t.id = id;
                id += 1;
                s.tracks.push(t);
            }
        }
        let fast = detect_keeping(&s, d, keep).unwrap();
        let reference = collisions_all_pairs(&s, d).unwrap();
        prop_assert_eq!(fast.pair_total, reference.pair_total);
        prop_assert_eq!(fast.event_total, reference.event_total);
        prop_assert_eq!(fast.closest, reference.closest);
        prop_assert!(fast.pairs.len() <= keep && fast.events.len() <= keep && fast.clusters.len() <= keep);
    }
}

#[test]
fn people_standing_within_the_threshold_are_one_cluster() {
    // 3,000 people standing within 0.1 m of (5, 5) for 1 s (not on one identical
    // track: before, every pair was evaluated, O(n²)), and walkers through them.
    let mut rng = crate::rng::SplitMix64::new(4);
    let mut tracks: Vec<Track> = (0..3_000)
        .map(|id| {
            let p = v(
                5.0 + rng.uniform(-0.05, 0.05),
                5.0 + rng.uniform(-0.05, 0.05),
            );
            Track::linked(id, vec![p, p], vec![0.0, 1.0])
        })
        .collect();
    for k in 0..5 {
        let y = 4.9 + k as f64 * 0.05;
        tracks.push(line(10_000 + k, v(0.0, y), v(10.0, y), 0.0, 1.0));
    }
    let s = set(tracks);
    let c = detect(&s, 0.3).unwrap();
    let n = 3_000u64;
    assert_eq!(c.clusters.len(), 1);
    assert!(!c.clusters[0].identical);
    assert_eq!(c.clusters[0].pairs(), n * (n - 1) / 2);
    // The walkers' pairs (with each other and with everyone standing) are listed.
    assert_eq!(c.pair_total, n * (n - 1) / 2 + 10 + 5 * n);
    let reference = collisions_all_pairs(&s, 0.3).unwrap();
    assert_eq!(c.pair_total, reference.pair_total);
    assert_eq!(c.event_total, reference.event_total);
    assert_eq!(c.closest, reference.closest);
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        rng_seed: RngSeed::Fixed(0x7374_616e),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn prop_standing_people_count_as_the_reference(
        places in prop::collection::vec((0.0f64..0.4, 0.0f64..0.4, 0u8..4), 2..150),
        s in crowd(),
        d in 0.05f64..1.5,
    ) {
        // People standing at random places at one of four sets of times (some
        // copied, so identical tracks inside standing clusters), among walkers.
        let mut s = s;
        let times = [vec![0.0, 1.0], vec![0.0, 1.0, 3.0], vec![0.5], vec![0.0, 1.0]];
        for (k, &(x, y, which)) in places.iter().enumerate() {
            let t = times[which as usize].clone();
            let mut tr = Track::linked(5_000 + k as u64, vec![v(x, y); t.len()], t);
            if which == 3 {
                tr.linked = vec![false];
            }
            if k % 7 == 6 {
                let mut copy = tr.clone();
                copy.id += 10_000;
                s.tracks.push(copy);
            }
            s.tracks.push(tr);
        }
        let fast = detect_keeping(&s, d, 3).unwrap();
        let reference = collisions_all_pairs(&s, d).unwrap();
        prop_assert_eq!(fast.pair_total, reference.pair_total);
        prop_assert_eq!(fast.event_total, reference.event_total);
        prop_assert_eq!(fast.closest, reference.closest);
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x7368_6966),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn prop_closest_shifted_is_detection_on_the_shifted_tracks(s in crowd(), shift in -3.0f64..3.0) {
        // Avoidance's rigid shifts are judged by `closest_shifted`: it must be
        // what the all-pairs reference finds once the person's times are moved.
        prop_assume!(s.tracks.len() >= 2);
        let mut moved = s.clone();
        for t in &mut moved.tracks[0].times_s {
            *t += shift;
        }
        let reference = collisions_all_pairs(&moved, 1e6).unwrap();
        let a = super::PersonPieces::of(&s.tracks[0].as_ref());
        for k in 1..s.tracks.len() {
            let b = super::PersonPieces::of(&s.tracks[k].as_ref());
            let want = reference.pairs.iter().find(|p| p.a == 0 && p.b == k).map(|p| p.closest.distance_m);
            prop_assert_eq!(super::closest_shifted(&a, shift, &b, 1e6), want, "person {}", k);
            // Under a cutoff: the same distance when it is below, else nothing.
            let cut = 0.7;
            prop_assert_eq!(super::closest_shifted(&a, shift, &b, cut), want.filter(|d| *d < cut), "person {}", k);
            let near = super::NearPieces::of(&a, &b, cut, shift.abs());
            prop_assert_eq!(near.closest_shifted(shift, cut), want.filter(|d| *d < cut), "person {}", k);
        }
    }
}
