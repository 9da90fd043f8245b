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
use std::net::{SocketAddr, TcpStream};
use std::os::unix::net::UnixStream;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::time::{Duration, Instant};
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::{Message, WebSocket};

type Ws = WebSocket<TcpStream>;

const TOKEN: &str = "0123456789abcdef-test";

fn websocket(addr: SocketAddr, privileged: bool, token: Option<&str>) -> OutputConfig {
    OutputConfig::WebSocket {
        listen: addr.to_string(),
        token: token.map(str::to_string),
        privileged,
        max_clients: 8,
        max_message_bytes: 4096,
        viewer: true,
        metrics: false,
        origins: vec![],
        privileged_origins: vec![],
        hosts: vec![],
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
            collect: None,
        },
    )
    .expect("daemon starts")
}

/// A WebSocket client of `addr` with `query` (`?token=...`) and extra headers.
fn connect(addr: SocketAddr, query: &str, bearer: Option<&str>) -> Result<Ws, tungstenite::Error> {
    let auth = bearer.map(|t| format!("Bearer {t}"));
    connect_with(addr, query, &[("Authorization", auth.as_deref())])
}

/// A tungstenite client of `addr` with `query` whose upgrade carries `headers`
/// (those given `None` are left out).
fn connect_with(
    addr: SocketAddr,
    query: &str,
    headers: &[(&'static str, Option<&str>)],
) -> Result<Ws, tungstenite::Error> {
    use tungstenite::client::IntoClientRequest;
    let mut req = format!("ws://{addr}/ws{query}").into_client_request()?;
    for (name, value) in headers {
        if let Some(v) = value {
            req.headers_mut().insert(*name, v.parse().unwrap());
        }
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

/// A plain `GET path` with `Host: addr`.
fn get(path: &str, addr: SocketAddr) -> String {
    format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n")
}

/// A plain HTTP request: the status code and the whole response.
fn http(addr: SocketAddr, request: &[u8]) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    s.write_all(request).unwrap();
    // Until the server closes, or 5 s (an upgraded connection streams on).
    let (mut out, end) = (Vec::new(), Instant::now() + Duration::from_secs(5));
    let mut chunk = [0u8; 4096];
    while Instant::now() < end {
        match s.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => out.extend_from_slice(&chunk[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
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
    let (status, _) = http(addr, get("/", addr).as_bytes());
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
    let (status, page) = http(addr, get("/", addr).as_bytes());
    assert_eq!(status, 200);
    assert!(page.contains("Content-Type: text/html"), "{page}");
    assert!(page.ends_with(VIEWER_PAGE), "the embedded page, whole");
    assert_eq!(http(addr, get("/nope", addr).as_bytes()).0, 404);
    let post = format!("POST / HTTP/1.1\r\nHost: {addr}\r\nContent-Length: 0\r\n\r\n");
    assert_eq!(http(addr, post.as_bytes()).0, 405);
    let mut huge = format!("GET / HTTP/1.1\r\nHost: {addr}\r\nX-Pad: ").into_bytes();
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

// ---- Issue 27: who may connect, the handshake, close codes, ping floods ----------

/// A WebSocket upgrade of `/ws` on `addr` by hand: `version` (`"1.1"`), `host`,
/// the extra header lines `extra` (each ending in CRLF), `key`, `ws_version`.
fn upgrade_request(version: &str, host: &str, extra: &str, key: &str, ws_version: &str) -> String {
    format!(
        "GET /ws HTTP/{version}\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: {ws_version}\r\n{extra}\r\n"
    )
}

const KEY: &str = "dGhlIHNhbXBsZSBub25jZQ==";

/// A tungstenite client of `addr` whose upgrade carries `Origin: origin`.
fn connect_from(addr: SocketAddr, query: &str, origin: &str) -> Result<Ws, tungstenite::Error> {
    connect_with(addr, query, &[("Origin", Some(origin))])
}

fn status_of(r: Result<Ws, tungstenite::Error>) -> u16 {
    match r {
        Err(tungstenite::Error::Http(resp)) => resp.status().as_u16(),
        Ok(_) => 101,
        Err(e) => panic!("expected an HTTP status, got {e}"),
    }
}

#[test]
fn a_page_of_another_origin_is_refused_403_on_loopback_and_with_a_token() {
    let dir = tempfile::tempdir().unwrap();
    let open = free_addr();
    // Listening on every address (with its token); the test connects over loopback.
    let port = free_addr().port();
    let wide: SocketAddr = format!("0.0.0.0:{port}").parse().unwrap();
    let wide_local: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.outputs = vec![
        websocket(open, true, None),
        websocket(wide, true, Some(TOKEN)),
    ];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let stats = daemon.publisher_stats().clone();
    assert_eq!(
        status_of(connect_from(open, "", "http://evil.example")),
        403
    );
    assert_eq!(
        status_of(connect_from(
            wide_local,
            &format!("?token={TOKEN}"),
            "http://evil.example"
        )),
        403
    );
    // The raw answer says why.
    let (status, text) = http(
        open,
        upgrade_request(
            "1.1",
            &open.to_string(),
            "Origin: https://evil.example\r\n",
            KEY,
            "13",
        )
        .as_bytes(),
    );
    assert_eq!(status, 403);
    assert!(
        text.contains("origin \"https://evil.example\" may not connect"),
        "{text}"
    );
    // Its own origin (the page it serves) still connects, privileged.
    let mut own = connect_from(open, "", &format!("http://{open}")).expect("its own origin");
    let got = read_ws(&mut own, 5.0, |_| true);
    let refused = stats.websocket_refused();
    daemon.shutdown();
    assert_eq!(got[0].json().unwrap()["privileged"], true);
    assert_eq!(refused, 3, "each refusal counted");
}

#[test]
fn a_request_for_another_host_is_refused_421() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    let mut out = websocket(addr, true, None);
    if let OutputConfig::WebSocket { hosts, .. } = &mut out {
        hosts.push("kiosk.local".to_string());
    }
    cfg.outputs = vec![out];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let port = addr.port();
    let page = |host: &str| {
        http(
            addr,
            format!("GET / HTTP/1.1\r\nHost: {host}\r\n\r\n").as_bytes(),
        )
    };
    // A rebound name (the attacker's page, its DNS now saying 127.0.0.1).
    let (status, text) = page(&format!("evil.example:{port}"));
    assert_eq!(status, 421, "{text}");
    assert!(
        text.contains("does not answer for host \"evil.example:"),
        "{text}"
    );
    assert_eq!(page(&format!("127.0.0.2:{port}")).0, 421);
    assert_eq!(page(&format!("localhost:{}", port.wrapping_add(1))).0, 421);
    assert_eq!(page("localhost").0, 421, "port 80 is not this one");
    assert_eq!(http(addr, b"GET / HTTP/1.1\r\n\r\n").0, 400, "no Host");
    // The names it answers for.
    assert_eq!(page(&format!("127.0.0.1:{port}")).0, 200);
    assert_eq!(page(&format!("LOCALHOST:{port}")).0, 200);
    assert_eq!(page(&format!("kiosk.local:{port}")).0, 200);
    // An upgrade for another host is refused the same way.
    let (status, _) = http(
        addr,
        upgrade_request("1.1", &format!("evil.example:{port}"), "", KEY, "13").as_bytes(),
    );
    let refused = daemon.publisher_stats().websocket_refused();
    daemon.shutdown();
    assert_eq!(status, 421);
    assert_eq!(refused, 6);
}

#[test]
fn another_allowed_origin_is_read_only_unless_privileged_and_no_origin_is_as_configured() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    let mut out = websocket(addr, true, None);
    if let OutputConfig::WebSocket {
        origins,
        privileged_origins,
        ..
    } = &mut out
    {
        origins.push("http://allowed.example".to_string());
        privileged_origins.push("https://trusted.example:8443".to_string());
    }
    cfg.outputs = vec![out];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let mut allowed = connect_from(addr, "", "http://allowed.example").expect("an allowed origin");
    send(&mut allowed, r#"{"type":"command","id":9,"name":"pause"}"#);
    let got = read_ws(&mut allowed, 5.0, |g| {
        g.json().is_some_and(|v| v["type"] == "error")
    });
    let mut trusted =
        connect_from(addr, "", "https://trusted.example:8443").expect("a privileged origin");
    let trusted_hello = read_ws(&mut trusted, 5.0, |_| true);
    let mut engine = connect(addr, "", None).expect("no Origin: not a browser");
    let engine_hello = read_ws(&mut engine, 5.0, |_| true);
    daemon.shutdown();
    let got: Vec<&Value> = got.iter().filter_map(Got::json).collect();
    assert_eq!(got[0]["type"], "hello");
    assert_eq!(got[0]["privileged"], false, "another origin is read-only");
    let err = got.last().unwrap();
    assert_eq!((&err["type"], &err["id"]), (&"error".into(), &9.into()));
    assert!(
        err["message"]
            .as_str()
            .unwrap()
            .starts_with("read-only client"),
        "{err}"
    );
    assert_eq!(trusted_hello[0].json().unwrap()["privileged"], true);
    assert_eq!(engine_hello[0].json().unwrap()["privileged"], true);
}

#[test]
fn the_handshake_follows_rfc_6455() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.outputs = vec![websocket(addr, true, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let host = addr.to_string();
    let try_it = |version: &str, key: &str, ws_version: &str| {
        http(
            addr,
            upgrade_request(version, &host, "", key, ws_version).as_bytes(),
        )
    };
    let (http10, text10) = try_it("1.0", KEY, "13");
    let (not_b64, text_b64) = try_it("1.1", "not base64 at all", "13");
    let (short, _) = try_it("1.1", "AAAAAAAAAAAAAAAAAAAA", "13"); // 15 bytes
    let (long, _) = try_it("1.1", "AAAAAAAAAAAAAAAAAAAAAAAA", "13"); // 18 bytes
    let (v12, text12) = try_it("1.1", KEY, "12");
    drop(raw_upgrade(addr)); // the same request with version 13: 101
    daemon.shutdown();
    assert_eq!(http10, 400, "{text10}");
    assert!(text10.contains("HTTP/1.1"), "{text10}");
    assert_eq!(not_b64, 400, "{text_b64}");
    assert!(text_b64.contains("base64 of 16 bytes"), "{text_b64}");
    assert_eq!((short, long), (400, 400));
    assert_eq!(v12, 426, "{text12}");
    assert!(text12.contains("Sec-WebSocket-Version: 13\r\n"), "{text12}");
}

/// A client frame: FIN, `rsv` bits (0..=7), `opcode`, masked or not.
fn frame(fin: bool, rsv: u8, opcode: u8, payload: &[u8], masked: bool) -> Vec<u8> {
    let mut f = vec![(u8::from(fin) << 7) | (rsv << 4) | opcode];
    let m = if masked { 0x80 } else { 0 };
    match payload.len() {
        n if n < 126 => f.push(m | n as u8),
        n if n < 65536 => {
            f.push(m | 126);
            f.extend_from_slice(&(n as u16).to_be_bytes());
        }
        n => {
            f.push(m | 127);
            f.extend_from_slice(&(n as u64).to_be_bytes());
        }
    }
    if masked {
        let key = [0x12, 0x34, 0x56, 0x78];
        f.extend_from_slice(&key);
        f.extend(payload.iter().enumerate().map(|(i, b)| b ^ key[i % 4]));
    } else {
        f.extend_from_slice(payload);
    }
    f
}

/// Reads the server's frames until its close frame: its code and reason; `None`
/// when the connection ends (or 5 s pass) without one.
fn close_code(s: &mut TcpStream) -> Option<(u16, String)> {
    let end = Instant::now() + Duration::from_secs(5);
    while Instant::now() < end {
        let mut h = [0u8; 2];
        s.read_exact(&mut h).ok()?;
        let len = match h[1] & 0x7f {
            126 => {
                let mut l = [0u8; 2];
                s.read_exact(&mut l).ok()?;
                u16::from_be_bytes(l) as usize
            }
            127 => {
                let mut l = [0u8; 8];
                s.read_exact(&mut l).ok()?;
                u64::from_be_bytes(l) as usize
            }
            n => n as usize,
        };
        let mut payload = vec![0u8; len];
        s.read_exact(&mut payload).ok()?;
        if h[0] & 0x0f == 0x8 {
            let code = u16::from_be_bytes([payload[0], payload[1]]);
            return Some((code, String::from_utf8_lossy(&payload[2..]).into_owned()));
        }
    }
    None
}

#[test]
fn protocol_errors_close_with_1002_1007_and_1009() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 20;
    cfg.outputs = vec![websocket(addr, true, None)];
    let daemon = start(cfg, &dir.path().join("ct.sock"));
    let cases: Vec<(&str, Vec<u8>, u16)> = vec![
        ("unmasked frame", frame(true, 0, 0x1, b"{}", false), 1002),
        (
            "RSV1 without an extension",
            frame(true, 4, 0x1, b"{}", true),
            1002,
        ),
        ("unknown data opcode", frame(true, 0, 0x3, b"x", true), 1002),
        (
            "unknown control opcode",
            frame(true, 0, 0xb, b"x", true),
            1002,
        ),
        ("fragmented ping", frame(false, 0, 0x9, b"x", true), 1002),
        ("continuation first", frame(true, 0, 0x0, b"x", true), 1002),
        (
            "text not UTF-8",
            frame(true, 0, 0x1, &[0x22, 0xff, 0xfe, 0x22], true),
            1007,
        ),
        (
            "close reason not UTF-8",
            frame(true, 0, 0x8, &[0x03, 0xe8, 0xff, 0xfe], true),
            1007,
        ),
        (
            "too large",
            frame(true, 0, 0x1, &vec![b' '; 5000], true),
            1009,
        ),
    ];
    let mut got = Vec::new();
    for (what, bytes, _) in &cases {
        let mut s = raw_upgrade(addr);
        s.write_all(bytes).unwrap();
        got.push((what.to_string(), close_code(&mut s)));
    }
    let bad = daemon.publisher_stats().websocket_bad_frames();
    daemon.shutdown();
    for ((what, _, want), (_, got)) in cases.iter().zip(&got) {
        let (code, reason) = got
            .clone()
            .unwrap_or_else(|| panic!("{what}: no close frame"));
        assert_eq!(code, *want, "{what}: closed {code} {reason:?}");
    }
    assert!(bad >= 8, "bad frames counted: {bad}");
}

/// `demo --http ADDR --host NAME`: the viewer answers for the name given and the
/// listen address, and refuses any other host (421).
#[test]
fn demo_answers_for_the_hosts_it_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["demo", "--agents", "20", "--seconds", "30", "--socket"])
        .arg(dir.path().join("ct.sock"))
        .args(["--http", &addr.to_string(), "--host", "kiosk-7"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let up = Instant::now() + Duration::from_secs(20);
    while TcpStream::connect(addr).is_err() && Instant::now() < up {
        std::thread::sleep(Duration::from_millis(50));
    }
    let port = addr.port();
    let page = |host: &str| {
        http(
            addr,
            format!("GET / HTTP/1.1\r\nHost: {host}\r\n\r\n").as_bytes(),
        )
        .0
    };
    let (named, listen, other) = (
        page(&format!("kiosk-7:{port}")),
        page(&format!("127.0.0.1:{port}")),
        page(&format!("evil.example:{port}")),
    );
    let _ = child.kill();
    let _ = child.wait();
    assert_eq!((named, listen, other), (200, 200, 421));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["demo", "--http", "127.0.0.1:0", "--host", "http://kiosk-7/"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--host http://kiosk-7/: a host is name or name:port"),
        "{err}"
    );
}
