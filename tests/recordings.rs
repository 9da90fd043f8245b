//! Recording readers against real fixtures, the JSON Lines round trip, error
//! paths, robustness (property tests) and the shipped synthetic recordings.
//!
//! Fixture provenance and licences: `tests/fixtures/README.md`.

use crowdtouch::input::recording::{
    parse_recording, read_evemu_with_desc, read_recording, write_jsonl, OnBadFrame, Recording,
    RecordingError, UnsupportedReason,
};
use crowdtouch::input::synth;
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{ContactFlags, TouchFrame};
use proptest::prelude::*;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(fixture(name)).expect("fixture")
}

fn with_desc(desc: &str, events: &str) -> Recording {
    read_evemu_with_desc(
        &text(desc),
        &text(events),
        Path::new(events),
        OnBadFrame::Stop,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Contacts still down after each frame → number of frames.
fn histogram(rec: &Recording) -> BTreeMap<usize, usize> {
    let mut h = BTreeMap::new();
    for f in &rec.frames {
        let down = f.contacts().iter().filter(|c| !c.flags.ended()).count();
        *h.entry(down).or_insert(0) += 1;
    }
    h
}

/// Checks the life cycle of every contact: one DOWN first, one end last, in
/// between only continuing; coordinates in the unit square; time non-decreasing.
/// Returns the number of distinct contacts.
fn check_life_cycle(rec: &Recording) -> usize {
    let mut state: HashMap<u32, bool> = HashMap::new(); // id -> ended
    let mut prev_t = Micros::ZERO;
    for (i, f) in rec.frames.iter().enumerate() {
        assert!(f.t >= prev_t, "frame {i}: time goes back");
        prev_t = f.t;
        let mut seen = BTreeSet::new();
        for c in f.contacts() {
            assert!(seen.insert(c.id), "frame {i}: id {} twice", c.id.0);
            assert!(
                (0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y),
                "frame {i}: {c:?}"
            );
            let down = c.flags.contains(ContactFlags::DOWN);
            match state.get(&c.id.0) {
                None => assert!(down, "frame {i}: id {} appears without DOWN", c.id.0),
                Some(true) => panic!("frame {i}: id {} after its end", c.id.0),
                Some(false) => assert!(!down, "frame {i}: id {} DOWN twice", c.id.0),
            }
            assert!(
                !(c.flags.contains(ContactFlags::UP) && c.flags.contains(ContactFlags::CANCELLED)),
                "frame {i}: both UP and CANCELLED"
            );
            state.insert(c.id.0, c.flags.ended());
        }
        // Every contact down before and not ended must still be listed.
        for (id, ended) in &state {
            if !ended {
                assert!(
                    f.contacts().iter().any(|c| c.id.0 == *id),
                    "frame {i}: id {id} vanished without an end"
                );
            }
        }
    }
    assert!(state.values().all(|&ended| ended), "a contact never ended");
    state.len()
}

fn max_down(rec: &Recording) -> usize {
    histogram(rec).keys().copied().max().unwrap_or(0)
}

// ---------------------------------------------------------------------------
// Real fixtures

#[test]
fn atmel_one_finger_implicit_slot_zero() {
    let rec = with_desc(
        "atmel-maxtouch.desc",
        "atmel-maxtouch.1-finger-drag-up-down.events",
    );
    assert_eq!(rec.frames.len(), 150);
    assert_eq!(max_down(&rec), 1);
    assert_eq!(check_life_cycle(&rec), 1);
    assert_eq!(rec.surface.name, "Atmel maXTouch Touchscreen");
    assert_eq!(rec.surface.max_contacts, 10);
    assert!(rec.surface.size_mm().is_none());
    assert!(rec.warnings.is_empty(), "{:?}", rec.warnings);
    let d = rec.duration().as_secs_f64();
    assert!((2.1..2.3).contains(&d), "{d}");
    // The .events file carries its own header too: reading it alone agrees.
    let alone = read_recording(
        &fixture("atmel-maxtouch.1-finger-drag-up-down.events"),
        OnBadFrame::Stop,
    )
    .unwrap();
    assert_eq!(alone.frames, rec.frames);
}

#[test]
fn atmel_two_fingers() {
    let rec = with_desc(
        "atmel-maxtouch.desc",
        "atmel-maxtouch.2-fingers-touch-release.events",
    );
    assert_eq!(rec.frames.len(), 16);
    assert_eq!(max_down(&rec), 2);
    assert_eq!(check_life_cycle(&rec), 2);
    // First frame: tracking id 7 at (539, 167) of 0..799 × 0..479.
    let c = rec.frames[0].contacts()[0];
    assert_eq!(c.flags, ContactFlags::DOWN);
    assert!((c.x - 539.0 / 799.0).abs() < 1e-6 && (c.y - 167.0 / 479.0).abs() < 1e-6);
    assert_eq!(rec.frames[1].t, Micros(54_564));
}

#[test]
fn atmel_four_fingers_histogram() {
    let rec = with_desc(
        "atmel-maxtouch.desc",
        "atmel-maxtouch.4-finger-drag-down.events",
    );
    assert_eq!(rec.frames.len(), 31);
    assert_eq!(
        histogram(&rec),
        BTreeMap::from([(0, 1), (1, 1), (3, 4), (4, 25)])
    );
    assert_eq!(check_life_cycle(&rec), 4);
}

#[test]
fn ep0430m09_two_fingers() {
    let rec = with_desc("ep0430m09.desc", "ep0430m09.2-finger-scroll-down.events");
    assert_eq!(rec.frames.len(), 98);
    assert_eq!(max_down(&rec), 2);
    assert_eq!(check_life_cycle(&rec), 2);
    let rec = with_desc("ep0430m09.desc", "ep0430m09.2-fingers-touch-release.events");
    assert_eq!(rec.frames.len(), 14);
    assert_eq!(max_down(&rec), 2);
    check_life_cycle(&rec);
    assert_eq!(rec.surface.max_contacts, 5);
}

#[test]
fn dell_canvas_five_contacts() {
    let rec = read_recording(&fixture("dell-canvas-27-touch.evemu"), OnBadFrame::Stop).unwrap();
    assert_eq!(rec.frames.len(), 450);
    assert_eq!(max_down(&rec), 5);
    assert_eq!(check_life_cycle(&rec), 12);
    assert_eq!(
        histogram(&rec),
        BTreeMap::from([(0, 4), (1, 82), (2, 85), (3, 4), (4, 191), (5, 84)])
    );
    let (w, h) = rec.surface.size_mm().unwrap();
    assert!((w - 32767.0 / 55.0).abs() < 1e-9 && (h - 32767.0 / 98.0).abs() < 1e-9);
    assert_eq!(rec.surface.max_contacts, 5);
    let d = rec.duration().as_secs_f64();
    assert!((13.8..14.0).contains(&d), "{d}");
    assert!(rec.warnings.is_empty(), "{:?}", rec.warnings);
}

#[test]
fn libinput_record_yaml_two_contacts() {
    let path = fixture("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml");
    let rec = read_recording(&path, OnBadFrame::Stop).unwrap();
    assert_eq!(rec.surface.name, "ITE Tech. Inc. ITE Device(8595) Touchpad");
    assert_eq!(max_down(&rec), 2);
    assert_eq!(check_life_cycle(&rec), 2);
    let (w, h) = rec.surface.size_mm().unwrap();
    assert!((w - 1051.0 / 12.0).abs() < 1e-9 && (h - 571.0 / 12.0).abs() < 1e-9);
    assert_eq!(rec.frames[1].t, Micros(9_967));
    assert_eq!(rec.frames.len(), 13);
    assert!(rec.warnings.is_empty(), "{:?}", rec.warnings);
}

#[test]
fn ntrig_protocol_a_decodes() {
    let rec = with_desc(
        "ntrig-multitouch.desc",
        "ntrig-multitouch.1-finger-drag-NW-SE.events",
    );
    // Protocol A: one contact dragged across the whole panel, then lifted.
    assert_eq!(rec.frames.len(), 107);
    assert_eq!(max_down(&rec), 1);
    assert_eq!(check_life_cycle(&rec), 1);
    assert!(rec.warnings.is_empty(), "{:?}", rec.warnings);
    assert_eq!(
        rec.surface.max_contacts as usize,
        crowdtouch::vocab::MAX_CONTACTS
    );
}

#[test]
fn single_touch_device_is_unsupported() {
    let t = "N: single\nA: 00 42 1981 0 0\nA: 01 42 1981 0 0\nE: 0.000001 0001 014a 1\n";
    let err = parse_recording(t, Path::new("st"), OnBadFrame::Stop).unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::Unsupported {
                reason: UnsupportedReason::NoMultiTouch,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn headerless_events_need_their_desc() {
    let events = text("ntrig-multitouch.1-finger-drag-NW-SE.events");
    let err = parse_recording(&events, Path::new("x.events"), OnBadFrame::Stop).unwrap_err();
    match err {
        RecordingError::Parse { line, message, .. } => {
            assert_eq!(line, 1);
            assert!(message.contains("header"), "{message}");
        }
        e => panic!("{e}"),
    }
}

// ---------------------------------------------------------------------------
// JSON Lines round trip

fn assert_same_frames(a: &[TouchFrame], b: &[TouchFrame]) {
    assert_eq!(a.len(), b.len());
    for (i, (fa, fb)) in a.iter().zip(b).enumerate() {
        assert_eq!(fa.t, fb.t, "frame {i}");
        assert_eq!(fa.len(), fb.len(), "frame {i}");
        for (ca, cb) in fa.contacts().iter().zip(fb.contacts()) {
            assert_eq!((ca.id, ca.flags), (cb.id, cb.flags), "frame {i}");
            for (u, v) in [(ca.x, cb.x), (ca.y, cb.y)] {
                assert!(
                    (u - v).abs() <= 1e-6 * u.abs().max(1e-3),
                    "frame {i}: {u} vs {v}"
                );
            }
            assert_eq!(ca.pressure, cb.pressure, "frame {i}");
            for (u, v) in [(ca.major_mm, cb.major_mm), (ca.minor_mm, cb.minor_mm)] {
                match (u, v) {
                    (Some(u), Some(v)) => assert!((u - v).abs() <= 1e-6 * u.abs().max(1.0)),
                    (u, v) => assert_eq!(u, v),
                }
            }
        }
    }
}

#[test]
fn jsonl_round_trip_of_real_recordings() {
    for rec in [
        read_recording(&fixture("dell-canvas-27-touch.evemu"), OnBadFrame::Stop).unwrap(),
        with_desc(
            "atmel-maxtouch.desc",
            "atmel-maxtouch.4-finger-drag-down.events",
        ),
        read_recording(
            &fixture("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml"),
            OnBadFrame::Stop,
        )
        .unwrap(),
    ] {
        let mut out = Vec::new();
        write_jsonl(&rec.surface, &rec.frames, &mut out).unwrap();
        let back = parse_recording(
            std::str::from_utf8(&out).unwrap(),
            Path::new("rt.jsonl"),
            OnBadFrame::Stop,
        )
        .unwrap();
        assert_eq!(back.surface, rec.surface);
        assert_same_frames(&rec.frames, &back.frames);
        // Writing again gives the same bytes.
        let mut again = Vec::new();
        write_jsonl(&back.surface, &back.frames, &mut again).unwrap();
        assert_eq!(out, again);
    }
}

#[test]
fn jsonl_round_trip_keeps_cancel_palm_pressure_and_size() {
    let t = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"d","x":{"min":-100,"max":900,"resolution":4},"y":{"min":0,"max":500},"max_contacts":4}}
{"t_us":0,"contacts":[{"id":5,"x":0,"y":10,"pressure":0.25,"major":40,"minor":20,"palm":true},{"id":6,"x":1,"y":2}]}
{"t_us":10,"contacts":[{"id":6,"x":3,"y":4}],"cancelled":[5]}
"#;
    let rec = parse_recording(t, Path::new("a.jsonl"), OnBadFrame::Stop).unwrap();
    let c = rec.frames[0].contacts()[0];
    assert_eq!(c.flags, ContactFlags::DOWN | ContactFlags::PALM);
    assert_eq!(
        (c.major_mm, c.minor_mm, c.pressure),
        (Some(10.0), Some(5.0), Some(0.25))
    );
    assert!((c.x - 0.1).abs() < 1e-6);
    assert_eq!(
        rec.frames[1].contacts()[0].flags,
        ContactFlags::CANCELLED | ContactFlags::PALM
    );
    let mut out = Vec::new();
    write_jsonl(&rec.surface, &rec.frames, &mut out).unwrap();
    let back = parse_recording(
        std::str::from_utf8(&out).unwrap(),
        Path::new("b.jsonl"),
        OnBadFrame::Stop,
    )
    .unwrap();
    assert_same_frames(&rec.frames, &back.frames);
}

// ---------------------------------------------------------------------------
// Error paths: every one names the line

fn parse_err(t: &str) -> (usize, String) {
    match parse_recording(t, Path::new("bad"), OnBadFrame::Stop) {
        Err(RecordingError::Parse { line, message, .. }) => (line, message),
        Err(e) => panic!("not a parse error: {e}"),
        Ok(_) => panic!("accepted:\n{t}"),
    }
}

const JH: &str = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"d","x":{"min":0,"max":100},"y":{"min":0,"max":100},"max_contacts":2}}"#;
const F0: &str = r#"{"t_us":0,"contacts":[{"id":1,"x":1,"y":2}]}"#;

#[test]
fn jsonl_errors_name_line_and_field() {
    let cases: &[(String, usize, &str)] = &[
        (format!("{JH}\n{F0}\n{{\"t_us\":5,\"contacts\":[{{\"id\":1"), 3, "invalid JSON"),
        (format!("{JH}\n{F0}\n{{\"t_us\":5,\"contacts\":[{{\"id\":1,\"x\":\"a\",\"y\":2}}]}}"), 3, "contacts[0].x"),
        (format!("{JH}\n\n# c\n{F0}\n{{\"t_us\":\"5\",\"contacts\":[]}}"), 5, "t_us"),
        (format!("{JH}\n{{\"t_us\":50,\"contacts\":[]}}\n{F0}"), 3, "earlier"),
        (format!("{F0}\n{F0}"), 1, "missing header"),
        (format!("{JH}\n{{\"t_us\":1}}"), 2, "missing field `contacts`"),
        (format!("{JH}\n{{\"t_us\":1,\"contacts\":[{{\"id\":1,\"x\":1,\"y\":1}},{{\"id\":1,\"x\":1,\"y\":1}}]}}"), 2, "twice"),
        (format!("{JH}\n{{\"t_us\":1,\"contacts\":[{{\"id\":1,\"x\":1,\"y\":1,\"pressure\":2}}]}}"), 2, "pressure"),
        (JH.replace("\"max\":100}", "\"max\":0}"), 1, "device.x"),
        (JH.replace("crowdtouch-touch", "other"), 1, "format"),
        (JH.replace("\"max_contacts\":2", "\"max_contacts\":-2"), 1, "device.max_contacts"),
    ];
    for (t, line, what) in cases {
        let (l, m) = parse_err(t);
        assert_eq!(
            (l, m.contains(what)),
            (*line, true),
            "{what}: line {l}: {m}"
        );
    }
}

const EH: &str =
    "N: dev\nA: 2f 0 1 0 0 0\nA: 35 0 100 0 0 0\nA: 36 0 100 0 0 0\nA: 39 0 65535 0 0 0\n";

#[test]
fn evemu_errors_name_the_line() {
    let ok1 = "E: 0.000001 0003 0039 1\nE: 0.000001 0000 0000 0\n";
    let cases: &[(String, usize, &str)] = &[
        (format!("{EH}{ok1}E: 0.1 0003 0035"), 8, "4 fields"),
        (format!("{EH}{ok1}E: 0.1 0003 0035 abc"), 8, "value"),
        (format!("{EH}{ok1}E: x.1 0003 0035 5"), 8, "timestamp"),
        (
            format!("{EH}E: 1.0 0003 0039 1\nE: 0.5 0000 0000 0\n"),
            7,
            "goes back",
        ),
        (
            format!("{EH}{ok1}E: 0.2 0003 0030 5"),
            8,
            "does not declare",
        ),
        (format!("{EH}{ok1}E: 0.2 0003 0045 5"), 8, "unknown axis"),
        (format!("{EH}A: 47 0 1 0 0 0\n{ok1}"), 6, "unknown axis"),
        (format!("{EH}A: 30 0 1 0\n{ok1}"), 6, "A: code"),
        (format!("{EH}{ok1}Z: what"), 8, "unrecognised"),
        (format!("{EH}{ok1}N: again"), 8, "header line after"),
        (
            "A: 35 0 0 0 0 0\nA: 36 0 1 0 0\nA: 2f 0 1 0 0\nE: 0.1 0000 0000 0\n".to_string(),
            1,
            "empty range",
        ),
    ];
    for (t, line, what) in cases {
        let (l, m) = parse_err(t);
        assert_eq!(
            (l, m.contains(what)),
            (*line, true),
            "{what}: line {l}: {m}"
        );
    }
}

const YH: &str = "version: 1\ndevices:\n- evdev:\n    name: d\n    absinfo:\n      47: [0, 1, 0, 0, 0]\n      53: [0, 100, 0, 0, 0]\n      54: [0, 100, 0, 0, 0]\n      57: [0, 65535, 0, 0, 0]\n  events:\n";

#[test]
fn yaml_errors_name_the_line() {
    let ok = "  - evdev:\n    - [0, 0, 3, 57, 1]\n    - [0, 0, 0, 0, 0]\n";
    let cases: &[(String, usize, &str)] = &[
        (
            format!("{YH}{ok}  - evdev:\n    - [0, 1, 3, 53]\n"),
            15,
            "5 to 5",
        ),
        (
            format!("{YH}{ok}  - evdev:\n    - [0, 1, 3, 53, x]\n"),
            15,
            "not an integer",
        ),
        (
            format!("{YH}{ok}  - evdev:\n    - [0, 1, 3, 48, 4]\n"),
            15,
            "does not declare",
        ),
        (
            format!("{YH}  - evdev:\n    - [1, 0, 0, 0, 0]\n    - [0, 5, 0, 0, 0]\n"),
            13,
            "goes back",
        ),
        (
            format!("{YH}{ok}  - evdev:\n    - [0, 1, 3, 53, 1\n"),
            16,
            "invalid YAML",
        ),
        (
            YH.replace("      54: [0, 100, 0, 0, 0]\n", "      54: [0, 100]\n"),
            8,
            "absinfo.54",
        ),
        (
            YH.replace(
                "      57: [0, 65535, 0, 0, 0]\n",
                "      99: [0, 1, 0, 0, 0]\n",
            ),
            9,
            "unknown axis",
        ),
    ];
    for (t, line, what) in cases {
        let (l, m) = parse_err(t);
        assert_eq!(
            (l, m.contains(what)),
            (*line, true),
            "{what}: line {l}: {m}"
        );
    }
    let v2 = YH.replace("version: 1", "version: 2");
    assert!(matches!(
        parse_recording(&v2, Path::new("y"), OnBadFrame::Stop),
        Err(RecordingError::Unsupported {
            reason: UnsupportedReason::Version { version: 2, .. },
            ..
        })
    ));
}

#[test]
fn skip_mode_records_warnings_and_keeps_good_frames() {
    let t = format!(
        "{JH}\n{F0}\n{{\"t_us\":\"bad\",\"contacts\":[]}}\n{{\"t_us\":20,\"contacts\":[{{\"id\":1,\"x\":5,\"y\":5}}]}}\n"
    );
    let rec = parse_recording(&t, Path::new("s"), OnBadFrame::Skip).unwrap();
    assert_eq!(rec.frames.len(), 3); // 2 good frames + the final cancel
    assert_eq!(rec.warnings.len(), 1);
    assert_eq!(rec.warnings[0].line, 3);
    assert!(rec.warnings[0].message.contains("t_us"));

    let t = format!(
        "{EH}E: 0.1 0003 0039 1\nE: 0.1 0000 0000 0\nE: 0.2 0003 0035 zz\nE: 0.2 0003 0036 50\nE: 0.2 0000 0000 0\nE: 0.3 0003 0039 -1\nE: 0.3 0000 0000 0\n"
    );
    let rec = parse_recording(&t, Path::new("s"), OnBadFrame::Skip).unwrap();
    assert_eq!(rec.frames.len(), 2);
    assert_eq!(rec.frames[1].contacts()[0].flags, ContactFlags::UP);
    assert_eq!(
        rec.frames[1].contacts()[0].y,
        0.0,
        "the skipped frame's Y was discarded"
    );
    assert_eq!((rec.warnings[0].line, rec.warnings.len()), (8, 1));

    // A SYN_REPORT going back in time drops its own frame only.
    let t = format!(
        "{EH}E: 0.1 0003 0039 1\nE: 0.1 0000 0000 0\nE: 0.2 0003 0035 50\nE: 0.05 0000 0000 0\nE: 0.3 0003 0036 50\nE: 0.3 0000 0000 0\nE: 0.4 0003 0039 -1\nE: 0.4 0000 0000 0\n"
    );
    let rec = parse_recording(&t, Path::new("s"), OnBadFrame::Skip).unwrap();
    assert_eq!(rec.frames.len(), 3);
    let c = rec.frames[1].contacts()[0];
    assert_eq!((c.x, c.y, rec.frames[1].t), (0.0, 0.5, Micros(200_000)));
    assert_eq!((rec.warnings[0].line, rec.warnings.len()), (9, 1));
}

#[test]
fn description_errors_point_into_the_description() {
    let desc = "N: d\nA: 2f 0 1 0 0 0\nA: 35 0 0 0 0 0\nA: 36 0 100 0 0 0\n";
    let err = read_evemu_with_desc(
        desc,
        "E: 0.1 0000 0000 0\n",
        Path::new("d"),
        OnBadFrame::Stop,
    )
    .unwrap_err();
    match err {
        RecordingError::Parse { line, message, .. } => {
            assert_eq!(line, 3);
            assert!(
                message.starts_with("in the device description: "),
                "{message}"
            );
        }
        e => panic!("{e}"),
    }
    let err = read_evemu_with_desc(
        "N: d\nA: 2f 0 x 0 0\n",
        "",
        Path::new("d"),
        OnBadFrame::Stop,
    )
    .unwrap_err();
    assert!(
        matches!(err, RecordingError::Parse { line: 2, .. }),
        "{err}"
    );
}

#[test]
fn other_errors() {
    assert!(matches!(
        parse_recording("", Path::new("e"), OnBadFrame::Stop),
        Err(RecordingError::Empty { .. })
    ));
    assert!(matches!(
        parse_recording(JH, Path::new("e"), OnBadFrame::Stop),
        Err(RecordingError::Empty { .. })
    ));
    assert!(matches!(
        parse_recording(EH, Path::new("e"), OnBadFrame::Stop),
        Err(RecordingError::Empty { .. })
    ));
    assert!(matches!(
        parse_recording("hello world\n", Path::new("e"), OnBadFrame::Stop),
        Err(RecordingError::UnknownFormat { .. })
    ));
    let err = read_recording(Path::new("/nonexistent/rec.jsonl"), OnBadFrame::Stop).unwrap_err();
    assert!(matches!(err, RecordingError::Io { .. }));
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bin");
    std::fs::write(&p, [b'{', 0xff, 0xfe, b'\n']).unwrap();
    assert!(matches!(
        read_recording(&p, OnBadFrame::Stop),
        Err(RecordingError::Parse { line: 1, .. })
    ));
    let big = std::fs::File::create(dir.path().join("big")).unwrap();
    big.set_len(crowdtouch::input::recording::MAX_RECORDING_BYTES + 1)
        .unwrap();
    assert!(matches!(
        read_recording(&dir.path().join("big"), OnBadFrame::Stop),
        Err(RecordingError::TooLarge { .. })
    ));
}

// ---------------------------------------------------------------------------
// Robustness: no input makes a reader panic

fn check_any(t: &str) {
    for on_bad in [OnBadFrame::Stop, OnBadFrame::Skip] {
        if let Ok(rec) = parse_recording(t, Path::new("p"), on_bad) {
            for f in &rec.frames {
                for c in f.contacts() {
                    assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
                }
            }
        }
    }
}

fn mutate(base: &str, ops: &[(u8, usize, usize, String)]) -> String {
    let mut b = base.as_bytes().to_vec();
    for (kind, at, len, ins) in ops {
        if b.is_empty() {
            break;
        }
        let at = at % b.len();
        let end = (at + len % 64).min(b.len());
        match kind % 4 {
            0 => {
                b.drain(at..end);
            }
            1 => {
                b.splice(at..at, ins.bytes());
            }
            2 => {
                let chunk = b[at..end].to_vec();
                b.splice(end..end, chunk);
            }
            _ => b.truncate(at),
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

fn small_fixtures() -> Vec<String> {
    let yaml = text("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml");
    let evemu = text("atmel-maxtouch.2-fingers-touch-release.events");
    let rec = with_desc(
        "atmel-maxtouch.desc",
        "atmel-maxtouch.2-fingers-touch-release.events",
    );
    let mut jsonl = Vec::new();
    write_jsonl(&rec.surface, &rec.frames, &mut jsonl).unwrap();
    vec![yaml, evemu, String::from_utf8(jsonl).unwrap()]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(prefix in 0usize..4, body in ".{0,400}") {
        let p = ["", "N: x\nA: 2f 0 3 0 0\nA: 35 0 9 0 0\nA: 36 0 9 0 0\n", "version: 1\ndevices:\n", JH][prefix];
        check_any(&format!("{p}\n{body}"));
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        check_any(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn mutated_fixtures_never_panic(
        which in 0usize..3,
        ops in proptest::collection::vec((any::<u8>(), any::<usize>(), any::<usize>(), "[\\[\\]{}:#\\- 0-9a-f\n.,\"]{0,8}"), 1..6),
    ) {
        let base = &small_fixtures()[which];
        check_any(&mutate(base, &ops));
    }
}

// ---------------------------------------------------------------------------
// Shipped synthetic recordings

fn shipped_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("config/recordings")
}

fn jsonl_bytes(surface: &crowdtouch::input::SurfaceInfo, frames: &[TouchFrame]) -> Vec<u8> {
    let mut out = Vec::new();
    write_jsonl(surface, frames, &mut out).unwrap();
    out
}

/// Regenerate with `CROWDTOUCH_BLESS=1 cargo test --test recordings shipped`.
#[test]
fn shipped_recordings_match_config_files() {
    if std::env::var_os("CROWDTOUCH_BLESS").is_some() {
        synth::write_shipped(&shipped_dir()).unwrap();
    }
    let shipped = synth::shipped();
    let mut on_disk: Vec<String> = std::fs::read_dir(shipped_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".jsonl"))
        .collect();
    on_disk.sort();
    let names: Vec<String> = shipped.iter().map(|(n, ..)| n.clone()).collect();
    assert_eq!(on_disk, names);
    for (name, surface, frames) in &shipped {
        let file = std::fs::read(shipped_dir().join(name)).unwrap();
        assert!(
            file == jsonl_bytes(surface, frames),
            "config/recordings/{name} differs from synth::shipped(); regenerate it"
        );
        let rec = read_recording(&shipped_dir().join(name), OnBadFrame::Stop).unwrap();
        assert_eq!(&rec.surface, surface);
        assert!(rec.warnings.is_empty());
        assert_same_frames(frames, &rec.frames);
    }
}

#[test]
fn shipped_generation_is_deterministic() {
    let a: Vec<Vec<u8>> = synth::shipped()
        .iter()
        .map(|(_, s, f)| jsonl_bytes(s, f))
        .collect();
    let b: Vec<Vec<u8>> = synth::shipped()
        .iter()
        .map(|(_, s, f)| jsonl_bytes(s, f))
        .collect();
    assert_eq!(a, b);
    let dir = tempfile::tempdir().unwrap();
    let paths = synth::write_shipped(dir.path()).unwrap();
    assert_eq!(paths.len(), 7);
    for (p, bytes) in paths.iter().zip(&a) {
        assert_eq!(&std::fs::read(p).unwrap(), bytes);
    }
}

/// World metres of a surface point (default 16 m × 9 m world).
fn world(x: f32, y: f32) -> (f64, f64) {
    (f64::from(x) * 16.0, f64::from(y) * 9.0)
}

/// Positions of contact `id` over the recording, world metres.
fn track(frames: &[TouchFrame], id: u32) -> Vec<(f64, f64)> {
    frames
        .iter()
        .flat_map(|f| {
            f.contacts()
                .iter()
                .filter(|c| c.id.0 == id)
                .map(|c| world(c.x, c.y))
        })
        .collect()
}

fn near(a: (f64, f64), b: (f64, f64), tol_m: f64) -> bool {
    (a.0 - b.0).hypot(a.1 - b.1) <= tol_m
}

#[test]
fn shipped_recordings_are_what_they_say() {
    let surface = synth::surface();
    let (w_mm, h_mm) = surface.size_mm().unwrap();
    assert!((w_mm - 1210.0).abs() < 1e-9 && (h_mm - 680.0).abs() < 1e-9);
    let expect_fingers = [1, 2, 2, 3, 4, 5, 2];
    let shipped = synth::shipped();
    for ((name, _, frames), &fingers) in shipped.iter().zip(&expect_fingers) {
        let rec = Recording {
            surface: surface.clone(),
            frames: frames.clone(),
            warnings: Vec::new(),
        };
        assert_eq!(check_life_cycle(&rec), fingers, "{name}");
        assert_eq!(max_down(&rec), fingers, "{name}");
        let d = rec.duration().as_secs_f64();
        assert!((1.5..=4.0).contains(&d), "{name}: {d} s");
        // ~120 Hz with ±0.4 ms jitter.
        let period = 1e6 / 120.0;
        for w in frames.windows(2) {
            let dt = (w[1].t.0 - w[0].t.0) as f64;
            assert!((dt - period).abs() <= 800.0 + 1.0, "{name}: {dt} us");
        }
        let mean = (frames.last().unwrap().t.0 as f64) / (frames.len() - 1) as f64;
        assert!((mean - period).abs() < 50.0, "{name}: mean {mean}");
        // Fingers of a hand land 10–60 ms apart (seen through 120 Hz frames).
        let downs: Vec<u64> = frames
            .iter()
            .flat_map(|f| {
                f.contacts()
                    .iter()
                    .filter(|c| c.flags.contains(ContactFlags::DOWN))
                    .map(move |_| f.t.0)
            })
            .collect();
        for w in downs.windows(2) {
            assert!(
                w[1] - w[0] <= 60_000 + 9_000,
                "{name}: landing gap {}",
                w[1] - w[0]
            );
        }
    }
    let f = |i: usize| &shipped[i].2;
    // 01: lands at (9.9, 4.5), ends 2.5 m to the right.
    let t = track(f(0), 1);
    assert!(
        near(t[0], (9.9, 4.5), 0.02) && near(*t.last().unwrap(), (12.4, 4.5), 0.02),
        "{t:?}"
    );
    // 02: 1.8 m apart ≈ 136 mm on the glass, both end 2 m further left.
    let (a, b) = (track(f(1), 1), track(f(1), 2));
    assert!(((a[0].1 - b[0].1).abs() * 680.0 / 9.0 - 136.0).abs() < 1.0);
    assert!(near(*a.last().unwrap(), (4.1, a[0].1), 0.02) && (a[0].0 - 6.1).abs() < 0.02);
    // 03: pinch from 2 m to 0.8 m apart on y ≈ 3.1.
    let (a, b) = (track(f(2), 1), track(f(2), 2));
    let gap = |p: (f64, f64), q: (f64, f64)| (p.0 - q.0).hypot(p.1 - q.1);
    assert!(
        (gap(a[0], b[0]) - 2.0).abs() < 0.03
            && (gap(*a.last().unwrap(), *b.last().unwrap()) - 0.8).abs() < 0.03
    );
    assert!((a[0].1 - 3.1).abs() < 0.02);
    // 04: the triangle moves by (1, 1.5).
    for id in 1..=3 {
        let t = track(f(3), id);
        let (d0, d1) = (t.last().unwrap().0 - t[0].0, t.last().unwrap().1 - t[0].1);
        assert!(
            (d0 - 1.0).abs() < 0.02 && (d1 - 1.5).abs() < 0.02,
            "{d0} {d1}"
        );
    }
    // 05: each finger turns 60° about (8, 4.5) at radius 0.9 m.
    for id in 1..=4 {
        let t = track(f(4), id);
        let ang = |p: (f64, f64)| (p.1 - 4.5).atan2(p.0 - 8.0);
        let mut turn = (ang(*t.last().unwrap()) - ang(t[0])).to_degrees();
        if turn < -180.0 {
            turn += 360.0;
        }
        assert!((turn - 60.0).abs() < 1.0, "turn {turn}");
        assert!(((t[0].0 - 8.0).hypot(t[0].1 - 4.5) - 0.9).abs() < 0.02);
    }
    // 06: hand B lands ≥ 80 ms after hand A; hands > 250 mm apart in every frame.
    let frames = f(5);
    let first_b = frames
        .iter()
        .find(|fr| fr.contacts().iter().any(|c| c.id.0 >= 3))
        .unwrap();
    assert!(
        first_b.t.0 >= 80_000 && first_b.t.0 <= 80_000 + 9_000,
        "{}",
        first_b.t
    );
    for fr in frames {
        let cs = fr.contacts();
        for a in cs.iter().filter(|c| c.id.0 <= 2) {
            for b in cs.iter().filter(|c| c.id.0 >= 3) {
                let d = (f64::from(a.x - b.x) * 1210.0).hypot(f64::from(a.y - b.y) * 680.0);
                assert!(
                    d > synth::TWO_HANDS_MIN_GAP_MM,
                    "hands {d} mm apart at {}",
                    fr.t
                );
            }
        }
    }
    // 07: far from the crowd (x 6..10, y 3..6) all along; swipes 3 m right.
    for id in 1..=2 {
        let t = track(f(6), id);
        assert!(t.iter().all(|p| p.1 > 6.5 && p.0 < 6.0), "{t:?}");
        assert!((t.last().unwrap().0 - t[0].0 - 3.0).abs() < 0.02);
    }
}

// ---------------------------------------------------------------------------
// MtDecoder on arbitrary event streams

fn mt_event() -> impl Strategy<Value = (u16, u16, i32)> {
    use crowdtouch::input::evdev::*;
    prop_oneof![
        3 => Just((EV_SYN, SYN_REPORT, 0)),
        1 => (0u16..4).prop_map(|c| (EV_SYN, c, 0)),
        2 => (-2i32..6).prop_map(|v| (EV_ABS, ABS_MT_SLOT, v)),
        3 => (-1i32..8).prop_map(|v| (EV_ABS, ABS_MT_TRACKING_ID, v)),
        4 => (-100i32..1200).prop_map(|v| (EV_ABS, ABS_MT_POSITION_X, v)),
        4 => (-100i32..1200).prop_map(|v| (EV_ABS, ABS_MT_POSITION_Y, v)),
        1 => (0u16..0x40, any::<i32>()).prop_map(|(c, v)| (EV_ABS, c, v)),
        1 => (any::<u16>(), any::<u16>(), any::<i32>()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, rng_seed: proptest::test_runner::RngSeed::Fixed(0x3170), failure_persistence: None, ..ProptestConfig::default() })]

    /// Whatever the events, frames keep the contact life cycle and the unit square,
    /// and `cancel_all` ends everything.
    #[test]
    fn mt_decoder_keeps_life_cycle(events in proptest::collection::vec(mt_event(), 0..300), slots in 1usize..5) {
        use crowdtouch::input::evdev::{MtAxes, MtDecoder};
        use crowdtouch::input::AxisRange;
        let r = AxisRange { min: 0.0, max: 1000.0, resolution: 0.0 };
        let mut dec = MtDecoder::new(MtAxes { x: r, y: r, slots, pressure: None, touch_major: None, touch_minor: None }, 1);
        let mut f = TouchFrame::default();
        let mut frames = Vec::new();
        for (i, (ty, code, value)) in events.into_iter().enumerate() {
            if dec.event(Micros(i as u64), ty, code, value, &mut f) {
                prop_assert!(f.contacts().iter().filter(|c| !c.flags.ended()).count() <= slots);
                frames.push(f);
            }
        }
        if dec.cancel_all(Micros(1_000), &mut f) {
            frames.push(f);
        }
        let rec = Recording { surface: synth::surface(), frames, warnings: Vec::new() };
        let n = check_life_cycle(&rec);
        prop_assert_eq!(n as u32, dec.next_id() - 1);
    }
}

// ---------------------------------------------------------------------------
// Recordings through the replay source

#[test]
fn replay_of_shipped_and_real_recordings_keeps_life_cycle() {
    use crowdtouch::input::replay::{Pacing, ReplayItem, ReplaySource};
    use std::sync::atomic::AtomicBool;
    let mut total = 0;
    let mut items: Vec<ReplayItem> = synth::shipped()
        .into_iter()
        .map(|(n, _, f)| {
            total += f.len();
            ReplayItem::new(n, f)
        })
        .collect();
    let dell = read_recording(&fixture("dell-canvas-27-touch.evemu"), OnBadFrame::Stop).unwrap();
    total += dell.frames.len();
    items.push(ReplayItem::new("dell", dell.frames.clone()));
    let mut src = ReplaySource::new(items, false, Micros(500_000), Pacing::Virtual);
    let mut out: Vec<TouchFrame> = Vec::new();
    let mut started = Vec::new();
    src.run(&mut out, &AtomicBool::new(false), &mut |i| started.push(i));
    assert_eq!(started, (0..8).collect::<Vec<_>>());
    assert_eq!(out.len(), total);
    let rec = Recording {
        surface: synth::surface(),
        frames: out,
        warnings: Vec::new(),
    };
    // 1+2+2+3+4+5+2 synthetic fingers + 12 Dell contacts, all distinct ids.
    assert_eq!(check_life_cycle(&rec), 19 + 12);
}
