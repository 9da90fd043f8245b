//! The publisher end to end: a real Unix socket, `Server::run` on a thread, a fake
//! control side that sends `Outgoing` and answers `CommandRequest`s, and clients that
//! read the bytes a renderer would.

use crossbeam_channel::{bounded, Receiver, Sender};
use crowdtouch::config::SocketConfig;
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::pipeline::socket_options;
use crowdtouch::publish::protocol::{self, FRAME_KIND_JSON, FRAME_KIND_SNAPSHOT};
use crowdtouch::publish::Outgoing;
use crowdtouch::publish::{Error, HelloInfo, PublisherStats, Server, SocketOptions};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{
    AgentView, Command, CommandRequest, ControlKind, Event, MeshView, Snapshot, StatsReport,
    TouchView,
};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::os::unix::fs::PermissionsExt;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a test client waits for a message before the test fails.
const READ_TIMEOUT: Duration = Duration::from_secs(10);

/// The socket options the daemon derives from a config's `socket` section.
fn socket_config(client_queue: u32) -> SocketOptions {
    socket_options(&SocketConfig {
        path: None,
        mode: "0660".into(),
        group: None,
        client_queue,
        max_clients: 32,
        privileged: Default::default(),
    })
}

fn hello_info() -> HelloInfo {
    HelloInfo {
        world: Rect {
            min: [0.0, 0.0],
            max: [8.0, 5.0],
        },
        agents: 100,
        agent_radius_m: 0.15,
    }
}

/// A running publisher with a fake control thread.
struct Daemon {
    _dir: tempfile::TempDir,
    path: PathBuf,
    out: Option<Sender<Outgoing>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    control: Option<JoinHandle<()>>,
    _stuck: Option<Receiver<CommandRequest>>,
    stats: Arc<PublisherStats>,
}

enum ControlSide {
    /// Answers every command: `set_agent_count` with 0 is refused, others acknowledged.
    Answer,
    /// Never reads commands, with a command queue of one.
    Stuck(Receiver<CommandRequest>),
}

impl Daemon {
    fn start(cfg: SocketOptions) -> Daemon {
        Daemon::start_with(cfg, true)
    }

    fn start_with(cfg: SocketOptions, answer: bool) -> Daemon {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("crowdtouch.sock");
        let server = Server::bind(&cfg, &path, hello_info()).unwrap();
        let stats = server.stats();
        let (out_tx, out_rx) = bounded::<Outgoing>(1024);
        let (cmd_tx, cmd_rx) = bounded::<CommandRequest>(if answer { 16 } else { 1 });
        let stop = Arc::new(AtomicBool::new(false));
        let side = if answer {
            ControlSide::Answer
        } else {
            // Kept alive in the Daemon so the channel is full, not disconnected.
            ControlSide::Stuck(cmd_rx.clone())
        };
        let stuck = match &side {
            ControlSide::Stuck(rx) => Some(rx.clone()),
            ControlSide::Answer => None,
        };
        let control = match side {
            ControlSide::Answer => {
                let replies = out_tx.clone();
                Some(std::thread::spawn(move || {
                    for req in cmd_rx.iter() {
                        let result = match req.command {
                            Command::SetAgentCount { count: 0 } => {
                                Err("count must be in 1..=20000".to_string())
                            }
                            _ => Ok(()),
                        };
                        let reply = Outgoing::Reply {
                            client: req.client,
                            id: req.id,
                            result,
                        };
                        if replies.send(reply).is_err() {
                            return;
                        }
                    }
                }))
            }
            ControlSide::Stuck(_) => None,
        };
        let thread = {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || server.run(out_rx, cmd_tx, stop))
        };
        Daemon {
            _dir: dir,
            path,
            out: Some(out_tx),
            stop,
            thread: Some(thread),
            control,
            _stuck: stuck,
            stats,
        }
    }

    fn send(&self, msg: Outgoing) {
        self.out.as_ref().unwrap().send(msg).unwrap();
    }

    fn snapshot(&self, seq: u64, agents: usize) -> Arc<Snapshot> {
        let s = Arc::new(snapshot(seq, agents));
        self.send(Outgoing::Snapshot(Arc::clone(&s)));
        s
    }

    fn connect(&self) -> Client {
        Client::connect(&self.path)
    }

    /// Stops the publisher and waits for `run` to return.
    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
        self.out = None;
        if let Some(c) = self.control.take() {
            c.join().unwrap();
        }
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn snapshot(seq: u64, n: usize) -> Snapshot {
    let k = seq as f64 * 0.001;
    Snapshot {
        seq,
        t: Micros(seq * 8_333),
        input_t: Some(monotonic_now()),
        agents: (0..n)
            .map(|i| AgentView {
                pos: Vec2::new(i as f64 * 0.05 + k, 2.5 - i as f64 * 0.01),
                vel: Vec2::new(0.25, -0.125),
                goal: i as u32,
            })
            .collect(),
        goals: (0..n).map(|i| Vec2::new(i as f64 * 0.05, 1.0)).collect(),
        assignment_seq: seq.saturating_sub(3),
        touches: vec![TouchView {
            id: 1,
            pos: Vec2::new(1.5, 2.5),
            control: Some(4),
        }],
        paused: false,
        motions: Vec::new(),
    }
}

fn mesh(seq: u64, topology: u64) -> Arc<MeshView> {
    Arc::new(MeshView {
        seq,
        vertices: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ],
        triangles: Arc::new(vec![[0, 1, 2]]),
        outline: Arc::new(vec![0, 1, 2]),
        outlines: Arc::default(),
        topology,
    })
}

/// A test client: a raw socket read the way a renderer reads it.
struct Client {
    r: BufReader<UnixStream>,
    w: UnixStream,
}

impl Client {
    fn connect(path: &Path) -> Client {
        let s = UnixStream::connect(path).unwrap();
        s.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
        Client {
            w: s.try_clone().unwrap(),
            r: BufReader::new(s),
        }
    }

    /// Connects and consumes the server hello.
    fn ready(path: &Path) -> Client {
        let mut c = Client::connect(path);
        assert_eq!(c.json()["type"], "hello");
        c
    }

    fn raw_line(&mut self) -> Vec<u8> {
        let mut line = Vec::new();
        let n = self.r.read_until(b'\n', &mut line).unwrap();
        assert!(n > 0, "server closed the connection");
        assert_eq!(line.last(), Some(&b'\n'));
        line
    }

    fn json(&mut self) -> Value {
        let line = self.raw_line();
        serde_json::from_slice(&line)
            .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&line)))
    }

    /// Next JSON message whose type is not `snapshot`.
    fn next_not_snapshot(&mut self) -> Value {
        loop {
            let line = self.raw_line();
            if !line.starts_with(b"{\"type\":\"snapshot\"") {
                return serde_json::from_slice(&line).unwrap();
            }
        }
    }

    fn send(&mut self, line: &str) {
        self.w.write_all(line.as_bytes()).unwrap();
        self.w.write_all(b"\n").unwrap();
    }

    /// Sends a hello and returns the server's answer.
    fn hello(&mut self, v: Value) -> Value {
        self.send(&v.to_string());
        let reply = self.next_not_snapshot();
        assert_eq!(reply["type"], "hello", "{reply}");
        reply
    }

    /// One binary frame, length prefix included.
    fn frame(&mut self) -> Vec<u8> {
        let mut len = [0u8; 4];
        self.r.read_exact(&mut len).unwrap();
        let mut frame = len.to_vec();
        frame.resize(4 + u32::from_le_bytes(len) as usize, 0);
        self.r.read_exact(&mut frame[4..]).unwrap();
        frame
    }

    fn expect_eof(&mut self) {
        let mut rest = Vec::new();
        match self.r.read_to_end(&mut rest) {
            Ok(_) => assert!(
                rest.is_empty(),
                "more after the end: {}",
                String::from_utf8_lossy(&rest)
            ),
            Err(e) => assert_eq!(e.kind(), ErrorKind::ConnectionReset, "{e}"),
        }
    }
}

/// The unsigned integer after `"key":` near the start of a JSON line (cheap; the
/// snapshot's scalar fields precede its arrays).
fn field_u64(line: &[u8], key: &str) -> Option<u64> {
    let pat = format!("\"{key}\":");
    let head = &line[..line.len().min(256)];
    let at = head.windows(pat.len()).position(|w| w == pat.as_bytes())? + pat.len();
    let digits: Vec<u8> = head[at..]
        .iter()
        .copied()
        .take_while(u8::is_ascii_digit)
        .collect();
    std::str::from_utf8(&digits).ok()?.parse().ok()
}

fn is_snapshot(line: &[u8]) -> bool {
    line.starts_with(b"{\"type\":\"snapshot\"")
}

fn flat(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !cond() {
        assert!(t0.elapsed() < READ_TIMEOUT, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn raw_reader_gets_hello_then_snapshots_without_sending_anything() {
    let d = Daemon::start(socket_config(64));
    let mut c = d.connect();
    let hello = c.json();
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["protocol"], 1);
    assert_eq!(hello["formats"], json!(["json", "binary"]));
    assert_eq!(hello["format"], "json");
    assert_eq!(
        hello["world"],
        json!({"min": [0.0, 0.0], "max": [8.0, 5.0]})
    );
    assert_eq!(hello["agents"], 100);
    assert_eq!(hello["agent_radius_m"], 0.15);
    assert_eq!(
        hello["subscriptions"],
        json!(["snapshot", "mesh", "events", "stats"])
    );
    assert!(hello["max_rate_hz"].is_null());
    for seq in 1..=3 {
        let s = d.snapshot(seq, 20);
        let v = c.json();
        assert_eq!(v["type"], "snapshot");
        assert_eq!(v["seq"], seq);
        assert_eq!(v["dropped"], 0);
        assert_eq!(v["agents"], 20);
        assert!(v["latency_us"].as_u64().is_some());
        let pos = flat(&v["positions"]);
        for (i, a) in s.agents.iter().enumerate() {
            assert!((pos[2 * i] - a.pos.x).abs() <= 0.0005 + 1e-9);
            assert!((pos[2 * i + 1] - a.pos.y).abs() <= 0.0005 + 1e-9);
        }
        assert_eq!(
            v["touches"],
            json!([{"id": 1, "x": 1.5, "y": 2.5, "control": 4}])
        );
    }
    // The hello reports the current agent count once snapshots flow.
    let c2 = Client::connect(&d.path);
    let mut c2 = c2;
    assert_eq!(c2.json()["agents"], 20);
}

#[test]
fn events_stats_and_mesh_reach_a_default_client() {
    let d = Daemon::start(socket_config(64));
    d.send(Outgoing::Mesh(mesh(1, 1)));
    // Whether the publisher stores the mesh before or after accepting this client, the
    // client gets it next, with its triangles.
    let mut c = Client::ready(&d.path);
    let m = c.json();
    assert_eq!(m["type"], "mesh");
    assert_eq!(
        m["triangles"],
        json!([0, 1, 2]),
        "a new client gets the triangles"
    );
    d.send(Outgoing::Mesh(mesh(2, 1)));
    let m = c.json();
    assert_eq!(m["seq"], 2);
    assert!(
        m.get("triangles").is_none(),
        "same topology: no triangles: {m}"
    );
    assert_eq!(m["outline"], json!([0, 1, 2]));
    d.send(Outgoing::Mesh(mesh(3, 2)));
    let m = c.json();
    assert_eq!(
        m["triangles"],
        json!([0, 1, 2]),
        "new topology: triangles again"
    );
    d.send(Outgoing::Event(Arc::new(Event::ControlBegin {
        id: 3,
        kind: ControlKind::Area,
        fingers: vec![1, 2, 3],
        vertices: vec![4, 5, 6],
        t: Micros(10),
    })));
    d.send(Outgoing::Stats(Arc::new(StatsReport {
        t: Micros(99),
        clients: 1,
        ..Default::default()
    })));
    let e = c.json();
    assert_eq!(
        e,
        json!({"type":"control","phase":"begin","id":3,"kind":"area","fingers":[1,2,3],"vertices":[4,5,6],"t_us":10})
    );
    let s = c.json();
    assert_eq!(s["type"], "stats");
    assert_eq!(s["t_us"], 99);
}

#[test]
fn hello_switches_to_binary_and_frames_decode_back_to_the_snapshot() {
    let mut d = Daemon::start(socket_config(64));
    let mut c = Client::ready(&d.path);
    // The answer to a hello is the last message in the old format (a JSON line here).
    let reply = c.hello(json!({"type":"hello","protocol":1,"format":"binary"}));
    assert_eq!(reply["format"], "binary");
    let s = d.snapshot(7, 50);
    let frame = c.frame();
    assert_eq!(frame[4], FRAME_KIND_SNAPSHOT);
    let b = protocol::decode_snapshot_binary(&frame).unwrap();
    assert_eq!((b.seq, b.t_us, b.dropped, b.agents), (7, s.t.0, 0, 50));
    assert!(b.latency_us.is_some());
    assert_eq!(b.assignment_seq, 4);
    let pos = b.positions.unwrap();
    let vel = b.velocities.unwrap();
    for (i, a) in s.agents.iter().enumerate() {
        assert!((f64::from(pos[i][0]) - a.pos.x).abs() < 1e-5);
        assert!((f64::from(pos[i][1]) - a.pos.y).abs() < 1e-5);
        assert!((f64::from(vel[i][0]) - a.vel.x).abs() < 1e-6);
    }
    assert_eq!(b.goals.unwrap().len(), 50);
    assert_eq!(b.assignment.unwrap(), (0..50).collect::<Vec<u32>>());
    let t = b.touches.unwrap();
    assert_eq!((t[0].id, t[0].control), (1, Some(4)));
    // Other messages are JSON inside frames.
    d.send(Outgoing::Event(Arc::new(Event::Reset {
        agents: 50,
        hard: false,
        t: Micros(5),
    })));
    let frame = c.frame();
    assert_eq!(frame[4], FRAME_KIND_JSON);
    let v: Value = serde_json::from_slice(&frame[5..]).unwrap();
    assert_eq!(v["type"], "reset");
    // Fields narrow the binary layout too.
    c.send(r#"{"type":"hello","protocol":1,"format":"binary","fields":["positions"]}"#);
    let frame = c.frame();
    assert_eq!(frame[4], FRAME_KIND_JSON);
    let v: Value = serde_json::from_slice(&frame[5..]).unwrap();
    assert_eq!(
        (v["type"].as_str(), v["fields"].clone()),
        (Some("hello"), json!(["positions"]))
    );
    d.snapshot(8, 50);
    let frame = c.frame();
    assert_eq!(frame.len(), protocol::BINARY_HEADER_BYTES + 50 * 8);
    let b = protocol::decode_snapshot_binary(&frame).unwrap();
    assert!(b.velocities.is_none() && b.positions.is_some());
    d.shutdown();
    let frame = c.frame();
    assert_eq!(frame[4], FRAME_KIND_JSON);
    let v: Value = serde_json::from_slice(&frame[5..]).unwrap();
    assert_eq!(v["type"], "bye");
    c.expect_eof();
}

#[test]
fn subscriptions_and_fields_filter() {
    let d = Daemon::start(socket_config(64));
    let mut c = Client::ready(&d.path);
    let reply = c.hello(json!({"type":"hello","protocol":1,"subscribe":["events","stats"]}));
    assert_eq!(reply["subscriptions"], json!(["events", "stats"]));
    d.snapshot(1, 10);
    d.send(Outgoing::Mesh(mesh(1, 1)));
    d.send(Outgoing::Event(Arc::new(Event::GestureBegin {
        id: 5,
        t: Micros(3),
    })));
    d.send(Outgoing::Stats(Arc::new(StatsReport::default())));
    assert_eq!(
        c.json(),
        json!({"type":"gesture","phase":"begin","id":5,"t_us":3})
    );
    assert_eq!(c.json()["type"], "stats");

    let reply = c.hello(json!({"type":"hello","protocol":1,"subscribe":["snapshot"],"fields":["positions","touches"]}));
    assert_eq!(reply["fields"], json!(["positions", "touches"]));
    d.send(Outgoing::Event(Arc::new(Event::GestureBegin {
        id: 6,
        t: Micros(4),
    })));
    d.snapshot(2, 10);
    let v = c.json();
    assert_eq!(
        v["type"], "snapshot",
        "events are no longer subscribed: {v}"
    );
    assert_eq!(v["seq"], 2);
    assert_eq!(flat(&v["positions"]).len(), 20);
    assert!(v.get("touches").is_some());
    for absent in ["velocities", "goals", "assignment", "assignment_seq"] {
        assert!(v.get(absent).is_none(), "{absent} sent: {v}");
    }

    // Subscribing to the mesh again sends the newest mesh with its triangles.
    let reply = c.hello(json!({"type":"hello","protocol":1,"subscribe":["mesh"]}));
    assert_eq!(reply["subscriptions"], json!(["mesh"]));
    let m = c.json();
    assert_eq!(
        (m["type"].as_str(), m["triangles"].clone()),
        (Some("mesh"), json!([0, 1, 2]))
    );
}

#[test]
fn max_rate_hz_limits_snapshots() {
    let d = Daemon::start(socket_config(1024));
    let mut limited = Client::ready(&d.path);
    limited.hello(
        json!({"type":"hello","protocol":1,"subscribe":["snapshot","events"],"max_rate_hz":25}),
    );
    let mut full = Client::ready(&d.path);
    const N: u64 = 150;
    let t0 = Instant::now();
    for seq in 1..=N {
        d.snapshot(seq, 5);
        std::thread::sleep(Duration::from_millis(2));
    }
    let elapsed = t0.elapsed().as_secs_f64();
    d.send(Outgoing::Event(Arc::new(Event::Paused {
        paused: true,
        t: Micros(1),
    })));
    let mut got = Vec::new();
    loop {
        let v = limited.json();
        if v["type"] != "snapshot" {
            break;
        }
        assert_eq!(v["dropped"], 0, "rate skips are not drops");
        got.push(v["seq"].as_u64().unwrap());
    }
    let expect = elapsed * 25.0;
    assert!(
        (got.len() as f64) <= expect + 2.0 && (got.len() as f64) >= expect * 0.5,
        "{} snapshots in {elapsed:.3} s at 25 Hz: {got:?}",
        got.len()
    );
    assert!(got.windows(2).all(|w| w[0] < w[1]));
    let mut n_full = 0;
    while n_full < N {
        let v = full.json();
        if v["type"] == "snapshot" {
            n_full += 1;
            assert_eq!(v["seq"], n_full);
        }
    }
    assert!(d.stats.snapshots_rate_skipped() >= N - got.len() as u64);
    assert_eq!(d.stats.snapshots_dropped(), 0);
}

#[test]
fn many_clients_all_get_every_snapshot_in_order() {
    let d = Daemon::start(socket_config(256));
    const N: u64 = 120;
    let clients: Vec<Client> = (0..8).map(|_| Client::ready(&d.path)).collect();
    let readers: Vec<JoinHandle<Vec<u64>>> = clients
        .into_iter()
        .map(|mut c| {
            std::thread::spawn(move || {
                let mut seqs = Vec::new();
                while seqs.last() != Some(&N) {
                    let line = c.raw_line();
                    if is_snapshot(&line) {
                        assert_eq!(field_u64(&line, "dropped"), Some(0));
                        seqs.push(field_u64(&line, "seq").unwrap());
                    }
                }
                seqs
            })
        })
        .collect();
    assert_eq!(d.stats.clients(), 8);
    for seq in 1..=N {
        d.snapshot(seq, 40);
        std::thread::sleep(Duration::from_micros(500));
    }
    for r in readers {
        assert_eq!(r.join().unwrap(), (1..=N).collect::<Vec<_>>());
    }
    // Writers count a snapshot after its write returns, which can be after the
    // reader has it.
    let t0 = std::time::Instant::now();
    while d.stats.snapshots_sent() < 8 * N && t0.elapsed() < Duration::from_secs(2) {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(d.stats.snapshots_sent() >= 8 * N);
    assert_eq!(d.stats.snapshots_dropped(), 0);
}

#[test]
fn a_client_that_never_reads_loses_its_oldest_snapshots_and_is_told() {
    // The good client has QUEUE ticks of slack before it would lose anything.
    const QUEUE: u32 = 32;
    const N: u64 = 300;
    let d = Daemon::start(socket_config(QUEUE));
    let mut slow = Client::ready(&d.path);
    let mut good = Client::ready(&d.path);
    let good_reader = std::thread::spawn(move || {
        let mut seqs = Vec::new();
        while seqs.last() != Some(&N) {
            let line = good.raw_line();
            if is_snapshot(&line) {
                assert_eq!(field_u64(&line, "dropped"), Some(0));
                seqs.push(field_u64(&line, "seq").unwrap());
            }
        }
        seqs
    });
    // ~15 kB per snapshot: the slow client's socket buffer fills after a few dozen.
    for seq in 1..=N {
        d.snapshot(seq, 300);
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(good_reader.join().unwrap(), (1..=N).collect::<Vec<_>>());

    // Now the slow client reads everything that is left for it.
    let mut seqs = Vec::new();
    let mut last_dropped = 0;
    let mut notices = Vec::new();
    while seqs.last() != Some(&N) {
        let line = slow.raw_line();
        if is_snapshot(&line) {
            seqs.push(field_u64(&line, "seq").unwrap());
            let dropped = field_u64(&line, "dropped").unwrap();
            assert!(dropped >= last_dropped);
            last_dropped = dropped;
        } else {
            let v: Value = serde_json::from_slice(&line).unwrap();
            assert_eq!(v["type"], "dropped", "{v}");
            notices.push((v["count"].as_u64().unwrap(), v["total"].as_u64().unwrap()));
        }
    }
    assert!(
        seqs.windows(2).all(|w| w[0] < w[1]),
        "out of order: {seqs:?}"
    );
    assert!(
        last_dropped > 0,
        "nothing dropped: is the socket buffer that large?"
    );
    assert_eq!(
        seqs.len() as u64 + last_dropped,
        N,
        "every snapshot is sent or counted"
    );
    assert!(!notices.is_empty());
    assert_eq!(notices.iter().map(|n| n.0).sum::<u64>(), last_dropped);
    assert_eq!(notices.last().unwrap().1, last_dropped);
    // The oldest went: the newest QUEUE snapshots all arrived.
    let tail: Vec<u64> = (N - u64::from(QUEUE) + 1..=N).collect();
    assert_eq!(seqs[seqs.len() - tail.len()..], tail[..]);
    assert_eq!(d.stats.snapshots_dropped(), last_dropped);
}

#[test]
fn a_client_whose_event_backlog_passes_the_cap_is_disconnected() {
    let d = Daemon::start(socket_config(8));
    let mut stuck = Client::ready(&d.path);
    stuck.hello(json!({"type":"hello","protocol":1,"subscribe":["events"]}));
    let mut good = Client::ready(&d.path);
    good.hello(json!({"type":"hello","protocol":1,"subscribe":["events"]}));
    // More than the socket buffer plus MAX_BACKLOG_MESSAGES.
    let n = 3 * crowdtouch::publish::socket::MAX_BACKLOG_MESSAGES as u32;
    let progress = Arc::new(std::sync::atomic::AtomicU32::new(0));
    let good_reader = {
        let progress = Arc::clone(&progress);
        std::thread::spawn(move || {
            for id in 0..n {
                let v = good.json();
                assert_eq!(v["id"], id, "{v}");
                progress.store(id + 1, Ordering::Relaxed);
            }
            // Handed back open: a closed client is dropped too.
            good
        })
    };
    for id in 0..n {
        // Keep the reading client well inside its cap.
        while id - progress.load(Ordering::Relaxed) > 1024 {
            std::thread::sleep(Duration::from_micros(200));
        }
        d.send(Outgoing::Event(Arc::new(Event::GestureBegin {
            id,
            t: Micros(1),
        })));
    }
    let _good = good_reader.join().unwrap();
    // Events are never dropped: the stuck client gets an in-order prefix, then the error.
    let mut next = 0;
    let e = loop {
        let v = stuck.json();
        if v["type"] != "gesture" {
            break v;
        }
        assert_eq!(v["id"], next);
        next += 1;
    };
    assert!(next < n);
    assert_eq!(
        (e["type"].as_str(), e["fatal"].as_bool()),
        (Some("error"), Some(true)),
        "{e}"
    );
    assert!(
        e["message"].as_str().unwrap().contains("not reading"),
        "{e}"
    );
    stuck.expect_eof();
    wait_until("the stuck client to be reaped", || d.stats.clients() == 1);
}

#[test]
fn garbage_gets_a_fatal_error_and_a_disconnect_while_others_continue() {
    let d = Daemon::start(socket_config(64));
    let mut bad = Client::ready(&d.path);
    let mut good = Client::ready(&d.path);
    bad.send("this is not json");
    let e = bad.next_not_snapshot();
    assert_eq!(e["type"], "error");
    assert_eq!(e["fatal"], true);
    assert!(e["id"].is_null());
    let msg = e["message"].as_str().unwrap();
    assert_eq!(msg, "line is not JSON at column 2: expected ident");
    bad.expect_eof();

    let mut long = Client::ready(&d.path);
    long.w
        .write_all(&vec![b'x'; protocol::MAX_LINE_BYTES + 10])
        .unwrap();
    let e = long.next_not_snapshot();
    assert!(e["message"].as_str().unwrap().contains("byte limit"), "{e}");
    long.expect_eof();

    let mut odd = Client::ready(&d.path);
    odd.send(r#"{"type":"subscribe"}"#);
    let e = odd.next_not_snapshot();
    assert!(
        e["message"]
            .as_str()
            .unwrap()
            .contains("unknown message type"),
        "{e}"
    );
    odd.expect_eof();

    let mut old = Client::ready(&d.path);
    old.send(r#"{"type":"hello","protocol":2}"#);
    let e = old.next_not_snapshot();
    assert_eq!(e["fatal"], true);
    assert!(
        e["message"]
            .as_str()
            .unwrap()
            .contains("protocol version 2"),
        "{e}"
    );
    old.expect_eof();

    // Nesting as deep as a line can hold: refused by the parser's depth limit on the
    // socket's I/O thread (a small stack of its own), not a stack overflow.
    let mut deep = Client::ready(&d.path);
    deep.send(&"[".repeat(protocol::MAX_LINE_BYTES - 1));
    let e = deep.next_not_snapshot();
    assert_eq!(e["fatal"], true, "{e}");
    assert!(e["message"].as_str().unwrap().contains("recursion"), "{e}");
    deep.expect_eof();

    for seq in 1..=5 {
        d.snapshot(seq, 10);
    }
    for seq in 1..=5 {
        assert_eq!(good.json()["seq"], seq);
    }
    wait_until("the bad clients to be reaped", || d.stats.clients() == 1);
    assert!(d.stats.protocol_errors() >= 4);
}

#[test]
fn commands_get_ack_or_error_with_their_id() {
    let d = Daemon::start(socket_config(64));
    let mut c = Client::ready(&d.path);
    c.send(r#"{"type":"command","id":7,"name":"pause"}"#);
    assert_eq!(c.next_not_snapshot(), json!({"type":"ack","id":7}));
    c.send(r#"{"type":"command","id":"abc","name":"set_agent_count","count":0}"#);
    assert_eq!(
        c.next_not_snapshot(),
        json!({"type":"error","id":"abc","message":"count must be in 1..=20000","fatal":false})
    );
    c.send(r#"{"type":"command","id":9,"name":"explode"}"#);
    let e = c.next_not_snapshot();
    assert_eq!(
        (e["id"].clone(), e["fatal"].clone()),
        (json!(9), json!(false))
    );
    assert!(
        e["message"]
            .as_str()
            .unwrap()
            .contains("unknown command `explode`"),
        "{e}"
    );
    c.send(r#"{"type":"command","name":"pause"}"#);
    let e = c.next_not_snapshot();
    assert!(e["id"].is_null());
    assert_eq!(e["message"], "missing `id` in command");
    c.send(r#"{"type":"command","id":10,"name":"reset","hard":"yes"}"#);
    let e = c.next_not_snapshot();
    assert_eq!(
        (e["id"].clone(), e["fatal"].clone()),
        (json!(10), json!(false))
    );
    // Still connected after non-fatal errors.
    c.send(r#"{"type":"command","id":11,"name":"reset","hard":true}"#);
    assert_eq!(c.next_not_snapshot(), json!({"type":"ack","id":11}));
}

#[test]
fn a_full_command_queue_answers_busy_after_the_replies_before_it() {
    let d = Daemon::start_with(socket_config(64), false);
    let mut c = Client::ready(&d.path);
    c.send(r#"{"type":"command","id":1,"name":"pause"}"#); // fills the queue of one
    c.send(r#"{"type":"command","id":2,"name":"resume"}"#);
    wait_until("the busy refusal", || d.stats.commands_busy() == 1);
    // Replies come in the order of the requests: the refusal of 2 waits for the
    // answer to 1, which the control thread gives now.
    let req = d
        ._stuck
        .as_ref()
        .unwrap()
        .recv_timeout(READ_TIMEOUT)
        .unwrap();
    assert_eq!(req.id, json!(1));
    d.send(Outgoing::Reply {
        client: req.client,
        id: req.id,
        result: Ok(()),
    });
    assert_eq!(c.next_not_snapshot(), json!({"type":"ack","id":1}));
    let e = c.next_not_snapshot();
    assert_eq!(
        (e["type"].as_str(), e["id"].clone()),
        (Some("error"), json!(2))
    );
    assert_eq!(e["fatal"], false);
    assert!(e["message"].as_str().unwrap().starts_with("busy"), "{e}");
    assert_eq!(d.stats.commands_busy(), 1);
}

#[test]
fn a_dead_client_is_dropped_and_nobody_else_notices() {
    let d = Daemon::start(socket_config(4));
    let mut good = Client::ready(&d.path);
    let dead = Client::ready(&d.path);
    assert_eq!(d.stats.clients(), 2);
    drop(dead);
    let mut seq = 0;
    wait_until("the dead client to be dropped", || {
        seq += 1;
        d.snapshot(seq, 10);
        assert_eq!(good.json()["seq"], seq);
        d.stats.clients() == 1
    });
    for _ in 0..5 {
        seq += 1;
        d.snapshot(seq, 10);
        assert_eq!(good.json()["seq"], seq);
    }
}

#[test]
fn a_command_client_that_subscribes_to_nothing_is_dropped_when_it_closes() {
    // A client sent nothing (no subscription, its replies all read) gives its writer
    // no write to find it gone: the reader must see the hang-up. Without that, every
    // such client kept a slot until `socket.max_clients` refused everyone.
    let d = Daemon::start(socket_config(4));
    for round in 0..3u64 {
        let mut c = Client::ready(&d.path);
        c.hello(json!({"type":"hello","protocol":1,"subscribe":[]}));
        c.send(&format!(
            r#"{{"type":"command","id":{round},"name":"pause"}}"#
        ));
        assert_eq!(c.next_not_snapshot(), json!({"type":"ack","id":round}));
        assert_eq!(d.stats.clients(), 1);
        drop(c);
        wait_until("the closed client to be dropped", || d.stats.clients() == 0);
    }
}

#[test]
fn a_half_closed_client_keeps_getting_snapshots() {
    let d = Daemon::start(socket_config(64));
    let mut c = Client::ready(&d.path);
    c.w.shutdown(std::net::Shutdown::Write).unwrap();
    // Give the reader time to see the end of the client's stream.
    std::thread::sleep(Duration::from_millis(50));
    for seq in 1..=5 {
        d.snapshot(seq, 10);
        assert_eq!(c.json()["seq"], seq);
    }
    assert_eq!(d.stats.clients(), 1);
}

#[test]
fn shutdown_says_bye_and_removes_the_socket() {
    let mut d = Daemon::start(socket_config(64));
    let mut c = Client::ready(&d.path);
    d.snapshot(1, 5);
    d.shutdown();
    assert_eq!(c.json()["seq"], 1);
    assert_eq!(c.json(), json!({"type":"bye","reason":"shutdown"}));
    c.expect_eof();
    assert!(!d.path.exists(), "socket file left behind");
}

#[test]
fn closing_the_control_channel_ends_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sock");
    let server = Server::bind(&socket_config(8), &path, hello_info()).unwrap();
    let (tx, rx) = bounded(4);
    let (ctx, _crx) = bounded(4);
    let t = std::thread::spawn(move || server.run(rx, ctx, Arc::new(AtomicBool::new(false))));
    drop(tx);
    t.join().unwrap();
    assert!(!path.exists());
}

#[test]
fn latency_histograms_fill_and_reset() {
    let d = Daemon::start(socket_config(64));
    let mut c = Client::ready(&d.path);
    for seq in 1..=10 {
        d.snapshot(seq, 100);
        assert_eq!(c.json()["seq"], seq);
    }
    // The writer records after its write returns; the client may read first.
    wait_until("end-to-end samples", || d.stats.snapshots_sent() >= 10);
    let e2e = d.stats.take_end_to_end();
    assert_eq!(e2e.len(), 10);
    assert!(e2e.max() < 5_000_000);
    assert_eq!(d.stats.take_end_to_end().len(), 0, "take resets");
    assert_eq!(d.stats.take_encode().len(), 10);
    assert!(d.stats.bytes_written() > 0);
}

#[test]
fn too_many_clients_are_refused_with_an_error() {
    let mut cfg = socket_config(8);
    cfg.max_clients = 1;
    let d = Daemon::start(cfg);
    let _first = Client::ready(&d.path);
    let mut second = d.connect();
    let e = second.json();
    assert_eq!(
        (e["type"].as_str(), e["fatal"].as_bool()),
        (Some("error"), Some(true))
    );
    assert!(
        e["message"].as_str().unwrap().contains("too many clients"),
        "{e}"
    );
    second.expect_eof();
    assert_eq!(d.stats.clients_refused(), 1);
}

#[test]
fn stale_socket_file_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sock");
    drop(UnixListener::bind(&path).unwrap()); // leaves the file, nobody listening
    assert!(path.exists());
    let server = Server::bind(&socket_config(8), &path, hello_info()).unwrap();
    assert_eq!(server.path(), path);
    UnixStream::connect(&path).unwrap();
    drop(server);
    assert!(!path.exists());
}

#[test]
fn live_socket_is_refused_with_in_use() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sock");
    let first = Server::bind(&socket_config(8), &path, hello_info()).unwrap();
    match Server::bind(&socket_config(8), &path, hello_info()) {
        Err(Error::InUse { path: p }) => assert_eq!(p, path),
        other => panic!("expected InUse, got {other:?}"),
    }
    // The refused attempt must not have removed the live socket.
    UnixStream::connect(&path).unwrap();
    drop(first);
}

#[test]
fn something_that_is_not_a_socket_is_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sock");
    std::fs::write(&path, "precious").unwrap();
    match Server::bind(&socket_config(8), &path, hello_info()) {
        Err(e @ Error::NotASocket { .. }) => assert!(e.to_string().contains("not a socket")),
        other => panic!("expected NotASocket, got {other:?}"),
    }
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "precious");
}

#[test]
fn socket_mode_is_applied() {
    for (mode, bits) in [("0600", 0o600), ("0660", 0o660), ("0666", 0o666)] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.sock");
        let cfg = socket_options(&SocketConfig {
            path: None,
            mode: mode.into(),
            group: None,
            client_queue: 8,
            max_clients: 32,
            privileged: Default::default(),
        });
        let _server = Server::bind(&cfg, &path, hello_info()).unwrap();
        let got = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(got, bits, "mode {mode}");
    }
}

#[test]
fn socket_group_is_applied_or_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sock");
    let mut cfg = socket_config(8);
    cfg.group = Some("no-such-group-crowdtouch".into());
    match Server::bind(&cfg, &path, hello_info()) {
        Err(Error::UnknownGroup { group }) => assert_eq!(group, "no-such-group-crowdtouch"),
        other => panic!("expected UnknownGroup, got {other:?}"),
    }
    assert!(!path.exists(), "a failed bind leaves no socket behind");
    // Our own primary group is always allowed.
    let gid = nix::unistd::getegid();
    if let Ok(Some(g)) = nix::unistd::Group::from_gid(gid) {
        cfg.group = Some(g.name);
        let _server = Server::bind(&cfg, &path, hello_info()).unwrap();
        use std::os::unix::fs::MetadataExt;
        assert_eq!(std::fs::metadata(&path).unwrap().gid(), gid.as_raw());
    }
}

/// A snapshot in a scene: one motion per agent, cycling through every type; no
/// input time, so its encoding does not depend on when it is written.
fn scene_snapshot(seq: u64, n: usize) -> Snapshot {
    use crowdtouch::vocab::MotionType;
    let mut s = snapshot(seq, n);
    s.input_t = None;
    s.motions = (0..n)
        .map(|i| MotionType::ALL[i % MotionType::ALL.len()])
        .collect();
    s
}

#[test]
fn binary_motions_reach_only_the_clients_that_name_them() {
    use crowdtouch::publish::protocol::{FieldSet, FLAG_MOTIONS};
    let mut d = Daemon::start(socket_config(64));
    // A binary client written before the motions array: no `fields`.
    let mut old = Client::ready(&d.path);
    let reply = old.hello(json!({"type":"hello","protocol":1,"format":"binary"}));
    assert_eq!(
        reply["fields"],
        json!(["positions", "velocities", "goals", "assignment", "touches"])
    );
    // A binary client that asks for motions.
    let mut new = Client::ready(&d.path);
    let reply = new.hello(
        json!({"type":"hello","protocol":1,"format":"binary","fields":["positions","motions"]}),
    );
    assert_eq!(reply["fields"], json!(["positions", "motions"]));
    // A JSON client with the defaults.
    let mut js = Client::ready(&d.path);
    let n = 9;
    let s = Arc::new(scene_snapshot(11, n));
    d.send(Outgoing::Snapshot(Arc::clone(&s)));

    // The old client's frame is byte for byte the frame of the same tick without a
    // scene: the layout it was written for.
    let frame = old.frame();
    let mut no_scene = (*s).clone();
    no_scene.motions.clear();
    let mut expected = Vec::new();
    protocol::encode_snapshot_binary(&no_scene, None, 0, &FieldSet::BINARY_DEFAULT, &mut expected);
    assert_eq!(frame, expected);
    assert_eq!(
        frame.len(),
        protocol::BINARY_HEADER_BYTES + 8 * n * 3 + 4 * n + protocol::BINARY_TOUCH_BYTES
    );
    let b = protocol::decode_snapshot_binary(&frame).unwrap();
    assert!(b.motions.is_none());

    // The new one gets a byte per agent after the positions, padded to 4.
    let frame = new.frame();
    assert_eq!(frame[4], FRAME_KIND_SNAPSHOT);
    let flags = u16::from_le_bytes([frame[6], frame[7]]);
    assert_ne!(flags & FLAG_MOTIONS, 0);
    assert_eq!(frame.len(), protocol::BINARY_HEADER_BYTES + 8 * n + 12);
    let b = protocol::decode_snapshot_binary(&frame).unwrap();
    let names: Vec<&str> = b
        .motions
        .as_ref()
        .unwrap()
        .iter()
        .map(|&c| protocol::motion_from_code(c).unwrap().as_str())
        .collect();
    assert_eq!(
        names,
        [
            "run",
            "crawl",
            "duck",
            "swim",
            "jump",
            "climb_up",
            "climb_down",
            "run",
            "crawl"
        ]
    );
    assert_eq!(
        &frame[protocol::BINARY_HEADER_BYTES + 8 * n..],
        &[0, 1, 2, 3, 4, 5, 6, 0, 1, 0, 0, 0]
    );
    assert_eq!(b.positions.unwrap().len(), n);

    // The JSON client gets the same motions by name.
    let v = js.json();
    assert_eq!(v["type"], "snapshot");
    let json_names: Vec<&str> = v["motions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m.as_str().unwrap())
        .collect();
    assert_eq!(json_names, names);

    // Without a scene, even the client that asked gets no motions bytes.
    d.send(Outgoing::Snapshot(Arc::new(no_scene)));
    let frame = new.frame();
    assert_eq!(frame.len(), protocol::BINARY_HEADER_BYTES + 8 * n);
    assert!(protocol::decode_snapshot_binary(&frame)
        .unwrap()
        .motions
        .is_none());
    d.shutdown();
}

/// Runs `examples/client.py`'s binary decoder on each frame (length prefix
/// included); `None` when python3 cannot run.
fn python_decode(frames: &[Vec<u8>]) -> Option<Vec<Value>> {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let hex: Vec<String> = frames
        .iter()
        .map(|f| f[4..].iter().map(|b| format!("{b:02x}")).collect())
        .collect();
    let out = match std::process::Command::new("python3")
        .arg("-c")
        .arg(
            "import json, sys\n\
             sys.path.insert(0, sys.argv[1])\n\
             import client\n\
             for h in sys.argv[2:]:\n    print(json.dumps(client.decode_binary_snapshot(bytes.fromhex(h))))\n",
        )
        .arg(&examples)
        .args(&hex)
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            eprintln!("SKIPPED: python3 not runnable ({e})");
            return None;
        }
    };
    assert!(
        out.status.success(),
        "client.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(
        String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect(),
    )
}

/// The Python reference client reads the frames a real socket carries, with and
/// without the motions array, as the crate's own decoder does.
#[test]
fn the_python_reference_client_decodes_binary_motions() {
    let mut d = Daemon::start(socket_config(64));
    let mut every = Client::ready(&d.path);
    every.hello(json!({"type":"hello","protocol":1,"format":"binary","fields":["positions","velocities","goals","assignment","touches","motions"]}));
    let mut old = Client::ready(&d.path);
    old.hello(json!({"type":"hello","protocol":1,"format":"binary"}));
    let n = 6;
    d.send(Outgoing::Snapshot(Arc::new(scene_snapshot(3, n))));
    let frames = vec![every.frame(), old.frame()];
    d.shutdown();
    let Some(decoded) = python_decode(&frames) else {
        return;
    };
    for (frame, py) in frames.iter().zip(&decoded) {
        let b = protocol::decode_snapshot_binary(frame).unwrap();
        assert_eq!(py["seq"], 3);
        assert_eq!(py["agents"], n);
        let pos: Vec<f32> = flat(&py["positions"]).iter().map(|&x| x as f32).collect();
        let ours: Vec<f32> = b.positions.unwrap().iter().flatten().copied().collect();
        assert_eq!(pos, ours);
        assert_eq!(py["touches"][0]["control"], 4);
        match b.motions {
            Some(codes) => {
                let names: Vec<Value> = codes
                    .iter()
                    .map(|&c| json!(protocol::motion_from_code(c).unwrap().as_str()))
                    .collect();
                assert_eq!(py["motions"], Value::Array(names));
            }
            None => assert!(py.get("motions").is_none(), "{py}"),
        }
    }
    assert_eq!(
        decoded[0]["motions"],
        json!(["run", "crawl", "duck", "swim", "jump", "climb_up"])
    );
}

/// Gesture commands on the wire: a `gesture` end event carries its recognition to
/// every events client; `gesture_motion`, `plan` and `demo_motion` reach only the
/// clients that subscribed to `plan`, in JSON lines or as JSON frames.
#[test]
fn plans_reach_only_the_clients_that_subscribe_to_them() {
    use crowdtouch::vocab::{MotionPhase, NeighbourView, PlanOrigin, PlanView, Recognition};
    let d = Daemon::start(socket_config(64));
    // A client written before plans existed: the default hello.
    let mut old = Client::ready(&d.path);
    let reply = old.hello(json!({"type":"hello","protocol":1}));
    assert_eq!(
        reply["subscriptions"],
        json!(["snapshot", "mesh", "events", "stats"])
    );
    let mut js = Client::ready(&d.path);
    let reply = js.hello(json!({"type":"hello","protocol":1,"subscribe":["plan","stats"]}));
    assert_eq!(reply["subscriptions"], json!(["stats", "plan"]));
    let mut bin = Client::ready(&d.path);
    bin.hello(json!({"type":"hello","protocol":1,"format":"binary","subscribe":["plan"]}));

    d.send(Outgoing::Event(Arc::new(Event::GestureEnd {
        id: 4,
        fingers: 2,
        contacts: 2,
        duration_us: 900_000,
        cancelled: false,
        recognition: Some(Recognition {
            class: "expand".into(),
            weight: 1.0,
            neighbours: vec![NeighbourView {
                class: "expand".into(),
                distance: 0.0,
                weight: 1.0,
                origin: "generated".into(),
            }],
            synth_us: 3100,
            agents: 3,
        }),
        rejected: None,
        t: Micros(20),
    })));
    d.send(Outgoing::Event(Arc::new(Event::GestureMotion {
        id: 4,
        class: "expand".into(),
        phase: MotionPhase::Approach,
        t: Micros(21),
    })));
    let plan = PlanView {
        origin: PlanOrigin::Gesture { id: 4 },
        class: "expand".into(),
        duration_s: 2.5,
        samples: 2,
        points: vec![
            Vec2::new(1.0, 1.0),
            Vec2::new(0.5, 0.5),
            Vec2::new(2.0, 1.0),
            Vec2::new(2.5, 0.5),
            Vec2::new(1.5, 2.0),
            Vec2::new(1.5, 2.75),
        ],
    };
    d.send(Outgoing::Plan(Arc::new(plan.clone())));
    let demo = PlanView {
        origin: PlanOrigin::Demo { motion: 7 },
        ..plan
    };
    d.send(Outgoing::Plan(Arc::new(demo)));
    d.send(Outgoing::Stats(Arc::new(StatsReport::default())));

    // The old client: the end event with its recognition, then stats; nothing new.
    let end = old.json();
    assert_eq!(
        (end["type"].as_str(), end["phase"].as_str()),
        (Some("gesture"), Some("end"))
    );
    assert_eq!(end["recognition"]["class"], "expand");
    assert_eq!(end["recognition"]["neighbours"][0]["origin"], "generated");
    assert_eq!(end["recognition"]["synth_us"], 3100);
    assert_eq!(end["rejected"], Value::Null);
    assert_eq!(old.json()["type"], "stats");

    // The plan client: the motion's life and the plans, then stats; no event.
    let m = js.json();
    assert_eq!(
        m,
        json!({"type":"gesture_motion","id":4,"class":"expand","phase":"approach","t_us":21})
    );
    let p = js.json();
    assert_eq!(p["type"], "plan");
    assert_eq!(p["gesture"], 4);
    assert_eq!(p["duration_s"], 2.5);
    assert_eq!(p["samples"], 2);
    assert_eq!(
        p["agents"],
        json!([
            [1.0, 1.0, 0.5, 0.5],
            [2.0, 1.0, 2.5, 0.5],
            [1.5, 2.0, 1.5, 2.75]
        ])
    );
    let demo = js.json();
    assert_eq!(demo["type"], "demo_motion");
    assert_eq!(demo["motion"], 7);
    assert_eq!(demo["agents"], p["agents"]);
    assert_eq!(js.json()["type"], "stats");

    // The binary plan client: the same messages as JSON frames.
    for expect in ["gesture_motion", "plan", "demo_motion"] {
        let frame = bin.frame();
        assert_eq!(frame[4], FRAME_KIND_JSON);
        let v: Value = serde_json::from_slice(&frame[5..]).unwrap();
        assert_eq!(v["type"], expect);
    }
}
