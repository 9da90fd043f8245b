//! The `crowdtouch` binary: replay determinism, bad input, config checking, demo.

mod common;

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

#[test]
fn help_lists_every_subcommand() {
    let out = bin().arg("--help").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for sub in [
        "run",
        "demo",
        "replay",
        "watch",
        "check-config",
        "bench",
        "synth-recordings",
        "devices",
        "calibrate",
        "record",
        "hid",
        "scene",
    ] {
        assert!(text.contains(sub), "--help misses {sub}:\n{text}");
    }
}

#[test]
fn replay_output_is_byte_identical_across_runs() {
    let rec = common::shipped("04-area-drag.jsonl");
    let run = || {
        bin()
            .arg("replay")
            .arg(&rec)
            .arg("--agents")
            .arg("60")
            .output()
            .unwrap()
    };
    let (a, b) = (run(), run());
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    assert_eq!(a.stdout, b.stdout);
    let text = String::from_utf8(a.stdout).unwrap();
    let mut types = std::collections::BTreeSet::new();
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        types.insert(v["type"].as_str().unwrap().to_string());
    }
    assert!(
        types.contains("snapshot") && types.contains("control") && types.contains("mesh"),
        "{types:?}"
    );
}

/// Asserts that a command exited with success, showing its stderr when not.
fn assert_success(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn write_tmp(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn corrupt_recording(dir: &tempfile::TempDir) -> std::path::PathBuf {
    let text = std::fs::read_to_string(common::shipped("01-point-drag.jsonl")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // Line 6 truncated mid-object.
    let l = lines[5].clone();
    lines[5] = l[..l.len() / 2].to_string();
    write_tmp(dir, "bad.jsonl", &(lines.join("\n") + "\n"))
}

#[test]
fn a_corrupt_recording_line_is_named_and_replay_stops() {
    let dir = tempfile::tempdir().unwrap();
    let bad = corrupt_recording(&dir);
    let out = bin().arg("replay").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.jsonl") && err.contains(":6"),
        "error should name file and line 6: {err}"
    );
}

#[test]
fn skip_bad_frames_replays_the_rest_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let bad = corrupt_recording(&dir);
    let out = bin()
        .arg("replay")
        .arg(&bad)
        .arg("--skip-bad-frames")
        .output()
        .unwrap();
    assert_success(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(":6") && err.contains("skipped"), "{err}");
    assert!(!out.stdout.is_empty());
}

#[test]
fn check_config_reports_every_error_with_place_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let good = crowdtouch::config::DEFAULT_CONFIG_RON;
    let ok = write_tmp(&dir, "ok.ron", good);
    let out = bin().arg("check-config").arg(&ok).output().unwrap();
    assert_success(&out);
    let bad = write_tmp(
        &dir,
        "bad.ron",
        &good.replacen("agents: 100", "agents: 0", 1).replacen(
            "max_speed_m_s: 1.5",
            "max_speed_m_s: -1.0",
            1,
        ),
    );
    let out = bin().arg("check-config").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 2, "{err}");
    assert!(
        lines[0].contains("bad.ron:") && lines[0].contains("crowd.agents"),
        "{err}"
    );
    assert!(lines[1].contains("crowd.max_speed_m_s"), "{err}");
    let missing = bin()
        .arg("check-config")
        .arg(dir.path().join("nope.ron"))
        .output()
        .unwrap();
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("nope.ron"));
}

#[test]
fn demo_serves_the_socket_and_prints_status() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("demo.sock");
    let mut child = bin()
        .args(["demo", "--seconds", "4", "--socket"])
        .arg(&sock)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    assert!(
        first.contains(&sock.display().to_string()),
        "first line names the socket: {first}"
    );
    let mut r = BufReader::new(std::os::unix::net::UnixStream::connect(&sock).unwrap());
    let mut line = String::new();
    let mut snapshots = 0;
    let t0 = Instant::now();
    while snapshots < 50 && t0.elapsed() < Duration::from_secs(3) {
        line.clear();
        if r.read_line(&mut line).unwrap() == 0 {
            break;
        }
        if line.starts_with("{\"type\":\"snapshot\"") {
            snapshots += 1;
        }
    }
    assert!(snapshots >= 50);
    let rest: Vec<String> = out.lines().map_while(Result::ok).collect();
    let status = rest
        .iter()
        .filter(|l| l.contains("agents") && l.contains("latency"))
        .count();
    assert!(status >= 2, "status lines: {rest:?}");
    assert!(child.wait().unwrap().success());
}

/// `run --config cfg` on a socket in `dir`, stderr piped; returns once the socket
/// exists. A debug build on a loaded machine may take several seconds to start (the
/// scene is loaded and checked first), so the wait is generous; it ends as soon as
/// the socket is there.
fn run_daemon(
    cfg: &std::path::Path,
    dir: &std::path::Path,
) -> (std::process::Child, std::path::PathBuf) {
    let sock = dir.join("run.sock");
    let child = bin()
        .args(["run", "--config"])
        .arg(cfg)
        .arg("--socket")
        .arg(&sock)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !sock.exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(sock.exists(), "the daemon made no socket in 60 s");
    (child, sock)
}

/// The default config with its inputs replaced by one shipped recording, looped.
fn looped_replay_config(recording: &str) -> String {
    let rec = common::shipped(recording);
    let base = crowdtouch::config::DEFAULT_CONFIG_RON;
    let a = base.find("inputs: [").unwrap();
    let b = a + base[a..].find("\n    ],\n").unwrap() + "\n    ],\n".len();
    format!(
        "{}inputs: [Replay(files: [{:?}], looped: true)],\n{}",
        &base[..a],
        rec.display().to_string(),
        &base[b..]
    )
}

#[test]
fn sighup_with_a_bad_config_keeps_the_old_one_running() {
    let dir = tempfile::tempdir().unwrap();
    let cfg_path = dir.path().join("crowdtouch.ron");
    let text = looped_replay_config("07-open-space-swipe.jsonl");
    std::fs::write(&cfg_path, &text).unwrap();
    let check = bin().arg("check-config").arg(&cfg_path).output().unwrap();
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let (child, sock) = run_daemon(&cfg_path, dir.path());
    std::fs::write(&cfg_path, "(version: 1, oops").unwrap();
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGHUP).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    // Still serving.
    let mut r = BufReader::new(std::os::unix::net::UnixStream::connect(&sock).unwrap());
    let mut line = String::new();
    r.read_line(&mut line).unwrap();
    assert!(line.contains("\"hello\""));
    // A valid new config is applied.
    std::fs::write(
        &cfg_path,
        text.replacen("max_speed_m_s: 1.5", "max_speed_m_s: 2.0", 1),
    )
    .unwrap();
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGHUP).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(log.contains("config reloaded"), "{log}");
    assert!(
        log.contains("rejected") && log.contains("crowdtouch.ron:1"),
        "{log}"
    );
    let _ = std::io::stderr().flush();
}

/// A scene whose one patch covers the crowd and the ground around it.
fn patch_scene(name: &str, motion: &str, speed: &str) -> String {
    format!(
        "(\n    version: 1,\n    name: \"{name}\",\n    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n    patches: [\n        (name: \"floor\", motion: {motion}, speed_factor: {speed}, parts: [\n            Polygon(vertices_m: [(3.0, 1.0), (13.0, 1.0), (13.0, 8.0), (3.0, 8.0)]),\n        ]),\n    ],\n)\n"
    )
}

/// Reads snapshots for `secs`, or until `stop` is true of `extra` more snapshots
/// after the one it was first true of, and returns the motions of each.
fn snapshot_motions(
    r: &mut BufReader<std::os::unix::net::UnixStream>,
    secs: f64,
    extra: usize,
    stop: impl Fn(&[String]) -> bool,
) -> Vec<Vec<String>> {
    r.get_ref()
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let end = Instant::now() + Duration::from_secs_f64(secs);
    let mut out: Vec<Vec<String>> = Vec::new();
    let mut line = String::new();
    let mut stopped_at = None;
    while Instant::now() < end && stopped_at.is_none_or(|at| out.len() <= at + extra) {
        line.clear();
        match r.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) if line.starts_with("{\"type\":\"snapshot\"") => {
                let v: serde_json::Value = serde_json::from_str(&line).unwrap();
                out.push(
                    v["motions"]
                        .as_array()
                        .map(|m| m.iter().map(|x| x.as_str().unwrap().to_string()).collect())
                        .unwrap_or_default(),
                );
                if stopped_at.is_none() && stop(out.last().unwrap()) {
                    stopped_at = Some(out.len() - 1);
                }
            }
            Ok(_) => {}
            Err(_) => {}
        }
    }
    out
}

/// SIGHUP re-reads the scene file: a broken scene is rejected with its file, line
/// and column in the log and the running scene stays; a fixed one is swapped in.
#[test]
fn sighup_reloads_the_scene_and_a_broken_scene_keeps_the_old_one() {
    let dir = tempfile::tempdir().unwrap();
    let cfg_path = dir.path().join("crowdtouch.ron");
    let scene_path = dir.path().join("room.ron");
    let text = looped_replay_config("07-open-space-swipe.jsonl")
        .replacen("agents: 100", "agents: 40", 1)
        .replacen("scene: None", "scene: Some(\"room.ron\")", 1);
    std::fs::write(&cfg_path, &text).unwrap();
    std::fs::write(&scene_path, patch_scene("net room", "crawl", "None")).unwrap();
    let (child, sock) = run_daemon(&cfg_path, dir.path());
    let pid = nix::unistd::Pid::from_raw(child.id() as i32);
    let mut r = BufReader::new(std::os::unix::net::UnixStream::connect(&sock).unwrap());
    let all = |snaps: &[Vec<String>], motion: &str| {
        !snaps.is_empty()
            && snaps
                .iter()
                .all(|m| m.len() == 40 && m.iter().all(|x| x == motion))
    };
    let first = snapshot_motions(&mut r, 0.5, 0, |_| false);
    assert!(all(&first, "crawl"), "scene at start: {:?}", first.last());

    // Broken: a patch speed of -0.5 on line 6.
    std::fs::write(&scene_path, patch_scene("pool room", "swim", "Some(-0.5)")).unwrap();
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGHUP).unwrap();
    let kept = snapshot_motions(&mut r, 1.0, 0, |_| false);
    assert!(
        all(&kept, "crawl"),
        "after a broken scene: {:?}",
        kept.last()
    );

    // Fixed: the pool is swapped in while the daemon runs.
    std::fs::write(&scene_path, patch_scene("pool room", "swim", "None")).unwrap();
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGHUP).unwrap();
    let swim = |m: &[String]| !m.is_empty() && m.iter().all(|x| x == "swim");
    let after = snapshot_motions(&mut r, 10.0, 60, swim);
    let swapped = after
        .iter()
        .position(|m| swim(m))
        .expect("the fixed scene was not swapped in");
    assert!(all(&after[swapped..], "swim"), "{:?}", after.last());
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let log = String::from_utf8_lossy(&out.stderr);
    let line = text
        .lines()
        .position(|l| l.contains("scene: Some"))
        .unwrap()
        + 1;
    assert!(
        log.contains("rejected")
            && log.contains(&format!("crowdtouch.ron:{line}:"))
            && log.contains("room.ron:6:")
            && log.contains("speed must be positive"),
        "{log}"
    );
    assert!(
        log.contains("scene \"pool room\" loaded") && log.contains("replaces scene \"net room\""),
        "{log}"
    );
}

/// `replay --frames` prints the daemon's decoding of a real device recording.
#[test]
fn replay_frames_prints_decoded_touches() {
    let rec = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/dell-canvas-27-touch.evemu");
    let out = bin()
        .arg("replay")
        .arg("--frames")
        .arg(&rec)
        .output()
        .unwrap();
    assert_success(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    let (mut downs, mut ends, mut frames) = (0, 0, 0);
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        frames += 1;
        for c in v["contacts"].as_array().unwrap() {
            let x = c["x"].as_f64().unwrap();
            assert!((0.0..=1.0).contains(&x));
            match c["state"].as_str().unwrap() {
                "down" => downs += 1,
                "up" | "cancelled" => ends += 1,
                "tap" => {
                    downs += 1;
                    ends += 1
                }
                _ => {}
            }
        }
    }
    // The Dell Canvas 27 recording: 450 frames, 12 touches.
    assert_eq!(frames, 450);
    assert_eq!((downs, ends), (12, 12));
}

fn fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// `hid describe` on a real touchscreen descriptor, a hid-recorder log and a
/// keyboard descriptor.
#[test]
fn hid_describe_prints_the_layout_or_why_not() {
    let describe = |path: &std::path::Path| {
        let out = bin().args(["hid", "describe"]).arg(path).output().unwrap();
        assert_success(&out);
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    // The ActionStar in the R:/N:/I: form: 2 fingers per report, report id 1.
    let v = describe(&fixture("hid/actionstar-2101-1011.inrange-sequence.hid"));
    assert_eq!(v["touch"], true, "{v}");
    let c = &v["collections"][0];
    assert_eq!(c["application"], "touchscreen");
    assert!(c["contacts_per_report"].as_u64().unwrap() >= 1);
    assert!(c["max_contacts"].as_u64().unwrap() >= c["contacts_per_report"].as_u64().unwrap());
    assert!(!c["report_ids"].as_array().unwrap().is_empty());
    let fields = c["finger_fields"].as_object().unwrap();
    for f in ["tip_switch", "contact_id", "x", "y"] {
        assert!(fields.contains_key(f), "{f} missing: {c}");
    }
    assert_eq!(fields["x"]["logical"], serde_json::json!([0, 19967]));
    // A USB boot keyboard descriptor (HID spec appendix E.6) is not a digitizer.
    let dir = tempfile::tempdir().unwrap();
    let kb = dir.path().join("keyboard.rdesc");
    std::fs::write(
        &kb,
        [
            0x05u8, 0x01, 0x09, 0x06, 0xa1, 0x01, 0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7, 0x15, 0x00,
            0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0x95, 0x01, 0x75, 0x08, 0x81, 0x01,
            0x95, 0x06, 0x75, 0x08, 0x15, 0x00, 0x25, 0x65, 0x05, 0x07, 0x19, 0x00, 0x29, 0x65,
            0x81, 0x00, 0xc0,
        ],
    )
    .unwrap();
    let v = describe(&kb);
    assert_eq!(v["touch"], false, "{v}");
    assert!(!v["reason"].as_str().unwrap().is_empty());
    // A file that is not there is an error naming it.
    let out = bin()
        .args(["hid", "describe", "/nonexistent/x.rdesc"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.rdesc"));
}

/// `replay --frames` decodes a hid-recorder log (the Wacom touch node: 72 frames,
/// two fingers).
#[test]
fn replay_frames_reads_hid_recorder_logs() {
    let out = bin()
        .args(["replay", "--frames"])
        .arg(fixture(
            "hid/wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
        ))
        .output()
        .unwrap();
    assert_success(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    let mut ids = std::collections::BTreeSet::new();
    let mut frames = 0;
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        frames += 1;
        for c in v["contacts"].as_array().unwrap() {
            ids.insert(c["id"].as_u64().unwrap());
        }
    }
    assert_eq!(frames, 72);
    assert_eq!(ids.len(), 2);
}

/// `record` on a device that is not there says what it looked for.
#[test]
fn record_without_the_device_explains() {
    let out = bin()
        .args([
            "record",
            "--device",
            "/nonexistent/event9",
            "--seconds",
            "1",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/event9"), "{err}");
    let out = bin()
        .args(["record", "--device", "auto", "--seconds", "-1"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn scene_check_summarises_a_good_scene_and_lists_every_error() {
    let street = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/street.ron");
    let out = bin()
        .args(["scene", "check"])
        .arg(&street)
        .output()
        .unwrap();
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("ok") && text.contains("16 x 9 m"), "{text}");
    assert!(
        text.contains("2 obstacles") && text.contains("4 dynamic (4 obstacles, 0 patches)"),
        "{text}"
    );
    assert!(
        text.contains("1 patch,") && text.contains("0 checkpoints"),
        "{text}"
    );

    let dir = tempfile::tempdir().unwrap();
    let bad = write_tmp(
        &dir,
        "bad.ron",
        "(\n    version: 1,\n    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n    obstacles: [\n        (name: \"dent\", parts: [Polygon(vertices_m: [(2.0, 2.0), (4.0, 2.0), (3.0, 2.5), (4.0, 4.0), (2.0, 4.0)])]),\n        (name: \"near\", parts: [Circle(centre_m: (4.2, 6.0), radius_m: 0.1)]),\n        (name: \"close\", parts: [Circle(centre_m: (4.5, 6.0), radius_m: 0.1)]),\n    ],\n    patches: [(motion: crawl, speed_factor: Some(-1.0), parts: [Circle(centre_m: (9.0, 5.0), radius_m: 1.0)])],\n)\n",
    );
    let out = bin().args(["scene", "check"]).arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{err}");
    assert!(
        lines[0].contains("bad.ron:5:")
            && lines[0]
                .contains(": obstacles[0].parts[0].vertices_m: polygon is not convex at vertex 2"),
        "{err}"
    );
    assert!(
        lines[1].contains("bad.ron:7:")
            && lines[1].contains("obstacles[2].parts: is 0.100 m from obstacles[1] \"near\""),
        "{err}"
    );
    assert!(
        lines[2].contains("bad.ron:9:")
            && lines[2].contains("patches[0].speed_factor: speed must be positive"),
        "{err}"
    );

    // A checkpoint must name a formation of the config: the shipped shapes, or
    // the config's own with --config.
    let gate = write_tmp(
        &dir,
        "gate.ron",
        "(\n    version: 1,\n    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n    checkpoints: [\n        (name: \"gate\", formation: \"star\",\n         region: Circle(centre_m: (8.0, 4.0), radius_m: 1.0)),\n    ],\n)\n",
    );
    let out = bin().args(["scene", "check"]).arg(&gate).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("gate.ron:5:")
            && err.contains("checkpoints[0].formation: no formation is called `star`; the config defines start, square, arrow, column, line, wedge, diamond"),
        "{err}"
    );
    let cfg = write_tmp(
        &dir,
        "star.ron",
        &crowdtouch::config::DEFAULT_CONFIG_RON.replace(
            "        shapes: [],",
            "        shapes: [(name: \"star\", outline: [(1.0, 0.0), (0.2, 0.2), (0.0, 1.0), (-0.2, 0.2), (-1.0, 0.0), (-0.2, -0.2), (0.0, -1.0), (0.2, -0.2)])],",
        ),
    );
    let out = bin()
        .args(["scene", "check", "--config"])
        .arg(&cfg)
        .arg(&gate)
        .output()
        .unwrap();
    assert_success(&out);
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 checkpoint;"));

    let missing = bin()
        .args(["scene", "check"])
        .arg(dir.path().join("nope.ron"))
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("nope.ron"));
}

#[test]
fn formations_lists_and_draws_every_shape_of_the_config() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_tmp(
        &dir,
        "c.ron",
        &crowdtouch::config::DEFAULT_CONFIG_RON.replace(
            "        shapes: [],",
            "        shapes: [(name: \"tee\", outline: [(0.0, 0.0), (3.0, 0.0), (3.0, 1.0), (2.0, 1.0), (2.0, 3.0), (1.0, 3.0), (1.0, 1.0), (0.0, 1.0)])],",
        ),
    );
    let svg = dir.path().join("f.svg");
    let out = bin()
        .args(["formations", "--config"])
        .arg(&cfg)
        .arg("-o")
        .arg(&svg)
        .output()
        .unwrap();
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    // Every known name (start and the shipped shapes, pinned in the library's tests)
    // and the config's own.
    let lib = crowdtouch::crowd::formation::FormationLibrary::shipped();
    for name in lib.known_names().into_iter().chain(["tee"]) {
        assert!(
            text.lines().any(|l| l.starts_with(&format!("{name} "))),
            "{name} missing:\n{text}"
        );
    }
    let pic = std::fs::read_to_string(&svg).unwrap();
    assert!(pic.starts_with("<svg") && pic.contains(">tee</text>"));
    // 100 sampled target points drawn per formation (none for the start grid);
    // holes dashed (ring, letter_a).
    assert_eq!(pic.matches("<circle").count(), 12 * 100);
    assert_eq!(pic.matches("stroke-dasharray").count(), 2);
}

#[test]
fn bench_edit_reports_cage_detection_and_tick_rows() {
    let out = bin()
        .args([
            "bench",
            "edit",
            "--people",
            "40",
            "--n",
            "50",
            "--repeats",
            "2",
            "--json",
        ])
        .output()
        .unwrap();
    assert_success(&out);
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = rows.as_array().unwrap();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["workload"].as_str().unwrap())
        .collect();
    for want in [
        "edit cage new + first drag",
        "edit drag + apply",
        "edit detect 50 walkers",
        "edit detect crowds_zara01",
        "edit detect students001",
        "edit tick 40 tracks dragging",
    ] {
        assert!(names.contains(&want), "no row {want}: {names:?}");
    }
    for r in rows {
        for key in ["samples", "p50_us", "p99_us", "max_us", "note"] {
            assert!(r.get(key).is_some(), "{key} missing in {r}");
        }
        assert!(r["samples"].as_u64().unwrap() > 0, "{r}");
        assert!(r["p50_us"].as_f64().unwrap() <= r["max_us"].as_f64().unwrap());
    }
}

#[test]
fn bench_assign_reports_quantiles_and_certificates() {
    let dir = tempfile::tempdir().unwrap();
    let dump = dir.path().join("instances.json");
    for warm in [false, true] {
        let mut cmd = bin();
        cmd.args([
            "bench",
            "assign",
            "--n",
            "40",
            "--repeats",
            "5",
            "--json",
            "--dump",
        ])
        .arg(&dump);
        if warm {
            cmd.arg("--warm");
        }
        let out = cmd.output().unwrap();
        assert_success(&out);
        let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let row = &rows[0];
        let want = if warm {
            "assign_warm uniform n=40"
        } else {
            "assign_cold uniform n=40"
        };
        assert_eq!(row["workload"], want);
        assert_eq!(row["samples"], 5);
        let (p50, p99, max) = (
            row["p50_us"].as_f64().unwrap(),
            row["p99_us"].as_f64().unwrap(),
            row["max_us"].as_f64().unwrap(),
        );
        assert!(0.0 < p50 && p50 <= p99 && p99 <= max, "{row}");
        assert!(
            row["note"].as_str().unwrap().contains("held on 5/5"),
            "{row}"
        );
        let inst: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&dump).unwrap()).unwrap();
        let frames = inst["frames"].as_array().unwrap();
        assert_eq!(frames.len(), if warm { 6 } else { 5 });
        assert_eq!(frames[0]["agents"].as_array().unwrap().len(), 40);
    }
    // Bad size: an error, not a panic.
    let out = bin()
        .args(["bench", "assign", "--n", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn bench_assign_from_positions_and_bench_fmm_report_checked_rows() {
    let out = bin()
        .args([
            "bench",
            "assign",
            "--n",
            "150",
            "--repeats",
            "3",
            "--warm",
            "--points",
            "--json",
        ])
        .output()
        .unwrap();
    assert_success(&out);
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(rows[0]["workload"], "assign_warm_points uniform n=150");
    assert!(
        rows[0]["note"].as_str().unwrap().contains("held on 3/3"),
        "{}",
        rows[0]
    );
    // Every layout, one row each, every answer certified.
    let out = bin()
        .args([
            "bench",
            "assign",
            "--n",
            "150",
            "--repeats",
            "2",
            "--points",
            "--layout",
            "all",
            "--json",
        ])
        .output()
        .unwrap();
    assert_success(&out);
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = rows
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["workload"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "uniform",
            "clustered",
            "pinched",
            "line",
            "to-line",
            "corner",
            "shifted"
        ]
        .map(|l| format!("assign_cold_points {l} n=150"))
    );
    for r in rows.as_array().unwrap() {
        assert!(r["note"].as_str().unwrap().contains("held on 2/2"), "{r}");
    }
    let out = bin()
        .args(["bench", "assign", "--layout", "round"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown layout `round`") && err.contains("to-line"),
        "{err}"
    );
    for obstacles in [false, true] {
        let mut cmd = bin();
        cmd.args(["bench", "fmm", "--grid", "48", "--repeats", "3", "--json"]);
        if obstacles {
            cmd.arg("--obstacles");
        }
        let out = cmd.output().unwrap();
        assert_success(&out);
        let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let note = rows[0]["note"].as_str().unwrap();
        if obstacles {
            assert_eq!(rows[0]["workload"], "fmm 48x48 obstacles");
            assert!(note.contains("cells reachable"), "{note}");
        } else {
            assert_eq!(rows[0]["workload"], "fmm 48x48");
            // Second order on a uniform cost: within about 1.5 cm of the distance.
            let mm: f64 = note
                .split("Euclidean distance ")
                .nth(1)
                .and_then(|s| s.split(' ').next())
                .and_then(|s| s.parse().ok())
                .unwrap_or_else(|| panic!("{note}"));
            assert!(mm < 15.0, "{note}");
        }
    }
    // Bad grid: an error naming the option, not a panic.
    let out = bin()
        .args(["bench", "fmm", "--grid", "1"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--grid"));
}
