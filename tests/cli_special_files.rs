//! Issue 27, finding 2: the commands that read a file a person names refuse a
//! device, a FIFO and a directory at once with a clear message, instead of reading
//! `/dev/zero` until memory is gone or waiting on a FIFO for ever.
//!
//! Each command must exit with status 1 having used at most a second of CPU more
//! than the same command reporting a missing file (its start-up — the config, the
//! gesture library — is slow in a debug build; wall-clock time on a busy
//! two-core machine says little), and at most [`MAX_RSS_KB`] of memory; one that
//! goes over, or is still running long after the missing file was reported (a
//! FIFO it waits on uses no CPU), is killed and the test fails.

use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// How much more CPU than reporting a missing file a refusal may take (the
/// issue's bound of a second).
const LIMIT: Duration = Duration::from_secs(1);

/// The most memory a refusing command may hold (kB): far below what reading
/// `/dev/zero` reaches in a second (about 1 GB).
const MAX_RSS_KB: u64 = 400_000;

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/crowd/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// CPU time (user + system) and resident memory (kB) of a running child, from
/// `/proc/PID/stat` and `/proc/PID/status`; `None` once it is gone.
fn usage(child: &Child) -> Option<(Duration, u64)> {
    let stat = std::fs::read_to_string(format!("/proc/{}/stat", child.id())).ok()?;
    // Fields after the command name in parentheses: state is field 3; utime and
    // stime are fields 14 and 15, in clock ticks (100 a second on Linux).
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    let status = std::fs::read_to_string(format!("/proc/{}/status", child.id())).ok()?;
    let rss = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0);
    Some((Duration::from_millis(ticks * 10), rss))
}

/// Runs `crowdtouch args…` (embedded default config, `home` as HOME) until it
/// exits: its status, stderr, wall and CPU time (the last reading before it
/// exited); `Err` with why when it went over `cpu_limit`, [`MAX_RSS_KB`] or
/// `wall_limit` and was killed.
fn run(
    home: &Path,
    args: &[&str],
    cpu_limit: Duration,
    wall_limit: Duration,
) -> Result<(ExitStatus, String, Duration, Duration), String> {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(args)
        .env("HOME", home)
        .env("XDG_CONFIG_HOME", home)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut cpu = Duration::ZERO;
    let status = loop {
        if let Some((c, rss)) = usage(&child) {
            cpu = cpu.max(c);
            let over = if c > cpu_limit {
                Some(format!("used {c:?} of CPU"))
            } else if rss > MAX_RSS_KB {
                Some(format!("held {rss} kB"))
            } else if start.elapsed() > wall_limit {
                Some(format!("still running after {:?}", start.elapsed()))
            } else {
                None
            };
            if let Some(why) = over {
                let _ = child.kill();
                let _ = child.wait();
                return Err(why);
            }
        }
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = start.elapsed();
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    Ok((status, err, took, cpu))
}

/// Runs `crowdtouch args…` with `file` in place of `{}`, and returns its stderr
/// once it exited with status 1 within [`LIMIT`] of CPU more than the same command
/// given a missing file; kills it and fails otherwise.
fn refused_in_time(home: &Path, args: &[&str], file: &str) -> String {
    let with = |f: &str| -> Vec<String> {
        args.iter()
            .map(|a| {
                if *a == "{}" {
                    f.to_string()
                } else {
                    a.to_string()
                }
            })
            .collect()
    };
    let missing = home.join("missing-file");
    let base_args = with(&missing.display().to_string());
    let base_args: Vec<&str> = base_args.iter().map(String::as_str).collect();
    let forever = Duration::from_secs(120);
    let (status, err, base_wall, base_cpu) =
        run(home, &base_args, forever, forever).expect("a missing file is reported");
    assert_eq!(status.code(), Some(1), "{err}");
    let args = with(file);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let shown = args.join(" ");
    let (status, err, took, cpu) = run(
        home,
        &args,
        base_cpu + LIMIT,
        4 * base_wall + Duration::from_secs(10),
    )
    .unwrap_or_else(|why| {
        panic!("`crowdtouch {shown}` {why} (a missing file: {base_wall:?}, {base_cpu:?} of CPU)")
    });
    assert_eq!(status.code(), Some(1), "`{shown}`: {err}");
    assert!(err.starts_with("crowdtouch: error:"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    eprintln!(
        "`crowdtouch {shown}`: refused in {took:?}, {cpu:?} of CPU (a missing file: {base_wall:?}, {base_cpu:?})"
    );
    err
}

fn mkfifo(p: &Path) {
    let ok = Command::new("mkfifo").arg(p).status().unwrap().success();
    assert!(ok, "mkfifo {}", p.display());
}

#[test]
fn edit_check_refuses_dev_zero_a_fifo_and_a_directory() {
    let home = tempfile::tempdir().unwrap();
    let fifo = home.path().join("tracks.csv");
    mkfifo(&fifo);
    let fifo = fifo.display().to_string();
    let dir = home.path().display().to_string();
    for (file, what) in [
        ("/dev/zero", "is a character device, not a regular file"),
        (fifo.as_str(), "is a FIFO, not a regular file"),
        (dir.as_str(), "is a directory, not a regular file"),
    ] {
        let err = refused_in_time(home.path(), &["edit", "check", "{}"], file);
        assert!(err.contains(&format!("{file}: {what}")), "{err}");
    }
}

#[test]
fn edit_apply_refuses_ops_from_dev_zero_and_a_fifo() {
    let home = tempfile::tempdir().unwrap();
    let fifo = home.path().join("ops.ron");
    mkfifo(&fifo);
    let fifo = fifo.display().to_string();
    let out = home.path().join("x.jsonl").display().to_string();
    let tracks = fixture("crowds_zara01.txt");
    for (file, what) in [
        ("/dev/zero", "is a character device"),
        (fifo.as_str(), "is a FIFO"),
    ] {
        let err = refused_in_time(
            home.path(),
            &["edit", "apply", &tracks, "--ops", "{}", "-o", &out],
            file,
        );
        assert!(err.contains(&format!("{file}: {what}")), "{err}");
        assert!(!Path::new(&out).exists());
    }
}

#[test]
fn transform_refuses_a_formation_from_dev_zero_and_a_fifo() {
    let home = tempfile::tempdir().unwrap();
    let fifo = home.path().join("shape.png");
    mkfifo(&fifo);
    let fifo = fifo.display().to_string();
    for (file, what) in [
        ("/dev/zero", "is a character device"),
        (fifo.as_str(), "is a FIFO"),
    ] {
        let err = refused_in_time(
            home.path(),
            &[
                "transform",
                "--from",
                "square",
                "--to",
                "{}",
                "--agents",
                "20",
            ],
            file,
        );
        assert!(err.contains(&format!("{file}: {what}")), "{err}");
    }
}

#[test]
fn gesture_classify_refuses_dev_zero_and_a_fifo() {
    let home = tempfile::tempdir().unwrap();
    let fifo = home.path().join("rec.jsonl");
    mkfifo(&fifo);
    let fifo = fifo.display().to_string();
    for (file, what) in [
        ("/dev/zero", "is a character device"),
        (fifo.as_str(), "is a FIFO"),
    ] {
        let err = refused_in_time(home.path(), &["gesture", "classify", "{}"], file);
        assert!(err.contains(what), "{err}");
    }
}
