//! The `gestures.library` config field (issue 15): a corrupt library file is
//! refused at the field, naming the problem, by `check-config` and `run`; and a
//! library corrupted under a running daemon is refused on SIGHUP while the running
//! library goes on recognising gestures.

mod common;

use crowdtouch::gesture::library::SHIPPED_BYTES;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

const WAIT: Duration = Duration::from_secs(60);

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

/// The default config with one shipped recording looped as its input, no
/// real-time scheduling, its socket in `dir`, the given edits; written as
/// `dir/c.ron`.
fn config(dir: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let rec = common::shipped("07-open-space-swipe.jsonl");
    let base = crowdtouch::config::DEFAULT_CONFIG_RON;
    let a = base.find("inputs: [").unwrap();
    let b = a + base[a..].find("\n    ],\n").unwrap() + "\n    ],\n".len();
    let mut text = format!(
        "{}inputs: [Replay(files: [{:?}], looped: true, gap_ms: 300)],\n{}",
        &base[..a],
        rec.display().to_string(),
        &base[b..]
    );
    let sock = format!(
        "path: Some({:?}),",
        dir.join("ct.sock").display().to_string()
    );
    for (from, to) in [
        ("priority: Some(20),", "priority: None,"),
        ("lock_memory: true,", "lock_memory: false,"),
        ("path: None,", sock.as_str()),
    ]
    .iter()
    .chain(edits)
    {
        assert!(text.contains(from), "the config has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    let p = dir.join("c.ron");
    std::fs::write(&p, text).unwrap();
    p
}

/// The shipped library with four bytes of its first motion's mean flipped.
fn corrupt() -> Vec<u8> {
    let mut b = SHIPPED_BYTES.to_vec();
    for x in &mut b[1000..1004] {
        *x ^= 0xff;
    }
    b
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_corrupt_library_is_refused_at_gestures_library() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ctgl");
    std::fs::write(&bad, corrupt()).unwrap();
    let c = config(
        dir.path(),
        &[("library: None,", "library: Some(\"bad.ctgl\"),")],
    );
    let text = std::fs::read_to_string(&c).unwrap();
    let (n, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.contains("library: Some"))
        .unwrap();
    let at = format!(
        "{}:{}:{}: field `gestures.library`",
        c.display(),
        n + 1,
        line.find("library: Some").unwrap() + 1
    );
    let check = bin().arg("check-config").arg(&c).output().unwrap();
    let err = stderr(&check);
    assert_eq!(check.status.code(), Some(1), "{err}");
    assert!(err.starts_with(&at), "want {at}…, got:\n{err}");
    assert!(
        err.contains(&format!("{}: offset ", bad.display())) && err.contains("CRC-32"),
        "{err}"
    );
    let run = bin()
        .args(["run", "--config"])
        .arg(&c)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains(&at), "{}", stderr(&run));
}

/// `crowdtouch run` with its stderr collected.
struct Running {
    child: Child,
    log: Arc<Mutex<Vec<String>>>,
}

impl Running {
    fn start(cfg: &Path, sock: &Path) -> Running {
        let mut child = bin()
            .args(["run", "--config"])
            .arg(cfg)
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
        while UnixStream::connect(sock).is_err() && t0.elapsed() < WAIT {
            std::thread::sleep(Duration::from_millis(20));
        }
        Running { child, log }
    }

    fn signal(&self, sig: nix::sys::signal::Signal) {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        nix::sys::signal::kill(pid, sig).unwrap();
    }

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

    fn stop(mut self) {
        self.signal(nix::sys::signal::Signal::SIGTERM);
        let status = self.child.wait().unwrap();
        assert!(status.success(), "{:?}", self.log.lock().unwrap());
    }
}

/// The next `gesture` end event with a recognition, from a fresh connection.
fn next_recognition(sock: &Path) -> Value {
    let stream = UnixStream::connect(sock).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    let mut r = BufReader::new(stream);
    let t0 = Instant::now();
    let mut line = String::new();
    while t0.elapsed() < WAIT {
        match r.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) if line.ends_with('\n') => {
                let v: Value = serde_json::from_str(&line).unwrap();
                line.clear();
                if v["type"] == "gesture" && v["phase"] == "end" && !v["recognition"].is_null() {
                    return v;
                }
            }
            _ => {}
        }
    }
    panic!("no recognised gesture in {WAIT:?}");
}

#[test]
fn a_library_corrupted_under_a_running_daemon_is_refused_and_the_old_one_kept() {
    let dir = tempfile::tempdir().unwrap();
    let lib = dir.path().join("mine.ctgl");
    std::fs::write(&lib, SHIPPED_BYTES).unwrap();
    let c = config(
        dir.path(),
        &[("library: None,", "library: Some(\"mine.ctgl\"),")],
    );
    let sock = dir.path().join("ct.sock");
    let d = Running::start(&c, &sock);
    let before = next_recognition(&sock);
    assert_eq!(before["recognition"]["class"], "translate", "{before}");
    std::fs::write(&lib, corrupt()).unwrap();
    let from = d.log.lock().unwrap().len();
    d.signal(nix::sys::signal::Signal::SIGHUP);
    d.wait_line(from, "SIGHUP: new config rejected");
    let log = d.log.lock().unwrap()[from..].join("\n");
    assert!(
        log.contains("gestures.library") && log.contains(&lib.display().to_string()),
        "{log}"
    );
    // The running library still recognises the looped swipe.
    let after = next_recognition(&sock);
    assert_eq!(after["recognition"]["class"], "translate", "{after}");
    d.stop();
}
