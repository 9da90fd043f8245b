//! Every `stats` field reports what it names: for each one, a running daemon is
//! made to change it (or, for `transitions_lost`, to keep it at zero while frames
//! are merged), and a last test checks that no field of the report goes untested.

mod common;

use common::{daemon_on_channel, read_until, send_drag, shipped};
use crowdtouch::config::{Config, InputConfig};
use crowdtouch::input::recording::{read_recording, OnBadFrame};
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions, SourceSpec};
use crowdtouch::vocab::{DeviceState, StatsReport};
use std::io::{BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The fields the tests below make a running daemon change, one line each.
const TESTED: &[&str] = &[
    "t",
    "interval_us",
    "stages",
    "frames",
    "frames_coalesced",
    "transitions_lost",
    "ticks",
    "assignments",
    "assignment_hz",
    "snapshots_dropped",
    "clients",
    "agents",
    "controls",
    "rss_bytes",
    "last_gesture",
    "formation",
    "formation_switches",
    "transforms",
    "last_transform",
    "restart_pending",
    "outputs",
    "touches",
    "devices",
];

const INTERVAL_MS: u64 = 250;

fn config(agents: u32) -> Config {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    cfg.pipeline.realtime = Default::default();
    cfg.pipeline.stats_interval_ms = INTERVAL_MS;
    cfg
}

fn report(d: &mut Daemon) -> Arc<StatsReport> {
    d.next_report(Duration::from_secs(5))
        .expect("a stats report within 5 s")
}

/// Reports until one satisfies `ok` (at most `secs`), returned with the ones
/// before it.
fn report_until(
    d: &mut Daemon,
    secs: f64,
    what: &str,
    mut ok: impl FnMut(&StatsReport) -> bool,
) -> Arc<StatsReport> {
    let end = Instant::now() + Duration::from_secs_f64(secs);
    loop {
        let r = report(d);
        if ok(&r) {
            return r;
        }
        assert!(Instant::now() < end, "no report with {what}: last {r:?}");
    }
}

/// A client that reads everything until the daemon closes it.
fn reader(path: &Path) -> std::thread::JoinHandle<()> {
    let mut s = UnixStream::connect(path).unwrap();
    std::thread::spawn(move || {
        let mut buf = [0u8; 65536];
        while matches!(s.read(&mut buf), Ok(n) if n > 0) {}
    })
}

fn command(w: &mut UnixStream, id: u32, body: &str) {
    writeln!(w, r#"{{"type":"command","id":{id},{body}}}"#).unwrap();
}

/// A drag through the daemon: the figures of time, frames, touches, controls,
/// gestures, ticks, stages, assignments, clients, memory, the TUIO output's
/// counters, and a device input's state.
#[test]
fn a_drag_moves_the_touch_figures_and_the_rates() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let udp = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    // The drag takes the crowd over the gate: a formation switch at a checkpoint.
    std::fs::write(dir.path().join("scene.ron"), SCENE_GATE).unwrap();
    let text = crowdtouch::config::DEFAULT_CONFIG_RON
        .replacen("method: transform", "method: mesh", 1)
        .replacen("scene: None", "scene: Some(\"scene.ron\")", 1);
    std::fs::write(dir.path().join("crowdtouch.ron"), text).unwrap();
    let mut cfg = Config::load(&dir.path().join("crowdtouch.ron")).unwrap();
    cfg.crowd.agents = 40;
    cfg.pipeline.realtime = Default::default();
    cfg.pipeline.stats_interval_ms = INTERVAL_MS;
    cfg.outputs = ron::from_str(&format!(
        "[Tuio(target: \"{}\", privileged: true)]",
        udp.local_addr().unwrap()
    ))
    .unwrap();
    // A device input that finds nothing on this machine: its state is `failed`.
    cfg.inputs = vec![ron::from_str::<InputConfig>(
        "Device(select: Name(\"no such crowdtouch test device\"))",
    )
    .unwrap()];
    let mut sources = sources_from_config(&cfg).unwrap();
    let (tx, rx) = crossbeam_channel::bounded(4096);
    sources.push(SourceSpec::Channel { rx, glass_mm: None });
    let mut d = Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path: path.clone(),
            collect: None,
        },
    )
    .unwrap();
    let r0 = report(&mut d);
    // The TUIO target counts as one client.
    assert_eq!(r0.clients, 1, "clients before any connected");
    assert_eq!(r0.touches, 0);
    assert_eq!(r0.controls, 0);
    assert_eq!(r0.last_gesture, None);
    let _a = reader(&path);
    let _b = reader(&path);
    let r1 = report_until(&mut d, 5.0, "two more clients", |r| r.clients == 3);

    // devices: the device input failed to find its device, and says why.
    assert_eq!(r1.devices.len(), 1, "{:?}", r1.devices);
    assert_eq!(r1.devices[0].input, 0);
    assert_eq!(r1.devices[0].state, Some(DeviceState::Failed));
    assert!(r1.devices[0].message.is_some());

    let drag = {
        let tx = tx.clone();
        std::thread::spawn(move || send_drag(&tx, true))
    };
    let during = report_until(&mut d, 10.0, "a control", |r| r.controls > 0);
    drag.join().unwrap();
    let after = report_until(&mut d, 10.0, "the control ended", |r| {
        r.controls == 0 && r.last_gesture.is_some()
    });
    let rec = read_recording(&shipped("01-point-drag.jsonl"), OnBadFrame::Stop).unwrap();
    // t and interval_us: the report's time advances by its interval.
    assert!(after.t > during.t && during.t > r1.t);
    for r in [&during, &after] {
        let ms = r.interval_us / 1000;
        assert!(
            (INTERVAL_MS / 2..INTERVAL_MS * 4).contains(&ms),
            "interval {ms} ms, configured {INTERVAL_MS} ms"
        );
    }
    // frames and touches: every frame sent, one finger.
    assert_eq!(after.frames, rec.frames.len() as u64);
    assert_eq!(after.touches, 1);
    // controls and last_gesture.
    assert_eq!(during.controls, 1);
    assert!(
        after.last_gesture.as_deref().unwrap().contains("point"),
        "{:?}",
        after.last_gesture
    );
    // formation and formation_switches: the gate's column.
    assert_eq!((r1.formation.as_str(), r1.formation_switches), ("start", 0));
    let switched = report_until(&mut d, 10.0, "the switch at the gate", |r| {
        r.formation_switches == 1
    });
    assert_eq!(switched.formation, "column");
    // ticks.
    assert!(after.ticks > r1.ticks);
    // stages: the latency path's stages counted samples in the drag's interval.
    for stage in ["queue", "control", "publish", "end_to_end"] {
        let s = during
            .stages
            .iter()
            .find(|s| s.stage == stage)
            .unwrap_or_else(|| panic!("no stage {stage} in {:?}", during.stages));
        assert!(s.count > 0 && s.max_us >= s.p50_us, "{s:?}");
    }
    // assignments and assignment_hz: the worker solves while the crowd moves, and
    // the rate is the increase over the interval.
    let mut prev = report(&mut d);
    let mut rates = Vec::new();
    for _ in 0..4 {
        let r = report(&mut d);
        let expect = (r.assignments - prev.assignments) as f64 / (r.interval_us as f64 * 1e-6);
        assert!(
            (r.assignment_hz - expect).abs() < 1e-6 * expect.max(1.0),
            "{} Hz reported, {expect} Hz counted",
            r.assignment_hz
        );
        rates.push(r.assignment_hz);
        prev = r;
    }
    assert!(after.assignments > r0.assignments);
    assert!(
        rates.iter().any(|&hz| hz > 0.0) || during.assignment_hz > 0.0,
        "assignment rates {rates:?}, during the drag {}",
        during.assignment_hz
    );
    // rss_bytes.
    assert!(after.rss_bytes.unwrap() > 1 << 20);
    // outputs: the TUIO output's counters rose.
    let (_, count) = common::output_counts(&after, "tuio");
    let (_, count0) = common::output_counts(&r1, "tuio");
    assert!(count("frames") > count0("frames"));
    assert!(count("datagrams") > count0("datagrams"));
    // transitions_lost stays 0.
    assert_eq!(after.transitions_lost, 0);
    // clients: one gone.
    d.shutdown();
}

/// The queue holds two frames and the drag arrives all at once: motion frames are
/// merged (`frames_coalesced` rises) and no touch-down or lift is lost
/// (`transitions_lost` stays 0, as it must).
#[test]
fn a_burst_coalesces_motion_and_loses_no_transition() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let mut cfg = config(400);
    cfg.pipeline.queue_frames = 2;
    let (mut d, tx) = daemon_on_channel(cfg, &path, 4096);
    let r0 = report(&mut d);
    assert_eq!(r0.frames_coalesced, 0);
    for _ in 0..3 {
        send_drag(&tx, false);
    }
    let r = report_until(&mut d, 20.0, "three touches ended", |r| {
        r.touches == 3 && r.controls == 0 && r.frames_coalesced > 0
    });
    assert!(r.frames_coalesced > 0);
    assert_eq!(r.transitions_lost, 0);
    d.shutdown();
}

/// A client that never reads: the snapshots it cannot take are counted.
#[test]
fn a_client_that_does_not_read_counts_dropped_snapshots() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let mut cfg = config(1000);
    cfg.socket.client_queue = 2;
    let (mut d, _tx) = daemon_on_channel(cfg, &path, 16);
    let r0 = report(&mut d);
    assert_eq!(r0.snapshots_dropped, 0);
    let _stalled = UnixStream::connect(&path).unwrap();
    let r = report_until(&mut d, 30.0, "dropped snapshots", |r| {
        r.snapshots_dropped > 0
    });
    assert_eq!(r.clients, 1);
    d.shutdown();
}

/// Commands and a reload: `set_agent_count` changes `agents`; a formation
/// transform counts in `transforms`, ends in `last_transform` and puts the crowd
/// in its `formation`; a reload that changes a
/// restart field lists it in `restart_pending`.
#[test]
fn commands_and_a_reload_change_the_crowd_figures() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ct.sock");
    let (mut d, _tx) = daemon_on_channel(config(30), &path, 16);
    let r0 = report(&mut d);
    assert_eq!(r0.agents, 30);
    assert_eq!(r0.formation, "start");
    assert_eq!((r0.transforms, r0.formation_switches), (0, 0));
    assert!(r0.last_transform.is_none());
    assert!(r0.restart_pending.is_empty());
    let stream = UnixStream::connect(&path).unwrap();
    let mut w = stream.try_clone().unwrap();
    let mut r = BufReader::new(stream);
    read_until(&mut r, 3.0, |v| v["type"] == "hello");
    let drain = std::thread::spawn(move || {
        read_until(&mut r, 60.0, |v| v["type"] == "bye");
    });

    command(&mut w, 1, r#""name":"set_agent_count","count":44"#);
    report_until(&mut d, 20.0, "44 agents", |r| r.agents == 44);

    command(
        &mut w,
        2,
        r#""name":"set_formation","formation":"arrow","duration":1"#,
    );
    let started = report_until(&mut d, 20.0, "a transform", |r| r.transforms == 1);
    assert!(started.transforms > r0.transforms);
    let ended = report_until(&mut d, 60.0, "the transform's end", |r| {
        r.last_transform.is_some() && r.formation == "arrow"
    });
    assert_eq!(
        ended.formation_switches, 0,
        "a command's transform is not a checkpoint's switch"
    );

    let mut changed = config(44);
    changed.socket.path = Some(dir.path().join("elsewhere.sock"));
    d.reload(changed);
    let pending = report_until(&mut d, 5.0, "a pending restart", |r| {
        !r.restart_pending.is_empty()
    });
    assert_eq!(pending.restart_pending[0].field, "socket.path");
    d.shutdown();
    drain.join().unwrap();
}

const SCENE_GATE: &str = "(
    version: 1,
    name: \"gate\",
    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
    checkpoints: [
        (name: \"gate\", formation: \"column\",
         region: Polygon(vertices_m: [(8.8, 0.0), (9.2, 0.0), (9.2, 9.0), (8.8, 9.0)])),
    ],
)";

/// No field of `stats` goes without a test above.
#[test]
fn every_stats_field_has_a_test() {
    let r = StatsReport {
        outputs: vec![Default::default()],
        devices: vec![crowdtouch::vocab::DeviceStatus {
            input: 0,
            state: None,
            node: String::new(),
            message: None,
        }],
        ..Default::default()
    };
    let v = serde_json::to_value(&r).unwrap();
    let fields: Vec<&String> = v.as_object().unwrap().keys().collect();
    for f in &fields {
        assert!(
            TESTED.contains(&f.as_str()),
            "stats field `{f}` has no test"
        );
    }
    assert_eq!(fields.len(), TESTED.len(), "{fields:?}");
}
