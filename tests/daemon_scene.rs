//! The scene through the whole daemon, as a socket client sees it: a client
//! subscribed to `scene` gets the scene's obstacles, patches, moving things and
//! checkpoints when it subscribes, the moving things' poses every tick (where the
//! scene's own paths put them), and the scene again when a reload changes it; a
//! client that did not subscribe gets none of these message types.

mod common;

use common::{daemon_on_channel, read_until};
use crowdtouch::config::Config;
use crowdtouch::crowd::environment::{load_scene, Scene};
use serde_json::Value;
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::sync::Arc;

fn street() -> Arc<Scene> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes/street.ron");
    Arc::new(load_scene(&p, 0.15).unwrap())
}

fn config(scene: Option<Arc<Scene>>) -> Config {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 40;
    cfg.pipeline.realtime = Default::default();
    cfg.set_loaded_scene(scene);
    cfg
}

fn subscribe(path: &Path, streams: &str) -> (BufReader<UnixStream>, UnixStream) {
    let stream = UnixStream::connect(path).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    writeln!(
        w,
        r#"{{"type":"hello","protocol":1,"subscribe":[{streams}]}}"#
    )
    .unwrap();
    // The server's own hello (on connect), then the answer to ours.
    read_until(&mut r, 3.0, |v| v["type"] == "hello");
    read_until(&mut r, 3.0, |v| v["type"] == "hello");
    (r, w)
}

fn xy(v: &Value) -> (f64, f64) {
    (v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

#[test]
fn a_subscriber_gets_the_scene_its_moving_things_and_the_scene_after_a_reload() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let scene = street();
    let (mut daemon, _frames) = daemon_on_channel(config(Some(Arc::clone(&scene))), &path, 16);
    let (mut plain, _pw) = subscribe(&path, r#""snapshot","events""#);
    let (mut r, _w) = subscribe(&path, r#""snapshot","scene""#);

    // The scene, as the file has it.
    let msgs = read_until(&mut r, 5.0, |v| v["type"] == "scene");
    let s = msgs
        .last()
        .filter(|v| v["type"] == "scene")
        .expect("a scene");
    assert_eq!(s["name"], "street");
    assert_eq!(s["bounds"], serde_json::json!([[0.0, 0.0], [16.0, 9.0]]));
    let names = |k: &str| -> Vec<String> {
        s[k].as_array()
            .unwrap()
            .iter()
            .map(|o| o["name"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(names("obstacles"), ["west bollard", "east bollard"]);
    assert_eq!(
        names("dynamic"),
        ["small car", "second small car", "bus", "loop car"]
    );
    assert_eq!(names("patches"), ["north kerb"]);
    let bollard = &s["obstacles"][0]["parts"][0];
    assert_eq!(bollard["shape"], "circle");
    assert_eq!(xy(&bollard["centre"]), (6.0, 6.6));
    assert_eq!(bollard["radius"], 0.15);
    let kerb = &s["patches"][0];
    assert_eq!(kerb["motion"], "climb_down");
    assert_eq!(kerb["parts"][0]["points"].as_array().unwrap().len(), 4);
    let bus = &s["dynamic"][2];
    assert_eq!(bus["kind"], "obstacle");
    // In its own frame: a 4 m × 1 m box round the origin.
    let xs: Vec<f64> = bus["parts"][0]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| xy(p).0)
        .collect();
    assert_eq!(
        xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        2.0,
        "{xs:?}"
    );

    // Poses every tick, where the scene's paths put the cars at the scene time.
    let msgs = read_until(&mut r, 5.0, |_| false);
    let poses: Vec<&Value> = msgs.iter().filter(|v| v["type"] == "scene_poses").collect();
    // Every tick; a reader that falls behind gets the newest instead of a backlog,
    // so there may be fewer of them than of snapshots.
    assert!(poses.len() > 100, "{} scene_poses in 5 s", poses.len());
    let mut seqs = poses.iter().map(|v| v["seq"].as_u64().unwrap());
    let mut last = seqs.next().unwrap();
    for s in seqs {
        assert!(s > last, "poses out of order: {s} after {last}");
        last = s;
    }
    for p in &poses {
        let t = p["t_s"].as_f64().unwrap();
        let list = p["poses"].as_array().unwrap();
        assert_eq!(list.len(), 4);
        for (i, d) in scene.dynamic().iter().enumerate() {
            let want = d.placement_at(t);
            let (x, y) = xy(&list[i]);
            let h = list[i][2].as_f64().unwrap();
            assert!(
                (x - want.position.x).abs() < 1e-9 && (y - want.position.y).abs() < 1e-9,
                "{} at t = {t}: ({x}, {y}) vs {:?}",
                d.name,
                want.position
            );
            assert!((h - want.heading_rad()).abs() < 1e-9);
        }
    }
    // The cars moved: the first small car's x over the run spans metres.
    let car_x: Vec<f64> = poses.iter().map(|p| xy(&p["poses"][0]).0).collect();
    let span = car_x.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - car_x.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(span > 5.0, "the car moved {span} m in 5 s");
    // A reload without the scene: a scene with no name and nothing in it, and no
    // more poses.
    daemon.reload(config(None));
    let msgs = read_until(&mut r, 5.0, |v| v["type"] == "scene");
    let s = msgs
        .last()
        .filter(|v| v["type"] == "scene")
        .expect("a scene");
    assert!(s["name"].is_null(), "{s}");
    assert_eq!(s["dynamic"], serde_json::json!([]));
    assert_eq!(s["bounds"], serde_json::json!([[0.0, 0.0], [16.0, 9.0]]));
    let after = read_until(&mut r, 1.0, |_| false);
    assert!(after.iter().any(|v| v["type"] == "snapshot"));
    assert!(after.iter().all(|v| v["type"] != "scene_poses"));

    // A client that subscribes now gets the scene in effect at once.
    let (mut late, _lw) = subscribe(&path, r#""scene""#);
    let msgs = read_until(&mut late, 3.0, |v| v["type"] == "scene");
    assert!(msgs.last().unwrap()["name"].is_null());

    // The client that did not ask got none of it.
    let theirs = read_until(&mut plain, 1.0, |_| false);
    assert!(theirs.iter().any(|v| v["type"] == "snapshot"));
    assert!(theirs
        .iter()
        .all(|v| v["type"] != "scene" && v["type"] != "scene_poses"));
    daemon.shutdown();
}
