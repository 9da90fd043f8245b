//! `check-config` finds what `run` refuses, at the field it comes from, in the
//! words a user reads: one test per gap the probe found (issue 14, item 6).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const DEFAULT: &str = crowdtouch::config::DEFAULT_CONFIG_RON;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

/// The default config with `from` replaced by `to`, written as `c.ron` in `dir`.
/// Its socket is `dir/ct.sock` unless `from` is the socket path: the default one
/// may be another daemon's.
fn config(dir: &Path, from: &str, to: &str) -> PathBuf {
    assert!(DEFAULT.contains(from), "{from}");
    let mut text = DEFAULT.replacen(from, to, 1);
    if from != "path: None," {
        let sock = dir.join("ct.sock").display().to_string();
        text = text.replacen("path: None,", &format!("path: Some({sock:?}),"), 1);
    }
    let p = dir.join("c.ron");
    std::fs::write(&p, text).unwrap();
    p
}

/// `file:line:col` of the first line of `file` holding `needle`, at the needle.
fn place(file: &Path, needle: &str) -> String {
    let text = std::fs::read_to_string(file).unwrap();
    let (n, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.contains(needle))
        .unwrap();
    format!(
        "{}:{}:{}",
        file.display(),
        n + 1,
        line.find(needle).unwrap() + 1
    )
}

fn check(file: &Path) -> Output {
    bin().arg("check-config").arg(file).output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// check-config fails with exactly `expected` (one line), and `run` refuses the
/// config with the same line.
fn refused_by_both(file: &Path, expected: &str) {
    let out = check(file);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert_eq!(stderr(&out), format!("{expected}\n"));
    assert!(out.stdout.is_empty());
    let run = bin()
        .args(["run", "--config"])
        .arg(file)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(
        stderr(&run).contains(&format!("the config cannot be run:\n{expected}\n")),
        "{}",
        stderr(&run)
    );
}

#[test]
fn a_missing_socket_directory_is_refused_at_socket_path() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("missing/ct.sock");
    let c = config(
        dir.path(),
        "path: None,",
        &format!("path: Some({:?}),", sock.display().to_string()),
    );
    refused_by_both(
        &c,
        &format!(
            "{}: field `socket.path`: {}: the socket's directory {} does not exist",
            place(&c, "path: Some"),
            sock.display(),
            dir.path().join("missing").display()
        ),
    );
}

#[test]
fn an_unknown_socket_group_is_refused_at_socket_group() {
    let dir = tempfile::tempdir().unwrap();
    let c = config(
        dir.path(),
        "group: None,",
        "group: Some(\"no-such-group-ct14\"),",
    );
    refused_by_both(
        &c,
        &format!(
            "{}: field `socket.group`: socket group `no-such-group-ct14` does not exist (config socket.group)",
            place(&c, "group: Some")
        ),
    );
}

#[test]
fn a_socket_path_longer_than_a_socket_address_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sock = format!("{}/{}.sock", dir.path().display(), "x".repeat(120));
    let c = config(dir.path(), "path: None,", &format!("path: Some({sock:?}),"));
    refused_by_both(
        &c,
        &format!(
            "{}: field `socket.path`: {sock}: socket path is {} bytes, more than the 107 a Unix socket address holds",
            place(&c, "path: Some"),
            sock.len()
        ),
    );
}

#[test]
fn a_file_or_directory_at_the_socket_path_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("ct.sock");
    let c = config(
        dir.path(),
        "path: None,",
        &format!("path: Some({:?}),", sock.display().to_string()),
    );
    for (make, kind) in [
        (
            Box::new(|p: &Path| std::fs::write(p, "x").unwrap()) as Box<dyn Fn(&Path)>,
            "a regular file",
        ),
        (
            Box::new(|p: &Path| std::fs::create_dir(p).unwrap()),
            "a directory",
        ),
    ] {
        make(&sock);
        refused_by_both(
            &c,
            &format!(
                "{}: field `socket.path`: {}: is {kind}, not a socket; refusing to replace it",
                place(&c, "path: Some"),
                sock.display()
            ),
        );
        // Left as it was.
        assert!(sock.exists());
        let _ = std::fs::remove_file(&sock);
        let _ = std::fs::remove_dir(&sock);
    }
}

#[test]
fn a_missing_recording_is_refused_at_its_entry() {
    let dir = tempfile::tempdir().unwrap();
    let c = config(
        dir.path(),
        "\"recordings/02-line-drag.jsonl\"",
        "\"recordings/no-such-recording.jsonl\"",
    );
    let missing = dir.path().join("recordings/no-such-recording.jsonl");
    let expected = format!(
        "{}: field `inputs[0].files[1]`: recording not usable: {}: cannot read: No such file or directory (os error 2)",
        place(&c, "\"recordings/no-such"),
        missing.display()
    );
    let out = check(&c);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(stderr(&out), format!("{expected}\n"));
    // `run` refuses it as it reads the recordings, with the same words, once.
    let run = bin()
        .args(["run", "--config"])
        .arg(&c)
        .arg("--socket")
        .arg(dir.path().join("r.sock"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(
        stderr(&run).ends_with(&format!(
            "crowdtouch: error: {}: cannot read: No such file or directory (os error 2)\n",
            missing.display()
        )),
        "{}",
        stderr(&run)
    );
}

#[test]
fn input_cpus_this_machine_lacks_are_a_located_warning() {
    let online = crowdtouch::pipeline::online_cpus().expect("/sys lists the online CPUs");
    let cpu = (0..1024).rev().find(|c| !online.contains(c)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let c = config(
        dir.path(),
        "lock_memory: true,",
        &format!("lock_memory: true,\n            input_cpus: Some([{cpu}]),"),
    );
    let out = check(&c);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let err = stderr(&out);
    let prefix = format!(
        "{}: field `pipeline.realtime.input_cpus[0]`: warning: CPU {cpu} is not online on this machine (online: ",
        place(&c, &format!("{cpu}]"))
    );
    assert!(
        err.starts_with(&prefix)
            && err.ends_with("); none of the listed CPUs is, so the input thread is not pinned (it runs on any CPU)\n")
            && err.lines().count() == 1,
        "{err}"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains(": ok ("));
    // `run` starts, and logs the same warning.
    let sock = dir.path().join("ct.sock");
    let mut child = bin()
        .args(["run", "--config"])
        .arg(&c)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !sock.exists() && child.try_wait().unwrap().is_none() {
        assert!(t0.elapsed().as_secs() < 60, "run made no socket in 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGTERM,
    )
    .unwrap();
    let run = child.wait_with_output().unwrap();
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let warning = err.trim_end();
    assert!(
        stderr(&run).lines().any(|l| l.ends_with(warning)),
        "{}",
        stderr(&run)
    );
    // A number no CPU set holds is an error.
    let c = config(
        dir.path(),
        "lock_memory: true,",
        "lock_memory: true,\n            input_cpus: Some([0, 5000]),",
    );
    let out = check(&c);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out),
        format!(
            "{}: field `pipeline.realtime.input_cpus[1]`: CPU 5000 is not a CPU number: Linux numbers CPUs 0..1024\n",
            place(&c, "5000])")
        )
    );
}

#[test]
fn a_negative_or_fractional_count_says_what_was_written() {
    let dir = tempfile::tempdir().unwrap();
    for (value, words) in [
        ("-5", "expected a whole number of 0 or more, found -5"),
        ("1.5", "expected a whole number, found 1.5"),
    ] {
        let c = config(dir.path(), "agents: 100,", &format!("agents: {value},"));
        let out = check(&c);
        assert_eq!(out.status.code(), Some(1));
        assert_eq!(
            stderr(&out),
            format!(
                "{}: field `crowd.agents`: {words}\n",
                place(&c, &format!("{value},"))
            )
        );
    }
}

#[test]
fn a_field_given_twice_is_named_once_at_its_second_place() {
    let dir = tempfile::tempdir().unwrap();
    let c = config(
        dir.path(),
        "agents: 100,",
        "agents: 100,\n        agents: 7,",
    );
    let first = place(&c, "agents: 100");
    let first_line = first.split(':').nth(1).unwrap();
    let out = check(&c);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out),
        format!(
            "{}: field `crowd.agents`: `agents` is given twice (first on line {first_line})\n",
            place(&c, "agents: 7")
        )
    );
}

#[test]
fn run_writes_an_os_error_once() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.ron");
    let out = bin()
        .args(["run", "--config"])
        .arg(&missing)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out),
        format!(
            "crowdtouch: error: {}: cannot read config: No such file or directory (os error 2)\n",
            missing.display()
        )
    );
}

#[test]
fn a_daemon_on_the_socket_is_a_warning_for_check_config_and_refused_by_run() {
    let dir = tempfile::tempdir().unwrap();
    let c = config(dir.path(), "agents: 100,", "agents: 100,");
    let sock = dir.path().join("ct.sock");
    let _live = std::os::unix::net::UnixListener::bind(&sock).unwrap();
    let line = format!(
        "{}: field `socket.path`: {}: another process is already listening on this socket (is crowdtouch already running?); `run` refuses to start while it listens",
        place(&c, "path: Some"),
        sock.display()
    );
    // Checking a config while its daemon runs (before a reload) is normal.
    let out = check(&c);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        line.replacen("`socket.path`: ", "`socket.path`: warning: ", 1) + "\n"
    );
    let run = bin()
        .args(["run", "--config"])
        .arg(&c)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(
        stderr(&run).contains(&format!("the config cannot be run:\n{line}\n")),
        "{}",
        stderr(&run)
    );
    assert!(sock.exists(), "the live socket was left alone");
}

#[test]
fn a_systemd_runtime_directory_not_created_yet_is_a_warning_for_check_config() {
    let dir = tempfile::tempdir().unwrap();
    let c = dir.path().join("c.ron");
    std::fs::write(&c, DEFAULT).unwrap();
    let rundir = dir.path().join("run/crowdtouch");
    let sock = rundir.join("crowdtouch.sock");
    let line = format!(
        "{}: field `socket.path`: {}: the socket's directory {} does not exist (`path: None` resolves to this path here); systemd creates $RUNTIME_DIRECTORY when it starts the service",
        place(&c, "path: None"),
        sock.display(),
        rundir.display()
    );
    let out = bin()
        .arg("check-config")
        .arg(&c)
        .env("RUNTIME_DIRECTORY", &rundir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        line.replacen("`socket.path`: ", "`socket.path`: warning: ", 1) + "\n"
    );
    // `run` in that environment cannot bind there.
    let run = bin()
        .args(["run", "--config"])
        .arg(&c)
        .env("RUNTIME_DIRECTORY", &rundir)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains(&line), "{}", stderr(&run));
}
