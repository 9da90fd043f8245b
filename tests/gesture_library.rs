//! The shipped gesture library (issue 15, "Done when" 2): it is what the builder
//! makes, its leave-one-out accuracy on the six basic classes reaches the paper's
//! 89.6 % (gesture-driven section 8.2), so does a separately generated test set
//! (other seeds, devices and style ranges, cut from touch frames by the daemon's own
//! segmentation), and the FPCA of its motions reconstructs them within 1 %
//! (section 6.2).

use crowdtouch::crowd::motion::{
    build_library, fpca, library_agents, library_specs, simulate, BuildParams, CrowdMotion,
    SHIPPED_SEED,
};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::capture::TapThresholds;
use crowdtouch::gesture::eval::{evaluate, outcomes, train_test, Evaluation, Example};
use crowdtouch::gesture::features::GestureFeatures;
use crowdtouch::gesture::find::find_gestures;
use crowdtouch::gesture::knn::SearchParams;
use crowdtouch::gesture::library::{
    read_library, shipped, write_library, MotionClass, SHIPPED_BYTES,
};
use crowdtouch::gesture::physical::{PhysicalFeatures, PhysicalWeights};
use crowdtouch::gesture::reject::Movement;
use crowdtouch::gesture::segment::SegmentParams;
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle, StyleRanges};
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::Micros;

/// The paper's leave-one-out accuracy on the basic classes (section 8.2).
const PAPER_BASIC_ACCURACY: f64 = 0.896;

fn labelled_basic() -> Vec<(MotionClass, GestureFeatures)> {
    let lib = shipped().unwrap();
    lib.gestures
        .iter()
        .filter_map(|g| Some((lib.kind(g.class)?, g)))
        .filter(|(kind, _)| kind.is_basic())
        .map(|(kind, g)| (kind, GestureFeatures::of(&g.gesture)))
        .collect()
}

fn print(what: &str, e: &Evaluation) {
    eprintln!(
        "{what}: accuracy {:.1} % (mean of classes {:.1} %)",
        100.0 * e.accuracy,
        100.0 * e.mean_class_accuracy
    );
    for (c, row) in e.confusion.classes.iter().zip(&e.confusion.counts) {
        eprintln!("  {:<24} {row:?}", c.as_str());
    }
}

/// (a) `config/gestures/library.ctgl` is exactly what `library build` with its
/// defaults makes: nobody edited it by hand, and the builder is deterministic. It
/// is compared as the library it reads as, and as bytes (format version 2, as a
/// rebuild writes it).
#[test]
#[ignore = "rebuilds the whole library: about 2 minutes in a debug build; run with --ignored"]
fn the_shipped_file_is_what_the_builder_makes() {
    let t = std::time::Instant::now();
    let lib = build_library(&BuildParams::default()).unwrap();
    eprintln!("built the shipped library in {:?}", t.elapsed());
    assert_eq!(BuildParams::default().seed, SHIPPED_SEED);
    assert_eq!((lib.motions.len(), lib.gestures.len()), (150, 750));
    let shipped = shipped().unwrap();
    assert!(lib == shipped, "the shipped library differs from a rebuild");
    let bytes = write_library(&lib);
    assert_eq!(read_library(&bytes, "rebuilt").unwrap(), shipped);
    // The shipped file is this build's writing of it, byte for byte.
    assert!(
        bytes == SHIPPED_BYTES,
        "the shipped file is not the rebuild's bytes"
    );
}

/// (b) Leave-one-out on the shipped library's basic classes, default search, by
/// the recogniser's distance (eq. 12 plus the physical features; the library
/// holds gestures of both generators, on which eq. 12 alone reaches 85 %).
/// The shipped library's gestures of the basic classes as the recogniser sees
/// them (their movement unknown: never rejected as still).
fn library_basic_examples() -> Vec<Example> {
    let lib = shipped().unwrap();
    lib.gestures
        .iter()
        .filter_map(|g| Some((lib.kind(g.class).filter(|k| k.is_basic())?, g)))
        .map(|(class, g)| Example {
            class,
            features: GestureFeatures::of(&g.gesture),
            physical: PhysicalFeatures::of(&g.gesture, g.scale_mm),
            movement: Movement {
                travel_mm: f64::INFINITY,
                jitter_mm: 0.0,
            },
        })
        .collect()
}

#[test]
fn leave_one_out_basic_accuracy_reaches_the_papers() {
    let set = library_basic_examples();
    assert_eq!(set.len(), 6 * 15 * 5);
    let e = evaluate(&outcomes(
        &set,
        None,
        &PhysicalWeights::default(),
        &SearchParams::default(),
    ));
    print("leave-one-out, basic classes", &e);
    assert_eq!(e.unclassified, 0);
    assert!(
        e.accuracy >= PAPER_BASIC_ACCURACY,
        "leave-one-out basic accuracy {:.3}",
        e.accuracy
    );
}

/// (c) A test set made apart from the library: other seeds (and seeds unlike
/// `library test-set`'s), the test ranges; each gesture turned into touch frames and
/// cut by the daemon's segmentation (`find_gestures`, the default config's
/// thresholds) before it is recognised against the shipped library's basic classes,
/// by the recogniser's distance (eq. 12 plus the physical features). Eq. 12 alone
/// is printed beside it: since `synth` draws a pinch as a thumb closing on the
/// fingers opposite it (two groups converging, as a join's hands do) eq. 12's
/// scale-free features take many such pinches for joins (85 % here), which is what
/// the physical features are for.
#[test]
fn a_separate_test_set_reaches_the_papers_accuracy() {
    let ranges = StyleRanges::test_set();
    let defaults = crowdtouch::config::Config::embedded_default();
    let seg: SegmentParams = crowdtouch::engine::segment_params(&defaults);
    let taps: TapThresholds = crowdtouch::engine::tap_thresholds(&defaults);
    let mut rng = SplitMix64::new(0x7e57_0015);
    let per_class = 25;
    let mut test = Vec::new();
    let mut lost = Vec::new();
    for class in MotionClass::BASIC {
        for _ in 0..per_class {
            let (style_seed, seed) = (rng.next_u64(), rng.next_u64());
            let style = GestureStyle::random(class, style_seed, &ranges);
            let tracks = generate(class, &style, seed);
            let frames = to_frames(&tracks, style.device_mm, Micros(2_000_000));
            let glass = Vec2::new(style.device_mm.0, style.device_mm.1);
            let found = find_gestures(&frames, glass, seg, taps);
            // One gesture with every finger, recognisable.
            match found.as_slice() {
                [f] => match &f.tracks {
                    Ok(t) if t.fingers.len() == tracks.fingers.len() => {
                        test.push(Example::of(class, t).unwrap());
                    }
                    other => lost.push(format!("{class} {seed:#x}: {other:?}")),
                },
                _ => lost.push(format!("{class} {seed:#x}: {} gestures found", found.len())),
            }
        }
    }
    assert!(lost.is_empty(), "segmentation lost gestures: {lost:#?}");
    let baseline: Vec<(MotionClass, GestureFeatures)> =
        test.iter().map(|e| (e.class, e.features.clone())).collect();
    let b = train_test(&labelled_basic(), &baseline, &SearchParams::default());
    print("separate test set, basic classes, eq. 12 alone", &b);
    let e = evaluate(&outcomes(
        &library_basic_examples(),
        Some(&test),
        &PhysicalWeights::default(),
        &SearchParams::default(),
    ));
    print("separate test set, basic classes", &e);
    assert_eq!(test.len(), 6 * per_class);
    assert!(
        e.accuracy >= PAPER_BASIC_ACCURACY,
        "test-set basic accuracy {:.3}",
        e.accuracy
    );
}

/// (d) FPCA with 15 components reconstructs every sampled library motion within
/// 1 % (section 6.2), rebuilt from the builder's pieces: 3 motions of each class,
/// the same specs and simulation as the shipped build (their FPCA means are the
/// shipped library's). "1 %" is the share of the motion's variation about its mean
/// trajectory that is lost (`‖X − X̂‖ / ‖X − X̄‖`), and also the RMS error in units
/// of the crowd's starting RMS radius. Over all 150 shipped motions these are at
/// most 0.33 % and 0.28 %; measured against how far agents move from their starts
/// (the strictest reading) the worst is 1.61 % (contract motion 12, whose agents
/// move least), printed here and in docs/gestures.md.
#[test]
fn fpca_reconstructs_library_motions_within_one_percent() {
    let p = BuildParams::default();
    let lib = shipped().unwrap();
    // The builder draws each class's spec seed first from one stream; the draws
    // between them (per motion: its mixture seed, and two per gesture) are
    // replayed to keep in step.
    let mut rng = SplitMix64::new(p.seed);
    let mut worst = (0.0, String::new());
    let mut worst_displacement: f64 = 0.0;
    for &class in &p.classes {
        let specs = library_specs(class, p.motions_per_class, rng.next_u64());
        for _ in 0..p.motions_per_class * (1 + 2 * p.gestures_per_motion) {
            rng.next_u64();
        }
        for index in [0, 7, 12] {
            let sim = simulate(&specs[index], &library_agents(), p.dt_s).unwrap();
            let m = CrowdMotion::from_world(&sim.tracks, sim.duration_s).unwrap();
            let f = fpca(&m, 15).unwrap();
            // The motion rebuilt is the shipped one.
            let k = class.index() * p.motions_per_class + index;
            assert_eq!(lib.motions[k].class, class.id());
            // Equal to rounding (1e-9 of the largest value, at least of 1e-6): the
            // agents' step sums its forces in another order
            // than the one the shipped library was built with (last bits only).
            let shipped_mean = &lib.motions[k].mean;
            let scale = shipped_mean.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert_eq!(shipped_mean.len(), f.mean.len());
            for (a, b) in shipped_mean.iter().zip(&f.mean) {
                assert!(
                    (a - b).abs() <= 1e-9 * scale.max(1e-6),
                    "{class} motion {index}: {a} rebuilt as {b}"
                );
            }
            let err = f.reconstruction_error(&m);
            assert!(err.relative_to_variation.is_finite() && err.rms.is_finite());
            let e = err.relative_to_variation.max(err.rms);
            if e > worst.0 {
                worst = (e, format!("{class} {index}"));
            }
            worst_displacement = worst_displacement.max(err.relative);
        }
    }
    eprintln!(
        "largest FPCA reconstruction error: {:.4} % ({}); against the agents' displacement {:.4} %",
        100.0 * worst.0,
        worst.1,
        100.0 * worst_displacement
    );
    assert!(worst.0 < 0.01, "reconstruction error {worst:?}");
}
