//! The whole daemon: a recording replayed in real time through the input thread,
//! queue, control thread and publisher, read by socket clients.

mod common;

use common::*;
use crowdtouch::config::Config;
use crowdtouch::geom::Vec2;
use crowdtouch::input::replay::ReplayItem;
use crowdtouch::pipeline::{Daemon, DaemonOptions, SourceSpec};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::TouchFrame;
use serde_json::Value;
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn sock(dir: &tempfile::TempDir) -> PathBuf {
    dir.path().join("ct.sock")
}

fn source(names: &[&str], looped: bool) -> SourceSpec {
    // Each file starts with half a second of nothing, so a test client connected right
    // after `Daemon::start` sees the first touch.
    let items = names
        .iter()
        .map(|n| {
            let mut frames = vec![TouchFrame::new(Micros::ZERO)];
            frames.extend(load(n).frames.into_iter().map(|mut f| {
                f.t = f.t + Micros(500_000);
                f
            }));
            ReplayItem::new(n.to_string(), frames)
        })
        .collect();
    SourceSpec::Replay {
        items,
        looped,
        gap: Micros(200_000),
        reset_between: false,
        glass_mm: load(names[0]).surface.size_mm(),
    }
}

fn start(mut cfg: Config, names: &[&str], path: &Path) -> Daemon {
    // Real-time scheduling and mlockall would apply to the whole test process.
    cfg.pipeline.realtime = Default::default();
    Daemon::start(
        cfg,
        vec![source(names, false)],
        DaemonOptions {
            socket_path: path.to_path_buf(),
            collect: None,
        },
    )
    .expect("daemon starts")
}

fn pairs(v: &Value) -> Vec<Vec2> {
    v.as_array()
        .unwrap()
        .chunks_exact(2)
        .map(|c| Vec2::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
        .collect()
}

#[test]
fn a_reading_client_sees_the_crowd_follow_a_point_drag() {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 40;
    let daemon = start(cfg, &["01-point-drag.jsonl"], &path);
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    // Like `socat - UNIX-CONNECT:...`: sends nothing, gets hello then the stream.
    let mut ended_at: Option<Instant> = None;
    let msgs = read_until(&mut r, 12.0, |v| {
        if v["type"] == "control" && v["phase"] == "end" {
            ended_at = Some(Instant::now());
        }
        ended_at.is_some_and(|t| t.elapsed() > Duration::from_secs(4))
    });
    daemon.shutdown();
    assert_eq!(msgs[0]["type"], "hello");
    assert_eq!(msgs[0]["protocol"], 1);
    let snaps: Vec<&Value> = msgs.iter().filter(|v| v["type"] == "snapshot").collect();
    assert!(snaps.len() > 300, "only {} snapshots", snaps.len());
    let seqs: Vec<u64> = snaps.iter().map(|s| s["seq"].as_u64().unwrap()).collect();
    assert!(
        seqs.windows(2).all(|w| w[1] > w[0]),
        "snapshots out of order"
    );
    let kinds: Vec<(&str, &str)> = msgs
        .iter()
        .filter(|v| v["type"] == "control")
        .map(|v| (v["phase"].as_str().unwrap(), v["kind"].as_str().unwrap()))
        .collect();
    assert_eq!(kinds, vec![("begin", "point"), ("end", "point")]);
    // Snapshots driven by touches carry their latency.
    assert!(snaps.iter().any(|s| s["latency_us"].is_u64()));
    let before = centroid(pairs(&snaps[0]["positions"]));
    let after = centroid(pairs(&snaps.last().unwrap()["positions"]));
    assert!(
        after.x - before.x > 2.0,
        "crowd moved from {before} to {after}"
    );
    // Agents are at (or very near) the goals they were sent to.
    let last = snaps.last().unwrap();
    let (pos, goals) = (pairs(&last["positions"]), pairs(&last["goals"]));
    let assign: Vec<u64> = last["assignment"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g.as_u64().unwrap())
        .collect();
    for (p, g) in pos.iter().zip(&assign) {
        assert!((p - goals[*g as usize]).norm() < 0.1);
    }
}

#[test]
fn the_worker_assignment_is_optimal_for_the_state_it_was_solved_on() {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 80;
    let daemon = start(cfg, &["05-area-twist.jsonl"], &path);
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    let msgs = read_until(&mut r, 4.0, |_| false);
    daemon.shutdown();
    let snaps: Vec<&Value> = msgs.iter().filter(|v| v["type"] == "snapshot").collect();
    let by_seq = |seq: u64| snaps.iter().find(|s| s["seq"] == seq);
    let mut checked = 0;
    for s in snaps.iter().step_by(10) {
        let Some(solved_on) = by_seq(s["assignment_seq"].as_u64().unwrap()) else {
            continue;
        };
        if s["assignment_seq"] == 0 {
            continue;
        }
        let (agents, goals) = (pairs(&solved_on["positions"]), pairs(&solved_on["goals"]));
        let assign = s["assignment"]
            .as_array()
            .unwrap()
            .iter()
            .map(|g| g.as_u64().unwrap() as u32);
        let goal_of: Vec<u32> = assign.collect();
        let ours = assignment_cost(&agents, &goals, goal_of.iter().copied());
        let best = reference_optimal_cost(&agents, &goals);
        // Positions on the wire are rounded to the millimetre, so each agent-goal
        // vector is off by at most e = 2·√2·0.5 mm; a squared length |d|² then moves
        // by at most 2|d|e + e². Both totals move, hence the factor 2.
        let e = 2.0 * 2f64.sqrt() * 0.0005;
        let slack: f64 = 2.0
            * agents
                .iter()
                .zip(&goal_of)
                .map(|(a, &g)| 2.0 * (a - goals[g as usize]).norm() * e + e * e)
                .sum::<f64>();
        assert!(
            ours <= best + slack,
            "seq {}: {ours} vs {best} (slack {slack})",
            s["seq"]
        );
        checked += 1;
    }
    assert!(checked >= 10, "checked {checked}");
}

#[test]
fn commands_reset_resize_and_pause() {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    let daemon = start(Config::embedded_default(), &["01-point-drag.jsonl"], &path);
    let stream = UnixStream::connect(&path).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    read_until(&mut r, 2.0, |v| v["type"] == "hello");
    writeln!(
        w,
        r#"{{"type":"command","id":7,"name":"set_agent_count","count":50}}"#
    )
    .unwrap();
    let msgs = read_until(&mut r, 3.0, |v| {
        v["type"] == "snapshot" && v["agents"] == 50
    });
    assert!(
        msgs.iter().any(|v| v["type"] == "ack" && v["id"] == 7),
        "no ack: {:?}",
        msgs.iter().map(|v| &v["type"]).collect::<Vec<_>>()
    );
    writeln!(w, r#"{{"type":"command","id":"p","name":"pause"}}"#).unwrap();
    let msgs = read_until(&mut r, 3.0, |v| {
        v["type"] == "snapshot" && v["paused"] == true
    });
    assert!(msgs.iter().any(|v| v["type"] == "ack" && v["id"] == "p"));
    writeln!(
        w,
        r#"{{"type":"command","id":8,"name":"set_agent_count","count":0}}"#
    )
    .unwrap();
    let msgs = read_until(&mut r, 3.0, |v| v["type"] == "error");
    let err = msgs.last().unwrap();
    assert_eq!(err["id"], 8);
    assert!(
        err["message"].as_str().unwrap().contains("out of range"),
        "{err}"
    );
    writeln!(
        w,
        r#"{{"type":"command","id":9,"name":"reset","hard":true}}"#
    )
    .unwrap();
    let msgs = read_until(&mut r, 3.0, |v| v["type"] == "ack");
    assert_eq!(msgs.last().unwrap()["id"], 9);
    daemon.shutdown();
}

#[test]
fn a_live_socket_is_refused_and_a_stale_one_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    // A stale socket file: bound once, its listener gone.
    drop(std::os::unix::net::UnixListener::bind(&path).unwrap());
    assert!(path.exists());
    let daemon = start(
        Config::embedded_default(),
        &["07-open-space-swipe.jsonl"],
        &path,
    );
    let mut cfg = Config::embedded_default();
    cfg.pipeline.realtime = Default::default();
    let second = Daemon::start(
        cfg,
        vec![source(&["07-open-space-swipe.jsonl"], false)],
        DaemonOptions {
            socket_path: path.clone(),
            collect: None,
        },
    );
    let err = second
        .err()
        .expect("a second daemon on a live socket must fail")
        .to_string();
    assert!(err.contains(&path.display().to_string()), "{err}");
    // The first daemon still serves.
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    let msgs = read_until(&mut r, 2.0, |v| v["type"] == "snapshot");
    assert_eq!(msgs.last().unwrap()["type"], "snapshot");
    daemon.shutdown();
    assert!(!path.exists(), "socket file removed on shutdown");
}

#[test]
fn shutdown_says_bye_and_nothing_is_left_down() {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    let daemon = start(Config::embedded_default(), &["06-two-hands.jsonl"], &path);
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    // Stop in the middle of the recording, fingers down.
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "control" && v["kind"] == "area"
    });
    assert!(msgs.iter().any(|v| v["type"] == "control"));
    daemon.shutdown();
    let rest = read_until(&mut r, 3.0, |v| v["type"] == "bye");
    assert_eq!(rest.last().unwrap()["type"], "bye");
    let last_snap = rest
        .iter()
        .rev()
        .find(|v| v["type"] == "snapshot")
        .expect("a final snapshot");
    assert_eq!(
        last_snap["touches"].as_array().unwrap().len(),
        0,
        "touches left down: {}",
        last_snap["touches"]
    );
    let ends = rest
        .iter()
        .filter(|v| v["type"] == "control" && v["phase"] == "end")
        .count();
    assert!(ends >= 1);
}

/// Scene A of the reload tests: one block east of the crowd, open ground under it.
const SCENE_EAST_BLOCK: &str = "(
    version: 1,
    name: \"east block\",
    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
    obstacles: [
        (name: \"block\", parts: [
            Polygon(vertices_m: [(11.5, 3.5), (13.5, 3.5), (13.5, 5.5), (11.5, 5.5)]),
        ]),
    ],
)";

/// A config file in `dir` naming the scene file `scene.ron` beside it (or no scene),
/// with `agents` agents, assigned on the worker or inside the tick.
fn scene_config(dir: &Path, with_scene: bool, agents: u32, worker: bool) -> PathBuf {
    let text = crowdtouch::config::DEFAULT_CONFIG_RON
        .replacen("agents: 100", &format!("agents: {agents}"), 1)
        .replacen("worker: true", &format!("worker: {worker}"), 1)
        // The checkpoint test watches the mesh switch (transforms: daemon_transforms.rs).
        .replacen("method: transform", "method: mesh", 1)
        .replacen(
            "scene: None",
            if with_scene {
                "scene: Some(\"scene.ron\")"
            } else {
                "scene: None"
            },
            1,
        );
    let path = dir.join("crowdtouch.ron");
    std::fs::write(&path, text).unwrap();
    path
}

fn motions(v: &Value) -> Vec<&str> {
    v["motions"]
        .as_array()
        .map(|m| m.iter().map(|x| x.as_str().unwrap()).collect())
        .unwrap_or_default()
}

/// A reload re-reads the scene file: the edited scene (its block moved into the
/// crowd, a pool added) applies while the crowd keeps running: no reset, ticks go
/// on, no agent is ever inside the new block once the new scene is in use (checked
/// over `ticks_after` ticks), agents in the pool report `swim`, and assignments
/// solved in the new scene keep coming. A reload without a scene returns to open
/// ground.
fn reload_swaps_the_scene(agents: u32, worker: bool, ticks_after: u64) {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    std::fs::write(dir.path().join("scene.ron"), SCENE_EAST_BLOCK).unwrap();
    let cfg_path = scene_config(dir.path(), true, agents, worker);
    let cfg = Config::load(&cfg_path).unwrap();
    assert_eq!(cfg.loaded_scene().unwrap().name(), "east block");
    let mut daemon = start(cfg, &["07-open-space-swipe.jsonl"], &path);
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    // Scene A running: everyone on open ground, some agents where B's block will be.
    let before = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && v["assignment_seq"].as_u64() > Some(0)
    });
    let last_a = before.last().unwrap();
    assert_eq!(last_a["type"], "snapshot", "no snapshot in scene A");
    assert!(motions(last_a).iter().all(|m| *m == "run"));
    assert!(pairs(&last_a["positions"])
        .into_iter()
        .any(|p| common::in_crowd_block(p, 0.001)));

    std::fs::write(dir.path().join("scene.ron"), common::BLOCK_IN_THE_CROWD).unwrap();
    daemon.reload(Config::load(&cfg_path).unwrap());
    let mut swapped_at = None;
    let mut solved_in_b = false;
    let mut last_seq = last_a["seq"].as_u64().unwrap();
    // The worker runs at nice 10: on a loaded machine (a parallel test run) its
    // first solve in the new scene can take seconds of wall time in a debug build.
    let msgs = read_until(&mut r, 30.0, |v| {
        if v["type"] != "snapshot" {
            return false;
        }
        let seq = v["seq"].as_u64().unwrap();
        assert!(seq > last_seq, "ticks go on in order");
        last_seq = seq;
        if swapped_at.is_none() && motions(v).contains(&"swim") {
            swapped_at = Some(seq);
        }
        if let Some(s) = swapped_at {
            solved_in_b |= v["assignment_seq"].as_u64().unwrap() >= s;
        }
        solved_in_b && swapped_at.is_some_and(|s| seq > s + ticks_after)
    });
    let swapped_at = swapped_at.expect("the new scene's pool never showed in motions");
    assert!(solved_in_b, "no assignment solved in the new scene");
    assert!(
        !msgs.iter().any(|v| v["type"] == "reset"),
        "a scene reload does not reset the crowd"
    );
    let mut checked = 0;
    for v in msgs.iter().filter(|v| v["type"] == "snapshot") {
        assert_eq!(v["agents"], agents);
        if v["seq"].as_u64().unwrap() < swapped_at {
            continue;
        }
        for (i, p) in pairs(&v["positions"]).into_iter().enumerate() {
            assert!(
                !common::in_crowd_block(p, 0.001),
                "seq {}: agent {i} at {p} inside the new block",
                v["seq"]
            );
        }
        checked += 1;
    }
    assert!(
        checked as u64 > ticks_after,
        "only {checked} snapshots in the new scene"
    );

    // The scene removed from the config: open ground, no motions.
    daemon.reload(Config::load(&scene_config(dir.path(), false, agents, worker)).unwrap());
    let msgs = read_until(&mut r, 5.0, |v| {
        v["type"] == "snapshot" && v.get("motions").is_none()
    });
    assert!(
        msgs.last().unwrap().get("motions").is_none(),
        "motions still sent without a scene"
    );
    daemon.shutdown();
}

/// [`reload_swaps_the_scene`] with the assignment worker: it builds its planner for
/// the new scene on its own thread.
#[test]
fn a_reload_swaps_in_the_edited_scene_while_the_crowd_keeps_running() {
    reload_swaps_the_scene(60, true, 120);
}

/// [`reload_swaps_the_scene`] with the assignment inside the tick: the reload hands
/// the control thread a planner built for the new scene on the supervisor's thread.
#[test]
fn a_reload_with_inline_assignment_swaps_in_a_prepared_planner() {
    reload_swaps_the_scene(20, false, 30);
}

/// A scene with one checkpoint a little east of the crowd's start, across the
/// whole world: a drag east takes the crowd's centre over it.
const SCENE_GATE: &str = "(
    version: 1,
    name: \"gate\",
    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
    checkpoints: [
        (name: \"gate\", formation: \"column\",
         region: Polygon(vertices_m: [(8.8, 0.0), (9.2, 0.0), (9.2, 9.0), (8.8, 9.0)])),
    ],
)";

/// Section 7.3 end to end: a recorded drag takes the crowd over a checkpoint; a
/// client gets the `formation` event, then a `mesh` with the new topology and its
/// triangles, and the snapshots' goals lie in the new column (four times as long
/// along the drag as across it) with the crowd's size unchanged.
#[test]
fn a_client_sees_the_formation_switch_at_a_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let path = sock(&dir);
    std::fs::write(dir.path().join("scene.ron"), SCENE_GATE).unwrap();
    let cfg = Config::load(&scene_config(dir.path(), true, 40, true)).unwrap();
    let daemon = start(cfg, &["01-point-drag.jsonl"], &path);
    let mut r = BufReader::new(UnixStream::connect(&path).unwrap());
    let mut switched = false;
    let mut first_topology = None;
    let msgs = read_until(&mut r, 15.0, |v| {
        if v["type"] == "mesh" && first_topology.is_none() {
            first_topology = v["topology"].as_u64();
        }
        switched |= v["type"] == "formation";
        // Stop at the first mesh of the new topology.
        switched && v["type"] == "mesh" && v["topology"].as_u64() != first_topology
    });
    daemon.shutdown();
    let ev: Vec<&Value> = msgs.iter().filter(|v| v["type"] == "formation").collect();
    assert_eq!(ev.len(), 1, "formation events: {ev:?}");
    assert_eq!(ev[0]["name"], "column");
    assert_eq!(ev[0]["checkpoint"], "gate");
    let mesh = msgs.last().unwrap();
    assert_eq!(mesh["type"], "mesh", "no mesh after the switch");
    let verts = pairs(&mesh["vertices"]);
    assert_eq!(verts.len() as u64, ev[0]["vertices"].as_u64().unwrap());
    let tris = mesh["triangles"]
        .as_array()
        .expect("new topology comes with triangles");
    assert!(tris.len() >= 3 && tris.len() % 3 == 0);
    assert!(tris
        .iter()
        .all(|i| (i.as_u64().unwrap() as usize) < verts.len()));
    // The next snapshot's goals: 40, in a column along the drag (east).
    let snap = msgs
        .iter()
        .rev()
        .find(|v| v["type"] == "snapshot")
        .expect("a snapshot");
    let goals = pairs(&snap["goals"]);
    assert_eq!(goals.len(), 40);
    let (lo, hi) = verts.iter().fold(
        (Vec2::repeat(f64::MAX), Vec2::repeat(f64::MIN)),
        |(l, h), p| (l.inf(p), h.sup(p)),
    );
    let ratio = (hi.x - lo.x) / (hi.y - lo.y);
    assert!(ratio > 2.5, "column length / width {ratio}");
}
