//! SIGHUP on `crowdtouch run`: live fields are applied and restart fields keep their
//! running values, and one log line says which is which (issue 14, item 5: a reload
//! said "config reloaded" while `crowd.agents`, `socket.max_clients` and
//! `socket.path` changes were silently ignored).

mod common;

use serde_json::{json, Value};
use std::io::{BufRead, BufReader};
use std::os::unix::fs::PermissionsExt;
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Generous bound for "does not hang" waits (a debug build on a loaded machine).
const WAIT: Duration = Duration::from_secs(60);

/// `crowdtouch run` with its stderr collected line by line.
struct Running {
    child: Child,
    log: Arc<Mutex<Vec<String>>>,
}

impl Running {
    /// Starts `run --config cfg` (with `--socket socket` when given) and waits for
    /// the socket at `expect`.
    fn start(cfg: &Path, socket: Option<&Path>, expect: &Path) -> Running {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_crowdtouch"));
        cmd.args(["run", "--config"]).arg(cfg);
        if let Some(s) = socket {
            cmd.arg("--socket").arg(s);
        }
        let mut child = cmd
            .env_remove("RUST_LOG")
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let log = Arc::new(Mutex::new(Vec::new()));
        let stderr = BufReader::new(child.stderr.take().unwrap());
        let sink = Arc::clone(&log);
        std::thread::spawn(move || {
            for line in stderr.lines().map_while(Result::ok) {
                sink.lock().unwrap().push(line);
            }
        });
        let t0 = Instant::now();
        // The file appears at bind(), a moment before listen(): wait until a
        // client can connect.
        while UnixStream::connect(expect).is_err() && t0.elapsed() < WAIT {
            std::thread::sleep(Duration::from_millis(20));
        }
        assert!(
            expect.exists(),
            "the daemon made no socket: {:?}",
            log.lock()
        );
        Running { child, log }
    }

    fn signal(&self, sig: nix::sys::signal::Signal) {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        nix::sys::signal::kill(pid, sig).unwrap();
    }

    /// Sends SIGHUP and returns the reload's "config reloaded" line (the first one
    /// after the log lines already there).
    fn reload(&self) -> String {
        let from = self.log.lock().unwrap().len();
        self.signal(nix::sys::signal::Signal::SIGHUP);
        self.wait_line(from, "config reloaded")
    }

    /// The first log line from index `from` on containing `text`.
    fn wait_line(&self, from: usize, text: &str) -> String {
        let t0 = Instant::now();
        while t0.elapsed() < WAIT {
            if let Some(l) = self.log.lock().unwrap()[from..]
                .iter()
                .find(|l| l.contains(text))
            {
                return l.clone();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("no log line with {text:?}: {:?}", self.log.lock().unwrap());
    }

    fn log_len(&self) -> usize {
        self.log.lock().unwrap().len()
    }

    /// SIGTERM; asserts a clean exit.
    fn stop(mut self) {
        self.signal(nix::sys::signal::Signal::SIGTERM);
        let status = self.child.wait().unwrap();
        assert!(status.success(), "{:?}", self.log.lock().unwrap());
    }
}

/// The default config with its inputs replaced by one shipped recording, looped,
/// and the given `(from, to)` edits (each must apply).
fn config_text(edits: &[(&str, &str)]) -> String {
    let rec = common::shipped("07-open-space-swipe.jsonl");
    let base = crowdtouch::config::DEFAULT_CONFIG_RON;
    let a = base.find("inputs: [").unwrap();
    let b = a + base[a..].find("\n    ],\n").unwrap() + "\n    ],\n".len();
    let mut text = format!(
        "{}inputs: [Replay(files: [{:?}], looped: true)],\n{}",
        &base[..a],
        rec.display().to_string(),
        &base[b..]
    );
    // No real-time scheduling or locked memory for a test process.
    for (from, to) in [
        ("priority: Some(20),", "priority: None,"),
        ("lock_memory: true,", "lock_memory: false,"),
    ]
    .iter()
    .chain(edits)
    {
        assert!(text.contains(from), "the config has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    text
}

/// A client: reads its `hello` and returns it with the stream.
fn connect(path: &Path) -> (Value, BufReader<UnixStream>) {
    let stream = UnixStream::connect(path)
        .unwrap_or_else(|e| panic!("connecting to {}: {e}", path.display()));
    let mut r = BufReader::new(stream);
    r.get_ref()
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let v = next_message(&mut r).expect("a hello");
    (v, r)
}

/// The next JSON message, or `None` at the end of the stream.
fn next_message(r: &mut BufReader<UnixStream>) -> Option<Value> {
    let t0 = Instant::now();
    let mut line = String::new();
    while t0.elapsed() < WAIT {
        match r.read_line(&mut line) {
            Ok(0) => return None,
            Ok(_) if line.ends_with('\n') => return Some(serde_json::from_str(&line).unwrap()),
            _ => {}
        }
    }
    panic!("no message in {WAIT:?}");
}

/// Reads messages until one satisfies `f` and returns it.
fn read_until(r: &mut BufReader<UnixStream>, what: &str, f: impl Fn(&Value) -> bool) -> Value {
    let t0 = Instant::now();
    while t0.elapsed() < WAIT {
        match next_message(r) {
            Some(v) if f(&v) => return v,
            Some(_) => {}
            None => break,
        }
    }
    panic!("no {what} in the stream");
}

fn write_config(path: &Path, edits: &[(&str, &str)]) {
    std::fs::write(path, config_text(edits)).unwrap();
}

#[test]
fn live_fields_are_applied_and_the_log_line_names_them() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("crowdtouch.ron");
    let sock = dir.path().join("run.sock");
    let start = [
        ("agents: 100,", "agents: 40,"),
        ("max_clients: 32,", "max_clients: 8,"),
    ];
    write_config(&cfg, &start);
    let daemon = Running::start(&cfg, Some(&sock), &sock);
    let (hello, mut reader) = connect(&sock);
    assert_eq!(hello["agents"], 40);
    let before = daemon.log_len();

    write_config(
        &cfg,
        &[
            ("log_level: info,", "log_level: debug,"),
            ("agents: 100,", "agents: 25,"),
            ("max_speed_m_s: 1.5,", "max_speed_m_s: 2.0,"),
            ("mode: \"0660\",", "mode: \"0600\","),
            ("max_clients: 32,", "max_clients: 2,"),
        ],
    );
    let line = daemon.reload();
    assert!(
        line.ends_with(
            "config reloaded: applied log_level \"info\" → \"debug\", crowd.agents 40 → 25, \
             crowd.max_speed_m_s 1.5 → 2.0, socket.mode \"0660\" → \"0600\", \
             socket.max_clients 8 → 2"
        ),
        "{line}"
    );

    // crowd.agents: the crowd is resized, and clients are told.
    let reset = read_until(&mut reader, "reset event", |v| v["type"] == "reset");
    assert_eq!(reset["agents"], 25);
    let snap = read_until(&mut reader, "snapshot", |v| v["type"] == "snapshot");
    assert_eq!(snap["agents"], 25);
    let (hello, _second) = connect(&sock);
    assert_eq!(hello["agents"], 25, "a new client's hello has the new size");
    // socket.max_clients: two clients are connected now; a third is refused.
    let (refused, mut third) = connect(&sock);
    assert_eq!(refused["type"], "error", "{refused}");
    assert_eq!(refused["fatal"], true);
    assert!(
        refused["message"]
            .as_str()
            .unwrap()
            .contains("too many clients"),
        "{refused}"
    );
    assert!(
        next_message(&mut third).is_none(),
        "the refused client is closed"
    );
    // socket.mode: the socket file.
    let mode = std::fs::metadata(&sock).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
    // log_level: debug lines (the supervisor's status line) from now on, none before.
    let status = daemon.wait_line(before, "| controls");
    assert!(status.contains("agents    25"), "{status}");
    let log = daemon.log.lock().unwrap().clone();
    let reload_at = log
        .iter()
        .position(|l| l.contains("config reloaded"))
        .unwrap();
    assert!(
        !log[..reload_at].iter().any(|l| l.contains("| controls")),
        "debug lines before the reload: {log:?}"
    );
    drop(log);
    daemon.stop();
}

/// Reads `stats` messages until one whose `restart_pending` is `want`.
fn pending_in_stats(r: &mut BufReader<UnixStream>, want: &Value) {
    let seen = read_until(r, "stats with the expected restart_pending", |v| {
        v["type"] == "stats" && &v["restart_pending"] == want
    });
    assert_eq!(&seen["restart_pending"], want);
}

#[test]
fn restart_fields_keep_their_running_values_in_use_and_in_stats() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("crowdtouch.ron");
    let a = dir.path().join("a.sock");
    let b = dir.path().join("b.sock");
    let path_a = format!("path: Some({:?}),", a.display().to_string());
    let path_b = format!("path: Some({:?}),", b.display().to_string());
    write_config(&cfg, &[("path: None,", &path_a)]);
    let daemon = Running::start(&cfg, None, &a);
    let (_, mut reader) = connect(&a);
    pending_in_stats(&mut reader, &json!([]));

    write_config(
        &cfg,
        &[
            ("path: None,", &path_b),
            ("cols: 10,", "cols: 12,"),
            ("kp_per_s2: 16.0,", "kp_per_s2: 20.0,"),
        ],
    );
    let line = daemon.reload();
    let (a_s, b_s) = (a.display().to_string(), b.display().to_string());
    assert!(
        line.contains(" WARN ")
            && line.ends_with(&format!(
                "config reloaded: applied crowd.kp_per_s2 16.0 → 20.0; needs restart (the old \
                 values stay in use): mesh.cols 10 → 12, socket.path \"{a_s}\" → \"{b_s}\" \
                 (serving {a_s})"
            )),
        "{line}"
    );
    // The old values are in use: the socket stays where it was, the mesh keeps its
    // 10 × 8 vertices.
    assert!(!b.exists(), "a socket was bound at the new path");
    let (_, mut late) = connect(&a);
    let mesh = read_until(&mut late, "mesh", |v| v["type"] == "mesh");
    assert_eq!(mesh["vertices"].as_array().unwrap().len(), 2 * 10 * 8);
    // ...and listed in every stats message until the restart.
    let pending = json!([
        {"field": "mesh.cols", "running": 10, "configured": 12},
        {"field": "socket.path", "running": a_s, "configured": b_s},
    ]);
    pending_in_stats(&mut reader, &pending);

    // The same file again: still pending, still said.
    let line = daemon.reload();
    assert!(line.contains("needs restart"), "{line}");
    assert!(!line.contains("applied"), "{line}");
    pending_in_stats(&mut reader, &pending);

    // The file back at the running values (the live change kept): nothing pending.
    write_config(
        &cfg,
        &[
            ("path: None,", &path_a),
            ("kp_per_s2: 16.0,", "kp_per_s2: 20.0,"),
        ],
    );
    let line = daemon.reload();
    assert!(
        line.ends_with("config reloaded: no field changed"),
        "{line}"
    );
    pending_in_stats(&mut reader, &json!([]));
    daemon.stop();
    assert!(!a.exists(), "the socket file is removed at exit");
}
