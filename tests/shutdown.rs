//! Large crowds and bad moments: SIGTERM ends the daemon promptly in every state
//! (a big resize being prepared, a big crowd being solved, a big formation switch
//! being prepared), a stale solve is given up and fresh results flow soon after the
//! crowd shrinks back, and the control thread keeps publishing while a large resize
//! is prepared.
//!
//! Bounds here are "does not hang" bounds, far above the targets (SIGTERM to exit
//! within 1 s, a stale solve abandoned within 50 ms): `crowdtouch bench shutdown`
//! measures the real figures (docs/benchmarks.md).

use crowdtouch::config::{Config, MAX_AGENTS};
use crowdtouch::pipeline::{Daemon, DaemonOptions, SourceSpec};
use crowdtouch::vocab::{StatsReport, TouchFrame};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// "Does not hang": a SIGTERM answered later than this is a failure.
const EXIT_BOUND: Duration = Duration::from_secs(10);

/// `crowdtouch demo` on a socket in `dir` (the embedded default: the shipped
/// recordings looped), stderr piped; returns once a client is connected and has
/// read the server's hello.
fn demo(dir: &Path, agents: u32) -> (Child, BufReader<UnixStream>, UnixStream) {
    let sock = dir.join("demo.sock");
    let child = Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["demo", "--agents", &agents.to_string(), "--socket"])
        .arg(&sock)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    // Generous: a debug build draws the start crowd's goals before it listens.
    // The socket's file appears when it is bound, a moment before it listens:
    // connecting in between is refused, so refusals are retried too.
    let stream = loop {
        match UnixStream::connect(&sock) {
            Ok(s) => break s,
            Err(e) if t0.elapsed() > Duration::from_secs(120) => {
                panic!("the demo listens on {}: {e}", sock.display())
            }
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    };
    let w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    let mut w2 = w.try_clone().unwrap();
    // Events and replies only: no snapshot stream to keep up with.
    writeln!(
        w2,
        r#"{{"type":"hello","protocol":1,"subscribe":["events","stats"]}}"#
    )
    .unwrap();
    let hello = read_json_until(&mut r, Duration::from_secs(30), |v| {
        hello_answer(v, &["events", "stats"])
    });
    assert!(hello.is_some(), "no hello answer");
    (child, r, w)
}

/// Whether `v` is the server's answer to a client hello subscribing to `subs`.
fn hello_answer(v: &Value, subs: &[&str]) -> bool {
    let mut got: Vec<&str> = v["subscriptions"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    got.sort_unstable();
    let mut want = subs.to_vec();
    want.sort_unstable();
    v["type"] == "hello" && got == want
}

/// Reads JSON lines until `until` holds (returns that message) or `secs` pass.
fn read_json_until(
    r: &mut BufReader<UnixStream>,
    within: Duration,
    mut until: impl FnMut(&Value) -> bool,
) -> Option<Value> {
    r.get_ref()
        .set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    let end = Instant::now() + within;
    let mut line = String::new();
    while Instant::now() < end {
        match r.read_line(&mut line) {
            Ok(0) => return None,
            Ok(_) => {
                let v: Value = serde_json::from_str(&line).unwrap();
                line.clear();
                if until(&v) {
                    return Some(v);
                }
            }
            Err(e)
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("read: {e}"),
        }
    }
    None
}

/// Sends SIGTERM and waits for the exit; returns the exit status, the time it
/// took and the log.
fn terminate(mut child: Child) -> (std::process::ExitStatus, Duration, String) {
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let t0 = Instant::now();
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut log = String::new();
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut log)
                .unwrap();
            return (status, t0.elapsed(), log);
        }
        if t0.elapsed() > EXIT_BOUND {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the daemon did not exit within {EXIT_BOUND:?} of SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn command(w: &mut UnixStream, id: u32, body: &str) {
    writeln!(w, r#"{{"type":"command","id":{id},{body}}}"#).unwrap();
}

/// The exit is clean: status 0 (and, by `terminate`, within the bound).
fn assert_clean_exit(status: std::process::ExitStatus, took: Duration, log: &str) {
    assert!(status.success(), "exit {status:?} after {took:?}:\n{log}");
}

/// SIGTERM while the goals of the largest crowd are being drawn (seconds in a
/// release build, tens of seconds in a debug one): the preparation is given up.
#[test]
fn sigterm_while_a_big_resize_is_prepared_exits_promptly() {
    let dir = tempfile::tempdir().unwrap();
    let (child, _r, mut w) = demo(dir.path(), 100);
    command(
        &mut w,
        1,
        &format!(r#""name":"set_agent_count","count":{MAX_AGENTS}"#),
    );
    std::thread::sleep(Duration::from_millis(300));
    let (status, took, log) = terminate(child);
    assert_clean_exit(status, took, &log);
}

/// SIGTERM while a big crowd is being solved and while a formation switch for it
/// is prepared (the least-effort pairing of every agent).
#[test]
fn sigterm_while_a_big_crowd_is_solved_and_switched_exits_promptly() {
    let dir = tempfile::tempdir().unwrap();
    let (child, mut r, mut w) = demo(dir.path(), 4000);
    // The worker is solving once the first stats count assignments.
    let busy = read_json_until(&mut r, Duration::from_secs(60), |v| {
        v["type"] == "stats" && v["assignments"].as_u64().unwrap_or(0) > 0
    });
    assert!(busy.is_some(), "no assignment within a minute");
    command(&mut w, 2, r#""name":"set_formation","formation":"square""#);
    std::thread::sleep(Duration::from_millis(200));
    let (status, took, log) = terminate(child);
    assert_clean_exit(status, took, &log);
}

/// An in-process daemon with no touches (a channel input that stays quiet), its
/// mesh with `mesh_side²` vertices: a crowd of exactly that many agents gets its
/// goals at once (one per vertex), so a big crowd is quick to make even in a debug
/// build, and slow to solve.
fn quiet_daemon(dir: &Path, mesh_side: u32) -> (Daemon, crossbeam_channel::Sender<TouchFrame>) {
    let mut cfg = Config::embedded_default();
    cfg.pipeline.realtime = Default::default();
    cfg.mesh.cols = mesh_side;
    cfg.mesh.rows = mesh_side;
    cfg.pipeline.stats_interval_ms = 250;
    let (tx, rx) = crossbeam_channel::bounded(16);
    let daemon = Daemon::start(
        cfg,
        vec![SourceSpec::Channel { rx, glass_mm: None }],
        DaemonOptions {
            socket_path: dir.join("q.sock"),
            collect: None,
        },
    )
    .expect("daemon starts");
    (daemon, tx)
}

/// A client of `daemon` that subscribed to `subs` (with `fields`, a JSON array).
fn client(
    daemon: &Daemon,
    subs: &[&str],
    fields: Option<&str>,
) -> (BufReader<UnixStream>, UnixStream) {
    let stream = UnixStream::connect(daemon.socket_path()).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    let fields = fields.map_or(String::new(), |f| format!(r#","fields":{f}"#));
    writeln!(
        w,
        r#"{{"type":"hello","protocol":1,"subscribe":{}{fields}}}"#,
        serde_json::json!(subs)
    )
    .unwrap();
    let answered = read_json_until(&mut r, Duration::from_secs(10), |v| hello_answer(v, subs));
    assert!(answered.is_some(), "no hello answer");
    (r, w)
}

fn stage<'a>(r: &'a StatsReport, name: &str) -> Option<&'a crowdtouch::vocab::StageStats> {
    r.stages.iter().find(|s| s.stage == name)
}

/// Grown to a big crowd and shrunk back while its solve runs: the stale solve is
/// given up (the stats count it under `abandon`) and assignments for the small
/// crowd flow soon after, instead of the worker finishing a solve for a crowd
/// that no longer exists.
#[test]
fn a_stale_solve_is_abandoned_and_fresh_results_flow_after_shrinking_back() {
    let dir = tempfile::tempdir().unwrap();
    // A big square crowd (100 × 100, the most the default budgets allow): its
    // first, cold solve takes long enough to be overtaken.
    let side = 100;
    let big = side * side;
    let (mut daemon, _tx) = quiet_daemon(dir.path(), side);
    let (mut r, mut w) = client(&daemon, &["events"], None);
    let mut abandoned = 0;
    for cycle in 0..3 {
        let id = 10 + 2 * cycle;
        command(
            &mut w,
            id,
            &format!(r#""name":"set_agent_count","count":{big}"#),
        );
        let ack = read_json_until(&mut r, Duration::from_secs(60), |v| v["id"] == id);
        assert_eq!(ack.unwrap()["type"], "ack");
        // The resize is acknowledged once the crowd has its new size; a few
        // ticks later the worker has taken up the big crowd's first solve, which
        // starts cold (a new crowd) and is still running when the crowd shrinks
        // back. (Waiting for its first result instead left only the quick warm
        // solves of a settling crowd to be overtaken, by chance.)
        std::thread::sleep(Duration::from_millis(30));
        command(&mut w, id + 1, r#""name":"set_agent_count","count":100"#);
        let ack = read_json_until(&mut r, Duration::from_secs(30), |v| v["id"] == id + 1);
        assert_eq!(ack.unwrap()["type"], "ack");
        // Fresh results for the small crowd flow within the bound.
        let t0 = Instant::now();
        let mut first: Option<u64> = None;
        let mut flowing = false;
        while t0.elapsed() < Duration::from_secs(10) && !flowing {
            let Some(rep) = daemon.next_report(Duration::from_millis(300)) else {
                continue;
            };
            abandoned += stage(&rep, "abandon").map_or(0, |s| s.count);
            if rep.agents != 100 {
                continue;
            }
            match first {
                None => first = Some(rep.assignments),
                Some(a) => flowing = rep.assignments > a + 5,
            }
        }
        assert!(
            flowing,
            "cycle {cycle}: no fresh assignments within 10 s of shrinking back"
        );
        if abandoned > 0 {
            break;
        }
    }
    assert!(abandoned > 0, "no stale solve was given up in three cycles");
    daemon.shutdown();
}

/// The control thread goes on publishing at the old size while a resize to the
/// largest crowd the default budgets allow (10,000) is prepared, and the resize is
/// acknowledged when the crowd has its new size.
#[test]
fn snapshots_keep_flowing_while_a_large_resize_is_prepared() {
    let dir = tempfile::tempdir().unwrap();
    let (daemon, _tx) = quiet_daemon(dir.path(), 10);
    let (mut r, mut w) = client(&daemon, &["snapshot", "events"], Some(r#"["positions"]"#));
    let count = MAX_AGENTS;
    assert!(count >= 10_000, "the daemon takes 10,000 agents");
    command(
        &mut w,
        3,
        &format!(r#""name":"set_agent_count","count":{count}"#),
    );
    let mut during = 0;
    let ack = read_json_until(&mut r, Duration::from_secs(120), |v| {
        if v["type"] == "snapshot" && v["agents"] == 100 {
            during += 1;
        }
        v["id"] == 3
    });
    assert_eq!(ack.expect("an answer")["type"], "ack");
    // Drawing 10,000 goals takes a quarter to half a second in a release build
    // (seconds in a debug one): at 120 ticks per second, dozens of snapshots. A
    // control thread that drew them itself would have published none meanwhile, so
    // a handful is the line (how many more depends on the machine, not the daemon).
    assert!(
        during >= 5,
        "{during} snapshots at the old size while the resize was prepared"
    );
    let next = read_json_until(&mut r, Duration::from_secs(5), |v| v["type"] == "snapshot");
    assert_eq!(next.expect("snapshots go on")["agents"], count);
    daemon.shutdown();
}
