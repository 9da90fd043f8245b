//! Track files from the daemon and for it: `crowdtouch replay --tracks` records every
//! agent of a replayed recording as JSON Lines tracks (docs/tracks.md), and
//! `crowdtouch edit path` lays a group out along a path through a scene.

mod common;

use crowdtouch::crowd::edit::io::read_jsonl;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

/// A replayed area drag: every agent has a track, sampled on the step grid from the
/// first tick to the end of the settling time, linked throughout, and the drag
/// moved the crowd.
#[test]
fn replay_writes_every_agents_track_on_the_step_grid() {
    let dir = tempfile::tempdir().unwrap();
    let tracks = dir.path().join("drag.jsonl");
    let out = bin()
        .arg("replay")
        .arg(common::shipped("04-area-drag.jsonl"))
        .args(["--agents", "60", "--settle", "1", "--track-step", "0.2"])
        .arg("--tracks")
        .arg(&tracks)
        .arg("-o")
        .arg(dir.path().join("snapshots.jsonl"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&tracks).unwrap();
    assert!(
        text.starts_with(r#"{"format":"crowdtouch-tracks","version":1,"step_s":0.2,"source":"04-area-drag.jsonl"}"#),
        "{}",
        text.lines().next().unwrap_or("")
    );
    let set = read_jsonl(&text).unwrap();
    set.validate().unwrap();
    assert_eq!(set.step_s, 0.2);
    let mut ids: Vec<u64> = set.tracks.iter().map(|t| t.id).collect();
    ids.sort_unstable();
    assert_eq!(ids, (0..60).collect::<Vec<u64>>(), "every agent, by index");
    let n = set.tracks[0].len();
    assert!(n > 10, "{n} samples: the replay lasts seconds");
    let mut moved = 0;
    for t in &set.tracks {
        assert_eq!(
            t.len(),
            n,
            "person {}: every agent sampled every step",
            t.id
        );
        for (k, ts) in t.times_s.iter().enumerate() {
            assert_eq!(
                *ts,
                k as f64 * 0.2,
                "person {}: sample {k} on the grid",
                t.id
            );
        }
        assert!(t.linked.iter().all(|l| *l), "person {}: no gaps", t.id);
        let first = t.points[0];
        if t.points.iter().any(|p| (p - first).norm() > 0.5) {
            moved += 1;
        }
    }
    assert!(
        moved >= 30,
        "only {moved} of 60 agents moved more than 0.5 m"
    );
}

#[test]
fn replay_refuses_a_bad_track_step() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("replay")
        .arg(common::shipped("01-point-drag.jsonl"))
        .args(["--agents", "10", "--track-step", "0"])
        .arg("--tracks")
        .arg(dir.path().join("t.jsonl"))
        .arg("-o")
        .arg(dir.path().join("s.jsonl"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("track step"), "{err}");
}

/// `edit path` on a shipped scene named without its extension: one track per
/// person, the first starting at `--from`, readable as JSON Lines tracks; an
/// existing output is kept unless `--force`.
#[test]
fn edit_path_writes_a_group_and_keeps_an_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("group.jsonl");
    let run = |force: bool| {
        let mut c = bin();
        c.args(["edit", "path", "--scene", "single_block", "--from", "8,4.5"])
            .args(["--to", "15.5,4.5", "--people", "6", "--spacing", "0.5"])
            .arg("-o")
            .arg(&out_path);
        if force {
            c.arg("--force");
        }
        c.output().unwrap()
    };
    let out = run(false);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&out_path).unwrap();
    let set = read_jsonl(&text).unwrap();
    set.validate().unwrap();
    assert_eq!(set.tracks.len(), 6);
    assert_eq!(set.step_s, 0.1);
    for t in &set.tracks {
        for j in 0..t.len() - 1 {
            let v = t.segment_speed(j);
            assert!((v - 1.3).abs() < 0.026, "person {}: {v} m/s", t.id);
        }
    }
    let again = run(false);
    assert!(!again.status.success());
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("exists") && err.contains("--force"), "{err}");
    assert!(run(true).status.success());
    assert_eq!(
        std::fs::read_to_string(&out_path).unwrap(),
        text,
        "deterministic"
    );

    let bad = bin()
        .args([
            "edit",
            "path",
            "--scene",
            "single_block",
            "--from",
            "12.5,4.5",
        ])
        .args(["--to", "15.5,4.5", "--people", "2", "-o"])
        .arg(dir.path().join("x.jsonl"))
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("inside an obstacle"), "{err}");
}
