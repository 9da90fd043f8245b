//! Gestures people drew against the generated cold start (issue 28 item 6,
//! `gestures.collected`): a person whose convention differs from the generator's
//! (they spread their fingers to *contract* the crowd, as if pulling it in) adds
//! eight such gestures to the shipped library. The more their gestures weigh
//! (`Weigh(w)`), the more of their new spreads are read their way; `Replace`
//! recognises contract from their gestures alone; and the config loads either.

use crowdtouch::config::{load_recogniser, Collected};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::knn::{SearchParams, Searcher};
use crowdtouch::gesture::library::{shipped, write_library, Library, LibraryGesture, MotionClass};
use crowdtouch::gesture::recognise::Recogniser;
use crowdtouch::gesture::resample::prepare_scaled;
use crowdtouch::gesture::synth::{generate, GestureStyle};
use crowdtouch::gesture::track::GestureTracks;

fn style() -> GestureStyle {
    GestureStyle {
        fingers: vec![3],
        duration_s: 0.9,
        size_mm: 140.0,
        placement: Vec2::new(0.5, 0.5),
        orientation_rad: 0.3,
        jitter_mm: 0.4,
        device_mm: (1210.0, 680.0),
        rate_hz: 120.0,
        stagger_ms: 25.0,
        early_lifts: 0,
        bow: 0.0,
        spacing_mm: 22.0,
        clockwise: false,
    }
}

fn spread(seed: u64) -> GestureTracks {
    generate(MotionClass::Expand, &style(), seed)
}

/// The shipped library with p1's eight spreads labelled contract.
fn personal() -> Library {
    let mut lib = shipped().unwrap();
    let contract = lib.class_id("contract").unwrap();
    let motion = lib
        .motions
        .iter()
        .position(|m| m.class == contract)
        .unwrap() as u32;
    for seed in 0..8 {
        let (gesture, scale_mm) = prepare_scaled(&spread(100 + seed)).unwrap();
        lib.gestures.push(LibraryGesture {
            class: contract,
            motion,
            gesture,
            origin: format!("collected from p1 #{seed}"),
            participant: "p1".into(),
            device: "table".into(),
            scale_mm: Some(scale_mm),
        });
    }
    lib
}

/// Of p1's ten new spreads, how many are read as contract, and contract's mean
/// share of the vote.
fn contract_reads(r: &Recogniser) -> (usize, f64) {
    let mut searcher = Searcher::new();
    let params = SearchParams::default();
    let mut n = 0;
    let mut share = 0.0;
    for seed in 500..510 {
        let c = r.classify(&spread(seed), &params, &mut searcher).unwrap();
        let rec = c.recognised;
        let contract: f64 = rec
            .neighbours
            .iter()
            .filter(|nb| r.class_name(r.class_of(nb.entry)) == "contract")
            .map(|nb| nb.weight)
            .sum();
        share += contract / 10.0;
        if r.class_name(rec.class) == "contract" {
            n += 1;
        }
        let total: f64 = rec.neighbours.iter().map(|nb| nb.weight).sum();
        assert!((total - 1.0).abs() < 1e-9, "weights sum to {total}");
    }
    (n, share)
}

#[test]
fn a_persons_gestures_count_more_the_more_they_weigh() {
    let lib = personal();
    let at = |w: f64| {
        let r = Recogniser::new(lib.clone(), "personal", None)
            .unwrap()
            .with_collected_weight(w);
        contract_reads(&r)
    };
    let (n1, s1) = at(1.0);
    let (n3, s3) = at(3.0);
    let (n20, s20) = at(20.0);
    eprintln!("contract reads {n1} {n3} {n20}, shares {s1:.3} {s3:.3} {s20:.3}");
    assert!(
        s1 < s3 && s3 < s20,
        "contract shares {s1:.2} {s3:.2} {s20:.2}"
    );
    assert!(n1 <= n3 && n3 <= n20, "contract reads {n1} {n3} {n20}");
    // Measured: 4, 4 and 7 of 10; shares 0.27, 0.42, 0.69.
    assert!(
        n20 > n1 && n20 >= 6,
        "at weight 20, {n20} of 10 spreads read as contract ({n1} at 1)"
    );
    // Without the person's gestures, the generator's convention: expand.
    let r = Recogniser::new(shipped().unwrap(), "shipped", None).unwrap();
    assert_eq!(contract_reads(&r).0, 0);
}

#[test]
fn replace_recognises_a_class_from_the_persons_gestures_alone_and_the_config_loads_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("personal.ctgl");
    std::fs::write(&path, write_library(&personal())).unwrap();
    let replaced = load_recogniser(Some(&path), None, Collected::Replace).unwrap();
    let lib = replaced.library();
    let contract = lib.class_id("contract").unwrap();
    let of_contract: Vec<&str> = lib
        .gestures
        .iter()
        .filter(|g| g.class == contract)
        .map(|g| g.participant.as_str())
        .collect();
    assert_eq!(of_contract, vec!["p1"; 8]);
    // Other classes keep their generated gestures.
    let expand = lib.class_id("expand").unwrap();
    assert!(lib.gestures.iter().filter(|g| g.class == expand).count() >= 50);
    let weighed = load_recogniser(Some(&path), None, Collected::Weigh(4.0)).unwrap();
    assert_eq!(weighed.collected_weight(), 4.0);
    assert_eq!(weighed.library().gestures.len(), personal().gestures.len());
}
