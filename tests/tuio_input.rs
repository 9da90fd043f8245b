//! The TUIO input through the whole daemon: cursors sent over UDP by an
//! independent encoder (rosc) drive the crowd, seen by a Unix-socket client.

mod common;

use common::*;
use crowdtouch::config::{Config, InputConfig};
use crowdtouch::geom::Vec2;
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions};
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
use serde_json::Value;
use std::io::BufReader;
use std::net::UdpSocket;
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

fn msg(addr: &str, args: Vec<OscType>) -> OscPacket {
    OscPacket::Message(OscMessage {
        addr: addr.into(),
        args,
    })
}

/// One TUIO 1.1 frame: source, alive, a set per cursor, fseq.
fn frame(cursors: &[(i32, f32, f32)], fseq: i32) -> Vec<u8> {
    let s = |v: &str| OscType::String(v.into());
    let mut c = vec![msg("/tuio/2Dcur", vec![s("source"), s("test@localhost")])];
    let mut alive = vec![s("alive")];
    alive.extend(cursors.iter().map(|k| OscType::Int(k.0)));
    c.push(msg("/tuio/2Dcur", alive));
    for &(id, x, y) in cursors {
        c.push(msg(
            "/tuio/2Dcur",
            vec![
                s("set"),
                OscType::Int(id),
                OscType::Float(x),
                OscType::Float(y),
                OscType::Float(0.0),
                OscType::Float(0.0),
                OscType::Float(0.0),
            ],
        ));
    }
    c.push(msg("/tuio/2Dcur", vec![s("fseq"), OscType::Int(fseq)]));
    rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
        timetag: OscTime::from((0, 1)),
        content: c,
    }))
    .unwrap()
}

fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn pairs(v: &Value) -> Vec<Vec2> {
    v.as_array()
        .unwrap()
        .chunks_exact(2)
        .map(|c| Vec2::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
        .collect()
}

/// The touches of a snapshot: (x, y) in world metres.
fn touches(v: &Value) -> Vec<Vec2> {
    v["touches"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|t| Vec2::new(t["x"].as_f64().unwrap(), t["y"].as_f64().unwrap()))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn tuio_cursors_drag_the_crowd_and_lift_when_they_leave_alive() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let port = free_udp_port();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 40;
    cfg.pipeline.realtime = Default::default();
    cfg.inputs = vec![InputConfig::Tuio {
        listen: format!("127.0.0.1:{port}"),
        region: None,
        calibration: Default::default(),
        timeout_ms: 1000,
        max_sessions_per_frame: 64,
        max_senders: 8,
        max_packets_per_s: 4000,
    }];
    assert_eq!(cfg.validate(), vec![], "the config is valid");
    let sources = sources_from_config(&cfg).expect("the TUIO port binds");
    let daemon = Daemon::start(
        cfg.clone(),
        sources,
        DaemonOptions {
            socket_path: path.clone(),
            collect: None,
        },
    )
    .expect("daemon starts");
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    let hello = read_until(&mut r, 5.0, |v| v["type"] == "hello");
    let world = &hello.last().unwrap()["world"];
    let (min, max) = (pairs(&world["min"])[0], pairs(&world["max"])[0]);
    let to_world = |x: f32, y: f32| {
        Vec2::new(
            min.x + f64::from(x) * (max.x - min.x),
            min.y + f64::from(y) * (max.y - min.y),
        )
    };
    let first = read_until(&mut r, 5.0, |v| v["type"] == "snapshot");
    let before = centroid(pairs(&first.last().unwrap()["positions"]));

    // A finger on the crowd's centre, dragged 3 m to the right over a second.
    let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
    let table = (
        ((before.x - min.x) / (max.x - min.x)) as f32,
        ((before.y - min.y) / (max.y - min.y)) as f32,
    );
    let dx = (3.0 / (max.x - min.x)) as f32;
    let steps = 60;
    let mut fseq = 1;
    for k in 0..=steps {
        let x = table.0 + dx * k as f32 / steps as f32;
        sender
            .send_to(&frame(&[(5, x, table.1)], fseq), ("127.0.0.1", port))
            .unwrap();
        fseq += 1;
        std::thread::sleep(Duration::from_millis(16));
    }
    let end = to_world(table.0 + dx, table.1);
    // The touch is where the finger is, in world metres.
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && touches(v).iter().any(|t| (t - end).norm() < 0.01)
    });
    let at_end = msgs.last().unwrap();
    assert_eq!(touches(at_end).len(), 1, "one touch: {at_end}");
    assert!(
        (touches(at_end)[0] - end).norm() < 0.01,
        "touch at {} not at {end}",
        touches(at_end)[0]
    );
    // Held there (the sender keeps sending the same frame) until the crowd follows.
    let hold_until = Instant::now() + Duration::from_secs(2);
    while Instant::now() < hold_until {
        sender
            .send_to(
                &frame(&[(5, table.0 + dx, table.1)], fseq),
                ("127.0.0.1", port),
            )
            .unwrap();
        fseq += 1;
        std::thread::sleep(Duration::from_millis(50));
    }
    // It leaves `alive`: lifted.
    sender
        .send_to(&frame(&[], fseq), ("127.0.0.1", port))
        .unwrap();
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && touches(v).is_empty()
    });
    let lifted = msgs.last().unwrap();
    daemon.shutdown();
    let controls: Vec<(&str, &str)> = msgs
        .iter()
        .filter(|v| v["type"] == "control")
        .map(|v| (v["phase"].as_str().unwrap(), v["kind"].as_str().unwrap()))
        .collect();
    assert!(touches(lifted).is_empty(), "the touch was not lifted");
    assert!(
        controls.contains(&("end", "point")),
        "no end of the point control: {controls:?}"
    );
    let after = centroid(pairs(&lifted["positions"]));
    assert!(
        after.x - before.x > 2.0 && (after.y - before.y).abs() < 0.5,
        "the crowd went from {before} to {after}, not 3 m right"
    );
}

#[test]
fn a_silent_sender_is_lifted_and_garbage_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let port = free_udp_port();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.pipeline.realtime = Default::default();
    cfg.inputs = vec![InputConfig::Tuio {
        listen: format!("127.0.0.1:{port}"),
        region: None,
        calibration: Default::default(),
        timeout_ms: 300,
        max_sessions_per_frame: 64,
        max_senders: 8,
        max_packets_per_s: 4000,
    }];
    let daemon = Daemon::start(
        cfg.clone(),
        sources_from_config(&cfg).unwrap(),
        DaemonOptions {
            socket_path: path.clone(),
            collect: None,
        },
    )
    .unwrap();
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    read_until(&mut r, 5.0, |v| v["type"] == "snapshot");
    let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
    sender
        .send_to(
            &frame(&[(1, 0.1, 0.1), (2, 0.9, 0.9)], 1),
            ("127.0.0.1", port),
        )
        .unwrap();
    // Not OSC, an unknown tag, a bundle without fseq: dropped, the touches stay.
    sender
        .send_to(b"not osc at all!!", ("127.0.0.1", port))
        .unwrap();
    sender
        .send_to(b"/a\0\0,b\0\0\0\0\0\0", ("127.0.0.1", port))
        .unwrap();
    let mut no_fseq = frame(&[], 2);
    no_fseq.truncate(no_fseq.len() - 32); // the fseq message, size included
    sender.send_to(&no_fseq, ("127.0.0.1", port)).unwrap();
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && touches(v).len() == 2
    });
    assert_eq!(
        touches(msgs.last().unwrap()).len(),
        2,
        "the two touches came"
    );
    // Then nothing more is sent: lifted once the sender has been silent 300 ms.
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && touches(v).is_empty()
    });
    // `stats` counts what was wrong, under the input's address.
    let mut daemon = daemon;
    let report = daemon
        .next_report(std::time::Duration::from_secs(5))
        .expect("a stats report");
    daemon.shutdown();
    assert!(
        touches(msgs.last().unwrap()).is_empty(),
        "a silent sender's touches stayed"
    );
    let (input, count) = output_counts(&report, "tuio-input");
    assert_eq!(input["address"], format!("127.0.0.1:{port}"));
    assert_eq!(count("malformed"), 2, "{input}");
    assert_eq!(count("timeouts"), 1, "{input}");
    assert!(count("packets") >= 4, "{input}");
}

/// The daemon on one TUIO input written as the config writes it (`Tuio(...)`, the
/// listen address filled in), its socket client past the first snapshot, and the
/// port it listens on.
fn daemon_on_tuio(
    input: &str,
    agents: u32,
) -> (Daemon, BufReader<UnixStream>, u16, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let port = free_udp_port();
    let text = input.replace("LISTEN", &format!("\"127.0.0.1:{port}\""));
    let input: InputConfig = ron::from_str(&text).unwrap_or_else(|e| panic!("{text}: {e}"));
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    cfg.pipeline.realtime = Default::default();
    cfg.inputs = vec![input];
    assert_eq!(cfg.validate(), vec![], "the config is valid");
    let daemon = Daemon::start(
        cfg.clone(),
        sources_from_config(&cfg).expect("the TUIO port binds"),
        DaemonOptions {
            socket_path: path.clone(),
            collect: None,
        },
    )
    .expect("daemon starts");
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    read_until(&mut r, 5.0, |v| v["type"] == "snapshot");
    (daemon, r, port, dir)
}

/// `n` cursors with ids from `first`, spread over the table.
fn cursors(first: i32, n: i32) -> Vec<(i32, f32, f32)> {
    (0..n)
        .map(|k| {
            let (col, row) = (k % 10, k / 10);
            (
                first + k,
                0.05 + 0.09 * col as f32,
                0.05 + 0.09 * row as f32,
            )
        })
        .collect()
}

/// One TUIO 1.1 frame from the sender named `source`.
fn frame_from(source: &str, cursors: &[(i32, f32, f32)], fseq: i32) -> Vec<u8> {
    let mut p = rosc::decoder::decode_udp(&frame(cursors, fseq)).unwrap().1;
    if let OscPacket::Bundle(b) = &mut p {
        if let OscPacket::Message(m) = &mut b.content[0] {
            m.args[1] = OscType::String(source.into());
        }
    }
    rosc::encoder::encode(&p).unwrap()
}

#[test]
fn a_frame_of_100_sessions_gives_the_default_limit_and_counts_the_rest() {
    // The shipped limit: 64 sessions a frame (a touch frame's capacity).
    let (mut daemon, mut r, port, _dir) = daemon_on_tuio("Tuio(listen: LISTEN)", 20);
    let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
    let packet = frame(&cursors(1, 100), 1);
    assert!(
        packet.len() < 65_000,
        "one datagram: {} bytes",
        packet.len()
    );
    sender.send_to(&packet, ("127.0.0.1", port)).unwrap();
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && !touches(v).is_empty()
    });
    let report = daemon
        .next_report(Duration::from_secs(5))
        .expect("a stats report");
    daemon.shutdown();
    assert_eq!(
        touches(msgs.last().unwrap()).len(),
        64,
        "the limit of touches"
    );
    let (input, count) = output_counts(&report, "tuio-input");
    assert_eq!(
        count("sessions_refused"),
        36,
        "the 36 over the limit: {input}"
    );
    assert_eq!(count("frames"), 1, "{input}");
}

/// Sends `frames(k)` to `port` every 16 ms (60 Hz) for `ms` on a thread of its own;
/// the thread returns how many it sent.
fn send_steadily(
    port: u16,
    ms: u64,
    frames: impl Fn(i32) -> Vec<Vec<u8>> + Send + 'static,
) -> std::thread::JoinHandle<i32> {
    std::thread::spawn(move || {
        let s = UdpSocket::bind("127.0.0.1:0").unwrap();
        let end = Instant::now() + Duration::from_millis(ms);
        let mut k = 0;
        while Instant::now() < end {
            k += 1;
            for f in frames(k) {
                s.send_to(&f, ("127.0.0.1", port)).unwrap();
            }
            std::thread::sleep(Duration::from_millis(16));
        }
        k
    })
}

#[test]
fn the_configured_limits_of_sessions_and_senders_hold_and_are_counted() {
    let (mut daemon, mut r, port, _dir) = daemon_on_tuio(
        "Tuio(listen: LISTEN, max_sessions_per_frame: 10, max_senders: 2)",
        20,
    );
    // Sender a: 20 cursors, 10 kept. Sender b: one. Sender c, a third over the
    // limit of 2 senders, sends once while a and b hold touches down: refused.
    let steady = send_steadily(port, 1500, |k| {
        vec![
            frame_from("a@host", &cursors(1, 20), k),
            frame_from("b@host", &[(1, 0.5, 0.95)], k),
        ]
    });
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && touches(v).len() == 11
    });
    assert_eq!(touches(msgs.last().unwrap()).len(), 11, "10 of a, 1 of b");
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .send_to(
            &frame_from("c@host", &[(1, 0.95, 0.5)], 1),
            ("127.0.0.1", port),
        )
        .unwrap();
    let seen = read_until(&mut r, 0.5, |_| false);
    let sent = steady.join().unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let report = daemon
        .next_report(Duration::from_secs(5))
        .expect("a stats report");
    daemon.shutdown();
    for v in seen.iter().filter(|v| v["type"] == "snapshot") {
        assert_eq!(touches(v).len(), 11, "not the limits' touches: {v}");
    }
    let (input, count) = output_counts(&report, "tuio-input");
    assert_eq!(count("senders_refused"), 1, "c's one frame: {input}");
    // 10 of a's 20 in each of its frames.
    assert_eq!(
        count("sessions_refused"),
        10 * sent as u64,
        "{sent} frames of a: {input}"
    );
}

#[test]
fn a_flooding_sender_does_not_starve_a_steady_one() {
    let (mut daemon, mut r, port, _dir) =
        daemon_on_tuio("Tuio(listen: LISTEN, timeout_ms: 500)", 20);
    let at = (0.25f32, 0.5f32);
    let steady = send_steadily(port, 3500, move |k| {
        vec![frame_from("good@host", &[(1, at.0, at.1)], k)]
    });
    read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && touches(v).len() == 1
    });
    // Another sender floods with empty frames for 2.5 s, as fast as it can
    // (loopback only), while the good one sends its touch at 60 Hz.
    let flood = std::thread::spawn(move || {
        let s = UdpSocket::bind("127.0.0.1:0").unwrap();
        let end = Instant::now() + Duration::from_millis(2500);
        let mut sent = 0u64;
        while Instant::now() < end {
            for _ in 0..100 {
                let f = frame_from("flood@host", &[], (sent % 1_000_000) as i32);
                let _ = s.send_to(&f, ("127.0.0.1", port));
                sent += 1;
            }
        }
        sent
    });
    let snapshots: Vec<Value> = read_until(&mut r, 2.5, |_| false)
        .into_iter()
        .filter(|v| v["type"] == "snapshot")
        .collect();
    let sent = flood.join().unwrap();
    steady.join().unwrap();
    let report = daemon
        .next_report(Duration::from_secs(5))
        .expect("a stats report");
    daemon.shutdown();
    let (input, count) = output_counts(&report, "tuio-input");
    assert!(count("flood_dropped") > 0, "no flood: {sent} sent, {input}");
    assert!(snapshots.len() > 20, "{} snapshots read", snapshots.len());
    let missing = snapshots.iter().filter(|v| touches(v).len() != 1).count();
    eprintln!(
        "flood: {sent} datagrams sent, {} dropped, {} taken; {} snapshots read",
        count("flood_dropped"),
        count("packets"),
        snapshots.len()
    );
    assert_eq!(
        missing,
        0,
        "the steady touch missing from {missing} of {} snapshots ({sent} flood datagrams, {input})",
        snapshots.len()
    );
}

#[test]
fn the_limits_are_checked_with_their_place_in_the_config() {
    let text = crowdtouch::config::DEFAULT_CONFIG_RON.replacen(
        "inputs: [",
        "inputs: [\n        Tuio(listen: \"127.0.0.1:3333\", max_sessions_per_frame: 65, max_senders: 0, max_packets_per_s: 5),",
        1,
    );
    let err = Config::from_str(&text, std::path::Path::new("t.ron"))
        .unwrap_err()
        .to_string();
    for field in ["max_sessions_per_frame", "max_senders", "max_packets_per_s"] {
        assert!(
            err.lines()
                .any(|l| l.starts_with("t.ron:") && l.contains(&format!("inputs[0].{field}"))),
            "{field} not named: {err}"
        );
    }
    // The shipped defaults are the decoder's.
    let InputConfig::Tuio {
        max_sessions_per_frame,
        max_senders,
        max_packets_per_s,
        ..
    } = ron::from_str("Tuio()").unwrap()
    else {
        unreachable!()
    };
    let d = crowdtouch::input::tuio::TuioLimits::default();
    assert_eq!(
        (
            max_sessions_per_frame as usize,
            max_senders as usize,
            max_packets_per_s
        ),
        (d.sessions_per_frame, d.senders, d.packets_per_s)
    );
}
