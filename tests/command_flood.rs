//! A client flooding commands does not flood the other clients: `paused` is sent on
//! a change only and at most once per tick, `reset` at most once per tick, and a
//! slow reader keeps its connection (issue 14, item 8: 10,000 pause/reset commands
//! a second used to broadcast ~72k `paused` and ~73k `reset` events and disconnect
//! a reader taking 50 lines a second).

mod common;

use common::daemon_on_channel;
use crowdtouch::config::Config;
use serde_json::Value;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Commands the flooding client sends: ten seconds of them at the socket's pace of
/// 200 lines a second, 20 per tick of the daemon under test.
const COMMANDS: u64 = 2_000;
/// Ticks per second of the daemon under test: few, so that a reader taking 50 lines
/// a second keeps up with everything a tick may publish (a snapshot and at most one
/// `paused` and one `reset` event) however long the flood takes.
const TICK_HZ: f64 = 10.0;
/// The slow reader's pace (lines per second), as in the issue's reproduction.
const SLOW_LINES_PER_S: u64 = 50;

#[derive(Default, Debug)]
struct Seen {
    paused: Vec<bool>,
    resets: u64,
    replies: u64,
    first_seq: Option<u64>,
    last_seq: u64,
    last_snapshot_paused: bool,
    fatal: Option<String>,
}

/// Reads `r` at [`SLOW_LINES_PER_S`] until a snapshot with `seq >= until_seq` (once
/// it is set), the end of the stream, or a fatal error.
fn read_stream(mut r: BufReader<UnixStream>, until_seq: Arc<AtomicU64>) -> Seen {
    r.get_ref()
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let mut seen = Seen::default();
    let mut line = String::new();
    let deadline = Instant::now() + Duration::from_secs(300);
    while Instant::now() < deadline {
        line.clear();
        match r.read_line(&mut line) {
            Ok(0) => {
                seen.fatal.get_or_insert_with(|| "end of stream".into());
                break;
            }
            Ok(_) => {}
            Err(_) => continue,
        }
        std::thread::sleep(Duration::from_millis(1000 / SLOW_LINES_PER_S));
        let v: Value = serde_json::from_str(&line).unwrap();
        match v["type"].as_str().unwrap() {
            "paused" => seen.paused.push(v["paused"].as_bool().unwrap()),
            "reset" => seen.resets += 1,
            "ack" | "error" if v["fatal"] != true => seen.replies += 1,
            "error" => {
                seen.fatal = Some(v["message"].to_string());
                break;
            }
            "snapshot" => {
                let seq = v["seq"].as_u64().unwrap();
                seen.first_seq.get_or_insert(seq);
                seen.last_seq = seq;
                seen.last_snapshot_paused = v["paused"].as_bool().unwrap();
                let until = until_seq.load(Ordering::SeqCst);
                if until > 0 && seq >= until {
                    break;
                }
            }
            _ => {}
        }
    }
    seen
}

fn connect(path: &std::path::Path) -> BufReader<UnixStream> {
    let mut r = BufReader::new(UnixStream::connect(path).unwrap());
    let mut hello = String::new();
    r.read_line(&mut hello).unwrap();
    assert!(hello.starts_with("{\"type\":\"hello\""), "{hello}");
    r
}

#[test]
fn a_command_flood_reaches_other_clients_as_a_few_state_events() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 40;
    cfg.pipeline.tick_hz = TICK_HZ;
    cfg.pipeline.realtime = Default::default();
    let (daemon, _frames) = daemon_on_channel(cfg, &path, 1);

    // The slow reader: the default stream, 50 lines a second.
    let until_seq = Arc::new(AtomicU64::new(0));
    let slow = {
        let r = connect(&path);
        let until = Arc::clone(&until_seq);
        std::thread::spawn(move || read_stream(r, until))
    };
    // The flooding client: commands only, its replies read on a thread of its own.
    let mut flood = connect(&path);
    writeln!(
        flood.get_mut(),
        r#"{{"type":"hello","protocol":1,"subscribe":[]}}"#
    )
    .unwrap();
    let mut echo = String::new();
    while !echo.starts_with("{\"type\":\"hello\"") {
        echo.clear();
        flood.read_line(&mut echo).unwrap();
    }
    assert!(echo.contains("\"subscriptions\":[]"), "{echo}");
    let mut w = BufWriter::new(flood.get_ref().try_clone().unwrap());
    let replies = std::thread::spawn(move || {
        let mut n = 0u64;
        let mut line = String::new();
        let deadline = Instant::now() + Duration::from_secs(300);
        while n < COMMANDS && Instant::now() < deadline {
            line.clear();
            if flood.read_line(&mut line).unwrap_or(0) == 0 {
                break;
            }
            let v: Value = serde_json::from_str(&line).unwrap();
            assert_ne!(v["fatal"], true, "the flooding client was dropped: {v}");
            if matches!(v["type"].as_str(), Some("ack" | "error")) {
                n += 1;
            }
        }
        n
    });
    for i in 0..COMMANDS {
        let cmd = match i % 4 {
            0 => r#""name":"pause""#,
            1 => r#""name":"reset","hard":true"#,
            2 => r#""name":"resume""#,
            _ => r#""name":"reset""#,
        };
        writeln!(w, r#"{{"type":"command","id":{i},{cmd}}}"#).unwrap();
    }
    w.flush().unwrap();
    assert_eq!(
        replies.join().unwrap(),
        COMMANDS,
        "every command is answered to its sender"
    );

    // Every command has been handled; its events are published by the next tick.
    // A fresh client's first snapshot gives a tick number; five ticks later
    // everything the flood caused is in the slow reader's stream.
    let mut probe = connect(&path);
    let mut line = String::new();
    let now_seq = loop {
        line.clear();
        probe.read_line(&mut line).unwrap();
        let v: Value = serde_json::from_str(&line).unwrap();
        if v["type"] == "snapshot" {
            break v["seq"].as_u64().unwrap();
        }
    };
    until_seq.store(now_seq + 5, Ordering::SeqCst);
    let seen = slow.join().unwrap();
    daemon.shutdown();

    assert_eq!(seen.fatal, None, "the slow reader lost its connection");
    assert!(seen.last_seq >= now_seq + 5, "{seen:?}");
    assert_eq!(
        seen.replies, 0,
        "another client's replies reached the reader"
    );
    let ticks = seen.last_seq - seen.first_seq.unwrap() + 1;
    assert!(!seen.paused.is_empty(), "the pause state changed: {seen:?}");
    assert!(
        seen.paused.len() as u64 <= ticks,
        "{} paused events in {ticks} ticks",
        seen.paused.len()
    );
    assert!(
        seen.resets <= ticks,
        "{} reset events in {ticks} ticks",
        seen.resets
    );
    // On a change only: consecutive events alternate, and the last one is the state
    // the crowd is in.
    assert!(
        seen.paused.windows(2).all(|w| w[0] != w[1]),
        "{:?}",
        seen.paused
    );
    assert_eq!(seen.paused.last().copied(), Some(seen.last_snapshot_paused));
    println!(
        "{COMMANDS} commands: {} paused and {} reset events over {ticks} ticks",
        seen.paused.len(),
        seen.resets
    );
}
