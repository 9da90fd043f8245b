//! The WebSocket output through the whole daemon: a recording replayed in real time,
//! read by `tungstenite` clients (and the viewer page fetched over plain HTTP); the
//! privileged/read-only split on the WebSocket and on the Unix socket.

mod common;

use common::*;
use crowdtouch::config::{Config, OutputConfig};
use crowdtouch::input::replay::ReplayItem;
use crowdtouch::pipeline::{Daemon, DaemonOptions, SourceSpec};
use crowdtouch::publish::protocol::decode_snapshot_binary;
use crowdtouch::publish::websocket::VIEWER_PAGE;
use crowdtouch::vocab::{Micros, TouchFrame};
use serde_json::Value;
use std::io::{BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::os::unix::net::UnixStream;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::time::{Duration, Instant};
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::{Message, WebSocket};

type Ws = WebSocket<TcpStream>;

const TOKEN: &str = "0123456789abcdef-test";

/// A port free a moment ago on loopback.
fn free_addr() -> SocketAddr {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
}

fn websocket(addr: SocketAddr, privileged: bool, token: Option<&str>) -> OutputConfig {
    OutputConfig::WebSocket {
        listen: addr.to_string(),
        token: token.map(str::to_string),
        privileged,
        max_clients: 8,
        max_message_bytes: 4096,
        viewer: true,
    }
}

/// The daemon on `01-point-drag.jsonl` (half a second of nothing first, so a client
/// connected right after the start sees the touches).
fn start(mut cfg: Config, sock: &Path) -> Daemon {
    cfg.pipeline.realtime = Default::default();
    let mut frames = vec![TouchFrame::new(Micros::ZERO)];
    let rec = load("01-point-drag.jsonl");
    frames.extend(rec.frames.into_iter().map(|mut f| {
        f.t = f.t + Micros(500_000);
        f
    }));
    let source = SourceSpec::Replay {
        items: vec![ReplayItem::new("01-point-drag.jsonl".to_string(), frames)],
        looped: false,
        gap: Micros(200_000),
        reset_between: false,
        glass_mm: rec.surface.size_mm(),
    };
    Daemon::start(
        cfg,
        vec![source],
        DaemonOptions {
            socket_path: sock.to_path_buf(),
        },
    )
    .expect("daemon starts")
}

/// A WebSocket client of `addr` with `query` (`?token=...`) and extra headers.
fn connect(addr: SocketAddr, query: &str, bearer: Option<&str>) -> Result<Ws, tungstenite::Error> {
    use tungstenite::client::IntoClientRequest;
    let mut req = format!("ws://{addr}/ws{query}").into_client_request()?;
    if let Some(t) = bearer {
        req.headers_mut()
            .insert("Authorization", format!("Bearer {t}").parse().unwrap());
    }
    let stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    match tungstenite::client(req, stream) {
        Ok((ws, _)) => Ok(ws),
        Err(tungstenite::HandshakeError::Failure(e)) => Err(e),
        Err(tungstenite::HandshakeError::Interrupted(_)) => panic!("handshake interrupted"),
    }
}

/// What a client received.
#[derive(Debug)]
enum Got {
    Json(Value),
    Binary(Vec<u8>),
    Closed(Option<(CloseCode, String)>),
}

impl Got {
    fn json(&self) -> Option<&Value> {
        match self {
            Got::Json(v) => Some(v),
            _ => None,
        }
    }
}

/// Reads messages until `until` says so (that one is the last returned), the
/// connection closes, or `secs` are up.
fn read_ws(ws: &mut Ws, secs: f64, mut until: impl FnMut(&Got) -> bool) -> Vec<Got> {
    let end = Instant::now() + Duration::from_secs_f64(secs);
    let mut out = vec![];
    while Instant::now() < end {
        let got = match ws.read() {
            Ok(Message::Text(t)) => Got::Json(
                serde_json::from_str(t.as_str()).unwrap_or_else(|e| panic!("bad text {t:?}: {e}")),
            ),
            Ok(Message::Binary(b)) => Got::Binary(b.to_vec()),
            Ok(Message::Close(f)) => Got::Closed(f.map(|f| (f.code, f.reason.to_string()))),
            Ok(_) => continue,
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                continue
            }
            Err(_) => break,
        };
        let stop = until(&got) || matches!(got, Got::Closed(_));
        out.push(got);
        if stop {
            break;
        }
    }
    out
}

fn send(ws: &mut Ws, text: &str) {
    ws.send(Message::Text(text.to_string().into())).unwrap();
}

/// A plain HTTP request: the status code and the whole response.
fn http(addr: SocketAddr, request: &[u8]) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    s.write_all(request).unwrap();
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (status, text)
}

#[test]
fn a_websocket_client_gets_hello_and_snapshots_in_json_then_binary() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 40;
    cfg.outputs = vec![websocket(addr, true, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let mut ws = connect(addr, "", None).expect("upgrade");
    let mut snaps = 0;
    let json = read_ws(&mut ws, 10.0, |g| {
        if g.json().is_some_and(|v| {
            v["type"] == "snapshot" && v["touches"].as_array().is_some_and(|t| !t.is_empty())
        }) {
            snaps += 1;
        }
        snaps >= 5
    });
    let hello = json[0].json().expect("a text hello first");
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["protocol"], 1);
    assert_eq!(hello["privileged"], true);
    let snap = json
        .iter()
        .filter_map(Got::json)
        .rfind(|v| v["type"] == "snapshot")
        .expect("JSON snapshots");
    assert_eq!(snap["positions"].as_array().unwrap().len(), 80);
    assert_eq!(snaps, 5, "a privileged client sees the touches of the drag");
    // The binary encoding, negotiated in hello: the reply, then binary snapshots.
    send(
        &mut ws,
        r#"{"type":"hello","protocol":1,"format":"binary"}"#,
    );
    let mut binaries = 0;
    let got = read_ws(&mut ws, 5.0, |g| {
        binaries += usize::from(matches!(g, Got::Binary(_)));
        binaries >= 5
    });
    daemon.shutdown();
    let reply = got
        .iter()
        .filter_map(Got::json)
        .find(|v| v["type"] == "hello")
        .unwrap_or_else(|| panic!("the hello reply: {got:?}"));
    assert_eq!(reply["format"], "binary");
    let frames: Vec<&Vec<u8>> = got
        .iter()
        .filter_map(|g| match g {
            Got::Binary(b) => Some(b),
            _ => None,
        })
        .collect();
    assert_eq!(frames.len(), 5);
    for f in frames {
        let s = decode_snapshot_binary(f).expect("one binary snapshot per message");
        assert_eq!(s.agents, 40);
        assert_eq!(s.positions.as_ref().map(Vec::len), Some(40));
    }
}

#[test]
fn a_slow_websocket_client_loses_snapshots_and_is_told() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 2000;
    cfg.socket.client_queue = 2;
    cfg.outputs = vec![websocket(addr, true, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let mut ws = connect(addr, "", None).expect("upgrade");
    // Reads nothing for a while: its socket buffers fill, then its queue.
    std::thread::sleep(Duration::from_secs(4));
    let dropped_meanwhile = daemon.publisher_stats().snapshots_dropped();
    let mut notice: Option<Value> = None;
    let got = read_ws(&mut ws, 20.0, |g| {
        if let Some(v) = g.json().filter(|v| v["type"] == "dropped") {
            notice = Some(v.clone());
        }
        notice.is_some() && g.json().is_some_and(|v| v["type"] == "snapshot")
    });
    daemon.shutdown();
    assert!(
        dropped_meanwhile > 0,
        "the publisher dropped snapshots for it"
    );
    let notice = notice.expect("a dropped notice");
    assert!(notice["count"].as_u64().unwrap() > 0, "{notice}");
    let last = got
        .last()
        .and_then(Got::json)
        .expect("a snapshot after the notice");
    assert_eq!(last["type"], "snapshot");
    assert!(last["dropped"].as_u64().unwrap() >= notice["count"].as_u64().unwrap());
}

#[test]
fn a_token_protected_output_refuses_a_wrong_token_and_accepts_the_right_one() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.outputs = vec![websocket(addr, false, Some(TOKEN))];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    for (query, bearer) in [
        ("?token=wrong-token-0000000", None),
        ("", None),
        ("", Some("nope")),
    ] {
        match connect(addr, query, bearer) {
            Err(tungstenite::Error::Http(resp)) => assert_eq!(resp.status(), 401),
            other => panic!("{query} {bearer:?}: expected 401, got {other:?}"),
        }
    }
    let stats = daemon.publisher_stats().clone();
    assert_eq!(stats.websocket_refused(), 3);
    // The right token, on the URL or as a bearer token.
    for (query, bearer) in [
        (format!("?token={TOKEN}"), None),
        (String::new(), Some(TOKEN)),
    ] {
        let mut ws = connect(addr, &query, bearer).expect("the right token is let in");
        let got = read_ws(&mut ws, 5.0, |_| true);
        assert_eq!(got[0].json().unwrap()["type"], "hello");
    }
    // The page needs no token (it passes its own URL's token on).
    let (status, _) = http(addr, b"GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    daemon.shutdown();
    assert_eq!(status, 200);
}

#[test]
fn an_oversize_message_closes_only_its_client() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.outputs = vec![websocket(addr, true, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let mut big = connect(addr, "", None).unwrap();
    let mut other = connect(addr, "", None).unwrap();
    read_ws(&mut big, 5.0, |_| true);
    read_ws(&mut other, 5.0, |_| true);
    let huge = format!(r#"{{"type":"hello","pad":"{}"}}"#, "x".repeat(8000));
    send(&mut big, &huge);
    let got = read_ws(&mut big, 5.0, |_| false);
    let Some(Got::Closed(Some((code, reason)))) = got.last() else {
        panic!("closed with a reason, got {:?}", got.last());
    };
    assert_eq!(*code, CloseCode::Size);
    assert!(reason.contains("4096 bytes"), "{reason}");
    // The other client goes on.
    let mut n = 0;
    let rest = read_ws(&mut other, 5.0, |g| {
        n += usize::from(g.json().is_some_and(|v| v["type"] == "snapshot"));
        n >= 10
    });
    let oversize = daemon.publisher_stats().websocket_oversize();
    daemon.shutdown();
    assert_eq!(n, 10, "the other client still gets snapshots: {rest:?}");
    assert_eq!(oversize, 1);
}

#[test]
fn the_page_is_served_and_bad_requests_get_their_status() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.outputs = vec![websocket(addr, false, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let (status, page) = http(addr, b"GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    assert_eq!(status, 200);
    assert!(page.contains("Content-Type: text/html"), "{page}");
    assert!(page.ends_with(VIEWER_PAGE), "the embedded page, whole");
    assert_eq!(http(addr, b"GET /nope HTTP/1.1\r\n\r\n").0, 404);
    assert_eq!(
        http(addr, b"POST / HTTP/1.1\r\nContent-Length: 0\r\n\r\n").0,
        405
    );
    let mut huge = b"GET / HTTP/1.1\r\nX-Pad: ".to_vec();
    huge.resize(10_000, b'a');
    huge.extend_from_slice(b"\r\n\r\n");
    assert_eq!(http(addr, &huge).0, 431);
    assert_eq!(http(addr, b"\x16\x03\x01\x02\x00 not http\r\n\r\n").0, 400);
    // A client gone in the middle of its head bothers nobody.
    let mut half = TcpStream::connect(addr).unwrap();
    half.write_all(b"GET /ws HTTP/1.1\r\nUpgr").unwrap();
    drop(half);
    let mut ws = connect(addr, "", None).expect("still serving");
    let got = read_ws(&mut ws, 5.0, |_| true);
    daemon.shutdown();
    assert_eq!(got[0].json().unwrap()["type"], "hello");
}

#[test]
fn a_read_only_websocket_client_gets_no_touches_and_no_commands() {
    let dir = tempfile::tempdir().unwrap();
    let (open, shut) = (free_addr(), free_addr());
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 30;
    cfg.outputs = vec![websocket(open, true, None), websocket(shut, false, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let mut privileged = connect(open, "", None).unwrap();
    let mut read_only = connect(shut, "", None).unwrap();
    // Even when it asks for them.
    send(
        &mut read_only,
        r#"{"type":"hello","protocol":1,"fields":["positions","touches"]}"#,
    );
    send(
        &mut read_only,
        r#"{"type":"command","id":7,"name":"reset","hard":true}"#,
    );
    let mut seen_control = false;
    let ro = read_ws(&mut read_only, 10.0, |g| {
        seen_control |= g.json().is_some_and(|v| v["type"] == "control");
        seen_control
    });
    let mut touching = 0;
    let pr = read_ws(&mut privileged, 10.0, |g| {
        touching += usize::from(g.json().is_some_and(|v| {
            v["type"] == "snapshot" && v["touches"].as_array().is_some_and(|t| !t.is_empty())
        }));
        touching >= 3
    });
    daemon.shutdown();
    let ro: Vec<&Value> = ro.iter().filter_map(Got::json).collect();
    assert_eq!(ro[0]["privileged"], false, "the hello says so");
    let reply = ro
        .iter()
        .find(|v| v["type"] == "hello" && v["fields"].is_array())
        .unwrap();
    assert!(!reply["fields"]
        .as_array()
        .unwrap()
        .contains(&"touches".into()));
    let err = ro
        .iter()
        .find(|v| v["type"] == "error")
        .expect("the command is refused");
    assert_eq!(err["id"], 7, "{ro:?}");
    assert!(
        err["message"]
            .as_str()
            .unwrap()
            .starts_with("read-only client"),
        "{err}"
    );
    assert!(seen_control, "controls still reach a read-only client");
    let snaps: Vec<&&Value> = ro.iter().filter(|v| v["type"] == "snapshot").collect();
    assert!(!snaps.is_empty());
    assert!(
        snaps.iter().all(|s| s.get("touches").is_none()),
        "no raw touches"
    );
    assert_eq!(touching, 3, "the privileged client sees them: {}", pr.len());
}

/// Runs in a child process as another user (see the test below): connects to the
/// socket named by `CT_READ_ONLY_PEER_SOCKET`, sends a command, and prints the
/// lines it gets on stdout.
#[test]
#[ignore = "run by unix_socket_peers_are_privileged_by_their_credentials as another user"]
fn read_only_peer_child() {
    let path = std::env::var("CT_READ_ONLY_PEER_SOCKET").expect("run by the parent test");
    let s = UnixStream::connect(path).unwrap();
    let mut w = s.try_clone().unwrap();
    writeln!(
        w,
        r#"{{"type":"command","id":3,"name":"reset","hard":true}}"#
    )
    .unwrap();
    let mut r = BufReader::new(s);
    let got = read_until(&mut r, 10.0, |v| v["type"] == "error");
    for v in got.iter().filter(|v| v["type"] != "snapshot") {
        println!("LINE {v}");
    }
    let touches = got
        .iter()
        .filter(|v| v["type"] == "snapshot")
        .any(|v| v.get("touches").is_some());
    println!("TOUCHES {touches}");
}

#[test]
fn unix_socket_peers_are_privileged_by_their_credentials() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.socket.mode = "0666".into();
    let daemon = start(cfg, &path);
    // This process's own user is privileged.
    let s = UnixStream::connect(&path).unwrap();
    let mut w = s.try_clone().unwrap();
    writeln!(w, r#"{{"type":"command","id":1,"name":"pause"}}"#).unwrap();
    let mut r = BufReader::new(s);
    let own = read_until(&mut r, 5.0, |v| v["id"] == 1);
    assert_eq!(own[0]["privileged"], true);
    assert_eq!(own.last().unwrap()["type"], "ack", "{:?}", own.last());
    if !nix::unistd::geteuid().is_root() {
        daemon.shutdown();
        println!("SKIPPED the read-only peer: making a client of another user needs root");
        return;
    }
    // Another user (nobody), not listed in socket.privileged: read-only.
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "read_only_peer_child",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("CT_READ_ONLY_PEER_SOCKET", &path)
        .uid(65534)
        .gid(65534)
        .output()
        .unwrap();
    daemon.shutdown();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "child: {text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = text
        .lines()
        .filter_map(|l| l.split_once("LINE ").map(|(_, v)| v))
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines[0]["type"], "hello", "{text}");
    assert_eq!(lines[0]["privileged"], false, "{text}");
    let err = lines.last().unwrap();
    assert_eq!((&err["type"], &err["id"]), (&"error".into(), &3.into()));
    assert!(err["message"]
        .as_str()
        .unwrap()
        .starts_with("read-only client"));
    assert!(text.contains("TOUCHES false"), "{text}");
}
