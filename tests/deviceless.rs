//! A table with no touch device, through the binary as a user runs it: `run -c` on
//! a config whose touches come only from clients starts, says where they come
//! from, reads no device, serves the viewer page, and the viewer's touches (the
//! `touch` command its page sends for a mouse drag, over the WebSocket) drag the
//! crowd. A config whose only input is TUIO starts too, and its senders drag the
//! crowd.

mod common;

use common::centroid;
use common::run_process::{free_port, Env, Running};
use crowdtouch::geom::Vec2;
use crowdtouch::publish::websocket::VIEWER_PAGE;
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
use serde_json::{json, Value};
use std::io::{BufReader, Read, Write};
use std::net::{TcpStream, UdpSocket};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// The shipped config of a table with no touch device.
const NO_DEVICE: &str = include_str!("../config/no-device.ron");

/// `NO_DEVICE` with each `(from, to)` replaced once, at normal priority (the tests
/// share the machine), written into `env`.
fn config(env: &Env, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = NO_DEVICE.to_string();
    let realtime = [
        ("priority: Some(20)", "priority: None"),
        ("lock_memory: true", "lock_memory: false"),
    ];
    for (from, to) in edits.iter().chain(&realtime) {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, to, 1);
    }
    let p = env.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The viewer's WebSocket output on `port`.
fn viewer_on(port: u16) -> (&'static str, String) {
    (
        "WebSocket(listen: \"127.0.0.1:8080\", privileged: true),",
        format!("WebSocket(listen: \"127.0.0.1:{port}\", privileged: true),"),
    )
}

/// The second line of `check-config`'s answer (where touches come from), the
/// first saying the config has `inputs` inputs.
fn touch_line(out: &std::process::Output, inputs: &str) -> String {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 2, "{stdout}");
    assert!(
        lines[0].contains(&format!(": ok (100 agents, {inputs}, socket ")),
        "{stdout}"
    );
    lines[1].to_string()
}

/// The names of a process's threads.
fn threads(pid: u32) -> Vec<String> {
    std::fs::read_dir(format!("/proc/{pid}/task"))
        .unwrap()
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("comm")).ok())
        .map(|n| n.trim().to_string())
        .collect()
}

/// What a process's file descriptors point to.
fn open_files(pid: u32) -> Vec<String> {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .unwrap()
        .filter_map(|f| std::fs::read_link(f.ok()?.path()).ok())
        .map(|p| p.display().to_string())
        .collect()
}

/// No input thread ran, no device node or inotify watch is open: nothing looked
/// for a device.
fn assert_reads_no_device(daemon: &Running) {
    let threads = threads(daemon.pid());
    assert!(threads.iter().any(|t| t == "ct-control"), "{threads:?}");
    assert!(!threads.iter().any(|t| t == "ct-input"), "{threads:?}");
    let files = open_files(daemon.pid());
    assert!(
        !files.iter().any(|f| f.starts_with("/dev/input")
            || f.starts_with("/dev/hidraw")
            || f.contains("inotify")),
        "{files:?}"
    );
}

/// `GET /` of the viewer: status and the whole response.
fn get_page(port: u16) -> (u16, String) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    write!(s, "GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n").unwrap();
    let (mut out, end) = (Vec::new(), Instant::now() + Duration::from_secs(5));
    let mut chunk = [0u8; 8192];
    while Instant::now() < end {
        match s.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => out.extend_from_slice(&chunk[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) => {}
            Err(_) => break,
        }
    }
    let text = String::from_utf8_lossy(&out).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (status, text)
}

/// The page's WebSocket, as a browser opens it from the page (its own origin).
fn viewer_socket(port: u16) -> WebSocket<TcpStream> {
    use tungstenite::client::IntoClientRequest;
    let mut req = format!("ws://127.0.0.1:{port}/ws")
        .into_client_request()
        .unwrap();
    req.headers_mut().insert(
        "Origin",
        format!("http://127.0.0.1:{port}").parse().unwrap(),
    );
    let stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    match tungstenite::client(req, stream) {
        Ok((ws, _)) => ws,
        Err(e) => panic!("the viewer's upgrade: {e}"),
    }
}

/// Reads JSON messages until `until` holds (that one is the last returned) or
/// `secs` are up.
fn read_ws(
    ws: &mut WebSocket<TcpStream>,
    secs: f64,
    mut until: impl FnMut(&Value) -> bool,
) -> Vec<Value> {
    let end = Instant::now() + Duration::from_secs_f64(secs);
    let mut out = vec![];
    while Instant::now() < end {
        match ws.read() {
            Ok(Message::Text(t)) => {
                let v: Value = serde_json::from_str(t.as_str()).unwrap();
                let stop = until(&v);
                out.push(v);
                if stop {
                    break;
                }
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => panic!("the viewer's socket: {e}"),
        }
    }
    out
}

fn send(ws: &mut WebSocket<TcpStream>, v: &Value) {
    ws.send(Message::Text(v.to_string().into())).unwrap();
}

fn xy(v: &Value) -> Vec2 {
    Vec2::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

fn positions(v: &Value) -> Vec<Vec2> {
    v["positions"]
        .as_array()
        .unwrap()
        .chunks_exact(2)
        .map(|c| Vec2::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
        .collect()
}

fn touches(v: &Value) -> usize {
    v["touches"].as_array().map_or(0, Vec::len)
}

/// The world rectangle of a `hello`: (min, size).
fn world(hello: &Value) -> (Vec2, Vec2) {
    let (min, max) = (xy(&hello["world"]["min"]), xy(&hello["world"]["max"]));
    (min, max - min)
}

/// `check-config` passes the shipped config of a table with no touch device and
/// says where its touches come from; `run` starts on it with no input thread and
/// no device open, logs the same line, serves the viewer page, and a mouse drag
/// on the page — the `touch` commands the page sends, one per frame, then the
/// empty list when the button is released — takes the crowd 3 m to the right.
#[test]
fn a_table_with_only_the_viewer_runs_and_the_viewers_drag_moves_the_crowd() {
    let env = Env::new();
    let port = free_port();
    let (from, to) = viewer_on(port);
    let file = config(&env, "viewer.ron", &[(from, &to)]);
    let line = touch_line(&env.check_config(&file), "0 inputs");
    assert_eq!(
        line,
        format!(
            "no touch device configured: touches come only from clients: the viewer page and \
             the WebSocket clients of http://127.0.0.1:{port}/ (`touch` command), privileged \
             clients of the Unix socket (`touch` command: root, the daemon's user, \
             socket.privileged)"
        )
    );
    let daemon = env.run(&file).unwrap_or_else(|(code, log)| {
        panic!("run refused a config check-config passed (exit {code:?}):\n{log}")
    });
    assert!(daemon.logged(&line), "{}", daemon.log());
    assert_reads_no_device(&daemon);

    // The page.
    let (status, page) = get_page(port);
    assert_eq!(status, 200, "{page}");
    assert!(page.ends_with(VIEWER_PAGE), "the viewer page, whole");
    assert!(
        VIEWER_PAGE.contains(r#"send({ type: "command", id, name: "touch", contacts })"#),
        "the page sends its pointers as the `touch` command"
    );

    // The page's socket, and its hello.
    let mut ws = viewer_socket(port);
    send(
        &mut ws,
        &json!({"type": "hello", "protocol": 1, "format": "json",
            "subscribe": ["snapshot", "mesh", "events", "stats", "transform", "scene", "plan", "edit"],
            "max_rate_hz": 60, "fields": ["positions", "touches", "motions"]}),
    );
    let got = read_ws(&mut ws, 10.0, |v| {
        v["type"] == "hello" && v.get("privileged").is_some()
    });
    let hello = got.last().expect("the daemon's hello").clone();
    assert_eq!(hello["privileged"], true, "{hello}");
    let (min, size) = world(&hello);
    let first = read_ws(&mut ws, 10.0, |v| v["type"] == "snapshot");
    let before = centroid(positions(first.last().expect("a snapshot")));
    assert!(first.last().unwrap()["positions"].as_array().unwrap().len() == 200);

    // A mouse drag from the crowd's centre, 3 m to the right over half a second,
    // held (the page repeats its contacts every 200 ms while the button is down),
    // then released. Each command is answered before the next, as the page keeps
    // at most a few in flight. Pointer 1 (`pointerId & 0xffff`).
    let table = |p: Vec2| ((p.x - min.x) / size.x, (p.y - min.y) / size.y);
    let (x0, y0) = table(before);
    let dx = 3.0 / size.x;
    let mut n = 0;
    let mut touch = |ws: &mut WebSocket<TcpStream>, contacts: Value| {
        n += 1;
        let id = format!("t{n}");
        send(
            ws,
            &json!({"type": "command", "id": id, "name": "touch", "contacts": contacts}),
        );
        let got = read_ws(ws, 5.0, |v| {
            (v["type"] == "ack" || v["type"] == "error") && v["id"] == id.as_str()
        });
        let answer = got.last().expect("an answer").clone();
        assert_eq!(answer["type"], "ack", "{answer}");
        got
    };
    for k in 0..=30 {
        let x = x0 + dx * f64::from(k) / 30.0;
        touch(&mut ws, json!([{"id": 1, "x": x, "y": y0}]));
        std::thread::sleep(Duration::from_millis(16));
    }
    let held_until = Instant::now() + Duration::from_secs(2);
    let mut seen_down = false;
    while Instant::now() < held_until {
        let got = touch(&mut ws, json!([{"id": 1, "x": x0 + dx, "y": y0}]));
        seen_down |= got
            .iter()
            .any(|v| v["type"] == "snapshot" && touches(v) == 1);
        std::thread::sleep(Duration::from_millis(200));
    }
    assert!(seen_down, "the page's touch is in the snapshots");
    touch(&mut ws, json!([]));
    read_ws(&mut ws, 5.0, |v| v["type"] == "snapshot" && touches(v) == 0);
    // A second on, the crowd rests where the finger left it.
    let mut snapshots = 0;
    let later = read_ws(&mut ws, 10.0, |v| {
        snapshots += usize::from(v["type"] == "snapshot");
        snapshots == 60
    });
    let last = later
        .iter()
        .rev()
        .find(|v| v["type"] == "snapshot")
        .expect("snapshots after the release");
    let after = centroid(positions(last));
    let (status, log) = daemon.stop();
    assert!(status.success(), "{log}");
    assert!(
        after.x - before.x > 2.0 && (after.y - before.y).abs() < 0.5,
        "the crowd went from {before} to {after}, not about 3 m right"
    );
}

fn osc(addr: &str, args: Vec<OscType>) -> OscPacket {
    OscPacket::Message(OscMessage {
        addr: addr.into(),
        args,
    })
}

/// One TUIO 1.1 frame: source, alive, a set per cursor, fseq.
fn tuio_frame(cursors: &[(i32, f32, f32)], fseq: i32) -> Vec<u8> {
    let s = |v: &str| OscType::String(v.into());
    let mut c = vec![osc("/tuio/2Dcur", vec![s("source"), s("test@localhost")])];
    let mut alive = vec![s("alive")];
    alive.extend(cursors.iter().map(|k| OscType::Int(k.0)));
    c.push(osc("/tuio/2Dcur", alive));
    for &(id, x, y) in cursors {
        c.push(osc(
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
    c.push(osc("/tuio/2Dcur", vec![s("fseq"), OscType::Int(fseq)]));
    rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
        timetag: OscTime::from((0, 1)),
        content: c,
    }))
    .unwrap()
}

/// Reads socket lines until `until` holds or `secs` are up.
fn read_lines(
    r: &mut BufReader<UnixStream>,
    secs: f64,
    until: impl FnMut(&Value) -> bool,
) -> Vec<Value> {
    common::read_until(r, secs, until)
}

/// A config whose only input is TUIO (no device, no recording, no output) passes
/// `check-config`, starts with one input thread and no device open, says that its
/// touches come from TUIO senders and the socket, and a TUIO cursor dragged 3 m
/// to the right takes the crowd with it (seen by a client of the Unix socket).
#[test]
fn a_table_with_only_a_tuio_input_runs_and_its_senders_drag_the_crowd() {
    let env = Env::new();
    let port = free_port();
    let (viewer, _) = viewer_on(port);
    let file = config(
        &env,
        "tuio.ron",
        &[
            (
                "    inputs: [],",
                &format!("    inputs: [Tuio(listen: \"127.0.0.1:{port}\")],"),
            ),
            (viewer, ""),
        ],
    );
    let line = touch_line(&env.check_config(&file), "1 input");
    assert_eq!(
        line,
        format!(
            "no touch device configured: touches come only from clients: TUIO senders to \
             127.0.0.1:{port}, privileged clients of the Unix socket (`touch` command: root, \
             the daemon's user, socket.privileged)"
        )
    );
    let daemon = env.run(&file).unwrap_or_else(|(code, log)| {
        panic!("run refused a config check-config passed (exit {code:?}):\n{log}")
    });
    assert!(daemon.logged(&line), "{}", daemon.log());
    let threads = threads(daemon.pid());
    assert_eq!(
        threads.iter().filter(|t| *t == "ct-input").count(),
        1,
        "the TUIO input's thread: {threads:?}"
    );
    let files = open_files(daemon.pid());
    assert!(
        !files
            .iter()
            .any(|f| f.starts_with("/dev/input") || f.starts_with("/dev/hidraw")),
        "{files:?}"
    );

    let mut r = BufReader::new(UnixStream::connect(env.socket()).unwrap());
    let hello = read_lines(&mut r, 10.0, |v| v["type"] == "hello");
    let (min, size) = world(hello.last().expect("the daemon's hello"));
    let first = read_lines(&mut r, 10.0, |v| v["type"] == "snapshot");
    let before = centroid(positions(first.last().expect("a snapshot")));
    let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
    let (x0, y0) = (
        ((before.x - min.x) / size.x) as f32,
        ((before.y - min.y) / size.y) as f32,
    );
    let dx = (3.0 / size.x) as f32;
    let mut fseq = 1;
    for k in 0..=60 {
        let x = x0 + dx * k as f32 / 60.0;
        sender
            .send_to(&tuio_frame(&[(5, x, y0)], fseq), ("127.0.0.1", port))
            .unwrap();
        fseq += 1;
        std::thread::sleep(Duration::from_millis(16));
    }
    let held_until = Instant::now() + Duration::from_secs(2);
    while Instant::now() < held_until {
        sender
            .send_to(&tuio_frame(&[(5, x0 + dx, y0)], fseq), ("127.0.0.1", port))
            .unwrap();
        fseq += 1;
        std::thread::sleep(Duration::from_millis(50));
    }
    sender
        .send_to(&tuio_frame(&[], fseq), ("127.0.0.1", port))
        .unwrap();
    let msgs = read_lines(&mut r, 10.0, |v| {
        v["type"] == "snapshot" && touches(v) == 0 && {
            let c = centroid(positions(v));
            c.x - before.x > 2.0
        }
    });
    let last = msgs.last().expect("snapshots");
    let after = centroid(positions(last));
    let (status, log) = daemon.stop();
    assert!(status.success(), "{log}");
    assert!(
        after.x - before.x > 2.0 && (after.y - before.y).abs() < 0.5,
        "the crowd went from {before} to {after}, not about 3 m right"
    );
}
