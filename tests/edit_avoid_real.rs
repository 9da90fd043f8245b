//! Collision avoidance by retiming on real pedestrian files (tests/fixtures/crowd,
//! UCY via the Social-GAN release; provenance in its README): never worse than
//! the input, on the number of colliding pairs and on the closest distance;
//! every person's times strictly increasing, never negative, moved by no more
//! than the bound; only people who were in a collision retimed (at most twice as
//! many as were, the bound, and here never more than were); the places
//! untouched.
//!
//! students001 at 0.5 m (606 pairs) takes seconds in a release build and is run
//! by `crowdtouch edit apply tests/fixtures/crowd/students001.txt --format eth
//! --avoid-collisions --threshold 0.5 --json` (docs/motion-editing.md); here
//! the debug build runs the other five cases.

use crowdtouch::crowd::edit::io::{read_eth, EthOptions};
use crowdtouch::crowd::edit::{avoid, detect, AvoidParams, AvoidReport, Stuck, TrackSet};

fn load(name: &str) -> TrackSet {
    let path = format!("{}/tests/fixtures/crowd/{name}", env!("CARGO_MANIFEST_DIR"));
    read_eth(
        &std::fs::read_to_string(&path).expect("fixture"),
        EthOptions::default(),
    )
    .expect("a valid ETH/UCY file")
}

/// Runs avoidance and checks everything that must hold on any input.
fn never_worse(name: &str, threshold_m: f64) -> AvoidReport {
    let before = load(name);
    let params = AvoidParams {
        threshold_m,
        ..AvoidParams::default()
    };
    let c0 = detect(&before, threshold_m).unwrap();
    let mut set = before.clone();
    let r = avoid(&mut set, &params).unwrap();
    let c1 = detect(&set, threshold_m).unwrap();
    eprintln!(
        "{name} at {threshold_m} m: pairs {} -> {} ({} companions), closest {:?} -> {:?}, \
         {} of {} people in a collision retimed ({} shifts, {} retimings), median {:.2} s, max {:.2} s",
        c0.pair_count(),
        c1.pair_count(),
        r.companions,
        c0.min_distance_m(),
        c1.min_distance_m(),
        r.retimed_people,
        r.people_in_collision,
        r.shifts,
        r.retimings,
        r.median_shift_s,
        r.max_shift_s
    );
    assert_eq!(r.pairs_before, c0.pair_count());
    assert_eq!(
        r.pairs_after,
        c1.pair_count(),
        "the report counts what detection finds"
    );
    assert!(
        c1.pair_count() <= c0.pair_count(),
        "{name}: more pairs than the input"
    );
    if let (Some(a), Some(b)) = (c1.min_distance_m(), c0.min_distance_m()) {
        assert!(a >= b, "{name}: closest pair {a} m, the input's {b} m");
    }
    assert!(!r.reverted, "{name}: each kept change makes things better");
    set.validate().unwrap();
    let mut in_pair = vec![false; before.tracks.len()];
    for q in &c0.pairs {
        in_pair[q.a] = true;
        in_pair[q.b] = true;
    }
    assert!(c0.is_complete());
    let mut retimed = 0;
    for (k, (a, b)) in set.tracks.iter().zip(&before.tracks).enumerate() {
        assert_eq!(a.points, b.points, "{name}: person {} moved", a.id);
        assert!(a.times_s.windows(2).all(|w| w[1] > w[0]));
        assert!(a.times_s[0] >= 0.0);
        let shift = a
            .times_s
            .iter()
            .zip(&b.times_s)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(
            shift <= params.max_shift_s + 1e-9,
            "{name}: {} moved {shift} s",
            a.id
        );
        if shift > 0.0 {
            retimed += 1;
            assert!(in_pair[k], "{name}: {} retimed, never in a collision", a.id);
        }
    }
    let in_collision = in_pair.iter().filter(|&&x| x).count();
    assert_eq!(retimed, r.retimed_people);
    assert_eq!(in_collision, r.people_in_collision);
    assert!(retimed <= 2 * in_collision);
    r
}

#[test]
fn zara01_at_three_thresholds() {
    assert_eq!(never_worse("crowds_zara01.txt", 0.2).pairs_before, 0);
    // 0.3 m: the file's three pairs all separated.
    let r = never_worse("crowds_zara01.txt", 0.3);
    assert_eq!((r.pairs_before, r.pairs_after), (3, 0), "{r:?}");
    // 0.5 m: 27 pairs; those left are people walking together.
    let r = never_worse("crowds_zara01.txt", 0.5);
    assert_eq!(r.pairs_before, 27);
    assert!(r.pairs_after <= 5, "{r:?}");
}

#[test]
fn students001_at_0_2_m() {
    let r = never_worse("students001.txt", 0.2);
    assert_eq!(r.pairs_before, 48);
    assert!(r.pairs_after <= 12, "{r:?}");
}

#[test]
fn students001_at_0_3_m_halves_the_pairs_that_are_not_companions() {
    let r = never_worse("students001.txt", 0.3);
    assert_eq!(r.pairs_before, 168);
    let companions_left = r
        .remaining
        .iter()
        .filter(|x| x.why == Stuck::Companions)
        .count();
    assert_eq!(companions_left, r.companions);
    // Companions walk together throughout and are in the input's pairs too: the
    // pairs that are not companions at least halve.
    let others_before = r.pairs_before - r.companions;
    let others_after = r.pairs_after - r.companions;
    assert!(2 * others_after <= others_before, "{r:?}");
}
