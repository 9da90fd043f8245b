//! Input quoted in messages is escaped: a file or a client that puts control
//! characters (`ESC [ 2 J`, the C1 controls, bidirectional overrides) in what it
//! sends cannot drive the terminal or the log that shows the error.

mod common;

use common::*;
use crowdtouch::config::Config;
use crowdtouch::input::recording::{parse_recording, OnBadFrame};
use crowdtouch::located::needs_escape;
use serde_json::Value;
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
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

#[test]
fn a_socket_client_s_duplicate_key_and_control_characters_get_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.pipeline.realtime = Default::default();
    let (daemon, _tx) = daemon_on_channel(cfg, &path, 1);
    let mut w = UnixStream::connect(&path).unwrap();
    let mut r = BufReader::new(w.try_clone().unwrap());
    read_until(&mut r, 5.0, |v| v["type"] == "hello");
    let reply = |r: &mut BufReader<UnixStream>, id: i64| -> Value {
        read_until(r, 5.0, |v| v["id"] == id)
            .pop()
            .filter(|v| v["id"] == id)
            .unwrap_or_else(|| panic!("no reply to {id}"))
    };
    // A touch whose contact says x twice: refused, named, the client stays.
    w.write_all(
        b"{\"type\":\"command\",\"id\":1,\"name\":\"touch\",\"contacts\":[{\"id\":1,\"x\":0.5,\"x\":0.9,\"y\":0.5}]}\n",
    )
    .unwrap();
    let e = reply(&mut r, 1);
    assert_eq!(e["type"], "error", "{e}");
    let msg = e["message"].as_str().unwrap_or_default();
    assert!(msg.starts_with("duplicate key `x` at column "), "{e}");
    // A command name with controls JSON leaves as they are (C1, bidi).
    w.write_all(b"{\"type\":\"command\",\"id\":2,\"name\":\"pa\\u009b2J\\u202euse\"}\n")
        .unwrap();
    let e = reply(&mut r, 2);
    assert_eq!(e["type"], "error", "{e}");
    let msg = e["message"].as_str().unwrap_or_default().to_string();
    assert!(
        msg.contains("unknown command `pa\\u{9b}2J\\u{202e}use`"),
        "{e}"
    );
    assert!(!msg.chars().any(needs_escape), "{msg:?}");
    // Still connected and answered.
    w.write_all(b"{\"type\":\"command\",\"id\":3,\"name\":\"pause\"}\n")
        .unwrap();
    assert_eq!(reply(&mut r, 3)["type"], "ack");
    daemon.shutdown();
}

#[test]
fn a_bad_hex_byte_of_a_hid_recording_is_quoted_escaped() {
    let text = "R: 2 05 \u{1b}[2J\nE: 0.000001 1 01\n";
    let e = parse_recording(text, Path::new("x.hid"), OnBadFrame::Stop)
        .unwrap_err()
        .to_string();
    assert!(e.contains("`\\u{1b}[2J` is not a hex byte"), "{e}");
    assert!(!e.chars().any(needs_escape), "{e:?}");
}
