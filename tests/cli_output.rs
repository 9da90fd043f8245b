//! Output that cannot be written: every command that prints, with stdout or stderr
//! on a full device (`/dev/full`) or on a pipe whose reader has gone. A broken pipe
//! ends the command quietly with status 0 (a command that had failed keeps its
//! status); any other write error gives one `crowdtouch: error:` line and status 1;
//! nothing panics (status 101), and the daemon's socket file never outlives it.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

/// A writer on `/dev/full`: every write fails with `ENOSPC`.
fn full() -> Stdio {
    Stdio::from(
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap(),
    )
}

/// The write end of a pipe whose read end is already closed: every write fails with
/// `EPIPE`.
fn closed_pipe() -> Stdio {
    let (r, w) = nix::unistd::pipe().unwrap();
    drop(r);
    Stdio::from(w)
}

/// Two handles on one closed pipe, for `2>&1 | true`.
fn closed_pipe_pair() -> (Stdio, Stdio) {
    let (r, w) = nix::unistd::pipe().unwrap();
    drop(r);
    let w2 = w.try_clone().unwrap();
    (Stdio::from(w), Stdio::from(w2))
}

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn assert_no_panic(what: &str, out: &Output) {
    let err = stderr_of(out);
    assert!(
        out.status.code() != Some(101) && !err.contains("panicked"),
        "{what}: {:?}\n{err}",
        out.status
    );
}

/// The commands that print to stdout, each as it is run.
struct Printing {
    dir: tempfile::TempDir,
}

impl Printing {
    fn new() -> Printing {
        Printing {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    fn ok_config(&self) -> PathBuf {
        let p = self.dir.path().join("ok.ron");
        std::fs::write(&p, crowdtouch::config::DEFAULT_CONFIG_RON).unwrap();
        p
    }

    fn commands(&self) -> Vec<(&'static str, Command)> {
        let rec = common::shipped("01-point-drag.jsonl");
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/corridor.ron");
        let desc = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/atmel-maxtouch.desc");
        let d = self.dir.path();
        let cmd = |args: &[&std::ffi::OsStr]| {
            let mut c = bin();
            c.args(args);
            c
        };
        let s = |x: &'static str| std::ffi::OsStr::new(x);
        vec![
            ("--help", cmd(&[s("--help")])),
            (
                "check-config",
                cmd(&[s("check-config"), self.ok_config().as_os_str()]),
            ),
            ("replay", cmd(&[s("replay"), rec.as_os_str()])),
            (
                "replay --frames",
                cmd(&[s("replay"), s("--frames"), rec.as_os_str()]),
            ),
            (
                "synth-recordings",
                cmd(&[s("synth-recordings"), s("--out"), d.join("rec").as_os_str()]),
            ),
            ("formations", cmd(&[s("formations")])),
            (
                "scene check",
                cmd(&[s("scene"), s("check"), scene.as_os_str()]),
            ),
            (
                "scene render",
                cmd(&[
                    s("scene"),
                    s("render"),
                    scene.as_os_str(),
                    s("-o"),
                    d.join("s.svg").as_os_str(),
                    s("--cell-m"),
                    s("0.25"),
                ]),
            ),
            (
                "hid describe",
                cmd(&[s("hid"), s("describe"), desc.as_os_str()]),
            ),
            ("devices", cmd(&[s("devices")])),
        ]
    }
}

#[test]
fn a_full_stdout_is_one_error_line_and_status_1() {
    let p = Printing::new();
    for (what, mut c) in p.commands() {
        let out = c
            .env("CROWDTOUCH_CONFIG", "/nonexistent")
            .stdout(full())
            .output()
            .unwrap();
        assert_no_panic(what, &out);
        assert_eq!(out.status.code(), Some(1), "{what}: {}", stderr_of(&out));
        let err = stderr_of(&out);
        let last = err.lines().last().unwrap_or_default();
        assert!(
            last.starts_with("crowdtouch: error: ")
                && last.ends_with(": No space left on device (os error 28)"),
            "{what}: {err}"
        );
    }
}

#[test]
fn a_reader_that_went_away_ends_the_command_quietly_with_status_0() {
    let p = Printing::new();
    for (what, mut c) in p.commands() {
        let out = c
            .env("CROWDTOUCH_CONFIG", "/nonexistent")
            .stdout(closed_pipe())
            .output()
            .unwrap();
        assert_no_panic(what, &out);
        assert_eq!(out.status.code(), Some(0), "{what}: {}", stderr_of(&out));
        assert_eq!(stderr_of(&out), "", "{what}");
    }
}

fn bad_config(dir: &Path) -> PathBuf {
    let p = dir.join("bad.ron");
    std::fs::write(
        &p,
        crowdtouch::config::DEFAULT_CONFIG_RON.replacen("agents: 100", "agents: 0", 1),
    )
    .unwrap();
    p
}

/// The shipped point drag with line 6 cut in half.
fn corrupt_recording(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(common::shipped("01-point-drag.jsonl")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let l = lines[5].clone();
    lines[5] = l[..l.len() / 2].to_string();
    let p = dir.join("bad.jsonl");
    std::fs::write(&p, lines.join("\n") + "\n").unwrap();
    p
}

#[test]
fn errors_and_warnings_that_cannot_be_written_keep_the_commands_status() {
    let dir = tempfile::tempdir().unwrap();
    let ok = Printing::new();
    let bad = bad_config(dir.path());
    let check = |file: &Path, stderr: Stdio| {
        bin()
            .arg("check-config")
            .arg(file)
            .stdout(Stdio::null())
            .stderr(stderr)
            .output()
            .unwrap()
    };
    // A valid config writes nothing on stderr; an invalid one fails whether or not
    // its errors could be written.
    assert_eq!(check(&ok.ok_config(), full()).status.code(), Some(0));
    assert_eq!(check(&bad, full()).status.code(), Some(1));
    assert_eq!(check(&bad, closed_pipe()).status.code(), Some(1));
    let scene_bad = dir.path().join("scene.ron");
    std::fs::write(&scene_bad, "(version: 1,, )").unwrap();
    let out = bin()
        .args(["scene", "check"])
        .arg(&scene_bad)
        .stderr(closed_pipe())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));

    // `replay --skip-bad-frames FILE 2>&1 | true`: both streams on the gone reader.
    let rec = corrupt_recording(dir.path());
    let (o, e) = closed_pipe_pair();
    let out = bin()
        .args(["replay", "--skip-bad-frames"])
        .arg(&rec)
        .stdout(o)
        .stderr(e)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    // Its warning on a full stderr: the replay stops (the warning is lost), status 1.
    let out = bin()
        .args(["replay", "--skip-bad-frames"])
        .arg(&rec)
        .stdout(Stdio::null())
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
}

/// Waits for a child for up to `limit` ("does not hang" bound, not a timing).
fn wait_for(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let t0 = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("the daemon did not exit within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn wait_for_socket(sock: &Path, child: &mut Child) {
    let t0 = Instant::now();
    // The file appears at bind(), a moment before listen(): wait until a client
    // can connect.
    while std::os::unix::net::UnixStream::connect(sock).is_err() {
        if let Some(s) = child.try_wait().unwrap() {
            panic!("the daemon exited before making its socket: {s:?}");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the daemon made no socket in 60 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn demo_stops_and_removes_its_socket_when_its_status_lines_cannot_be_written() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("demo.sock");
    let demo = |stdout: Stdio, stderr: Stdio| {
        bin()
            .args(["demo", "--agents", "50", "--seconds", "30", "--socket"])
            .arg(&sock)
            .stdout(stdout)
            .stderr(stderr)
            .spawn()
            .unwrap()
    };
    // `demo >/dev/full`: the first line fails.
    let mut child = demo(full(), Stdio::piped());
    let status = wait_for(&mut child, Duration::from_secs(60));
    let out = child.wait_with_output().unwrap();
    assert_eq!(status.code(), Some(1));
    assert!(
        stderr_of(&out)
            .contains("crowdtouch: error: cannot write to stdout: No space left on device"),
        "{}",
        stderr_of(&out)
    );
    assert!(!sock.exists(), "demo >/dev/full left its socket behind");
    // `demo | true`.
    let mut child = demo(closed_pipe(), Stdio::null());
    assert_eq!(
        wait_for(&mut child, Duration::from_secs(60)).code(),
        Some(0)
    );
    assert!(!sock.exists(), "demo | true left its socket behind");
}

#[test]
fn the_daemon_keeps_running_when_its_log_cannot_be_written_and_cleans_up_on_signals() {
    use nix::sys::signal::{kill, Signal};
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("run.sock");
    let cfg = dir.path().join("c.ron");
    std::fs::write(&cfg, crowdtouch::config::DEFAULT_CONFIG_RON).unwrap();
    let run = ["run", "--config", cfg.to_str().unwrap()];
    let demo = ["demo", "--agents", "50"];
    for (args, stderr, signal) in [
        (run, full(), Signal::SIGTERM),
        (run, closed_pipe(), Signal::SIGINT),
        (demo, full(), Signal::SIGINT),
        (demo, closed_pipe(), Signal::SIGTERM),
    ] {
        let mut child = bin()
            .args(args)
            .arg("--socket")
            .arg(&sock)
            .stdout(Stdio::null())
            .stderr(stderr)
            .spawn()
            .unwrap();
        wait_for_socket(&sock, &mut child);
        // It serves: a client gets its hello although no log line can be written.
        let mut hello = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(std::os::unix::net::UnixStream::connect(&sock).unwrap()),
            &mut hello,
        )
        .unwrap();
        assert!(hello.contains("\"hello\""), "{hello}");
        kill(nix::unistd::Pid::from_raw(child.id() as i32), signal).unwrap();
        assert_eq!(
            wait_for(&mut child, Duration::from_secs(30)).code(),
            Some(0),
            "{} {signal:?}",
            args[0]
        );
        assert!(!sock.exists(), "the socket outlived {} {signal:?}", args[0]);
    }
}

#[test]
fn run_refuses_a_bad_recording_before_it_makes_a_socket() {
    let dir = tempfile::tempdir().unwrap();
    let rec = corrupt_recording(dir.path());
    let base = crowdtouch::config::DEFAULT_CONFIG_RON;
    let a = base.find("inputs: [").unwrap();
    let b = a + base[a..].find("\n    ],\n").unwrap() + "\n    ],\n".len();
    let cfg = dir.path().join("c.ron");
    std::fs::write(
        &cfg,
        format!(
            "{}inputs: [Replay(files: [{:?}])],\n{}",
            &base[..a],
            rec.display().to_string(),
            &base[b..]
        ),
    )
    .unwrap();
    let sock = dir.path().join("run.sock");
    let out = bin()
        .args(["run", "--config"])
        .arg(&cfg)
        .arg("--socket")
        .arg(&sock)
        .output()
        .unwrap();
    assert_no_panic("run", &out);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr_of(&out).contains("bad.jsonl:6:"),
        "{}",
        stderr_of(&out)
    );
    assert!(!sock.exists());
}
