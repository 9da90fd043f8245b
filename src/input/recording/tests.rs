//! The readers through [`parse_recording`]: what only a whole reading shows.

use super::yaml_events::{MAX_YAML_FLOW_DEPTH, MAX_YAML_INDENT, MAX_YAML_SPAN_BYTES};
use super::{parse_recording, OnBadFrame, Recording, RecordingError, END_CANCEL_US};
use crate::vocab::{ContactFlags, Micros};
use std::path::Path;

// crowdtouch JSON Lines

fn pj() -> &'static Path {
    Path::new("t.jsonl")
}

const HEADER: &str = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"d","x":{"min":0,"max":1000,"resolution":10},"y":{"min":0,"max":500},"max_contacts":4}}"#;

#[test]
fn jsonl_derives_flags() {
    let text = format!(
        "{HEADER}\n# comment\n\n{}\n{}\n{}\n",
        r#"{"t_us":0,"contacts":[{"id":7,"x":100,"y":250}]}"#,
        r#"{"t_us":8333,"contacts":[{"id":7,"x":200,"y":250},{"id":9,"x":0,"y":0,"pressure":0.5}]}"#,
        r#"{"t_us":16666,"contacts":[{"id":9,"x":0,"y":0}]}"#,
    );
    let rec = parse_recording(&text, pj(), OnBadFrame::Stop).unwrap();
    let fl: Vec<Vec<(u32, ContactFlags)>> = rec
        .frames
        .iter()
        .map(|f| f.contacts().iter().map(|c| (c.id.0, c.flags)).collect())
        .collect();
    assert_eq!(
        fl,
        vec![
            vec![(1, ContactFlags::DOWN)],
            vec![(1, ContactFlags::NONE), (2, ContactFlags::DOWN)],
            vec![(1, ContactFlags::UP), (2, ContactFlags::NONE)],
            vec![(2, ContactFlags::CANCELLED)],
        ]
    );
    assert_eq!(rec.frames[3].t, Micros(16_666 + END_CANCEL_US));
    // The lift is reported at the last position.
    assert!((rec.frames[2].contacts()[0].x - 0.2).abs() < 1e-6);
    assert_eq!(rec.frames[1].contacts()[1].pressure, Some(0.5));
    assert!((rec.frames[0].contacts()[0].y - 0.5).abs() < 1e-6);
}

// libinput record YAML

fn p() -> &'static Path {
    Path::new("t.yml")
}

fn parse(text: &str) -> Result<Recording, RecordingError> {
    parse_recording(text, p(), OnBadFrame::Stop)
}

#[test]
fn deep_yaml_is_refused_or_survived() {
    let header = "version: 1\ndevices:\n";
    let dashes = format!("{header}{}x\n", "- ".repeat(100_000));
    assert!(matches!(
        parse(&dashes),
        Err(RecordingError::Parse { line: 3, .. })
    ));
    let flow = format!("{header}{}\n", "[".repeat(100_000));
    match parse(&flow) {
        Err(RecordingError::Parse { line, message, .. }) => {
            assert_eq!(line, 3);
            assert!(
                message.contains(&MAX_YAML_FLOW_DEPTH.to_string()),
                "{message}"
            );
        }
        other => panic!("{other:?}"),
    }
    // The deepest ladder the guard lets through is read without recursion.
    let mut ladder = String::from(header);
    for i in 0..MAX_YAML_INDENT {
        ladder.push_str(&" ".repeat(i));
        ladder.push_str("k:\n");
    }
    assert!(parse(&ladder).is_err());
}

#[test]
fn yaml_marker_lines_are_one_based() {
    let text = "version: 1\ndevices:\n- evdev:\n    absinfo: 7\n";
    let err = parse(text).unwrap_err();
    match err {
        RecordingError::Parse { line, message, .. } => {
            assert_eq!(line, 4, "{message}");
            assert!(message.contains("absinfo"), "{message}");
        }
        e => panic!("{e}"),
    }
}

const YAML_HEADER: &str = "version: 1\ndevices:\n- evdev:\n    name: d\n    absinfo:\n      47: [0, 1, 0, 0, 0]\n      53: [0, 100, 0, 0, 0]\n      54: [0, 100, 0, 0, 0]\n      57: [0, 65535, 0, 0, 0]\n";
const EVENTS: &str = "  events:\n  - evdev:\n    - [0, 0, 3, 57, 1]\n    - [0, 0, 0, 0, 0]\n  - evdev:\n    - [0, 9, 3, 57, -1]\n    - [0, 9, 0, 0, 0]\n";

#[test]
fn keys_in_any_order_and_unknown_keys_are_skipped() {
    let base = parse(&format!("{YAML_HEADER}{EVENTS}")).unwrap();
    assert_eq!(base.frames.len(), 2);
    // `version` after the devices, extra keys with nested values, a second device.
    let text = format!(
            "ndevices: 2\nsystem:\n  kernel: [1, [2, {{a: b}}]]\n{}{EVENTS}  quirks: [x]\n- evdev: {{name: other}}\nversion: 1\n",
            &YAML_HEADER["version: 1\n".len()..]
        );
    let rec = parse(&text).unwrap();
    assert_eq!(rec.frames, base.frames);
    assert_eq!(rec.warnings.len(), 1, "{:?}", rec.warnings);
    assert_eq!(rec.warnings[0].line, 20);
    assert!(rec.warnings[0].message.contains("only the first device"));
}

#[test]
fn an_absinfo_list_is_counted_without_being_kept() {
    let long = format!("[{}0]", "0, ".repeat(10_000));
    let text = YAML_HEADER.replace("[0, 100, 0, 0, 0]\n      54", &format!("{long}\n      54"));
    let err = parse(&format!("{text}{EVENTS}")).unwrap_err();
    assert!(err.to_string().contains("found 10001"), "{err}");
}

#[test]
fn anchors_are_limited() {
    let mut text = format!("{YAML_HEADER}{EVENTS}  extra:\n");
    for i in 0..1100 {
        text.push_str(&format!("  - &a{i} {i}\n"));
    }
    let err = parse(&text).unwrap_err();
    assert!(err.to_string().contains("anchors"), "{err}");
}

#[test]
fn a_long_value_is_refused_before_it_is_kept() {
    // A multi-line plain scalar of more than the span limit.
    let line = format!("    {}\n", "z".repeat(60_000));
    let count = MAX_YAML_SPAN_BYTES / 60_000 + 2;
    let text = format!("{YAML_HEADER}  note:\n{}{EVENTS}", line.repeat(count));
    let err = parse(&text).unwrap_err();
    assert!(err.to_string().contains("without a value ending"), "{err}");
}
