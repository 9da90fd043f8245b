//! Issue 27, findings 1 to 3, through the whole daemon as a socket client sees it:
//! `edit.load` and `edit.save` name entries of the daemon's edit directory, never
//! paths; a path (absolute, `..`, a symbolic link out) is refused with a clear
//! error and touches nothing; a FIFO in the directory is refused at once and the
//! client's next command is answered; saving never replaces a file unless the
//! config allows it; an error never holds the file's text.

mod common;

use common::{daemon_on_channel, read_until};
use crowdtouch::config::Config;
use crowdtouch::crowd::edit::io::{write_tracks, Format, ReadOptions};
use crowdtouch::crowd::edit::{Track, TrackSet};
use crowdtouch::geom::Vec2;
use serde_json::Value;
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::{Duration, Instant};

/// The first line of a file the daemon must never send to a client.
const SECRET: &str = "root:*:20228:0:99999:7:::";

/// Three people walking for 5 s.
fn walkers() -> TrackSet {
    let times: Vec<f64> = (0..=10).map(|k| k as f64 * 0.5).collect();
    let tracks = (0..3)
        .map(|i| {
            let p0 = Vec2::new(2.0 + 2.0 * i as f64, 3.0);
            Track::linked(
                i,
                times.iter().map(|t| p0 + Vec2::new(0.1 * t, 0.0)).collect(),
                times.clone(),
            )
        })
        .collect();
    TrackSet {
        tracks,
        step_s: 0.5,
    }
}

struct Client {
    w: UnixStream,
    r: BufReader<UnixStream>,
    next_id: u64,
}

impl Client {
    fn connect(socket: &Path) -> Client {
        let stream = UnixStream::connect(socket).unwrap();
        let mut w = stream.try_clone().unwrap();
        let mut r = BufReader::new(stream);
        writeln!(w, r#"{{"type":"hello","protocol":1,"subscribe":[]}}"#).unwrap();
        read_until(&mut r, 3.0, |v| v["type"] == "hello");
        Client { w, r, next_id: 1 }
    }

    /// Sends a command (the JSON after `"id":N,`) and returns its reply (`ack` or
    /// `error`) and how long it took; panics after `secs`.
    fn command(&mut self, body: &str, secs: f64) -> (Value, Duration) {
        let id = self.next_id;
        self.next_id += 1;
        let t = Instant::now();
        writeln!(self.w, r#"{{"type":"command","id":{id},{body}}}"#).unwrap();
        let got = read_until(&mut self.r, secs, |v| {
            (v["type"] == "ack" || v["type"] == "error") && v["id"] == id
        });
        let reply = got
            .last()
            .filter(|v| v["id"] == id)
            .unwrap_or_else(|| panic!("no reply to {body} within {secs} s"))
            .clone();
        (reply, t.elapsed())
    }

    fn error(&mut self, body: &str) -> String {
        let (reply, _) = self.command(body, 5.0);
        assert_eq!(reply["type"], "error", "{body}: {reply}");
        reply["message"].as_str().unwrap().to_string()
    }
}

/// A daemon whose edit directory is `dir` (and which starts editing `start`,
/// when given).
fn daemon(
    dir: &Path,
    socket: &Path,
    allow_overwrite: bool,
) -> (
    crowdtouch::pipeline::Daemon,
    crossbeam_channel::Sender<crowdtouch::vocab::TouchFrame>,
) {
    let mut cfg = Config::from_str(
        &crowdtouch::config::DEFAULT_CONFIG_RON.replace(
            "    pipeline: (",
            &format!(
                "    edit: Some((dir: Some({:?}), allow_overwrite: {allow_overwrite})),\n    pipeline: (",
                dir.display().to_string()
            ),
        ),
        Path::new("<test>"),
    )
    .expect("config with an edit directory");
    cfg.pipeline.realtime = Default::default();
    daemon_on_channel(cfg, socket, 64)
}

/// Paths in every form are refused with an error that says to name an entry;
/// nothing is read (the secret never shows) and nothing is written outside the
/// directory. A symbolic link in the directory that leads out is refused as one.
#[test]
fn paths_are_refused_and_touch_nothing() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("tracks");
    std::fs::create_dir(&dir).unwrap();
    let outside = root.path().join("shadow");
    std::fs::write(&outside, format!("{SECRET}\n")).unwrap();
    std::os::unix::fs::symlink(&outside, dir.join("link.txt")).unwrap();
    write_tracks(
        &walkers(),
        &dir.join("walk.jsonl"),
        Format::Jsonl,
        &ReadOptions::default(),
        false,
    )
    .unwrap();
    let socket = root.path().join("ct.sock");
    let (daemon, _tx) = daemon(&dir, &socket, true);
    let mut c = Client::connect(&socket);
    let outside_s = outside.display().to_string();
    // The old `path` field: refused, saying what to use.
    for body in [
        format!(r#""name":"edit.load","path":{outside_s:?}"#),
        r#""name":"edit.load","path":"walk.jsonl""#.to_string(),
    ] {
        let e = c.error(&body);
        assert!(
            e.contains("`path` is not taken") && e.contains("`entry`") && e.contains("edit.dir"),
            "{e}"
        );
    }
    // Entries that are paths: absolute, `..`, `.`.
    for (entry, what) in [
        (outside_s.as_str(), "holds `/`"),
        ("../shadow", "holds `/`"),
        ("..", "starts with `.`"),
        ("tracks/../../shadow", "holds `/`"),
    ] {
        let e = c.error(&format!(r#""name":"edit.load","entry":{entry:?}"#));
        assert!(
            e.contains("`entry` is not a file name") && e.contains(what),
            "{entry}: {e}"
        );
        assert!(!e.contains("root:"), "{e}");
    }
    // A symbolic link out of the directory.
    let e = c.error(r#""name":"edit.load","entry":"link.txt""#);
    assert_eq!(e, "link.txt: is a symbolic link, not a regular file");
    // Saving to a path: refused at the parser, and nothing appears outside.
    let (ack, _) = c.command(r#""name":"edit.load","entry":"walk.jsonl""#, 5.0);
    assert_eq!(ack["type"], "ack", "{ack}");
    for body in [
        format!(
            r#""name":"edit.save","path":{:?},"overwrite":true"#,
            root.path().join("written.jsonl").display().to_string()
        ),
        r#""name":"edit.save","entry":"../written.jsonl","overwrite":true"#.to_string(),
        format!(
            r#""name":"edit.save","entry":{:?},"overwrite":true"#,
            root.path().join("written.jsonl").display().to_string()
        ),
    ] {
        c.error(&body);
    }
    assert!(!root.path().join("written.jsonl").exists());
    assert_eq!(
        std::fs::read_to_string(&outside).unwrap(),
        format!("{SECRET}\n"),
        "the file outside is untouched"
    );
    daemon.shutdown();
}

/// A FIFO in the edit directory (no writer) is refused within a second, and the
/// same client's `pause` right after is answered (finding 3: the read blocked the
/// formation thread and every later reply waited behind it).
#[test]
fn a_fifo_in_the_edit_directory_is_refused_at_once_and_later_commands_are_answered() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("tracks");
    std::fs::create_dir(&dir).unwrap();
    let fifo = dir.join("pipe.csv");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let socket = root.path().join("ct.sock");
    let (daemon, _tx) = daemon(&dir, &socket, false);
    let mut c = Client::connect(&socket);
    let (reply, took) = c.command(r#""name":"edit.load","entry":"pipe.csv""#, 3.0);
    assert_eq!(reply["type"], "error", "{reply}");
    assert_eq!(
        reply["message"], "pipe.csv: is a FIFO, not a regular file",
        "{reply}"
    );
    assert!(took < Duration::from_secs(1), "refused in {took:?}");
    let (reply, took) = c.command(r#""name":"pause""#, 3.0);
    assert_eq!(reply["type"], "ack", "{reply}");
    assert!(took < Duration::from_secs(1), "pause answered in {took:?}");
    // And the same again: nothing was left busy.
    let (reply, _) = c.command(r#""name":"edit.load","entry":"pipe.csv""#, 3.0);
    assert_eq!(reply["type"], "error", "{reply}");
    // A 10 GB sparse file: refused by the size it reports, before a byte is read.
    std::fs::File::create(dir.join("big.jsonl"))
        .unwrap()
        .set_len(10_000_000_000)
        .unwrap();
    let (reply, took) = c.command(r#""name":"edit.load","entry":"big.jsonl""#, 3.0);
    assert_eq!(
        reply["message"], "big.jsonl: 10000000000 bytes, more than the 268435456 byte limit",
        "{reply}"
    );
    assert!(took < Duration::from_secs(1), "refused in {took:?}");
    daemon.shutdown();
}

/// `edit.save` creates entries; it replaces one only when the client asks and the
/// config's `edit.allow_overwrite` is on.
#[test]
fn saving_replaces_an_entry_only_when_the_config_allows_it() {
    for allow in [false, true] {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("tracks");
        std::fs::create_dir(&dir).unwrap();
        write_tracks(
            &walkers(),
            &dir.join("walk.jsonl"),
            Format::Jsonl,
            &ReadOptions::default(),
            false,
        )
        .unwrap();
        std::fs::write(dir.join("keep.jsonl"), "precious\n").unwrap();
        let socket = root.path().join("ct.sock");
        let (daemon, _tx) = daemon(&dir, &socket, allow);
        let mut c = Client::connect(&socket);
        let (ack, _) = c.command(r#""name":"edit.load","entry":"walk.jsonl""#, 5.0);
        assert_eq!(ack["type"], "ack", "{ack}");
        // A new entry is written.
        let (ack, _) = c.command(r#""name":"edit.save","entry":"new.jsonl""#, 5.0);
        assert_eq!(ack["type"], "ack", "{ack}");
        assert!(dir.join("new.jsonl").is_file());
        // An existing one is not, without `overwrite`.
        let e = c.error(r#""name":"edit.save","entry":"keep.jsonl""#);
        assert_eq!(e, "keep.jsonl exists; saving does not replace it");
        // With it: only when allowed.
        let (reply, _) = c.command(
            r#""name":"edit.save","entry":"keep.jsonl","overwrite":true"#,
            5.0,
        );
        let kept = std::fs::read_to_string(dir.join("keep.jsonl")).unwrap();
        if allow {
            assert_eq!(reply["type"], "ack", "{reply}");
            assert!(
                kept.starts_with(r#"{"format":"crowdtouch-tracks""#),
                "{kept}"
            );
        } else {
            assert_eq!(reply["type"], "error", "{reply}");
            assert!(
                reply["message"]
                    .as_str()
                    .unwrap()
                    .contains("`edit.allow_overwrite` is off"),
                "{reply}"
            );
            assert_eq!(kept, "precious\n");
        }
        daemon.shutdown();
    }
}

/// A file in the directory that is not a track file: the error names the entry
/// and line, never the line's text (finding 1: ``frame `root:*:…` is not a
/// number``).
#[test]
fn an_error_never_holds_the_files_first_line() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("tracks");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("shadow"), format!("{SECRET}\nbin:*:1:0:::\n")).unwrap();
    std::fs::write(dir.join("shadow.csv"), format!("{SECRET}\n")).unwrap();
    std::fs::write(
        dir.join("shadow.jsonl"),
        format!("{{\"format\":\"{SECRET}\"}}\n"),
    )
    .unwrap();
    let socket = root.path().join("ct.sock");
    let (daemon, _tx) = daemon(&dir, &socket, false);
    let mut c = Client::connect(&socket);
    for entry in ["shadow", "shadow.csv", "shadow.jsonl"] {
        let e = c.error(&format!(r#""name":"edit.load","entry":"{entry}""#));
        assert!(e.starts_with(&format!("{entry}:1: ")), "{e}");
        assert!(!e.contains("root") && !e.contains("20228"), "{entry}: {e}");
        assert!(
            !e.contains(&dir.display().to_string()),
            "the directory's path is not told: {e}"
        );
    }
    daemon.shutdown();
}
