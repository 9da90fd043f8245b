//! `crowdtouch gesture classify` and `crowdtouch library …` on the command line
//! (issue 15, "Done when" 3): every recording format the project reads, a labelled
//! test directory, adding a person's gesture, and a corrupt library.

use crowdtouch::crowd::motion::BuildParams;
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::{MotionClass, SHIPPED_BYTES};
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle};
use crowdtouch::input::recording::JsonlWriter;
use crowdtouch::input::{AxisRange, SurfaceInfo};
use crowdtouch::vocab::Micros;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The binary, with an empty config search path (the embedded default config).
fn bin(home: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_crowdtouch"));
    c.env("XDG_CONFIG_HOME", home).env("HOME", home);
    c
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// A generated gesture of `class` as a JSONL recording on a 1210 × 680 mm glass.
fn write_gesture(class: MotionClass, seed: u64, path: &Path) {
    let device = (1210.0, 680.0);
    let two_hands = matches!(
        class,
        MotionClass::Join
            | MotionClass::Split
            | MotionClass::SplitThenTranslate
            | MotionClass::TranslateThenJoin
    );
    let fingers = if two_hands { vec![2, 2] } else { vec![3] };
    let style = GestureStyle {
        fingers,
        duration_s: 1.0,
        size_mm: 150.0,
        placement: Vec2::new(0.5, 0.5),
        orientation_rad: 0.3,
        jitter_mm: 0.3,
        device_mm: device,
        rate_hz: 100.0,
        stagger_ms: 30.0,
        early_lifts: 0,
        bow: 0.05,
        spacing_mm: 20.0,
        clockwise: seed % 2 == 0,
    };
    let surface = SurfaceInfo {
        name: "generated".to_string(),
        x: AxisRange {
            min: 0.0,
            max: device.0 * 10.0,
            resolution: 10.0,
        },
        y: AxisRange {
            min: 0.0,
            max: device.1 * 10.0,
            resolution: 10.0,
        },
        max_contacts: 10,
    };
    let frames = to_frames(&generate(class, &style, seed), device, Micros(250_000));
    let file = std::fs::File::create(path).unwrap();
    let mut w = JsonlWriter::new(&surface, std::io::BufWriter::new(file)).unwrap();
    for f in &frames {
        w.frame(f).unwrap();
    }
    w.flush().unwrap();
}

/// `gesture classify --json` reads every format: JSONL, evemu (a `.events` file
/// with its own header, and a `.evemu`), libinput's YAML and hid-recorder; every
/// line is a JSON object with the documented keys, every file has a line.
#[test]
fn classify_json_reads_every_recording_format() {
    let dir = tempfile::tempdir().unwrap();
    let jsonl = dir.path().join("twist.jsonl");
    write_gesture(MotionClass::Twist, 4, &jsonl);
    let files = [
        jsonl.clone(),
        fixture("atmel-maxtouch.4-finger-drag-down.events"),
        fixture("dell-canvas-27-touch.evemu"),
        fixture("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml"),
        fixture("hid/wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid"),
    ];
    let out = bin(dir.path())
        .args(["gesture", "classify", "--json"])
        .args(&files)
        .output()
        .unwrap();
    let stdout = ok(&out);
    let mut per_file = vec![0; files.len()];
    for line in stdout.lines() {
        let v: Value =
            serde_json::from_str(line).unwrap_or_else(|e| panic!("not JSON ({e}): {line}"));
        for key in ["file", "t_us", "fingers", "class", "weight"] {
            assert!(v.get(key).is_some(), "no {key}: {line}");
        }
        assert!(v["t_us"].is_u64() && v["fingers"].is_u64() && v["weight"].is_f64());
        let w = v["weight"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&w), "{line}");
        match &v["class"] {
            Value::String(c) => {
                assert!(c.parse::<MotionClass>().is_ok(), "{line}");
                assert!(v["neighbours"].as_array().is_some_and(|n| !n.is_empty()));
            }
            Value::Null => assert!(v["rejected"].is_string(), "{line}"),
            other => panic!("class {other}: {line}"),
        }
        let file = v["file"].as_str().unwrap();
        let k = files
            .iter()
            .position(|f| f.display().to_string() == file)
            .unwrap_or_else(|| panic!("unknown file {file}"));
        per_file[k] += 1;
    }
    eprintln!("{stdout}");
    for (f, n) in files.iter().zip(&per_file) {
        assert!(*n > 0, "no gesture line for {}", f.display());
    }
    // The generated gesture is one gesture, recognised as what was drawn.
    let first: Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
    assert_eq!(per_file[0], 1);
    assert_eq!(first["class"], "twist", "{first}");
    assert_eq!(first["fingers"], 3);
}

/// `library eval --test DIR` on a small labelled directory prints both confusion
/// matrices (basic classes and all ten) and the feature ablation.
#[test]
fn library_eval_on_a_test_directory_prints_both_matrices() {
    let dir = tempfile::tempdir().unwrap();
    let test = dir.path().join("test");
    for (i, class) in MotionClass::ALL.iter().enumerate() {
        let sub = test.join(class.as_str());
        std::fs::create_dir_all(&sub).unwrap();
        write_gesture(*class, 100 + i as u64, &sub.join("a.jsonl"));
    }
    let out = bin(dir.path())
        .args(["library", "eval", "--test"])
        .arg(&test)
        .output()
        .unwrap();
    let stdout = ok(&out);
    eprintln!("{stdout}");
    assert!(stdout.contains("10 test gestures"), "{stdout}");
    let basic = stdout.find("six basic classes").expect("basic matrix");
    let all = stdout.find("all ten classes").expect("all-class matrix");
    assert!(basic < all);
    assert_eq!(stdout.matches("true \\ recognised").count(), 2, "{stdout}");
    // Each matrix has a row per class tested: 6, then 10.
    let rows = |from: usize, to: usize| {
        stdout[from..to]
            .lines()
            .filter(|l| {
                MotionClass::ALL
                    .iter()
                    .any(|c| l.split_whitespace().next() == Some(c.as_str()))
            })
            .count()
    };
    let ablation = stdout
        .find("with one of eq. 12's features removed")
        .unwrap();
    assert_eq!(rows(basic, all), 6);
    assert_eq!(rows(all, ablation), 10);
    for f in ["centroid", "spread", "rotation", "mobb"] {
        assert!(stdout[ablation..].contains(f), "{stdout}");
    }
}

/// The gesture count of `class` in `library show`'s table.
fn shown(out: &str, class: &str) -> u64 {
    let row = out
        .lines()
        .find(|l| l.split_whitespace().next() == Some(class))
        .unwrap_or_else(|| panic!("no {class} row:\n{out}"));
    row.split_whitespace().nth(2).unwrap().parse().unwrap()
}

/// `library add --class twist` writes a library with one more twist gesture.
#[test]
fn library_add_writes_a_library_with_one_more_gesture() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("mine.jsonl");
    write_gesture(MotionClass::Twist, 6, &rec);
    let lib = dir.path().join("mine.ctgl");
    let out = bin(dir.path())
        .args(["library", "add", "--class", "twist", "--out"])
        .arg(&lib)
        .arg(&rec)
        .output()
        .unwrap();
    let said = ok(&out);
    assert!(said.contains("1 twist gestures added"), "{said}");
    // The shipped library: its builder's gestures per class, and ten classes.
    let p = BuildParams::default();
    let per_class = (p.motions_per_class * p.gestures_per_motion) as u64;
    let after = ok(&bin(dir.path())
        .args(["library", "show", "--library"])
        .arg(&lib)
        .output()
        .unwrap());
    assert_eq!(shown(&after, "twist"), per_class + 1);
    assert_eq!(shown(&after, "translate"), per_class);
    assert_eq!(shown(&after, "total"), 10 * per_class + 1);
}

/// A corrupt library is refused by `library eval` with its file and the offset at
/// fault, exit status 1: bytes flipped inside a motion (caught by the checksum)
/// and a gesture count made absurd (caught where the structure breaks).
#[test]
fn library_eval_refuses_a_corrupt_file_naming_file_and_offset() {
    let dir = tempfile::tempdir().unwrap();
    let mut flipped = SHIPPED_BYTES.to_vec();
    for b in &mut flipped[1000..1004] {
        *b ^= 0xff;
    }
    let mut count = SHIPPED_BYTES.to_vec();
    count[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    for (name, bytes) in [("flipped.ctgl", flipped), ("count.ctgl", count)] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = bin(dir.path())
            .args(["library", "eval", "--library"])
            .arg(&path)
            .output()
            .unwrap();
        let err = text(&out.stderr);
        eprintln!("{name}: {err}");
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains(&path.display().to_string()), "{err}");
        assert!(err.contains("offset "), "{err}");
        assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    }
}

/// Every gesture line `gesture classify --json` prints for `files` (with `config`
/// when given), as `(file name, t_us, fingers, class or None, line)`.
fn classified(
    home: &Path,
    files: &[PathBuf],
    config: Option<&Path>,
) -> Vec<(String, u64, u64, Option<String>, String)> {
    let mut cmd = bin(home);
    cmd.args(["gesture", "classify", "--json"]);
    if let Some(c) = config {
        cmd.arg("--config").arg(c);
    }
    let stdout = ok(&cmd.args(files).output().unwrap());
    stdout
        .lines()
        .map(|line| {
            let v: Value = serde_json::from_str(line).unwrap();
            let file = Path::new(v["file"].as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned();
            let class = v["class"].as_str().map(str::to_string);
            if class.is_none() {
                assert!(v["rejected"].is_string(), "{line}");
            }
            (
                file,
                v["t_us"].as_u64().unwrap(),
                v["fingers"].as_u64().unwrap(),
                class,
                line.to_string(),
            )
        })
        .collect()
}

/// The real recordings in `tests/fixtures/` come out as a person would label them
/// (issue 28): multi-finger drags and scrolls are translate; touch-and-release
/// files and taps are rejected (`"class": null` with a reason); the one-finger
/// drag up and down is not a twist.
#[test]
fn real_recordings_come_out_as_a_person_would_label_them() {
    let dir = tempfile::tempdir().unwrap();
    // The N-Trig events come without their device header: joined to its `.desc`.
    // That description has no resolution, so a config gives the glass's size
    // (a 12.1" tablet, 261 x 163 mm).
    let ntrig = |events: &str| {
        let path = dir.path().join(events);
        let mut text = std::fs::read_to_string(fixture("ntrig-multitouch.desc")).unwrap();
        text.push_str(&std::fs::read_to_string(fixture(events)).unwrap());
        std::fs::write(&path, text).unwrap();
        path
    };
    let ntrig_files = [
        ntrig("ntrig-multitouch.1-finger-drag-NW-SE.events"),
        ntrig("ntrig-multitouch.2-fingers-touch-release.events"),
    ];
    // Files without an axis resolution are read with a config giving their glass's
    // size, as a table's config would (sizes from tests/fixtures/gestures/expected.tsv):
    // the physical features are in mm of glass.
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/crowdtouch.ron"),
    )
    .unwrap();
    let sized = |name: &str, w: f64, h: f64| {
        let text = shipped.replace(
            "size_mm: Some((1210.0, 680.0))",
            &format!("size_mm: Some(({w:.1}, {h:.1}))"),
        );
        assert_ne!(text, shipped, "the shipped config names the glass's size");
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    // A 12.1" tablet, 261 x 163 mm.
    let config = sized("ntrig.ron", 261.0, 163.0);
    let atmel = [
        fixture("atmel-maxtouch.1-finger-drag-up-down.events"),
        fixture("atmel-maxtouch.2-fingers-touch-release.events"),
        fixture("atmel-maxtouch.4-finger-drag-down.events"),
    ];
    let ep = [
        fixture("ep0430m09.2-finger-scroll-down.events"),
        fixture("ep0430m09.2-fingers-touch-release.events"),
    ];
    let files = [
        fixture("dell-canvas-27-touch.evemu"),
        fixture("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml"),
    ];
    let mut lines = classified(dir.path(), &files, None);
    lines.extend(classified(
        dir.path(),
        &atmel,
        Some(&sized("atmel.ron", 154.0, 92.0)),
    ));
    lines.extend(classified(
        dir.path(),
        &ep,
        Some(&sized("ep0430m09.ron", 95.0, 57.0)),
    ));
    lines.extend(classified(dir.path(), &ntrig_files, Some(&config)));
    for l in &lines {
        eprintln!("{}", l.4);
    }
    let of = |name: &str| -> Vec<&(String, u64, u64, Option<String>, String)> {
        lines.iter().filter(|l| l.0 == name).collect()
    };
    let only = |name: &str| {
        let v = of(name);
        assert_eq!(v.len(), 1, "{name}: {v:?}");
        v[0].3.clone()
    };
    // Drags and scrolls of several fingers: translate.
    assert_eq!(
        only("atmel-maxtouch.4-finger-drag-down.events").as_deref(),
        Some("translate")
    );
    assert_eq!(
        only("ep0430m09.2-finger-scroll-down.events").as_deref(),
        Some("translate")
    );
    // Touch and release: never a command.
    for name in [
        "atmel-maxtouch.2-fingers-touch-release.events",
        "ep0430m09.2-fingers-touch-release.events",
        "ntrig-multitouch.2-fingers-touch-release.events",
    ] {
        for l in of(name) {
            assert_eq!(l.3, None, "{name}: {}", l.4);
        }
    }
    // One finger dragged: a translate (or nothing), never a twist.
    for name in [
        "atmel-maxtouch.1-finger-drag-up-down.events",
        "ntrig-multitouch.1-finger-drag-NW-SE.events",
    ] {
        for l in of(name) {
            assert_ne!(l.3.as_deref(), Some("twist"), "{name}: {}", l.4);
        }
    }
    assert_eq!(
        only("ntrig-multitouch.1-finger-drag-NW-SE.events").as_deref(),
        Some("translate")
    );
    // The Dell Canvas: the two-finger touch at the start is a tap; the four
    // fingers moving together at 9.76 s are a translate.
    let dell = of("dell-canvas-27-touch.evemu");
    assert_eq!(dell[0].3, None, "{}", dell[0].4);
    let four = dell
        .iter()
        .find(|l| l.2 == 4 && (9_700_000..9_800_000).contains(&l.1))
        .expect("the four-finger gesture at 9.76 s");
    assert_eq!(four.3.as_deref(), Some("translate"), "{}", four.4);
    // The touchpad's two-finger scroll travels 7 mm: too short to be a command on
    // a table, but if it is one, it is a translate.
    for l in of("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml") {
        assert!(
            matches!(l.3.as_deref(), None | Some("translate")),
            "{}",
            l.4
        );
    }
}

/// `library eval --cross-style` prints the four evaluations (leave-one-out on each
/// generator, each trained on one and tested on the other), each with both
/// matrices and eq. 12's baseline beside, a summary and the rejection figures.
#[test]
fn library_eval_cross_style_prints_four_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin(dir.path())
        .args(["library", "eval", "--cross-style", "--per-class", "3"])
        .output()
        .unwrap();
    let stdout = ok(&out);
    eprintln!("{stdout}");
    for run in [
        "== leave-one-out synth ==",
        "== leave-one-out style2 ==",
        "== train synth, test style2 ==",
        "== train style2, test synth ==",
    ] {
        assert!(stdout.contains(run), "{run}");
    }
    assert_eq!(stdout.matches("true \\ recognised").count(), 8, "{stdout}");
    assert_eq!(stdout.matches("eq. 12 alone (baseline)").count(), 4);
    assert!(stdout.contains("summary") && stdout.contains("rejection ("));
}

/// Cross-style recognition on a small deterministic set (6 gestures per class and
/// generator, seed 28): the recogniser (eq. 12 plus the physical features) beats
/// eq. 12 alone in both directions and reaches issue 28's 90 % both ways on the
/// six basic classes (91.7 % each here; 92–99 % with 30 per class over seeds
/// 27–33, docs/gestures.md "Accuracy"). Leave-one-out on so small a set is
/// coarse — K = 10 neighbours and only 5 others of the gesture's class — so its
/// floor is what it reaches (88.9 % synth), a regression failing.
#[test]
fn cross_style_recognition_beats_eq_12_both_ways() {
    use crowdtouch::gesture::eval::{cross_style, Example};
    use crowdtouch::gesture::generator::{labelled_set, Generator};
    use crowdtouch::gesture::knn::SearchParams;
    use crowdtouch::gesture::physical::PhysicalWeights;
    use crowdtouch::gesture::synth::StyleRanges;
    let set = |g: Generator| -> Vec<Example> {
        labelled_set(g, &MotionClass::ALL, 6, 28, Some(&StyleRanges::default()))
            .iter()
            .filter_map(|d| Example::of(d.class, &d.tracks).ok())
            .collect()
    };
    let (a, b) = (set(Generator::Synth), set(Generator::Style2));
    let runs = cross_style(
        ("synth", &a),
        ("style2", &b),
        &PhysicalWeights::default(),
        &SearchParams::default(),
    );
    for r in &runs {
        eprintln!(
            "{}: basic {:.3} (eq. 12 {:.3}), all {:.3} (eq. 12 {:.3})",
            r.name,
            r.basic.accuracy,
            r.baseline_basic.accuracy,
            r.all.accuracy,
            r.baseline_all.accuracy
        );
    }
    for r in &runs[2..] {
        assert!(r.basic.accuracy >= 0.9, "{}: {}", r.name, r.basic.accuracy);
        assert!(r.basic.accuracy > r.baseline_basic.accuracy, "{}", r.name);
        assert!(r.all.accuracy > r.baseline_all.accuracy, "{}", r.name);
    }
    assert!(runs[0].basic.accuracy >= 0.88, "{}", runs[0].basic.accuracy);
    assert!(runs[1].all.accuracy > runs[1].baseline_all.accuracy);
}
