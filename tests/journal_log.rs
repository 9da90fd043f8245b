//! Under systemd the daemon's log lines are journal lines: `<N>` priority prefixes
//! (sd-daemon(3)) and no timestamp of their own, since the journal stamps each
//! line; elsewhere they keep `env_logger`'s timestamped format.

use std::os::unix::fs::MetadataExt;
use std::process::{Command, Stdio};

/// `demo` for a second with stderr to a file; `journal` sets `JOURNAL_STREAM` to
/// that file's device and inode, as systemd does for its stream.
fn demo_log(journal: bool) -> String {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("stderr");
    let file = std::fs::File::create(&log).unwrap();
    let meta = file.metadata().unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_crowdtouch"));
    cmd.args(["demo", "--agents", "20", "--seconds", "1", "--socket"])
        .arg(dir.path().join("d.sock"))
        .stdout(Stdio::null())
        .stderr(file)
        .env_remove("RUST_LOG")
        .env_remove("JOURNAL_STREAM");
    if journal {
        cmd.env("JOURNAL_STREAM", format!("{}:{}", meta.dev(), meta.ino()));
    }
    let status = cmd.status().unwrap();
    assert!(status.success());
    std::fs::read_to_string(&log).unwrap()
}

#[test]
fn journal_lines_carry_priorities_and_no_timestamp() {
    let text = demo_log(true);
    let lines: Vec<&str> = text.lines().collect();
    assert!(!lines.is_empty(), "the demo logged nothing");
    for l in &lines {
        let p = l.strip_prefix('<').and_then(|r| r.split_once('>'));
        let Some((prio, rest)) = p else {
            panic!("no priority prefix: {l:?}")
        };
        assert!(
            matches!(prio, "3" | "4" | "6" | "7"),
            "priority {prio} in {l:?}"
        );
        assert!(
            !rest.starts_with('[') && !rest.contains(" INFO ") && !rest.contains("Z "),
            "a timestamp or level word of its own: {l:?}"
        );
    }
    assert!(
        lines.iter().any(|l| l.starts_with("<6>")),
        "no info line: {text}"
    );
}

#[test]
fn other_stderr_keeps_the_timestamped_format() {
    let text = demo_log(false);
    let first = text.lines().next().expect("a log line");
    assert!(first.starts_with('['), "{first:?}");
    assert!(!first.starts_with('<'), "{first:?}");
}
