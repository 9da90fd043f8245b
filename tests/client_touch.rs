//! Touches sent by a socket client (`touch` commands, as the viewer page sends
//! them) drive the crowd like a device's; bad ones are refused with a clear
//! `error` and change nothing.

mod common;

use common::*;
use crowdtouch::config::Config;
use crowdtouch::geom::Vec2;
use crowdtouch::pipeline::Daemon;
use crowdtouch::vocab::TouchFrame;
use serde_json::{json, Value};
use std::io::{BufReader, Write};
use std::os::unix::net::UnixStream;
use std::time::Duration;

struct Rig {
    daemon: Daemon,
    r: BufReader<UnixStream>,
    w: UnixStream,
    min: Vec2,
    size: Vec2,
    _dir: tempfile::TempDir,
    _tx: crossbeam_channel::Sender<TouchFrame>,
}

fn xy(v: &Value) -> Vec2 {
    Vec2::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

fn positions(v: &Value) -> Vec<Vec2> {
    v["positions"]
        .as_array()
        .unwrap()
        .chunks_exact(2)
        .map(|c| Vec2::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
        .collect()
}

fn start() -> Rig {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 30;
    cfg.pipeline.realtime = Default::default();
    // A source that never sends: the only touches are the client's.
    let (daemon, tx) = daemon_on_channel(cfg, &path, 1);
    let w = UnixStream::connect(&path).unwrap();
    let mut r = BufReader::new(w.try_clone().unwrap());
    let hello = read_until(&mut r, 5.0, |v| v["type"] == "hello");
    let world = &hello.last().unwrap()["world"];
    let (min, max) = (xy(&world["min"]), xy(&world["max"]));
    Rig {
        daemon,
        r,
        w,
        min,
        size: max - min,
        _dir: dir,
        _tx: tx,
    }
}

impl Rig {
    fn send(&mut self, v: Value) {
        writeln!(self.w, "{v}").unwrap();
    }
    /// Sends `v` and returns its answer (ack or error).
    fn ask(&mut self, v: Value) -> Value {
        let id = v["id"].clone();
        self.send(v);
        let msgs = read_until(&mut self.r, 5.0, |m| {
            (m["type"] == "ack" || m["type"] == "error") && m["id"] == id
        });
        msgs.last().cloned().expect("an answer")
    }
    fn snapshot(&mut self) -> Value {
        read_until(&mut self.r, 5.0, |m| m["type"] == "snapshot")
            .pop()
            .unwrap()
    }
    fn table(&self, p: Vec2) -> (f64, f64) {
        (
            (p.x - self.min.x) / self.size.x,
            (p.y - self.min.y) / self.size.y,
        )
    }
}

#[test]
fn a_clients_touch_drags_the_crowd_and_lifts() {
    let mut rig = start();
    let before = centroid(positions(&rig.snapshot()));
    let (x0, y0) = rig.table(before);
    let dx = 3.0 / rig.size.x;
    for k in 0..=30 {
        let x = x0 + dx * f64::from(k) / 30.0;
        let a = rig.ask(
            json!({"type":"command","id":k,"name":"touch","contacts":[{"id":1,"x":x,"y":y0}]}),
        );
        assert_eq!(a["type"], "ack", "{a}");
        std::thread::sleep(Duration::from_millis(16));
    }
    // The touch is in the stream at its world position.
    let s = rig.snapshot();
    let t = &s["touches"][0];
    let want = Vec2::new(rig.min.x + (x0 + dx) * rig.size.x, before.y);
    assert!(
        (Vec2::new(t["x"].as_f64().unwrap(), t["y"].as_f64().unwrap()) - want).norm() < 0.01,
        "touch {t} not at {want}"
    );
    // Held (repeated, as a page does while the button is down), then lifted.
    for k in 0..40 {
        rig.ask(json!({"type":"command","id":100 + k,"name":"touch","contacts":[{"id":1,"x":x0 + dx,"y":y0}]}));
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(
        rig.ask(json!({"type":"command","id":"up","name":"touch","contacts":[]}))["type"],
        "ack"
    );
    let msgs = read_until(&mut rig.r, 5.0, |m| {
        m["type"] == "snapshot" && m["touches"].as_array().is_some_and(|t| t.is_empty())
    });
    // A second on, the crowd has come to rest where the finger left it.
    let mut n = 0;
    let later = read_until(&mut rig.r, 5.0, |m| {
        n += usize::from(m["type"] == "snapshot");
        n == 60
    });
    rig.daemon.shutdown();
    let kinds: Vec<&str> = msgs
        .iter()
        .filter(|m| m["type"] == "control")
        .map(|m| m["phase"].as_str().unwrap())
        .collect();
    assert!(kinds.contains(&"end"), "the point control ended: {kinds:?}");
    let after = centroid(positions(later.last().unwrap()));
    assert!(
        after.x - before.x > 2.0,
        "the crowd went from {before} to {after}, not 3 m right"
    );
}

#[test]
fn bad_touches_get_a_clear_error_and_change_nothing() {
    let mut rig = start();
    let before = positions(&rig.snapshot());
    let eleven: Vec<Value> = (0..11)
        .map(|i| json!({"id": i, "x": 0.5, "y": 0.5}))
        .collect();
    let cases = [
        // A browser's JSON.stringify(NaN) is null.
        (
            json!([{"id":1,"x":null,"y":0.5}]),
            "contacts[0].x must be a number in [0, 1] (table units), got null",
        ),
        (
            json!([{"id":1,"x":0.5,"y":1.5}]),
            "contacts[0].y must be a number in [0, 1] (table units), got 1.5",
        ),
        (
            json!(eleven),
            "11 contacts, more than the 10 a touch may list",
        ),
        (
            json!([{"id":70000,"x":0.5,"y":0.5}]),
            "contacts[0].id must be an integer in 0..=65535, got 70000",
        ),
        (
            json!([{"id":-1,"x":0.5,"y":0.5}]),
            "contacts[0].id must be an integer in 0..=65535, got -1",
        ),
        (
            json!([{"id":1,"x":0.5,"y":0.5},{"id":1,"x":0.2,"y":0.2}]),
            "contacts[1].id 1 is listed twice",
        ),
        (
            json!([{"id":1,"x":0.5,"y":0.5,"pressure":1}]),
            "contacts[0]: unknown field `pressure`",
        ),
        (
            json!("here"),
            "`contacts` must be a list of {\"id\", \"x\", \"y\"}, got \"here\"",
        ),
    ];
    for (k, (contacts, why)) in cases.iter().enumerate() {
        let a = rig.ask(json!({"type":"command","id":k,"name":"touch","contacts":contacts}));
        assert_eq!(a["type"], "error", "{a}");
        assert_eq!(a["fatal"], false);
        assert_eq!(
            a["message"],
            format!("invalid arguments for command `touch`: {why}")
        );
    }
    // The client is still served, no touch appeared and the crowd stood still.
    std::thread::sleep(Duration::from_millis(300));
    let s = rig.snapshot();
    rig.daemon.shutdown();
    assert_eq!(s["touches"], json!([]));
    for (p, q) in positions(&s).iter().zip(&before) {
        assert!((p - q).norm() < 1e-3, "an agent moved from {q} to {p}");
    }
}

#[test]
fn a_client_that_leaves_mid_touch_is_lifted() {
    let mut rig = start();
    // A second client touches, then hangs up.
    let path = rig._dir.path().join("ct.sock");
    let mut other = UnixStream::connect(&path).unwrap();
    writeln!(
        other,
        "{}",
        json!({"type":"command","id":1,"name":"touch","contacts":[{"id":3,"x":0.5,"y":0.5}]})
    )
    .unwrap();
    let msgs = read_until(&mut rig.r, 5.0, |m| {
        m["type"] == "snapshot" && m["touches"].as_array().is_some_and(|t| t.len() == 1)
    });
    assert_eq!(msgs.last().unwrap()["touches"].as_array().unwrap().len(), 1);
    drop(other);
    // Lifted at the hang-up: well before the touch timeout, so no touch command
    // from anyone and no timeout is needed. (A second reading of the stream.)
    let msgs = read_until(&mut rig.r, 5.0, |m| {
        m["type"] == "snapshot" && m["touches"].as_array().is_some_and(|t| t.is_empty())
    });
    rig.daemon.shutdown();
    assert_eq!(msgs.last().unwrap()["touches"], json!([]));
}
