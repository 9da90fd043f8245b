//! `check-config` finds what `run` refuses, at the field it comes from, in the
//! words a user reads: one test per gap the probe found (issue 14, item 6).

mod common;

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

/// The top-level fields of a config, in the order of the documented default.
const TOP_LEVEL: [&str; 15] = [
    "version",
    "log_level",
    "inputs",
    "surface",
    "crowd",
    "mesh",
    "controls",
    "assignment",
    "scene",
    "formations",
    "gestures",
    "edit",
    "pipeline",
    "socket",
    "outputs",
];

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every daemon config shipped under `config/` (scenes and formation shapes are
/// other files: a daemon config has top-level `inputs` and `socket`).
fn shipped_configs() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "ron") {
                let text = std::fs::read_to_string(&p).unwrap();
                let top = |k: &str| text.lines().any(|l| l.starts_with(&format!("    {k}:")));
                if top("inputs") && top("socket") {
                    out.push(p);
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(&repo().join("config"), &mut out);
    out.sort();
    out
}

/// The end (exclusive) of the RON value starting at `text[start..]`: a bracketed
/// value to its matching bracket, anything else to the end of its line; strings
/// and `//` comments are skipped.
fn value_end(text: &str, start: usize) -> usize {
    let b = text.as_bytes();
    if !matches!(b[start], b'(' | b'[') {
        return start + text[start..].find('\n').unwrap();
    }
    let (mut depth, mut i) = (0usize, start);
    loop {
        match b[i] {
            b'"' => {
                i += 1;
                while b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
            }
            b'/' if b[i + 1] == b'/' => i += text[i..].find('\n').unwrap(),
            b'(' | b'[' => depth += 1,
            b')' | b']' => {
                depth -= 1;
                if depth == 0 {
                    return i + 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
}

/// The documented default with each top-level entry of `fragment` (`inputs: [...],`
/// at column 0) in place of its own, or added at the end.
fn splice(fragment: &[(String, String)]) -> String {
    let mut text = DEFAULT.to_string();
    for (key, entry) in fragment {
        let mut entry: String = entry
            .trim_end()
            .lines()
            .map(|l| format!("    {l}\n"))
            .collect();
        if !entry.trim_end().ends_with(',') {
            entry = format!("{},\n", entry.trim_end());
        }
        match text.find(&format!("\n    {key}: ")) {
            Some(i) => {
                let value = i + 1 + 4 + key.len() + 2;
                let mut end = value_end(&text, value);
                end += usize::from(text[end..].starts_with(','));
                end += usize::from(text[end..].starts_with('\n'));
                text.replace_range(i + 1..end, &entry);
            }
            None => {
                let close = text.rfind("\n)").unwrap();
                text.insert_str(close + 1, &entry);
            }
        }
    }
    text
}

/// Every config the docs show (`docs/*.md`, `README.md`), as a whole file: a
/// fenced RON block that is a whole config as it is, and one made of top-level
/// config entries (`outputs: [...]`) in the documented default. Other RON blocks
/// (edit scripts, scenes) are left out. Named `file:line`.
fn documented_configs() -> Vec<(String, String)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    files.sort();
    files.push(repo().join("README.md"));
    let mut out = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let mut i = 0;
        while i < lines.len() {
            if lines[i].trim() != "```ron" {
                i += 1;
                continue;
            }
            let first = i + 2;
            let mut block = String::new();
            i += 1;
            while lines[i].trim() != "```" {
                block.push_str(lines[i]);
                block.push('\n');
                i += 1;
            }
            let name = format!("{}:{first}", f.strip_prefix(repo()).unwrap().display());
            let code: Vec<&str> = block
                .lines()
                .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with("//"))
                .collect();
            if code.first() == Some(&"(") && block.lines().any(|l| l.starts_with("    version:")) {
                out.push((name, block));
                continue;
            }
            // Top-level entries: a line at column 0 naming a config field.
            let mut entries: Vec<(String, String)> = Vec::new();
            let mut whole = true;
            for l in block.lines() {
                let note = l.trim().is_empty() || l.trim_start().starts_with("//");
                let key = l.split_once(':').map(|(k, _)| k).filter(|k| {
                    !k.is_empty() && k.chars().all(|c| c.is_ascii_lowercase() || c == '_')
                });
                match key {
                    Some(k) if TOP_LEVEL.contains(&k) => {
                        entries.push((k.to_string(), String::new()))
                    }
                    _ if !note
                        && l.starts_with(|c: char| !c.is_whitespace() && c != ']' && c != ')') =>
                    {
                        whole = false;
                    }
                    _ => {}
                }
                match entries.last_mut() {
                    Some((_, e)) => {
                        e.push_str(l);
                        e.push('\n');
                    }
                    None if note => {}
                    None => whole = false,
                }
            }
            if whole && !entries.is_empty() {
                out.push((name, splice(&entries)));
            }
        }
    }
    out
}

/// A configuration's verdicts: `check-config`'s and `run`'s start-up.
#[derive(Debug)]
struct Verdicts {
    name: String,
    check_ok: bool,
    run_ok: bool,
    said: String,
}

fn verdicts(env: &common::run_process::Env, name: &str, file: &Path) -> Verdicts {
    let check = env.check_config(file);
    let check_ok = match check.status.code() {
        Some(0) => true,
        Some(1) => false,
        other => panic!("{name}: check-config exit {other:?}: {}", stderr(&check)),
    };
    let stdout = String::from_utf8_lossy(&check.stdout).into_owned();
    let (run_ok, log) = match env.run(file) {
        Ok(running) => {
            let (status, log) = running.stop();
            assert!(
                status.success(),
                "{name}: run stopped with {status}:\n{log}"
            );
            (true, log)
        }
        Err((code, log)) => {
            assert_eq!(code, Some(1), "{name}: run exit {code:?}:\n{log}");
            (false, log)
        }
    };
    if check_ok && run_ok {
        // Where touches come from, in the same words.
        for line in stdout.lines().skip(1) {
            assert!(
                log.lines().any(|l| l.ends_with(line)),
                "{name}: check-config said {line:?}, run did not:\n{log}"
            );
        }
    }
    Verdicts {
        name: name.to_string(),
        check_ok,
        run_ok,
        said: format!("check-config:\n{stdout}{}\nrun:\n{log}", stderr(&check)),
    }
}

/// Every daemon config shipped under `config/` and every config the docs show
/// goes through `check-config` and `run` (the binary, as a user runs it: `run`
/// until it serves its socket, then SIGTERM): both accept it, and they say in the
/// same words where its touches come from. A config both refuse shows that a
/// refusal is told apart.
#[test]
fn every_shipped_and_documented_config_gets_the_same_verdict_from_check_config_and_run() {
    use common::run_process::{free_listen_ports, Env};
    let env = Env::new();
    let mut cases: Vec<(String, PathBuf)> = Vec::new();
    for f in shipped_configs() {
        let name = f.strip_prefix(repo()).unwrap().display().to_string();
        let text = std::fs::read_to_string(&f).unwrap();
        let freed = free_listen_ports(&text);
        if freed == text {
            cases.push((name, f));
        } else {
            // Its listeners on free ports; beside it in a directory of the test's
            // (the shipped recordings it names are also in the binary).
            let copy = env.path().join(f.file_name().unwrap());
            std::fs::write(&copy, freed).unwrap();
            cases.push((name, copy));
        }
    }
    let shipped: Vec<String> = cases.iter().map(|(n, _)| n.clone()).collect();
    for want in [
        "config/crowdtouch.ron",
        "config/kiosk.ron",
        "config/no-device.ron",
    ] {
        assert!(
            shipped.iter().any(|n| n == want),
            "{want} not in {shipped:?}"
        );
    }
    let documented = documented_configs();
    assert!(
        documented
            .iter()
            .any(|(n, t)| n.starts_with("docs/devices.md:") && t.contains("    inputs: [],")),
        "the devices doc's table with no touch device is among {:?}",
        documented.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    assert!(documented.len() >= 9, "{}", documented.len());
    for (k, (name, text)) in documented.into_iter().enumerate() {
        let file = env.path().join(format!("documented-{k}.ron"));
        std::fs::write(&file, free_listen_ports(&text)).unwrap();
        cases.push((name, file));
    }
    let refused = env.path().join("refused.ron");
    std::fs::write(
        &refused,
        DEFAULT.replacen(
            "recordings/02-line-drag.jsonl",
            "recordings/no-such.jsonl",
            1,
        ),
    )
    .unwrap();
    let mut all = Vec::new();
    for (name, file) in &cases {
        all.push(verdicts(&env, name, file));
    }
    let broken = verdicts(&env, "a missing recording", &refused);
    assert!(!broken.check_ok && !broken.run_ok, "{broken:#?}");
    for v in &all {
        assert_eq!(
            v.check_ok, v.run_ok,
            "{}: verdicts differ\n{}",
            v.name, v.said
        );
        assert!(v.check_ok, "{}: refused\n{}", v.name, v.said);
    }
}
