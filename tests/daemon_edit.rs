//! The edit mode through the whole daemon, as a socket client sees it: the config
//! names a track file, the daemon plays its people as the crowd; the shipped
//! recording of a finger dragging right (`01-point-drag`), replayed through the
//! daemon's input queue at its own pace, lands on a group of people and drags
//! their tracks; a client subscribed to `edit` receives the group's tracks as the
//! finger moves, then every person's edited tracks after the release, moved the way
//! the finger went. `edit.undo` brings the old tracks back; `edit.save` writes them;
//! bad edit commands are `error` replies and nothing changes.

mod common;

use common::{daemon_on_channel, read_until, shipped};
use crowdtouch::config::Config;
use crowdtouch::crowd::edit::io::{read_tracks, write_tracks, Format, ReadOptions};
use crowdtouch::crowd::edit::{Track, TrackSet};
use crowdtouch::geom::Vec2;
use crowdtouch::input::recording::{read_recording, OnBadFrame};
use crowdtouch::vocab::{Micros, TouchFrame};
use serde_json::Value;
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::{Duration, Instant};

/// A block of 5 × 5 people 0.8 m apart around (9.9, 4.5) m, where the recording's
/// finger lands, walking slowly right (0.05 m/s) for a minute, sampled every 0.5 s;
/// and one person far off (id 100) who must not move.
fn block() -> TrackSet {
    let times: Vec<f64> = (0..=120).map(|k| k as f64 * 0.5).collect();
    let mut tracks = Vec::new();
    for r in 0..5 {
        for c in 0..5 {
            let p0 = Vec2::new(9.9 + (c as f64 - 2.0) * 0.8, 4.5 + (r as f64 - 2.0) * 0.8);
            let points = times
                .iter()
                .map(|t| p0 + Vec2::new(0.05 * t, 0.0))
                .collect();
            tracks.push(Track::linked((r * 5 + c) as u64, points, times.clone()));
        }
    }
    tracks.push(Track::linked(
        100,
        times
            .iter()
            .map(|t| Vec2::new(2.0 + 0.05 * t, 1.0))
            .collect(),
        times.clone(),
    ));
    TrackSet {
        tracks,
        step_s: 0.5,
    }
}

/// The block's tracks written to a temporary directory and the default config
/// with an edit section playing them (its `edit.dir` that directory when
/// `with_dir`); the directory (kept alive by the caller), the config and a socket
/// path in it.
fn block_config(with_dir: bool) -> (tempfile::TempDir, Config, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let tracks_path = dir.path().join("block.jsonl");
    write_tracks(
        &block(),
        &tracks_path,
        Format::Jsonl,
        &ReadOptions::default(),
        false,
    )
    .unwrap();
    let edit_dir = if with_dir {
        format!(", dir: Some({:?})", dir.path().display().to_string())
    } else {
        String::new()
    };
    let mut cfg = Config::from_str(
        &crowdtouch::config::DEFAULT_CONFIG_RON.replace(
            "    pipeline: (",
            &format!(
                "    edit: Some((tracks: {:?}, threshold_m: 0.3{edit_dir})),\n    pipeline: (",
                tracks_path.display().to_string(),
            ),
        ),
        Path::new("<test>"),
    )
    .expect("config with an edit section");
    cfg.pipeline.realtime = Default::default();
    let socket = dir.path().join("ct.sock");
    (dir, cfg, socket)
}

fn x_of(msg: &Value, id: u64, k: usize) -> f64 {
    let t = msg["tracks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == id)
        .unwrap();
    t["points"][k][0].as_f64().unwrap()
}

#[test]
fn a_recorded_drag_through_the_daemon_changes_the_tracks_a_client_receives() {
    let (dir, cfg, socket) = block_config(true);
    assert!(cfg.loaded_tracks().is_some());
    let (daemon, tx) = daemon_on_channel(cfg, &socket, 64);
    let stream = UnixStream::connect(&socket).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    writeln!(
        w,
        r#"{{"type":"hello","protocol":1,"subscribe":["edit","snapshot"],"max_rate_hz":10}}"#
    )
    .unwrap();
    read_until(&mut r, 3.0, |v| v["type"] == "hello");
    // The people play as the crowd: 26 agents.
    let snap = read_until(&mut r, 3.0, |v| v["type"] == "snapshot");
    assert_eq!(snap.last().unwrap()["agents"], 26);
    // Bad commands: errors, nothing changes.
    writeln!(w, r#"{{"type":"command","id":1,"name":"edit.undo"}}"#).unwrap();
    let e = read_until(&mut r, 3.0, |v| v["type"] == "error");
    assert!(e.last().unwrap()["message"]
        .as_str()
        .unwrap()
        .contains("nothing to undo"));
    writeln!(
        w,
        r#"{{"type":"command","id":2,"name":"edit.load","entry":"nonexistent.jsonl"}}"#
    )
    .unwrap();
    let e = read_until(&mut r, 3.0, |v| v["type"] == "error");
    assert!(
        e.last().unwrap()["message"]
            .as_str()
            .unwrap()
            .contains("nonexistent.jsonl: no such entry in the edit directory"),
        "{:?}",
        e.last()
    );
    // The recording, replayed through the input queue at its own pace.
    let rec = read_recording(&shipped("01-point-drag.jsonl"), OnBadFrame::Stop).unwrap();
    let start = Instant::now();
    let t0 = rec.frames[0].t;
    let sender = std::thread::spawn(move || {
        for f in rec.frames {
            let due = Duration::from_micros(f.t.saturating_since(t0).0);
            if let Some(wait) = due.checked_sub(start.elapsed()) {
                std::thread::sleep(wait);
            }
            let mut f = f;
            f.t = Micros(0);
            let mut g = TouchFrame::new(crowdtouch::rt::monotonic_now());
            for c in f.contacts() {
                g.push(*c).unwrap();
            }
            tx.send(g).unwrap();
        }
        tx
    });
    let msgs = read_until(&mut r, 15.0, |v| {
        v["type"] == "tracks" && v["full"] == true && v["version"].as_u64() > Some(1)
    });
    let _tx = sender.join().unwrap();
    let partial: Vec<&Value> = msgs
        .iter()
        .filter(|v| v["type"] == "tracks" && v["full"] == false)
        .collect();
    assert!(
        !partial.is_empty(),
        "tracks of the held group while the finger moves"
    );
    assert!(partial.iter().all(|v| v["tracks"]
        .as_array()
        .unwrap()
        .iter()
        .all(|t| t["id"] != 100)));
    assert!(msgs.iter().any(|v| v["type"] == "edit"
        && v["state"] == "grabbed"
        && v["hull"].as_array().unwrap().len() >= 3));
    let done = msgs.last().unwrap();
    assert_eq!(
        done["type"],
        "tracks",
        "{:?}",
        msgs.iter().map(|v| v["type"].clone()).collect::<Vec<_>>()
    );
    let original = block();
    // The finger went 2.5 m right: the person it held (the centre, id 12) and their
    // group moved right; the far person did not.
    let moved = x_of(done, 12, 2) - original.tracks[12].points[2].x;
    assert!(
        moved > 1.5,
        "the held person's tracks moved with the finger: {moved} m"
    );
    assert_eq!(x_of(done, 100, 2), original.tracks[25].points[2].x);
    // Undo, then save the edit again to a file.
    writeln!(w, r#"{{"type":"command","id":3,"name":"edit.undo"}}"#).unwrap();
    let back = read_until(&mut r, 5.0, |v| v["type"] == "tracks" && v["full"] == true);
    assert!((x_of(back.last().unwrap(), 12, 2) - original.tracks[12].points[2].x).abs() < 1e-9);
    let saved = dir.path().join("saved.jsonl");
    writeln!(
        w,
        r#"{{"type":"command","id":4,"name":"edit.save","entry":"saved.jsonl"}}"#
    )
    .unwrap();
    let ack = read_until(&mut r, 5.0, |v| {
        (v["type"] == "ack" || v["type"] == "error") && v["id"] == 4
    });
    assert_eq!(ack.last().unwrap()["type"], "ack", "{:?}", ack.last());
    let (again, _) = read_tracks(&saved, None, &ReadOptions::default()).unwrap();
    assert_eq!(again.tracks.len(), 26);
    // The existing file is not overwritten unless asked.
    writeln!(
        w,
        r#"{{"type":"command","id":5,"name":"edit.save","entry":"saved.jsonl","overwrite":true}}"#
    )
    .unwrap();
    let e = read_until(&mut r, 5.0, |v| {
        (v["type"] == "ack" || v["type"] == "error") && v["id"] == 5
    });
    assert_eq!(e.last().unwrap()["type"], "error");
    daemon.shutdown();
}

/// Through the daemon's socket, as the viewer page does it: `edit.select` picks
/// two people of the block, a client's `touch` on one of them grabs the two (not
/// the block), the lift shows the edit as a preview (`state: "preview"`, a
/// `tracks` message with `preview: true`, the `preview` object), and `edit.accept`
/// keeps it. A bad selection is an `error` naming what is wrong.
#[test]
fn a_client_selects_drags_and_accepts_through_the_socket() {
    let (_dir, cfg, socket) = block_config(false);
    let (daemon, _tx) = daemon_on_channel(cfg, &socket, 64);
    let stream = UnixStream::connect(&socket).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    writeln!(
        w,
        r#"{{"type":"hello","protocol":1,"subscribe":["edit"],"max_rate_hz":30}}"#
    )
    .unwrap();
    read_until(&mut r, 3.0, |v| v["type"] == "hello");
    let answer = |r: &mut BufReader<UnixStream>, id: u64| {
        read_until(r, 5.0, |v| {
            (v["type"] == "ack" || v["type"] == "error") && v["id"] == id
        })
        .pop()
        .unwrap()
    };
    writeln!(w, r#"{{"type":"command","id":1,"name":"pause"}}"#).unwrap();
    assert_eq!(answer(&mut r, 1)["type"], "ack");
    writeln!(
        w,
        r#"{{"type":"command","id":2,"name":"edit.select","lasso":[[0,0],[1,1]]}}"#
    )
    .unwrap();
    let e = answer(&mut r, 2);
    assert_eq!(e["type"], "error");
    assert!(e["message"].as_str().unwrap().contains("3 to"), "{e}");
    writeln!(
        w,
        r#"{{"type":"command","id":3,"name":"edit.select","ids":[12,13]}}"#
    )
    .unwrap();
    assert_eq!(answer(&mut r, 3)["type"], "ack");
    let sel = read_until(&mut r, 5.0, |v| {
        v["type"] == "edit" && v["selection"]["ids"] == serde_json::json!([12, 13])
    });
    let sel = sel.last().unwrap();
    assert_eq!(sel["selection"]["ids"], serde_json::json!([12, 13]));
    let t = sel["play_t_s"].as_f64().unwrap();
    // Person 12 (the block's centre) at the play time, in table units.
    let at = Vec2::new(9.9 + 0.05 * t, 4.5);
    let touch = |w: &mut UnixStream, id: u64, p: Option<Vec2>| {
        let contacts = match p {
            Some(p) => format!(r#"[{{"id":1,"x":{},"y":{}}}]"#, p.x / 16.0, p.y / 9.0),
            None => "[]".to_string(),
        };
        writeln!(
            w,
            r#"{{"type":"command","id":{id},"name":"touch","contacts":{contacts}}}"#
        )
        .unwrap();
    };
    touch(&mut w, 10, Some(at));
    let grabbed = read_until(&mut r, 5.0, |v| {
        v["type"] == "edit" && v["state"] == "grabbed"
    });
    assert_eq!(
        grabbed.last().unwrap()["selected"],
        serde_json::json!([12, 13]),
        "the selection, not the block"
    );
    for k in 1..=10u64 {
        std::thread::sleep(Duration::from_millis(30));
        touch(&mut w, 10 + k, Some(at + Vec2::new(0.0, 0.1 * k as f64)));
    }
    std::thread::sleep(Duration::from_millis(100));
    touch(&mut w, 30, None);
    let msgs = read_until(&mut r, 10.0, |v| {
        v["type"] == "edit" && v["state"] == "preview"
    });
    let preview = msgs.last().unwrap();
    assert_eq!(preview["state"], "preview", "{preview}");
    assert!(preview["preview"]["retimed"].is_array());
    assert!(preview["preview"]["pairs_after"].is_u64());
    let tracks = msgs
        .iter()
        .rev()
        .find(|v| v["type"] == "tracks" && v["full"] == true)
        .expect("the previewed tracks");
    assert_eq!(tracks["preview"], true);
    let y_of = |id: u64| {
        tracks["tracks"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["id"] == id)
            .unwrap()["points"][0][1]
            .as_f64()
            .unwrap()
    };
    assert!(y_of(12) - 4.5 > 0.5, "the held person moved: {}", y_of(12));
    assert_eq!(
        y_of(7),
        block().tracks[7].points[0].y,
        "not selected, not moved"
    );
    writeln!(w, r#"{{"type":"command","id":40,"name":"edit.accept"}}"#).unwrap();
    assert_eq!(answer(&mut r, 40)["type"], "ack");
    let idle = read_until(&mut r, 5.0, |v| v["type"] == "edit" && v["state"] == "idle");
    let idle = idle.last().unwrap();
    assert_eq!(idle["state"], "idle");
    assert!(idle["preview"].is_null());
    assert_eq!(idle["undo_depth"], 1);
    daemon.shutdown();
}

/// A client that subscribes to `edit` after the tracks were loaded (a renderer or a
/// viewer page opened later) gets them at once, every person, then the edit state;
/// one that leaves `edit` out gets neither.
#[test]
fn a_client_subscribing_later_gets_the_tracks_as_they_are() {
    let (_dir, cfg, socket) = block_config(false);
    let (daemon, _tx) = daemon_on_channel(cfg, &socket, 64);
    let hello = |subscribe: &str| {
        let stream = UnixStream::connect(&socket).unwrap();
        let mut w = stream.try_clone().unwrap();
        let mut r = BufReader::new(stream);
        writeln!(
            w,
            r#"{{"type":"hello","protocol":1,"subscribe":{subscribe},"max_rate_hz":10}}"#
        )
        .unwrap();
        read_until(&mut r, 3.0, |v| v["type"] == "hello");
        (w, r)
    };
    // The people play first: the load is over before anyone asks.
    let (_w0, mut r0) = hello(r#"["snapshot"]"#);
    let snap = read_until(&mut r0, 3.0, |v| v["type"] == "snapshot");
    assert_eq!(snap.last().unwrap()["agents"], 26);
    let (_w1, mut r1) = hello(r#"["edit"]"#);
    let got = read_until(&mut r1, 3.0, |v| v["type"] == "edit");
    let tracks: Vec<&Value> = got.iter().filter(|v| v["type"] == "tracks").collect();
    assert_eq!(tracks.len(), 1, "{got:?}");
    assert_eq!(tracks[0]["full"], true);
    assert_eq!(tracks[0]["tracks"].as_array().unwrap().len(), 26);
    let original = block();
    // Points go out to the millimetre.
    assert!((x_of(tracks[0], 12, 2) - original.tracks[12].points[2].x).abs() <= 5e-4);
    assert_eq!(got.last().unwrap()["state"], "idle", "{:?}", got.last());
    // Without `edit`: none of it.
    let more = read_until(&mut r0, 1.0, |v| {
        v["type"] == "tracks" || v["type"] == "edit"
    });
    assert!(
        more.iter()
            .all(|v| v["type"] != "tracks" && v["type"] != "edit"),
        "{more:?}"
    );
    daemon.shutdown();
}
