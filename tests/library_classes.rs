//! Classes and motions are data (issue 28, item 4): a library of three classes of
//! our choosing — `translate` and `twist` built from the simulator, and `crossing`,
//! a crowd motion imported from the UCY zara01 pedestrian tracks and paired with a
//! person's gestures (two hands drawn together) — is made with the `library`
//! commands, loads in the daemon, and a replayed gesture of each class is recognised
//! as that class and plays its motion (`gesture` event, `gesture_motion`, `plan`).
//! A class named in `gestures.disabled` is recognised and ignored; config names of
//! classes are checked against the library.

mod common;

use crowdtouch::config::Config;
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::{read_library, MotionClass};
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle, StyleRanges};
use crowdtouch::input::recording::{load_recording, OnBadFrame};
use crowdtouch::vocab::{Event, Micros, MotionPhase, TouchFrame};
use serde_json::Value;
use std::convert::Infallible;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const WAIT: Duration = Duration::from_secs(90);

/// The default config's glass (mm).
const GLASS_MM: (f64, f64) = (1210.0, 680.0);

/// The three classes and the built-in kind each one's gestures are drawn as.
const CLASSES: [(&str, MotionClass); 3] = [
    ("translate", MotionClass::Translate),
    ("twist", MotionClass::Twist),
    ("crossing", MotionClass::Join),
];

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

fn run_ok(args: &[&str]) -> String {
    let o = bin().args(args).output().unwrap();
    assert!(
        o.status.success(),
        "crowdtouch {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

fn run_err(args: &[&str]) -> String {
    let o = bin().args(args).output().unwrap();
    assert!(!o.status.success(), "crowdtouch {args:?} succeeded");
    String::from_utf8(o.stderr).unwrap()
}

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/crowd")
        .join(name)
        .display()
        .to_string()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A gesture of `kind` in open space left of the crowd, as the daemon's tests of
/// gesture commands draw them: 3 fingers (2 per hand for two hands), 150 mm.
fn style(kind: MotionClass, orientation_rad: f64) -> GestureStyle {
    let two_hands = matches!(kind, MotionClass::Join | MotionClass::Split);
    GestureStyle {
        fingers: if two_hands { vec![2, 2] } else { vec![3] },
        duration_s: 1.0,
        size_mm: 150.0,
        placement: Vec2::new(0.17, 0.5),
        orientation_rad,
        jitter_mm: 0.3,
        device_mm: GLASS_MM,
        rate_hz: 120.0,
        stagger_ms: 30.0,
        early_lifts: 0,
        bow: 0.0,
        spacing_mm: 20.0,
        clockwise: false,
    }
}

/// Writes frames as a JSONL recording of the default glass (0.1 mm units).
fn write_recording(frames: &[TouchFrame], path: &Path) {
    common::write_jsonl(frames, GLASS_MM, "test glass", path);
}

/// The three-class library, made with the `library` commands in `dir`.
fn three_class_library(dir: &Path) -> PathBuf {
    let base = dir.join("base.ctgl");
    let with_motion = dir.join("with-motion.ctgl");
    let lib = dir.join("three.ctgl");
    let cfg = dir.join("default.ron");
    std::fs::write(&cfg, crowdtouch::config::DEFAULT_CONFIG_RON).unwrap();
    run_ok(&[
        "library",
        "build",
        "--classes",
        "translate,twist",
        "--motions-per-class",
        "3",
        "--gestures-per-motion",
        "4",
        "--out",
        s(&base),
    ]);
    let out = run_ok(&[
        "library",
        "import-motion",
        "--library",
        s(&base),
        "--class",
        "crossing",
        &fixture("crowds_zara01.txt"),
        "--out",
        s(&with_motion),
    ]);
    assert!(
        out.contains("motion 6 of class crossing (a new class)"),
        "{out}"
    );
    // A person's crossing gestures: two hands drawn together, turned every way,
    // on the glass the recordings are written for (a gesture drawn for a smaller
    // glass and written as this one's would be scaled up, its hands spread past
    // one gesture's span).
    let mut recordings = Vec::new();
    for k in 0..8u64 {
        let mut st = GestureStyle::random(MotionClass::Join, 900 + k, &StyleRanges::default());
        st.orientation_rad = k as f64 * std::f64::consts::FRAC_PI_4;
        st.device_mm = GLASS_MM;
        let tracks = generate(MotionClass::Join, &st, 77 + k);
        let p = dir.join(format!("crossing-{k}.jsonl"));
        write_recording(&to_frames(&tracks, st.device_mm, Micros(500_000)), &p);
        recordings.push(p.display().to_string());
    }
    let mut args = vec![
        "library",
        "add",
        "--library",
        s(&with_motion),
        "--class",
        "crossing",
        "--participant",
        "p01",
        "--config",
        s(&cfg),
        "--out",
        s(&lib),
    ];
    args.extend(recordings.iter().map(String::as_str));
    let out = run_ok(&args);
    assert!(out.contains("8 crossing gestures added"), "{out}");
    lib
}

/// One recording of a gesture of each class, 3.5 s apart (`recording.jsonl`).
fn query_recording(dir: &Path) -> PathBuf {
    let mut frames = Vec::new();
    for (k, (_, kind)) in CLASSES.iter().enumerate() {
        let tracks = generate(*kind, &style(*kind, 0.3), 4242 + k as u64);
        frames.extend(to_frames(
            &tracks,
            GLASS_MM,
            Micros(500_000 + 3_500_000 * k as u64),
        ));
    }
    let p = dir.join("queries.jsonl");
    write_recording(&frames, &p);
    p
}

/// The default config with `queries` looped as its input, every touch a gesture,
/// `lib` as the gesture library, no real-time scheduling, its socket in `dir`, and
/// the given edits; written as `dir/c.ron`.
fn config(dir: &Path, queries: &Path, lib: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let base = crowdtouch::config::DEFAULT_CONFIG_RON;
    let a = base.find("inputs: [").unwrap();
    let b = a + base[a..].find("\n    ],\n").unwrap() + "\n    ],\n".len();
    let mut text = format!(
        "{}inputs: [Replay(files: [{:?}], looped: true, gap_ms: 300)],\n{}",
        &base[..a],
        queries.display().to_string(),
        &base[b..]
    );
    let sock = format!(
        "path: Some({:?}),",
        dir.join("ct.sock").display().to_string()
    );
    let library = format!("library: Some({:?}),", lib.display().to_string());
    for (from, to) in [
        ("priority: Some(20),", "priority: None,"),
        ("lock_memory: true,", "lock_memory: false,"),
        ("path: None,", sock.as_str()),
        ("library: None,", library.as_str()),
        (
            "all_touches_are_gestures: false,",
            "all_touches_are_gestures: true,",
        ),
    ]
    .iter()
    .chain(edits)
    {
        assert!(text.contains(from), "the config has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    let p = dir.join("c.ron");
    std::fs::write(&p, text).unwrap();
    p
}

/// A daemon started with a config; stopped (SIGTERM) on drop.
struct Daemon(Child);

impl Drop for Daemon {
    fn drop(&mut self) {
        let pid = nix::unistd::Pid::from_raw(self.0.id() as i32);
        let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
        let _ = self.0.wait();
    }
}

/// What a client saw of one gesture.
#[derive(Default, Debug)]
struct Seen {
    end: Option<Value>,
    approach: bool,
    plan_agents: Option<usize>,
}

#[test]
fn a_three_class_library_with_an_imported_motion_plays_each_class_in_the_daemon() {
    let dir = tempfile::tempdir().unwrap();
    let lib = three_class_library(dir.path());
    let show = run_ok(&["library", "show", "--library", s(&lib)]);
    for (name, motions, gestures) in [("translate", 3, 12), ("twist", 3, 12), ("crossing", 1, 8)] {
        let line = show
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no {name} in\n{show}"));
        let counts: Vec<&str> = line.split_whitespace().skip(1).collect();
        assert_eq!(
            counts,
            [motions.to_string(), gestures.to_string()],
            "{show}"
        );
    }
    assert!(
        show.contains("classes 3, participants 1 (24 gestures by no one named), devices 1"),
        "{show}"
    );
    let read = read_library(&std::fs::read(&lib).unwrap(), "three.ctgl").unwrap();
    assert_eq!(read.classes, ["translate", "twist", "crossing"]);
    assert!(read
        .gestures
        .iter()
        .filter(|g| read.class_name(g.class) == "crossing")
        .all(|g| g.motion == 6 && g.participant == "p01" && g.device == "test glass"));

    let queries = query_recording(dir.path());
    let c = config(dir.path(), &queries, &lib, &[]);
    let check = bin().args(["check-config"]).arg(&c).output().unwrap();
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let sock = dir.path().join("ct.sock");
    let _daemon = Daemon(
        bin()
            .args(["run", "--config"])
            .arg(&c)
            .env_remove("RUST_LOG")
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let t0 = Instant::now();
    let stream = loop {
        match UnixStream::connect(&sock) {
            Ok(s) => break s,
            Err(_) if t0.elapsed() < WAIT => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => panic!("no socket: {e}"),
        }
    };
    stream
        .set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    (&stream)
        .write_all(b"{\"type\":\"hello\",\"protocol\":1,\"subscribe\":[\"events\",\"plan\"]}\n")
        .unwrap();
    let mut r = BufReader::new(&stream);
    // Per gesture id, what was seen of it; per class, the first gesture that
    // played it fully.
    let mut by_id: std::collections::BTreeMap<u64, Seen> = Default::default();
    let mut done: Vec<&str> = Vec::new();
    let mut line = String::new();
    while done.len() < CLASSES.len() && t0.elapsed() < WAIT {
        line.clear();
        match r.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) if line.ends_with('\n') => {}
            _ => continue,
        }
        let v: Value = serde_json::from_str(&line).unwrap();
        match v["type"].as_str() {
            Some("gesture") if v["phase"] == "end" => {
                let id = v["id"].as_u64().unwrap();
                by_id.entry(id).or_default().end = Some(v);
            }
            Some("gesture_motion") if v["phase"] == "approach" => {
                by_id.entry(v["id"].as_u64().unwrap()).or_default().approach = true;
            }
            Some("plan") => {
                by_id
                    .entry(v["gesture"].as_u64().unwrap())
                    .or_default()
                    .plan_agents = v["agents"].as_array().map(Vec::len);
            }
            _ => continue,
        }
        for seen in by_id.values() {
            let Some(end) = &seen.end else { continue };
            let Some(class) = end["recognition"]["class"].as_str() else {
                continue;
            };
            let Some(&(name, _)) = CLASSES.iter().find(|c| c.0 == class) else {
                continue;
            };
            if seen.approach
                && seen.plan_agents == Some(100)
                && end["rejected"].is_null()
                && !done.contains(&name)
            {
                done.push(name);
            }
        }
    }
    let mut played = done.clone();
    played.sort_unstable();
    assert_eq!(
        played,
        ["crossing", "translate", "twist"],
        "every class recognised and played within {WAIT:?}; seen: {by_id:#?}"
    );
    // Every recognised gesture was recognised as the class drawn: the looped
    // recording's order, from wherever the client came in.
    let recognised: Vec<&str> = by_id
        .values()
        .filter_map(|s| s.end.as_ref()?["recognition"]["class"].as_str())
        .collect();
    let first = CLASSES.iter().position(|c| c.0 == recognised[0]).unwrap();
    for (k, class) in recognised.iter().enumerate() {
        assert_eq!(
            *class,
            CLASSES[(first + k) % 3].0,
            "gesture {k} of {recognised:?}"
        );
    }
}

/// Replays `queries` through the engine (the config at `cfg`, inline work, a
/// virtual clock) and returns its events.
fn replay_events(cfg: &Path, queries: &Path) -> Vec<Event> {
    let mut cfg = Config::load(cfg).unwrap();
    cfg.pipeline.tick_hz = 60.0;
    let rec = load_recording(queries, OnBadFrame::Stop).unwrap();
    let mut engine = Engine::new(&cfg, rec.surface.size_mm(), true);
    let clock = VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros::from_secs_f64(2.0),
        max_gap: Micros(crowdtouch::input::replay::MAX_GAP_US),
    };
    let mut events = Vec::new();
    replay_virtual(
        &mut engine,
        rec.frames.iter().map(|f| Ok(*f)),
        clock,
        |_| {},
        |o| {
            events.extend(o.events.iter().cloned());
            Ok::<(), Infallible>(())
        },
    )
    .unwrap();
    events
}

#[test]
fn a_disabled_class_is_recognised_and_ignored_and_config_names_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let lib = three_class_library(dir.path());
    let queries = query_recording(dir.path());
    let c = config(
        dir.path(),
        &queries,
        &lib,
        &[("disabled: [],", "disabled: [\"crossing\"],")],
    );
    let events = replay_events(&c, &queries);
    let ends: Vec<(u32, String, Option<String>)> = events
        .iter()
        .filter_map(|e| match e {
            Event::GestureEnd {
                id,
                recognition: Some(r),
                rejected,
                ..
            } => Some((*id, r.class.clone(), rejected.clone())),
            _ => None,
        })
        .collect();
    let classes: Vec<&str> = ends.iter().map(|e| e.1.as_str()).collect();
    assert_eq!(classes, ["translate", "twist", "crossing"], "{ends:?}");
    assert_eq!(ends[0].2, None);
    assert_eq!(ends[2].2.as_deref(), Some("class_disabled"));
    let approached = |id: u32| {
        events.iter().any(|e| {
            matches!(e, Event::GestureMotion { id: i, phase: MotionPhase::Approach, class, .. }
                if *i == id && class != "crossing")
        })
    };
    assert!(approached(ends[0].0) && approached(ends[1].0));
    assert!(
        !events
            .iter()
            .any(|e| matches!(e, Event::GestureMotion { id, .. } if *id == ends[2].0)),
        "a disabled class plays no motion"
    );

    // Names the library does not have are refused at their field, listing its
    // classes; so is a class both disabled and mapped to a formation.
    let bad = config(
        dir.path(),
        &queries,
        &lib,
        &[
            ("disabled: [],", "disabled: [\"wave\"],"),
            (
                "        gestures: [],",
                "        gestures: [(class: \"crossing\", formation: \"circle\")],",
            ),
        ],
    );
    let e = run_err(&["check-config", s(&bad)]);
    assert!(
        e.contains("field `gestures.disabled[0]`: the gesture library")
            && e.contains("has no class `wave`; its classes are translate, twist, crossing"),
        "{e}"
    );
    let both = config(
        dir.path(),
        &queries,
        &lib,
        &[
            ("disabled: [],", "disabled: [\"crossing\"],"),
            (
                "        gestures: [],",
                "        gestures: [(class: \"crossing\", formation: \"circle\")],",
            ),
        ],
    );
    let e = run_err(&["check-config", s(&both)]);
    assert!(
        e.contains("class `crossing` is disabled and also mapped to formation `circle`"),
        "{e}"
    );
    // A class of this library mapped to a formation is accepted (the shipped
    // library has no `crossing`).
    let mapped = config(
        dir.path(),
        &queries,
        &lib,
        &[(
            "        gestures: [],",
            "        gestures: [(class: \"crossing\", formation: \"circle\")],",
        )],
    );
    run_ok(&["check-config", s(&mapped)]);
}

#[test]
fn bad_classes_and_motion_files_get_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let empty = d.join("empty.ctgl");
    run_ok(&["library", "new", "--out", s(&empty)]);
    // An empty class table is refused where a library must recognise.
    let e = run_err(&["library", "eval", "--library", s(&empty)]);
    assert!(e.contains("library: the library has no class"), "{e}");
    let e = run_err(&[
        "library",
        "new",
        "--out",
        s(&d.join("dup.ctgl")),
        "--class",
        "a,b,a",
    ]);
    assert!(
        e.contains("class 2: class `a` is named twice (also class 0)"),
        "{e}"
    );
    // A motion file with one person.
    let one = d.join("one.txt");
    std::fs::write(&one, "0 1 1.0 2.0\n10 1 1.5 2.0\n20 1 2.0 2.0\n").unwrap();
    let e = run_err(&[
        "library",
        "import-motion",
        "--library",
        s(&empty),
        "--class",
        "walk",
        s(&one),
        "--out",
        s(&d.join("x.ctgl")),
    ]);
    assert!(
        e.contains(&format!("{}: no crowd motion", one.display()))
            && e.contains("1 person is on the scene")
            && e.contains("a crowd motion needs at least 2"),
        "{e}"
    );
    // A motion file with a NaN position: the track reader names its line.
    let nan = d.join("nan.txt");
    std::fs::write(
        &nan,
        "0 1 1.0 2.0\n0 2 3.0 2.0\n10 1 NaN 2.0\n10 2 3.5 2.0\n",
    )
    .unwrap();
    let e = run_err(&[
        "library",
        "import-motion",
        "--library",
        s(&empty),
        "--class",
        "walk",
        s(&nan),
        "--out",
        s(&d.join("x.ctgl")),
    ]);
    assert!(e.contains(&nan.display().to_string()), "{e}");
    assert!(
        e.to_lowercase().contains("nan") || e.contains("finite"),
        "{e}"
    );
    assert!(!d.join("x.ctgl").exists(), "nothing written");
    // A class with gestures but no motions: the one motion removed by hand.
    let lib = d.join("two.ctgl");
    run_ok(&[
        "library",
        "build",
        "--classes",
        "translate,twist",
        "--motions-per-class",
        "1",
        "--gestures-per-motion",
        "2",
        "--out",
        s(&lib),
    ]);
    let mut l = read_library(&std::fs::read(&lib).unwrap(), "two.ctgl").unwrap();
    l.motions[1].class = l.motions[0].class;
    let broken = d.join("broken.ctgl");
    std::fs::write(&broken, crowdtouch::gesture::library::write_library(&l)).unwrap();
    let e = run_err(&["library", "show", "--library", s(&broken)]);
    assert!(
        e.contains("gesture 2: class `twist` has gestures but no motions"),
        "{e}"
    );
    // Removing a class takes its gestures and motions with it.
    let out = run_ok(&[
        "library",
        "remove",
        "--library",
        s(&lib),
        "--class",
        "translate",
        "--out",
        s(&d.join("twist-only.ctgl")),
    ]);
    assert!(
        out.contains("class translate removed with 1 motions and 2 gestures; 1 classes"),
        "{out}"
    );
    let e = run_err(&[
        "library",
        "remove",
        "--library",
        s(&lib),
        "--class",
        "wave",
        "--out",
        s(&d.join("y.ctgl")),
    ]);
    assert!(
        e.contains("the library has no class `wave`; its classes are: translate, twist"),
        "{e}"
    );
}

/// `library eval --by participant`: two people's translate and twist gestures
/// added to a generated two-class library; each person's are classified against
/// the rest (the generated gestures always train), one confusion matrix, each
/// person's accuracy. With one person named there is nothing to leave out.
#[test]
fn leave_one_participant_out_prints_each_person_and_one_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base.ctgl");
    let cfg = dir.path().join("default.ron");
    std::fs::write(&cfg, crowdtouch::config::DEFAULT_CONFIG_RON).unwrap();
    run_ok(&[
        "library",
        "build",
        "--classes",
        "translate,twist",
        "--motions-per-class",
        "2",
        "--gestures-per-motion",
        "2",
        "--out",
        s(&base),
    ]);
    let mut lib = base.clone();
    for (who, seed) in [("p01", 300u64), ("p02", 600)] {
        for (name, kind) in [
            ("translate", MotionClass::Translate),
            ("twist", MotionClass::Twist),
        ] {
            let mut recordings = Vec::new();
            for k in 0..4u64 {
                let tracks = generate(kind, &style(kind, 0.4 * k as f64), seed + k);
                let p = dir.path().join(format!("{who}-{name}-{k}.jsonl"));
                write_recording(&to_frames(&tracks, GLASS_MM, Micros(500_000)), &p);
                recordings.push(p.display().to_string());
            }
            let next = dir.path().join(format!("{who}-{name}.ctgl"));
            let mut args = vec![
                "library",
                "add",
                "--library",
                s(&lib),
                "--class",
                name,
                "--participant",
                who,
                "--config",
                s(&cfg),
                "--out",
                s(&next),
            ];
            args.extend(recordings.iter().map(String::as_str));
            run_ok(&args);
            lib = next;
            if who == "p01" && name == "twist" {
                let one = run_err(&[
                    "library",
                    "eval",
                    "--by",
                    "participant",
                    "--library",
                    s(&lib),
                ]);
                assert!(one.contains("at least two named participants"), "{one}");
            }
        }
    }
    let out = run_ok(&[
        "library",
        "eval",
        "--by",
        "participant",
        "--library",
        s(&lib),
    ]);
    eprintln!("{out}");
    assert!(
        out.contains("2 participants, 16 of their gestures; 8 gestures of no one named"),
        "{out}"
    );
    for who in ["p01", "p02"] {
        let line = out
            .lines()
            .find(|l| l.starts_with(who))
            .unwrap_or_else(|| panic!("no line for {who} in\n{out}"));
        assert_eq!(line.split_whitespace().nth(1), Some("8"), "{line}");
    }
    assert!(out.contains("true \\ recognised"), "{out}");
    let accuracy: f64 = out
        .lines()
        .find_map(|l| l.strip_prefix("accuracy "))
        .and_then(|l| l.split('%').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no accuracy in\n{out}"));
    assert!(
        accuracy >= 75.0,
        "translate against twist by other people: {accuracy}%\n{out}"
    );
}
