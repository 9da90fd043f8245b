//! Input quoted in messages is escaped: a file or a client that puts control
//! characters (`ESC [ 2 J`, the C1 controls, bidirectional overrides) in what it
//! sends cannot drive the terminal or the log that shows the error.

use crowdtouch::input::recording::{parse_recording, OnBadFrame};
use crowdtouch::located::needs_escape;
use std::path::Path;
use std::process::Command;

fn recording_error(text: &str) -> String {
    match parse_recording(text, Path::new("x.rec"), OnBadFrame::Stop) {
        Ok(_) => panic!("{text:?} read as a recording"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_recording_starting_with_escape_sequences_is_quoted_escaped() {
    let e = recording_error("\u{1b}[2J\u{1b}]0;owned\u{7}\u{9b}31m hello\n");
    assert!(e.contains("unknown recording format"), "{e}");
    assert!(
        e.contains("`\\u{1b}[2J\\u{1b}]0;owned\\u{7}\\u{9b}31m hello`"),
        "{e}"
    );
    assert!(!e.chars().any(needs_escape), "{e:?}");
}

#[test]
fn a_bad_frame_quoting_the_file_is_escaped() {
    // JSON's own escapes: the string holds the controls once decoded.
    let e = recording_error("{\"format\":\"x\\u001b[2J\\u009b1m\\u202e\",\"version\":1}\n");
    assert!(e.contains("field `format`"), "{e}");
    assert!(!e.chars().any(needs_escape), "{e:?}");
}

#[test]
fn gesture_classify_does_not_echo_a_file_s_escape_sequences() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("evil.txt");
    std::fs::write(&file, "\u{1b}[2J\u{1b}[31mowned\u{9b}\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["gesture", "classify"])
        .arg(&file)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown recording format"), "{err}");
    assert!(!out.stderr.contains(&0x1b), "a raw ESC on stderr: {err:?}");
    assert!(!out.stdout.contains(&0x1b), "a raw ESC on stdout");
}
