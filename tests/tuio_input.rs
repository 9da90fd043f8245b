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
    }];
    assert_eq!(cfg.validate(), vec![], "the config is valid");
    let sources = sources_from_config(&cfg).expect("the TUIO port binds");
    let daemon = Daemon::start(
        cfg.clone(),
        sources,
        DaemonOptions {
            socket_path: path.clone(),
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
    }];
    let daemon = Daemon::start(
        cfg.clone(),
        sources_from_config(&cfg).unwrap(),
        DaemonOptions {
            socket_path: path.clone(),
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
