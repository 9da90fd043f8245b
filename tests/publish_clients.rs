//! The socket with many clients and busy ones: replies in the order of each
//! client's requests and only to it, one client's command flood not taking the
//! others' room, the client limit changed while running, and a fixed number of
//! threads however many clients connect (the real daemon, `/proc/<pid>/task`).

use crossbeam_channel::{bounded, Receiver, Sender};
use crowdtouch::geom::Rect;
use crowdtouch::publish::socket::{COMMAND_WINDOW, LINE_BURST};
use crowdtouch::publish::{HelloInfo, Outgoing, PublisherStats, Server, SocketOptions};
use crowdtouch::vocab::{Command, CommandRequest, Micros, Snapshot};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Command as Process, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a test client waits for a message before the test fails.
const READ_TIMEOUT: Duration = Duration::from_secs(10);

/// The publisher on a real socket with a fake control thread.
struct Socket {
    _dir: tempfile::TempDir,
    path: PathBuf,
    out: Sender<Outgoing>,
    stop: Arc<AtomicBool>,
    stats: Arc<PublisherStats>,
    run: Option<JoinHandle<()>>,
    /// The control side's end of the command channel when the test answers itself.
    commands: Option<Receiver<CommandRequest>>,
}

impl Socket {
    /// A socket whose command channel holds `capacity` commands. With `answer`, a
    /// control thread answers every command (`set_agent_count` 0 refused, the rest
    /// acknowledged), taking `delay` over each; without, the test answers.
    fn start(max_clients: u32, capacity: usize, answer: Option<Duration>) -> Socket {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.sock");
        let opts = SocketOptions {
            mode: 0o600,
            group: None,
            client_queue: 8,
            max_clients,
        };
        let info = HelloInfo {
            world: Rect {
                min: [0.0, 0.0],
                max: [8.0, 5.0],
            },
            agents: 10,
            agent_radius_m: 0.15,
        };
        let server = Server::bind(&opts, &path, info).unwrap();
        let stats = server.stats();
        let (out, rx) = bounded::<Outgoing>(1024);
        let (cmd_tx, cmd_rx) = bounded::<CommandRequest>(capacity);
        let stop = Arc::new(AtomicBool::new(false));
        let mut commands = Some(cmd_rx);
        if let Some(delay) = answer {
            let (cmd_rx, replies) = (commands.take().unwrap(), out.clone());
            std::thread::spawn(move || {
                for req in cmd_rx.iter() {
                    std::thread::sleep(delay);
                    let result = match req.command {
                        Command::SetAgentCount { count: 0 } => Err("count must be positive".into()),
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
            });
        }
        let run = {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || server.run(rx, cmd_tx, stop))
        };
        Socket {
            _dir: dir,
            path,
            out,
            stop,
            stats,
            run: Some(run),
            commands,
        }
    }

    fn snapshot(&self, seq: u64) {
        let s = Snapshot {
            seq,
            input_t: Some(Micros(1)),
            ..Snapshot::default()
        };
        self.out.send(Outgoing::Snapshot(Arc::new(s))).unwrap();
    }
}

impl Drop for Socket {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.run.take() {
            let _ = t.join();
        }
    }
}

/// A client reading JSON lines.
struct Client {
    r: BufReader<UnixStream>,
    w: UnixStream,
}

impl Client {
    /// Connects, takes the server's hello and asks for `subscribe`.
    fn connect(path: &Path, subscribe: Value) -> Client {
        let s = UnixStream::connect(path).unwrap();
        s.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
        let mut c = Client {
            w: s.try_clone().unwrap(),
            r: BufReader::new(s),
        };
        assert_eq!(c.json()["type"], "hello");
        c.send(&json!({"type":"hello","protocol":1,"subscribe":subscribe}).to_string());
        assert_eq!(c.json()["type"], "hello");
        c
    }

    fn send(&mut self, line: &str) {
        self.w.write_all(line.as_bytes()).unwrap();
        self.w.write_all(b"\n").unwrap();
    }

    fn json(&mut self) -> Value {
        let mut line = Vec::new();
        let n = self.r.read_until(b'\n', &mut line).unwrap();
        assert!(n > 0, "the server closed the connection");
        serde_json::from_slice(&line)
            .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&line)))
    }

    /// The next `n` replies (`ack` or `error`), skipping nothing: the client
    /// subscribed to nothing, so every line is a reply.
    fn replies(&mut self, n: usize) -> Vec<Value> {
        (0..n).map(|_| self.json()).collect()
    }
}

/// Line `k` of a burst from client `who`: a command the control thread answers,
/// or (every third) one the socket refuses on the spot (unknown command).
fn burst_line(who: &str, k: usize) -> String {
    let name = if k % 3 == 2 { "explode" } else { "pause" };
    json!({"type":"command","id":format!("{who}{k}"),"name":name}).to_string()
}

#[test]
fn replies_come_back_in_the_order_of_the_requests_and_only_to_the_asker() {
    // A slow control thread and a small command channel: some commands are answered
    // by the control thread, some refused "busy" on the spot, malformed ones refused
    // on the spot; every reply still comes back in request order.
    let s = Socket::start(8, 2, Some(Duration::from_micros(300)));
    const N: usize = 150;
    let senders: Vec<JoinHandle<(Vec<Value>, Client)>> = ["a", "b"]
        .into_iter()
        .map(|who| {
            let mut c = Client::connect(&s.path, json!([]));
            std::thread::spawn(move || {
                let burst: String = (0..N).map(|k| burst_line(who, k) + "\n").collect();
                c.w.write_all(burst.as_bytes()).unwrap();
                (c.replies(N), c)
            })
        })
        .collect();
    let mut open = Vec::new();
    for (who, t) in ["a", "b"].into_iter().zip(senders) {
        let (replies, client) = t.join().unwrap();
        open.push(client);
        let ids: Vec<String> = replies
            .iter()
            .map(|r| r["id"].as_str().unwrap_or_default().to_string())
            .collect();
        let expected: Vec<String> = (0..N).map(|k| format!("{who}{k}")).collect();
        assert_eq!(
            ids, expected,
            "client {who}: replies out of order or astray"
        );
        for (k, r) in replies.iter().enumerate() {
            if k % 3 == 2 {
                assert_eq!(r["type"], "error", "{r}");
                assert!(
                    r["message"].as_str().unwrap().contains("unknown command"),
                    "{r}"
                );
            } else {
                assert!(
                    r["type"] == "ack" || r["message"].as_str().unwrap().starts_with("busy"),
                    "{r}"
                );
            }
        }
    }
    assert_eq!(s.stats.clients(), 2, "bursts are paced, not refused");
}

#[test]
fn a_flooding_client_cannot_take_the_command_channel_from_the_others() {
    // The channel has room for two clients' windows: however fast one client sends,
    // it holds at most COMMAND_WINDOW places, and another's commands find room.
    let s = Socket::start(8, 2 * COMMAND_WINDOW, Some(Duration::from_micros(200)));
    const FLOOD: usize = 400;
    let mut flood = Client::connect(&s.path, json!([]));
    let flooding = std::thread::spawn(move || {
        let lines: String = (0..FLOOD)
            .map(|k| json!({"type":"command","id":k,"name":"pause"}).to_string() + "\n")
            .collect();
        flood.w.write_all(lines.as_bytes()).unwrap();
        flood.replies(FLOOD)
    });
    let mut other = Client::connect(&s.path, json!(["snapshot"]));
    let mut seq = 0;
    for k in 0..5 {
        other.send(&json!({"type":"command","id":format!("mine{k}"),"name":"resume"}).to_string());
        // Snapshots go on meanwhile; the reply is the next non-snapshot line.
        seq += 1;
        s.snapshot(seq);
        let reply = loop {
            let v = other.json();
            if v["type"] != "snapshot" {
                break v;
            }
        };
        assert_eq!(reply, json!({"type":"ack","id":format!("mine{k}")}));
    }
    let replies = flooding.join().unwrap();
    let acks: Vec<Value> = (0..FLOOD).map(|k| json!({"type":"ack","id":k})).collect();
    assert_eq!(
        replies, acks,
        "the flood is slowed, never refused or reordered"
    );
    assert_eq!(s.stats.commands_busy(), 0);
}

#[test]
fn a_hello_waits_for_the_replies_before_it() {
    let mut s = Socket::start(8, 4, None);
    let mut c = Client::connect(&s.path, json!([]));
    c.send(r#"{"type":"command","id":1,"name":"pause"}"#);
    c.send(r#"{"type":"hello","protocol":1,"format":"binary","subscribe":[]}"#);
    let commands = s.commands.take().unwrap();
    let req = commands.recv_timeout(READ_TIMEOUT).unwrap();
    // Let the socket read the hello before the answer comes (if it has not yet, the
    // order below holds all the same).
    std::thread::sleep(Duration::from_millis(50));
    s.out
        .send(Outgoing::Reply {
            client: req.client,
            id: req.id,
            result: Ok(()),
        })
        .unwrap();
    // The ack in the old format (a JSON line), then the hello's answer, the last
    // JSON line; binary frames after it.
    assert_eq!(c.json(), json!({"type":"ack","id":1}));
    let hello = c.json();
    assert_eq!(
        (hello["type"].as_str(), hello["format"].as_str()),
        (Some("hello"), Some("binary"))
    );
}

#[test]
fn lines_past_the_burst_are_paced_and_all_answered() {
    // Malformed commands are answered by the socket itself: only the line budget
    // paces them. More than a burst's worth all get their error, in order.
    let s = Socket::start(8, 4, Some(Duration::ZERO));
    let n = 2 * LINE_BURST as usize;
    let mut c = Client::connect(&s.path, json!([]));
    let lines: String = (0..n)
        .map(|k| json!({"type":"command","id":k,"name":"explode"}).to_string() + "\n")
        .collect();
    c.w.write_all(lines.as_bytes()).unwrap();
    let ids: Vec<Value> = c.replies(n).iter().map(|r| r["id"].clone()).collect();
    assert_eq!(ids, (0..n).map(|k| json!(k)).collect::<Vec<_>>());
    assert_eq!(s.stats.protocol_errors(), n as u64);
}

#[test]
fn the_client_limit_can_change_while_the_socket_runs() {
    let s = Socket::start(4, 4, Some(Duration::ZERO));
    let _a = Client::connect(&s.path, json!([]));
    let _b = Client::connect(&s.path, json!([]));
    s.stats.set_max_clients(2);
    assert_eq!(s.stats.max_clients(), 2);
    let refused = UnixStream::connect(&s.path).unwrap();
    refused.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
    let mut line = String::new();
    BufReader::new(refused).read_line(&mut line).unwrap();
    assert!(line.contains("too many clients"), "{line}");
    assert_eq!(s.stats.clients(), 2, "the clients already connected stay");
    s.stats.set_max_clients(1);
    assert_eq!(
        s.stats.clients(),
        2,
        "lowering the limit disconnects nobody"
    );
    s.stats.set_max_clients(3);
    let _c = Client::connect(&s.path, json!([]));
    assert_eq!(s.stats.clients(), 3);
    assert_eq!(s.stats.clients_refused(), 1);
}

/// The names of process `pid`'s threads, sorted.
fn threads(pid: u32) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(format!("/proc/{pid}/task"))
        .unwrap()
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("comm")).ok())
        .map(|n| n.trim().to_string())
        .collect();
    names.sort();
    names
}

/// Reads lines from `c` until a snapshot.
fn read_snapshot(r: &mut BufReader<UnixStream>) {
    let mut line = Vec::new();
    loop {
        line.clear();
        let n = r.read_until(b'\n', &mut line).unwrap();
        assert!(n > 0, "the daemon closed the connection");
        if line.starts_with(b"{\"type\":\"snapshot\"") {
            return;
        }
    }
}

#[test]
fn thirty_two_clients_are_served_by_the_same_threads_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("demo.sock");
    let mut daemon = Process::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["demo", "--seconds", "60", "--socket"])
        .arg(&sock)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let pid = daemon.id();
    let t0 = Instant::now();
    let first = loop {
        if let Ok(s) = UnixStream::connect(&sock) {
            break s;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "no socket in 60 s");
        std::thread::sleep(Duration::from_millis(20));
    };
    first.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
    let mut first = BufReader::new(first);
    read_snapshot(&mut first);
    // Every thread has started once the last one, the input thread, has its name.
    while !threads(pid).iter().any(|n| n == "ct-input") {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no input thread in 60 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let with_one = threads(pid);
    // 31 more (the demo's socket.max_clients is 32), each reading a snapshot.
    let mut others: Vec<BufReader<UnixStream>> = (0..31)
        .map(|_| {
            let s = UnixStream::connect(&sock).unwrap();
            s.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
            BufReader::new(s)
        })
        .collect();
    for r in &mut others {
        read_snapshot(r);
    }
    read_snapshot(&mut first);
    let with_32 = threads(pid);
    // Connect/close churn on top, with room for it (a closed connection may still be
    // counted when the next one comes: then that one is refused, also fine here).
    others.truncate(others.len() - 4);
    let mut served = 0;
    for _ in 0..100 {
        let s = UnixStream::connect(&sock).unwrap();
        s.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
        let mut line = String::new();
        BufReader::new(s).read_line(&mut line).unwrap();
        if line.starts_with("{\"type\":\"hello\"") {
            served += 1;
        } else {
            assert!(line.contains("too many clients"), "{line}");
        }
    }
    assert!(served > 0);
    let after_churn = threads(pid);
    let _ = daemon.kill();
    let _ = daemon.wait();
    assert_eq!(with_32, with_one, "threads with 1 client, then with 32");
    assert_eq!(
        after_churn, with_one,
        "threads with 1 client, then after churn"
    );
}
